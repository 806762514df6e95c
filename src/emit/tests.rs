use super::shard::{shard_payload, ShardEmission};
use super::*;

/// The guided pick is the binary search it replaced: for random u, for u
/// at every CDF value and either side of it, and at the ends.
#[test]
fn guided_pick_equals_the_binary_search() {
    let scene = Scene::coastal(&Default::default()).unwrap();
    let e = Emitter::new(&scene).unwrap();
    let search = |u: f64| e.cdf.partition_point(|&c| c <= u).min(e.cdf.len() - 1);
    let mut rng = Pcg32::new(1, 2);
    let mut us: Vec<f64> = (0..100_000).map(|_| rng.uniform_f64()).collect();
    for &c in &e.cdf {
        us.extend([c, c.next_down(), c.next_up()]);
    }
    us.extend([0.0, 1.0 - f64::EPSILON / 2.0, 1.0]);
    for u in us.into_iter().filter(|u| (0.0..=1.0).contains(u)) {
        assert_eq!(e.pick(u), search(u), "u {u}");
    }
}

/// A shard's payload carries the tallies' 128-bit fixed-point sums whole:
/// sums of squares past 2^63 (a shard of 10^8 photons a band) survive the
/// shard header's JSON, where `serde_json::Value` refused them.
#[test]
fn shard_payloads_carry_sums_past_64_bits() {
    let scene = Scene::coastal(&Default::default()).unwrap();
    let e = Emitter::new(&scene).unwrap();
    let mut totals = Totals::new(scene.bands.len(), scene.tally_depths.len());
    totals.sum[0] = i128::MAX / 3;
    totals.sum_sq[1] = (i64::MAX as i128) * 1000 + 7;
    totals.sum[2] = i128::MIN / 5;
    let payload = ShardEmission {
        totals: totals.clone(),
        report_inputs: report::ReportInputs::new(&scene, &e.photon_power),
    };
    assert!(serde_json::to_value(&payload).is_err());
    let raw = shard_payload(&payload).unwrap();
    let back: ShardEmission = serde_json::from_str(raw.get()).unwrap();
    assert_eq!(back.totals, totals);
    assert_eq!(back.report_inputs, payload.report_inputs);
}
