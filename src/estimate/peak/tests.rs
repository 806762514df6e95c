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

/// Directions drawn into the forward delta follow its shape: weighted by
/// `sample_peak`'s weights, the draws' mass in each of 8 bins of
/// 1 - cos over the cone (equal in log between 1e-6 and the cone's edge,
/// the first bin from 0) is the integral of (p - p_t) / f over the bin
/// (midpoint rule, 20 000 steps per bin), within five standard errors of
/// the weighted counts plus 1e-3; the weights average 1 within five
/// standard errors; every direction lies in the cone; and the delta's
/// mass found from the quantiles is the truncated table's `f` within 1e-3.
#[test]
fn peak_directions_follow_the_shape_of_the_delta() {
    for (p, deg) in [
        (PhaseFunction::fournier_forand(0.0183).unwrap(), 20.0),
        (PhaseFunction::petzold(), 10.0),
        (PhaseFunction::henyey_greenstein(0.8).unwrap(), 20.0),
    ] {
        let t = TruncatedPhase::new(&p, deg);
        let s = t.peak.as_ref().unwrap();
        let cos_t = f64::cos(f64::to_radians(deg));
        let x_t = 1.0 - cos_t;
        let mass = 1.0 / s.scale * (1.0 - s.u_t);
        assert!(
            (mass / t.forward_fraction() - 1.0).abs() < 1e-3,
            "{p:?}: delta mass {mass} against the table's {}",
            t.forward_fraction()
        );
        let bins = 8;
        let edge = |i: usize| {
            if i == 0 {
                0.0
            } else {
                1e-6 * (x_t / 1e-6).powf(i as f64 / bins as f64)
            }
        };
        let mut expected = vec![0.0; bins];
        for (i, e) in expected.iter_mut().enumerate() {
            let (a, b) = (edge(i), edge(i + 1));
            let steps = 20_000;
            let h = (b - a) / steps as f64;
            *e = (0..steps)
                .map(|k| (p.eval_one_minus_cos(a + (k as f64 + 0.5) * h) - s.p_t).max(0.0))
                .sum::<f64>()
                * h
                * TAU
                / mass;
        }
        let n = 400_000;
        let (mut sum, mut sum_sq) = (vec![0.0; bins], vec![0.0; bins]);
        let (mut w_sum, mut w_sq) = (0.0, 0.0);
        let mut rng = Pcg32::new(3, 0);
        let axis = Vec3::new(0.3, -0.4, 0.866).normalize();
        for _ in 0..n {
            let (d, w) = t.sample_peak(axis, &mut rng).unwrap();
            let x = 0.5 * (d - axis).length_squared() as f64;
            assert!(
                x <= x_t * 1.001 + 1e-6,
                "{p:?}: outside the cone at 1 - cos = {x}"
            );
            let bin = (0..bins).rev().find(|&i| x >= edge(i)).unwrap_or(0);
            sum[bin] += w;
            sum_sq[bin] += w * w;
            w_sum += w;
            w_sq += w * w;
        }
        let nf = n as f64;
        let w_se = ((w_sq / nf - (w_sum / nf).powi(2)) / nf).sqrt();
        assert!(
            (w_sum / nf - 1.0).abs() < 5.0 * w_se + 1e-9,
            "{p:?}: mean weight {}",
            w_sum / nf
        );
        for i in 0..bins {
            let got = sum[i] / nf;
            let se = ((sum_sq[i] / nf - got * got) / nf).sqrt();
            assert!(
                (got - expected[i]).abs() < 5.0 * se + 1e-3,
                "{p:?}, bin {i}: {got} +- {se} against {}",
                expected[i]
            );
        }
    }
}

/// The interleaved mixture gives each part's own value, mixed, to the bit:
/// tabulated parts, an exact part (no truncation) beside a tabulated one,
/// at the ends of the table and outside [-1, 1].
#[test]
fn mixed_phase_is_the_parts_mixed_to_the_bit() {
    let water = PhaseFunction::rayleigh(0.84).unwrap();
    let particle = PhaseFunction::petzold();
    for (dw, dp) in [(DEFAULT_FORWARD_PEAK_DEG, 20.0), (0.0, 20.0), (10.0, 0.0)] {
        let (w, p) = (
            TruncatedPhase::new(&water, dw),
            TruncatedPhase::new(&particle, dp),
        );
        let mixed = MixedPhase::new(w.clone(), p.clone());
        let mut rng = crate::rng::Pcg32::new(3, 5);
        let ends = [-1.5, -1.0, -0.999_999, 0.0, 0.999_999, 1.0, 1.5];
        let draws = (0..10_000).map(|_| 2.0 * rng.uniform_f64() - 1.0);
        for mu in ends.into_iter().chain(draws) {
            for fw in [0.0, 0.3, 1.0] {
                let want = fw * w.eval(mu) + (1.0 - fw) * p.eval(mu);
                assert_eq!(
                    mixed.mix(fw, mu).to_bits(),
                    want.to_bits(),
                    "{dw} {dp} {mu} {fw}"
                );
            }
        }
    }
}
