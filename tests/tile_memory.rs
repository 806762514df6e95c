//! `cache::tile_bytes` must bound what a decoded tile really holds: the
//! photons plus the kiddo tree, measured here with a counting allocator
//! (this test binary holds one test so nothing else allocates meanwhile).

use glam::Vec3;
use littoral::photon::PackedPhoton;
use littoral::store::cache::tile_bytes;
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
    for n in [1usize, 17, 33, 1000, 4097, 65_536, 131_000] {
        let before = LIVE.load(Ordering::SeqCst);
        let photons: Vec<PackedPhoton> = (0..n)
            .map(|_| {
                // Many share one z, as on a flat floor.
                let z = if rng.uniform_f32() < 0.3 {
                    -10.0
                } else {
                    rng.uniform_f32()
                };
                PackedPhoton {
                    position: Vec3::new(rng.uniform_f32(), rng.uniform_f32(), z).to_array(),
                    ..Default::default()
                }
            })
            .collect();
        let points: Vec<[f32; 3]> = photons.iter().map(|p| p.position).collect();
        let tree: kiddo::ImmutableKdTree<f32, 3> =
            kiddo::ImmutableKdTree::new_from_slice(&points).unwrap();
        drop(points);
        let held = (LIVE.load(Ordering::SeqCst) - before) as u64;
        assert!(
            held <= tile_bytes(n as u32),
            "n {n}: tile holds {held} B, bound {}",
            tile_bytes(n as u32)
        );
        drop(tree);
        drop(photons);
    }
}
