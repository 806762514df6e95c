//! `cache::tile_bytes` must bound what a decoded tile really holds: the
//! photons plus its search tree, measured here with a counting allocator
//! (this test binary holds one test so nothing else allocates meanwhile),
//! and `DecodedTile::bytes` must be what it holds.

use glam::Vec3;
use littoral::photon::Photon;
use littoral::store::cache::{tile_bytes, DecodedTile};
use littoral::store::codec::{StagedPhoton, TileDecoder, TileEncoder};
use littoral::store::tiletree::TileTree;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicIsize, Ordering};

struct Counting;
static LIVE: AtomicIsize = AtomicIsize::new(0);

// SAFETY: forwards to the system allocator and only counts sizes.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        LIVE.fetch_add(l.size() as isize, Ordering::SeqCst);
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        LIVE.fetch_sub(l.size() as isize, Ordering::SeqCst);
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, new: usize) -> *mut u8 {
        LIVE.fetch_add(new as isize - l.size() as isize, Ordering::SeqCst);
        unsafe { System.realloc(p, l, new) }
    }
}

#[global_allocator]
static A: Counting = Counting;

#[test]
fn tile_bytes_bounds_photons_and_tree() {
    let mut rng = littoral::rng::Pcg32::new(4, 4);
    let mut encoder = TileEncoder::default();
    let mut decoder = TileDecoder::default();
    for n in [1usize, 17, 33, 1000, 4097, 65_536, 131_000] {
        let staged: Vec<StagedPhoton> = (0..n)
            .map(|_| {
                // Many share one z, as on a flat floor.
                let z = if rng.uniform_f32() < 0.3 {
                    -10.0
                } else {
                    rng.uniform_f32()
                };
                let p = Photon {
                    position: Vec3::new(rng.uniform_f32(), rng.uniform_f32(), z),
                    direction: Vec3::Z,
                    band: 0,
                    power: 1.0,
                    group: 0,
                };
                StagedPhoton::new(&p, 0)
            })
            .collect();
        let tile = encoder.encode(&staged).unwrap();
        let entry = tile.entry(0);
        drop(staged);
        // Grow the decoder's scratch first: it is the thread's, not the tile's.
        let mut photons = Vec::new();
        decoder.decode(&tile.blob, &entry, &mut photons).unwrap();
        photons = Vec::new();
        let before = LIVE.load(Ordering::SeqCst);
        decoder.decode(&tile.blob, &entry, &mut photons).unwrap();
        photons.shrink_to_fit();
        let tree = TileTree::from_morton(decoder.codes(), decoder.cells(), &entry.quant);
        let decoded = DecodedTile { photons, tree };
        let held = (LIVE.load(Ordering::SeqCst) - before) as u64;
        assert_eq!(
            held,
            decoded.bytes(),
            "n {n}: bytes() is what the tile holds"
        );
        assert!(
            held <= tile_bytes(n as u32),
            "n {n}: tile holds {held} B, bound {}",
            tile_bytes(n as u32)
        );
        drop(decoded);
    }
}
