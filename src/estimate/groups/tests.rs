use super::*;
use crate::rng::Pcg32;

/// A sum of random draws split into random groups: the group variance
/// estimate averages to the variance of the sum. As for photons in a
/// search region, the number of draws is Poisson (a small share of
/// many independent paths), so the variance of the sum is
/// ITEMS E[w^2]. (With a fixed number of draws it would be
/// ITEMS Var(w), and the estimator would read high by E[w^2] / Var(w).)
#[test]
fn group_variance_is_the_variance_of_the_sum() {
    const TRIALS: usize = 4000;
    const ITEMS: f64 = 300.0;
    let (mut sum_var, mut sum, mut sum_sq) = (0.0, 0.0, 0.0);
    for t in 0..TRIALS {
        let mut rng = Pcg32::new(7, t as u64);
        let mut groups = vec![0.0; GROUPS];
        let mut total = 0.0;
        // Poisson arrivals: unit-rate exponential gaps until ITEMS.
        let mut clock = rng.exponential(1.0);
        while clock < ITEMS {
            clock += rng.exponential(1.0);
            // Heavy-tailed weights, as phase weights are.
            let w = rng.exponential(1.0).powi(2);
            let g = rng.below(GROUPS as u32) as usize;
            groups[g] += w;
            total += w;
        }
        let mut v = [0.0];
        variance(&groups, &mut v);
        sum_var += v[0];
        sum += total;
        sum_sq += total * total;
    }
    let n = TRIALS as f64;
    let observed = (sum_sq / n - (sum / n).powi(2)) * n / (n - 1.0);
    let predicted = sum_var / n;
    // The truth, ITEMS E[w^2] = 300 x 24: the observed one is near it.
    assert!(
        (observed / 7200.0 - 1.0).abs() < 0.08,
        "observed {observed}"
    );
    // Standard errors: the observed variance's is sqrt((kappa - 1) / n)
    // with kappa the kurtosis of the sum (3 + E w^4 / (ITEMS (E w^2)^2)
    // = 3.23 for w = X^2, X ~ Exp(1)): 2.4 %; the predicted mean's about
    // sqrt(2 / 15 / n) ~ 0.6 % plus the tail's share: under 1 %.
    // 8 % is three combined standard errors.
    let rel = (predicted / observed - 1.0).abs();
    assert!(rel < 0.08, "predicted {predicted} observed {observed}");
}

#[test]
fn sums_skip_bad_values_and_keep_bands_on_request() {
    let mut s = GroupSums::new(3);
    s.clear(true);
    s.add(2, 1, 1.5);
    s.add(2, 1, f64::NAN);
    s.add(2, 7, 1.0);
    s.add(18, 0, 0.5); // groups wrap
    assert_eq!(s.totals()[2], 2.0);
    assert_eq!(s.bands_of(2), &[0.5, 1.5, 0.0]);
    s.clear(false);
    assert_eq!(s.totals()[2], 0.0);
}
