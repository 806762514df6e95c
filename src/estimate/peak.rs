//! Phase functions as the photon-map estimate sees them: the forward peak
//! truncated into a delta (the delta-M idea of Wiscombe 1977, applied to
//! the rendering equation along a sensor ray).
//!
//! A photon's contribution is weighted by p(w_p . w). With a forward-peaked
//! particle phase function (Fournier–Forand, Petzold: p reaches 10^3–10^4
//! sr^-1 within a degree) one photon travelling almost exactly toward the
//! viewer outweighs thousands of others, and the estimate becomes speckle.
//!
//! Write p = f delta(w' - w) + p*, where p* equals p outside a cone of
//! half-angle theta_t around the forward direction and is flat inside it
//! (p* = p(theta_t)), and f = 1 - integral of p* is the excess mass of the
//! peak. Along a ray, the delta part scatters light of the ray's own
//! direction back into it: dL/dt = -c L + f b L + b integral(p* L) + ...,
//! so L is marched with the reduced extinction c - f b and the photons are
//! weighted by p*. This is exact except that the radiance inside the peak
//! (a few degrees) is taken as the radiance along the ray itself, which is
//! smooth there — except over a target smaller than the cone's footprint
//! on it, or where the light brightens toward the sun inside the cone, so
//! rays scatter into the particles' delta
//! explicitly (`render::march`, drawing directions from the delta's own
//! shape with [`TruncatedPhase::sample_peak`]) instead of keeping it. Single scattering of the sun keeps the exact phase
//! function and the full extinction, since the direct beam is not in the
//! photon map.
//!
//! theta_t is `[estimate] forward_peak_deg` along rays looking up or
//! sideways (default [`crate::scene::settings::DEFAULT_FORWARD_PEAK_DEG`]) and `forward_peak_down_deg`
//! along rays looking down (default
//! [`crate::scene::settings::DEFAULT_FORWARD_PEAK_DOWN_DEG`]), and
//! `forward_peak_target_deg` along rays looking down at a target (default
//! [`crate::scene::settings::DEFAULT_FORWARD_PEAK_TARGET_DEG`]; see
//! `render::march`); 0 = the exact phase function, f = 0.
//!
//! Measured in deep water (a = 0.3, b = 0.6, Fournier–Forand bb = 0.02, 10 M
//! photons, 8 identical bands, 4 positions), as the ratio of radiometers to
//! the emission tallies of radiance within 10 degrees of straight up or
//! down (band means with 2 % standard error at 0 and 1 m and 6 % at 6 m for
//! Lu; 0.5 % for Ld). Nadir view, sun at 20 degrees, k = 800 with the
//! expanded search of 800 (no photons counted at the expanded scale) or
//! 6400 (`k_expanded`; see `estimate::estimator`):
//!
//! | theta_t | k_expanded | 0.01 m | 1 m | 6 m | spread over bands |
//! |---|---|---|---|---|---|
//! | 10 deg | 800 | 1.057 | 1.023 | 0.987 | 9-14 % |
//! | 10 deg | 6400 | 1.036 | 1.007 | 1.036 | 5-10 % |
//! | 20 deg | 800 | 1.047 | 1.003 | 1.033 | 4-9 % |
//! | 20 deg | 6400 | 1.039 | 0.996 | 1.051 | 2-6 % |
//!
//! (With k = 3200 and no expanded scale: 5 deg 1.035 / 1.013 / 0.975, 10 deg
//! 1.046 / 1.007 / 1.027.) Looking up (zenith view) with the sun at 60
//! degrees, so that its aureole is far from the view: 0.978 / 0.911 at 1 and
//! 6 m with 5 deg (noisy), 0.968 / 0.960 with 10 deg, 0.947 / 0.946 with
//! 20 deg — the delta takes the radiance inside the peak to be the ray's
//! own, and looking up the light field brightens toward the sun, so a wider
//! peak reads lower. With the sun at 20 degrees the zenith view is 15
//! degrees from the refracted sun and the 20-degree delta reads 10 %
//! below the 10-degree one (no oracle there: the tally's 10-degree cone
//! reaches into the aureole). Each ray's equation holds for any theta_t, so
//! the angle is chosen by where the ray looks: 10 degrees looking up or
//! sideways (`forward_peak_deg`), 20 looking down into the smooth upwelling
//! light (`forward_peak_down_deg`), where it cuts the pixel noise of the
//! built-in scene from 9.3 % to 6.9 % per band at no measured bias.
//! Averaging the phase
//! function over a cone instead (tried first) smooths the radiance the
//! forward peak re-scatters over the whole cone, and biased the decay of
//! upwelling radiance low (K_Lu 0.279 1/m against Kd 0.358 with a 30-degree
//! cone). p* is tabulated in cos(theta), which also
//! makes the estimate's inner loop a table lookup; f is the integral of the
//! table itself, so the split conserves scattering exactly as evaluated.

use crate::optics::phase::PhaseFunction;
use crate::rng::Pcg32;
use glam::Vec3;

/// Rejections before [`TruncatedPhase::sample_peak`] returns a weighted draw.
const PEAK_TRIES: usize = 64;

/// Table entries over cos(theta) in [-1, 1].
const TABLE: usize = 8192;

/// A phase function with its forward peak replaced by a flat top, and the
/// removed fraction.
#[derive(Clone, Debug)]
pub struct TruncatedPhase {
    table: Vec<f64>,
    /// The fraction f of scattering moved into the forward delta.
    forward: f64,
    /// Without truncation the exact phase function is used.
    exact: Option<PhaseFunction>,
    /// Directions inside the delta, for rays that scatter into the peak
    /// explicitly (`render::march`); None without a delta.
    peak: Option<PeakSampling>,
}

/// Draws directions with the density of the forward delta's own shape,
/// (p - p(theta_t)) / f on the cone theta < theta_t: the cosine from p
/// restricted to the cone (its inverse CDF on [u_t, 1)), weighted by the
/// ratio of the two densities, (1 - p_t / p) P_cone / f. The weight is at
/// most P_cone / f and close to 1 for a peaked phase function.
#[derive(Clone, Debug)]
struct PeakSampling {
    phase: PhaseFunction,
    /// The CDF of p at cos(theta_t).
    u_t: f64,
    /// p(theta_t) (sr^-1).
    p_t: f64,
    /// P_cone / f, with f = P_cone - p_t 2 pi (1 - cos theta_t) the
    /// delta's mass.
    scale: f64,
    /// f itself.
    mass: f64,
    /// 1 - cos theta_t.
    x_t: f64,
}

impl PeakSampling {
    fn new(p: &PhaseFunction, cos_t: f64) -> Option<Self> {
        // Bisection for the CDF at cos_t: sample_cos is non-decreasing in u.
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for _ in 0..64 {
            let mid = 0.5 * (lo + hi);
            if p.sample_cos(mid) < cos_t {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let u_t = hi;
        let p_t = p.eval(cos_t);
        let cone = 1.0 - u_t;
        let mass = cone - p_t * std::f64::consts::TAU * (1.0 - cos_t);
        (mass > 1e-9 * cone && cone > 0.0).then(|| PeakSampling {
            phase: p.clone(),
            u_t,
            p_t,
            scale: cone / mass,
            mass,
            x_t: 1.0 - cos_t,
        })
    }
}

impl TruncatedPhase {
    /// Truncate `p` at `peak_half_angle_deg` (0 keeps it exact).
    pub fn new(p: &PhaseFunction, peak_half_angle_deg: f64) -> Self {
        if peak_half_angle_deg < 1e-3 {
            return TruncatedPhase {
                table: Vec::new(),
                forward: 0.0,
                exact: Some(p.clone()),
                peak: None,
            };
        }
        let cos_t = peak_half_angle_deg.to_radians().cos();
        let cap = p.eval(cos_t);
        let table: Vec<f64> = (0..TABLE)
            .map(|i| {
                let mu = -1.0 + 2.0 * i as f64 / (TABLE - 1) as f64;
                let v = p.eval(mu);
                if mu > cos_t {
                    v.min(cap)
                } else {
                    v
                }
            })
            .collect();
        // The table is evaluated by linear interpolation: its integral is the
        // trapezoid sum, exactly.
        let h = 2.0 / (TABLE - 1) as f64;
        let integral = std::f64::consts::TAU
            * h
            * (table.iter().sum::<f64>() - 0.5 * (table[0] + table[TABLE - 1]));
        TruncatedPhase {
            table,
            forward: (1.0 - integral).max(0.0),
            exact: None,
            peak: PeakSampling::new(p, cos_t),
        }
    }

    /// The density per sr of [`Self::sample_peak`]'s directions `to`
    /// around `w` (unit vectors): (p - p_t) / f inside the cone, 0 outside
    /// it and without a delta.
    pub fn peak_density(&self, w: Vec3, to: Vec3) -> f64 {
        let Some(s) = self.peak.as_ref() else {
            return 0.0;
        };
        let x = 0.5 * (to - w).length_squared() as f64;
        if x > s.x_t {
            return 0.0;
        }
        (s.phase.eval_one_minus_cos(x) - s.p_t).max(0.0) / s.mass
    }

    /// The cone's half-angle (radians), 0 without a delta.
    pub fn peak_half_angle(&self) -> f64 {
        self.peak.as_ref().map_or(0.0, |s| (1.0 - s.x_t).acos())
    }

    /// A direction of travel scattered into the forward delta from `w`,
    /// with its weight (mean 1): the delta's own angular shape, p - p_t
    /// on the cone, rather than `w` itself. None without a delta.
    ///
    /// By rejection (a draw of p on the cone is kept with probability
    /// 1 - p_t / p), so that the weight is 1: a ray turns several times,
    /// and weights of a few tenths multiplied along it were pixel noise
    /// (12 % in deep Fournier–Forand water). After [`PEAK_TRIES`]
    /// rejections (a delta of a few per cent of its cone's mass) a fresh
    /// draw is returned with its weight, (1 - p_t / p) P_cone / f, which
    /// keeps the mean exact.
    pub fn sample_peak(&self, w: Vec3, rng: &mut Pcg32) -> Option<(Vec3, f64)> {
        let s = self.peak.as_ref()?;
        let draw = |rng: &mut Pcg32| {
            let u = s.u_t + (1.0 - s.u_t) * rng.uniform_f64();
            let v = rng.uniform_f64();
            let p = s.phase.eval(s.phase.sample_cos(u));
            let keep = if p > 0.0 {
                (1.0 - s.p_t / p).max(0.0)
            } else {
                0.0
            };
            (s.phase.sample_direction(w, [u, v]), keep)
        };
        for _ in 0..PEAK_TRIES {
            let (d, keep) = draw(rng);
            if rng.uniform_f64() < keep {
                return Some((d, 1.0));
            }
        }
        let (d, keep) = draw(rng);
        Some((d, keep * s.scale))
    }

    /// The fraction of scattering in the forward delta.
    pub fn forward_fraction(&self) -> f64 {
        self.forward
    }

    /// p* at cos(theta) (sr^-1), linear between table entries.
    #[inline]
    pub fn eval(&self, mu: f64) -> f64 {
        if let Some(p) = &self.exact {
            return p.eval(mu);
        }
        let (i, t) = table_at(mu);
        self.table[i] * (1.0 - t) + self.table[i + 1] * t
    }
}

/// The table entry at or below cos(theta) = `mu` and the fraction of the
/// way to the next (`mu` clamped to [-1, 1]).
#[inline]
fn table_at(mu: f64) -> (usize, f64) {
    let x = (mu.clamp(-1.0, 1.0) + 1.0) * 0.5 * (TABLE - 1) as f64;
    let i = (x as usize).min(TABLE - 2);
    (i, x - i as f64)
}

/// The truncated phase functions of pure water and of the particles,
/// tabulated side by side as well: a photon's weight is the two mixed at
/// one cosine, and with the rows interleaved both values come from one
/// cache line instead of two tables of 64 KiB (the default render 2 %
/// faster).
#[derive(Clone, Debug)]
pub struct MixedPhase {
    parts: [TruncatedPhase; 2],
    /// [water, particle] at each entry of the tables, where both are
    /// tabulated (empty where either is exact).
    pairs: Vec<[f64; 2]>,
}

impl MixedPhase {
    /// The mixture of `water` and `particle`.
    pub fn new(water: TruncatedPhase, particle: TruncatedPhase) -> Self {
        let pairs = if water.exact.is_none() && particle.exact.is_none() {
            water
                .table
                .iter()
                .zip(&particle.table)
                .map(|(&w, &p)| [w, p])
                .collect()
        } else {
            Vec::new()
        };
        MixedPhase {
            parts: [water, particle],
            pairs,
        }
    }

    /// [water, particle].
    pub fn parts(&self) -> &[TruncatedPhase; 2] {
        &self.parts
    }

    /// fw p*_w(mu) + (1 - fw) p*_p(mu) (sr^-1): the pure-water share `fw`
    /// of scattering, each part as its own [`TruncatedPhase::eval`] gives
    /// it, to the bit.
    #[inline]
    pub fn mix(&self, fw: f64, mu: f64) -> f64 {
        if self.pairs.is_empty() {
            let [w, p] = &self.parts;
            return fw * w.eval(mu) + (1.0 - fw) * p.eval(mu);
        }
        let (i, t) = table_at(mu);
        let (a, b) = (self.pairs[i], self.pairs[i + 1]);
        fw * (a[0] * (1.0 - t) + b[0] * t) + (1.0 - fw) * (a[1] * (1.0 - t) + b[1] * t)
    }
}

#[cfg(test)]
mod tests;
