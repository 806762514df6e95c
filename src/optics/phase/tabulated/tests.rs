use crate::optics::phase::PhaseFunction;

/// The embedded table parses; node values are the corrected column over
/// the numerical normalisation, and the power law continues it to 0.1°
/// (printed 1766.61).
///
/// Normalisation and backscatter: linear in angle and integrated exactly,
/// the table's integral is 1.01798 (the data notes' 1.00001 is a
/// trapezoid on p sin psi; the exact integral of the interpolant exceeds it
/// by 1.8 %, almost all between 0.126° and 30°). Dividing by it gives
/// B = 0.01782, 2.6 % under the 0.0183 of OPTICS.md (which is the
/// unnormalised 0.01813 of the data notes, rounded). So the check against
/// 0.0183 allows 3 %, and the exact figures are pinned separately.
#[test]
fn petzold_matches_its_table() {
    let pf = PhaseFunction::petzold();
    let PhaseFunction::Tabulated(t) = &pf else {
        unreachable!()
    };
    let norm = t.raw_integral();
    let b = pf.backscatter_fraction();
    eprintln!(
        "Petzold: table integrates to {norm:.7}, B {b:.6}, g {:.6}",
        pf.mean_cosine()
    );
    assert!((norm - 1.01798).abs() < 1e-5, "normalisation {norm}");
    let at = |deg: f64| pf.eval(deg.to_radians().cos()) * norm;
    for (deg, value) in [(0.50119, 201.839), (10.0, 1.15257), (90.0, 0.00429232)] {
        assert!((at(deg) / value - 1.0).abs() < 1e-7, "{deg}: {}", at(deg));
    }
    assert!((at(180.0) / 0.00315366 - 1.0).abs() < 1e-12);
    assert!((at(0.1) / 1766.61 - 1.0).abs() < 1e-3, "{}", at(0.1));
    assert!(
        (b * norm - 0.018142).abs() < 1e-5,
        "unnormalised B {}",
        b * norm
    );
    assert!((b / 0.0183 - 1.0).abs() < 0.03, "B {b}");
}
