use super::*;
use crate::testing::chi_square;

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

/// Exp(1) by the ziggurat: 2 M draws in 20 bins of equal probability
/// (edges -ln(1 - k/20)) and two tail bins past the ziggurat's base strip
/// (r = 7.697, where a separate draw takes over): chi-square with 21
/// degrees of freedom below 46.8 (p = 0.001); the mean within four
/// standard errors of 1.
#[test]
fn exp1_follows_the_exponential_distribution() {
    let n = 2_000_000u64;
    let mut edges: Vec<f64> = (1..20).map(|k| -(1.0 - k as f64 / 20.0).ln()).collect();
    edges.extend([7.5, 9.0]);
    let cdf = |x: f64| 1.0 - (-x).exp();
    let mut p = Vec::new();
    let mut lo = 0.0;
    for &e in &edges {
        p.push(cdf(e) - cdf(lo));
        lo = e;
    }
    p.push(1.0 - cdf(lo));
    let mut counts = vec![0u64; p.len()];
    let mut rng = Pcg32::new(11, 5);
    let mut sum = 0.0;
    for _ in 0..n {
        let x = rng.exp1();
        assert!(x >= 0.0 && x.is_finite());
        sum += x;
        counts[edges.partition_point(|&e| e <= x)] += 1;
    }
    let chi2 = chi_square(&counts, &p);
    assert!(chi2 < 46.8, "chi2 {chi2}, counts {counts:?}");
    let mean = sum / n as f64;
    assert!((mean - 1.0).abs() < 4.0 / (n as f64).sqrt(), "mean {mean}");
    assert!(
        counts[p.len() - 1] > 0,
        "no draw beyond 9 (expected {:.0})",
        p[p.len() - 1] * n as f64
    );
}

/// N(0, 1) by the ziggurat: 2 M draws in 18 bins with edges -4, -3.5, …,
/// 4 (the outer ones past the base strip, r = 3.654), against
/// probabilities from erfc: chi-square with 17 degrees of freedom below
/// 40.8 (p = 0.001); mean and variance within four standard errors.
#[test]
fn normal_follows_the_normal_distribution() {
    let n = 2_000_000u64;
    let edges: Vec<f64> = (0..17).map(|k| -4.0 + 0.5 * k as f64).collect();
    let cdf = |x: f64| 0.5 * libm::erfc(-x / std::f64::consts::SQRT_2);
    let mut p = Vec::new();
    let mut lo = f64::NEG_INFINITY;
    for &e in &edges {
        p.push(cdf(e) - if lo.is_finite() { cdf(lo) } else { 0.0 });
        lo = e;
    }
    p.push(1.0 - cdf(lo));
    let mut counts = vec![0u64; p.len()];
    let mut rng = Pcg32::new(12, 6);
    let (mut sum, mut sum2) = (0.0, 0.0);
    for _ in 0..n {
        let x = rng.normal();
        assert!(x.is_finite());
        sum += x;
        sum2 += x * x;
        counts[edges.partition_point(|&e| e <= x)] += 1;
    }
    let chi2 = chi_square(&counts, &p);
    assert!(chi2 < 40.8, "chi2 {chi2}, counts {counts:?}");
    let mean = sum / n as f64;
    let var = sum2 / n as f64 - mean * mean;
    // SE of the mean 1/sqrt(n); of the variance sqrt(2/n).
    assert!(mean.abs() < 4.0 / (n as f64).sqrt(), "mean {mean}");
    assert!(
        (var - 1.0).abs() < 4.0 * (2.0 / n as f64).sqrt(),
        "variance {var}"
    );
}

/// The draws are pure functions of the stream, like every other draw.
#[test]
fn ziggurat_draws_are_deterministic() {
    let draw = || {
        let mut rng = Pcg32::new(5, 77);
        (0..1000)
            .map(|_| (rng.exp1().to_bits(), rng.normal().to_bits()))
            .collect::<Vec<_>>()
    };
    assert_eq!(draw(), draw());
}
