use super::*;

#[test]
fn streams_are_pure_functions_of_seed_and_index() {
    let draw = |seed, index| {
        let mut rng = Pcg32::new(seed, index);
        (0..8).map(|_| rng.next_u32()).collect::<Vec<_>>()
    };
    assert_eq!(draw(7, 42), draw(7, 42));
    assert_ne!(draw(7, 42), draw(7, 43));
    assert_ne!(draw(7, 42), draw(8, 42));
}

/// Mean of U(0,1) is 1/2 with standard error 1/sqrt(12 n).
#[test]
fn uniform_mean_within_standard_error() {
    let n = 200_000;
    let mut rng = Pcg32::new(1, 0);
    let mean: f64 = (0..n).map(|_| rng.uniform_f64()).sum::<f64>() / n as f64;
    let se = 1.0 / (12.0 * n as f64).sqrt();
    assert!((mean - 0.5).abs() < 4.0 * se, "mean {mean}");
}

/// Each of 10 bins holds n/10 draws; chi-square with 9 dof stays below 27.9 (p = 0.001).
#[test]
fn below_is_uniform() {
    let n = 100_000;
    let mut counts = [0u32; 10];
    let mut rng = Pcg32::new(3, 9);
    for _ in 0..n {
        counts[rng.below(10) as usize] += 1;
    }
    let e = n as f64 / 10.0;
    let chi2: f64 = counts.iter().map(|&c| (c as f64 - e).powi(2) / e).sum();
    assert!(chi2 < 27.9, "chi2 {chi2}");
}
