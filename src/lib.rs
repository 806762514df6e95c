//! littoral — out-of-core spectral photon mapping for coastal waters.
//!
//! The modules, in data-flow order:
//! - [`scene`]: the scene file, validated ([`scene::Scene`]).
//! - [`optics`]: embedded spectral tables averaged over the band grid
//!   ([`optics::tables::Table`]), IOPs, phase functions with exact samplers
//!   ([`optics::phase::PhaseFunction`]), the sea surface.
//! - [`geometry`]: floor and targets in one BVH ([`geometry::Geometry`]).
//! - [`emit`]: photon tracing into the store, tallies, energy ([`emit::Emitter`]).
//! - [`spectral`]: the band grid every photon indexes ([`BandGrid`]).
//! - [`photon`]: the stored photon and its quantised encodings ([`Photon`]).
//! - [`synth`]: synthetic photon sources for tests and benchmarks ([`synth::SynthSource`]).
//! - [`store`]: the map file — streaming tile sort, codec, format, reader
//!   ([`store::build_map`], [`store::MapFile`]).
//! - [`cache`]: decoded tiles and their k-d trees under a byte budget ([`cache::TileCache`]).
//! - [`query`]: exact kNN and radius queries over a map ([`query::PhotonMap`]).
//! - [`estimate`]: density estimation; so far the boundary-bias compensation
//!   ([`estimate::boundary::BoundaryMode`]).
//!
//! Support: [`error`] (typed errors naming file, tile and field), [`rng`]
//! (per-index random streams), [`progress`] (progress hooks), [`size`]
//! (memory sizes such as `64MiB`), [`mem`] (the process's own peak memory),
//! [`output`] (files written whole or not at all).

pub mod cache;
pub mod emit;
pub mod error;
pub mod estimate;
pub mod geometry;
pub mod mem;
pub mod optics;
pub mod output;
pub mod photon;
pub mod progress;
pub mod query;
pub mod rng;
pub mod scene;
pub mod size;
pub mod spectral;
pub mod store;
pub mod synth;

pub use error::{Error, Result};
pub use photon::Photon;
pub use spectral::BandGrid;
