//! Geometry tests: BVH queries against a brute-force oracle, analytic
//! scenes with known hits, parsers, and the self-intersection policy.

use std::io::Write;
use std::path::{Path, PathBuf};

use glam::{DVec3, Vec3};

use super::builder::GeometryBuilder;
use super::{Axis, Geometry, Hit, SurfaceId, EPSILON_MIN_M};
use crate::bounds::Aabb;
use crate::rng::Pcg32;
use crate::Error;

const FLOOR: SurfaceId = 0;
const BOX: SurfaceId = 1;
const PANEL: SurfaceId = 2;

fn uniform_dir(rng: &mut Pcg32) -> Vec3 {
    let z = 1.0 - 2.0 * rng.uniform_f32();
    let phi = std::f32::consts::TAU * rng.uniform_f32();
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

fn uniform_in(rng: &mut Pcg32, lo: f32, hi: f32) -> f32 {
    lo + (hi - lo) * rng.uniform_f32()
}

/// Möller–Trumbore in f64: an oracle independent of the watertight test used
/// by the BVH queries. Returns t in (t_min, t_max].
fn moller_trumbore(o: Vec3, d: Vec3, tri: &[Vec3; 3], t_min: f32, t_max: f32) -> Option<f32> {
    let (o, d) = (o.as_dvec3(), d.as_dvec3());
    let [a, b, c]: [DVec3; 3] = tri.map(|v| v.as_dvec3());
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - a;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > t_min as f64 && t <= t_max as f64).then_some(t as f32)
}

/// Any brute-force hit with t in (t_min, t_max): what `occluded` answers.
fn brute_occluded(tris: &[[Vec3; 3]], o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> bool {
    tris.iter()
        .any(|tri| moller_trumbore(o, d, tri, t_min, t_max).is_some_and(|t| t < t_max))
}

/// The smallest ray parameter the queries accept, as `Geometry` computes it.
fn t_min_of(geom: &Geometry, dir: Vec3) -> f32 {
    (geom.epsilon_m() / dir.length()).max(EPSILON_MIN_M)
}

/// Closest hit over all triangles in builder order: (triangle, t).
fn brute_closest(
    tris: &[[Vec3; 3]],
    o: Vec3,
    d: Vec3,
    t_min: f32,
    t_max: f32,
) -> Option<(u32, f32)> {
    let mut best: Option<(u32, f32)> = None;
    for (i, tri) in tris.iter().enumerate() {
        if let Some(t) = moller_trumbore(o, d, tri, t_min, t_max) {
            if best.is_none_or(|(_, bt)| t < bt) {
                best = Some((i as u32, t));
            }
        }
    }
    best
}

/// Heightfield floor, boxes (some resting on or cutting into the floor) and
/// a panel, over a 100 m x 80 m domain.
fn oracle_scene() -> GeometryBuilder {
    let mut rng = Pcg32::new(7, 0);
    let (nx, ny) = (17, 13);
    let depths: Vec<f32> = (0..nx * ny)
        .map(|_| uniform_in(&mut rng, 5.0, 15.0))
        .collect();
    let mut b = GeometryBuilder::new([100.0, 80.0]);
    b.heightfield_floor(&depths, nx, ny, FLOOR).unwrap();
    for _ in 0..6 {
        let c = Vec3::new(
            uniform_in(&mut rng, 5.0, 95.0),
            uniform_in(&mut rng, 5.0, 75.0),
            uniform_in(&mut rng, -10.0, -2.0),
        );
        let s = Vec3::new(
            uniform_in(&mut rng, 0.5, 8.0),
            uniform_in(&mut rng, 0.5, 8.0),
            uniform_in(&mut rng, 0.5, 4.0),
        );
        b.add_box(c, s, BOX);
    }
    b.add_panel(Vec3::new(40.0, 30.0, -3.0), [6.0, 4.0], PANEL);
    b
}

/// Rays for the oracle tests: random origins and directions with finite and
/// infinite t_max, axis-aligned directions (zero components exercise obvhs'
/// safe inverse), and downward rays from the sea surface (the common case).
fn oracle_rays() -> Vec<(Vec3, Vec3, f32)> {
    let mut rng = Pcg32::new(11, 0);
    let mut rays = Vec::new();
    let origin = |rng: &mut Pcg32| {
        Vec3::new(
            uniform_in(rng, -10.0, 110.0),
            uniform_in(rng, -10.0, 90.0),
            uniform_in(rng, -20.0, 5.0),
        )
    };
    for i in 0..4000 {
        let o = origin(&mut rng);
        let d = uniform_dir(&mut rng);
        let t_max = if i % 2 == 0 {
            f32::INFINITY
        } else {
            uniform_in(&mut rng, 0.0, 150.0)
        };
        rays.push((o, d, t_max));
    }
    for i in 0..1200 {
        let o = origin(&mut rng);
        // Negated axes carry -0.0 components, which obvhs mishandles
        // unless the queries normalise them (see `positive_zeros`).
        let d = Vec3::AXES[i % 3] * if (i / 3) % 2 == 0 { 1.0 } else { -1.0 };
        rays.push((o, d, f32::INFINITY));
    }
    for _ in 0..1000 {
        let o = Vec3::new(
            uniform_in(&mut rng, 0.0, 100.0),
            uniform_in(&mut rng, 0.0, 80.0),
            0.0,
        );
        let mut d = uniform_dir(&mut rng);
        d.z = -d.z.abs();
        rays.push((o, d, f32::INFINITY));
    }
    rays
}

fn close(a: f32, b: f32, rel: f32) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1.0)
}

/// The BVH's closest hit is the brute-force closest hit: the same triangle
/// (in builder order), or a triangle at the same t where two tie (shared
/// edges), and misses agree.
#[test]
fn closest_hit_matches_brute_force() {
    let builder = oracle_scene();
    let tris = builder.tris_for_tests().to_vec();
    let geom = builder.build();
    assert_eq!(geom.triangle_count(), tris.len());
    let mut hits = 0;
    for (i, &(o, d, t_max)) in oracle_rays().iter().enumerate() {
        let got = geom.intersect(o, d, t_max);
        let want = brute_closest(&tris, o, d, t_min_of(&geom, d), t_max);
        match (got, want) {
            (None, None) => {}
            (Some(h), Some((tri, t))) => {
                hits += 1;
                assert!(
                    h.triangle == tri || close(h.t, t, 1e-5),
                    "ray {i}: BVH hit triangle {} at t {}, brute force {tri} at t {t}",
                    h.triangle,
                    h.t
                );
                assert!(close(h.t, t, 1e-5), "ray {i}: t {} vs {t}", h.t);
                assert!(h.t <= t_max);
                assert!(
                    (h.position - (o + d * h.t)).length() < 1e-3,
                    "ray {i}: position"
                );
                assert!(
                    h.normal.dot(d) < 0.0,
                    "ray {i}: normal faces away from the ray"
                );
                assert!((h.normal.length() - 1.0).abs() < 1e-5);
            }
            (got, want) => panic!("ray {i} ({o}, {d}, {t_max}): BVH {got:?}, brute force {want:?}"),
        }
    }
    // The test means something only if many rays hit (2222 of 6200 do;
    // most upward rays escape).
    assert!(hits > 2000, "only {hits} hits");
}

/// `occluded` agrees with "any brute-force hit with t in (eps, t_max)".
#[test]
fn occluded_matches_brute_force() {
    let builder = oracle_scene();
    let tris = builder.tris_for_tests().to_vec();
    let geom = builder.build();
    let mut blocked = 0;
    for (i, &(o, d, t_max)) in oracle_rays().iter().enumerate() {
        // Finite shadow-ray lengths for every ray.
        let t_max = if t_max.is_finite() {
            t_max
        } else {
            10.0 + (i % 50) as f32
        };
        let want = brute_occluded(&tris, o, d, t_min_of(&geom, d), t_max);
        assert_eq!(
            geom.occluded(o, d, t_max),
            want,
            "ray {i} ({o}, {d}, {t_max})"
        );
        blocked += want as usize;
    }
    assert!(blocked > 1000, "only {blocked} occluded");
}

/// A flat floor at depth D: a vertical ray from the surface hits at t = D
/// everywhere, including exactly on the domain edges and on the quad's
/// diagonal; `floor_depth_at` is D inside the domain and None well outside.
#[test]
fn flat_floor_depth() {
    let mut b = GeometryBuilder::new([100.0, 80.0]);
    b.flat_floor(12.5, FLOOR);
    let geom = b.build();
    assert_eq!(geom.triangle_count(), 2);
    let mut rng = Pcg32::new(3, 0);
    let mut points = vec![
        (0.0, 0.0),
        (100.0, 80.0),
        (0.0, 80.0),
        (100.0, 0.0),
        (50.0, 40.0),
        (25.0, 20.0),
    ];
    points.extend((0..200).map(|_| {
        (
            uniform_in(&mut rng, 0.0, 100.0),
            uniform_in(&mut rng, 0.0, 80.0),
        )
    }));
    for (x, y) in points {
        let h = geom
            .intersect(Vec3::new(x, y, 0.0), Vec3::NEG_Z, f32::INFINITY)
            .expect("hit");
        assert!(close(h.t, 12.5, 1e-6), "({x}, {y}): t = {}", h.t);
        assert_eq!(h.normal, Vec3::Z);
        assert_eq!(h.surface, FLOOR);
        assert!(close(geom.floor_depth_at(x, y).unwrap(), 12.5, 1e-6));
    }
    assert_eq!(geom.floor_depth_at(-50.0, 10.0), None);
    assert_eq!(geom.floor_depth_at(10.0, 200.0), None);
}

/// A slope floor's depth is linear along its axis and constant across it.
#[test]
fn slope_floor_is_linear() {
    for axis in [Axis::X, Axis::Y] {
        let mut b = GeometryBuilder::new([100.0, 80.0]);
        b.slope_floor(5.0, 25.0, axis, FLOOR);
        let geom = b.build();
        assert_eq!(geom.triangle_count(), 2);
        let mut rng = Pcg32::new(5, 0);
        for _ in 0..200 {
            let (x, y) = (
                uniform_in(&mut rng, 0.0, 100.0),
                uniform_in(&mut rng, 0.0, 80.0),
            );
            let want = match axis {
                Axis::X => 5.0 + 20.0 * x / 100.0,
                Axis::Y => 5.0 + 20.0 * y / 80.0,
            };
            let h = geom
                .intersect(Vec3::new(x, y, 0.0), Vec3::NEG_Z, f32::INFINITY)
                .expect("hit");
            assert!(
                close(h.t, want, 1e-5),
                "{axis:?} ({x}, {y}): {} vs {want}",
                h.t
            );
            assert!(close(geom.floor_depth_at(x, y).unwrap(), want, 1e-5));
            assert!(h.normal.z > 0.0);
        }
    }
}

/// A heightfield reproduces its depths at the grid points, interpolates
/// linearly along each cell's diagonal, and covers the domain edges.
#[test]
fn heightfield_floor_depths() {
    let (nx, ny) = (5, 4);
    let depths: Vec<f32> = (0..nx * ny).map(|i| 3.0 + (i * 7 % 11) as f32).collect();
    let mut b = GeometryBuilder::new([40.0, 30.0]);
    b.heightfield_floor(&depths, nx, ny, FLOOR).unwrap();
    // Grid cells plus the skirt around the edges.
    assert_eq!(b.triangle_count(), 2 * (nx + 1) * (ny + 1));
    let geom = b.build();
    let (dx, dy) = (40.0 / (nx - 1) as f32, 30.0 / (ny - 1) as f32);
    for iy in 0..ny {
        for ix in 0..nx {
            let got = geom.floor_depth_at(ix as f32 * dx, iy as f32 * dy).unwrap();
            assert!(
                close(got, depths[iy * nx + ix], 1e-5),
                "({ix}, {iy}): {got}"
            );
        }
    }
    for iy in 0..ny - 1 {
        for ix in 0..nx - 1 {
            let want = 0.5 * (depths[iy * nx + ix] + depths[(iy + 1) * nx + ix + 1]);
            let got = geom
                .floor_depth_at((ix as f32 + 0.5) * dx, (iy as f32 + 0.5) * dy)
                .unwrap();
            assert!(close(got, want, 1e-5), "cell ({ix}, {iy}): {got} vs {want}");
        }
    }
    // Just outside the domain the skirt repeats the edge depth.
    assert!(close(
        geom.floor_depth_at(-0.01, 0.0).unwrap(),
        depths[0],
        1e-5
    ));
}

#[test]
fn heightfield_rejects_bad_grids() {
    let mut b = GeometryBuilder::new([10.0, 10.0]);
    assert!(b.heightfield_floor(&[1.0, 2.0], 2, 1, FLOOR).is_err());
    assert!(b.heightfield_floor(&[1.0, 2.0, 3.0], 2, 2, FLOOR).is_err());
    assert!(b
        .heightfield_floor(&[1.0, 2.0, f32::NAN, 4.0], 2, 2, FLOOR)
        .is_err());
    let err = b
        .heightfield_floor(&[1.0, 2.0, 3.0, f32::INFINITY], 2, 2, FLOOR)
        .unwrap_err();
    assert!(err.to_string().contains("row 1][column 1]"), "{err}");
    assert!(b
        .heightfield_floor(&[1.0; 4], usize::MAX, 2, FLOOR)
        .is_err());
    let mut bad_domain = GeometryBuilder::new([0.0, 10.0]);
    assert!(bad_domain
        .heightfield_floor(&[1.0; 4], 2, 2, FLOOR)
        .is_err());
    assert_eq!(b.triangle_count(), 0);
}

/// Rays from outside along each axis hit the facing side at the known
/// distance with that side's outward normal; from inside, the normal is
/// flipped to face the ray. The rays pass through each face's centre, which
/// lies on the diagonal shared by its two triangles.
#[test]
fn box_faces_and_normals() {
    let center = Vec3::new(10.0, 20.0, -5.0);
    let size = Vec3::new(2.0, 4.0, 6.0);
    let mut b = GeometryBuilder::new([100.0, 100.0]);
    b.add_box(center, size, BOX);
    assert_eq!(b.triangle_count(), 12);
    let geom = b.build();
    for axis in 0..3 {
        for side in [-1.0f32, 1.0] {
            let outward = Vec3::AXES[axis] * side;
            let half = size[axis] * 0.5;
            let face = center + outward * half;
            let h = geom
                .intersect(center + outward * (half + 10.0), -outward, f32::INFINITY)
                .expect("hit from outside");
            assert!(close(h.t, 10.0, 1e-6), "axis {axis} side {side}: t {}", h.t);
            assert_eq!(h.normal, outward);
            assert!((h.position - face).length() < 1e-5);
            assert_eq!(h.surface, BOX);
            let h = geom
                .intersect(center, outward, f32::INFINITY)
                .expect("hit from inside");
            assert!(close(h.t, half, 1e-6));
            assert_eq!(h.normal, -outward);
        }
    }
    // Winding: every triangle's (v1 - v0) x (v2 - v0) points away from the centre.
    let tris = geom.tris.iter();
    for tri in tris {
        let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
        let c = (tri[0] + tri[1] + tri[2]) / 3.0;
        assert!(n.dot(c - center) > 0.0, "inward winding");
    }
}

/// A panel is hit from above (normal up) and from below (normal down).
#[test]
fn panel_two_sided() {
    let mut b = GeometryBuilder::new([100.0, 80.0]);
    b.add_panel(Vec3::new(50.0, 40.0, -3.0), [4.0, 2.0], PANEL);
    let geom = b.build();
    let h = geom
        .intersect(Vec3::new(50.5, 40.2, 0.0), Vec3::NEG_Z, f32::INFINITY)
        .expect("from above");
    assert!(close(h.t, 3.0, 1e-6));
    assert_eq!(h.normal, Vec3::Z);
    assert_eq!(h.surface, PANEL);
    let h = geom
        .intersect(Vec3::new(50.5, 40.2, -10.0), Vec3::Z, f32::INFINITY)
        .expect("from below");
    assert!(close(h.t, 7.0, 1e-6));
    assert_eq!(h.normal, Vec3::NEG_Z);
    assert!(geom.occluded(Vec3::new(51.9, 40.9, -10.0), Vec3::Z, 10.0));
    assert!(geom
        .intersect(Vec3::new(52.1, 40.0, 0.0), Vec3::NEG_Z, f32::INFINITY)
        .is_none());
    assert!(!geom.occluded(Vec3::new(52.1, 40.0, 0.0), Vec3::NEG_Z, 100.0));
    // The panel is not floor.
    assert_eq!(geom.floor_depth_at(50.0, 40.0), None);
}

/// Closest hit includes t_max, occlusion excludes it; t scales with |dir|.
#[test]
fn t_range_and_direction_length() {
    let mut b = GeometryBuilder::new([100.0, 80.0]);
    b.flat_floor(10.0, FLOOR);
    b.add_panel(Vec3::new(50.0, 40.0, -4.0), [2.0, 2.0], PANEL);
    let geom = b.build();
    let o = Vec3::new(20.0, 20.0, 0.0);
    assert!(geom.intersect(o, Vec3::NEG_Z, 10.0).is_some());
    assert!(geom.intersect(o, Vec3::NEG_Z, 9.999).is_none());
    assert!(!geom.occluded(o, Vec3::NEG_Z, 10.0));
    assert!(geom.occluded(o, Vec3::NEG_Z, 10.001));
    let h = geom
        .intersect(o, Vec3::new(0.0, 0.0, -2.0), f32::INFINITY)
        .unwrap();
    assert!(close(h.t, 5.0, 1e-6));
    // The floor is found under the panel.
    assert!(close(geom.floor_depth_at(50.0, 40.0).unwrap(), 10.0, 1e-6));
    let h = geom
        .intersect(Vec3::new(50.0, 40.0, 0.0), Vec3::NEG_Z, f32::INFINITY)
        .unwrap();
    assert_eq!(h.surface, PANEL);
}

/// No floor and no targets: infinitely deep water.
#[test]
fn empty_geometry() {
    let geom = GeometryBuilder::new([100.0, 80.0]).build();
    assert_eq!(geom.triangle_count(), 0);
    assert_eq!(geom.bounds(), Aabb::EMPTY);
    assert!(geom
        .intersect(Vec3::ZERO, Vec3::NEG_Z, f32::INFINITY)
        .is_none());
    assert!(!geom.occluded(Vec3::ZERO, Vec3::NEG_Z, 1e9));
    assert_eq!(geom.floor_depth_at(1.0, 1.0), None);
    // One Geometry is shared by all tracing threads.
    fn shareable<T: Send + Sync>(_: &T) {}
    shareable(&geom);
}

/// One triangle builds and is hit; degenerate and non-finite triangles are
/// dropped and counted; invalid rays return no hit rather than panicking.
#[test]
fn single_degenerate_and_invalid() {
    let mut b = GeometryBuilder::new([10.0, 10.0]);
    b.add_triangle(
        Vec3::new(1.0, 1.0, -1.0),
        Vec3::new(1.0, 1.0, -1.0),
        Vec3::new(2.0, 1.0, -1.0),
        5,
    );
    b.add_triangle(
        Vec3::new(f32::NAN, 1.0, -1.0),
        Vec3::new(3.0, 1.0, -1.0),
        Vec3::new(2.0, 3.0, -1.0),
        5,
    );
    b.add_triangle(
        Vec3::new(0.0, 0.0, -2.0),
        Vec3::new(4.0, 0.0, -2.0),
        Vec3::new(0.0, 4.0, -2.0),
        7,
    );
    let geom = b.build();
    assert_eq!(geom.triangle_count(), 1);
    assert_eq!(geom.skipped_triangles(), 2);
    let h = geom
        .intersect(Vec3::new(1.0, 1.0, 0.0), Vec3::NEG_Z, f32::INFINITY)
        .unwrap();
    assert_eq!((h.surface, h.triangle), (7, 2));
    assert!(geom.bounds().is_valid());
    let o = Vec3::new(1.0, 1.0, 0.0);
    assert!(geom
        .intersect(Vec3::new(f32::NAN, 1.0, 0.0), Vec3::NEG_Z, 10.0)
        .is_none());
    assert!(geom.intersect(o, Vec3::ZERO, 10.0).is_none());
    assert!(geom
        .intersect(o, Vec3::new(0.0, f32::INFINITY, -1.0), 10.0)
        .is_none());
    assert!(geom.intersect(o, Vec3::NEG_Z, f32::NAN).is_none());
    assert!(geom.intersect(o, Vec3::NEG_Z, -1.0).is_none());
    assert!(!geom.occluded(o, Vec3::ZERO, 10.0));
    assert_eq!(geom.floor_depth_at(f32::NAN, 0.0), None);
    // Shapes with nonsense sizes degrade to skipped triangles, not panics.
    let mut b = GeometryBuilder::new([f32::NAN, 0.0]);
    b.flat_floor(10.0, FLOOR);
    b.slope_floor(1.0, 2.0, Axis::Y, FLOOR);
    b.add_box(Vec3::ZERO, Vec3::new(1.0, 0.0, 1.0), BOX);
    b.add_panel(Vec3::splat(f32::INFINITY), [1.0, 1.0], PANEL);
    let geom = b.build();
    // Only the box's two 1 x 1 faces (at y = 0) have area.
    assert_eq!(geom.triangle_count(), 4);
    assert!(geom
        .intersect(Vec3::new(5.0, 5.0, 0.0), Vec3::NEG_Z, f32::INFINITY)
        .is_none());
}

fn write_file(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    let mut f = std::fs::File::create(&path).unwrap();
    f.write_all(text.as_bytes()).unwrap();
    path
}

const TETRA_AND_QUAD: &str = "\
# a tetrahedron and a quad
mtllib none.mtl
o tet
v 0 0 0
v 1 0 0
v 0 1 0
v 0 0 1 1.0
vt 0 0
vn 0 0 1
f 1 3 2
f 1/1 2/1 4/1
f 1//1 4//1 3//1
f -3/1/1 -2/1/1 -1/1/1   # vertices 2 3 4
s off
v 5 5 0
v 6 5 0
v 6 6 0
v 5 6 0
usemtl x
f -4 -3 -2 -1
";

/// The OBJ reader takes every face form, negative indices and polygons; the
/// mesh is placed at offset + scale * v.
#[test]
fn obj_faces_and_transform() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_file(dir.path(), "mesh.obj", TETRA_AND_QUAD);
    let mut b = GeometryBuilder::new([100.0, 100.0]);
    b.add_obj(&path, Vec3::new(10.0, 10.0, -5.0), 2.0, 3)
        .unwrap();
    assert_eq!(b.triangle_count(), 6);
    let geom = b.build();
    // The slanted face x + y + z = 1 (local) under local (0.1, 0.1): z = 0.8.
    let h = geom
        .intersect(Vec3::new(10.2, 10.2, 0.0), Vec3::NEG_Z, f32::INFINITY)
        .unwrap();
    assert!(close(h.t, 5.0 - 1.6, 1e-5), "t {}", h.t);
    assert!((h.normal - Vec3::ONE.normalize()).length() < 1e-5);
    assert_eq!(h.surface, 3);
    // The quad spans local [5, 6]^2 at z = 0, i.e. world [20, 22]^2 at z = -5.
    let h = geom
        .intersect(Vec3::new(21.0, 21.5, 0.0), Vec3::NEG_Z, f32::INFINITY)
        .unwrap();
    assert!(close(h.t, 5.0, 1e-6));
    assert!(geom
        .intersect(Vec3::new(22.5, 21.0, 0.0), Vec3::NEG_Z, f32::INFINITY)
        .is_none());
}

fn assert_err_at(err: Error, path: &Path, line: usize, what: &str) {
    let msg = err.to_string();
    assert!(
        msg.contains(&format!("{}: line {line}:", path.display())),
        "{msg}"
    );
    assert!(msg.contains(what), "{msg}");
}

/// Malformed OBJ files give errors naming the file and line, and add nothing.
#[test]
fn obj_errors_name_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "v 0 0 0\nv 1 0 0\nv 1 x 0\n",
            3,
            "bad vertex coordinate 'x'",
        ),
        ("v 0 0 0\nv 1 0\n", 2, "needs 3 coordinates"),
        ("v 0 0 0\nv 1 0 inf\n", 2, "not finite"),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 4\n",
            5,
            "index 4 out of range",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
            4,
            "index 0 out of range",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n",
            4,
            "index -4 out of range",
        ),
        ("v 0 0 0\nv 1 0 0\nf 1 2\n", 3, "needs at least 3"),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 a/2 3\n",
            4,
            "bad face vertex 'a/2'",
        ),
        // A face may only use vertices defined before it.
        ("v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n", 3, "out of range"),
    ];
    for (i, (text, line, what)) in cases.iter().enumerate() {
        let path = write_file(dir.path(), &format!("bad{i}.obj"), text);
        let mut b = GeometryBuilder::new([10.0, 10.0]);
        let err = b.add_obj(&path, Vec3::ZERO, 1.0, 0).unwrap_err();
        assert_err_at(err, &path, *line, what);
        assert_eq!(b.triangle_count(), 0);
    }
    let mut b = GeometryBuilder::new([10.0, 10.0]);
    let missing = dir.path().join("missing.obj");
    assert!(matches!(
        b.add_obj(&missing, Vec3::ZERO, 1.0, 0),
        Err(Error::Io { .. })
    ));
    let good = write_file(dir.path(), "good.obj", TETRA_AND_QUAD);
    assert!(b.add_obj(&good, Vec3::ZERO, 0.0, 0).is_err());
    assert!(b.add_obj(&good, Vec3::splat(f32::NAN), 1.0, 0).is_err());
}

#[test]
fn heightfield_csv() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_file(
        dir.path(),
        "floor.csv",
        "# depths in m, first row y = 0\n5, 6, 7\n\n8,9,10 # trailing comment\n11 12 13\n",
    );
    let (depths, nx, ny) = GeometryBuilder::heightfield_from_csv(&path).unwrap();
    assert_eq!((nx, ny), (3, 3));
    assert_eq!(depths, [5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0, 12.0, 13.0]);
    let mut b = GeometryBuilder::new([20.0, 20.0]);
    b.heightfield_floor(&depths, nx, ny, FLOOR).unwrap();
    assert!(close(
        b.build().floor_depth_at(20.0, 0.0).unwrap(),
        7.0,
        1e-6
    ));

    let cases = [
        ("1,2\n3,x\n", 2, "'x' is not a finite number"),
        ("1,2\n# c\n3,4,5\n", 3, "3 fields, but line 1 has 2 fields"),
        ("1,2,3\n3,,4\n", 2, "empty field"),
        ("1,2\n3,inf\n", 2, "'inf' is not a finite number"),
    ];
    for (i, (text, line, what)) in cases.iter().enumerate() {
        let path = write_file(dir.path(), &format!("bad{i}.csv"), text);
        let err = GeometryBuilder::heightfield_from_csv(&path).unwrap_err();
        assert_err_at(err, &path, *line, what);
    }
    let path = write_file(dir.path(), "short.csv", "1, 2, 3\n");
    assert!(GeometryBuilder::heightfield_from_csv(&path).is_err());
    let missing = dir.path().join("missing.csv");
    assert!(matches!(
        GeometryBuilder::heightfield_from_csv(&missing),
        Err(Error::Io { .. })
    ));
}

/// A direction leaving the surface with normal `n` at angle acos(cos_theta)
/// from it, at azimuth `phi`.
fn leaving(n: Vec3, cos_theta: f32, phi: f32) -> Vec3 {
    let (t, b) = n.any_orthonormal_pair();
    let s = (1.0 - cos_theta * cos_theta).sqrt();
    (n * cos_theta + (t * phi.cos() + b * phi.sin()) * s).normalize()
}

/// Self-intersection policy: a ray starting exactly at a hit point and
/// leaving the surface (up to ~87° from its normal, either side of two-sided
/// surfaces) does not hit that surface again; with `spawn_origin` not even
/// at 89.9°. Hit points are aimed at random points of every surface — a
/// slope, box faces, a 45° slab, a panel — on a 100 m scene and a 10 km one,
/// where f32 hit points are ~100x coarser. Tilted surfaces matter: on an
/// axis-aligned plane the interpolated hit point is exact.
#[test]
fn leaving_rays_do_not_rehit() {
    const SLAB: SurfaceId = 3;
    for size in [100.0f32, 10_000.0] {
        let mut b = GeometryBuilder::new([size, size]);
        b.slope_floor(20.0, 40.0, Axis::X, FLOOR);
        b.add_box(
            Vec3::new(0.2 * size, 0.2 * size, -12.0),
            Vec3::new(0.15 * size, 0.15 * size, 6.0),
            BOX,
        );
        b.add_panel(
            Vec3::new(0.5 * size, 0.5 * size, -8.0),
            [0.2 * size, 0.2 * size],
            PANEL,
        );
        let (c, u, v) = (
            Vec3::new(0.8 * size, 0.7 * size, -10.0),
            Vec3::new(0.1 * size, 0.0, 0.0),
            Vec3::new(0.0, 10.0, 10.0),
        );
        b.add_triangle(c - u - v, c + u - v, c + u + v, SLAB);
        b.add_triangle(c - u - v, c + u + v, c - u + v, SLAB);
        let (tris, surfaces) = (b.tris.clone(), b.surfaces.clone());
        let geom = b.build();
        let mut rng = Pcg32::new(13, size as u64);
        let mut count = [0usize; 4];
        for _ in 0..4000 {
            // Aim at a uniform random point of a random triangle, from the
            // outside of the box and the top of the floor, from either side
            // of the two-sided panel and slab.
            let i = rng.below(tris.len() as u32) as usize;
            let [p0, p1, p2] = tris[i];
            let su = rng.uniform_f32().sqrt();
            let (b0, b1) = (1.0 - su, rng.uniform_f32() * su);
            let target = p0 * b0 + p1 * b1 + p2 * (1.0 - b0 - b1);
            let mut n = (p1 - p0).cross(p2 - p0).normalize();
            if matches!(surfaces[i], PANEL | SLAB) && rng.uniform_f32() < 0.5 {
                n = -n;
            }
            let d_in = -leaving(
                n,
                uniform_in(&mut rng, 0.3, 1.0),
                std::f32::consts::TAU * rng.uniform_f32(),
            );
            let Some(hit) = geom.intersect(target - d_in * 3.0, d_in, f32::INFINITY) else {
                continue;
            };
            count[hit.surface as usize] += 1;
            // Every surface here is convex or flat, so any hit on the surface
            // just left is a self-intersection.
            let same = |h: Option<Hit>| h.is_some_and(|h| h.surface == hit.surface);
            let n = hit.normal; // faces the side the ray came from
            let phi = std::f32::consts::TAU * rng.uniform_f32();
            let cos_theta = uniform_in(&mut rng, 0.05, 1.0);
            let r = leaving(n, cos_theta, phi);
            assert!(
                !same(geom.intersect(hit.position, r, f32::INFINITY)),
                "{size}: re-hit {hit:?} along {r}"
            );
            if matches!(hit.surface, PANEL | SLAB) {
                let tr = leaving(-n, cos_theta, phi);
                assert!(
                    !same(geom.intersect(hit.position, tr, f32::INFINITY)),
                    "{size}: transmitted re-hit {hit:?} along {tr}"
                );
            }
            let g = leaving(n, 1e-3, phi);
            let o2 = geom.spawn_origin(hit.position, hit.normal, g);
            assert!(
                !same(geom.intersect(o2, g, f32::INFINITY)),
                "{size}: grazing re-hit {hit:?} along {g}"
            );
        }
        assert!(
            count.iter().all(|&c| c > 100),
            "{size}: hits per surface {count:?}"
        );
    }
}

impl GeometryBuilder {
    /// The collected triangles in builder order, for oracles.
    fn tris_for_tests(&self) -> &[[Vec3; 3]] {
        &self.tris
    }
}

/// From a point nearer a surface than the self-intersection epsilon (an
/// instrument 0.1 mm above the floor), `intersect` misses the floor but
/// `intersect_from_point` finds it at the right distance; a surface behind
/// the point is not reported, and farther hits agree with `intersect`.
#[test]
fn intersect_from_point_finds_a_surface_inside_the_epsilon() {
    let mut b = GeometryBuilder::new([100.0, 80.0]);
    b.flat_floor(3.0, FLOOR);
    b.add_panel(Vec3::new(50.0, 40.0, -1.0), [4.0, 4.0], 1);
    let g = b.build();
    assert!(g.epsilon_m() > 1e-4);
    let p = Vec3::new(20.0, 20.0, -3.0 + 1e-4);
    assert!(g.intersect(p, -Vec3::Z, 10.0).is_none());
    let h = g
        .intersect_from_point(p, -Vec3::Z, 10.0)
        .expect("the floor");
    assert_eq!(h.surface, FLOOR);
    assert!((h.t - 1e-4).abs() < 5e-5, "t {}", h.t);
    // Just below the panel, looking down: the panel is behind, the floor ahead.
    let q = Vec3::new(50.0, 40.0, -1.0 - 1e-4);
    let h = g
        .intersect_from_point(q, -Vec3::Z, 10.0)
        .expect("the floor");
    assert_eq!(h.surface, FLOOR);
    let far = Vec3::new(30.0, 30.0, -1.5);
    let (a, b) = (
        g.intersect(far, -Vec3::Z, 10.0).unwrap(),
        g.intersect_from_point(far, -Vec3::Z, 10.0).unwrap(),
    );
    assert!((a.t - b.t).abs() < 1e-5 && a.surface == b.surface);
}

mod ceiling;

#[test]
fn extent_since_bounds_the_last_shape_and_counts_proper_triangles() {
    let mut b = GeometryBuilder::new([10.0, 10.0]);
    b.flat_floor(3.0, 0);
    let first = b.triangle_count();
    b.add_box(Vec3::new(5.0, 4.0, -1.0), Vec3::new(2.0, 1.0, 0.5), 1);
    let (bounds, proper) = b.extent_since(first);
    assert_eq!(bounds.min, Vec3::new(4.0, 3.5, -1.25));
    assert_eq!(bounds.max, Vec3::new(6.0, 4.5, -0.75));
    assert_eq!(proper, 12);
    // Zero-area triangles count in the bounds but not as proper.
    let first = b.triangle_count();
    b.add_triangle(Vec3::ZERO, Vec3::X, 2.0 * Vec3::X, 2);
    assert_eq!(
        b.extent_since(first),
        (
            Aabb {
                min: Vec3::ZERO,
                max: 2.0 * Vec3::X
            },
            0
        )
    );
    assert_eq!(b.extent_since(b.triangle_count()).0, Aabb::EMPTY);
}
