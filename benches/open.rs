//! Time from opening a 10 M photon map to the answer of its first kNN query
//! (cold tile cache; the file itself in the OS page cache).

mod common;

use common::*;
use criterion::{criterion_group, criterion_main, Criterion};
use littoral::store::MapFile;
use littoral::store::{PhotonMap, PhotonQuery, Search};

fn open(c: &mut Criterion) {
    let path = water_map(10_000_000, 64);
    let at = query_points(1, 64)[0];
    let mut g = c.benchmark_group("open");
    g.sample_size(20);
    g.bench_function("open_to_first_knn50_10M", |b| {
        b.iter(|| {
            let map = PhotonMap::new(MapFile::open(&path).unwrap(), 256 * MIB).unwrap();
            map.query(
                at,
                Search::Nearest {
                    k: 50,
                    max_radius: None,
                },
            )
            .unwrap()
            .len()
        })
    });
    g.finish();
}

criterion_group!(benches, open);
criterion_main!(benches);
