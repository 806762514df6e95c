//! The last phase of the map writer: cells handed to encoder threads and
//! their tiles appended to the map in cell order (see `writer`).

use super::MapWriter;
use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::store::codec::{EncodedTile, StagedPhoton};
use crate::store::format::TileEntry;
use crate::store::spill::Frame;
use std::path::Path;

/// A tile from an encoder thread: its index, the encoding, and the photon
/// buffer back for reuse.
pub(super) type Encoded = (u32, Result<EncodedTile>, Vec<StagedPhoton>);

/// A cell for an encoder thread: its tile index, its newest spilled frame,
/// its buffered chunks, and a buffer (reserved for the cell's photons) to
/// gather them in.
pub(super) struct Job {
    pub(super) index: u32,
    pub(super) frames: Option<Frame>,
    pub(super) chunks: Vec<Vec<StagedPhoton>>,
    pub(super) staged: Vec<StagedPhoton>,
}

/// The tiles handed to the encoder threads, and their results put back in
/// order.
pub(super) struct TileQueue {
    pub(super) width: usize,
    pub(super) done: crossbeam_channel::Receiver<Encoded>,
    /// Tiles sent to the encoders, and results received.
    pub(super) sent: u32,
    pub(super) received: u32,
    /// Results that arrived before an earlier tile's.
    pub(super) waiting: std::collections::BTreeMap<u32, Result<EncodedTile>>,
    pub(super) entries: Vec<TileEntry>,
    /// Photon buffers to reuse.
    pub(super) spare: Vec<Vec<StagedPhoton>>,
}

impl TileQueue {
    /// Wait for one encoded tile, then append every tile now next in order.
    pub(super) fn receive(
        &mut self,
        writer: &mut MapWriter,
        progress: &dyn Progress,
    ) -> Result<()> {
        let (index, tile, staged) = self.done.recv().map_err(|_| self.stopped(&writer.path))?;
        self.received += 1;
        if staged.capacity() <= 4 * writer.plan.target_tile_photons as usize {
            self.spare.push(staged);
        }
        self.waiting.insert(index, tile);
        while let Some(tile) = self.waiting.remove(&(self.entries.len() as u32)) {
            let tile = tile?;
            writer.append(&tile, &mut self.entries)?;
            progress.advance(tile.count as u64);
        }
        Ok(())
    }

    /// The error when the encoder threads stopped early.
    pub(super) fn stopped(&self, path: &Path) -> Error {
        Error::tile(path, self.received, "the tile encoder threads stopped")
    }
}
