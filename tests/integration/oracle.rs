//! Query oracle: kNN and radius results from the tiled store equal a brute
//! force search over every decoded photon — at random points, on and near
//! tile borders, outside the bounds and on the flat floor layer.
//!
//! The same checks run against the in-memory map built from the map's
//! decoded photons, and the two implementations of `PhotonQuery` are
//! compared with each other.
//!
//! Distances are compared with a relative slack of 1e-6 (f32 rounding in the
//! two distance computations); photons at distances within that slack of the
//! cut-off are ties and may be in either result.

use crate::common::*;
use glam::Vec3;
use littoral::photon::Photon;
use littoral::store::{InMemoryMap, MapFile, Neighbour, PhotonMap, PhotonQuery, Search};
use littoral::synth::Distribution;
use proptest::prelude::*;
use std::sync::OnceLock;

const REL: f32 = 1e-6;

struct Fixture {
    _dir: tempfile::TempDir,
    map: PhotonMap,
    memory: InMemoryMap,
    photons: Vec<Photon>,
}

impl Fixture {
    /// Both implementations of the query interface over the same photons.
    fn maps(&self) -> [&dyn PhotonQuery; 2] {
        [&self.map, &self.memory]
    }
}

fn fixture(d: Distribution) -> &'static Fixture {
    static UNIFORM: OnceLock<Fixture> = OnceLock::new();
    static WATER: OnceLock<Fixture> = OnceLock::new();
    let cell = match d {
        Distribution::Uniform => &UNIFORM,
        Distribution::Water => &WATER,
    };
    cell.get_or_init(|| {
        let dir = tempdir();
        // Small tiles: ~40 tiles, so most searches cross tile borders.
        let src = source(30_000, 8, 17, d);
        let (path, summary) = synth_map(dir.path(), "m.map", &src, Some(800), 2, 64 * MIB);
        assert!(summary.tiles >= 30, "{summary:?}");
        let file = MapFile::open(&path).unwrap();
        let photons = all_photons(&file);
        let memory = InMemoryMap::from_file(&file).unwrap();
        let map = PhotonMap::new(file, 1024 * MIB).unwrap();
        Fixture {
            _dir: dir,
            map,
            memory,
            photons,
        }
    })
}

fn close(a: f32, b: f32) -> bool {
    (a - b).abs() <= REL * a.abs().max(b.abs()) + 1e-12
}

pub fn check_knn(
    map: &dyn PhotonQuery,
    photons: &[Photon],
    at: Vec3,
    k: usize,
    max_r: Option<f32>,
) {
    let got = map
        .query(
            at,
            Search::Nearest {
                k,
                max_radius: max_r,
            },
        )
        .unwrap();
    let mut want = brute_sorted(photons, at);
    if let Some(r) = max_r {
        let r_sq = r * r;
        // Photons within rounding of the radius are ties: accept either count.
        let lo = want.partition_point(|&d| d < r_sq * (1.0 - REL));
        let hi = want.partition_point(|&d| d <= r_sq * (1.0 + REL));
        let n = got.len();
        assert!(
            n == k.min(want.len()) || (n >= lo.min(k) && n <= hi.min(k)),
            "at {at}: {n} neighbours, expected between {} and {}",
            lo.min(k),
            hi.min(k)
        );
        want.truncate(n);
    } else {
        want.truncate(k);
    }
    assert_eq!(got.len(), want.len(), "at {at}: neighbour count");
    check_sorted_and_real(&got, at);
    check_any_order(
        map,
        at,
        Search::Nearest {
            k,
            max_radius: max_r,
        },
        &got,
    );
    for (i, (g, w)) in got.iter().zip(&want).enumerate() {
        assert!(
            close(g.distance_sq, *w),
            "at {at}: neighbour {i}: {} vs brute {}",
            g.distance_sq,
            w
        );
    }
}

pub fn check_radius(map: &dyn PhotonQuery, photons: &[Photon], at: Vec3, r: f32) {
    let got = map.query(at, Search::Radius { radius: r }).unwrap();
    let want = brute_sorted(photons, at);
    let r_sq = r * r;
    let lo = want.partition_point(|&d| d < r_sq * (1.0 - REL));
    let hi = want.partition_point(|&d| d <= r_sq * (1.0 + REL));
    assert!(
        got.len() >= lo && got.len() <= hi,
        "at {at} r {r}: {} photons, brute force {lo}..={hi}",
        got.len()
    );
    check_sorted_and_real(&got, at);
    check_any_order(map, at, Search::Radius { radius: r }, &got);
    for (i, g) in got.iter().enumerate().take(lo) {
        assert!(close(g.distance_sq, want[i]), "at {at}: photon {i}");
    }
}

/// The unordered query finds the same photons (the same distances; photons
/// tied at the k-th distance may differ).
fn check_any_order(map: &dyn PhotonQuery, at: Vec3, search: Search, sorted: &[Neighbour]) {
    let mut any = Vec::new();
    map.query_any_order_into(at, None, search, &mut any)
        .unwrap();
    any.sort_by(|a, b| a.distance_sq.total_cmp(&b.distance_sq));
    let d = |v: &[Neighbour]| v.iter().map(|n| n.distance_sq).collect::<Vec<_>>();
    assert_eq!(d(&any), d(sorted), "at {at}: unordered query");
}

/// Results are ordered and each one's distance is its photon's real distance.
fn check_sorted_and_real(got: &[Neighbour], at: Vec3) {
    for w in got.windows(2) {
        assert!(w[0].distance_sq <= w[1].distance_sq);
    }
    for n in got {
        assert!(close(n.distance_sq, dist_sq(n.photon.position, at)));
    }
}

/// Points on, just inside and just outside the faces of every tile.
fn border_points(map: &MapFile) -> Vec<Vec3> {
    let mut pts = Vec::new();
    for t in map.tiles() {
        let c = (t.bounds.min + t.bounds.max) * 0.5;
        for axis in 0..3 {
            for face in [t.bounds.min[axis], t.bounds.max[axis]] {
                for eps in [0.0, 1e-4, -1e-4, 0.05] {
                    let mut p = c;
                    p[axis] = face + eps;
                    pts.push(p);
                }
            }
        }
        pts.push(t.bounds.min);
        pts.push(t.bounds.max);
    }
    pts
}

#[test]
fn knn_and_radius_at_tile_borders() {
    for d in [Distribution::Uniform, Distribution::Water] {
        let f = fixture(d);
        for at in border_points(f.map.file()) {
            for map in f.maps() {
                check_knn(map, &f.photons, at, 10, None);
                check_knn(map, &f.photons, at, 50, Some(1.5));
                check_radius(map, &f.photons, at, 1.2);
            }
        }
    }
}

#[test]
fn knn_on_the_floor_layer_and_far_outside() {
    let f = fixture(Distribution::Water);
    for at in [
        Vec3::new(50.0, 50.0, -10.0),
        Vec3::new(0.0, 0.0, -10.0),
        Vec3::new(99.9, 0.1, -10.0),
        Vec3::new(30.0, 70.0, -9.999),
        Vec3::new(-500.0, 40.0, 3.0),
        Vec3::new(50.0, 50.0, 1000.0),
        Vec3::new(1e6, -1e6, -1e6),
    ] {
        for map in f.maps() {
            check_knn(map, &f.photons, at, 1, None);
            check_knn(map, &f.photons, at, 64, None);
            check_radius(map, &f.photons, at, 2.0);
        }
    }
    // k larger than the map returns every photon.
    let all = f
        .map
        .query(
            Vec3::ZERO,
            Search::Nearest {
                k: 1_000_000,
                max_radius: None,
            },
        )
        .unwrap();
    assert_eq!(all.len(), f.photons.len());
    // A radius that catches nothing.
    let none = f
        .map
        .query(Vec3::new(1e6, 0.0, 0.0), Search::Radius { radius: 1.0 })
        .unwrap();
    assert!(none.is_empty());
}

/// Many random queries against a larger water map with the default tile size.
#[test]
fn large_random_cases() {
    let dir = tempdir();
    let src = source(300_000, 32, 99, Distribution::Water);
    let (path, _) = synth_map(dir.path(), "big.map", &src, Some(20_000), 2, 64 * MIB);
    let file = MapFile::open(&path).unwrap();
    let photons = all_photons(&file);
    assert_eq!(photons.len(), 300_000);
    let map = PhotonMap::new(file, 1024 * MIB).unwrap();
    let mut rng = littoral::rng::Pcg32::new(3, 0);
    for i in 0..400 {
        let at = Vec3::new(
            -5.0 + 110.0 * rng.uniform_f32(),
            -5.0 + 110.0 * rng.uniform_f32(),
            -11.0 + 12.0 * rng.uniform_f32(),
        );
        match i % 3 {
            0 => check_knn(&map, &photons, at, 50, None),
            1 => check_knn(&map, &photons, at, 50, Some(0.5)),
            _ => check_radius(&map, &photons, at, 0.6),
        }
    }
    // The batch API returns the same as one query at a time, in input order.
    let pts: Vec<Vec3> = (0..300)
        .map(|_| {
            Vec3::new(
                100.0 * rng.uniform_f32(),
                100.0 * rng.uniform_f32(),
                -3.0 * rng.uniform_f32(),
            )
        })
        .collect();
    let search = Search::Nearest {
        k: 20,
        max_radius: None,
    };
    let batch = map.query_batch(&pts, search).unwrap();
    for (p, b) in pts.iter().zip(&batch) {
        assert_eq!(*b, map.query(*p, search).unwrap());
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn knn_matches_brute_force(
        x in -20.0f32..120.0, y in -20.0f32..120.0, z in -14.0f32..4.0,
        k in 1usize..80, water in any::<bool>(), cap in proptest::option::of(0.05f32..5.0),
    ) {
        let f = fixture(if water { Distribution::Water } else { Distribution::Uniform });
        for map in f.maps() {
            check_knn(map, &f.photons, Vec3::new(x, y, z), k, cap);
        }
    }

    #[test]
    fn radius_matches_brute_force(
        x in -5.0f32..105.0, y in -5.0f32..105.0, z in -11.0f32..1.0,
        r in 0.0f32..4.0, water in any::<bool>(),
    ) {
        let f = fixture(if water { Distribution::Water } else { Distribution::Uniform });
        for map in f.maps() {
            check_radius(map, &f.photons, Vec3::new(x, y, z), r);
        }
    }

    #[test]
    fn queries_on_tile_faces(tile in 0usize..30, axis in 0usize..3, upper in any::<bool>(), u in 0.0f32..1.0, v in 0.0f32..1.0) {
        let f = fixture(Distribution::Water);
        let tiles = f.map.file().tiles();
        let b = tiles[tile % tiles.len()].bounds;
        let mut at = b.min + (b.max - b.min) * Vec3::new(u, v, (u + v) * 0.5);
        at[axis] = if upper { b.max[axis] } else { b.min[axis] };
        check_knn(&f.map, &f.photons, at, 16, None);
        check_radius(&f.map, &f.photons, at, 0.8);
    }
}

/// Queries restricted to one layer equal brute force over that layer's
/// photons (the water map keeps its floor photons in the surface layer).
#[test]
fn layer_queries_match_brute_force() {
    use littoral::photon::{LAYERS, LAYER_SURFACE, LAYER_VOLUME, LAYER_VOLUME_UP};
    use littoral::store::codec::TileDecoder;
    let f = fixture(Distribution::Water);
    let file = f.map.file();
    let mut by_layer: [Vec<Photon>; LAYERS] = Default::default();
    let mut dec = TileDecoder::default();
    let mut tile = Vec::new();
    for t in 0..file.tiles().len() as u32 {
        file.decode_tile(t, &mut dec, &mut tile).unwrap();
        for p in &tile {
            by_layer[p.layer as usize].push(p.unpack());
        }
    }
    assert!(by_layer[1].iter().all(|p| p.position.z == -10.0));
    assert!(by_layer[0].len() > 2 * by_layer[1].len() && !by_layer[1].is_empty());
    // Layered by the direction before quantisation.
    let eps = littoral::photon::OCT_MAX_ANGLE_ERROR_RAD;
    assert!(by_layer[0].iter().all(|p| p.direction.z <= eps));
    assert!(by_layer[2].iter().all(|p| p.direction.z > -eps) && !by_layer[2].is_empty());
    assert_eq!(file.layer_photons(LAYER_SURFACE), by_layer[1].len() as u64);
    let mut rng = littoral::rng::Pcg32::new(8, 8);
    for _ in 0..200 {
        let at = Vec3::new(
            100.0 * rng.uniform_f32(),
            100.0 * rng.uniform_f32(),
            -10.5 + 11.0 * rng.uniform_f32(),
        );
        for (layer, photons) in [
            (LAYER_VOLUME, &by_layer[0]),
            (LAYER_SURFACE, &by_layer[1]),
            (LAYER_VOLUME_UP, &by_layer[2]),
        ] {
            for map in f.maps() {
                let got = map
                    .query_layer(
                        at,
                        layer,
                        Search::Nearest {
                            k: 20,
                            max_radius: None,
                        },
                    )
                    .unwrap();
                let want = brute_sorted(photons, at);
                assert_eq!(got.len(), 20);
                for (g, w) in got.iter().zip(&want) {
                    assert!(close(g.distance_sq, *w), "layer {layer} at {at}");
                }
            }
        }
    }
}

/// The tiled map and the in-memory map answer every query with the same
/// photons: same distances, and the same photons once ties are ordered.
#[test]
fn in_memory_map_equals_the_tiled_map() {
    use littoral::photon::{LAYER_SURFACE, LAYER_VOLUME};
    let f = fixture(Distribution::Water);
    assert_eq!(
        f.memory.layer_photons(LAYER_VOLUME),
        f.map.layer_photons(LAYER_VOLUME)
    );
    assert_eq!(
        f.memory.layer_photons(LAYER_SURFACE),
        f.map.layer_photons(LAYER_SURFACE)
    );
    assert_eq!(PhotonQuery::bounds(&f.memory), PhotonQuery::bounds(&f.map));
    assert_eq!(f.memory.bands(), f.map.bands());
    let key = |v: &[Neighbour]| {
        let mut v: Vec<_> = v
            .iter()
            .map(|n| {
                let p = n.photon;
                (
                    n.distance_sq.to_bits(),
                    p.position.to_array().map(f32::to_bits),
                    p.band,
                    p.power.to_bits(),
                )
            })
            .collect();
        v.sort();
        v
    };
    let mut rng = littoral::rng::Pcg32::new(21, 4);
    for i in 0..300 {
        let at = Vec3::new(
            -5.0 + 110.0 * rng.uniform_f32(),
            -5.0 + 110.0 * rng.uniform_f32(),
            -11.0 + 12.0 * rng.uniform_f32(),
        );
        let layer = [None, Some(LAYER_VOLUME), Some(LAYER_SURFACE)][i % 3];
        // Radius searches have no ties at a cut-off k: the sets are equal.
        let search = Search::Radius {
            radius: 0.3 + 2.0 * rng.uniform_f32(),
        };
        let (mut a, mut b) = (Vec::new(), Vec::new());
        f.map.query_into(at, layer, search, &mut a).unwrap();
        f.memory.query_into(at, layer, search, &mut b).unwrap();
        assert_eq!(key(&a), key(&b), "radius query {i} at {at}");
        // k nearest: the same distances in the same order.
        let search = Search::Nearest {
            k: 1 + i % 90,
            max_radius: None,
        };
        f.map.query_into(at, layer, search, &mut a).unwrap();
        f.memory.query_into(at, layer, search, &mut b).unwrap();
        let d = |v: &[Neighbour]| v.iter().map(|n| n.distance_sq).collect::<Vec<_>>();
        assert_eq!(d(&a), d(&b), "k-nearest query {i} at {at}");
    }
}
