//! Boundary-bias compensation per search site, on the built-in coastal scene
//! (200 m x 200 m, floor sloping from 0.5 m to 15 m, two targets): the six
//! axial distances by tracing and from grids of 1 m and 0.5 m spacing, and
//! the search volume of each mode for a site with six active planes (the
//! clipped sphere's worst case) and with one (a site near the floor).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::Vec3;
use littoral::estimate::boundary::{
    axial_distances_traced, clipped_sphere_volume, ellipsoid_volume, BoundaryGrid,
};
use littoral::rng::Pcg32;
use littoral::scene::{Overrides, Scene};
use std::hint::black_box;
use std::time::Instant;

const SITES: usize = 10_000;
const RADIUS_M: f32 = 2.0;

/// Uniform sites in the water column: random x, y and a depth between the
/// surface and the floor.
fn sites(scene: &Scene) -> Vec<Vec3> {
    let mut rng = Pcg32::new(5, 0);
    let [sx, sy] = scene.geometry.domain_size_m();
    (0..SITES)
        .map(|_| {
            let (x, y) = (sx * rng.uniform_f32(), sy * rng.uniform_f32());
            let depth = scene.geometry.floor_depth_at(x, y).unwrap_or(10.0);
            Vec3::new(x, y, -depth * rng.uniform_f32())
        })
        .collect()
}

fn distances(c: &mut Criterion) {
    let scene = Scene::coastal(&Overrides::default()).unwrap();
    let points = sites(&scene);
    let mut g = c.benchmark_group("axial_distances");
    g.throughput(Throughput::Elements(SITES as u64));
    g.bench_function("traced", |b| {
        b.iter(|| {
            for &o in &points {
                black_box(axial_distances_traced(&scene, o, RADIUS_M));
            }
        })
    });
    for spacing in [1.0f32, 0.5] {
        let start = Instant::now();
        let grid = BoundaryGrid::build(&scene, spacing, 2.0 * RADIUS_M).unwrap();
        eprintln!(
            "grid {spacing} m: {:?} nodes, {} bytes, built in {:.2?}",
            grid.dims(),
            grid.bytes(),
            start.elapsed()
        );
        g.bench_function(format!("grid_{spacing}m"), |b| {
            b.iter(|| {
                for &o in &points {
                    black_box(grid.distances(o, RADIUS_M));
                }
            })
        });
    }
    g.finish();
}

fn volumes(c: &mut Criterion) {
    let r = 1.0f64;
    let mut rng = Pcg32::new(6, 0);
    let six: Vec<[f64; 6]> = (0..1000)
        .map(|_| std::array::from_fn(|_| r * rng.uniform_f64()))
        .collect();
    let one: Vec<[f64; 6]> = (0..1000)
        .map(|_| [r, r, r, r, r, r * rng.uniform_f64()])
        .collect();
    let mut g = c.benchmark_group("search_volume");
    g.throughput(Throughput::Elements(1000));
    g.bench_function("clipped_sphere_six_planes", |b| {
        b.iter(|| six.iter().map(|b| clipped_sphere_volume(r, b)).sum::<f64>())
    });
    g.bench_function("clipped_sphere_one_plane", |b| {
        b.iter(|| one.iter().map(|b| clipped_sphere_volume(r, b)).sum::<f64>())
    });
    g.bench_function("ellipsoid", |b| {
        b.iter(|| six.iter().map(ellipsoid_volume).sum::<f64>())
    });
    g.finish();
}

criterion_group!(benches, distances, volumes);
criterion_main!(benches);
