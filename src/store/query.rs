//! Exact photon queries over a tiled map: k-nearest and fixed-radius.
//!
//! A query visits the tiles whose photon bounds meet its search sphere,
//! nearest box first, and searches each tile's k-d tree; a kNN query stops
//! when the next box is farther than its current k-th neighbour. The
//! results are those of one k-d tree over every photon of the map (up to
//! the order of photons at exactly equal distance). Each query pins one
//! tile at a time, which is what lets the cache stay inside its budget.
//!
//! [`PhotonQuery`] is the interface the estimator sees; [`PhotonMap`] (a
//! map file with its tile cache) and [`super::memory::InMemoryMap`] (a
//! plain vector with one k-d tree per layer) implement it, and the oracle
//! tests check that they give the same answers.
//!
//! Not for: radiance estimation (`estimate` builds that on these queries).

use crate::bounds::Aabb;
use crate::error::Result;
use crate::morton::morton3;
use crate::photon::{PackedPhoton, Photon};
use crate::spectral::BandGrid;
use crate::store::cache::{CacheStats, TileCache};
use crate::store::MapFile;
use glam::Vec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use std::num::NonZeroUsize;

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

/// One k-d tree's photons within `bound_sq` of `q` (all of them for
/// `k == usize::MAX`, else the `k` nearest), nearest first when `sorted`;
/// items index the tree's points.
pub(super) fn search_tree(
    tree: &ImmutableKdTree<f32, 3>,
    q: &[f32; 3],
    k: usize,
    bound_sq: f32,
    sorted: bool,
) -> Vec<kiddo::QueryResultItem<(), u32, f32>> {
    if k == usize::MAX {
        return tree
            .query(q)
            .within::<SquaredEuclidean<f32>>(bound_sq)
            .unsorted()
            .execute();
    }
    let want = NonZeroUsize::new(k).expect("k > 0");
    let nearest = tree.query(q).nearest_n::<SquaredEuclidean<f32>>(want);
    match (bound_sq.is_finite(), sorted) {
        (true, false) => nearest.within(bound_sq).unsorted().execute(),
        (true, true) => nearest.within(bound_sq).execute(),
        (false, _) => nearest.execute(),
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

/// Per-thread query scratch: candidate tiles, and results with directions
/// still packed.
type QueryScratch = (Vec<(f32, u32)>, Vec<(f32, PackedPhoton)>);

thread_local! {
    static CANDIDATES: std::cell::RefCell<QueryScratch> = const { std::cell::RefCell::new((Vec::new(), Vec::new())) };
}

/// A map file with its tile cache: the query interface of the store.
pub struct PhotonMap {
    file: MapFile,
    cache: TileCache,
}

/// Boxes are compared with this slack so that f32 rounding in the box
/// distance can never prune a tile holding a true neighbour.
const PRUNE_SLACK: f32 = 1.0 + 1e-5;

impl PhotonMap {
    /// Queries over `file` with a tile cache of `cache_budget` bytes.
    pub fn new(file: MapFile, cache_budget: u64) -> Result<PhotonMap> {
        let cache = TileCache::new(&file, cache_budget)?;
        Ok(PhotonMap { file, cache })
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
        CANDIDATES.with(|c| {
            let (candidates, packed) = &mut *c.borrow_mut();
            packed.clear();
            self.search_tiles(at, layer, k, limit_sq, sorted, candidates, packed)?;
            // Directions are decoded only for the photons that made the cut.
            out.extend(packed.iter().map(|(d, p)| Neighbour {
                photon: p.unpack(),
                distance_sq: *d,
            }));
            Ok(())
        })
    }

    /// Visit the tiles in `candidates` nearest box first, as long as a box
    /// can still hold a result. Picking the nearest box by a linear scan is
    /// cheaper than sorting: a query visits only a few of the map's tiles.
    /// Unsorted, the k nearest so far are kept by selection and the k-th
    /// distance is their maximum.
    #[allow(clippy::too_many_arguments)]
    fn search_tiles(
        &self,
        at: Vec3,
        layer: Option<u16>,
        k: usize,
        limit_sq: f32,
        sorted: bool,
        candidates: &mut Vec<(f32, u32)>,
        out: &mut Vec<(f32, PackedPhoton)>,
    ) -> Result<()> {
        candidates.clear();
        candidates.extend(
            self.file
                .tiles()
                .iter()
                .enumerate()
                .filter(|(_, e)| layer.is_none_or(|l| e.layer == l as u32))
                .map(|(t, e)| (e.bounds.distance_sq(at), t as u32))
                .filter(|&(d, _)| d <= limit_sq * PRUNE_SLACK),
        );
        let q = at.to_array();
        // The k-th distance so far, once k photons are known.
        let mut kth_sq = f32::INFINITY;
        while !candidates.is_empty() {
            let (i, &(box_sq, t)) = candidates
                .iter()
                .enumerate()
                .min_by(|a, b| a.1 .0.total_cmp(&b.1 .0).then(a.1 .1.cmp(&b.1 .1)))
                .expect("not empty");
            candidates.swap_remove(i);
            let bound_sq = if out.len() >= k { kth_sq } else { limit_sq };
            if box_sq > bound_sq * PRUNE_SLACK {
                break;
            }
            let tile = self.cache.get(&self.file, t)?;
            let before = out.len();
            let found = search_tree(&tile.tree, &q, k, bound_sq, sorted);
            out.extend(
                found
                    .into_iter()
                    .map(|r| (r.distance, tile.photons[r.item as usize])),
            );
            drop(tile);
            if out.len() > before {
                if sorted {
                    out.sort_by(|a, b| a.0.total_cmp(&b.0));
                    out.truncate(k);
                    if out.len() >= k {
                        kth_sq = out[k - 1].0;
                    }
                } else if out.len() >= k && k != usize::MAX {
                    if out.len() > k {
                        out.select_nth_unstable_by(k - 1, |a, b| a.0.total_cmp(&b.0));
                        out.truncate(k);
                    }
                    kth_sq = out.iter().fold(0.0f32, |m, p| m.max(p.0));
                }
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
