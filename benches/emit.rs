//! Emission throughput end to end (trace, route, spill if need be, sort,
//! encode, write): the built-in coastal scene (128 bands) at 1 M traced
//! photons under a 256 MiB budget, on one and on two tracer threads.
//! Throughput is counted in stored photons (about 1.76 per traced one),
//! the unit of the 3 M stored photons/s per core target; with one tracer
//! thread the writer's threads still use the second core.

mod common;

use common::*;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use littoral::job::{EmitJob, MemoryBudget};
use littoral::progress::Silent;
use littoral::scene::{Overrides, Scene, COASTAL_TOML};
use std::path::Path;

fn emit(c: &mut Criterion) {
    let traced = 1_000_000;
    let overrides = Overrides {
        photons: Some(traced),
        ..Overrides::default()
    };
    let scene = Scene::parse(COASTAL_TOML, Path::new("coastal.toml"), &overrides).unwrap();
    let job = |threads| EmitJob {
        scene: &scene,
        map: bench_dir().join("emit-coastal.map"),
        report: None,
        threads,
        budget: MemoryBudget::new(256 * MIB),
        scene_seconds: 0.0,
    };
    let stored = job(2).run(&Silent).unwrap().map.photons;
    eprintln!("coastal: {traced} traced -> {stored} stored photons");
    let mut g = c.benchmark_group("emit");
    g.sample_size(10);
    g.throughput(Throughput::Elements(stored));
    for threads in [1, 2] {
        g.bench_function(format!("coastal_1M_traced_{threads}_threads"), |b| {
            b.iter(|| job(threads).run(&Silent).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, emit);
criterion_main!(benches);
