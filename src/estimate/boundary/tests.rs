//! Tests of the parent module.
use super::*;
use crate::rng::Pcg32;
use crate::scene::Overrides;
use crate::testing::{rel, simpson};
use rayon::prelude::*;
use std::path::Path;

fn cap_volume(r: f64, d: f64) -> f64 {
    let h = r - d;
    PI * h * h * (3.0 * r - h) / 3.0
}

/// Circular segment beyond a chord at distance d from the centre.
fn segment_area(r: f64, d: f64) -> f64 {
    if d >= r {
        return 0.0;
    }
    r * r * (d / r).acos() - d * (r * r - d * d).sqrt()
}

/// Volume of {x > a, y > b} within the ball of radius r, as the integral
/// over x of the circular segment {y > b} of the slice — an independent
/// route (acos segment formula, adaptive Simpson) to the overlap of two
/// perpendicular caps.
fn two_cap_overlap(r: f64, a: f64, b: f64) -> f64 {
    let end = (r * r - b * b).sqrt();
    if a >= end {
        return 0.0;
    }
    let f = |x: f64| segment_area((r * r - x * x).max(0.0).sqrt(), b);
    simpson(&f, a, end, 1e-15)
}

/// Gauss-Legendre nodes integrate polynomials up to degree 2n - 1 exactly.
#[test]
fn gauss_legendre_is_exact_for_polynomials() {
    let rule = gauss_legendre(GL_POINTS);
    for k in 0..2 * GL_POINTS {
        let q: f64 = rule.iter().map(|&(t, w)| w * t.powi(k as i32)).sum();
        assert!(rel(q, 1.0 / (k as f64 + 1.0)) < 1e-13, "degree {k}: {q}");
    }
}

/// The quadrant area matches the direct integral int_0^a min(b, sqrt(rho^2 - u^2)) du.
#[test]
fn quadrant_area_matches_direct_integral() {
    let mut rng = Pcg32::new(11, 0);
    for _ in 0..200 {
        let rho = 0.5 + rng.uniform_f64();
        let a = 1.2 * rho * rng.uniform_f64();
        let b = 1.2 * rho * rng.uniform_f64();
        let f = |u: f64| b.min((rho * rho - u * u).max(0.0).sqrt());
        let direct = simpson(&f, 0.0, a.min(rho), 1e-14);
        let got = quadrant_area(rho, a, b);
        assert!(
            (got - direct).abs() < 1e-11,
            "rho {rho} a {a} b {b}: {got} vs {direct}"
        );
    }
}

/// Splitting every quadrature interval into 7 changes the octant volumes
/// by less than 1e-12 relative: the 20-point rule has converged.
#[test]
fn octant_quadrature_has_converged() {
    let mut rng = Pcg32::new(12, 0);
    let r = 1.7;
    let mut worst = 0.0f64;
    for _ in 0..2000 {
        let s = [0, 1, 2].map(|_| r * rng.uniform_f64());
        let coarse = octant_volume(r, s[0], s[1], s[2], 1);
        let fine = octant_volume(r, s[0], s[1], s[2], 7);
        worst = worst.max(rel(coarse, fine));
    }
    eprintln!("octant quadrature: worst relative change on refinement {worst:.2e}");
    assert!(worst < 1e-12, "{worst}");
}

/// Test 2: against closed forms to 1e-6 relative (observed ~1e-14).
/// One plane at distance d: V = 4/3 pi r^3 - pi h^2 (3r - h)/3, h = r - d,
/// on each of the six sides. Two perpendicular planes a, b:
/// V = sphere - cap(a) - cap(b) + overlap(a, b), the overlap integrated
/// independently ([`two_cap_overlap`]). Two opposite planes: the caps
/// never overlap. Degenerate boxes: V = 0, half, quarter, eighth.
#[test]
fn clipped_sphere_matches_closed_forms() {
    let r = 1.3;
    let sphere = sphere_volume(r);
    let mut worst = 0.0f64;
    let mut check = |got: f64, want: f64, what: &str| {
        let e = if want == 0.0 {
            got.abs()
        } else {
            rel(got, want)
        };
        assert!(e < 1e-6, "{what}: {got} vs {want}");
        worst = worst.max(e);
    };
    for d in [0.0, 1e-9, 0.01, 0.3, 0.65, 1.0, 1.29, 1.3] {
        for side in 0..6 {
            let mut b = [r; 6];
            b[side] = d;
            let want = sphere - cap_volume(r, d);
            check(
                clipped_sphere_volume(r, &b),
                want,
                &format!("cap d {d} side {side}"),
            );
        }
    }
    let pairs = [
        (0.0, 0.0),
        (0.1, 0.2),
        (0.5, 0.5),
        (0.9, 0.3),
        (1.0, 1.0),
        (1.2, 0.05),
    ];
    for &(a, bb) in &pairs {
        // Perpendicular pairs on several axis combinations.
        for (i, j) in [(0, 2), (1, 4), (3, 5), (5, 0)] {
            let mut b = [r; 6];
            b[i] = a;
            b[j] = bb;
            let want = sphere - cap_volume(r, a) - cap_volume(r, bb) + two_cap_overlap(r, a, bb);
            check(
                clipped_sphere_volume(r, &b),
                want,
                &format!("perpendicular {a} {bb}"),
            );
        }
        // Opposite planes.
        let mut b = [r; 6];
        b[2] = a;
        b[3] = bb;
        let want = sphere - cap_volume(r, a) - cap_volume(r, bb);
        check(
            clipped_sphere_volume(r, &b),
            want,
            &format!("opposite {a} {bb}"),
        );
    }
    // Thin slabs between opposite planes: pi (r^2 w - (a^3 + b^3)/3),
    // w = a + b, where sphere - cap - cap would cancel.
    for (a, bb) in [(1e-6, 2e-6), (1e-3, 0.0), (0.02, 0.03)] {
        let want = PI * (r * r * (a + bb) - (a * a * a + bb * bb * bb) / 3.0);
        let got = clipped_sphere_volume(r, &[r, r, r, r, a, bb]);
        check(got, want, &format!("slab {a} {bb}"));
    }
    let mut b = [r; 6];
    b[0] = 0.0;
    b[1] = 0.0;
    check(clipped_sphere_volume(r, &b), 0.0, "both x sides at O");
    check(
        clipped_sphere_volume(r, &[0.0, r, r, r, r, r]),
        sphere / 2.0,
        "half",
    );
    check(
        clipped_sphere_volume(r, &[0.0, r, 0.0, r, r, r]),
        sphere / 4.0,
        "quarter",
    );
    check(
        clipped_sphere_volume(r, &[r, 0.0, r, 0.0, 0.0, r]),
        sphere / 8.0,
        "eighth",
    );
    check(clipped_sphere_volume(r, &[r; 6]), sphere, "no planes");
    // A box inside the sphere is just the box.
    check(clipped_sphere_volume(r, &[0.5; 6]), 1.0, "inner box");
    eprintln!("clipped sphere vs closed forms: worst relative error {worst:.2e}");
}

/// Fraction of `n` uniform points of the cube [-r, r]^3 inside the sphere
/// and the box `b`, counted in parallel chunks with per-chunk streams.
fn mc_clipped_sphere(r: f64, b: &[f64; 6], n: u64, seed: u64) -> f64 {
    const CHUNK: u64 = 100_000;
    let hits: u64 = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut rng = Pcg32::new(seed, c);
            let count = CHUNK.min(n - c * CHUNK);
            let mut hits = 0u64;
            for _ in 0..count {
                let x = (2.0 * rng.uniform_f64() - 1.0) * r;
                let y = (2.0 * rng.uniform_f64() - 1.0) * r;
                let z = (2.0 * rng.uniform_f64() - 1.0) * r;
                let inside = x * x + y * y + z * z <= r * r
                    && x <= b[0]
                    && -x <= b[1]
                    && y <= b[2]
                    && -y <= b[3]
                    && z <= b[4]
                    && -z <= b[5];
                hits += inside as u64;
            }
            hits
        })
        .sum();
    hits as f64 / n as f64
}

/// Test 1: the clipped-sphere volume against Monte Carlo, 10^7 points per
/// configuration, 24 random configurations with 1 to 6 active planes
/// (B < R), plus a plane through O and two close opposite planes. The
/// estimate 8 r^3 p_hat has standard error 8 r^3 sqrt(p (1 - p) / n);
/// the tolerance is 4 standard errors.
#[test]
fn clipped_sphere_matches_monte_carlo() {
    let r = 1.3;
    let n = 10_000_000u64;
    let mut rng = Pcg32::new(2026, 0);
    let mut configs = Vec::new();
    for i in 0..24 {
        let active = 1 + i % 6;
        let mut sides = [0usize, 1, 2, 3, 4, 5];
        for s in 0..6 {
            let j = s + rng.below((6 - s) as u32) as usize;
            sides.swap(s, j);
        }
        let mut b = [r; 6];
        for &s in &sides[..active] {
            b[s] = r * rng.uniform_f64();
        }
        configs.push(b);
    }
    configs[3][5] = 0.0; // a plane through O (-z), with others
    configs[7][0] = 0.0;
    configs[10][2] = 0.08 * r; // two opposite planes, both close
    configs[10][3] = 0.05 * r;
    configs.push([0.1 * r, 0.12 * r, r, r, r, r]);
    let cube = 8.0 * r * r * r;
    let mut worst_z = 0.0f64;
    for (i, b) in configs.iter().enumerate() {
        let exact = clipped_sphere_volume(r, b);
        let p_hat = mc_clipped_sphere(r, b, n, 100 + i as u64);
        let p = exact / cube;
        let se = cube * (p * (1.0 - p) / n as f64).sqrt();
        let z = (cube * p_hat - exact) / se;
        worst_z = worst_z.max(z.abs());
        assert!(
            z.abs() < 4.0,
            "config {i} {b:?}: exact {exact}, MC {} ({z:.2} SE)",
            cube * p_hat
        );
    }
    eprintln!(
        "clipped sphere vs Monte Carlo: {} configurations, worst |z| = {worst_z:.2} SE",
        configs.len()
    );
}

/// Test 3: the ellipsoid volume. All B = R gives the sphere; one side
/// B_+z = d gives the upper half-ellipsoid (2/3 pi R^2 d) plus the lower
/// half-sphere; and the volume of {D' <= R} measured by Monte Carlo (2e6
/// uniform points of the cube [-R, R]^3 per configuration, tolerance 4
/// standard errors) matches.
#[test]
fn ellipsoid_volume_matches_its_region() {
    let r = 1.3f64;
    assert!(rel(ellipsoid_volume(&[r; 6]), sphere_volume(r)) < 1e-15);
    for d in [0.0, 0.2, 0.9] {
        let mut b = [r; 6];
        b[4] = d;
        let want = 2.0 / 3.0 * PI * r * r * d + sphere_volume(r) / 2.0;
        let got = ellipsoid_volume(&b);
        assert!((got - want).abs() <= 1e-14 * want, "d {d}: {got} vs {want}");
    }
    let rf = r as f32;
    let configs = [
        AxialDistances([rf; 6]),
        AxialDistances([rf, rf, rf, rf, 0.3, rf]),
        AxialDistances([0.2, 1.0, rf, 0.0, 0.7, 0.4]),
        AxialDistances([0.1, 0.15, 0.9, 0.5, 1.2, 0.05]),
    ];
    let n = 2_000_000u64;
    let cube = 8.0 * r * r * r;
    for (i, b) in configs.iter().enumerate() {
        let mut rng = Pcg32::new(31, i as u64);
        let mut hits = 0u64;
        for _ in 0..n {
            let p = Vec3::new(
                (2.0 * rng.uniform_f32() - 1.0) * rf,
                (2.0 * rng.uniform_f32() - 1.0) * rf,
                (2.0 * rng.uniform_f32() - 1.0) * rf,
            );
            hits += (ellipsoid_distance(p, rf, b) <= rf) as u64;
        }
        let exact = ellipsoid_volume(&b.to_f64());
        let p = exact / cube;
        let se = cube * (p * (1.0 - p) / n as f64).sqrt();
        let mc = cube * hits as f64 / n as f64;
        let z = (mc - exact) / se;
        eprintln!("ellipsoid config {i}: exact {exact:.6}, MC {mc:.6} ({z:+.2} SE)");
        assert!(z.abs() < 4.0, "config {i}: exact {exact}, MC {mc}");
    }
    // Offsets toward a side with B = 0 are outside; along it, inside.
    let b = AxialDistances([1.0, 0.0, 1.0, 1.0, 1.0, 1.0]);
    assert_eq!(
        ellipsoid_distance(Vec3::new(-1e-6, 0.0, 0.0), 1.0, &b),
        f32::INFINITY
    );
    assert_eq!(ellipsoid_distance(Vec3::new(0.0, 0.5, 0.0), 1.0, &b), 0.5);
}

/// Test 4: the clipped disc. Closed forms: one line at d, pi r^2 minus the
/// segment r^2 acos(d/r) - d sqrt(r^2 - d^2); two opposite lines, or two
/// perpendicular lines whose corner lies outside the disc, minus both
/// segments (they cannot overlap). Monte Carlo: 4e6 points of the square
/// per configuration, within 4 standard errors.
#[test]
fn clipped_disc_matches_closed_forms_and_monte_carlo() {
    let r = 0.8f64;
    let disc = PI * r * r;
    for d in [0.0, 1e-7, 0.2, 0.5, 0.79, 0.8] {
        for side in 0..4 {
            let mut b = [r; 4];
            b[side] = d;
            let want = disc - segment_area(r, d);
            let got = clipped_disc_area(r, &b);
            assert!(rel(got, want) < 1e-12, "d {d} side {side}: {got} vs {want}");
        }
    }
    for (a, c) in [(0.1, 0.3), (0.6, 0.7), (0.0, 0.5)] {
        let want = disc - segment_area(r, a) - segment_area(r, c);
        let opposite = clipped_disc_area(r, &[a, c, r, r]);
        assert!(rel(opposite, want) < 1e-12, "opposite {a} {c}: {opposite}");
        if a * a + c * c >= r * r {
            let perpendicular = clipped_disc_area(r, &[a, r, c, r]);
            assert!(
                rel(perpendicular, want) < 1e-12,
                "perp {a} {c}: {perpendicular}"
            );
        }
    }
    assert_eq!(clipped_disc_area(r, &[0.0, 0.0, r, r]), 0.0);
    let configs = [
        [0.3, r, 0.2, r],
        [0.1, 0.75, 0.6, 0.05],
        [0.0, r, 0.4, 0.7],
        [0.6; 4],
    ];
    let n = 4_000_000u64;
    let square = 4.0 * r * r;
    for (i, b) in configs.iter().enumerate() {
        let mut rng = Pcg32::new(41, i as u64);
        let mut hits = 0u64;
        for _ in 0..n {
            let u = (2.0 * rng.uniform_f64() - 1.0) * r;
            let v = (2.0 * rng.uniform_f64() - 1.0) * r;
            let inside =
                u * u + v * v <= r * r && u <= b[0] && -u <= b[1] && v <= b[2] && -v <= b[3];
            hits += inside as u64;
        }
        let exact = clipped_disc_area(r, b);
        let p = exact / square;
        let se = square * (p * (1.0 - p) / n as f64).sqrt();
        let mc = square * hits as f64 / n as f64;
        let z = (mc - exact) / se;
        eprintln!("disc config {i}: exact {exact:.6}, MC {mc:.6} ({z:+.2} SE)");
        assert!(z.abs() < 4.0, "config {i}: exact {exact}, MC {mc}");
    }
}

#[test]
fn modes_parse_and_print() {
    let b = AxialDistances::unbounded(2.0);
    for m in BoundaryMode::ALL {
        assert!(rel(m.volume(2.0, &b), sphere_volume(2.0)) < 1e-12, "{m}");
    }
}

/// A 20 m x 10 m domain, floor at 5 m, a 2 x 2 x 1 m box spanning
/// x 9..11, y 4..6, z -4.5..-3.5.
fn box_scene(edges: &str) -> Scene {
    let toml = crate::testing::minimal_with(&format!(
        r#"
spectral = {{ start_nm = 500.0, end_nm = 500.0, bands = 1 }}
domain = {{ size_m = [20.0, 10.0], edges = "{edges}" }}
water = {{ iop = {{ a = 0.1, b = 0.1 }} }}
bottom = {{ depth_m = 5.0, reflectance = 0.1 }}
target = [{{ kind = "box", center_m = [10.0, 5.0, -4.0], size_m = [2.0, 2.0, 1.0], reflectance = 0.2 }}]
"#
    ));
    Scene::parse(&toml, Path::new("t.toml"), &Overrides::default())
        .unwrap_or_else(|e| panic!("{e}"))
}

/// What f32 rounding can leave of an interpolation that is exact in exact
/// arithmetic, in the 20 m box scene (see [`grid_matches_tracing`]).
const ROUNDING_M: f32 = 1e-4;

fn assert_close(got: AxialDistances, want: [f32; 6], what: &str) {
    for k in 0..6 {
        assert!(
            (got.0[k] - want[k]).abs() < 1e-4,
            "{what}: side {k}: {:?} vs {want:?}",
            got.0
        );
    }
}

/// Test 5: traced distances to the surface, floor, box and walls, the
/// cap at R, and periodic edges (wrapping rays, R when nothing is hit).
#[test]
fn traced_distances_in_a_box_scene() {
    let s = box_scene("open");
    let t = |o: Vec3, r| axial_distances_traced(&s, o, r);
    // Surface 2 m up, floor 3 m down, wall 3 m to -x; the rest beyond R.
    assert_close(
        t(Vec3::new(3.0, 5.0, -2.0), 4.0),
        [4.0, 3.0, 4.0, 4.0, 2.0, 3.0],
        "o1",
    );
    assert_close(t(Vec3::new(3.0, 5.0, -2.0), 1.0), [1.0; 6], "o1 capped");
    // Beside the box: its -x face 2 m ahead, floor 0.8 m down.
    assert_close(
        t(Vec3::new(7.0, 4.5, -4.2), 4.0),
        [2.0, 4.0, 4.0, 4.0, 4.0, 0.8],
        "o2",
    );
    // Above the box: its top 1.5 m down.
    assert_close(
        t(Vec3::new(10.0, 5.0, -2.0), 4.0),
        [4.0, 4.0, 4.0, 4.0, 2.0, 1.5],
        "o3",
    );
    // Near the -x, +y walls and the floor.
    assert_close(
        t(Vec3::new(0.5, 9.7, -4.9), 4.0),
        [4.0, 0.5, 0.3, 4.0, 4.0, 0.1],
        "o4",
    );
    // Outside the water: zero toward the boundary crossed.
    assert_eq!(t(Vec3::new(3.0, 5.0, 0.5), 4.0).0[4], 0.0);
    assert_eq!(t(Vec3::new(-1.0, 5.0, -1.0), 4.0).0[1], 0.0);
    assert_eq!(t(Vec3::NAN, 4.0).0, [0.0; 6]);

    let p = box_scene("periodic");
    let t = |o: Vec3, r| axial_distances_traced(&p, o, r);
    assert_close(
        t(Vec3::new(3.0, 5.0, -2.0), 4.0),
        [4.0, 4.0, 4.0, 4.0, 2.0, 3.0],
        "p1",
    );
    // +x wraps at 0.5 m and meets the box's -x face at x = 9.
    assert_close(
        t(Vec3::new(19.5, 5.0, -4.0), 10.0),
        [9.5, 8.5, 10.0, 10.0, 4.0, 1.0],
        "p2",
    );
    assert_close(
        t(Vec3::new(19.5, 5.0, -4.0), 4.0),
        [4.0, 4.0, 4.0, 4.0, 4.0, 1.0],
        "p2 capped",
    );
}

/// Test 6: the grid against tracing at 20 000 random water sites, R = 3 m,
/// spacing 0.25 m. A direction's field is discontinuous where its ray
/// starts or stops meeting the box: across the box's faces parallel to
/// the ray, and in cells reaching into the box. Away from those (2
/// spacings) the field is linear or constant per cell (the box's faces,
/// the floor and the 4 m storage cap fall on nodes), so interpolation is
/// exact up to f32 rounding, and so is the below-floor extension for the
/// -z distance next to the floor. Rounding: site coordinates up to 20 m
/// carry 1.9e-6 m, the trilinear sum of eight nodes of up to 4 m a few
/// ulps of 4 m (4.8e-7 m each), and the fields' gradients are at most 1:
/// [`ROUNDING_M`] = 1e-4 m is over 20 times that (measured 4.8e-7 m and
/// 6e-8 m). A periodic grid must carry wrapped distances.
#[test]
fn grid_matches_tracing() {
    let s = box_scene("open");
    let h = 0.25f32;
    let r = 3.0f32;
    let grid = BoundaryGrid::build(&s, h, 4.0).unwrap();
    assert_eq!(
        grid.bytes(),
        BoundaryGrid::planned_bytes(&s, h, 4.0).unwrap()
    );
    let (lo, hi) = (Vec3::new(9.0, 4.0, -4.5), Vec3::new(11.0, 6.0, -3.5));
    let m = 2.0 * h;
    let smooth = |o: Vec3, k: usize| {
        let near_box = (0..3).all(|a| o[a] > lo[a] - m && o[a] < hi[a] + m);
        let near_parallel_face = (0..3)
            .filter(|&a| a != k / 2)
            .any(|a| (o[a] - lo[a]).abs() < m || (o[a] - hi[a]).abs() < m);
        !near_box && !near_parallel_face
    };
    let mut rng = Pcg32::new(61, 0);
    let (mut all_sum, mut all_max, mut all_n) = (0f64, 0f32, 0usize);
    let (mut smooth_sum, mut smooth_max, mut smooth_n) = (0f64, 0f32, 0usize);
    let (mut floor_max, mut floor_n) = (0f32, 0usize);
    let mut sites = 0;
    while sites < 20_000 {
        let o = Vec3::new(
            20.0 * rng.uniform_f32(),
            10.0 * rng.uniform_f32(),
            -5.0 * rng.uniform_f32(),
        );
        let in_box = (0..3).all(|a| o[a] > lo[a] && o[a] < hi[a]);
        if in_box || o.z > -1e-3 || o.z < -4.999 {
            continue;
        }
        sites += 1;
        let traced = axial_distances_traced(&s, o, r);
        let interp = grid.distances(o, r);
        for k in 0..6 {
            let e = (traced.0[k] - interp.0[k]).abs();
            all_n += 1;
            all_sum += e as f64;
            all_max = all_max.max(e);
            if smooth(o, k) {
                smooth_n += 1;
                smooth_sum += e as f64;
                smooth_max = smooth_max.max(e);
                if k == 5 && o.z < -5.0 + m {
                    floor_n += 1;
                    floor_max = floor_max.max(e);
                }
            }
        }
    }
    eprintln!(
        "grid vs traced (spacing {h} m, R {r} m, {} bytes, {sites} sites): \
         all {all_n} distances mean {:.2e} m max {all_max:.3} m; \
         away from box discontinuities {smooth_n} mean {:.2e} m max {smooth_max:.2e} m; \
         -z within {m} m of the floor {floor_n} max {floor_max:.2e} m",
        grid.bytes(),
        all_sum / all_n as f64,
        smooth_sum / smooth_n as f64,
    );
    assert!(floor_n > 100 && smooth_n > all_n / 2);
    assert!(smooth_max < ROUNDING_M, "{smooth_max}");
    assert!(floor_max < ROUNDING_M, "{floor_max}");

    let p = box_scene("periodic");
    let grid = BoundaryGrid::build(&p, h, 10.0).unwrap();
    for o in [Vec3::new(19.5, 5.0, -4.0), Vec3::new(19.9, 5.1, -3.9)] {
        let want = axial_distances_traced(&p, o, 10.0);
        let got = grid.distances(o, 10.0);
        assert!(
            (want.0[0] - got.0[0]).abs() < 1e-3,
            "{o}: {want:?} vs {got:?}"
        );
        assert!((want.0[0] - (29.0 - o.x)).abs() < 1e-4, "{o}: {want:?}");
    }
}

/// The grid on the built-in coastal scene (floor sloping 14.5 m over
/// 200 m, periodic edges), 1 m spacing, R = 2 m, at 20 000 water sites
/// more than 5 m from the targets. On a gentle slope the horizontal
/// distance toward the shore grows ~14 m per metre of height, so a grid
/// that stores distances capped at 2R has a kink inside the cells next to
/// the floor and interpolates it badly; storing up to 30 m keeps the
/// field linear there (the below-floor extension is exact for a planar
/// slope). The periodic edge joins the beach to 15 m water: a -x
/// ray near the shore either meets the slope or passes over the step
/// into deep water, a discontinuity like a target's edge, so sites
/// within 15 m of the edge are reported apart. Away from the step the 30 m
/// grid is exact up to f32 rounding: site coordinates up to 200 m carry
/// 1.5e-5 m (gradient 1 along x), depths up to 15 m 1e-6 m times the
/// horizontal field's gradient of 14 per metre of height, and the
/// eight-node sum a few ulps of 30 m (1.9e-6 m each): 3e-4 m is about
/// eight times their sum (measured 1.7e-5 m).
#[test]
fn grid_on_a_sloping_floor() {
    let s = Scene::coastal(&Overrides::default()).unwrap();
    let r = 2.0f32;
    let targets = [
        Vec3::new(66.0, 140.0, -3.95),
        Vec3::new(114.0, 150.0, -7.65),
    ];
    let mut rng = Pcg32::new(71, 0);
    let mut sites = Vec::new();
    while sites.len() < 20_000 {
        let (x, y) = (200.0 * rng.uniform_f32(), 200.0 * rng.uniform_f32());
        let far = targets
            .iter()
            .all(|t| (t.x - x).abs() > 6.5 || (t.y - y).abs() > 6.5);
        let depth = s.geometry.floor_depth_at(x, y).unwrap();
        // (Under water: the beach rises above it toward x = 0.)
        if far && depth > 0.0 {
            sites.push(Vec3::new(
                x,
                y,
                -depth * (0.001 + 0.998 * rng.uniform_f32()),
            ));
        }
    }
    let traced: Vec<_> = sites
        .iter()
        .map(|&o| axial_distances_traced(&s, o, r))
        .collect();
    let mut worst_interior = 0.0;
    for max_distance in [2.0 * r, 30.0] {
        let grid = BoundaryGrid::build(&s, 1.0, max_distance).unwrap();
        // [interior, near the periodic step] x per side.
        let (mut sum, mut max, mut n) = ([[0f64; 6]; 2], [[0f32; 6]; 2], [0usize; 2]);
        for (o, t) in sites.iter().zip(&traced) {
            let g = grid.distances(*o, r);
            let part = usize::from(o.x < 15.0 || o.x > 185.0);
            n[part] += 1;
            for k in 0..6 {
                let e = (t.0[k] - g.0[k]).abs();
                sum[part][k] += e as f64;
                max[part][k] = max[part][k].max(e);
            }
        }
        for (part, name) in ["interior", "near the periodic step"].iter().enumerate() {
            let mean = sum[part].map(|v| format!("{:.1e}", v / n[part] as f64));
            eprintln!(
                "coastal grid 1 m, stored up to {max_distance} m ({} bytes), {name} ({} sites): \
                 mean error per side {mean:?} m, max {:.3?} m",
                grid.bytes(),
                n[part],
                max[part],
            );
        }
        worst_interior = max[0].iter().copied().fold(0.0, f32::max);
    }
    eprintln!("coastal grid stored up to 30 m: worst interior error {worst_interior:.2e} m");
    assert!(worst_interior < 3e-4, "{worst_interior}");
}

#[test]
fn grid_rejects_bad_spacing() {
    let s = box_scene("periodic");
    for bad in [0.0, -1.0, f32::NAN, f32::INFINITY, 1e-9] {
        assert!(BoundaryGrid::build(&s, bad, 4.0).is_err(), "{bad}");
    }
    assert!(BoundaryGrid::build(&s, 1.0, 0.0).is_err());
}

/// The local-linear factor recovers the density at the site from photons
/// of a density that varies linearly with depth: a sphere of radius 2 cut
/// 0.6 above the site (the sea surface) and whole below, the density 1 +
/// 0.4 z, integrated on a 160^3 grid of cells over the cut sphere (an
/// oracle independent of the slab moments the factor uses). The plain
/// estimate (weight over volume) reads the centroid's density, 0.85 here;
/// with the factor it reads 1 within the grid's error. Uncut, the factor
/// is 1.
#[test]
fn vertical_linear_factor_recovers_the_density_at_the_site() {
    let r = 2.0f64;
    let b = AxialDistances([2.0, 2.0, 2.0, 2.0, 0.6, 2.0]);
    let n = 160;
    let h = 2.0 * r / n as f64;
    let (mut v, mut s0, mut s1) = (0.0, 0.0, 0.0);
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                let c = |m: usize| -r + (m as f64 + 0.5) * h;
                let (x, y, z) = (c(i), c(j), c(k));
                if x * x + y * y + z * z > r * r || z > 0.6 {
                    continue;
                }
                let rho = 1.0 + 0.4 * z;
                v += h * h * h;
                s0 += rho * h * h * h;
                s1 += rho * z * h * h * h;
            }
        }
    }
    let plain = s0 / v;
    let linear = plain * vertical_linear_factor(r, &b, s1 / s0);
    assert!(
        (plain - 1.0).abs() > 0.1,
        "the plain estimate is biased: {plain}"
    );
    assert!(
        (linear - 1.0).abs() < 2e-3,
        "local-linear {linear} (plain {plain})"
    );
    assert_eq!(
        vertical_linear_factor(r, &AxialDistances::unbounded(2.0), 0.3),
        1.0
    );
}
