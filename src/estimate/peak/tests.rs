use super::*;
use crate::scene::settings::DEFAULT_FORWARD_PEAK_DEG;
use std::f64::consts::{PI, TAU};

/// Integral of p* over the sphere by the midpoint rule in mu.
fn integral(t: &TruncatedPhase) -> f64 {
    let n = 400_000;
    (0..n)
        .map(|i| t.eval(-1.0 + 2.0 * (i as f64 + 0.5) / n as f64))
        .sum::<f64>()
        * 2.0
        / n as f64
        * TAU
}

/// p* plus the delta conserves scattering; p* is p outside the peak and
/// flat inside; f is the peak's excess mass, found independently from
/// the phase function's own quantiles.
#[test]
fn truncation_conserves_scattering_and_keeps_the_wings() {
    for p in [
        PhaseFunction::petzold(),
        PhaseFunction::fournier_forand(0.02).unwrap(),
        PhaseFunction::henyey_greenstein(0.9).unwrap(),
    ] {
        let t = TruncatedPhase::new(&p, DEFAULT_FORWARD_PEAK_DEG);
        let f = t.forward_fraction();
        assert!((integral(&t) + f - 1.0).abs() < 1e-5, "{p:?}: {f}");
        let cos_t = DEFAULT_FORWARD_PEAK_DEG.to_radians().cos();
        let top = p.eval(cos_t);
        for mu in [1.0, 0.9999, 0.5 * (1.0 + cos_t)] {
            assert!((t.eval(mu) / top - 1.0).abs() < 1e-3, "flat top at {mu}");
        }
        for deg in [20.0f64, 45.0, 90.0, 150.0, 180.0] {
            let mu = deg.to_radians().cos();
            assert!(
                (t.eval(mu) / p.eval(mu) - 1.0).abs() < 2e-3,
                "wing at {deg}"
            );
        }
        // f = E_p[(1 - top / p(mu)) for mu > cos_t], over 10^6 quantiles.
        let n = 1_000_000;
        let excess = (0..n)
            .map(|i| p.sample_cos((i as f64 + 0.5) / n as f64))
            .filter(|&mu| mu > cos_t)
            .map(|mu| (1.0 - top / p.eval(mu)).max(0.0))
            .sum::<f64>()
            / n as f64;
        assert!((f - excess).abs() < 2e-3, "{p:?}: f {f} vs {excess}");
        assert!(f > 0.3, "a forward-peaked function loses most of its peak");
    }
    // Functions without a peak lose (almost) nothing.
    let iso = TruncatedPhase::new(&PhaseFunction::isotropic(), DEFAULT_FORWARD_PEAK_DEG);
    assert!(iso.forward_fraction() < 1e-9);
    assert!((iso.eval(0.3) * 4.0 * PI - 1.0).abs() < 1e-9);
    let exact = TruncatedPhase::new(&PhaseFunction::petzold(), 0.0);
    assert_eq!(exact.eval(0.7), PhaseFunction::petzold().eval(0.7));
    assert_eq!(exact.forward_fraction(), 0.0);
}
