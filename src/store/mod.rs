//! The out-of-core photon store: file format, tile codec, partition,
//! streaming writer and memory-mapped reader.
//!
//! A map is written once by [`build_map`] (or a [`MapWriter`] fed directly)
//! and never modified; readers map it read-only with [`MapFile::open`].
//!
//! Modules: writing — [`build`] (parallel producers, one writer thread),
//! [`writer`] (the streaming tile sort within a memory budget), [`spill`]
//! (photons at rest in its scratch file), [`radix`] (its sorts),
//! [`partition`] (the pilot k-d partition into tiles), [`codec`] (a tile's
//! compressed records), [`format`](mod@format) (the file layout), [`shard`] (one
//! machine's part of a sharded emission); reading — [`reader`] (open and
//! validate), [`cache`] (decoded tiles under a byte budget), [`tiletree`]
//! (a tile's k-d tree), [`boxtree`] (the hierarchy over the tile boxes),
//! [`query`] (k-nearest and fixed-radius searches), [`in_memory`] (an
//! in-memory map for tests and small tools).

pub mod boxtree;
pub mod build;
pub mod cache;
pub mod codec;
pub mod format;
pub mod in_memory;
pub mod partition;
pub mod query;
pub mod radix;
pub mod reader;
pub mod shard;
pub mod spill;
pub mod tiletree;
pub mod writer;

pub use build::{build_map, BuildOptions, PhotonSource};
pub use codec::{StagedPhoton, ENCODE_BYTES_PER_PHOTON};
pub use format::{Header, TileEntry};
pub use in_memory::InMemoryMap;
pub use partition::Partition;
pub use query::{Neighbour, PhotonMap, PhotonQuery, Search};
pub use reader::MapFile;
pub use writer::{
    MapWriter, WriteSummary, WriterPlan, EXTRA_ENCODER_BYTES, FETCH_BUFFER_BYTES, MAX_FETCHERS,
    MIN_FETCHERS,
};
