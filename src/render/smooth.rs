//! Phase functions as seen by the photon-map estimate: averaged over a cone.
//!
//! A photon's contribution is weighted by p(w_p . w). With a forward-peaked
//! particle phase function (Fournier–Forand, Petzold: p reaches 10^3–10^4
//! sr^-1 within a degree) one photon travelling almost exactly toward the
//! viewer outweighs thousands of others, and the estimate becomes speckle.
//! The underwater light field is smooth in angle over a few degrees, so the
//! estimate uses the phase function averaged over a cone of half-angle
//! [`CONE_HALF_ANGLE_DEG`] (a convolution on the sphere: normalisation is
//! kept; the forward peak is spread over the cone). Single scattering of
//! the sun is computed with the exact phase function. The smoothed function
//! is tabulated in cos(theta), which also makes the estimate's inner loop a
//! table lookup.

use crate::optics::phase::PhaseFunction;

/// Half-angle of the smoothing cone (degrees).
pub const CONE_HALF_ANGLE_DEG: f64 = 30.0;
const TABLE: usize = 2048;

/// A cone-averaged phase function tabulated over cos(theta) in [-1, 1].
#[derive(Clone, Debug)]
pub struct SmoothedPhase {
    table: Vec<f64>,
}

impl SmoothedPhase {
    pub fn new(p: &PhaseFunction) -> Self {
        let alpha = CONE_HALF_ANGLE_DEG.to_radians();
        let (nb, nphi) = (48usize, 48usize);
        // Gauss-free midpoint quadrature over the cap: in cos(beta) (uniform
        // solid angle) and in azimuth.
        let cos_a = alpha.cos();
        let table = (0..TABLE)
            .map(|i| {
                let mu0 = -1.0 + 2.0 * i as f64 / (TABLE - 1) as f64;
                let s0 = (1.0 - mu0 * mu0).max(0.0).sqrt();
                let mut sum = 0.0;
                for j in 0..nb {
                    let cb = 1.0 - (1.0 - cos_a) * (j as f64 + 0.5) / nb as f64;
                    let sb = (1.0 - cb * cb).max(0.0).sqrt();
                    for k in 0..nphi {
                        let phi = std::f64::consts::TAU * (k as f64 + 0.5) / nphi as f64;
                        let mu = (mu0 * cb + s0 * sb * phi.cos()).clamp(-1.0, 1.0);
                        sum += p.eval(mu);
                    }
                }
                sum / (nb * nphi) as f64
            })
            .collect();
        SmoothedPhase { table }
    }

    /// Smoothed p at cos(theta) (sr^-1), linear between table entries.
    #[inline]
    pub fn eval(&self, mu: f64) -> f64 {
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
            let s = SmoothedPhase::new(&p);
            let n = 200_000;
            let integral: f64 = (0..n)
                .map(|i| s.eval(-1.0 + 2.0 * (i as f64 + 0.5) / n as f64))
                .sum::<f64>()
                * 2.0
                / n as f64
                * 2.0
                * std::f64::consts::PI;
            assert!((integral - 1.0).abs() < 2e-3, "{integral}");
            assert!(s.eval(1.0) <= p.eval(1.0) + 1e-9);
        }
        let iso = SmoothedPhase::new(&PhaseFunction::isotropic());
        assert!((iso.eval(0.3) - 1.0 / (4.0 * std::f64::consts::PI)).abs() < 1e-9);
    }
}
