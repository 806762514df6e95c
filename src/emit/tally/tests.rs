use super::*;
use crate::emit::trace::FATE_UNIT;

/// A whole photon that escaped.
const ESCAPED: [u64; Fate::COUNT] = [FATE_UNIT, 0, 0, 0, 0, 0, 0];

#[test]
fn merging_in_any_order_gives_identical_totals() {
    let mut photons = Vec::new();
    for i in 0..100 {
        let mut t = PhotonTally::new(2);
        t.add(0, ED, 1.0);
        t.add(1, EOD, 1.0 / (0.013 + i as f64 * 0.0097));
        t.add_above_up(1.0);
        photons.push((i % 3, t));
    }
    let mut a = Totals::new(3, 2);
    let mut b = Totals::new(3, 2);
    let mut parts = [Totals::new(3, 2), Totals::new(3, 2)];
    for (i, (band, t)) in photons.iter().enumerate() {
        a.record(*band, &ESCAPED, t);
        parts[i % 2].record(*band, &ESCAPED, t);
    }
    b.merge(&parts[1]);
    b.merge(&parts[0]);
    assert_eq!(a, b);
    let (m, se) = a.mean_and_stderr(a.slot(0, ED), 0);
    assert!((m - 34.0 / 100.0).abs() < 1e-9 && se > 0.0);
}

/// The standard error the totals report is the sample standard error of
/// the mean over traced photons (zeros included), computed here by hand
/// with the two-pass formula sqrt(sum (x - m)^2 / (n (n - 1))).
#[test]
fn standard_error_matches_a_hand_computation() {
    let mut rng = crate::rng::Pcg32::new(5, 1);
    let n = 1000;
    // Heavy-tailed contributions with many zeros, like 1/|mu| crossings.
    let xs: Vec<f64> = (0..n)
        .map(|_| {
            let u = rng.uniform_f64();
            if u < 0.4 {
                0.0
            } else {
                1.0 / (0.01 + rng.uniform_f64())
            }
        })
        .collect();
    let mut totals = Totals::new(1, 1);
    for &x in &xs {
        let mut t = PhotonTally::new(1);
        t.add(0, EOU, x);
        totals.record(0, &ESCAPED, &t);
    }
    let m = xs.iter().sum::<f64>() / n as f64;
    let ss = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>();
    let se = (ss / (n as f64 * (n as f64 - 1.0))).sqrt();
    let (got_m, got_se) = totals.mean_and_stderr(totals.slot(0, EOU), 0);
    // Fixed-point sums (2^-32) leave ~1e-9 relative.
    assert!((got_m - m).abs() < 1e-9 * m, "{got_m} vs {m}");
    assert!((got_se - se).abs() < 1e-7 * se, "{got_se} vs {se}");
    // A quantity nothing contributed to has mean and error 0.
    assert_eq!(totals.mean_and_stderr(totals.slot(0, ED), 0), (0.0, 0.0));
}

/// One tally reused across photons (cleared between them), with more
/// slots than the touched mask has bits (12 depths: 74 slots): the totals
/// equal sums over every slot of every photon's contributions computed
/// without the mask, and a cleared tally holds nothing.
#[test]
fn touched_slots_account_every_contribution() {
    let depths = 12;
    let slots = depths * QUANTITIES + 2;
    let bands = 3;
    let mut rng = crate::rng::Pcg32::new(9, 4);
    let mut tally = PhotonTally::new(depths);
    let mut totals = Totals::new(bands, depths);
    let mut want = vec![0i128; slots * bands];
    let mut want_sq = vec![0i128; slots * bands];
    for photon in 0..500 {
        tally.clear();
        assert!(tally.values().iter().all(|&v| v == 0.0));
        let band = photon % bands;
        let mut values = vec![0.0; slots];
        for _ in 0..rng.below(6) {
            let slot = rng.below(slots as u32) as usize;
            let x = rng.uniform_f64();
            if slot == depths * QUANTITIES {
                values[slot] += 1.0;
                tally.add_above_down();
                continue;
            }
            values[slot] += x;
            if slot == depths * QUANTITIES + 1 {
                tally.add_above_up(x);
            } else {
                tally.add(slot / QUANTITIES, slot % QUANTITIES, x);
            }
        }
        for (slot, &x) in values.iter().enumerate() {
            if x != 0.0 {
                want[slot * bands + band] += fixed(x);
                want_sq[slot * bands + band] += fixed(x * x);
            }
        }
        assert_eq!(tally.values(), &values[..]);
        totals.record(band, &ESCAPED, &tally);
    }
    assert_eq!(totals.sum, want);
    assert_eq!(totals.sum_sq, want_sq);
}
