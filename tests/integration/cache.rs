//! The tile cache under a tiny budget with many threads: resident bytes
//! never exceed the budget, each residency costs exactly one decode, and
//! query results do not change.

use crate::common::*;
use glam::Vec3;
use littoral::store::cache::tile_bytes;
use littoral::store::MapFile;
use littoral::store::{PhotonMap, PhotonQuery, Search};
use littoral::synth::Distribution;
use std::sync::atomic::{AtomicBool, Ordering};

#[test]
fn tiny_budget_many_threads() {
    let dir = tempdir();
    let src = source(200_000, 32, 8, Distribution::Water);
    let (path, summary) = synth_map(dir.path(), "m.map", &src, Some(5_000), 2, 64 * MIB);
    assert!(summary.tiles >= 30);
    let reference = PhotonMap::new(MapFile::open(&path).unwrap(), 4096 * MIB).unwrap();
    let file = MapFile::open(&path).unwrap();
    let largest = file
        .tiles()
        .iter()
        .map(|t| tile_bytes(t.count))
        .max()
        .unwrap();
    // Room for three of the largest tiles while eight threads query.
    let budget = 3 * largest;
    let map = PhotonMap::new(file, budget).unwrap();

    let mut rng = littoral::rng::Pcg32::new(1, 1);
    let points: Vec<Vec3> = (0..4_000)
        .map(|_| {
            Vec3::new(
                100.0 * rng.uniform_f32(),
                100.0 * rng.uniform_f32(),
                -10.0 * rng.uniform_f32(),
            )
        })
        .collect();
    let searches = [
        Search::Nearest {
            k: 30,
            max_radius: None,
        },
        Search::Radius { radius: 0.7 },
    ];
    let over_budget = AtomicBool::new(false);
    std::thread::scope(|s| {
        for t in 0..8 {
            let (map, points, reference, over) = (&map, &points, &reference, &over_budget);
            s.spawn(move || {
                for (i, p) in points.iter().enumerate().skip(t).step_by(8) {
                    let search = searches[i % 2];
                    let got = map.query(*p, search).unwrap();
                    assert_eq!(got, reference.query(*p, search).unwrap(), "query {i}");
                    if map.cache_stats().resident_bytes > budget {
                        over.store(true, Ordering::Relaxed);
                    }
                }
            });
        }
    });
    let stats = map.cache_stats();
    assert!(!over_budget.load(Ordering::Relaxed));
    assert!(
        stats.peak_resident_bytes <= budget,
        "{stats:?} budget {budget}"
    );
    assert_eq!(
        stats.decodes, stats.misses,
        "one decode per residency: {stats:?}"
    );
    assert!(stats.evictions > 0 && stats.hits > 0, "{stats:?}");
    // Every miss beyond the first residency of each tile followed an eviction.
    assert!(stats.misses <= stats.evictions + map.file().tiles().len() as u64);
}

#[test]
fn budget_below_one_tile_is_refused() {
    let dir = tempdir();
    let src = source(50_000, 8, 2, Distribution::Uniform);
    let (path, _) = synth_map(dir.path(), "m.map", &src, None, 1, 64 * MIB);
    let e = PhotonMap::new(MapFile::open(&path).unwrap(), 1024)
        .err()
        .unwrap();
    assert!(e.to_string().contains("m.map"), "{e}");
}
