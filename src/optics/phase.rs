//! Phase functions of ocean optics, each with an exact sampler.
//!
//! A phase function p(mu) [sr^-1] is the angular distribution of one
//! scattering event over mu = cos(psi), psi the angle between the directions
//! of travel before and after. Every model here is normalised,
//! 2 pi int_{-1}^{1} p(mu) dmu = 1, and `sample_cos` maps one uniform number to
//! a cosine distributed as 2 pi p(mu) dmu: closed-form inversion, a
//! safeguarded Newton solve of the exact CDF to round-off, or (Fournier–
//! Forand) cubic Hermite interpolation in a table of the CDF's exact roots
//! and slopes, within 2e-10 in ln sin^2(psi/2) of the root (tested):
//! never a fitted approximation of the phase function.
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
mod lookup;
mod tabulated;

pub use fournier_forand::{FournierForand, FF_BB_RATIO_RANGE};
pub use lookup::PhaseLookup;
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

    /// The bytes it holds on the heap (a table's).
    pub fn heap_bytes(&self) -> u64 {
        match self {
            PhaseFunction::Tabulated(t) => t.heap_bytes(),
            _ => 0,
        }
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
            PhaseFunction::Rayleigh { q } => rayleigh_density(*q, 1.0 - x),
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

/// Scattering by two phase functions at once: `q` of it by `first` (pure
/// water), the rest by `second` (particles).
pub struct Mixture<'a> {
    pub first: &'a PhaseFunction,
    pub second: &'a PhaseFunction,
    pub q: f64,
}

impl Mixture<'_> {
    /// The density per sr at `m` = 1 - cos of the scattering angle.
    pub fn eval_one_minus_cos(&self, m: f64) -> f64 {
        self.q * self.first.eval_one_minus_cos(m)
            + (1.0 - self.q) * self.second.eval_one_minus_cos(m)
    }

    /// A direction drawn from the mixture around unit `axis` (the cosine's
    /// uniform first, then the choice of function, then the azimuth).
    pub fn sample_around(&self, axis: Vec3, rng: &mut crate::rng::Pcg32) -> Vec3 {
        let u = rng.uniform_f64();
        let mu = if rng.uniform_f64() < self.q {
            self.first.sample_cos(u)
        } else {
            self.second.sample_cos(u)
        };
        let phi = TWO_PI * rng.uniform_f64();
        scatter(axis, mu as f32, phi as f32)
    }
}

/// Cosine-weighted (Lambertian) direction of travel in the hemisphere
/// around the unit normal `n`.
pub fn cosine_hemisphere(n: Vec3, rng: &mut crate::rng::Pcg32) -> Vec3 {
    // cos(theta) = sqrt(u) has density 2 cos(theta) sin(theta): Lambertian.
    let cos_theta = rng.uniform_f64().sqrt();
    let phi = std::f64::consts::TAU * rng.uniform_f64();
    scatter(n, cos_theta as f32, phi as f32)
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
fn solve_increasing(lo: f64, hi: f64, x0: f64, tol: f64, f: impl Fn(f64) -> (f64, f64)) -> f64 {
    solve_increasing_quadratic(lo, hi, x0, 0.0, tol, f)
}

/// As [`solve_increasing`], for an `f` whose Newton steps converge
/// quadratically from the start: a Newton step of at most `last_step`
/// (whose square is below the wanted precision) is the last one.
fn solve_increasing_quadratic(
    mut lo: f64,
    mut hi: f64,
    x0: f64,
    last_step: f64,
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
        let (next, converging) = if dfx > 0.0 && newton > lo && newton < hi {
            (newton, (newton - x).abs() <= last_step)
        } else {
            (0.5 * (lo + hi), false)
        };
        if converging || (next - x).abs() <= tol || hi - lo <= tol {
            return next;
        }
        x = next;
    }
    x
}

/// The Rayleigh-like phase function 3 (1 + q mu^2) / (4 pi (3 + q)) at
/// cosine `mu` (sr^-1); written out for loops that inline it (the sky's
/// local estimates).
#[inline]
pub fn rayleigh_density(q: f64, mu: f64) -> f64 {
    3.0 / (FOUR_PI * (3.0 + q)) * (1.0 + q * mu * mu)
}

#[cfg(test)]
mod tests;
