use super::*;

/// The backscatter fraction of Fournier & Forand as printed in OPTICS.md,
/// with delta90 = 4 sin^2(45°) / (3 (n-1)^2).
fn ff_backscatter_printed(n: f64, mu: f64) -> f64 {
    let nu = (3.0 - mu) / 2.0;
    let d90 = 4.0 * 0.5 / (3.0 * (n - 1.0).powi(2));
    1.0 - (1.0 - d90.powf(nu + 1.0) - 0.5 * (1.0 - d90.powf(nu))) / ((1.0 - d90) * d90.powf(nu))
}

/// Asking for B gives B to 1e-12 (bisection runs to the last bit of mu), with n on the tie,
/// and the printed B formula agrees.
#[test]
fn fournier_forand_hits_requested_backscatter() {
    for target in [1e-4, 0.001, 0.01, 0.0183, 0.1, 0.15] {
        let ff = FournierForand::from_backscatter(target).unwrap();
        let b = ff.backscatter_fraction();
        eprintln!("B {target}: mu {:.6} n {:.6} -> B {b:.15}", ff.mu(), ff.n());
        assert!((b - target).abs() < 1e-12, "{target}: {b}");
        assert!((ff.n() - FournierForand::tied_n(ff.mu())).abs() < 1e-15);
        let printed = ff_backscatter_printed(ff.n(), ff.mu());
        assert!(
            (printed - target).abs() < 1e-10,
            "printed formula {printed}"
        );
    }
}

/// OPTICS.md check values: B 0.0183 at mu 3.5835 (n 1.0999) on the tie;
/// (n, mu, B) = (1.08, 3.483, 0.01) and (1.175, 4.065, 0.1), quoted to 3–4
/// figures (they give B 0.01004 and 0.10008); the Petzold-equivalent FF
/// (1.10, 3.5835) has B = 0.01831 (data file notes).
#[test]
fn fournier_forand_check_values() {
    let ff = FournierForand::from_backscatter(0.0183).unwrap();
    assert!((ff.mu() - 3.5835).abs() < 2e-4, "mu {}", ff.mu());
    assert!((ff.n() - 1.0999).abs() < 1e-4, "n {}", ff.n());
    let b = |n, mu| FournierForand::new(n, mu).unwrap().backscatter_fraction();
    let b1 = b(1.08, 3.483);
    let b2 = b(1.175, 4.065);
    let b3 = b(1.10, 3.5835);
    eprintln!("B(1.08, 3.483) {b1}, B(1.175, 4.065) {b2}, B(1.10, 3.5835) {b3}");
    assert!((b1 / 0.01 - 1.0).abs() < 5e-3, "{b1}");
    assert!((b2 / 0.1 - 1.0).abs() < 1e-3, "{b2}");
    assert!((b3 - 0.01831).abs() < 1e-5, "{b3}");
}

/// Near delta = 1 the series and the printed 0/0 forms agree (to the
/// round-off the printed forms suffer there), and the density is the
/// derivative of the CDF: dP/ds2 = 4 pi p.
#[test]
fn fournier_forand_series_and_derivative_consistent() {
    for bb in [1e-4, 0.0183, 0.15] {
        let ff = FournierForand::from_backscatter(bb).unwrap();
        let shape = ff.shape;
        for x in [0.049, 0.03, -0.03, -0.049, 0.01, -0.01] {
            let s2 = shape.k * (1.0 - x);
            let (ds, dd) = (shape.density_series(s2), shape.density_direct(s2));
            assert!((ds / dd - 1.0).abs() < 1e-10, "density x {x}: {ds} vs {dd}");
            let (cs, cd) = (shape.cdf_series(s2), shape.cdf_direct(s2));
            assert!((cs / cd - 1.0).abs() < 1e-12, "cdf x {x}: {cs} vs {cd}");
        }
        for s2 in [1e-8, 1e-4, shape.k, 0.01, 0.3, 0.5, 0.9] {
            let h = 1e-6 * s2;
            let derivative = (shape.cdf(s2 + h) - shape.cdf(s2 - h)) / (2.0 * h);
            let p = FOUR_PI * shape.density(s2);
            assert!(
                (derivative / p - 1.0).abs() < 1e-6,
                "s2 {s2}: {derivative} vs {p}"
            );
        }
        // P(pi) = 1 exactly as printed.
        assert!((shape.cdf(1.0) - 1.0).abs() < 1e-14);
    }
}

/// The sampler's largest error in ln s2, as its documentation states.
const FF_SAMPLE_LN_S2_ERROR: f64 = 2e-10;

/// The sampler's ln s2 is within FF_SAMPLE_LN_S2_ERROR of the CDF's
/// exact root (a Newton solve run until its steps stop changing anything,
/// tolerance 1e-15), halfway between the inverse table's nodes, where
/// interpolation is worst, and at random points, from the forward peak to
/// the backward end; and the cosine it gives is the one of that root to
/// twice as much.
#[test]
fn sampler_is_within_its_stated_error_of_the_exact_root() {
    let mut rng = crate::rng::Pcg32::new(5, 0);
    for bb in [1e-4, 0.0183, 0.05, 0.15] {
        let ff = FournierForand::from_backscatter(bb).unwrap();
        let h = 1.0 / ff.inverse_scale;
        let (mut worst, mut worst_cos) = (0.0f64, 0.0f64);
        let mids = (0..FF_INVERSE_NODES - 1).map(|j| ff.z_min + (j as f64 + 0.5) * h);
        let randoms: Vec<f64> = (0..20_000)
            .map(|_| ff.z_min + rng.uniform_f64() * (FF_INVERSE_Z_MAX - ff.z_min))
            .collect();
        for z in mids.chain(randoms) {
            // P = 1 / (1 + e^-z), 1 - P = 1 / (1 + e^z).
            let (ln_v, ln_u) = (-(-z).exp().ln_1p(), -z.exp().ln_1p());
            if ln_v >= 0.0 || ln_v <= ff.cdf_min.ln() {
                continue;
            }
            let t = ff.sample_ln_s2(ln_v - ln_u);
            let exact = super::super::solve_increasing(S2_MIN.ln(), 0.0, t, 1e-15, |t| {
                let s2 = t.exp();
                let cdf = ff.shape.cdf(s2);
                (cdf.ln() - ln_v, FOUR_PI * s2 * ff.shape.density(s2) / cdf)
            });
            worst = worst.max((t - exact).abs());
            worst_cos = worst_cos.max((2.0 * t.exp() - 2.0 * exact.exp()).abs());
        }
        assert!(
            worst <= FF_SAMPLE_LN_S2_ERROR,
            "B {bb}: ln s2 off by {worst:e}"
        );
        assert!(
            worst_cos <= 2.0 * FF_SAMPLE_LN_S2_ERROR * (1.0 + 1e-6),
            "B {bb}: cosine off by {worst_cos:e}"
        );
    }
}

/// The fused CDF and density are the separate ones to round-off, across
/// ln s2 from S2_MIN to 1 (both sides of the series radius).
#[test]
fn fused_cdf_and_density_match_the_separate_forms() {
    for bb in [1e-4, 0.0183, 0.15] {
        let ff = FournierForand::from_backscatter(bb).unwrap();
        let sh = ff.shape;
        for i in 0..=20_000 {
            let s2 = (S2_MIN.ln() * (1.0 - i as f64 / 20_000.0)).exp();
            let (c, d) = sh.cdf_and_density(s2);
            assert!((c / sh.cdf(s2) - 1.0).abs() < 1e-13, "B {bb} s2 {s2}: cdf");
            assert!(
                (d / sh.density(s2) - 1.0).abs() < 1e-13,
                "B {bb} s2 {s2}: density"
            );
        }
    }
}
