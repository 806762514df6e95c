//! The ceiling's own kernels; the ceiling against brute force through the
//! whole geometry is in `geometry/tests/ceiling.rs` (it needs the geometry
//! tests' scenes and oracles).

use super::*;
use crate::rng::Pcg32;

/// The four-lane columns are the scalar ones, for segments inside,
/// across and beside the box, on its sides, far outside the grid, and
/// from points with infinite or NaN coordinates (to the finite ends
/// `clear` passes on).
#[test]
fn lane_columns_match_the_scalar_columns() {
    let tris = [
        [
            Vec3::new(-3.0, 2.0, -5.0),
            Vec3::new(57.0, 2.0, -1.0),
            Vec3::new(-3.0, 41.5, -9.0),
        ],
        [
            Vec3::new(57.0, 41.5, -2.0),
            Vec3::new(57.0, 2.0, -1.0),
            Vec3::new(-3.0, 41.5, -9.0),
        ],
    ];
    let bounds = Aabb {
        min: Vec3::new(-3.0, 2.0, -9.0),
        max: Vec3::new(57.0, 41.5, -1.0),
    };
    let c = Ceiling::new(&tris, &bounds, 1e-3).unwrap();
    let mut rng = Pcg32::new(31, 0);
    let mut coord = |lo: f32, hi: f32| lo + (hi - lo) * rng.uniform_f32();
    let mut points: Vec<Vec3> = (0..200_000)
        .map(|_| Vec3::new(coord(-10.0, 65.0), coord(-5.0, 50.0), coord(-10.0, 0.0)))
        .collect();
    let specials = [
        -3.0,
        57.0,
        2.0,
        41.5,
        -3.001,
        57.001,
        0.0,
        -0.0,
        1e30,
        -1e30,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        f32::MAX,
        f32::MIN,
    ];
    for &x in &specials {
        for &y in &specials {
            points.push(Vec3::new(x, y, -2.0));
        }
    }
    let (mut beside, mut inside) = (0, 0);
    for pair in points.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        if !(b.x.is_finite() && b.y.is_finite()) {
            continue;
        }
        let lanes = c.columns(a, b);
        assert_eq!(lanes, c.columns_scalar(a, b), "{a} -> {b}");
        match lanes {
            None => beside += 1,
            Some(_) => inside += 1,
        }
    }
    assert!(
        beside > 1000 && inside > 100_000,
        "{beside} beside, {inside} inside"
    );
}
