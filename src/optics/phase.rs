//! Phase functions of ocean optics, each with an exact sampler.
//!
//! A phase function p(mu) [sr^-1] is the angular distribution of one
//! scattering event over mu = cos(psi), psi the angle between the directions
//! of travel before and after. Every model here is normalised,
//! 2 pi int_{-1}^{1} p(mu) dmu = 1, and `sample_cos` maps one uniform number to
//! a cosine distributed exactly as 2 pi p(mu) dmu: closed-form inversion, or a
//! safeguarded Newton solve of the exact CDF to round-off, never a fitted or
//! tabulated approximation of the inverse.
//!
//! Design note: the models are one enum so that a medium holds a plain value
//! and the photon loop pays a `match`, not a virtual call. Everything is f64:
//! the forward peaks of particle phase functions put much of their
//! probability at angles whose cosines differ from 1 by less than f32 can
//! resolve. This module is not for mixing (the medium forms
//! (b_w p_w + b_p p_p)/b by choosing a component with probability b_x/b) nor
//! for polarisation.
//!
//! Models (parameters, units, defaults, sources):
//! - **Isotropic**: p = 1/(4 pi).
//! - **Henyey–Greenstein**, asymmetry `g` (the mean cosine), -1 < g < 1:
//!   p = (1 - g^2) / (4 pi (1 + g^2 - 2 g mu)^(3/2)) (Henyey & Greenstein 1941).
//! - **Rayleigh-like** (pure water), `q` in [0, 1]:
//!   p = 3/(4 pi (3+q)) (1 + q mu^2), q = (1-d)/(1+d) with d the
//!   depolarisation ratio; d = 0.09 gives [`RAYLEIGH_Q_WATER`] = 0.835 and
//!   p(90°) = 0.06225 sr^-1 (Morel 1974; Mobley 1994, Light and Water).
//! - **Fournier–Forand**, relative refractive index `n` in (1, 2] and Junge
//!   slope `mu` in (3, 5] (Fournier & Forand 1994, Proc. SPIE 2258;
//!   Fournier & Jonasz 1999, Proc. SPIE 3761), or a backscatter fraction B in
//!   [1e-4, 0.15] with n tied to mu by n = 1.01 + 0.1542 (mu - 3) (Mobley,
//!   Sundman & Boss 2002, Appl. Opt. 41, 1035). B = 0.0183 gives
//!   mu = 3.5834, n = 1.0999 (the Petzold-like FF).
//! - **Petzold "average particle"** (Mobley et al. 1993, Appl. Opt. 32, 7484,
//!   Table 2), embedded from `data/petzold_avg_particle_mobley1993.csv`
//!   (corrected column): linear in angle between nodes, and
//!   p(0.12589°) (0.12589°/psi)^1.346 below 0.12589°, as the paper defines it.
//!   So defined, the table integrates exactly to 1.01798, not to the 1.00001
//!   of the paper's normalisation recipe (a trapezoid on p sin psi, which
//!   under-counts the convex forward lobe between log-spaced nodes); the values
//!   are divided by 1.01798, which gives B = 0.01782 rather than 0.0183.
//! - **User tables** of (angle in degrees, value): linear in angle, each end
//!   value held constant out to 0° or 180° when the table stops short, then
//!   normalised to 1.
//!
//! Near the forward direction: cosines within 2^-54 of 1 round to exactly 1,
//! so `eval(1.0)` is the density at the edge of that cap (finite, although
//! Fournier–Forand and Petzold diverge as psi -> 0), and a sampler returns
//! 1.0 for every draw that falls inside it.

use std::f64::consts::PI;

use glam::Vec3;

use crate::error::{Error, Result};

mod fournier_forand;
mod tabulated;

pub use fournier_forand::{FournierForand, FF_BB_RATIO_RANGE};
pub use tabulated::TabulatedPhase;

/// q of the Rayleigh-like pure-water phase function: depolarisation ratio 0.09.
pub const RAYLEIGH_Q_WATER: f64 = 0.835;

/// sin^2(psi/2) below which cos psi = 1 - 2 sin^2(psi/2) rounds to 1 (2^-55).
const S2_MIN: f64 = 1.0 / 36_028_797_018_963_968.0;

const FOUR_PI: f64 = 4.0 * PI;
const TWO_PI: f64 = 2.0 * PI;

/// A normalised phase function p(cos_theta) in sr^-1: the integral over the sphere is 1.
#[derive(Clone, Debug)]
pub enum PhaseFunction {
    /// p = 1/(4 pi).
    Isotropic,
    /// Henyey–Greenstein with asymmetry `g`, -1 < g < 1.
    HenyeyGreenstein { g: f64 },
    /// Rayleigh-like p = 3/(4 pi (3+q)) (1 + q mu^2), 0 <= q <= 1.
    Rayleigh { q: f64 },
    /// Fournier–Forand.
    FournierForand(FournierForand),
    /// Piecewise linear in angle: Petzold or a user table.
    Tabulated(TabulatedPhase),
}

impl PhaseFunction {
    /// Isotropic scattering.
    pub fn isotropic() -> Self {
        PhaseFunction::Isotropic
    }

    /// Henyey–Greenstein with asymmetry `g`; needs |g| < 1 (error names "g").
    pub fn henyey_greenstein(g: f64) -> Result<Self> {
        if g.is_finite() && g.abs() < 1.0 {
            Ok(PhaseFunction::HenyeyGreenstein { g })
        } else {
            Err(Error::invalid(
                "g",
                format!("Henyey-Greenstein asymmetry must satisfy -1 < g < 1, got {g}"),
            ))
        }
    }

    /// Rayleigh-like pure-water scattering, p = 3/(4 pi (3+q)) (1 + q mu^2);
    /// q = (1-d)/(1+d) for a depolarisation ratio d in [0, 1], so q in [0, 1]
    /// (error names "q"). Water: [`RAYLEIGH_Q_WATER`].
    pub fn rayleigh(q: f64) -> Result<Self> {
        if (0.0..=1.0).contains(&q) {
            Ok(PhaseFunction::Rayleigh { q })
        } else {
            Err(Error::invalid(
                "q",
                format!("Rayleigh-like q = (1-d)/(1+d) must lie in [0, 1], got {q}"),
            ))
        }
    }

    /// Fournier–Forand with backscatter fraction `bb_ratio` in
    /// [`FF_BB_RATIO_RANGE`] (error names "bb_ratio"); see
    /// [`FournierForand::from_backscatter`].
    pub fn fournier_forand(bb_ratio: f64) -> Result<Self> {
        FournierForand::from_backscatter(bb_ratio).map(PhaseFunction::FournierForand)
    }

    /// The Petzold "average particle" phase function (Mobley et al. 1993).
    pub fn petzold() -> Self {
        PhaseFunction::Tabulated(TabulatedPhase::petzold())
    }

    /// A user table; see [`TabulatedPhase::new`]. Errors name `field`.
    pub fn tabulated(angles_deg: &[f64], values: &[f64], field: &str) -> Result<Self> {
        TabulatedPhase::new(angles_deg, values, field).map(PhaseFunction::Tabulated)
    }

    /// p(cos_theta) in sr^-1; `cos_theta` is clamped to [-1, 1].
    pub fn eval(&self, cos_theta: f64) -> f64 {
        // Exact for cos_theta >= 1/2 (Sterbenz), so no forward precision is lost here.
        self.eval_one_minus_cos(1.0 - cos_theta.clamp(-1.0, 1.0))
    }

    /// p as a function of 1 - cos_theta (clamped to [0, 2]), in sr^-1. Near
    /// the forward peak a cosine has too few digits: for unit directions a
    /// and b pass |a - b|^2 / 2, which keeps its relative precision as they
    /// become parallel.
    pub fn eval_one_minus_cos(&self, one_minus_cos: f64) -> f64 {
        let x = one_minus_cos.clamp(0.0, 2.0);
        match self {
            PhaseFunction::Isotropic => 1.0 / FOUR_PI,
            PhaseFunction::HenyeyGreenstein { g } => {
                let g = *g;
                // (1-g)^2 + 2 g x = 1 + g^2 - 2 g mu without cancellation at g, mu -> 1.
                let d = (1.0 - g) * (1.0 - g) + 2.0 * g * x;
                (1.0 - g) * (1.0 + g) / (FOUR_PI * d * d.sqrt())
            }
            PhaseFunction::Rayleigh { q } => {
                let mu = 1.0 - x;
                3.0 / (FOUR_PI * (3.0 + q)) * (1.0 + q * mu * mu)
            }
            PhaseFunction::FournierForand(ff) => ff.density(0.5 * x),
            PhaseFunction::Tabulated(t) => {
                // asin keeps small angles; acos of the (exact) cosine is better backward.
                let psi = if x <= 1.0 {
                    2.0 * (0.5 * x).sqrt().asin()
                } else {
                    (1.0 - x).acos()
                };
                t.density(psi)
            }
        }
    }

    /// A scattering cosine distributed as 2 pi p(mu) dmu, from `u` uniform in
    /// [0, 1) (clamped to [0, 1]). Non-decreasing in `u`: u -> 1 is forward.
    pub fn sample_cos(&self, u: f64) -> f64 {
        let u = u.clamp(0.0, 1.0);
        let mu = match self {
            PhaseFunction::Isotropic => 2.0 * u - 1.0,
            PhaseFunction::HenyeyGreenstein { g } => hg_sample_cos(*g, u),
            PhaseFunction::Rayleigh { q } => rayleigh_sample_cos(*q, u),
            PhaseFunction::FournierForand(ff) => ff.sample_cos(u),
            PhaseFunction::Tabulated(t) => t.sample_cos(u),
        };
        mu.clamp(-1.0, 1.0)
    }

    /// A new direction of travel for a photon travelling along unit `w`:
    /// cosine from `u[0]`, azimuth 2 pi `u[1]`. Unlike `scatter(w, cos as f32, ..)`
    /// it takes sin(psi) from the f64 cosine, so forward angles below f32's
    /// cosine resolution (about 3e-4 rad) are kept.
    pub fn sample_direction(&self, w: Vec3, u: [f64; 2]) -> Vec3 {
        let cos = self.sample_cos(u[0]);
        let sin = ((1.0 - cos) * (1.0 + cos)).max(0.0).sqrt();
        scatter_sin_cos(w, sin as f32, cos as f32, (TWO_PI * u[1]) as f32)
    }

    /// Backscatter fraction B = 2 pi int_{-1}^{0} p dmu.
    pub fn backscatter_fraction(&self) -> f64 {
        match self {
            PhaseFunction::Isotropic | PhaseFunction::Rayleigh { .. } => 0.5,
            PhaseFunction::HenyeyGreenstein { g } => {
                // (1-g^2)/(2g) [1/sqrt(1+g^2) - 1/(1+g)], rearranged to stay finite at g = 0.
                let g = *g;
                let r = (1.0 + g * g).sqrt();
                (1.0 - g) / ((1.0 + g + r) * r)
            }
            PhaseFunction::FournierForand(ff) => ff.backscatter_fraction(),
            PhaseFunction::Tabulated(t) => t.backscatter_fraction(),
        }
    }

    /// Mean cosine (asymmetry parameter) 2 pi int mu p dmu.
    pub fn mean_cosine(&self) -> f64 {
        match self {
            PhaseFunction::Isotropic | PhaseFunction::Rayleigh { .. } => 0.0,
            PhaseFunction::HenyeyGreenstein { g } => *g,
            PhaseFunction::FournierForand(ff) => ff.mean_cosine(),
            PhaseFunction::Tabulated(t) => t.mean_cosine(),
        }
    }
}

/// New direction of travel after scattering the direction `w` (unit) by polar
/// cosine `cos_theta` and azimuth `phi` (radians), in the robust orthonormal
/// basis of Duff et al. 2017 (glam's `any_orthonormal_pair`).
pub fn scatter(w: Vec3, cos_theta: f32, phi: f32) -> Vec3 {
    let cos_theta = cos_theta.clamp(-1.0, 1.0);
    // (1-c)(1+c) rather than 1 - c^2: keeps precision at small angles.
    let sin_theta = ((1.0 - cos_theta) * (1.0 + cos_theta)).max(0.0).sqrt();
    scatter_sin_cos(w, sin_theta, cos_theta, phi)
}

fn scatter_sin_cos(w: Vec3, sin_theta: f32, cos_theta: f32, phi: f32) -> Vec3 {
    let (b1, b2) = w.any_orthonormal_pair();
    let (sin_phi, cos_phi) = phi.sin_cos();
    // Renormalised so that length errors do not compound over many scatterings.
    (b1 * (sin_theta * cos_phi) + b2 * (sin_theta * sin_phi) + w * cos_theta).normalize()
}

/// Exact inverse of the Henyey–Greenstein CDF in mu.
fn hg_sample_cos(g: f64, u: f64) -> f64 {
    // Either form is exact; each is free of cancellation in its own range.
    if g.abs() <= 0.5 {
        hg_sample_cos_expanded(g, u)
    } else {
        hg_sample_cos_classic(g, u)
    }
}

/// mu = (1 + g^2 - T^2)/(2g), T = (1 - g^2)/(1 + g s), s = 2u - 1, with the
/// division by g carried out symbolically so g = 0 gives mu = s without 0/0.
fn hg_sample_cos_expanded(g: f64, u: f64) -> f64 {
    let s = 2.0 * u - 1.0;
    let a = 1.0 + g * s;
    (s + g * (0.5 * (s * s + 3.0) + g * (s + 0.5 * g * (s * s - 1.0)))) / (a * a)
}

/// The textbook form (e.g. pbrt-v4); loses digits as g -> 0.
fn hg_sample_cos_classic(g: f64, u: f64) -> f64 {
    let t = (1.0 - g) * (1.0 + g) / (1.0 + g * (2.0 * u - 1.0));
    (1.0 + g * g - t * t) / (2.0 * g)
}

/// Exact inverse of the Rayleigh-like CDF F(mu) = [3(mu+1) + q(mu^3+1)] / (2(3+q)).
///
/// F = u is the depressed cubic mu^3 + (3/q) mu + c/q = 0, c = (3+q)(1-2u),
/// which has one real root because 3/q > 0; Cardano's formula in its
/// hyperbolic form gives it without the cancellation of the two cube roots:
/// mu = -(2/sqrt q) sinh(asinh(c sqrt(q)/2)/3), which tends to 2u - 1 as q -> 0.
fn rayleigh_sample_cos(q: f64, u: f64) -> f64 {
    let c = (3.0 + q) * (1.0 - 2.0 * u);
    if q == 0.0 {
        return -c / 3.0;
    }
    let r = q.sqrt();
    -2.0 / r * ((0.5 * c * r).asinh() / 3.0).sinh()
}

/// Root of an increasing `f` on [lo, hi] (f(lo) <= 0 <= f(hi)) from `x0`:
/// Newton steps, replaced by bisection whenever a step would leave the
/// shrinking bracket; stops when a step or the bracket is below `tol`.
/// `f` returns (value, derivative).
fn solve_increasing(
    mut lo: f64,
    mut hi: f64,
    x0: f64,
    tol: f64,
    f: impl Fn(f64) -> (f64, f64),
) -> f64 {
    let mut x = x0.clamp(lo, hi);
    for _ in 0..200 {
        let (fx, dfx) = f(x);
        if fx == 0.0 {
            return x;
        }
        if fx < 0.0 {
            lo = x;
        } else {
            hi = x;
        }
        let newton = x - fx / dfx;
        let next = if dfx > 0.0 && newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        if (next - x).abs() <= tol || hi - lo <= tol {
            return next;
        }
        x = next;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;
    use std::sync::OnceLock;

    /// Samples per Monte Carlo check.
    const SAMPLES: usize = 200_000;
    /// Quadrature grid in x = 1 - mu: nodes 2^(j/40 - 50), j = 0..=2040, so
    /// x = 1 (mu = 0) is node 2000 and the forward peaks are resolved down to
    /// x = 2^-50.
    const GRID_PER_OCTAVE: usize = 40;
    const GRID_OCTAVES_BELOW_ONE: usize = 50;
    const GRID_INTERVALS: usize = GRID_PER_OCTAVE * (GRID_OCTAVES_BELOW_ONE + 1);
    const GRID_MU_ZERO: usize = GRID_PER_OCTAVE * GRID_OCTAVES_BELOW_ONE;

    fn cases() -> Vec<(&'static str, PhaseFunction)> {
        let hg = |g| PhaseFunction::henyey_greenstein(g).unwrap();
        let ff = |b| PhaseFunction::fournier_forand(b).unwrap();
        vec![
            ("isotropic", PhaseFunction::isotropic()),
            ("HG g=0", hg(0.0)),
            ("HG g=1e-4", hg(1e-4)),
            ("HG g=0.5", hg(0.5)),
            ("HG g=0.9", hg(0.9)),
            ("HG g=-0.3", hg(-0.3)),
            ("HG g=-0.8", hg(-0.8)),
            (
                "Rayleigh q=0.835",
                PhaseFunction::rayleigh(RAYLEIGH_Q_WATER).unwrap(),
            ),
            ("FF B=0.0183", ff(0.0183)),
            ("FF B=0.01", ff(0.01)),
            ("FF B=0.1", ff(0.1)),
            ("FF B=0.001", ff(0.001)),
            ("FF B=1e-4", ff(1e-4)),
            ("Petzold", PhaseFunction::petzold()),
            (
                "user table",
                PhaseFunction::tabulated(
                    &[0.0, 30.0, 90.0, 150.0, 180.0],
                    &[10.0, 4.0, 1.0, 0.5, 0.8],
                    "t",
                )
                .unwrap(),
            ),
            (
                "user table, partial range",
                PhaseFunction::tabulated(&[10.0, 45.0, 170.0], &[5.0, 1.0, 2.0], "t").unwrap(),
            ),
        ]
    }

    /// Adaptive Simpson on [a, b] to absolute tolerance `tol`.
    fn simpson(f: &dyn Fn(f64) -> f64, a: f64, b: f64, tol: f64) -> f64 {
        #[allow(clippy::too_many_arguments)]
        fn step(
            f: &dyn Fn(f64) -> f64,
            a: f64,
            b: f64,
            fa: f64,
            fm: f64,
            fb: f64,
            whole: f64,
            tol: f64,
            depth: u32,
        ) -> f64 {
            let m = 0.5 * (a + b);
            let (lm, rm) = (0.5 * (a + m), 0.5 * (m + b));
            let (flm, frm) = (f(lm), f(rm));
            let left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
            let right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
            let delta = left + right - whole;
            if depth == 0 || delta.abs() <= 15.0 * tol {
                left + right + delta / 15.0
            } else {
                step(f, a, m, fa, flm, fm, left, 0.5 * tol, depth - 1)
                    + step(f, m, b, fm, frm, fb, right, 0.5 * tol, depth - 1)
            }
        }
        let (fa, fm, fb) = (f(a), f(0.5 * (a + b)), f(b));
        let whole = (b - a) / 6.0 * (fa + 4.0 * fm + fb);
        step(f, a, b, fa, fm, fb, whole, tol, 40)
    }

    /// The density integrated independently of the samplers: over the grid
    /// intervals in w = ln(1 - mu) (where forward peaks are smooth), plus
    /// the cap x < 2^-50 as the power law p ~ x^s fitted to p at 2^-50 and 2^-49.
    struct Profile {
        /// x = 1 - mu at the grid nodes, increasing from 2^-50 to 2.
        x: Vec<f64>,
        /// 2 pi int p dmu over each interval.
        mass: Vec<f64>,
        /// 2 pi int mu p dmu over each interval.
        moment: Vec<f64>,
        /// Mass of the cap x < 2^-50.
        cap: f64,
    }

    impl Profile {
        fn new(pf: &PhaseFunction) -> Self {
            let x: Vec<f64> = (0..=GRID_INTERVALS)
                .map(|j| {
                    2f64.powf(j as f64 / GRID_PER_OCTAVE as f64 - GRID_OCTAVES_BELOW_ONE as f64)
                })
                .collect();
            let integrate = |weight: &dyn Fn(f64) -> f64| -> Vec<f64> {
                // dmu = -x dw. p is evaluated at x itself: a cosine near 1 would
                // round to a staircase in x that biases the sum by ~1e-8.
                let f = |w: f64| {
                    let x = w.exp();
                    TWO_PI * pf.eval_one_minus_cos(x) * weight(1.0 - x) * x
                };
                x.windows(2)
                    .map(|pair| simpson(&f, pair[0].ln(), pair[1].ln(), 1e-16))
                    .collect()
            };
            let mass = integrate(&|_| 1.0);
            let moment = integrate(&|mu| mu);
            let x0 = x[0];
            let (p0, p1) = (pf.eval_one_minus_cos(x0), pf.eval_one_minus_cos(2.0 * x0));
            let s = (p1 / p0).log2();
            let cap = TWO_PI * p0 * x0 / (s + 1.0);
            Profile {
                x,
                mass,
                moment,
                cap,
            }
        }

        fn total(&self) -> f64 {
            self.mass.iter().sum::<f64>() + self.cap
        }

        fn mean_cos(&self) -> f64 {
            // In the cap mu = 1 to within 2^-50.
            self.moment.iter().sum::<f64>() + self.cap
        }

        fn backscatter(&self) -> f64 {
            self.mass[GRID_MU_ZERO..].iter().sum()
        }
    }

    fn profiles() -> &'static [(&'static str, PhaseFunction, Profile)] {
        static PROFILES: OnceLock<Vec<(&'static str, PhaseFunction, Profile)>> = OnceLock::new();
        PROFILES.get_or_init(|| {
            cases()
                .into_iter()
                .map(|(name, pf)| {
                    let profile = Profile::new(&pf);
                    (name, pf, profile)
                })
                .collect()
        })
    }

    /// Upper-tail chi-square quantile at p = 0.001 (Wilson–Hilferty).
    fn chi_square_critical(dof: usize) -> f64 {
        const Z_999: f64 = 3.090_232_306_167_813;
        let k = dof as f64;
        let c = 2.0 / (9.0 * k);
        k * (1.0 - c + Z_999 * c.sqrt()).powi(3)
    }

    /// Pearson chi-square of SAMPLES draws of `sample_cos` against the density.
    /// Bins hold about 1/100 of the probability each: grid intervals are
    /// gathered from the back (x = 2) forward until each bin reaches 1/100;
    /// the last bin takes the rest and the cap (every draw that rounds to
    /// mu = 1). Bins expecting fewer than 5 draws are merged. Returns
    /// (chi2, degrees of freedom).
    fn chi_square(pf: &PhaseFunction, profile: &Profile, seed: u64) -> (f64, usize) {
        const TARGET: f64 = 0.01;
        let total = profile.total();
        // Bin b holds x in [edges[b+1], edges[b]); edges decrease from 2 to 0.
        let mut edges = vec![2.0];
        let mut probs = Vec::new();
        let mut acc = 0.0;
        for j in (0..GRID_INTERVALS).rev() {
            acc += profile.mass[j] / total;
            if acc >= TARGET {
                edges.push(profile.x[j]);
                probs.push(acc);
                acc = 0.0;
            }
        }
        probs.push(acc + profile.cap / total);
        edges.push(0.0);
        // Merge bins expecting fewer than 5 draws into their backward neighbour.
        let min_prob = 5.0 / SAMPLES as f64;
        let mut b = probs.len();
        while b > 1 {
            b -= 1;
            if probs[b] < min_prob {
                probs[b - 1] += probs[b];
                probs.remove(b);
                edges.remove(b);
            }
        }
        let mut counts = vec![0u64; probs.len()];
        let mut rng = Pcg32::new(seed, 0);
        for _ in 0..SAMPLES {
            let x = 1.0 - pf.sample_cos(rng.uniform_f64());
            let bin = edges[1..].partition_point(|&e| e > x).min(probs.len() - 1);
            counts[bin] += 1;
        }
        let chi2 = counts
            .iter()
            .zip(&probs)
            .map(|(&c, &p)| {
                let e = p * SAMPLES as f64;
                (c as f64 - e).powi(2) / e
            })
            .sum();
        (chi2, probs.len() - 1)
    }

    /// Physical fact: every phase function integrates to 1 over the sphere.
    /// The quadrature is independent of the closed forms used for sampling
    /// and good to about 1e-14 on the grid; the power-law fit of the cap below
    /// 2^-50 adds up to 8e-10 (FF at B = 1e-4, whose cap holds 37 % of the
    /// probability), hence the tolerance of 2e-9.
    #[test]
    fn every_phase_function_integrates_to_one() {
        for (name, _, profile) in profiles() {
            let total = profile.total();
            eprintln!("{name}: integral {total:.15}");
            assert!((total - 1.0).abs() < 2e-9, "{name}: integral {total}");
        }
    }

    /// Chi-square goodness of fit of `sample_cos` against the density, at the
    /// p = 0.001 critical value: a correct sampler fails one case in 1000.
    #[test]
    fn samplers_pass_chi_square() {
        let mut failures = Vec::new();
        for (i, (name, pf, profile)) in profiles().iter().enumerate() {
            let (chi2, dof) = chi_square(pf, profile, 1000 + i as u64);
            let critical = chi_square_critical(dof);
            eprintln!("{name}: chi2 {chi2:.1} dof {dof} critical {critical:.1}");
            if chi2 >= critical {
                failures.push(format!("{name}: chi2 {chi2} >= {critical} (dof {dof})"));
            }
        }
        assert!(failures.is_empty(), "{failures:#?}");
    }

    /// The sample mean of sample_cos agrees with mean_cosine() within 4
    /// standard errors (sample standard deviation / sqrt(N)), and
    /// mean_cosine() agrees with the independent quadrature.
    #[test]
    fn sample_mean_cosine_within_four_standard_errors() {
        for (i, (name, pf, profile)) in profiles().iter().enumerate() {
            let g = pf.mean_cosine();
            let quadrature = profile.mean_cos();
            assert!(
                (g - quadrature).abs() < 1e-9,
                "{name}: mean_cosine {g} vs quadrature {quadrature}"
            );
            let mut rng = Pcg32::new(77, i as u64);
            let (mut sum, mut sum_sq) = (0.0, 0.0);
            for _ in 0..SAMPLES {
                let mu = pf.sample_cos(rng.uniform_f64());
                sum += mu;
                sum_sq += mu * mu;
            }
            let n = SAMPLES as f64;
            let mean = sum / n;
            let se = ((sum_sq / n - mean * mean) / (n - 1.0)).sqrt();
            eprintln!(
                "{name}: g {g:.9}, sample mean {mean:.6}, {:.2} se",
                (mean - g) / se
            );
            assert!(
                (mean - g).abs() < 4.0 * se,
                "{name}: {mean} vs {g}, se {se}"
            );
        }
    }

    /// backscatter_fraction() agrees with the independent quadrature over mu < 0.
    #[test]
    fn backscatter_fraction_matches_quadrature() {
        for (name, pf, profile) in profiles() {
            let (b, quadrature) = (pf.backscatter_fraction(), profile.backscatter());
            assert!(
                (b - quadrature).abs() < 1e-10,
                "{name}: {b} vs quadrature {quadrature}"
            );
        }
    }

    /// sample_cos is non-decreasing in u and stays in [-1, 1], from u = 0 to
    /// the largest u below 1 that uniform_f64 produces.
    #[test]
    fn samplers_are_monotone_and_in_range() {
        let mut us: Vec<f64> = (0..=4000).map(|i| i as f64 / 4001.0).collect();
        us.extend([1.0 - 1e-9, 1.0 - 1e-12, 1.0 - f64::EPSILON / 2.0]);
        for (name, pf) in cases() {
            let mut prev = -1.0;
            for &u in &us {
                let mu = pf.sample_cos(u);
                assert!((-1.0..=1.0).contains(&mu), "{name}: u {u} gave {mu}");
                assert!(mu >= prev - 1e-12, "{name}: not monotone at u {u}");
                prev = mu;
            }
        }
    }

    /// The two exact HG inversions agree where they meet.
    #[test]
    fn hg_inversions_agree() {
        for g in [0.2, 0.5, 0.7, -0.5] {
            for i in 0..=100 {
                let u = i as f64 / 100.0;
                let (a, b) = (hg_sample_cos_expanded(g, u), hg_sample_cos_classic(g, u));
                assert!((a - b).abs() < 1e-13, "g {g} u {u}: {a} vs {b}");
            }
        }
    }

    /// Pure water (OPTICS.md): q = 0.835 gives p(90°) = 0.06225 sr^-1.
    #[test]
    fn rayleigh_water_value() {
        let p = PhaseFunction::rayleigh(RAYLEIGH_Q_WATER).unwrap().eval(0.0);
        assert!((p - 0.06225).abs() < 5e-6, "{p}");
    }

    /// eval and eval_one_minus_cos agree wherever the cosine is exact.
    #[test]
    fn eval_forms_agree() {
        for (name, pf) in cases() {
            for i in 0..=200 {
                let mu = -1.0 + i as f64 / 100.0;
                let (a, b) = (pf.eval(mu), pf.eval_one_minus_cos(1.0 - mu));
                assert!((a / b - 1.0).abs() < 1e-12, "{name} mu {mu}: {a} vs {b}");
            }
        }
    }

    /// `scatter` returns unit vectors at the requested cosine to w, for w
    /// anywhere including the poles the basis construction must survive.
    #[test]
    fn scatter_returns_unit_vector_at_requested_cosine() {
        let mut rng = Pcg32::new(5, 0);
        let mut ws = vec![
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(1e-7, 0.0, -1.0).normalize(),
        ];
        for _ in 0..1000 {
            let z = 2.0 * rng.uniform_f32() - 1.0;
            let phi = std::f32::consts::TAU * rng.uniform_f32();
            let r = (1.0 - z * z).max(0.0).sqrt();
            ws.push(Vec3::new(r * phi.cos(), r * phi.sin(), z));
        }
        for w in ws {
            for _ in 0..20 {
                let cos = 2.0 * rng.uniform_f32() - 1.0;
                let phi = std::f32::consts::TAU * rng.uniform_f32();
                let d = scatter(w, cos, phi);
                assert!(
                    (d.length() - 1.0).abs() < 1e-5,
                    "{w} {cos}: |d| {}",
                    d.length()
                );
                assert!((d.dot(w) - cos).abs() < 1e-5, "{w} {cos}: {}", d.dot(w));
            }
            for cos in [1.0, -1.0] {
                let d = scatter(w, cos, 0.3);
                assert!((d.dot(w) - cos).abs() < 1e-6);
            }
        }
        // sample_direction keeps the sampled cosine.
        let pf = PhaseFunction::henyey_greenstein(0.8).unwrap();
        for i in 0..100 {
            let u = [i as f64 / 100.0, 0.37];
            let d = pf.sample_direction(Vec3::Y, u);
            assert!((d.dot(Vec3::Y) as f64 - pf.sample_cos(u[0])).abs() < 1e-5);
        }
    }

    fn field_of(result: Result<PhaseFunction>) -> String {
        match result {
            Err(Error::Invalid { field, .. }) => field,
            other => panic!("expected an invalid-field error, got {other:?}"),
        }
    }

    /// Bad parameters are errors naming the field, not panics.
    #[test]
    fn bad_parameters_name_the_field() {
        for g in [1.0, -1.0, 1.5, f64::NAN, f64::INFINITY] {
            assert_eq!(field_of(PhaseFunction::henyey_greenstein(g)), "g");
        }
        for q in [-0.1, 1.5, f64::NAN] {
            assert_eq!(field_of(PhaseFunction::rayleigh(q)), "q");
        }
        for bb in [0.0, 5e-5, 0.2, -0.01, f64::NAN] {
            assert_eq!(field_of(PhaseFunction::fournier_forand(bb)), "bb_ratio");
        }
        let ff = |n, mu| FournierForand::new(n, mu).map(PhaseFunction::FournierForand);
        assert_eq!(field_of(ff(1.0, 3.5)), "n");
        assert_eq!(field_of(ff(f64::NAN, 3.5)), "n");
        assert_eq!(field_of(ff(1.1, 3.0)), "mu");
        assert_eq!(field_of(ff(1.1, 5.5)), "mu");
        let table = |a: &[f64], v: &[f64]| PhaseFunction::tabulated(a, v, "water.phase_table");
        let bad: [(&[f64], &[f64]); 10] = [
            (&[0.0, 180.0], &[1.0]),
            (&[90.0], &[1.0]),
            (&[], &[]),
            (&[0.0, 90.0, 45.0], &[1.0, 1.0, 1.0]),
            (&[0.0, 90.0, 90.0], &[1.0, 1.0, 1.0]),
            (&[0.0, 181.0], &[1.0, 1.0]),
            (&[-1.0, 180.0], &[1.0, 1.0]),
            (&[0.0, f64::NAN], &[1.0, 1.0]),
            (&[0.0, 180.0], &[1.0, -0.5]),
            (&[0.0, 180.0], &[0.0, 0.0]),
        ];
        for (angles, values) in bad {
            assert_eq!(field_of(table(angles, values)), "water.phase_table");
        }
        assert_eq!(
            field_of(table(&[0.0, 180.0], &[1.0, f64::NAN])),
            "water.phase_table"
        );
        let message = table(&[0.0, 181.0], &[1.0, 1.0]).unwrap_err().to_string();
        assert!(message.starts_with("water.phase_table: "), "{message}");
    }
}
