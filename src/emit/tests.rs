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
