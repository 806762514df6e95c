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
