//! kNN (k = 50) on a 10 M photon water map: one in-memory kiddo tree over
//! every photon (item numbers only, and as the in-memory photon map that
//! returns the photons), the store with the whole map cached, and the store with a
//! cache of 5 % of the decoded map in the renderer's image-tile order, in
//! a global Morton order and in random order.

mod common;

use common::*;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use littoral::store::cache::DecodedTile;
use littoral::store::codec::TileDecoder;
use littoral::store::in_memory::InMemoryMap;
use littoral::store::tiletree::TileTree;
use littoral::store::MapFile;
use littoral::store::{Neighbour, PhotonMap, PhotonQuery, Search};
use std::num::NonZeroUsize;

const PHOTONS: u64 = 10_000_000;
const BANDS: usize = 64;
/// Queries per iteration in coherent order: a renderer asks for millions,
/// so each tile serves many queries while it is resident.
const QUERIES: usize = 200_000;
/// In random order a 5 % cache misses on almost every query; fewer
/// queries keep the run short (throughput is per query either way).
const RANDOM_SMALL_CACHE_QUERIES: usize = 2_000;

fn knn(c: &mut Criterion) {
    let path = water_map(PHOTONS, BANDS);
    let random = query_points(QUERIES, BANDS);
    let ordered = coherent(&random);
    let image_tiles = image_tile_order(&random, 6.25);
    let search = Search::Nearest {
        k: 50,
        max_radius: None,
    };
    let mut g = c.benchmark_group("knn50_10M");
    g.sample_size(10);
    g.throughput(Throughput::Elements(QUERIES as u64));

    {
        // (a0) one kiddo ImmutableKdTree over all photons, in memory,
        // returning item numbers only (no photon is read).
        let file = MapFile::open(&path).unwrap();
        let mut dec = TileDecoder::default();
        let mut tile = Vec::new();
        let mut points: Vec<[f32; 3]> = Vec::with_capacity(PHOTONS as usize);
        let mut photons = Vec::with_capacity(PHOTONS as usize);
        for t in 0..file.tiles().len() as u32 {
            file.decode_tile(t, &mut dec, &mut tile).unwrap();
            points.extend(tile.iter().map(|p| p.position));
            photons.extend_from_slice(&tile);
        }
        let tree: kiddo::ImmutableKdTree<f32, 3> =
            kiddo::ImmutableKdTree::new_from_slice(&points).unwrap();
        let k = NonZeroUsize::new(50).unwrap();
        for (name, pts) in [
            ("a0_kiddo_items_only_random", &random),
            ("a0_kiddo_items_only_coherent", &ordered),
        ] {
            g.bench_function(name, |b| {
                b.iter(|| {
                    pts.iter()
                        .map(|p| {
                            tree.query(&p.to_array())
                                .nearest_n::<kiddo::SquaredEuclidean<f32>>(k)
                                .execute()
                                .len()
                        })
                        .sum::<usize>()
                })
            });
        }
        // (a1) the same tree returning the photons, as the store does:
        // records gathered and unpacked, nearest first.
        for (name, pts) in [
            ("a1_kiddo_photons_random", &random),
            ("a1_kiddo_photons_coherent", &ordered),
            ("a1_kiddo_photons_image_tiles", &image_tiles),
        ] {
            g.bench_function(name, |b| {
                b.iter(|| {
                    pts.iter()
                        .map(|p| {
                            let found: Vec<Neighbour> = tree
                                .query(&p.to_array())
                                .nearest_n::<kiddo::SquaredEuclidean<f32>>(k)
                                .execute()
                                .into_iter()
                                .map(|r| Neighbour {
                                    photon: photons[r.item as usize].unpack(),
                                    distance_sq: r.distance,
                                })
                                .collect();
                            found.len()
                        })
                        .sum::<usize>()
                })
            });
        }
    }

    {
        // (a) the in-memory photon map: one kiddo tree per layer over every
        // photon, answering the same queries with the same photons.
        let memory = InMemoryMap::from_file(&MapFile::open(&path).unwrap()).unwrap();
        for (name, pts) in [
            ("a_in_memory_random", &random),
            ("a_in_memory_coherent", &ordered),
            ("a_in_memory_image_tiles", &image_tiles),
        ] {
            g.bench_function(name, |b| {
                b.iter(|| {
                    pts.iter()
                        .map(|p| memory.query(*p, search).unwrap().len())
                        .sum::<usize>()
                })
            });
        }
    }

    let full = PhotonMap::new(MapFile::open(&path).unwrap(), 64 << 30).unwrap();
    for p in &random {
        full.query(*p, search).unwrap();
    }
    for (name, pts) in [
        ("b_store_all_cached_random", &random),
        ("b_store_all_cached_coherent", &ordered),
        ("b_store_all_cached_image_tiles", &image_tiles),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| {
                pts.iter()
                    .map(|p| full.query(*p, search).unwrap().len())
                    .sum::<usize>()
            })
        });
    }
    drop(full);

    let file = MapFile::open(&path).unwrap();
    // What the tiles hold decoded, with their trees (not the bound the
    // cache reserves while one decodes).
    let mut dec = TileDecoder::default();
    let mut decoded = 0u64;
    for t in 0..file.tiles().len() as u32 {
        let mut photons = Vec::new();
        file.decode_tile(t, &mut dec, &mut photons).unwrap();
        photons.shrink_to_fit();
        let tree = TileTree::from_morton(dec.codes(), dec.cells(), &file.tiles()[t as usize].quant);
        decoded += DecodedTile { photons, tree }.bytes();
    }
    let budget = decoded / 20;
    eprintln!(
        "decoded map {:.1} MiB; 5 % budget {:.1} MiB",
        decoded as f64 / MIB as f64,
        budget as f64 / MIB as f64
    );
    let small = PhotonMap::new(file, budget).unwrap();
    let few = &random[..RANDOM_SMALL_CACHE_QUERIES];
    for (name, pts) in [
        ("c_store_5pct_image_tiles", &image_tiles[..]),
        ("c_store_5pct_coherent", &ordered[..]),
        ("d_store_5pct_random", few),
    ] {
        g.throughput(Throughput::Elements(pts.len() as u64));
        let before = small.cache_stats();
        g.bench_function(name, |b| {
            b.iter(|| {
                pts.iter()
                    .map(|p| small.query(*p, search).unwrap().len())
                    .sum::<usize>()
            })
        });
        let after = small.cache_stats();
        let (h, m) = (after.hits - before.hits, after.misses - before.misses);
        eprintln!(
            "{name}: hit rate {:.3} ({h} hits, {m} misses)",
            h as f64 / (h + m).max(1) as f64
        );
    }
    g.finish();
}

criterion_group!(benches, knn);
criterion_main!(benches);
