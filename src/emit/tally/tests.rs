use super::*;

#[test]
fn merging_in_any_order_gives_identical_totals() {
    let mut photons = Vec::new();
    for i in 0..100 {
        let mut t = PhotonTally::new(2);
        t.add(0, ED, 1.0);
        t.add(1, EOD, 1.0 / (0.013 + i as f64 * 0.0097));
        t.add_above_up();
        photons.push((i % 3, t));
    }
    let mut a = Totals::new(3, 2);
    let mut b = Totals::new(3, 2);
    let mut parts = [Totals::new(3, 2), Totals::new(3, 2)];
    for (i, (band, t)) in photons.iter().enumerate() {
        a.record(*band, Fate::Escaped, t);
        parts[i % 2].record(*band, Fate::Escaped, t);
    }
    b.merge(&parts[1]);
    b.merge(&parts[0]);
    assert_eq!(a, b);
    let (m, se) = a.mean_and_stderr(a.slot(0, ED), 0);
    assert!((m - 34.0 / 100.0).abs() < 1e-9 && se > 0.0);
}
