//! The column ceiling (`geometry::ceiling`) against brute force: it may
//! skip the BVH only for segments that hit nothing.

use super::*;

/// Short segments, as between scattering events: every one the column
/// ceiling clears has no brute-force hit (close above the floor, the boxes
/// and the panel included), queries agree with brute force whether or not
/// the ceiling answered, and every segment clearly above the triangles
/// near it (more than the margin above any whose box comes within 1 m,
/// more than a column) is cleared without the BVH.
#[test]
fn the_ceiling_clears_only_segments_that_hit_nothing() {
    let builder = oracle_scene();
    let tris = builder.tris_for_tests().to_vec();
    let geom = builder.build();
    let margin = 4.0 * geom.epsilon_m;
    let mut rng = Pcg32::new(23, 0);
    let (mut cleared, mut near, mut clearly_above, mut hits) = (0, 0, 0, 0);
    let n = 40_000;
    for i in 0..n {
        let o = Vec3::new(
            uniform_in(&mut rng, -2.0, 102.0),
            uniform_in(&mut rng, -2.0, 82.0),
            uniform_in(&mut rng, -16.0, 0.0),
        );
        let d = uniform_dir(&mut rng);
        let t_max = uniform_in(&mut rng, 0.0, 3.0);
        let t_min = t_min_of(&geom, d);
        let want = brute_closest(&tris, o, d, t_min, t_max);
        let e = o + d * t_max;
        let (lo, hi) = (o.min(e), o.max(e));
        // The highest vertex of the triangles whose box comes within 1 m.
        let top_near = tris
            .iter()
            .filter(|t| {
                let (tl, th) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
                tl.x <= hi.x + 1.0 && th.x >= lo.x - 1.0 && tl.y <= hi.y + 1.0 && th.y >= lo.y - 1.0
            })
            .map(|t| t[0].z.max(t[1].z).max(t[2].z))
            .fold(f32::NEG_INFINITY, f32::max);
        let clear = geom.clear(o, d, t_max);
        if clear {
            cleared += 1;
            assert!(
                want.is_none(),
                "segment {i} ({o}, {d}, {t_max}) cleared but hits {want:?}"
            );
            near += (lo.z - top_near < 0.05) as usize;
        }
        if lo.z > top_near + margin {
            clearly_above += 1;
            assert!(
                clear,
                "segment {i} ({o}, {d}, {t_max}) is clearly above but not cleared"
            );
        }
        let got = geom.intersect(o, d, t_max);
        assert_eq!(
            got.is_some(),
            want.is_some(),
            "segment {i}: {got:?} vs {want:?}"
        );
        if let (Some(h), Some((_, t))) = (got, want) {
            hits += 1;
            assert!(close(h.t, t, 1e-5), "segment {i}: t {} vs {t}", h.t);
        }
        let want_blocked = brute_occluded(&tris, o, d, t_min, t_max);
        assert_eq!(
            geom.occluded(o, d, t_max),
            want_blocked,
            "segment {i}: occluded"
        );
    }
    // The test means something only if all three kinds are common.
    assert!(hits > 500, "only {hits} hits");
    assert!(
        clearly_above > n / 5,
        "only {clearly_above} of {n} clearly above"
    );
    assert!(
        near > 100,
        "only {near} cleared segments came within 5 cm of a surface's top"
    );
    assert!(cleared >= clearly_above);
}

/// A sloping floor of two triangles across the whole scene (the built-in
/// scene's): the ceiling follows the plane column by column, so a segment
/// a few centimetres above the floor anywhere is cleared, and none it
/// clears hits the floor.
#[test]
fn the_ceiling_follows_a_sloping_floor() {
    let mut b = GeometryBuilder::new([200.0, 200.0]);
    b.slope_floor(0.5, 15.0, Axis::X, FLOOR);
    let tris = b.tris_for_tests().to_vec();
    let geom = b.build();
    let mut rng = Pcg32::new(29, 0);
    let depth = |x: f32| 0.5 + 14.5 * x.clamp(0.0, 200.0) / 200.0;
    let (mut cleared, mut above) = (0, 0);
    for i in 0..20_000 {
        let o = Vec3::new(
            uniform_in(&mut rng, 0.0, 200.0),
            uniform_in(&mut rng, 0.0, 200.0),
            0.0,
        );
        let o = Vec3::new(o.x, o.y, -depth(o.x) * uniform_in(&mut rng, 0.0, 1.2));
        let d = uniform_dir(&mut rng);
        let t_max = uniform_in(&mut rng, 0.0, 2.0);
        let e = o + d * t_max;
        let want = brute_closest(&tris, o, d, t_min_of(&geom, d), t_max);
        let clear = geom.clear(o, d, t_max);
        if clear {
            cleared += 1;
            assert!(
                want.is_none(),
                "segment {i} ({o}, {d}, {t_max}) cleared but hits"
            );
        }
        // Deeper than the floor anywhere within two columns (3.1 m) of it,
        // by more than 5 cm: then the ceiling must clear it.
        let floor = (-2..=2)
            .map(|k| -depth(o.x.min(e.x) + k as f32 * 1.6))
            .chain((-2..=2).map(|k| -depth(o.x.max(e.x) + k as f32 * 1.6)))
            .fold(f32::NEG_INFINITY, f32::max);
        if o.z.min(e.z) > floor + 0.05 {
            above += 1;
            assert!(
                clear,
                "segment {i} ({o}, {d}, {t_max}) is above the floor but not cleared"
            );
        }
    }
    assert!(above > 10_000, "only {above} segments above the floor");
    assert!(cleared >= above);
}
