//! Map build throughput: `map synth` of water photons under a 64 MiB budget,
//! and the bytes per photon on disk at 16 and 256 bands.

mod common;

use common::*;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use littoral::progress::Silent;
use littoral::store::{build_map, BuildOptions};
use littoral::synth::{Distribution, SynthSource};

fn build(c: &mut Criterion) {
    let n = 2_000_000u64;
    let dir = bench_dir();
    let mut g = c.benchmark_group("build");
    g.sample_size(10);
    g.throughput(Throughput::Elements(n));
    for bands in [16usize, 256] {
        let src = SynthSource::new(n, bands, 1, Distribution::Water).unwrap();
        let path = dir.join(format!("build-{bands}.map"));
        g.bench_function(format!("water_{bands}_bands_64MiB"), |b| {
            b.iter(|| {
                build_map(&path, &src, &BuildOptions::with_budget(64 * MIB), &Silent).unwrap()
            })
        });
        let bytes = std::fs::metadata(&path).unwrap().len();
        eprintln!(
            "water, {bands} bands: {:.3} bytes/photon on disk ({bytes} bytes for {n} photons)",
            bytes as f64 / n as f64
        );
    }
    g.finish();
}

criterion_group!(benches, build);
criterion_main!(benches);
