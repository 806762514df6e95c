//! Phase functions as seen by the photon-map estimate: averaged over a cone.
//!
//! A photon's contribution is weighted by p(w_p . w). With a forward-peaked
//! particle phase function (Fournier–Forand, Petzold: p reaches 10^3–10^4
//! sr^-1 within a degree) one photon travelling almost exactly toward the
//! viewer outweighs thousands of others, and the estimate becomes speckle.
//! The underwater light field is smooth in angle over a few degrees, so the
//! estimate may use the phase function averaged over a cone (a convolution
//! on the sphere: normalisation is kept; the forward peak is spread over
//! the cone). The half-angle is `[estimate] phase_cone_deg` (default
//! [`DEFAULT_CONE_HALF_ANGLE_DEG`]; 0 = the exact phase function). It trades
//! bias for noise: in deep water (a = 0.3, b = 0.6, Fournier–Forand
//! bb = 0.02, 2 M photons, k = 800) the decay rate of Lu over 1–6 m was
//! 0.279 1/m with 30 degrees against Kd = 0.358 (biased low), and 0.329 and
//! 0.521 in two bands of identical water with 10 degrees (noise). Single scattering of
//! the sun is computed with the exact phase function. The smoothed function
//! is tabulated in cos(theta), which also makes the estimate's inner loop a
//! table lookup.

use crate::optics::phase::PhaseFunction;

/// Default half-angle of the smoothing cone (degrees).
pub const DEFAULT_CONE_HALF_ANGLE_DEG: f64 = 30.0;
const TABLE: usize = 1024;
/// Quantiles of the phase function used to integrate it.
const QUANTILES: usize = 8192;

/// A cone-averaged phase function tabulated over cos(theta) in [-1, 1].
#[derive(Clone, Debug)]
pub struct SmoothedPhase {
    table: Vec<f64>,
    /// Without smoothing the exact phase function is used.
    exact: Option<PhaseFunction>,
}

impl SmoothedPhase {
    /// Tabulate the cone average of `p`. The average over the cap around
    /// direction w0 is an integral over scattering angles of the azimuth
    /// length of each ring that lies in the cap; it is taken over the
    /// phase function's own quantiles (exact samples), so a forward peak far
    /// narrower than the table is integrated exactly.
    pub fn new(p: &PhaseFunction, cone_half_angle_deg: f64) -> Self {
        if cone_half_angle_deg < 1e-3 {
            return SmoothedPhase {
                table: Vec::new(),
                exact: Some(p.clone()),
            };
        }
        let cos_a = cone_half_angle_deg.to_radians().cos();
        let mus: Vec<f64> = (0..QUANTILES)
            .map(|j| p.sample_cos((j as f64 + 0.5) / QUANTILES as f64))
            .collect();
        let cap = std::f64::consts::TAU * (1.0 - cos_a);
        let table = (0..TABLE)
            .map(|i| {
                let mu0 = -1.0 + 2.0 * i as f64 / (TABLE - 1) as f64;
                let s0 = (1.0 - mu0 * mu0).max(0.0).sqrt();
                let inside: f64 = mus
                    .iter()
                    .map(|&mu| {
                        let s = (1.0 - mu * mu).max(0.0).sqrt();
                        let denom = s * s0;
                        if denom < 1e-12 {
                            return if mu * mu0 >= cos_a {
                                std::f64::consts::TAU
                            } else {
                                0.0
                            };
                        }
                        let c = (cos_a - mu * mu0) / denom;
                        if c <= -1.0 {
                            std::f64::consts::TAU
                        } else if c >= 1.0 {
                            0.0
                        } else {
                            2.0 * c.acos()
                        }
                    })
                    .sum::<f64>()
                    / QUANTILES as f64;
                // Fraction of scattered light landing in the cap, per steradian.
                inside / std::f64::consts::TAU / cap
            })
            .collect();
        SmoothedPhase { table, exact: None }
    }

    /// Smoothed p at cos(theta) (sr^-1), linear between table entries.
    #[inline]
    pub fn eval(&self, mu: f64) -> f64 {
        if let Some(p) = &self.exact {
            return p.eval(mu);
        }
        let x = (mu.clamp(-1.0, 1.0) + 1.0) * 0.5 * (TABLE - 1) as f64;
        let i = (x as usize).min(TABLE - 2);
        let t = x - i as f64;
        self.table[i] * (1.0 - t) + self.table[i + 1] * t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Smoothing keeps normalisation and caps the forward peak.
    #[test]
    fn smoothed_phase_integrates_to_one_and_flattens_the_peak() {
        for p in [
            PhaseFunction::petzold(),
            PhaseFunction::fournier_forand(0.0183).unwrap(),
            PhaseFunction::isotropic(),
        ] {
            let s = SmoothedPhase::new(&p, DEFAULT_CONE_HALF_ANGLE_DEG);
            let n = 200_000;
            let integral: f64 = (0..n)
                .map(|i| s.eval(-1.0 + 2.0 * (i as f64 + 0.5) / n as f64))
                .sum::<f64>()
                * 2.0
                / n as f64
                * 2.0
                * std::f64::consts::PI;
            // Quantile integration with 8192 quantiles: measured error 2e-5.
            assert!((integral - 1.0).abs() < 1e-4, "{integral}");
        }
        for p in [
            PhaseFunction::petzold(),
            PhaseFunction::fournier_forand(0.0183).unwrap(),
        ] {
            let s = SmoothedPhase::new(&p, DEFAULT_CONE_HALF_ANGLE_DEG);
            assert!(
                s.eval(1.0) < 0.01 * p.eval(1.0),
                "the forward peak is spread over the cone"
            );
            // At mu0 = 1 the average is the cap's share of scattering per steradian.
            let cap =
                std::f64::consts::TAU * (1.0 - DEFAULT_CONE_HALF_ANGLE_DEG.to_radians().cos());
            let share = 1.0
                - (0..100_000)
                    .filter(|&i| {
                        p.sample_cos((i as f64 + 0.5) / 1e5)
                            < DEFAULT_CONE_HALF_ANGLE_DEG.to_radians().cos()
                    })
                    .count() as f64
                    / 1e5;
            assert!((s.eval(1.0) * cap / share - 1.0).abs() < 2e-3);
        }
        let exact = SmoothedPhase::new(&PhaseFunction::petzold(), 0.0);
        assert_eq!(exact.eval(0.7), PhaseFunction::petzold().eval(0.7));
        let iso = SmoothedPhase::new(&PhaseFunction::isotropic(), DEFAULT_CONE_HALF_ANGLE_DEG);
        assert!((iso.eval(0.3) * 4.0 * std::f64::consts::PI - 1.0).abs() < 1e-3);
    }
}
