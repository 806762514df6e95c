//! The march's turns into the particles' forward peak drawn at a hero
//! band's rate, against each band's own law of turns; marches with
//! longer steps, and with steps paced by the transmittance, against the
//! march.

use super::{Course, PeakTurns, RayMarcher};
use crate::estimate::estimator::{with_scratch, Estimator};
use crate::rng::Pcg32;
use crate::scene::{Overrides, Scene};
use glam::Vec3;

/// Over a run of L = 3 m in steps of 0.5 m, turns drawn at a uniformly
/// chosen hero band's rate and weighted by [`PeakTurns::advance`] give each
/// band the Poisson law of its own rate: E[w_b; n turns] = P(n; sigma_b L)
/// for n = 0..3 and the tail, within 4 standard errors of 100 000 runs,
/// including a band with no peak (sigma = 0) and bands 5 times apart. The
/// weights stay within the balance heuristic's bound (the band count), and
/// the committed log weights are the product of the factors handed out.
#[test]
fn hero_turns_give_every_band_its_own_law() {
    let sigma = [0.0, 0.4, 0.8, 1.2, 1.6, 2.0];
    let nb = sigma.len();
    let (length, step) = (3.0f64, 0.5f64);
    const RUNS: usize = 100_000;
    const CLASSES: usize = 5;
    let mut rng = Pcg32::new(11, 0);
    let mut sum = vec![[0.0f64; CLASSES]; nb];
    let mut sum_sq = vec![[0.0f64; CLASSES]; nb];
    let mut factor = vec![0.0f64; nb];
    let mut largest = 0.0f64;
    for _ in 0..RUNS {
        let mut turns = PeakTurns::new(nb, &mut rng);
        turns.sigma.copy_from_slice(&sigma);
        let mut w = vec![1.0f64; nb];
        let (mut n, mut travelled) = (0usize, 0.0f64);
        while travelled < length - 1e-12 {
            let dt = step.min(length - travelled);
            let d = rng.exponential(turns.sigma[turns.hero]);
            let turned = d < dt;
            let len = if turned { d } else { dt };
            turns.advance(len, turned, true, &mut factor);
            w.iter_mut().zip(&factor).for_each(|(w, f)| *w *= f);
            n += usize::from(turned);
            travelled += len;
        }
        for (b, &wb) in w.iter().enumerate() {
            let logged = turns.log_p[b].exp();
            assert!(
                (wb - logged).abs() <= 1e-9 * wb.max(1.0),
                "band {b}: {wb} against {logged}"
            );
            sum[b][n.min(CLASSES - 1)] += wb;
            sum_sq[b][n.min(CLASSES - 1)] += wb * wb;
            largest = largest.max(wb);
        }
    }
    assert!(largest <= nb as f64 * (1.0 + 1e-9), "a weight of {largest}");
    for (b, &s) in sigma.iter().enumerate() {
        let lambda = s * length;
        let mut pmf = [0.0f64; CLASSES];
        let mut term = (-lambda).exp();
        for (i, p) in pmf.iter_mut().enumerate().take(CLASSES - 1) {
            *p = term;
            term *= lambda / (i + 1) as f64;
        }
        pmf[CLASSES - 1] = 1.0 - pmf[..CLASSES - 1].iter().sum::<f64>();
        for i in 0..CLASSES {
            let mean = sum[b][i] / RUNS as f64;
            let var = (sum_sq[b][i] / RUNS as f64 - mean * mean).max(0.0);
            let se = (var / RUNS as f64).sqrt();
            assert!(
                (mean - pmf[i]).abs() <= 4.0 * se + 1e-12,
                "sigma {s}, {i} turns: {mean:.5} +- {se:.5} against {:.5}",
                pmf[i]
            );
        }
    }
}

/// Per-band mean and variance of the mean of 4000 marches from 0.5 m
/// down looking down, in water with a forward peak (Fournier–Forand
/// particles, so that runs turn within steps) over a sand floor 6 m down,
/// each march on `course` (`stream` of the rng).
fn march_moments(course: impl Fn(f32) -> Course, stream: u64) -> Vec<(f64, f64)> {
    let text = include_str!("../../../tests/scenes/minimal.toml")
        .replace(
            "iop = { a = 0.1, b = 0.2 }",
            "iop = { a = 0.1, b = 0.4 }\nphase = { kind = \"fournier-forand\", bb_ratio = 0.0183 }",
        )
        .replace("count = 1000", "count = 40000")
        + "[bottom]\ndepth_m = 6.0\nreflectance = 0.3\n";
    let scene = Scene::parse(
        &text,
        std::path::Path::new("coarse.toml"),
        &Overrides::default(),
    )
    .unwrap();
    let emitter = crate::emit::Emitter::new(&scene).unwrap();
    let map = crate::store::InMemoryMap::from_source(&emitter).unwrap();
    let marcher = RayMarcher::new(&scene, Estimator::new(&scene, &map).unwrap());
    let nb = scene.bands.len();
    let n = 4000;
    let course = course(scene.estimate.step_m as f32);
    let mut rng = Pcg32::new(7, stream);
    let (mut sum, mut sum_sq) = (vec![0.0; nb], vec![0.0; nb]);
    let mut out = vec![0.0; nb];
    with_scratch(nb, |s| {
        for _ in 0..n {
            let p = Vec3::new(5.0, 5.0, -0.5);
            marcher
                .march_with(p, Vec3::NEG_Z, &mut rng, s, &mut out, course)
                .unwrap();
            for b in 0..nb {
                sum[b] += out[b];
                sum_sq[b] += out[b] * out[b];
            }
        }
    });
    (0..nb)
        .map(|b| {
            let m = sum[b] / n as f64;
            (m, (sum_sq[b] / n as f64 - m * m) / n as f64)
        })
        .collect()
}

/// Every band's mean of `other` within 4 standard errors of its
/// difference from `fine`'s.
fn assert_same_expectation(fine: &[(f64, f64)], other: &[(f64, f64)], what: &str) {
    for (b, (&(a, va), &(c, vc))) in fine.iter().zip(other).enumerate() {
        let se = (va + vc).sqrt();
        assert!(a > 0.0, "band {b}: no light");
        assert!(
            (c - a).abs() < 4.0 * se,
            "band {b}: {what} {c} against {a} (+- {se}, {:.1} se)",
            (c - a).abs() / se
        );
    }
}

/// Fixed steps of the scene's length.
fn fixed(step_m: f32) -> Course {
    Course {
        step_m,
        stretch_max: 1.0,
        share_min: 1.0,
        spans_turns: false,
        gather: true,
    }
}

/// A march with steps four times the scene's (`march_coarse`, the air
/// view's calls) has the march's expectation, every band's mean within 4
/// standard errors of their difference. A march that weighed its sources
/// by at most the scene's step failed it by about a hundred of them
/// (band 0: 106).
#[test]
fn longer_steps_keep_the_march_s_expectation() {
    let coarse = |step_m: f32| Course {
        step_m: 4.0 * step_m,
        ..fixed(step_m)
    };
    let (fine, coarse) = (march_moments(fixed, 1), march_moments(coarse, 2));
    assert_same_expectation(&fine, &coarse, "steps of 4 x");
}

/// Steps stretched as the light fades (`stretch`), here up to 16 times
/// the scene's, keep the march's expectation, every band's mean within 4
/// standard errors of their difference from fixed steps'. The stretch
/// follows the largest transmittance so far, which each step's own
/// weight carries; a march whose steps stretched without their weight
/// (each sample weighed by at most the scene's step) failed it by 48
/// standard errors (band 0).
#[test]
fn steps_paced_by_the_transmittance_keep_the_march_s_expectation() {
    let paced = |step_m: f32| Course {
        stretch_max: 16.0,
        ..fixed(step_m)
    };
    let (fine, paced) = (march_moments(fixed, 1), march_moments(paced, 2));
    assert_same_expectation(&fine, &paced, "steps paced by T");
}

/// Steps that run on across turns into the forward peak (`Step`), one
/// estimate per step wherever its sample falls, keep the expectation of
/// steps that end at every turn, every band's mean within 4 standard
/// errors of their difference. Estimates weighed by the straight piece
/// holding them instead of the whole step failed it by 7.5 standard
/// errors (band 0).
#[test]
fn steps_across_turns_keep_the_march_s_expectation() {
    let across = |step_m: f32| Course {
        spans_turns: true,
        ..fixed(step_m)
    };
    let (fine, across) = (march_moments(fixed, 1), march_moments(across, 2));
    assert_same_expectation(&fine, &across, "steps across turns");
}
