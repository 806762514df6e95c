//! Photons at rest between tracing and the map: the map writer's scratch
//! file (photons that did not fit in memory, kept until their tile is
//! encoded) and, through the same [`FrameCodec`], shard files.
//!
//! Positions are fixed point here. The writer snaps every photon it is
//! given to a [`SnapGrid`]: per axis, the multiples of the f32 spacing at
//! the largest coordinate magnitude of the map's bounds (61 µm across an
//! 800 m scene, 1.9 µm over 20 m of depth). Every multiple in range is an
//! f32, so snapping is idempotent and exact both ways, and it is finer
//! than the map's 16 bits per tile box unless a tile is under 65 536 steps
//! across (4 m at 61 µm). A frame holds each photon as its integer grid
//! coordinates relative to the frame's corner, sorted by their 126-bit
//! Morton code and stored as the difference from the previous code in as
//! few bytes as the frame needs, next to the direction, band, power and
//! layer. The records are byte-shuffled and each plane of like bytes is
//! compressed on its own: a zstd frame per plane gives each its own
//! entropy table (one table for all planes cost 10 % more), and planes of
//! noise, such as the low bytes of the deltas, are stored raw. Frames of
//! fewer than 1024 photons (at 10^9 photons under 256 MiB nearly all, a
//! few hundred photons each) compress all their planes as one zstd frame:
//! there a plane's own frame header and tables cost about what a shared
//! table loses, and a zstd call per plane, twenty a frame, kept the spill
//! thread half of one core busy.
//!
//! Why: full-precision positions in arrival order do not compress (their
//! low mantissa bits are noise), and at 10^9 photons under 256 MiB every
//! photon is spilled. Sorted grid deltas cost about 1.44 bits more than
//! log2(frame volume in grid steps / photons in the frame); the rest of a
//! record costs what the map's own record does. The map sorts 65 536
//! photons at 16 bits per tile axis, a frame a few thousand at the grid's
//! finer steps, so a spilled photon costs 1 to 4 bytes more than a
//! stored one: spill traffic is 1.1 to 1.4 times the map, not less.
//!
//! Scratch frame layout: the previous frame of the same cell (offset u64,
//! length u32, count u32; zeros for none), then a [`FrameCodec`] body.
//!
//! Not for: the map's tile format (`codec`), which quantises to the tile box.

use super::codec::StagedPhoton;
use crate::error::{Error, Result};
use crate::output::direct::{read_blocks, Blocks};
use std::fs::File;
use std::path::{Path, PathBuf};

mod frame;
mod snap;

pub use frame::{FrameCodec, FRAME_PHOTONS};
use frame::{BODY_HEAD, PAYLOAD_BYTES};
pub use snap::SnapGrid;

/// The most a scratch frame takes: its link, body head, the length field
/// of each plane and the planes of [`FRAME_PHOTONS`] photons at the widest
/// delta.
pub const MAX_FRAME_BYTES: usize =
    FRAME_LINK + BODY_HEAD + (16 + PAYLOAD_BYTES) * (2 + FRAME_PHOTONS);

/// Where a spilled frame lies in the scratch file.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    offset: u64,
    len: u32,
    pub count: u32,
}

/// Bytes before a scratch frame's body: its link to the previous frame.
const FRAME_LINK: usize = 16;

/// How much of the scratch file [`Scratch`] gathers in memory before a
/// write (256 KiB).
const SCRATCH_GATHER: usize = 1 << 18;

/// The scratch file of spilled frames: each a link to the previous frame
/// of the same cell (offset u64, length u32, count u32; zeros for none)
/// and a [`FrameCodec`] body. It is appended to around the page cache
/// where the system allows (`output::direct`), so frames are gathered and
/// written in whole blocks, and read back in whole blocks: at 10^9
/// photons every photon passes through it, and through the page cache each
/// of its pages would be a freshly allocated page (about a tenth of the
/// emission's time on two threads at 56 M photons).
pub struct Scratch {
    file: File,
    /// How errors name the (anonymous) scratch file.
    name: PathBuf,
    codec: FrameCodec,
    blocks: Blocks,
    pub frames_written: u64,
    batch: Vec<StagedPhoton>,
    frame: Vec<u8>,
}

impl Scratch {
    /// A scratch space in `file`, named `name` in errors, for photons on `grid`.
    pub fn new(file: File, name: PathBuf, grid: SnapGrid) -> Result<Scratch> {
        let codec = FrameCodec::new(grid).map_err(|e| Error::io(&name, "create", e))?;
        let blocks = Blocks::new(&file, SCRATCH_GATHER);
        Ok(Scratch {
            file,
            name,
            codec,
            blocks,
            frames_written: 0,
            batch: Vec::new(),
            frame: Vec::new(),
        })
    }

    /// The grid photons must be snapped to before they are spilled.
    pub fn grid(&self) -> SnapGrid {
        self.codec.grid()
    }

    fn err(&self, action: &'static str, e: std::io::Error) -> Error {
        Error::io(&self.name, action, e)
    }

    /// Bytes of the scratch file so far (frames, and the padding that
    /// makes [`Scratch::readable`]'s writes whole blocks).
    pub fn bytes(&self) -> u64 {
        self.blocks.written() + self.blocks.gathered().len() as u64
    }

    /// Make every frame up to and including `newest` readable from the
    /// file, by other handles too ([`Scratch::fetcher`]): frames still
    /// gathered in memory are written, padded to a whole block.
    pub fn readable(&mut self, newest: Option<Frame>) -> Result<()> {
        match newest {
            Some(f) if f.offset + f.len as u64 > self.blocks.written() => self
                .blocks
                .pad_and_drain(&self.file)
                .map_err(|e| self.err("write", e)),
            _ => Ok(()),
        }
    }

    /// Write `photons` (snapped to the grid) as frames of at most
    /// [`FRAME_PHOTONS`] after `last`, the newest frame of their cell;
    /// returns the new newest frame.
    pub fn spill<'a>(
        &mut self,
        photons: impl IntoIterator<Item = &'a StagedPhoton>,
        mut last: Option<Frame>,
    ) -> Result<Option<Frame>> {
        let mut batch = std::mem::take(&mut self.batch);
        batch.clear();
        for p in photons {
            batch.push(*p);
            if batch.len() == FRAME_PHOTONS {
                last = Some(self.write_frame(&batch, last)?);
                batch.clear();
            }
        }
        if !batch.is_empty() {
            last = Some(self.write_frame(&batch, last)?);
        }
        self.batch = batch;
        Ok(last)
    }

    fn write_frame(&mut self, batch: &[StagedPhoton], prev: Option<Frame>) -> Result<Frame> {
        let prev = prev.unwrap_or(Frame {
            offset: 0,
            len: 0,
            count: 0,
        });
        self.frame.clear();
        self.frame.extend_from_slice(&prev.offset.to_le_bytes());
        self.frame.extend_from_slice(&prev.len.to_le_bytes());
        self.frame.extend_from_slice(&prev.count.to_le_bytes());
        let encoded = self.codec.encode(batch, &mut self.frame);
        encoded.map_err(|e| self.err("compress spill", e))?;
        let written = Frame {
            offset: self.bytes(),
            len: self.frame.len() as u32,
            count: batch.len() as u32,
        };
        self.blocks
            .push(&self.file, &self.frame)
            .map_err(|e| self.err("write", e))?;
        self.frames_written += 1;
        Ok(written)
    }

    /// Read frame `f` back into `out` (cleared first); returns the frame
    /// before it in the same cell.
    pub fn read(&mut self, f: Frame, out: &mut Vec<StagedPhoton>) -> Result<Option<Frame>> {
        self.readable(Some(f))?;
        let (body, prev) = read_raw(&self.file, &self.name, &mut self.frame, f)?;
        decode_body(&mut self.codec, &self.name, body, f.count, out)?;
        Ok(prev)
    }

    /// Read every frame of a cell, from its newest frame back, into `out`
    /// undecoded: one chain of reads for a cell read more than once
    /// (decoded by [`Scratch::decode`]).
    pub fn fetch(&mut self, newest: Option<Frame>, out: &mut Fetched) -> Result<()> {
        self.readable(newest)?;
        fetch_chain(&self.file, &self.name, &mut self.frame, newest, out)
    }

    /// Decode one of [`Fetched::bodies`] (`count` photons) into `out`
    /// (cleared first).
    pub fn decode(&mut self, body: &[u8], count: u32, out: &mut Vec<StagedPhoton>) -> Result<()> {
        decode_body(&mut self.codec, &self.name, body, count, out)
    }

    /// Call `visit` with the records of every spilled frame of a cell,
    /// newest first, through the reusable buffer `buf`.
    pub fn for_each_frame(
        &mut self,
        mut next: Option<Frame>,
        buf: &mut Vec<StagedPhoton>,
        mut visit: impl FnMut(&[StagedPhoton]),
    ) -> Result<()> {
        while let Some(f) = next {
            next = self.read(f, buf)?;
            visit(buf);
        }
        Ok(())
    }

    /// A fetcher of this scratch file's frames for another thread (its
    /// own handle): frames made [`Scratch::readable`] can be read while
    /// more are appended. Its [`Fetched`] frames are decoded by a
    /// [`Scratch::decoder`].
    pub fn fetcher(&self) -> Result<ScratchFetcher> {
        let file = self.file.try_clone().map_err(|e| self.err("open", e))?;
        Ok(ScratchFetcher {
            file,
            name: self.name.clone(),
            frame: Vec::new(),
        })
    }

    /// A decoder of this scratch file's fetched frames for another thread.
    pub fn decoder(&self) -> Result<ScratchDecoder> {
        let codec = FrameCodec::new(self.grid()).map_err(|e| self.err("open", e))?;
        Ok(ScratchDecoder {
            name: self.name.clone(),
            codec,
            buf: Vec::new(),
        })
    }
}

/// Decodes the frames a [`ScratchFetcher`] read, on another thread.
pub struct ScratchDecoder {
    name: PathBuf,
    codec: FrameCodec,
    buf: Vec<StagedPhoton>,
}

/// Reads cells' frames from a [`Scratch`] on another thread without
/// decoding them: the part of reading a cell back that waits on the disk
/// (a chain of reads, each frame holding the link to the one before), so
/// that several cells can be read at once while others are decoded.
pub struct ScratchFetcher {
    file: File,
    name: PathBuf,
    frame: Vec<u8>,
}

impl ScratchFetcher {
    /// Read every frame of a cell, from its newest frame `next` back,
    /// into `out` (cleared first).
    pub fn fetch(&mut self, next: Option<Frame>, out: &mut Fetched) -> Result<()> {
        fetch_chain(&self.file, &self.name, &mut self.frame, next, out)
    }
}

/// Read every frame of a cell from `file` (named `name` in errors), from
/// its newest frame `next` back, through the buffer `frame`, into `out`
/// (cleared first), undecoded.
fn fetch_chain(
    file: &File,
    name: &Path,
    frame: &mut Vec<u8>,
    mut next: Option<Frame>,
    out: &mut Fetched,
) -> Result<()> {
    out.bytes.clear();
    out.frames.clear();
    while let Some(f) = next {
        let (body, prev) = read_raw(file, name, frame, f)?;
        out.bytes.extend_from_slice(body);
        out.frames.push((body.len() as u32, f.count));
        next = prev;
    }
    Ok(())
}

/// A cell's spilled frames as read from the scratch file, not yet decoded
/// ([`ScratchFetcher::fetch`]): their bodies end to end, and each one's
/// length and photon count.
#[derive(Debug, Default)]
pub struct Fetched {
    bytes: Vec<u8>,
    frames: Vec<(u32, u32)>,
}

impl Fetched {
    /// Room for `bytes` of frames, taken at once rather than by doubling
    /// (which could hold twice what the frames need).
    pub fn with_capacity(bytes: usize) -> Fetched {
        Fetched {
            bytes: Vec::with_capacity(bytes),
            frames: Vec::new(),
        }
    }

    /// Each frame's body and photon count, newest first.
    pub fn bodies(&self) -> impl Iterator<Item = (&[u8], u32)> {
        let mut at = 0;
        self.frames.iter().map(move |&(len, count)| {
            let body = &self.bytes[at..at + len as usize];
            at += len as usize;
            (body, count)
        })
    }
}

impl ScratchDecoder {
    /// Append the records of the frames `fetched` holds to `out`: the
    /// same records, in the same order, as [`Scratch::for_each_frame`]
    /// from the same newest frame.
    pub fn decode_fetched(&mut self, fetched: &Fetched, out: &mut Vec<StagedPhoton>) -> Result<()> {
        for (body, count) in fetched.bodies() {
            decode_body(&mut self.codec, &self.name, body, count, &mut self.buf)?;
            out.extend_from_slice(&self.buf);
        }
        Ok(())
    }
}

/// A damaged scratch frame, as an error naming the scratch file.
fn corrupt(name: &Path, what: &str) -> Error {
    Error::io(
        name,
        "read",
        std::io::Error::new(std::io::ErrorKind::InvalidData, what.to_string()),
    )
}

/// Read frame `f` of the scratch file `file` (named `name` in errors)
/// through the buffer `frame`: its body, and the frame before it in the
/// same cell.
fn read_raw<'b>(
    file: &File,
    name: &Path,
    frame: &'b mut Vec<u8>,
    f: Frame,
) -> Result<(&'b [u8], Option<Frame>)> {
    let frame = read_blocks(file, f.offset, f.len as usize, frame)
        .map_err(|e| Error::io(name, "read", e))?;
    if frame.len() < FRAME_LINK {
        return Err(corrupt(name, "spill frame too short"));
    }
    let link = &frame[..FRAME_LINK];
    let prev = Frame {
        offset: u64::from_le_bytes(link[0..8].try_into().unwrap()),
        len: u32::from_le_bytes(link[8..12].try_into().unwrap()),
        count: u32::from_le_bytes(link[12..16].try_into().unwrap()),
    };
    // The link is outside the body's CRC: a damaged one must not send a
    // read far afield (a huge buffer), into a loop (a link to this frame
    // or a later one) or quietly end the chain early.
    let no_link = prev.offset == 0 && prev.len == 0 && prev.count == 0;
    let sound = prev.count as usize <= FRAME_PHOTONS
        && prev.len as usize <= MAX_FRAME_BYTES
        && prev
            .offset
            .checked_add(prev.len as u64)
            .is_some_and(|end| end <= f.offset)
        && (prev.count > 0) == (prev.len > 0);
    if !no_link && !sound {
        return Err(corrupt(name, "spill frame link out of range"));
    }
    Ok((&frame[FRAME_LINK..], (prev.count > 0).then_some(prev)))
}

/// Decode the body of a scratch frame of `count` photons into `out`
/// (cleared first); damage is an error naming the scratch file `name`.
fn decode_body(
    codec: &mut FrameCodec,
    name: &Path,
    body: &[u8],
    count: u32,
    out: &mut Vec<StagedPhoton>,
) -> Result<()> {
    codec
        .decode(body, count as usize, out)
        .map_err(|e| corrupt(name, &format!("spill {e}")))
}

#[cfg(test)]
mod tests;
