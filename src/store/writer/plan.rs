//! How the map writer divides its memory budget (see `writer`): a fixed
//! reserve, the cell buffers, the encode share, and the frames read ahead
//! of encoding.

use super::{MIB, STAGED};
use crate::error::{Error, Result};
use crate::store::codec::ENCODE_BYTES_PER_PHOTON;
use crate::store::spill::MAX_FRAME_BYTES;

/// Memory the writer keeps outside its budgeted shares: zstd contexts
/// (level-1 compressor and a decompressor, about 1.5 MiB together), the
/// map's 1 MiB and the scratch file's 256 KiB write buffers, the spill
/// frame's sort keys and planes (about 1.3 MiB), the read buffers of
/// [`MIN_FETCHERS`] fetcher threads (a frame each, up to 2 MiB in all),
/// the producer channel and spill metadata.
pub const WRITER_FIXED_BYTES: u64 = 9 * MIB;

/// Memory of each tile encoder beyond the first (its zstd context and
/// buffers not counted per photon), charged to the encode share when tiles
/// are encoded in parallel.
pub const EXTRA_ENCODER_BYTES: u64 = 2 * MIB;

/// Bytes a spilled photon takes in the scratch file, for budgeting the
/// frames read ahead of encoding: 12-13 measured (`benches/README.md`),
/// 19.4 in frames of 32 photons (few are smaller: a spill takes the
/// fullest cells).
pub const FETCH_BYTES_PER_PHOTON: u64 = 20;

/// Fetcher threads (reading cells' spilled frames ahead of the encoders)
/// whose read buffers the fixed reserve holds ([`WriterPlan::fetchers`]).
pub const MIN_FETCHERS: usize = 8;

/// Fetcher threads at most: at 10^9 photons, eight kept the two encoders
/// a third busy, waiting on chains of reads.
pub const MAX_FETCHERS: usize = 32;

/// A fetcher's read buffer at most: the largest scratch frame, read in
/// whole 4 KiB blocks (a block more at each end).
pub const FETCH_BUFFER_BYTES: u64 = 256 << 10;
const _: () = assert!((MAX_FRAME_BYTES + 2 * 4096) as u64 <= FETCH_BUFFER_BYTES);

/// Bytes each partition cell costs outside the buffers, whatever it
/// holds, taken from the buffer share: per layer a cell buffer (about 80
/// bytes: its chunk list, newest spilled frame, count and box), the spill
/// thread's newest frame (24) and the spill's ranking of cells (16); the
/// partition's node, link and lookup step and the header's copy of them
/// (about 90); rounded up.
pub const CELL_BYTES: u64 = 512;

/// Smallest budget the writer accepts.
pub const MIN_WRITER_BUDGET: u64 = 14 * MIB;

/// Photons per tile the writer aims for when the budget allows: large
/// enough that per-tile overhead is small, small enough that the cache can
/// page tiles at a fine grain (about 2 MiB decoded with its search tree).
pub const DEFAULT_TILE_PHOTONS: u32 = 65_536;

/// How a memory budget is divided while writing a map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WriterPlan {
    /// The budget (bytes) this plan divides.
    pub budget: u64,
    /// Photons per tile the partition aims for.
    pub target_tile_photons: u32,
    /// A cell with more photons than this is split before encoding.
    pub split_threshold: u32,
    /// The most photons the encode share can hold in one tile.
    pub max_tile_photons: u32,
    /// Bytes of per-cell buffers before spilling starts.
    pub buffer_bytes: u64,
    /// Bytes taken from the buffer share for cells' spilled frames read
    /// ahead of their encoding, where the encode share leaves too little
    /// room for them ([`WriterPlan::fetch_bytes`]).
    pub fetch_reserve: u64,
    /// Records per buffer chunk ([`chunk_records`]).
    pub chunk_records: usize,
    /// The photons the plan expects (the partition's cells are these over
    /// the target tile, [`WriterPlan::cells_for`]).
    pub expected_photons: u64,
    /// The most cells the partition may have: their bookkeeping
    /// ([`CELL_BYTES`] each) takes at most half of the buffers. A finer
    /// partition than that has fewer, larger cells, and tiles past the
    /// split threshold are split at the end.
    pub max_cells: u64,
    /// Threads that may encode tiles at once at the end (0 = one per
    /// core); how many do is bounded by the encode share too
    /// ([`WriterPlan::encode_width`]).
    pub threads: usize,
}

impl WriterPlan {
    /// Divide `budget` bytes: a fixed reserve, a quarter of the rest for
    /// encoding one tile, the remainder for cell buffers (less a fetch
    /// reserve at small budgets, [`WriterPlan::fetch_bytes`], and the
    /// cells' bookkeeping, [`CELL_BYTES`] each). While
    /// photons arrive the encode share is headroom for routing during a
    /// spill.
    pub fn new(budget: u64, expected_photons: u64) -> Result<Self> {
        if budget < MIN_WRITER_BUDGET {
            return Err(Error::Budget {
                budget,
                what: format!(
                    "writing a map needs at least {} MiB",
                    MIN_WRITER_BUDGET / MIB
                ),
            });
        }
        let rest = budget - WRITER_FIXED_BYTES;
        let merge = rest / 4;
        let max_tile = (merge / ENCODE_BYTES_PER_PHOTON as u64).min(u32::MAX as u64) as u32;
        let target = DEFAULT_TILE_PHOTONS.min(max_tile / 2);
        // Frames read ahead of encoding fit in the encode share beside one
        // tile at budgets of a few hundred MiB; below that a sixteenth of
        // the rest is set aside for them.
        let tile_bytes = (2 * target).min(max_tile) as u64 * ENCODE_BYTES_PER_PHOTON as u64;
        let fetch_reserve = (rest / 16).saturating_sub(merge.saturating_sub(tile_bytes));
        let buffers = rest - merge - fetch_reserve;
        let max_cells = (buffers / 2 / CELL_BYTES).max(1);
        let cells = expected_photons.div_ceil(target as u64).clamp(1, max_cells);
        let buffer_bytes = buffers - cells * CELL_BYTES;
        let chunk_records = chunk_records(buffer_bytes, cells);
        Ok(WriterPlan {
            budget,
            target_tile_photons: target,
            split_threshold: (2 * target).min(max_tile),
            max_tile_photons: max_tile,
            buffer_bytes,
            fetch_reserve,
            chunk_records,
            expected_photons,
            max_cells,
            threads: 1,
        })
    }

    /// Encode tiles on up to `threads` threads (0 = one per core).
    pub fn with_threads(mut self, threads: usize) -> Self {
        self.threads = threads;
        self
    }

    /// Tiles encoded at once: at most the threads, and as many tiles of the
    /// split threshold (plus an encoder each beyond the first) as the
    /// encode share holds. The encode share is what one tile of
    /// `max_tile_photons` may take.
    pub fn encode_width(&self) -> usize {
        let threads = match self.threads {
            0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
            n => n,
        };
        let share = self.max_tile_photons as u64 * ENCODE_BYTES_PER_PHOTON as u64;
        let tile = self.split_threshold as u64 * ENCODE_BYTES_PER_PHOTON as u64;
        let fit = (1..=threads)
            .take_while(|&w| w as u64 * tile + (w as u64 - 1) * EXTRA_ENCODER_BYTES <= share)
            .last();
        fit.unwrap_or(1)
    }

    /// Bytes the last phase may hold of cells' spilled frames read ahead of
    /// their encoding, at [`FETCH_BYTES_PER_PHOTON`], and of their tiles
    /// waiting to be appended, at their size: the fetch share (see
    /// `fetch_share`) less the read buffers of the fetchers beyond
    /// [`MIN_FETCHERS`]. One cell is always allowed.
    pub fn fetch_bytes(&self) -> u64 {
        let extra = (self.fetchers() - MIN_FETCHERS) as u64;
        self.fetch_share() - extra * FETCH_BUFFER_BYTES
    }

    /// Threads that read cells' spilled frames at the end, each cell a
    /// chain of reads that wait on the disk (the scratch file is read
    /// around the page cache), so the more at once the better: the
    /// [`MIN_FETCHERS`] the fixed reserve holds, and up to
    /// [`MAX_FETCHERS`] with read buffers taken from a quarter of the fetch
    /// share.
    pub fn fetchers(&self) -> usize {
        let extra = (self.fetch_share() / 4 / FETCH_BUFFER_BYTES) as usize;
        MIN_FETCHERS + extra.min(MAX_FETCHERS - MIN_FETCHERS)
    }

    /// What the encode share leaves beside [`WriterPlan::encode_width`]
    /// tiles, or the reserve if that is more: for fetching.
    fn fetch_share(&self) -> u64 {
        let width = self.encode_width() as u64;
        let share = self.max_tile_photons as u64 * ENCODE_BYTES_PER_PHOTON as u64;
        let tiles = width * self.split_threshold as u64 * ENCODE_BYTES_PER_PHOTON as u64
            + (width - 1) * EXTRA_ENCODER_BYTES;
        share.saturating_sub(tiles).max(self.fetch_reserve)
    }

    /// Aim for `photons` per tile (at least 1, at most what the encode share allows).
    pub fn with_tile_photons(mut self, photons: u32) -> Self {
        let buffers = self.buffer_bytes + self.cells_for(self.expected_photons) as u64 * CELL_BYTES;
        self.target_tile_photons = photons.clamp(1, self.max_tile_photons / 2);
        self.split_threshold = (2 * self.target_tile_photons).min(self.max_tile_photons);
        let cells = self.cells_for(self.expected_photons) as u64;
        self.buffer_bytes = buffers - cells * CELL_BYTES;
        self.chunk_records = chunk_records(self.buffer_bytes, cells);
        self
    }

    /// Number of partition cells for `expected_photons`: one per target
    /// tile, at most [`WriterPlan::max_cells`].
    pub fn cells_for(&self, expected_photons: u64) -> usize {
        expected_photons
            .div_ceil(self.target_tile_photons as u64)
            .clamp(1, self.max_cells) as usize
    }
}

/// Records per buffer chunk for `cells` cells sharing `buffer_bytes`: at
/// least 8 chunks per cell fit in the buffers, so spills are sizeable, and
/// no cell holds much unused capacity: with 10^5 cells (10^9 photons)
/// chunks of 256 records filled the buffers with mostly empty chunks, and
/// spills wrote frames of a few dozen photons.
fn chunk_records(buffer_bytes: u64, cells: u64) -> usize {
    ((buffer_bytes / cells.max(1) / 8) as usize / STAGED).clamp(32, 4096)
}

#[cfg(test)]
mod tests;
