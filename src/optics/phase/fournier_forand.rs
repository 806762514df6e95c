//! The Fournier–Forand phase function: density, CDF and sampler.
//!
//! Written in s2 = sin^2(psi/2), in which the printed formulas (OPTICS.md;
//! Fournier & Forand 1994, Fournier & Jonasz 1999) are algebraic, 1 - cos psi
//! = 2 s2 keeps small angles, and ln P(<psi) is nearly linear in ln s2 over
//! the forward peak (P ~ s2^((mu-3)/2)), which is what the Newton solve of
//! the sampler's inverse table relies on. The printed forms are 0/0 at
//! delta = 1 (about 10° for Petzold-like parameters); series replace them
//! there.

use std::ops::RangeInclusive;
use std::sync::Arc;

use super::{solve_increasing_quadratic, FOUR_PI, S2_MIN, TWO_PI};
use crate::error::{Error, Result};

/// Backscatter fractions [`super::PhaseFunction::fournier_forand`] accepts: the range
/// over which Mobley et al. (2002) fitted the n–mu tie.
pub const FF_BB_RATIO_RANGE: RangeInclusive<f64> = 1e-4..=0.15;

/// |1 - delta| below which the series replace the removable 0/0 at delta = 1.
const FF_SERIES_RADIUS: f64 = 0.05;
/// Series terms: 0.05^16 is far below f64 round-off.
const FF_SERIES_TERMS: usize = 18;
/// Nodes of the table the sampler's inverse table is solved from, even in
/// ln sin^2(psi/2).
const FF_GUIDE_NODES: usize = 4097;
/// Nodes of the sampler's inverse table, even in z = ln P - ln(1 - P),
/// which resolves both the forward peak (small P) and the backward end
/// (P near 1).
const FF_INVERSE_NODES: usize = 4097;
/// The table's last z: that of the largest P below 1 that a sample can ask
/// for (1 - 2^-53, z = 36.74).
const FF_INVERSE_Z_MAX: f64 = 37.0;
/// Simpson intervals for the mean cosine.
const FF_MEAN_INTERVALS: usize = 4096;

/// Fournier–Forand phase function, in the variable s2 = sin^2(psi/2) in which
/// delta = 4 sin^2(psi/2) / (3 (n-1)^2) = s2 / k, k = 3 (n-1)^2 / 4.
#[derive(Clone, Debug)]
pub struct FournierForand {
    n: f64,
    mu: f64,
    shape: FfShape,
    /// P(<psi) at s2 = S2_MIN: the probability of a cosine that rounds to 1.
    cdf_min: f64,
    backscatter: f64,
    mean_cos: f64,
    /// The sampler's start: at FF_INVERSE_NODES values of z = ln P -
    /// ln(1 - P) evenly spaced over [z(cdf_min), FF_INVERSE_Z_MAX], the root
    /// ln s2 and its slope d ln s2 / dz, for cubic Hermite interpolation.
    inverse: Arc<[[f64; 2]]>,
    /// The table's first z, and its nodes per unit of z.
    z_min: f64,
    inverse_scale: f64,
}

/// The constants the density and CDF share.
#[derive(Clone, Copy, Debug)]
struct FfShape {
    /// nu = (3 - mu)/2, in [-1, 0).
    nu: f64,
    /// 3 (n-1)^2 / 4, the s2 at which delta = 1; delta180 = 1/k.
    k: f64,
    /// Coefficient of (3 cos^2 psi - 1) in p: (1 - d180^nu) / (16 pi (d180-1) d180^nu).
    c2: f64,
}

impl FournierForand {
    /// The n–mu tie of Mobley, Sundman & Boss (2002): n = 1.01 + 0.1542 (mu - 3).
    pub fn tied_n(mu: f64) -> f64 {
        1.01 + 0.1542 * (mu - 3.0)
    }

    /// From the particles' relative refractive index `n` in (1, 2] and the
    /// Junge slope `mu` in (3, 5] (errors name "n" or "mu"). The density has
    /// been checked non-negative over that box.
    pub fn new(n: f64, mu: f64) -> Result<Self> {
        if !(n > 1.0 && n <= 2.0) {
            return Err(Error::invalid(
                "n",
                format!("Fournier-Forand refractive index must lie in (1, 2], got {n}"),
            ));
        }
        if !(mu > 3.0 && mu <= 5.0) {
            return Err(Error::invalid(
                "mu",
                format!("Fournier-Forand Junge slope must lie in (3, 5], got {mu}"),
            ));
        }
        Ok(Self::build(n, mu))
    }

    /// The FF whose backscatter fraction is `bb_ratio` (in [`FF_BB_RATIO_RANGE`],
    /// else an error naming "bb_ratio"), n tied to mu by [`Self::tied_n`].
    /// B rises monotonically along the tie from 0 at mu = 3 to 1/2 at mu = 5,
    /// so bisection on mu converges to the last bit of mu.
    pub fn from_backscatter(bb_ratio: f64) -> Result<Self> {
        if !FF_BB_RATIO_RANGE.contains(&bb_ratio) {
            return Err(Error::invalid(
                "bb_ratio",
                format!(
                    "Fournier-Forand backscatter fraction must lie in [{}, {}], got {bb_ratio}",
                    FF_BB_RATIO_RANGE.start(),
                    FF_BB_RATIO_RANGE.end()
                ),
            ));
        }
        let backscatter = |mu: f64| 1.0 - FfShape::new(Self::tied_n(mu), mu).cdf(0.5);
        let (mut lo, mut hi) = (3.0_f64, 5.0_f64);
        loop {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if backscatter(mid) < bb_ratio {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let mu = 0.5 * (lo + hi);
        Ok(Self::build(Self::tied_n(mu), mu))
    }

    fn build(n: f64, mu: f64) -> Self {
        let shape = FfShape::new(n, mu);
        let ln_s2_min = S2_MIN.ln();
        let guide_ln_cdf: Vec<f64> = (0..FF_GUIDE_NODES)
            .map(|i| shape.cdf(ff_guide_s2(ln_s2_min, i)).ln())
            .collect();
        let cdf_min = shape.cdf(S2_MIN);
        let z_min = cdf_min.ln() - (-cdf_min).ln_1p();
        let last = FF_INVERSE_NODES - 1;
        let h = (FF_INVERSE_Z_MAX - z_min) / last as f64;
        let mut inverse: Vec<[f64; 2]> = (0..FF_INVERSE_NODES)
            .map(|j| {
                let z = z_min + j as f64 * h;
                // ln P = -ln(1 + e^-z); d ln P / dz = 1 - P.
                let ln_v = -(-z).exp().ln_1p();
                let t = if j == 0 {
                    ln_s2_min
                } else {
                    shape.solve_ln_s2(&guide_ln_cdf, ln_v)
                };
                let s2 = t.exp();
                let dt_dlnv = shape.cdf(s2) / (FOUR_PI * s2 * shape.density(s2));
                [t, dt_dlnv * -ln_v.exp_m1()]
            })
            .collect();
        // Where P is within round-off of 1 the roots are only known to
        // some 1e-12 and may step back by as much: keep the table (and so
        // the sampler's brackets) monotone.
        for j in 1..inverse.len() {
            inverse[j][0] = inverse[j][0].max(inverse[j - 1][0]);
        }
        let inverse: Arc<[[f64; 2]]> = inverse.into();
        FournierForand {
            n,
            mu,
            shape,
            cdf_min,
            backscatter: 1.0 - shape.cdf(0.5),
            mean_cos: shape.mean_cos(),
            inverse,
            z_min,
            inverse_scale: 1.0 / h,
        }
    }

    /// Relative refractive index n.
    pub fn n(&self) -> f64 {
        self.n
    }

    /// Junge slope mu.
    pub fn mu(&self) -> f64 {
        self.mu
    }

    /// Backscatter fraction B = 1 - P(<90°).
    pub fn backscatter_fraction(&self) -> f64 {
        self.backscatter
    }

    /// Mean cosine 2 pi int mu p dmu.
    pub fn mean_cosine(&self) -> f64 {
        self.mean_cos
    }

    /// p [sr^-1] at s2 = sin^2(psi/2) = (1 - cos psi)/2.
    pub(super) fn density(&self, s2: f64) -> f64 {
        self.shape.density(s2)
    }

    /// P(<psi) = 1 - u: the CDF runs from the forward direction, so that the
    /// tiny probabilities of the forward peak are resolved in ln P.
    pub(super) fn sample_cos(&self, u: f64) -> f64 {
        let v = 1.0 - u;
        if v <= self.cdf_min {
            return 1.0;
        }
        if v >= 1.0 {
            return -1.0;
        }
        1.0 - 2.0 * self.sample_ln_s2((v / u).ln()).exp()
    }

    /// ln s2 at which z = ln P - ln(1 - P), for cdf_min < P < 1: cubic
    /// Hermite interpolation in the inverse table, whose nodes hold the
    /// root and its slope solved to round-off.
    ///
    /// Within 2e-10 of the exact root for B from 1e-4 to 0.15
    /// (1.6e-10 measured at B = 0.15; tested at every
    /// midpoint between nodes, where it is worst, and at random points).
    /// That is a relative error in s2 = (1 - cos psi)/2, so the cosine is
    /// off by at most twice as much (4e-10) in absolute terms and the angle
    /// by half as much relatively, even in the forward peak: below the
    /// f32 spacing of the cosine emission stores (6e-8 near 1), and five
    /// orders of magnitude below the 5e-5 rad a stored direction keeps. A
    /// Newton step on the analytic CDF would refine it to round-off at the
    /// price of four more transcendental calls, a third of a scattering
    /// event's cost, and change nothing a photon map or image can resolve.
    fn sample_ln_s2(&self, z: f64) -> f64 {
        let inv = &self.inverse;
        let last = inv.len() - 1;
        let x = ((z - self.z_min) * self.inverse_scale).clamp(0.0, last as f64);
        let j = (x as usize).min(last - 1);
        let f = x - j as f64;
        let ([t0, m0], [t1, m1]) = (inv[j], inv[j + 1]);
        let h = 1.0 / self.inverse_scale;
        let g = 1.0 - f;
        (1.0 + 2.0 * f) * g * g * t0 + f * g * g * h * m0 + f * f * (3.0 - 2.0 * f) * t1
            - f * f * g * h * m1
    }
}

fn ff_guide_tau(ln_s2_min: f64, i: usize) -> f64 {
    ln_s2_min * (1.0 - i as f64 / (FF_GUIDE_NODES - 1) as f64)
}

fn ff_guide_s2(ln_s2_min: f64, i: usize) -> f64 {
    if i == FF_GUIDE_NODES - 1 {
        1.0
    } else {
        ff_guide_tau(ln_s2_min, i).exp()
    }
}

impl FfShape {
    /// ln s2 at which ln P(<psi) = `ln_v`, started from `guide` (ln P at
    /// FF_GUIDE_NODES values of ln s2 evenly spaced over [ln S2_MIN, 0]):
    /// bracketed by the guide, started by linear interpolation in it.
    fn solve_ln_s2(&self, guide: &[f64], ln_v: f64) -> f64 {
        let last = guide.len() - 1;
        // guide[0] = ln cdf_min < ln_v < 0 = guide[last], so i is in 1..=last.
        let i = guide.partition_point(|&g| g <= ln_v).clamp(1, last);
        let ln_s2_min = S2_MIN.ln();
        let (t_lo, t_hi) = (ff_guide_tau(ln_s2_min, i - 1), ff_guide_tau(ln_s2_min, i));
        let frac = (ln_v - guide[i - 1]) / (guide[i] - guide[i - 1]);
        let t0 = if frac.is_finite() {
            t_lo + frac * (t_hi - t_lo)
        } else {
            0.5 * (t_lo + t_hi)
        };
        self.newton_ln_s2(t_lo, t_hi, t0, ln_v)
    }

    /// Newton on ln P(ln s2) = `ln_v` from `t0` within [`lo`, `hi`]. ln P is
    /// nearly linear in ln s2 (P ~ s2^-nu near the peak), so Newton
    /// converges in a few steps; dP/d ln s2 = 4 pi s2 p. A Newton step
    /// below 1e-7 leaves an error of order its square (1e-14 in ln s2,
    /// round-off for the s2 it gives), so it is taken as the last.
    fn newton_ln_s2(&self, lo: f64, hi: f64, t0: f64, ln_v: f64) -> f64 {
        solve_increasing_quadratic(lo, hi, t0, 1e-7, 1e-13, |t| {
            let s2 = t.exp();
            let (cdf, density) = self.cdf_and_density(s2);
            (cdf.ln() - ln_v, FOUR_PI * s2 * density / cdf)
        })
    }

    /// [`Self::cdf`] and [`Self::density`] at once, for S2_MIN <= s2 <= 1:
    /// the printed forms share ln delta and delta^-nu (three transcendental
    /// calls instead of five).
    fn cdf_and_density(&self, s2: f64) -> (f64, f64) {
        let (nu, delta) = (self.nu, s2 / self.k);
        let x = 1.0 - delta;
        let (cdf, density) = if x.abs() < FF_SERIES_RADIUS {
            (self.cdf_series(s2), self.density_series(s2))
        } else {
            let nu_ln = nu * delta.ln();
            let d_minus_nu = (-nu_ln).exp();
            let cdf = (d_minus_nu * (1.0 - s2) - delta * (1.0 - self.k)) / x;
            let one_minus_dn = -nu_ln.exp_m1();
            let bracket = nu * x - one_minus_dn + (delta * one_minus_dn - nu * x) / s2;
            (cdf, bracket * d_minus_nu / (FOUR_PI * x * x))
        };
        let cos = 1.0 - 2.0 * s2;
        let sin_sq = 4.0 * s2 * (1.0 - s2);
        (
            (cdf + TWO_PI * self.c2 * cos * sin_sq).clamp(0.0, 1.0),
            density + self.c2 * (3.0 * cos * cos - 1.0),
        )
    }

    fn new(n: f64, mu: f64) -> Self {
        let nu = 0.5 * (3.0 - mu);
        let k = 0.75 * (n - 1.0) * (n - 1.0);
        let d180 = 1.0 / k;
        let nu_ln = nu * d180.ln();
        // expm1 keeps 1 - d180^nu accurate as nu -> 0.
        let c2 = -nu_ln.exp_m1() / (4.0 * FOUR_PI * (d180 - 1.0) * nu_ln.exp());
        FfShape { nu, k, c2 }
    }

    /// p(psi) [sr^-1] at s2 = sin^2(psi/2), no nearer forward than S2_MIN.
    fn density(&self, s2: f64) -> f64 {
        let s2 = s2.clamp(S2_MIN, 1.0);
        let x = 1.0 - s2 / self.k;
        let first = if x.abs() < FF_SERIES_RADIUS {
            self.density_series(s2)
        } else {
            self.density_direct(s2)
        };
        let cos = 1.0 - 2.0 * s2;
        first + self.c2 * (3.0 * cos * cos - 1.0)
    }

    /// First term of p as printed (OPTICS.md), with x = 1 - delta:
    /// [nu x - (1 - delta^nu) + (delta (1 - delta^nu) - nu x) / s2] / (4 pi x^2 delta^nu).
    fn density_direct(&self, s2: f64) -> f64 {
        let (nu, delta) = (self.nu, s2 / self.k);
        let x = 1.0 - delta;
        let nu_ln = nu * delta.ln();
        let one_minus_dn = -nu_ln.exp_m1();
        let bracket = nu * x - one_minus_dn + (delta * one_minus_dn - nu * x) / s2;
        bracket / (FOUR_PI * x * x * nu_ln.exp())
    }

    /// The same term near delta = 1, where the bracket vanishes as x^2: with
    /// s2 = k delta and b_j = C(nu, j) (-1)^j the coefficients of
    /// delta^nu = sum b_j x^j, bracket / x^2 = sum_{j>=2} [-nu/k + (1 - 1/k) b_j] x^(j-2).
    fn density_series(&self, s2: f64) -> f64 {
        let (nu, delta) = (self.nu, s2 / self.k);
        let x = 1.0 - delta;
        let inv_k = 1.0 / self.k;
        let mut b = -0.5 * nu * (1.0 - nu); // b_2
        let mut x_pow = 1.0;
        let mut sum = 0.0;
        for j in 2..2 + FF_SERIES_TERMS {
            sum += (-nu * inv_k + (1.0 - inv_k) * b) * x_pow;
            x_pow *= x;
            b *= (j as f64 - nu) / (j as f64 + 1.0);
        }
        sum / (FOUR_PI * (nu * delta.ln()).exp())
    }

    /// P(<psi), the probability of scattering by less than psi, at s2 = sin^2(psi/2).
    fn cdf(&self, s2: f64) -> f64 {
        let s2 = s2.clamp(0.0, 1.0);
        if s2 == 0.0 {
            return 0.0;
        }
        let x = 1.0 - s2 / self.k;
        let first = if x.abs() < FF_SERIES_RADIUS {
            self.cdf_series(s2)
        } else {
            self.cdf_direct(s2)
        };
        let cos = 1.0 - 2.0 * s2;
        let sin_sq = 4.0 * s2 * (1.0 - s2);
        (first + TWO_PI * self.c2 * cos * sin_sq).clamp(0.0, 1.0)
    }

    /// First term of P(<psi) as printed, multiplied through by delta^-nu:
    /// [delta^-nu (1 - s2) - delta (1 - k)] / (1 - delta).
    fn cdf_direct(&self, s2: f64) -> f64 {
        let delta = s2 / self.k;
        let d_minus_nu = (-self.nu * delta.ln()).exp();
        (d_minus_nu * (1.0 - s2) - delta * (1.0 - self.k)) / (1.0 - delta)
    }

    /// The same near delta = 1 (a removable 0/0): with a_j the coefficients of
    /// delta^-nu = sum a_j x^j (a_0 = 1, a_1 = nu),
    /// the term is (1-k) + sum_{j>=0} [(1-k) a_{j+1} + k a_j] x^j.
    fn cdf_series(&self, s2: f64) -> f64 {
        let (nu, k) = (self.nu, self.k);
        let x = 1.0 - s2 / k;
        let (mut a, mut a_next) = (1.0, nu);
        let mut x_pow = 1.0;
        let mut sum = 1.0 - k;
        for j in 0..FF_SERIES_TERMS {
            sum += ((1.0 - k) * a_next + k * a) * x_pow;
            x_pow *= x;
            a = a_next;
            a_next *= (j as f64 + 1.0 + nu) / (j as f64 + 2.0);
        }
        sum
    }

    /// <cos psi> = 2 int_0^1 P(<psi) ds2 - 1 (by parts, cos psi = 1 - 2 s2),
    /// integrated in ln s2 where the integrand is smooth; the cap below S2_MIN
    /// adds at most S2_MIN.
    fn mean_cos(&self) -> f64 {
        let (a, m) = (S2_MIN.ln(), FF_MEAN_INTERVALS);
        let h = -a / m as f64;
        let f = |t: f64| {
            let s2 = t.exp();
            self.cdf(s2) * s2
        };
        let mut sum = f(a) + f(0.0);
        for i in 1..m {
            sum += f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        let integral = sum * h / 3.0 + S2_MIN * self.cdf(S2_MIN);
        2.0 * integral - 1.0
    }
}

#[cfg(test)]
mod tests;
