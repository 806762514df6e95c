//! Radiance estimates per second on the built-in coastal scene's photon map
//! (its 4 M photons, 128 bands; k 200 / 2000, clipped-sphere boundary,
//! compensated spectra),
//! with a tile cache of 100 %, 25 % and 5 % of the decoded map; sites along
//! nadir rays of a 64 x 64 image in render (tile) order, one thread.

mod common;

use common::*;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::Vec3;
use littoral::estimate::estimator::{Estimator, Scratch};
use littoral::scene::{Overrides, Scene};
use littoral::store::cache::tile_bytes;
use littoral::store::{BuildOptions, MapFile};
use littoral::store::{PhotonMap, PhotonQuery};

fn estimate(c: &mut Criterion) {
    let scene = Scene::coastal(&Overrides::default()).unwrap();
    let path = bench_dir().join(format!("coastal-{}.map", scene.photons));
    if !path.exists() {
        littoral::emit::emit(
            &scene,
            &littoral::emit::emission_provenance(&scene).unwrap(),
            &path,
            &BuildOptions::with_budget(512 * MIB),
            &littoral::progress::Silent,
        )
        .unwrap();
    }
    // Sites: 64 x 64 columns over the domain, every 0.75 m down to the floor,
    // column by column in 8 x 8 blocks (as image tiles are rendered).
    let mut sites = Vec::new();
    for by in 0..8 {
        for bx in 0..8 {
            for j in 0..8 {
                for i in 0..8 {
                    let x = (bx * 8 + i) as f32 * 200.0 / 64.0 + 1.5;
                    let y = (by * 8 + j) as f32 * 200.0 / 64.0 + 1.5;
                    let floor = scene.geometry.floor_depth_at(x, y).unwrap_or(10.0);
                    let mut d = 0.3;
                    while d < floor {
                        sites.push(Vec3::new(x, y, -d));
                        d += 0.75;
                    }
                }
            }
        }
    }
    let decoded: u64 = MapFile::open(&path)
        .unwrap()
        .tiles()
        .iter()
        .map(|t| tile_bytes(t.count))
        .sum();
    let mut g = c.benchmark_group("estimate_coastal");
    g.sample_size(10);
    g.throughput(Throughput::Elements(sites.len() as u64));
    for (name, share) in [
        ("cache_100pct", 1.0),
        ("cache_25pct", 0.25),
        ("cache_5pct", 0.05),
    ] {
        let largest = MapFile::open(&path)
            .unwrap()
            .tiles()
            .iter()
            .map(|t| tile_bytes(t.count))
            .max()
            .unwrap();
        let budget = ((decoded as f64 * share) as u64).max(largest);
        let map = PhotonMap::new(MapFile::open(&path).unwrap(), budget).unwrap();
        let est = Estimator::new(&scene, &map).unwrap();
        let mut scratch = Scratch::new(scene.bands.len());
        let mut out = vec![0.0; scene.bands.len()];
        g.bench_function(name, |b| {
            b.iter(|| {
                for &x in &sites {
                    est.volume(x, Vec3::Z, &mut scratch, &mut out).unwrap();
                }
            })
        });
        let s = map.cache_stats();
        eprintln!(
            "{name}: {} sites, budget {:.1} of {:.1} MiB decoded, hit rate {:.4} ({} hits, {} misses, {} evictions)",
            sites.len(),
            budget as f64 / MIB as f64,
            decoded as f64 / MIB as f64,
            s.hits as f64 / (s.hits + s.misses).max(1) as f64,
            s.hits,
            s.misses,
            s.evictions
        );
    }
    g.finish();
}

criterion_group!(benches, estimate);
criterion_main!(benches);
