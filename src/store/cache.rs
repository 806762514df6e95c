//! The tile cache: decoded tiles with their k-d trees, shared across
//! threads under a byte budget.
//!
//! A tile's resident size (decoded photons plus an upper bound of its kiddo
//! tree) is known from its index entry before it is decoded, so the cache
//! reserves the bytes first and decodes outside the lock. A tile requested
//! by several threads at once is decoded once: the others wait for it.
//! Eviction is least-recently-used among tiles no reader holds; a reader's
//! [`TileRef`] pins its tile, and a thread needing room waits until a pin is
//! released. Resident bytes therefore never exceed the budget. Each thread
//! should pin one tile at a time (as the query code does); a budget smaller
//! than the largest tile is refused when the cache is made.
//!
//! Not for: deciding which tiles a query needs (see `store::query`).

use crate::error::{Error, Result};
use crate::photon::PackedPhoton;
use crate::store::codec::TileDecoder;
use crate::store::MapFile;
use kiddo::ImmutableKdTree;
use std::collections::HashMap;
use std::ops::Deref;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex};

/// A decoded tile: photons in stored (Morton) order and a k-d tree whose
/// items index them.
pub struct DecodedTile {
    pub photons: Vec<PackedPhoton>,
    pub tree: ImmutableKdTree<f32, 3>,
}

/// Upper bound of the bytes a tile of `count` photons occupies in the cache:
/// 24 B per decoded photon, and for the kiddo tree 16 B per point (12 B of
/// coordinates, 4 B item) plus leaf and stem tables and per-leaf padding.
/// Checked against a counting allocator in the tests.
pub fn tile_bytes(count: u32) -> u64 {
    let n = count as u64;
    let photons = n * std::mem::size_of::<PackedPhoton>() as u64;
    let tree = 16 * n + 8 * n / 2 + 16 * 1024;
    photons + tree
}

/// Cache counters, summed over all threads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct CacheStats {
    pub hits: u64,
    pub misses: u64,
    pub evictions: u64,
    /// Tiles decoded (one per miss that succeeded).
    pub decodes: u64,
    /// Decoded photon bytes produced.
    pub decoded_bytes: u64,
    /// Resident bytes now.
    pub resident_bytes: u64,
    /// Most resident bytes at any time.
    pub peak_resident_bytes: u64,
}

enum Slot {
    Loading,
    Ready {
        tile: Arc<DecodedTile>,
        last_used: u64,
    },
}

struct Inner {
    slots: HashMap<u32, Slot>,
    resident: u64,
    peak: u64,
    clock: u64,
}

/// A shared, budgeted cache of decoded tiles of one map.
pub struct TileCache {
    budget: u64,
    inner: Mutex<Inner>,
    changed: Condvar,
    hits: AtomicU64,
    misses: AtomicU64,
    evictions: AtomicU64,
    decodes: AtomicU64,
    decoded_bytes: AtomicU64,
}

/// A pinned tile; it cannot be evicted while this lives.
pub struct TileRef<'a> {
    tile: Option<Arc<DecodedTile>>,
    cache: &'a TileCache,
}

impl Deref for TileRef<'_> {
    type Target = DecodedTile;
    fn deref(&self) -> &DecodedTile {
        self.tile.as_ref().expect("pinned tile")
    }
}

impl Drop for TileRef<'_> {
    fn drop(&mut self) {
        // Unpin under the lock so a waiter cannot miss the wake-up.
        let _guard = self.cache.inner.lock().unwrap_or_else(|e| e.into_inner());
        self.tile = None;
        self.cache.changed.notify_all();
    }
}

thread_local! {
    static DECODER: std::cell::RefCell<TileDecoder> = std::cell::RefCell::new(TileDecoder::default());
}

impl TileCache {
    /// A cache of at most `budget` bytes for tiles of `map`.
    pub fn new(map: &MapFile, budget: u64) -> Result<TileCache> {
        let largest = map
            .tiles()
            .iter()
            .map(|t| tile_bytes(t.count))
            .max()
            .unwrap_or(0);
        if largest > budget {
            return Err(Error::Budget {
                budget,
                what: format!(
                    "{}: the largest tile needs {largest} bytes decoded; raise --mem-budget",
                    map.path().display()
                ),
            });
        }
        Ok(TileCache {
            budget,
            inner: Mutex::new(Inner {
                slots: HashMap::new(),
                resident: 0,
                peak: 0,
                clock: 0,
            }),
            changed: Condvar::new(),
            hits: AtomicU64::new(0),
            misses: AtomicU64::new(0),
            evictions: AtomicU64::new(0),
            decodes: AtomicU64::new(0),
            decoded_bytes: AtomicU64::new(0),
        })
    }

    /// The byte budget.
    pub fn budget(&self) -> u64 {
        self.budget
    }

    /// Counters so far.
    pub fn stats(&self) -> CacheStats {
        let inner = self.inner.lock().unwrap_or_else(|e| e.into_inner());
        CacheStats {
            hits: self.hits.load(Ordering::Relaxed),
            misses: self.misses.load(Ordering::Relaxed),
            evictions: self.evictions.load(Ordering::Relaxed),
            decodes: self.decodes.load(Ordering::Relaxed),
            decoded_bytes: self.decoded_bytes.load(Ordering::Relaxed),
            resident_bytes: inner.resident,
            peak_resident_bytes: inner.peak,
        }
    }

    /// Pin tile `t` of `map`, decoding it if it is not resident.
    pub fn get<'a>(&'a self, map: &MapFile, t: u32) -> Result<TileRef<'a>> {
        let need = tile_bytes(map.tiles()[t as usize].count);
        let mut inner = self.inner.lock().unwrap_or_else(|e| e.into_inner());
        loop {
            inner.clock += 1;
            let now = inner.clock;
            match inner.slots.get_mut(&t) {
                Some(Slot::Ready { tile, last_used }) => {
                    *last_used = now;
                    let tile = Arc::clone(tile);
                    self.hits.fetch_add(1, Ordering::Relaxed);
                    return Ok(TileRef {
                        tile: Some(tile),
                        cache: self,
                    });
                }
                Some(Slot::Loading) => {
                    inner = self.changed.wait(inner).unwrap_or_else(|e| e.into_inner());
                    continue;
                }
                None => {}
            }
            if inner.resident + need <= self.budget {
                break;
            }
            if !Self::evict_one(&mut inner, &self.evictions) {
                // Everything resident is pinned or loading: wait for a release.
                inner = self.changed.wait(inner).unwrap_or_else(|e| e.into_inner());
            }
        }
        inner.resident += need;
        inner.peak = inner.peak.max(inner.resident);
        inner.slots.insert(t, Slot::Loading);
        self.misses.fetch_add(1, Ordering::Relaxed);
        drop(inner);

        let decoded = Self::decode(map, t);

        let mut inner = self.inner.lock().unwrap_or_else(|e| e.into_inner());
        self.changed.notify_all();
        match decoded {
            Ok(tile) => {
                self.decodes.fetch_add(1, Ordering::Relaxed);
                self.decoded_bytes.fetch_add(
                    (tile.photons.len() * std::mem::size_of::<PackedPhoton>()) as u64,
                    Ordering::Relaxed,
                );
                let tile = Arc::new(tile);
                inner.clock += 1;
                let last_used = inner.clock;
                inner.slots.insert(
                    t,
                    Slot::Ready {
                        tile: Arc::clone(&tile),
                        last_used,
                    },
                );
                Ok(TileRef {
                    tile: Some(tile),
                    cache: self,
                })
            }
            Err(e) => {
                inner.slots.remove(&t);
                inner.resident -= need;
                Err(e)
            }
        }
    }

    fn decode(map: &MapFile, t: u32) -> Result<DecodedTile> {
        let mut photons = Vec::new();
        DECODER.with(|d| map.decode_tile(t, &mut d.borrow_mut(), &mut photons))?;
        photons.shrink_to_fit();
        let points: Vec<[f32; 3]> = photons.iter().map(|p| p.position).collect();
        let tree = ImmutableKdTree::new_from_slice(&points)
            .map_err(|e| Error::tile(map.path(), t, format!("k-d tree: {e:?}")))?;
        Ok(DecodedTile { photons, tree })
    }

    /// Evict the least recently used unpinned tile; false if none.
    fn evict_one(inner: &mut Inner, evictions: &AtomicU64) -> bool {
        let victim = inner
            .slots
            .iter()
            .filter_map(|(&t, s)| match s {
                Slot::Ready { tile, last_used } if Arc::strong_count(tile) == 1 => {
                    Some((*last_used, t))
                }
                _ => None,
            })
            .min();
        let Some((_, t)) = victim else {
            return false;
        };
        if let Some(Slot::Ready { tile, .. }) = inner.slots.remove(&t) {
            inner.resident -= tile_bytes(tile.photons.len() as u32);
            evictions.fetch_add(1, Ordering::Relaxed);
        }
        true
    }
}
