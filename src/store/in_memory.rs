//! An in-memory photon map: every photon in one vector per layer, each with
//! one k-d tree. The stand-in for [`super::query::PhotonMap`] where a map
//! fits in memory: estimator and boundary tests, small scenes, and the
//! oracle the tiled queries are checked against.
//!
//! Built from photons directly ([`InMemoryMap::new`]) or from a map file
//! ([`InMemoryMap::from_file`], which decodes every tile, so both answer
//! from the same quantised positions) or from a photon source
//! ([`InMemoryMap::from_source`]).
//!
//! Not for: maps larger than memory (the tiled map pages them under a budget).

use super::query::{Neighbour, PhotonQuery, Search};
use super::MapFile;
use crate::bounds::Aabb;
use crate::error::{Error, Result};
use crate::photon::{PackedPhoton, Photon, LAYERS};
use crate::spectral::BandGrid;
use glam::Vec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use std::num::NonZeroUsize;

/// One layer's photons and their k-d tree (items index `photons`).
struct Layer {
    photons: Vec<PackedPhoton>,
    tree: Option<ImmutableKdTree<f32, 3>>,
}

impl Layer {
    fn new(photons: Vec<PackedPhoton>) -> Result<Layer> {
        let tree = if photons.is_empty() {
            None
        } else {
            let points: Vec<[f32; 3]> = photons.iter().map(|p| p.position).collect();
            Some(
                ImmutableKdTree::new_from_slice(&points)
                    .map_err(|e| Error::invalid("in-memory map", format!("k-d tree: {e:?}")))?,
            )
        };
        Ok(Layer { photons, tree })
    }

    /// Append this layer's photons within `limit_sq` (the `k` nearest) as
    /// (squared distance, photon).
    fn search(&self, at: Vec3, k: usize, limit_sq: f32, out: &mut Vec<(f32, PackedPhoton)>) {
        let Some(tree) = &self.tree else { return };
        let found = search_tree(tree, &at.to_array(), k, limit_sq, true);
        out.extend(
            found
                .into_iter()
                .map(|r| (r.distance, self.photons[r.item as usize])),
        );
    }
}

/// A photon map held whole in memory.
pub struct InMemoryMap {
    layers: Vec<Layer>,
    bands: BandGrid,
    bounds: Aabb,
}

impl InMemoryMap {
    /// A map of `photons`, each with its layer (`photon::LAYER_*`), over
    /// `bands` and the scene `bounds`.
    pub fn new(
        photons: impl IntoIterator<Item = (Photon, u16)>,
        bands: BandGrid,
        bounds: Aabb,
    ) -> Result<InMemoryMap> {
        let mut by_layer: Vec<Vec<PackedPhoton>> = vec![Vec::new(); LAYERS];
        for (p, layer) in photons {
            let slot = by_layer.get_mut(layer as usize).ok_or_else(|| {
                Error::invalid("photon layer", format!("layer {layer} does not exist"))
            })?;
            if p.band as usize >= bands.len() {
                return Err(Error::invalid(
                    "photon band",
                    format!("band {} outside the {}-band grid", p.band, bands.len()),
                ));
            }
            slot.push(PackedPhoton::pack(&p, layer));
        }
        Self::from_layers(by_layer, bands, bounds)
    }

    /// Every photon a source produces, at full precision (no tile
    /// quantisation).
    pub fn from_source(source: &dyn super::PhotonSource) -> Result<InMemoryMap> {
        let mut staged = Vec::new();
        source.generate(0..source.indices(), &mut staged);
        Self::new(
            staged.iter().map(|s| (s.photon.unpack(), s.photon.layer)),
            source.bands(),
            source.bounds(),
        )
    }

    /// Every photon of a map file, decoded.
    pub fn from_file(file: &MapFile) -> Result<InMemoryMap> {
        let mut by_layer: Vec<Vec<PackedPhoton>> = vec![Vec::new(); LAYERS];
        let mut decoder = super::codec::TileDecoder::default();
        let mut tile = Vec::new();
        for (t, e) in file.tiles().iter().enumerate() {
            tile.clear();
            file.decode_tile(t as u32, &mut decoder, &mut tile)?;
            by_layer[e.layer as usize].extend_from_slice(&tile);
        }
        let h = file.header();
        Self::from_layers(by_layer, h.bands.clone(), h.bounds)
    }

    fn from_layers(
        by_layer: Vec<Vec<PackedPhoton>>,
        bands: BandGrid,
        bounds: Aabb,
    ) -> Result<InMemoryMap> {
        Ok(InMemoryMap {
            layers: by_layer
                .into_iter()
                .map(Layer::new)
                .collect::<Result<_>>()?,
            bands,
            bounds,
        })
    }
}

impl PhotonQuery for InMemoryMap {
    fn layer_bounds(&self, layer: u16) -> Aabb {
        let mut b = Aabb::EMPTY;
        if let Some(l) = self.layers.get(layer as usize) {
            for p in &l.photons {
                b.grow(p.pos());
            }
        }
        b
    }

    fn for_each_photon(&self, layer: u16, f: &mut dyn FnMut(&Photon)) -> Result<()> {
        if let Some(l) = self.layers.get(layer as usize) {
            for p in &l.photons {
                f(&p.unpack());
            }
        }
        Ok(())
    }

    fn query_into(
        &self,
        at: Vec3,
        layer: Option<u16>,
        search: Search,
        out: &mut Vec<Neighbour>,
    ) -> Result<()> {
        out.clear();
        let Some((k, limit_sq)) = search.limits() else {
            return Ok(());
        };
        let mut found = Vec::new();
        for (l, data) in self.layers.iter().enumerate() {
            if layer.is_none_or(|want| want as usize == l) {
                data.search(at, k, limit_sq, &mut found);
            }
        }
        found.sort_by(|a, b| a.0.total_cmp(&b.0));
        found.truncate(k);
        out.extend(found.iter().map(|(d, p)| Neighbour {
            photon: p.unpack(),
            distance_sq: *d,
        }));
        Ok(())
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn bands(&self) -> &BandGrid {
        &self.bands
    }

    fn layer_photons(&self, layer: u16) -> u64 {
        self.layers
            .get(layer as usize)
            .map_or(0, |l| l.photons.len() as u64)
    }
}

/// One k-d tree's photons within `bound_sq` of `q` (all of them for
/// `k == usize::MAX`, else the `k` nearest), nearest first when `sorted`;
/// items index the tree's points.
fn search_tree(
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
