//! Shared setup for the benchmarks: synthetic maps cached under
//! `target/bench-maps/v<format>` so repeated runs skip the build.

#![allow(dead_code)]

use glam::Vec3;
use littoral::progress::Silent;
use littoral::store::{build_map, BuildOptions};
use littoral::synth::{Distribution, SynthSource};
use std::path::PathBuf;

pub const MIB: u64 = 1 << 20;

/// `target/bench-maps/vN` for map format N: a format change rebuilds them.
pub fn bench_dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("target/bench-maps")
        .join(format!("v{}", littoral::store::format::FORMAT_VERSION));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A water map of `photons` photons and `bands` bands (built once).
pub fn water_map(photons: u64, bands: usize) -> PathBuf {
    let path = bench_dir().join(format!("water-{photons}-{bands}.map"));
    if !path.exists() {
        let src = SynthSource::new(photons, bands, 1, Distribution::Water).unwrap();
        build_map(&path, &src, &BuildOptions::with_budget(256 * MIB), &Silent).unwrap();
    }
    path
}

/// Query points drawn from the same distribution as the photons (queries
/// happen where light is), from indices no photon of the map uses.
pub fn query_points(n: usize, bands: usize) -> Vec<Vec3> {
    let src = SynthSource::new(1 << 40, bands, 1, Distribution::Water).unwrap();
    (0..n as u64)
        .map(|i| src.photon((1 << 39) + i).position)
        .collect()
}

/// Sort points along a Morton curve over the synthetic domain.
pub fn coherent(points: &[Vec3]) -> Vec<Vec3> {
    let b = littoral::bounds::Aabb {
        min: Vec3::new(0.0, 0.0, -10.0),
        max: Vec3::new(100.0, 100.0, 0.0),
    };
    let q = littoral::store::codec::BoxQuantizer::new(&b);
    let mut keyed: Vec<(u64, Vec3)> = points
        .iter()
        .map(|p| (littoral::morton::morton3(q.encode(p.to_array())), *p))
        .collect();
    keyed.sort_by_key(|k| k.0);
    keyed.into_iter().map(|k| k.1).collect()
}

/// Order points as the renderer asks for them: image tiles of `side` m
/// (16 x 16 pixels) in Morton order over the synthetic domain, within a
/// tile pixel by pixel in rows, and within a pixel down the water column.
pub fn image_tile_order(points: &[Vec3], side: f32) -> Vec<Vec3> {
    let pixel = side / 16.0;
    let mut keyed: Vec<(u64, u32, i64, Vec3)> = points
        .iter()
        .map(|p| {
            let (tx, ty) = ((p.x / side).floor() as u16, (p.y / side).floor() as u16);
            let (px, py) = (
                ((p.x - tx as f32 * side) / pixel).floor() as u32,
                ((p.y - ty as f32 * side) / pixel).floor() as u32,
            );
            (
                littoral::morton::morton3([tx, ty, 0]),
                py * 16 + px,
                -(p.z * 1e3) as i64,
                *p,
            )
        })
        .collect();
    keyed.sort_by_key(|k| (k.0, k.1, k.2));
    keyed.into_iter().map(|k| k.3).collect()
}
