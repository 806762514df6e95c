//! Helpers the unit tests share: binomial checks of Monte Carlo
//! fractions, an independent quadrature, relative differences and
//! Pearson's chi-square with its critical value. (The integration tests'
//! own helpers are in `tests/integration/common.rs`.)

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

/// Adaptive Simpson on [a, b] to an absolute tolerance `tol` (an
/// independent quadrature for checking closed forms and samplers).
pub fn simpson(f: &dyn Fn(f64) -> f64, a: f64, b: f64, tol: f64) -> f64 {
    /// One panel [a, b] with f at a, the midpoint and b, and its Simpson estimate.
    fn step(
        f: &dyn Fn(f64) -> f64,
        [a, b]: [f64; 2],
        [fa, fm, fb]: [f64; 3],
        whole: f64,
        tol: f64,
        depth: u32,
    ) -> f64 {
        let m = 0.5 * (a + b);
        let (flm, frm) = (f(0.5 * (a + m)), f(0.5 * (m + b)));
        let left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
        let right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
        let diff = left + right - whole;
        if depth == 0 || diff.abs() <= 15.0 * tol {
            return left + right + diff / 15.0;
        }
        step(f, [a, m], [fa, flm, fm], left, 0.5 * tol, depth - 1)
            + step(f, [m, b], [fm, frm, fb], right, 0.5 * tol, depth - 1)
    }
    let (fa, fm, fb) = (f(a), f(0.5 * (a + b)), f(b));
    let whole = (b - a) / 6.0 * (fa + 4.0 * fm + fb);
    step(f, [a, b], [fa, fm, fb], whole, tol, 40)
}

/// |a - b| / |b| (b = 0 counts as the smallest positive number).
pub fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(f64::MIN_POSITIVE)
}

/// Pearson's chi-square of `counts` against probabilities `p` (summing to 1).
pub fn chi_square(counts: &[u64], p: &[f64]) -> f64 {
    let n: u64 = counts.iter().sum();
    counts
        .iter()
        .zip(p)
        .map(|(&c, &p)| {
            let e = p * n as f64;
            (c as f64 - e).powi(2) / e
        })
        .sum()
}

/// Upper-tail chi-square quantile at p = 0.001 (Wilson–Hilferty).
pub fn chi_square_critical(dof: usize) -> f64 {
    const Z_999: f64 = 3.090_232_306_167_813;
    let k = dof as f64;
    let c = 2.0 / (9.0 * k);
    k * (1.0 - c + Z_999 * c.sqrt()).powi(3)
}

#[cfg(test)]
mod tests;

/// The smallest valid scene (`tests/scenes/minimal.toml`, which the
/// integration tests share) as a scene text to change.
pub fn minimal_scene() -> crate::scene::text::SceneText {
    crate::scene::text::SceneText::parse(include_str!("../tests/scenes/minimal.toml")).unwrap()
}

/// [`minimal_scene`] with the TOML `fragment` merged in table by table,
/// as scene text.
pub fn minimal_with(fragment: &str) -> String {
    minimal_scene().merge(fragment).unwrap().text()
}
