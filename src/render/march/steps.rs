//! How a march divides its ray: steps paced by the light along it
//! ([`stretch`]), steps that run on across turns ([`Step`]), and the
//! turns drawn at a hero band's rate for all bands ([`PeakTurns`]).

use crate::rng::Pcg32;

/// The longest step, as a multiple of the course's, where the ray's
/// transmittance has fallen (see [`stretch`]): reached at T = 1/16.
pub(super) const STEP_STRETCH_MAX: f32 = 4.0;
/// What is left of a step below this (m) is rounding: a new step starts.
pub(super) const STEP_REST_EPS_M: f32 = 1e-5;

/// How many times its course's step a march's next step takes: 1 /
/// sqrt(T), for T the largest transmittance of any band so far (MIS
/// weights of a hero band's turns included), from 1 up to `max`.
///
/// One jittered sample per step is unbiased for any partition of the
/// ray, so the steps may follow what is left of the light. A step's part
/// of the pixel falls as T, and the jitter's error in it as T times the
/// square of its length (the source varies across the step about
/// linearly): for the error of N steps over a given ray, sum T_i L_i^4
/// with sum L_i fixed, the best steps are 1 / sqrt(T) long. Measured on
/// the built-in scene from 3 km with a reused map (`max` 4), one run
/// each, against fixed steps (65.5 s render, L_w pixel noise over deep
/// water 2.62 / 3.00 / 3.57 % at 413 / 526 / 671 nm): 1 / sqrt(T) 53.0 s
/// and 2.92 / 3.11 / 3.77 %, at least as little noise for the time in
/// every band; 1 / T 47.5 s, but 3.35 / 3.28 / 4.02 %, more noise for
/// the time in the blue; 1 / T^2 (at most 8) 42.0 s and 5.44 / 4.63 /
/// 4.73 %. Band means over deep water, the shallow sand and the image
/// stayed within 0.08 % (`benches/README.md`, "Rendering").
pub(super) fn stretch(tr: &[f64], max: f32) -> f32 {
    let t = light_left(tr);
    if t > 0.0 {
        (1.0 / t.sqrt()).clamp(1.0, f64::from(max)) as f32
    } else {
        max
    }
}

/// The largest transmittance of any band in `tr`.
fn light_left(tr: &[f64]) -> f64 {
    tr.iter().fold(0.0f64, |m, &t| m.max(t))
}

/// The smallest share of the scene's searches a paced march's estimate
/// takes (see [`search_share`]).
pub(super) const SEARCH_SHARE_MIN: f64 = 0.1;

/// The share of the scene's searches an estimate takes where the march's
/// transmittance is `tr`: T, the largest of any band so far, from `min`
/// up to 1. The estimate then finds T times the scene's k and k_expanded
/// photons within T^(1/3) times its radii (`Estimator::volume_with_iops`).
///
/// Why: an estimate's photons cost time in proportion to their number,
/// while its part of the pixel falls with T. With steps 1 / sqrt(T) long
/// ([`stretch`]) an estimate weighs T / sqrt(T) = sqrt(T) in its pixel,
/// and its noise variance there goes as T / k: for a given variance the
/// fewest photons are k ~ sqrt(T). The march's other noise (its jitter,
/// the sun's single scattering, the air's) leaves room for fewer; as
/// measured on the built-in scene from 3 km with a reused map, against
/// whole searches (one run each; paired runs for the time, two pairs,
/// 0.84 x the wall time for T with a floor of 0.1):
/// T^0.5 (floor 0.1) 0.90 x the render time, L_w noise over deep water
/// 3.08 / 3.20 / 3.86 % at 413 / 526 / 671 nm against 3.00 / 3.11 /
/// 3.85 %; T^0.75 0.85 x, 3.12 / 3.27 / 3.87 %; T 0.80 x, 3.19 / 3.39 /
/// 3.87 % (noise squared times the paired time, 0.95 / 0.99 / 0.85 of
/// whole searches'); T^1.5 (floor 0.05) 0.75 x, 3.35 / 3.72 / 3.89 %,
/// more noise for the time at 526 nm. The floor keeps 20 photons in the
/// local search at the default k of 200. A smaller search is a
/// sharper kernel over the same density, so the estimate's expectation
/// changes only by its smoothing. In the same runs, which share their
/// random draws so that the difference is the kernel's own, L_w's band
/// means per 50 nm over deep water, the shallow sand and the whole image
/// moved by at most 0.11 %, and on the panel and the dark box (3 x 3
/// pixels, per 100 nm) by -0.5 % to +0.4 % (`benches/README.md`,
/// "Rendering").
pub(super) fn search_share(tr: &[f64], min: f64) -> f64 {
    light_left(tr).clamp(min, 1.0)
}

/// A march step of arc length `len` along the ray, turns included: `rest`
/// of it is still to be marched, and its photon estimate is taken `at`
/// that far on (none once taken, or when the ray ended before it).
///
/// Why: the ray turns into the particles' forward peak about every 2 m
/// in the built-in scene, and a step that ended at each turn made an
/// estimate for every straight run however short. One jittered sample in
/// each stretch of arc length is unbiased for the march's integral along
/// the bent ray, as along a straight one; what a turn changes is which
/// direction the sample looks along. Each straight piece still takes its
/// own sample for the sun's single scattering (in closed form over the
/// piece), which costs a hundredth of an estimate. Rays that turn at a
/// hero band's rate ([`PeakTurns`]) end their step at a turn as before:
/// their bands' weights change along the step.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Step {
    pub(super) len: f32,
    pub(super) rest: f32,
    pub(super) at: Option<f32>,
}

/// Turns into the particles' forward peak drawn at one band's rate for
/// all bands, on rays where the peak's delta would take the radiance
/// inside its cone to be the ray's own (looking down at a target). Each
/// march draws a hero band h uniformly and turns at its rate sigma_h =
/// f_p b_p(h); band b weighs the run by one-sample MIS over the hero's
/// choice (balance heuristic), p_b / mean_j p_j, where p_j = prod(sigma_j
/// at the turns) exp(-integral sigma_j) is the probability density of the
/// turns drawn so far at band j's own rate. So every band's particle peak
/// is scattered into exactly, none is kept as a delta, and a band's weight
/// stays within a small factor of 1 (drawn at the smallest rate instead,
/// the weights' second moment reached e^7 for a band of twice that rate
/// over seven turns; the mixture's stays below 2.1).
pub(super) struct PeakTurns {
    pub(super) hero: usize,
    /// ln p_b, normalised so that mean_b p_b = 1: the run's MIS weight
    /// for band b is exp(log_p[b]), already folded into the transmittance.
    pub(super) log_p: Vec<f64>,
    /// Each band's rate of turning, f_p b_p, at the step's sample.
    pub(super) sigma: Vec<f64>,
    /// Within a step: each band's weight at the sample relative to the
    /// weight at the step's start.
    pub(super) at_sample: Vec<f64>,
}

impl PeakTurns {
    pub(super) fn new(nb: usize, rng: &mut Pcg32) -> Self {
        PeakTurns {
            hero: rng.below(nb as u32) as usize,
            log_p: vec![0.0; nb],
            sigma: vec![0.0; nb],
            at_sample: vec![1.0; nb],
        }
    }

    /// The factors by which each band's weight changes when the run goes
    /// on `len` (m) without a turn, and with one at its end when `turned`,
    /// into `factor`; with `commit`, `log_p` moves there too.
    pub(super) fn advance(&mut self, len: f64, turned: bool, commit: bool, factor: &mut [f64]) {
        let step = |s: f64| {
            let mut d = -s * len;
            if turned {
                d += s.ln();
            }
            d
        };
        let top = self
            .log_p
            .iter()
            .zip(&self.sigma)
            .fold(f64::NEG_INFINITY, |m, (l, &s)| m.max(l + step(s)));
        let mean = self
            .log_p
            .iter()
            .zip(&self.sigma)
            .map(|(l, &s)| (l + step(s) - top).exp())
            .sum::<f64>()
            / self.log_p.len() as f64;
        let q = top + mean.ln();
        for ((f, l), &s) in factor
            .iter_mut()
            .zip(self.log_p.iter_mut())
            .zip(&self.sigma)
        {
            let d = step(s) - q;
            *f = d.exp();
            if commit {
                *l += d;
            }
        }
    }
}
