use super::*;

fn moments_of(samples: impl Iterator<Item = f64>) -> Moments {
    let mut m = Moments::new(1, 1);
    for x in samples {
        m.add(&[x]);
    }
    m
}

/// The relative variance of the variance is (kurtosis - 1) / N for
/// independent samples: 8 / N for an exponential distribution (kurtosis
/// 9; 200 000 samples give the fourth moment to about 2 %), about 1 for
/// one sample among zeros (where that sample is the whole sum), and 0 for
/// a constant.
#[test]
fn variance_of_the_variance_and_the_largest_share() {
    let n = 200_000u64;
    let mut rng = Pcg32::new(11, 0);
    let m = moments_of((0..n).map(|_| 2.5 * rng.exponential(1.0)));
    let (vov, share) = m.tail();
    let expected = 8.0 / n as f64;
    assert!(
        (vov[0] / expected - 1.0).abs() < 0.15,
        "{} against {expected}",
        vov[0]
    );
    assert!(share[0] < 1e-3, "{}", share[0]);

    let m = moments_of((0..1000).map(|i| if i == 500 { 3.0 } else { 0.0 }));
    let (vov, share) = m.tail();
    assert!((vov[0] - 0.998).abs() < 2e-3, "{}", vov[0]);
    assert!((share[0] - 1.0).abs() < 1e-12);

    let (vov, _) = moments_of((0..100).map(|_| 0.7)).tail();
    assert_eq!(vov[0], 0.0);
}

/// The band mean's standard error follows the bands' correlation: bands
/// that move together give each band's own standard error, bands that move
/// against each other give none, and independent bands give that over
/// the square root of their count. The photon groups' part is averaged
/// over the bands the same way.
#[test]
fn band_mean_standard_error_follows_the_correlation_of_the_bands() {
    let mut rng = Pcg32::new(5, 0);
    let xs: Vec<f64> = (0..4000).map(|_| rng.uniform_f64()).collect();
    let ys: Vec<f64> = (0..4000).map(|_| rng.uniform_f64()).collect();
    let run = |pair: &dyn Fn(usize) -> [f64; 2]| {
        let mut m = Moments::new(2, 1);
        (0..xs.len()).for_each(|i| m.add(&pair(i)));
        let mut se = [0.0; 2];
        m.standard_error(&mut se);
        (se, m.band_mean_standard_error())
    };
    let (se, mean) = run(&|i| [xs[i], xs[i]]);
    assert!((mean / se[0] - 1.0).abs() < 1e-9, "{mean} {se:?}");
    let (_, mean) = run(&|i| [xs[i], 1.0 - xs[i]]);
    assert!(mean < 1e-12, "{mean}");
    // Independent: sqrt(1/12 / 2 / n) / ... within the spread of a
    // standard error from 4000 samples (about 1.1 %, 5 sigma).
    let (se, mean) = run(&|i| [xs[i], ys[i]]);
    let expected = 0.5 * (se[0] * se[0] + se[1] * se[1]).sqrt();
    assert!(
        (mean / expected - 1.0).abs() < 0.06,
        "{mean} against {expected}"
    );

    // Photon groups: every sample's group channels carry the band values
    // in group 0 and nothing elsewhere, so the groups' band means spread
    // as the bands' do.
    let mut m = Moments::new(2, CHANNELS);
    let mut sample = vec![0.0; 2 * CHANNELS];
    for &x in &xs[..100] {
        sample[..2].copy_from_slice(&[1.0, 1.0]);
        sample[2..4].copy_from_slice(&[x, 1.0 - x]);
        m.add(&sample);
    }
    // The band means of the groups: group 0 sums to 100 * 0.5 = 50, the
    // others 0; variance GROUPS / (GROUPS - 1) * sum of squared
    // deviations, over n^2.
    let g = GROUPS as f64;
    let ss = 50.0f64.powi(2) * (1.0 - 1.0 / g);
    let expected = (g / (g - 1.0) * ss).sqrt() / 100.0;
    let got = m.band_mean_standard_error();
    assert!(
        (got / expected - 1.0).abs() < 1e-9,
        "{got} against {expected}"
    );
}

/// A radiometer is warned about when some band's VOV passes the limit,
/// and the warning names it and the band.
#[test]
fn dominated_readings_are_warned_about() {
    let reading = |vov: Vec<f64>| RadiometerReading {
        depth_m: 3.0,
        view: "zenith".into(),
        position_m: [1.0, 2.0],
        L: vec![1.0; vov.len()],
        stderr: vec![0.1; vov.len()],
        largest_share: vec![0.02; vov.len()],
        band_mean_stderr: 0.05,
        vov,
    };
    let w = crate::job::report::radiometer_warnings(&[
        reading(vec![0.01, 0.05]),
        reading(vec![0.02, 0.4, 0.2]),
    ]);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].starts_with("radiometer 1 (zenith at 3 m"), "{}", w[0]);
    assert!(
        w[0].contains("2 of 3 bands") && w[0].contains("band 1"),
        "{}",
        w[0]
    );
}

/// A radiometer's field of view weighs directions by the cosine of their
/// angle from its axis: over 200 000 draws in a 60-degree cone around a
/// slanted axis, every direction lies inside the cone, sin^2 of the angle
/// is uniform on [0, sin^2 60] (chi-square over 20 bins below its 0.1 %
/// point, 43.8; directions uniform in solid angle give a density
/// proportional to 1 / cos instead, and fail), and the azimuth around the
/// axis has no preferred side.
#[test]
fn field_of_view_is_cosine_weighted() {
    let axis = Vec3::new(0.3, -0.2, -0.9).normalize();
    let (t, _) = axis.as_dvec3().any_orthonormal_pair();
    let h = 60f64;
    let s2_max = h.to_radians().sin().powi(2);
    let n = 200_000;
    let bins = 20;
    let mut counts = vec![0f64; bins];
    let mut side = 0.0;
    for i in 0..n {
        let mut rng = Pcg32::new(9, i);
        let d = super::radiometer::within_field_of_view(axis, h, &mut rng).as_dvec3();
        let cos = d.dot(axis.as_dvec3());
        assert!(cos >= h.to_radians().cos() - 1e-6, "{cos}");
        let s2 = (1.0 - cos * cos).max(0.0) / s2_max;
        counts[((s2 * bins as f64) as usize).min(bins - 1)] += 1.0;
        side += d.dot(t).signum();
    }
    let expect = n as f64 / bins as f64;
    let chi2: f64 = counts.iter().map(|c| (c - expect).powi(2) / expect).sum();
    assert!(
        chi2 < 43.8,
        "chi-square {chi2} over {bins} bins: {counts:?}"
    );
    let se = (n as f64).sqrt();
    assert!(side.abs() < 4.0 * se, "azimuth: {side} of {n}");
}
