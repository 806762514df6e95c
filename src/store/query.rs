//! Exact photon queries over a tiled map: k-nearest and fixed-radius.
//!
//! A query walks a tree over the tiles' photon bounds (one per layer) and
//! visits the tiles whose boxes meet its search sphere, nearest box first,
//! searching each tile's own tree (`store::tiletree`); a kNN query keeps
//! one buffer of the k nearest across tiles and stops when the next box is
//! farther than its current k-th neighbour. The results are those of one
//! exact search over every photon of the map (up to the order of photons
//! at exactly equal distance). Each query pins one
//! tile at a time, which is what lets the cache stay inside its budget.
//!
//! [`PhotonQuery`] is the interface the estimator sees; [`PhotonMap`] (a
//! map file with its tile cache) and [`super::in_memory::InMemoryMap`] (a
//! plain vector with one k-d tree per layer) implement it, and the oracle
//! tests check that they give the same answers.
//!
//! Not for: radiance estimation (`estimate` builds that on these queries).

use crate::bounds::Aabb;
use crate::error::Result;
use crate::morton::morton3;
use crate::photon::{PackedPhoton, Photon};
use crate::spectral::BandGrid;
use crate::store::boxtree::BoxTree;
use crate::store::cache::{CacheStats, TileCache};
use crate::store::tiletree::Nearest;
use crate::store::MapFile;
use glam::Vec3;
use rayon::prelude::*;

/// One neighbour of a query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbour {
    pub photon: Photon,
    /// Squared distance from the query point (m^2).
    pub distance_sq: f32,
}

/// As `littoral map query` prints it: position, direction, band, power and
/// distance (m).
impl serde::Serialize for Neighbour {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let p = &self.photon;
        let mut m = s.serialize_struct("Neighbour", 9)?;
        for (k, v) in [
            ("x", p.position.x),
            ("y", p.position.y),
            ("z", p.position.z),
        ] {
            m.serialize_field(k, &v)?;
        }
        for (k, v) in [
            ("dx", p.direction.x),
            ("dy", p.direction.y),
            ("dz", p.direction.z),
        ] {
            m.serialize_field(k, &v)?;
        }
        m.serialize_field("band", &p.band)?;
        m.serialize_field("power", &p.power)?;
        m.serialize_field("distance", &self.distance_sq.sqrt())?;
        m.end()
    }
}

/// What to search for around a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Search {
    /// The `k` nearest photons, none farther than `max_radius` (m) if given.
    Nearest { k: usize, max_radius: Option<f32> },
    /// Every photon within `radius` (m).
    Radius { radius: f32 },
}

/// Exact photon queries: what an estimate needs from a photon map.
///
/// `layer` is `None` for every layer or `Some(photon::LAYER_*)`. Results are
/// those of one exact search over every photon of the map, up to the order
/// of photons at exactly equal distance.
pub trait PhotonQuery: Sync {
    /// Photons matching `search` around `at`, nearest first, into `out`.
    fn query_into(
        &self,
        at: Vec3,
        layer: Option<u16>,
        search: Search,
        out: &mut Vec<Neighbour>,
    ) -> Result<()>;

    /// The same photons as [`PhotonQuery::query_into`] in no particular (but
    /// deterministic) order: cheaper when the caller only sums over them.
    fn query_any_order_into(
        &self,
        at: Vec3,
        layer: Option<u16>,
        search: Search,
        out: &mut Vec<Neighbour>,
    ) -> Result<()> {
        self.query_into(at, layer, search, out)
    }

    /// Bounds of the scene the photons were traced in.
    fn bounds(&self) -> Aabb;

    /// The band grid the photons index.
    fn bands(&self) -> &BandGrid;

    /// Photons stored in `layer`.
    fn layer_photons(&self, layer: u16) -> u64;

    /// Tile-cache counters, for maps that page tiles.
    fn cache_stats(&self) -> CacheStats {
        CacheStats::default()
    }

    /// Every photon of `layer`, once, in a deterministic order, passed to
    /// `f`: one streaming pass (a tiled map decodes one tile at a time,
    /// outside its cache).
    fn for_each_photon(&self, layer: u16, f: &mut dyn FnMut(&Photon)) -> Result<()>;

    /// Bounds of the photons of `layer` (empty for none).
    fn layer_bounds(&self, layer: u16) -> Aabb;

    /// Photons of every layer matching `search` around `at`, nearest first.
    fn query(&self, at: Vec3, search: Search) -> Result<Vec<Neighbour>> {
        let mut out = Vec::new();
        self.query_into(at, None, search, &mut out)?;
        Ok(out)
    }

    /// Photons of `layer` matching `search` around `at`, nearest first.
    fn query_layer(&self, at: Vec3, layer: u16, search: Search) -> Result<Vec<Neighbour>> {
        let mut out = Vec::new();
        self.query_into(at, Some(layer), search, &mut out)?;
        Ok(out)
    }
}

impl Search {
    /// The most photons to return (`usize::MAX` for a radius search) and
    /// the squared distance they may lie at; `None` when the search can
    /// find nothing (k = 0, a negative or NaN radius).
    pub fn limits(self) -> Option<(usize, f32)> {
        let (k, limit_sq) = match self {
            Search::Nearest { k, max_radius } => (k, max_radius.map_or(f32::INFINITY, |r| r * r)),
            Search::Radius { radius } => (usize::MAX, radius * radius),
        };
        (k > 0 && limit_sq >= 0.0).then_some((k, limit_sq))
    }
}

/// Per-thread query scratch: the tile-box heap, radius results with
/// directions still packed, and the k nearest so far.
#[derive(Default)]
struct QueryScratch {
    boxes: Vec<(f32, u32)>,
    within: Vec<(f32, PackedPhoton)>,
    nearest: Nearest,
}

thread_local! {
    static SCRATCH: std::cell::RefCell<QueryScratch> = std::cell::RefCell::new(QueryScratch::default());
}

/// The tiles of one layer and a tree over their boxes.
struct LayerIndex {
    layer: u16,
    tiles: Vec<u32>,
    tree: BoxTree,
}

/// A map file with its tile cache: the query interface of the store.
pub struct PhotonMap {
    file: MapFile,
    index: Vec<LayerIndex>,
    cache: TileCache,
}

/// Boxes are compared with this slack so that f32 rounding in the box
/// distance can never prune a tile holding a true neighbour.
const PRUNE_SLACK: f32 = 1.0 + 1e-5;

impl PhotonMap {
    /// Queries over `file` with `cache_budget` bytes for the tile cache,
    /// of which the tile-box index and the cache's slots take their share
    /// first.
    pub fn new(file: MapFile, cache_budget: u64) -> Result<PhotonMap> {
        let mut index = Vec::new();
        for layer in 0..crate::photon::LAYERS as u16 {
            let tiles: Vec<u32> = (0..file.tiles().len() as u32)
                .filter(|&t| file.tiles()[t as usize].layer == layer as u32)
                .collect();
            if tiles.is_empty() {
                continue;
            }
            let boxes: Vec<Aabb> = tiles
                .iter()
                .map(|&t| file.tiles()[t as usize].bounds)
                .collect();
            index.push(LayerIndex {
                layer,
                tree: BoxTree::over_boxes(&boxes),
                tiles,
            });
        }
        let overhead = Self::index_bytes(file.tiles().len());
        let cache = TileCache::new(&file, cache_budget.saturating_sub(overhead))?;
        Ok(PhotonMap { file, index, cache })
    }

    /// Bytes the tile-box index and the cache's bookkeeping take for a map
    /// of `tiles` tiles (a tree node and a tile number per tile, and one
    /// cache slot): taken from the cache's budget.
    pub fn index_bytes(tiles: usize) -> u64 {
        (tiles * (64 + 4)) as u64 + TileCache::overhead_bytes(tiles)
    }

    /// The underlying map file.
    pub fn file(&self) -> &MapFile {
        &self.file
    }

    /// The tile cache.
    pub fn cache(&self) -> &TileCache {
        &self.cache
    }

    fn query_ordered_into(
        &self,
        at: Vec3,
        layer: Option<u16>,
        search: Search,
        sorted: bool,
        out: &mut Vec<Neighbour>,
    ) -> Result<()> {
        out.clear();
        let Some((k, limit_sq)) = search.limits() else {
            return Ok(());
        };
        SCRATCH.with(|c| {
            let s = &mut *c.borrow_mut();
            self.search_tiles(at, layer, k, limit_sq, s)?;
            // Directions are decoded only for the photons that made the cut.
            let neighbour = |(d, p): (f32, &PackedPhoton)| Neighbour {
                photon: p.unpack(),
                distance_sq: d,
            };
            if k == usize::MAX {
                if sorted {
                    s.within.sort_by(|a, b| a.0.total_cmp(&b.0));
                }
                out.extend(s.within.iter().map(|(d, p)| neighbour((*d, p))));
            } else {
                out.extend(s.nearest.results(sorted).map(neighbour));
            }
            Ok(())
        })
    }

    /// Visit the tiles whose boxes can still hold a result, nearest box
    /// first (through the tile-box index), and search each one's tree; the
    /// k nearest are kept in one buffer across tiles, whose k-th distance
    /// bounds the tiles still to visit. The results are left in
    /// `s.within` (a radius search, `k == usize::MAX`) or `s.nearest`.
    fn search_tiles(
        &self,
        at: Vec3,
        layer: Option<u16>,
        k: usize,
        limit_sq: f32,
        s: &mut QueryScratch,
    ) -> Result<()> {
        let q = at.to_array();
        let QueryScratch {
            boxes,
            within,
            nearest,
        } = s;
        within.clear();
        if k != usize::MAX {
            nearest.reset(k, limit_sq);
        }
        for index in &self.index {
            if layer.is_some_and(|l| l != index.layer) {
                continue;
            }
            if k == usize::MAX {
                index
                    .tree
                    .nearest_leaves(&q, limit_sq * PRUNE_SLACK, boxes, |_, item| {
                        let tile = self.cache.get(&self.file, index.tiles[item as usize])?;
                        tile.tree.within(&tile.photons, &q, limit_sq, within);
                        Ok::<_, crate::error::Error>(limit_sq * PRUNE_SLACK)
                    })?;
            } else {
                index.tree.nearest_leaves(
                    &q,
                    nearest.bound_sq() * PRUNE_SLACK,
                    boxes,
                    |_, item| {
                        let tile = self.cache.get(&self.file, index.tiles[item as usize])?;
                        tile.tree.nearest(&tile.photons, &q, nearest);
                        Ok::<_, crate::error::Error>(nearest.bound_sq() * PRUNE_SLACK)
                    },
                )?;
            }
        }
        Ok(())
    }

    /// Run many queries, reordered along a Morton curve so that consecutive
    /// queries share tiles, in parallel; results come back in input order.
    pub fn query_batch(&self, points: &[Vec3], search: Search) -> Result<Vec<Vec<Neighbour>>> {
        let b = &self.file.header().bounds;
        let q = crate::store::codec::BoxQuantizer::new(b);
        let mut order: Vec<(u64, u32)> = points
            .iter()
            .enumerate()
            .map(|(i, p)| {
                (
                    morton3(q.encode(p.clamp(b.min, b.max).to_array())),
                    i as u32,
                )
            })
            .collect();
        order.sort_unstable();
        let mut results: Vec<Vec<Neighbour>> = vec![Vec::new(); points.len()];
        let sorted: Vec<(u32, Vec<Neighbour>)> = order
            .par_chunks(256)
            .map(|chunk| {
                chunk
                    .iter()
                    .map(|&(_, i)| Ok((i, PhotonQuery::query(self, points[i as usize], search)?)))
                    .collect::<Result<Vec<_>>>()
            })
            .collect::<Result<Vec<_>>>()?
            .into_iter()
            .flatten()
            .collect();
        for (i, r) in sorted {
            results[i as usize] = r;
        }
        Ok(results)
    }
}

impl PhotonQuery for PhotonMap {
    fn query_into(
        &self,
        at: Vec3,
        layer: Option<u16>,
        search: Search,
        out: &mut Vec<Neighbour>,
    ) -> Result<()> {
        self.query_ordered_into(at, layer, search, true, out)
    }

    fn query_any_order_into(
        &self,
        at: Vec3,
        layer: Option<u16>,
        search: Search,
        out: &mut Vec<Neighbour>,
    ) -> Result<()> {
        self.query_ordered_into(at, layer, search, false, out)
    }

    fn bounds(&self) -> Aabb {
        self.file.header().bounds
    }

    fn bands(&self) -> &BandGrid {
        &self.file.header().bands
    }

    fn layer_photons(&self, layer: u16) -> u64 {
        self.file.layer_photons(layer)
    }

    fn cache_stats(&self) -> CacheStats {
        self.cache.stats()
    }

    /// From the index: every tile records its decoded photons' bounds.
    fn layer_bounds(&self, layer: u16) -> Aabb {
        self.file
            .tiles()
            .iter()
            .filter(|e| e.layer == layer as u32)
            .fold(Aabb::EMPTY, |b, e| b.union(&e.bounds))
    }

    fn for_each_photon(&self, layer: u16, f: &mut dyn FnMut(&Photon)) -> Result<()> {
        let mut decoder = super::codec::TileDecoder::default();
        let mut tile = Vec::new();
        for (t, e) in self.file.tiles().iter().enumerate() {
            if e.layer != layer as u32 {
                continue;
            }
            tile.clear();
            self.file.decode_tile(t as u32, &mut decoder, &mut tile)?;
            for p in &tile {
                f(&p.unpack());
            }
        }
        Ok(())
    }
}
