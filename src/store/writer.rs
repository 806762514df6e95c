//! The streaming tile sort: photons in any order in, one map file out,
//! within a memory budget.
//!
//! Photons are routed by layer (volume, surface) and by the cells of a pilot
//! [`Partition`] (shared by the layers) and appended to
//! per-cell buffers made of fixed-size chunks (so growth never copies). When
//! buffered bytes pass the budget's share, the largest buffers are spilled
//! to an anonymous scratch file next to the output, as sorted, delta-coded
//! frames (`spill`), by a thread of their own: routing goes on meanwhile
//! into the encode share, which nothing uses before the tiles are encoded,
//! and waits only if that fills too (on two cores this kept them 1.8
//! rather than 1.6 busy). Each frame starts with a reference to the previous
//! frame of its cell, so memory holds one reference per cell however much
//! was spilled. At the end each cell is read back (frames, then what is
//! still buffered; the frames read by fetcher threads, several cells at
//! once, since each cell's frames are a chain of reads that wait on the
//! disk), encoded by the tile codec and appended to the map; a
//! cell holding more than the split threshold is first split in two at the
//! median of an order-independent sample, streaming, so no tile ever needs
//! more memory than its share.
//!
//! Every photon is snapped to the map's grid as it arrives (`SnapGrid`: the
//! f32 spacing at the edge of the map's bounds), so the scratch file stores
//! exactly what memory holds. Nothing depends on the order photons arrive
//! in: split planes come from samples chosen by a hash of the record, and
//! the codec sorts each tile by Morton code and then by the record itself.
//! Hence a map is a function of the multiset of photons, byte-identical for
//! any number of producer threads.
//!
//! Not for: reading maps (see `reader`), or choosing which photons to store.

use super::codec::{EncodedTile, StagedPhoton, TileEncoder};
use super::format::{ByteWriter, Footer, Header, Section, TileEntry, FORMAT_VERSION};
use super::partition::Partition;
use super::spill::{Fetched, Frame, Scratch, SnapGrid};
use crate::bounds::Aabb;
use crate::error::{Error, Result};
use crate::photon::LAYERS;
use crate::progress::Progress;
use crate::provenance::Provenance;
use crate::spectral::BandGrid;
use std::io::{Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

mod plan;
mod spiller;
mod split;
mod tiles;
pub use plan::{
    WriterPlan, DEFAULT_TILE_PHOTONS, EXTRA_ENCODER_BYTES, FETCH_BUFFER_BYTES,
    FETCH_BYTES_PER_PHOTON, MAX_FETCHERS, MIN_FETCHERS, MIN_WRITER_BUDGET, WRITER_FIXED_BYTES,
};
use spiller::{Collected, SpillJob, Spiller};
use tiles::{Encoded, Fetch, Job, TileQueue};

const MIB: u64 = 1 << 20;

/// Photons routed to their cells together (see [`Partition::cells_of`]).
const ROUTE_BLOCK: usize = 64;
const STAGED: usize = std::mem::size_of::<StagedPhoton>();

/// Cells in flight at the end, per fetcher and encoder thread. Tiles are
/// appended in cell order, so the oldest cell in flight holds back the
/// rest; a cell whose chain of spilled frames is long (hundreds of reads
/// at 10^9 photons) would otherwise stop the dispatch of further cells
/// while the fetchers idle. What cells in flight hold is bounded apart:
/// their fetched frames and finished tiles by the fetch share, their
/// buffered chunks by the buffer share they came from.
const CELLS_IN_FLIGHT_PER_THREAD: usize = 4;

/// What a finished map holds and what writing it took.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct WriteSummary {
    pub photons: u64,
    pub tiles: u32,
    pub file_bytes: u64,
    /// zstd frames written to the scratch file (0 when everything fit).
    pub spilled_frames: u64,
    /// Bytes appended to the scratch file: compressed frames, and the
    /// padding that makes a frame readable from a whole block.
    pub spilled_bytes: u64,
    /// Cells split at the end because they overflowed.
    pub splits: u32,
    /// Largest number of buffered bytes at any time.
    pub peak_buffered_bytes: u64,
}

#[derive(Debug)]
struct CellBuf {
    chunks: Vec<Vec<StagedPhoton>>,
    /// The newest spilled frame; each frame links to the one before.
    last_frame: Option<Frame>,
    count: u64,
    bounds: Aabb,
}

impl CellBuf {
    /// Append a photon; true when that took a new chunk of `chunk_records`.
    fn push(&mut self, p: &StagedPhoton, chunk_records: usize) -> bool {
        self.count += 1;
        self.bounds.grow(p.pos());
        match self.chunks.last_mut() {
            Some(c) if c.len() < c.capacity() => {
                c.push(*p);
                false
            }
            _ => {
                let mut c = Vec::with_capacity(chunk_records);
                c.push(*p);
                self.chunks.push(c);
                true
            }
        }
    }

    /// What this cell's spilled photons are charged in the fetch share
    /// when read back, at [`FETCH_BYTES_PER_PHOTON`].
    fn fetch_bytes(&self) -> u64 {
        let buffered: usize = self.chunks.iter().map(Vec::len).sum();
        (self.count - buffered as u64) * FETCH_BYTES_PER_PHOTON
    }

    fn new() -> Self {
        CellBuf {
            chunks: Vec::new(),
            last_frame: None,
            count: 0,
            bounds: Aabb::EMPTY,
        }
    }
}

impl CellBuf {
    /// Spill every buffered photon of this cell to `scratch` and free the
    /// chunks; returns the buffer bytes freed.
    fn spill(&mut self, scratch: &mut Scratch) -> Result<u64> {
        self.last_frame = scratch.spill(self.chunks.iter().flatten(), self.last_frame)?;
        let freed = self
            .chunks
            .drain(..)
            .map(|c| (c.capacity() * STAGED) as u64)
            .sum();
        Ok(freed)
    }
}

/// Writes one map file from photons pushed in any order.
pub struct MapWriter {
    path: PathBuf,
    plan: WriterPlan,
    partition: Partition,
    header: Header,
    header_len: u64,
    out: crate::output::StreamOut,
    offset: u64,
    cells: Vec<CellBuf>,
    buffered: u64,
    /// The scratch file, when no spill thread holds it.
    scratch: Option<Scratch>,
    /// The spill thread, once the buffers first filled.
    spiller: Option<Spiller>,
    /// The scratch file's grid, kept here while a spill thread holds it.
    grid: SnapGrid,
    summary: WriteSummary,
}

impl MapWriter {
    /// Start a map at `path` (written under a temporary name beside it).
    pub fn create(
        path: &Path,
        plan: WriterPlan,
        partition: Partition,
        bands: BandGrid,
        bounds: Aabb,
        provenance: Provenance,
    ) -> Result<Self> {
        let dir = crate::output::parent_dir(path).to_path_buf();
        let tmp = crate::output::temp_beside(path)?;
        let scratch_name = PathBuf::from(format!(
            "{} (scratch space in {})",
            path.display(),
            dir.display()
        ));
        let scratch_file =
            tempfile::tempfile_in(&dir).map_err(|e| Error::io(&scratch_name, "create", e))?;
        let header = Header {
            photons: 0,
            tiles: 0,
            bands,
            bounds,
            partition: partition.nodes().to_vec(),
            provenance,
            metadata: Section::default(),
        };
        let bytes = header.encode();
        let mut out = crate::output::StreamOut::new(tmp);
        out.write_all(&bytes)
            .map_err(|e| Error::io(path, "write", e))?;
        let cells = (0..partition.cells() as usize * LAYERS)
            .map(|_| CellBuf::new())
            .collect();
        Ok(MapWriter {
            path: path.to_path_buf(),
            plan,
            partition,
            header,
            header_len: bytes.len() as u64,
            out,
            offset: bytes.len() as u64,
            cells,
            buffered: 0,
            scratch: Some(Scratch::new(
                scratch_file,
                scratch_name,
                SnapGrid::new(&bounds),
            )?),
            spiller: None,
            grid: SnapGrid::new(&bounds),
            summary: WriteSummary::default(),
        })
    }

    /// Add photons. Each is first snapped to the map's grid (see
    /// [`SnapGrid`]), so the map holds the same positions whether or not a
    /// photon passed through the scratch file.
    pub fn push(&mut self, photons: &[StagedPhoton]) -> Result<()> {
        if let Some(p) = photons.iter().find(|p| p.photon.layer as usize >= LAYERS) {
            return Err(Error::invalid(
                "photon layer",
                format!(
                    "a photon at {:?} has layer {}",
                    p.photon.position, p.photon.layer
                ),
            ));
        }
        let chunk_bytes = (self.plan.chunk_records * STAGED) as u64;
        let grid = self.grid;
        let cells = self.partition.cells() as usize;
        let mut snapped: [StagedPhoton; ROUTE_BLOCK] = bytemuck::Zeroable::zeroed();
        let mut positions = [glam::Vec3::ZERO; ROUTE_BLOCK];
        let mut cell = [0u32; ROUTE_BLOCK];
        for block in photons.chunks(ROUTE_BLOCK) {
            let n = block.len();
            for ((p, s), pos) in block.iter().zip(&mut snapped).zip(&mut positions) {
                *s = *p;
                if !grid.snap(s) {
                    return Err(grid.outside(s));
                }
                *pos = s.pos();
            }
            // The cells of the whole block at once (in lockstep), then the
            // three lines each push reads or writes in turn (the cell, its
            // newest chunk's header, the chunk's next slot), each asked for
            // a block ahead: each is a cache miss, which would otherwise be
            // waited out one after another for every photon.
            self.partition.cells_of(&positions[..n], &mut cell[..n]);
            for (p, c) in snapped[..n].iter().zip(&mut cell[..n]) {
                *c += p.photon.layer as u32 * cells as u32;
                crate::simd::prefetch(&self.cells[*c as usize]);
            }
            for &c in &cell[..n] {
                let chunks = &self.cells[c as usize].chunks;
                crate::simd::prefetch(chunks.as_ptr().wrapping_add(chunks.len().saturating_sub(1)));
            }
            for &c in &cell[..n] {
                if let Some(chunk) = self.cells[c as usize].chunks.last() {
                    crate::simd::prefetch(chunk.as_ptr().wrapping_add(chunk.len()));
                }
            }
            for (p, &index) in snapped[..n].iter().zip(&cell[..n]) {
                if self.cells[index as usize].push(p, self.plan.chunk_records) {
                    self.buffered += chunk_bytes;
                }
                self.summary.photons += 1;
                // Past the buffer share, look at the spill thread every 64
                // photons (or at once when the headroom is used up too).
                if self.buffered > self.plan.buffer_bytes
                    && (self.summary.photons.is_multiple_of(64)
                        || self.buffered > self.routing_limit())
                {
                    self.make_room()?;
                }
            }
        }
        self.summary.peak_buffered_bytes = self.summary.peak_buffered_bytes.max(self.buffered);
        Ok(())
    }

    /// Buffered bytes routing may reach while a spill runs: the buffer
    /// share and the encode share, which nothing uses until the tiles are
    /// encoded (before that, [`Self::stop_spilling`] spills back down to
    /// the buffer share).
    fn routing_limit(&self) -> u64 {
        self.plan.budget.saturating_sub(WRITER_FIXED_BYTES)
    }

    /// Keep the buffers within their share, spilling on a thread of its
    /// own so that routing (and the producers behind it) go on meanwhile.
    /// Past the buffer share the fullest cells go to the spill thread
    /// ([`Self::fullest_cells`]); their bytes count as buffered until it
    /// has written them. Routing goes on into the encode share meanwhile,
    /// and waits only when that is used up too.
    fn make_room(&mut self) -> Result<()> {
        self.summary.peak_buffered_bytes = self.summary.peak_buffered_bytes.max(self.buffered);
        let full = self.buffered > self.routing_limit();
        if let Some(spiller) = &mut self.spiller {
            match spiller.collect(full) {
                Collected::Idle => {}
                Collected::Freed(freed) => self.buffered -= freed,
                Collected::Running => return Ok(()),
                Collected::Stopped => return Err(self.spill_failure()),
            }
        }
        if self.buffered <= self.plan.buffer_bytes {
            return Ok(());
        }
        let job = self.fullest_cells();
        if self.spiller.is_none() {
            let scratch = self
                .scratch
                .take()
                .expect("the scratch file is here while no spill thread runs");
            self.spiller = Some(Spiller::start(scratch, self.cells.len())?);
        }
        let spiller = self.spiller.as_mut().expect("started above");
        if !spiller.send(job) {
            return Err(self.spill_failure());
        }
        Ok(())
    }

    /// Take the chunks of the fullest cells until half the buffer share
    /// would be left: the most photons per frame, so the smallest deltas
    /// and the least overhead per photon. Their bytes stay counted as
    /// buffered until they are written.
    fn fullest_cells(&mut self) -> SpillJob {
        let held: Vec<usize> = self
            .cells
            .iter()
            .map(|c| c.chunks.iter().map(Vec::len).sum())
            .collect();
        let mut order: Vec<usize> = (0..self.cells.len()).filter(|&i| held[i] > 0).collect();
        order.sort_by_key(|&i| std::cmp::Reverse(held[i]));
        let mut job = Vec::new();
        let mut left = self.buffered;
        for i in order {
            if left <= self.plan.buffer_bytes / 2 {
                break;
            }
            let chunks = std::mem::take(&mut self.cells[i].chunks);
            left -= chunks
                .iter()
                .map(|c| (c.capacity() * STAGED) as u64)
                .sum::<u64>();
            job.push((i as u32, chunks));
        }
        job
    }

    /// The error that stopped the spill thread.
    fn spill_failure(&mut self) -> Error {
        let stopped = Error::io(
            &self.path,
            "spill",
            std::io::Error::other("the spill thread stopped"),
        );
        match self.spiller.take() {
            Some(spiller) => spiller.stop(&self.path).err().unwrap_or(stopped),
            None => stopped,
        }
    }

    /// Wait for the spill thread to finish and take the scratch file back,
    /// with each cell's newest frame.
    fn stop_spilling(&mut self) -> Result<()> {
        if let Some(spiller) = self.spiller.take() {
            let (scratch, newest, freed) = spiller.stop(&self.path)?;
            self.buffered -= freed;
            for (cell, frame) in self.cells.iter_mut().zip(newest) {
                cell.last_frame = frame;
            }
            self.scratch = Some(scratch);
        }
        // Back within the buffer share, so that the encode share is free
        // for the tiles.
        if self.buffered > self.plan.buffer_bytes {
            self.summary.peak_buffered_bytes = self.summary.peak_buffered_bytes.max(self.buffered);
            for (cell, chunks) in self.fullest_cells() {
                let cell = &mut self.cells[cell as usize];
                cell.chunks = chunks;
                let scratch = self
                    .scratch
                    .as_mut()
                    .expect("the scratch file is back once spilling stopped");
                self.buffered -= cell.spill(scratch)?;
            }
        }
        Ok(())
    }

    /// The scratch file (once spilling stopped: [`Self::stop_spilling`]).
    fn scratch(&mut self) -> &mut Scratch {
        self.scratch
            .as_mut()
            .expect("the scratch file is back once spilling stopped")
    }

    /// Encode every cell, write `metadata` (e.g. the emission report), the
    /// index and footer, and publish the file under its final name. Cells
    /// are read back in order and encoded [`WriterPlan::encode_width`] at a
    /// time in parallel; tiles are written in the same order whatever the
    /// width, and a tile's bytes depend only on its photons.
    pub fn finish(mut self, metadata: &[u8], progress: &dyn Progress) -> Result<WriteSummary> {
        self.stop_spilling()?;
        progress.stage("encode tiles", self.summary.photons);
        let entries = self.encode_cells(progress)?;
        progress.finish();

        let io = |e| Error::io(&self.path, "write", e);
        self.header.metadata = Section {
            offset: self.offset,
            length: metadata.len() as u64,
            crc: crc32fast::hash(metadata),
        };
        self.out.write_all(metadata).map_err(io)?;
        self.offset += metadata.len() as u64;
        let mut index = ByteWriter::default();
        for e in &entries {
            e.encode(&mut index);
        }
        let footer = Footer {
            index_offset: self.offset,
            index_length: index.0.len() as u64,
            tiles: entries.len() as u32,
            index_crc: crc32fast::hash(&index.0),
            version: FORMAT_VERSION,
        };
        self.out.write_all(&index.0).map_err(io)?;
        self.out.write_all(&footer.encode()).map_err(io)?;
        let mut tmp = self.out.finish().map_err(io)?;
        self.header.photons = self.summary.photons;
        self.header.tiles = entries.len() as u32;
        let header = self.header.encode();
        debug_assert_eq!(header.len() as u64, self.header_len);
        tmp.seek(SeekFrom::Start(0)).map_err(io)?;
        tmp.write_all(&header).map_err(io)?;
        let file_bytes = self.offset + index.0.len() as u64 + super::format::FOOTER_LEN as u64;
        crate::output::publish(tmp, &self.path)?;
        self.summary.tiles = entries.len() as u32;
        self.summary.file_bytes = file_bytes;
        let scratch = self.scratch.as_ref().expect("spilling stopped");
        self.summary.spilled_frames = scratch.frames_written;
        self.summary.spilled_bytes = scratch.bytes();
        Ok(self.summary)
    }

    /// Read every cell back in order (splitting the overfull) and encode
    /// its tile on one of [`WriterPlan::encode_width`] encoder threads,
    /// appending the tiles to the map in cell order. A cell with spilled
    /// frames goes first to one of [`WriterPlan::fetchers`] threads, which
    /// reads them (undecoded, within [`WriterPlan::fetch_bytes`]); reading
    /// the next cells overlaps the encoding of the ones before them, and
    /// at most the width's tiles are being encoded at once.
    fn encode_cells(&mut self, progress: &dyn Progress) -> Result<Vec<TileEntry>> {
        let width = self.plan.encode_width();
        let fetch_threads = self.plan.fetchers();
        let (fetch_tx, fetch_rx) = crossbeam_channel::bounded::<Fetch>(fetch_threads);
        let (work_tx, work_rx) = crossbeam_channel::bounded::<Job>(width);
        let (done_tx, done_rx) = crossbeam_channel::unbounded::<Encoded>();
        let decoders = (0..width)
            .map(|_| self.scratch().decoder())
            .collect::<Result<Vec<_>>>()?;
        let fetchers = (0..fetch_threads)
            .map(|_| self.scratch().fetcher())
            .collect::<Result<Vec<_>>>()?;
        std::thread::scope(|scope| {
            // Fetchers read cells' frames, each cell a chain of reads that
            // wait on the disk (the scratch file is read around the page
            // cache), several cells at once, and pass them on undecoded.
            for mut fetcher in fetchers {
                let (rx, work, done) = (fetch_rx.clone(), work_tx.clone(), done_tx.clone());
                scope.spawn(move || {
                    for (mut job, newest, estimate) in rx {
                        let mut fetched = Fetched::with_capacity(estimate);
                        let sent = match fetcher.fetch(Some(newest), &mut fetched) {
                            Ok(()) => {
                                job.frames = Some(fetched);
                                work.send(job).is_ok()
                            }
                            Err(e) => done.send((job.index, Err(e))).is_ok(),
                        };
                        if !sent {
                            break;
                        }
                    }
                });
            }
            for mut decoder in decoders {
                let (rx, tx) = (work_rx.clone(), done_tx.clone());
                let path = self.path.clone();
                scope.spawn(move || {
                    let mut encoder = TileEncoder::default();
                    let mut staged: Vec<StagedPhoton> = Vec::new();
                    for mut job in rx {
                        staged.clear();
                        staged.reserve_exact(job.count);
                        let read = match job.frames.take() {
                            Some(fetched) => decoder.decode_fetched(&fetched, &mut staged),
                            None => Ok(()),
                        };
                        let tile = read.and_then(|()| {
                            for chunk in job.chunks {
                                staged.extend_from_slice(&chunk);
                            }
                            if staged.len() != job.count {
                                return Err(Error::tile(
                                    &path,
                                    job.index,
                                    format!(
                                        "read {} photons of a cell holding {} from the scratch file",
                                        staged.len(),
                                        job.count
                                    ),
                                ));
                            }
                            encoder
                                .encode(&staged)
                                .map_err(|e| Error::tile(&path, job.index, e.to_string()))
                        });
                        if tx.send((job.index, tile)).is_err() {
                            break;
                        }
                    }
                });
            }
            drop((fetch_rx, work_rx, done_tx));
            let mut tiles = TileQueue {
                width: CELLS_IN_FLIGHT_PER_THREAD * (width + fetch_threads),
                done: done_rx,
                sent: 0,
                received: 0,
                waiting: std::collections::BTreeMap::new(),
                entries: Vec::new(),
                fetch_bytes: 0,
                fetching: std::collections::BTreeMap::new(),
            };
            let read = self.read_cells(&mut tiles, &fetch_tx, &work_tx, progress);
            // Closing the queues ends the threads once they are done.
            drop((fetch_tx, work_tx));
            read?;
            while tiles.received < tiles.sent {
                tiles.receive(self, progress)?;
            }
            Ok(tiles.entries)
        })
    }

    /// The dispatching side of [`Self::encode_cells`]: cells in order,
    /// overfull ones split first, each handed with its buffered chunks to
    /// a fetcher thread (`fetch`) when it has spilled frames to read, or
    /// straight to an encoder thread (`work`).
    fn read_cells(
        &mut self,
        tiles: &mut TileQueue,
        fetch: &crossbeam_channel::Sender<Fetch>,
        work: &crossbeam_channel::Sender<Job>,
        progress: &dyn Progress,
    ) -> Result<()> {
        let mut frame_buf: Vec<StagedPhoton> = Vec::new();
        let fetch_share = self.plan.fetch_bytes();
        let cells = std::mem::take(&mut self.cells);
        for cell in cells {
            let mut stack = vec![cell];
            while let Some(mut cell) = stack.pop() {
                if cell.count == 0 {
                    continue;
                }
                if cell.count > self.plan.split_threshold as u64 {
                    // The split reads the cell twice: from one chain of
                    // reads held in the fetch share, when it fits there
                    // beside the cells in flight (waiting for them if need
                    // be), else from the scratch file each time.
                    let need = cell.fetch_bytes();
                    let fetched = if need > 0 && need <= fetch_share {
                        while tiles.fetch_bytes > 0 && tiles.fetch_bytes + need > fetch_share {
                            tiles.receive(self, progress)?;
                        }
                        let mut fetched = Fetched::with_capacity(need as usize);
                        self.scratch().fetch(cell.last_frame, &mut fetched)?;
                        Some(fetched)
                    } else {
                        None
                    };
                    let (left, right) = self.split(cell, fetched.as_ref(), &mut frame_buf)?;
                    self.summary.splits += 1;
                    stack.push(right);
                    stack.push(left);
                    continue;
                }
                // Room for one more cell in flight first, and for its
                // frames in the fetch share (or nothing else is read).
                let spilled = cell.fetch_bytes();
                let chunks = std::mem::take(&mut cell.chunks);
                // A tile counts until it is appended: one finished early
                // waits in order behind the cells still being read.
                while tiles.sent - tiles.entries.len() as u32 >= tiles.width as u32
                    || (tiles.fetch_bytes > 0 && tiles.fetch_bytes + spilled > fetch_share)
                {
                    tiles.receive(self, progress)?;
                }
                for chunk in &chunks {
                    self.buffered -= (chunk.capacity() * STAGED) as u64;
                }
                if spilled > 0 {
                    tiles.fetch_bytes += spilled;
                    tiles.fetching.insert(tiles.sent, spilled);
                }
                // The fetcher reads the frames through its own handle.
                self.scratch().readable(cell.last_frame)?;
                let job = Job {
                    index: tiles.sent,
                    count: cell.count as usize,
                    frames: None,
                    chunks,
                };
                let sent = match cell.last_frame.take() {
                    Some(newest) => fetch.send((job, newest, spilled as usize)).is_ok(),
                    None => work.send(job).is_ok(),
                };
                if !sent {
                    return Err(tiles.stopped(&self.path));
                }
                tiles.sent += 1;
            }
        }
        Ok(())
    }

    /// Append an encoded tile to the map.
    fn append(&mut self, tile: &EncodedTile, entries: &mut Vec<TileEntry>) -> Result<()> {
        self.out
            .write_all(&tile.blob)
            .map_err(|e| Error::io(&self.path, "write", e))?;
        entries.push(tile.entry(self.offset));
        self.offset += tile.blob.len() as u64;
        Ok(())
    }
}
