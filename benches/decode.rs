//! Tile decode speed (one core): zstd + unshuffle + dequantise, then the
//! full tile load (decode and the tile's search tree; and, for comparison,
//! decode and a kiddo tree), on a 64-band water map.

mod common;

use common::*;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use littoral::store::codec::{TileDecoder, RECORD_BYTES};
use littoral::store::tiletree::TileTree;
use littoral::store::MapFile;

fn decode(c: &mut Criterion) {
    let path = water_map(2_000_000, 64);
    let file = MapFile::open(&path).unwrap();
    // The largest tile: per-tile overheads aside, the codec's own speed.
    let t = (0..file.tiles().len())
        .max_by_key(|&i| file.tiles()[i].count)
        .unwrap() as u32;
    let e = file.tiles()[t as usize];
    let mut g = c.benchmark_group("tile_decode");
    let mut dec = TileDecoder::default();
    let mut out = Vec::new();
    // Throughput in bytes of 16-byte records produced (as stored before compression).
    g.throughput(Throughput::Bytes(e.count as u64 * RECORD_BYTES as u64));
    g.bench_function("decode_with_checksum", |b| {
        b.iter(|| file.decode_tile(t, &mut dec, &mut out).unwrap())
    });
    g.bench_function("decode_no_checksum", |b| {
        b.iter(|| dec.decode_unchecked(file.blob(t), &e, &mut out).unwrap())
    });
    // A cache miss: the decode and the tile's tree, cut from its codes.
    g.bench_function("decode_and_build_tree", |b| {
        b.iter(|| {
            file.decode_tile(t, &mut dec, &mut out).unwrap();
            TileTree::from_morton(dec.codes(), dec.cells(), &e.quant)
        })
    });
    // What a miss cost before: a kiddo tree built over the decoded positions.
    g.bench_function("decode_and_build_kiddo_tree", |b| {
        b.iter(|| {
            file.decode_tile(t, &mut dec, &mut out).unwrap();
            let pts: Vec<[f32; 3]> = out.iter().map(|p| p.position).collect();
            kiddo::ImmutableKdTree::<f32, 3>::new_from_slice(&pts).unwrap()
        })
    });
    eprintln!(
        "tile {t}: {} photons, {} compressed bytes",
        e.count, e.length
    );
    g.finish();
}

criterion_group!(benches, decode);
criterion_main!(benches);
