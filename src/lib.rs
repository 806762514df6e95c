//! littoral — out-of-core spectral photon mapping for coastal waters.
//!
//! The modules, in data-flow order:
//! - [`scene`]: the scene file, validated ([`scene::Scene`]), its
//!   `[estimate]` settings and defaults ([`scene::EstimateSettings`]) and its
//!   emission inputs for map provenance.
//! - [`optics`]: embedded spectral tables averaged over the band grid
//!   ([`optics::tables::Table`]), IOPs and their local majorants for delta
//!   tracking ([`optics::majorant::MajorantGrid`]), phase functions with exact samplers
//!   ([`optics::phase::PhaseFunction`]), the sky's radiance distribution
//!   ([`optics::sky::SkyModel`]), the sea surface with Smith shadowing, and
//!   the water's refractive index per band ([`optics::water_index`]).
//! - [`geometry`]: floor and targets in one BVH ([`geometry::Geometry`]).
//! - [`emit`]: photon tracing into the store, tallies, energy, the
//!   emission report ([`emit::Emitter`]); sharded emission and its merge
//!   ([`emit::shard::emit_shard`], [`emit::shard::merge_shards`]).
//! - [`store`]: the map file — streaming tile sort, codec, format, reader —
//!   and its read side: the tile cache ([`store::cache::TileCache`]) and exact
//!   kNN and radius queries behind one interface ([`store::PhotonQuery`]),
//!   implemented by the tiled map ([`store::PhotonMap`]) and an in-memory map
//!   ([`store::InMemoryMap`]); shard files of a sharded emission
//!   ([`store::shard`]).
//! - [`estimate`]: radiance from photons, with boundary- and spectral-bias
//!   compensation and the forward peak as a delta ([`estimate::Estimator`]).
//! - [`render`]: sensor rays, the two integrators behind one trait
//!   ([`render::Integrator`]): the photon map's ray marcher
//!   ([`render::march::RayMarcher`]) and the unbiased reference path tracer
//!   ([`render::path::PathTracer`]); the image loop, tile by tile
//!   ([`render::render_tile`]) into a sink ([`render::TileSink`]), and
//!   radiometers ([`render::render_with`]); it writes no file.
//! - [`cube`]: the radiance cube on disk (ENVI, spectral OpenEXR), its
//!   quicklook (PNG) and derived cubes ([`cube::ops`], e.g. resampled into
//!   a real sensor's bands, [`spectral::response::SpectralResponse`]).
//! - [`job`]: the whole pipeline as one call — scene, map (reused by
//!   provenance or emitted), render, outputs — with the typed report and the
//!   memory budget ([`job::RenderJob`], [`job::EmitJob`], [`job::MemoryBudget`]);
//!   the cube set and the run's files, staged and published as one set
//!   ([`job::outputs`], [`output::set`]); the HTML report ([`job::html`]); renders split into parts and
//!   assembled, or resumed ([`job::distributed::parts`]); Slurm batch scripts
//!   ([`job::distributed::plan`]).
//!
//! Data types every stage shares: [`spectral`] (the band grid every photon
//! indexes, [`BandGrid`]), [`photon`] (the stored photon and its quantised
//! encodings, [`Photon`]), [`bounds`] (axis-aligned boxes), [`provenance`]
//! (what a map was made from).
//!
//! Support: [`error`] (typed errors naming file, tile and field), [`csv`]
//! (the one reader of numeric tables), [`nan_json`] (reports read back),
//! [`morton`] (Z-order codes), [`parallel`] (worker pools), [`rng`]
//! (per-index random streams), [`progress`] (progress hooks), [`size`]
//! (memory sizes such as `64MiB`), [`mem`] (the process's own peak memory),
//! [`output`] (files written whole or not at all, positioned I/O), [`synth`]
//! (synthetic photon sources for tests and benchmarks), [`simd`] (prefetch
//! and the 16 x 16 byte transpose, each with a portable fallback giving the
//! same bits), [`cli`] (what the command-line programs share).
//!
//! Layering: `scene`, `optics`, `geometry`, `store` and `spectral` import
//! none of `job`, `render`, `estimate`, `emit` and `cube` (the stages build
//! on them, never the other way); `render` writes no file; only `job` and
//! the programs know every stage.

pub mod bounds;
pub mod cli;
pub mod csv;
pub mod cube;
pub mod emit;
pub mod error;
pub mod estimate;
pub mod geometry;
pub mod job;
pub mod mem;
pub mod morton;
pub mod nan_json;
pub mod optics;
pub mod output;
pub mod parallel;
pub mod photon;
pub mod progress;
pub mod provenance;
pub mod render;
pub mod rng;
pub mod scene;
pub mod simd;
pub mod size;
pub mod spectral;
pub mod store;
pub mod synth;
#[cfg(test)]
mod testing;

pub use error::{Error, Result};
pub use photon::Photon;
pub use spectral::BandGrid;
