//! The last phase of the map writer: cells handed to encoder threads and
//! their tiles appended to the map in cell order (see `writer`).

use super::MapWriter;
use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::store::codec::{EncodedTile, StagedPhoton};
use crate::store::format::TileEntry;
use crate::store::spill::{Fetched, Frame};
use std::path::Path;

/// A tile from an encoder thread: its index and the encoding.
pub(super) type Encoded = (u32, Result<EncodedTile>);

/// A cell for an encoder thread: its tile index, photon count, spilled
/// frames (read by a fetcher thread, not yet decoded; `None` if it never
/// spilled) and buffered chunks.
pub(super) struct Job {
    pub(super) index: u32,
    pub(super) count: usize,
    pub(super) frames: Option<Fetched>,
    pub(super) chunks: Vec<Vec<StagedPhoton>>,
}

/// A cell for a fetcher thread: its job, the newest of its spilled frames,
/// which the fetcher reads back from, and the bytes they are expected to
/// take (`FETCH_BYTES_PER_PHOTON` each).
pub(super) type Fetch = (Job, Frame, usize);

/// The cells handed to the fetcher and encoder threads, and their tiles
/// put back in order.
pub(super) struct TileQueue {
    /// Cells in flight at most (being read or encoded).
    pub(super) width: usize,
    pub(super) done: crossbeam_channel::Receiver<Encoded>,
    /// Tiles sent to the encoders, and results received.
    pub(super) sent: u32,
    pub(super) received: u32,
    /// Results that arrived before an earlier tile's.
    pub(super) waiting: std::collections::BTreeMap<u32, Result<EncodedTile>>,
    pub(super) entries: Vec<TileEntry>,
    /// Bytes charged to the fetch share for spilled cells in flight, in
    /// all and by tile index: their frames until encoded, then their tiles
    /// until appended.
    pub(super) fetch_bytes: u64,
    pub(super) fetching: std::collections::BTreeMap<u32, u64>,
}

impl TileQueue {
    /// Wait for one encoded tile, then append every tile now next in order.
    pub(super) fn receive(
        &mut self,
        writer: &mut MapWriter,
        progress: &dyn Progress,
    ) -> Result<()> {
        let (index, tile) = self.done.recv().map_err(|_| self.stopped(&writer.path))?;
        self.received += 1;
        // A spilled cell's frames are decoded now; its tile may wait for
        // the ones before it, charged at its own size until appended.
        if let Some(frames) = self.fetching.remove(&index) {
            self.fetch_bytes -= frames;
            if let Ok(t) = &tile {
                let blob = t.blob.len() as u64;
                self.fetch_bytes += blob;
                self.fetching.insert(index, blob);
            }
        }
        self.waiting.insert(index, tile);
        while let Some(tile) = self.waiting.remove(&(self.entries.len() as u32)) {
            let index = self.entries.len() as u32;
            self.fetch_bytes -= self.fetching.remove(&index).unwrap_or(0);
            let tile = tile?;
            writer.append(&tile, &mut self.entries)?;
            progress.advance(tile.count as u64);
            crate::progress::check(progress)?;
        }
        Ok(())
    }

    /// The error when the encoder threads stopped early.
    pub(super) fn stopped(&self, path: &Path) -> Error {
        Error::tile(path, self.received, "the tile encoder threads stopped")
    }
}
