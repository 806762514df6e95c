//! The tile cache: decoded tiles with their search trees, shared across
//! threads under a byte budget.
//!
//! An upper bound of a tile's resident size (decoded photons and tree) is
//! known from its index entry before it is decoded, so the cache reserves
//! that first, decodes outside the lock, and keeps what the tile really
//! holds once it is built. A hit takes only the tile's own lock. A tile requested
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
use crate::store::tiletree::TileTree;
use crate::store::MapFile;
use std::ops::Deref;
use std::sync::atomic::{fence, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex};

/// A decoded tile: photons in stored (Morton) order and the tree whose
/// leaves index them.
pub struct DecodedTile {
    pub photons: Vec<PackedPhoton>,
    pub tree: TileTree,
}

impl DecodedTile {
    /// Bytes this tile holds.
    pub fn bytes(&self) -> u64 {
        (self.photons.capacity() * std::mem::size_of::<PackedPhoton>() + self.tree.heap_bytes())
            as u64
    }
}

/// Upper bound of the bytes a tile of `count` photons occupies in the cache:
/// 24 B per decoded photon, 6 B of cell coordinates (and the tree's padding
/// after them) and at most two tree nodes per photon (every leaf holds one
/// photon or more). The cache reserves this while a tile decodes and keeps
/// [`DecodedTile::bytes`] once it is built (about 32 B per photon: a node
/// per five photons or so).
pub fn tile_bytes(count: u32) -> u64 {
    let n = count as u64;
    n * (std::mem::size_of::<PackedPhoton>() as u64 + 6)
        + TileTree::PAD_BYTES
        + 2 * TileTree::NODE_BYTES * n.max(1)
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

/// Two caches' statistics together (parts of one render, each with its own
/// cache): counts add, resident bytes take the larger of the two.
impl std::ops::AddAssign<&CacheStats> for CacheStats {
    fn add_assign(&mut self, c: &CacheStats) {
        self.hits += c.hits;
        self.misses += c.misses;
        self.evictions += c.evictions;
        self.decodes += c.decodes;
        self.decoded_bytes += c.decoded_bytes;
        self.resident_bytes = self.resident_bytes.max(c.resident_bytes);
        self.peak_resident_bytes = self.peak_resident_bytes.max(c.peak_resident_bytes);
    }
}

/// One tile's place in the cache. Its own lock guards its state, so a hit
/// touches no lock but this one.
struct Slot {
    state: Mutex<State>,
    last_used: AtomicU64,
}

enum State {
    Absent,
    Loading,
    Ready(Arc<DecodedTile>),
}

/// What the global lock guards: the byte account and the resident tiles.
struct Inner {
    resident_tiles: Vec<u32>,
    resident: u64,
    peak: u64,
}

/// A shared, budgeted cache of decoded tiles of one map.
pub struct TileCache {
    budget: u64,
    slots: Vec<Slot>,
    inner: Mutex<Inner>,
    changed: Condvar,
    /// Threads waiting on `changed` for a pin to be released.
    waiters: AtomicUsize,
    clock: AtomicU64,
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
        self.tile = None;
        // Pairs with the fence in `make_room`: either a waiter sees this
        // release when it looks for a tile to evict, or this sees the waiter
        // and wakes it (under the lock, so the wake-up cannot fall between
        // its look and its wait).
        fence(Ordering::SeqCst);
        if self.cache.waiters.load(Ordering::SeqCst) > 0 {
            let _guard = self.cache.inner.lock().unwrap_or_else(|e| e.into_inner());
            self.cache.changed.notify_all();
        }
    }
}

thread_local! {
    static DECODER: std::cell::RefCell<TileDecoder> = std::cell::RefCell::new(TileDecoder::default());
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
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
            slots: (0..map.tiles().len())
                .map(|_| Slot {
                    state: Mutex::new(State::Absent),
                    last_used: AtomicU64::new(0),
                })
                .collect(),
            inner: Mutex::new(Inner {
                resident_tiles: Vec::new(),
                resident: 0,
                peak: 0,
            }),
            changed: Condvar::new(),
            waiters: AtomicUsize::new(0),
            clock: AtomicU64::new(0),
            hits: AtomicU64::new(0),
            misses: AtomicU64::new(0),
            evictions: AtomicU64::new(0),
            decodes: AtomicU64::new(0),
            decoded_bytes: AtomicU64::new(0),
        })
    }

    /// Bytes of the cache's own bookkeeping (one slot per tile of the map).
    pub fn overhead_bytes(tiles: usize) -> u64 {
        (tiles * std::mem::size_of::<Slot>()) as u64
    }

    /// The byte budget.
    pub fn budget(&self) -> u64 {
        self.budget
    }

    /// Counters so far.
    pub fn stats(&self) -> CacheStats {
        let inner = lock(&self.inner);
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

    /// The tile of slot `t` if it is resident, pinned.
    fn hit(&self, t: u32) -> Option<TileRef<'_>> {
        let slot = &self.slots[t as usize];
        let state = lock(&slot.state);
        let State::Ready(tile) = &*state else {
            return None;
        };
        let tile = Arc::clone(tile);
        drop(state);
        slot.last_used.store(
            self.clock.fetch_add(1, Ordering::Relaxed),
            Ordering::Relaxed,
        );
        self.hits.fetch_add(1, Ordering::Relaxed);
        Some(TileRef {
            tile: Some(tile),
            cache: self,
        })
    }

    /// Pin tile `t` of `map`, decoding it if it is not resident.
    ///
    /// A hit takes only the tile's own lock. A miss takes the global lock to
    /// reserve the tile's bytes (evicting the least recently used unpinned
    /// tiles), decodes outside it, and takes it again to publish the tile.
    /// Locks are always taken global first, then a slot.
    pub fn get<'a>(&'a self, map: &MapFile, t: u32) -> Result<TileRef<'a>> {
        if let Some(r) = self.hit(t) {
            return Ok(r);
        }
        let need = tile_bytes(map.tiles()[t as usize].count);
        let mut inner = lock(&self.inner);
        loop {
            {
                let mut state = lock(&self.slots[t as usize].state);
                match &*state {
                    State::Ready(_) => {
                        drop(state);
                        drop(inner);
                        if let Some(r) = self.hit(t) {
                            return Ok(r);
                        }
                        // Evicted between the two looks: start again.
                        inner = lock(&self.inner);
                        continue;
                    }
                    State::Loading => {
                        drop(state);
                        inner = self.changed.wait(inner).unwrap_or_else(|e| e.into_inner());
                        continue;
                    }
                    State::Absent => {
                        if inner.resident + need <= self.budget {
                            *state = State::Loading;
                            break;
                        }
                    }
                }
            }
            inner = self.make_room(inner);
        }
        inner.resident += need;
        inner.peak = inner.peak.max(inner.resident);
        inner.resident_tiles.push(t);
        self.misses.fetch_add(1, Ordering::Relaxed);
        drop(inner);

        let decoded = Self::decode(map, t);

        let mut inner = lock(&self.inner);
        let mut state = lock(&self.slots[t as usize].state);
        let result = match decoded {
            Ok(tile) => {
                self.decodes.fetch_add(1, Ordering::Relaxed);
                self.decoded_bytes.fetch_add(
                    (tile.photons.len() * std::mem::size_of::<PackedPhoton>()) as u64,
                    Ordering::Relaxed,
                );
                // Keep what the tile holds, not the bound reserved for it.
                inner.resident -= need - tile.bytes().min(need);
                let tile = Arc::new(tile);
                *state = State::Ready(Arc::clone(&tile));
                self.slots[t as usize].last_used.store(
                    self.clock.fetch_add(1, Ordering::Relaxed),
                    Ordering::Relaxed,
                );
                Ok(TileRef {
                    tile: Some(tile),
                    cache: self,
                })
            }
            Err(e) => {
                *state = State::Absent;
                inner.resident -= need;
                inner.resident_tiles.retain(|&r| r != t);
                Err(e)
            }
        };
        drop(state);
        self.changed.notify_all();
        result
    }

    /// Evict the least recently used unpinned tile, or wait for a pin to be
    /// released when every resident tile is pinned or loading.
    fn make_room<'g>(
        &'g self,
        mut inner: std::sync::MutexGuard<'g, Inner>,
    ) -> std::sync::MutexGuard<'g, Inner> {
        self.waiters.fetch_add(1, Ordering::SeqCst);
        fence(Ordering::SeqCst);
        if !self.evict_one(&mut inner) {
            inner = self.changed.wait(inner).unwrap_or_else(|e| e.into_inner());
        }
        self.waiters.fetch_sub(1, Ordering::SeqCst);
        inner
    }

    /// Evict the least recently used unpinned tile; false if none.
    fn evict_one(&self, inner: &mut Inner) -> bool {
        let mut order: Vec<(u64, usize)> = inner
            .resident_tiles
            .iter()
            .enumerate()
            .map(|(i, &t)| (self.slots[t as usize].last_used.load(Ordering::Relaxed), i))
            .collect();
        order.sort_unstable();
        for (_, i) in order {
            let t = inner.resident_tiles[i];
            let mut state = lock(&self.slots[t as usize].state);
            // Pins are taken under the slot's lock, so none can appear
            // between this check and the eviction.
            let State::Ready(tile) = &*state else {
                continue;
            };
            if Arc::strong_count(tile) != 1 {
                continue;
            }
            inner.resident -= tile.bytes();
            *state = State::Absent;
            inner.resident_tiles.swap_remove(i);
            self.evictions.fetch_add(1, Ordering::Relaxed);
            return true;
        }
        false
    }

    fn decode(map: &MapFile, t: u32) -> Result<DecodedTile> {
        let mut photons = Vec::new();
        DECODER.with(|d| {
            let mut d = d.borrow_mut();
            map.decode_tile(t, &mut d, &mut photons)?;
            photons.shrink_to_fit();
            let tree = TileTree::from_morton(d.codes(), d.cells(), &map.tiles()[t as usize].quant);
            Ok(DecodedTile { photons, tree })
        })
    }
}
