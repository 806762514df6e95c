/// The quadrature against closed forms; the critical value against a
/// tabulated quantile (chi-square, 20 degrees of freedom, p = 0.001:
/// 45.315).
#[test]
fn helpers_match_closed_forms() {
    let q = super::simpson(&|x: f64| x.sin(), 0.0, std::f64::consts::PI, 1e-12);
    assert!((q - 2.0).abs() < 1e-10, "{q}");
    assert!((super::chi_square_critical(20) - 45.315).abs() < 0.2);
    assert_eq!(super::chi_square(&[50, 50], &[0.5, 0.5]), 0.0);
    assert!((super::rel(1.1, 1.0) - 0.1).abs() < 1e-12);
}
