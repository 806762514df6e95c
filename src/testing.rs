//! Helpers for the unit tests' Monte Carlo checks.

/// Assert that `hits` successes in `n` trials agree with probability `want`
/// within four binomial standard errors; `what` names the case.
pub(crate) fn assert_binomial(hits: u64, n: u64, want: f64, what: &str) {
    let got = hits as f64 / n as f64;
    let se = (want * (1.0 - want) / n as f64).sqrt();
    assert!(
        (got - want).abs() < 4.0 * se,
        "{what}: {got} against {want} (standard error {se})"
    );
}
