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

use super::codec::{StagedPhoton, ZSTD_LEVEL};
use crate::bounds::Aabb;
use crate::error::{Error, Result};
use crate::morton::{demorton3_wide, morton3_wide};
use crate::output::direct::{read_blocks, Blocks};
use crate::photon::{PackedPhoton, LAYERS};
use std::fs::File;
use std::path::{Path, PathBuf};

/// Most photons in one spilled frame: bounds the sort keys and frame
/// buffers (about 1 MiB together) and still sorts runs long enough that
/// their deltas are small.
pub const FRAME_PHOTONS: usize = 8192;

/// Grid coordinates must stay below this in magnitude (about 2^18 times the
/// map's largest coordinate), so a frame's offsets fit the 42 bits per axis
/// of its Morton codes.
const GRID_LIMIT: i64 = 1 << 41;

/// A plane's length field when it is stored uncompressed.
const RAW_PLANE: u16 = u16::MAX;
const _: () = assert!(FRAME_PHOTONS < RAW_PLANE as usize);

/// Frames of fewer photons than this store their planes as one zstd frame
/// (mode 1) rather than one each (mode 0).
const JOINED_BELOW: usize = 1024;

/// The length field of joined planes stored uncompressed.
const RAW_JOINED: u32 = u32::MAX;

/// Bytes of a record besides its Morton delta.
const PAYLOAD_BYTES: usize = 11;

/// The most a scratch frame takes: its link, body head, the length field
/// of each plane and the planes of [`FRAME_PHOTONS`] photons at the widest
/// delta.
pub const MAX_FRAME_BYTES: usize =
    FRAME_LINK + BODY_HEAD + (16 + PAYLOAD_BYTES) * (2 + FRAME_PHOTONS);

/// Per axis, the fixed-point grid photon positions are snapped to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SnapGrid {
    /// Grid spacing per axis, a power of two.
    step: [f64; 3],
    /// Its reciprocal (exact: a power of two), to divide by multiplying.
    per_m: [f64; 3],
    /// The map bounds it was made for (named in errors).
    bounds: Aabb,
}

impl SnapGrid {
    /// The grid of a map with `bounds`: per axis, the f32 spacing at the
    /// axis's largest coordinate magnitude (at least 2^-40).
    pub fn new(bounds: &Aabb) -> SnapGrid {
        let step = |axis: usize| {
            let m = bounds.min[axis].abs().max(bounds.max[axis].abs());
            let m = if m.is_finite() && m > 0.0 { m } else { 1.0 };
            // 2^exponent(m), then 23 bits below it: the f32 spacing at m.
            let binade = f32::from_bits(m.to_bits() & 0x7f80_0000) as f64;
            (binade * (-23f64).exp2()).max((-40f64).exp2())
        };
        let step = [step(0), step(1), step(2)];
        SnapGrid {
            step,
            per_m: step.map(|s| 1.0 / s),
            bounds: *bounds,
        }
    }

    /// Grid spacing (m) on each axis.
    pub fn step(&self) -> [f64; 3] {
        self.step
    }

    /// The grid coordinates of `position`, or `None` outside the grid's range.
    #[inline]
    pub fn index(&self, position: [f32; 3]) -> Option<[i64; 3]> {
        let mut out = [0i64; 3];
        for axis in 0..3 {
            let i = (position[axis] as f64 * self.per_m[axis]).round();
            if i.is_nan() || i.abs() >= GRID_LIMIT as f64 {
                return None;
            }
            out[axis] = i as i64;
        }
        Some(out)
    }

    /// The position of grid coordinates `i` (exact: every grid point in
    /// range is an f32).
    #[inline]
    pub fn position(&self, i: [i64; 3]) -> [f32; 3] {
        [
            (i[0] as f64 * self.step[0]) as f32,
            (i[1] as f64 * self.step[1]) as f32,
            (i[2] as f64 * self.step[2]) as f32,
        ]
    }

    /// `p` snapped to the grid, or the error for a photon outside its range.
    pub fn snapped(&self, p: &StagedPhoton) -> Result<StagedPhoton> {
        let mut p = *p;
        if self.snap(&mut p) {
            return Ok(p);
        }
        Err(self.outside(&p))
    }

    /// The error for a photon [`SnapGrid::snap`] refused.
    pub fn outside(&self, p: &StagedPhoton) -> Error {
        Error::invalid(
            "photon position",
            format!(
                "{:?} is not finite or lies far outside the map's bounds {:?}",
                p.photon.position, self.bounds
            ),
        )
    }

    /// Snap `p` to the grid in place; false if it lies outside the grid's range.
    #[inline]
    pub fn snap(&self, p: &mut StagedPhoton) -> bool {
        match self.index(p.photon.position) {
            Some(i) => {
                p.photon.position = self.position(i);
                true
            }
            None => false,
        }
    }
}

/// Encodes and decodes frame bodies: at most [`FRAME_PHOTONS`] staged
/// photons, snapped to the grid, as sorted grid deltas and byte planes.
///
/// A body is: delta width u8, the plane mode u8, the corner (3 × i64
/// grid units), the CRC-32 of the rest of the body, then the `width + 11`
/// byte planes of the records (Morton delta, octahedral direction 2 ×
/// u16, band and group u16, power f32 bits, layer u8). In mode 0 each
/// plane is its length as u16 (`RAW_PLANE` for raw bytes) and its bytes;
/// in mode 1 (frames of fewer than `JOINED_BELOW` photons) all planes
/// are one zstd frame, its length as u32 (`RAW_JOINED` for raw bytes)
/// first. The photon count is kept by the container (the scratch file's
/// links, a shard's frame header).
pub struct FrameCodec {
    grid: SnapGrid,
    compressor: zstd::bulk::Compressor<'static>,
    decompressor: zstd::bulk::Decompressor<'static>,
    /// The batch's grid coordinates, then its sort keys.
    cells: Vec<[i64; 3]>,
    keys: Vec<(u128, u32)>,
    /// The radix sort's second buffer.
    spare_keys: Vec<(u128, u32)>,
    planes: Vec<u8>,
    packed: Vec<u8>,
}

/// Bytes of a body before its planes.
const BODY_HEAD: usize = 2 + 24 + 4;

impl FrameCodec {
    /// A codec for photons snapped to `grid`.
    pub fn new(grid: SnapGrid) -> std::io::Result<FrameCodec> {
        Ok(FrameCodec {
            grid,
            compressor: zstd::bulk::Compressor::new(ZSTD_LEVEL)?,
            decompressor: zstd::bulk::Decompressor::new()?,
            cells: Vec::new(),
            keys: Vec::new(),
            spare_keys: Vec::new(),
            planes: Vec::new(),
            packed: Vec::new(),
        })
    }

    /// The grid photons must be snapped to before they are encoded.
    pub fn grid(&self) -> SnapGrid {
        self.grid
    }

    /// Append the body of `batch` (1 to [`FRAME_PHOTONS`] photons, snapped
    /// to the grid) to `out`.
    pub fn encode(&mut self, batch: &[StagedPhoton], out: &mut Vec<u8>) -> std::io::Result<()> {
        self.encode_as(batch, batch.len() < JOINED_BELOW, out)
    }

    /// [`Self::encode`] with the planes stored together (`joined`) or one
    /// zstd frame each.
    fn encode_as(
        &mut self,
        batch: &[StagedPhoton],
        joined: bool,
        out: &mut Vec<u8>,
    ) -> std::io::Result<()> {
        let n = batch.len();
        assert!((1..=FRAME_PHOTONS).contains(&n), "frame of {n} photons");
        let grid = self.grid;
        self.cells.clear();
        self.cells.extend(batch.iter().map(|p| {
            grid.index(p.photon.position)
                .expect("photons are snapped inside the grid's range before they are encoded")
        }));
        let mut corner = [i64::MAX; 3];
        for i in &self.cells {
            for a in 0..3 {
                corner[a] = corner[a].min(i[a]);
            }
        }
        self.keys.clear();
        self.keys
            .extend(self.cells.iter().enumerate().map(|(k, i)| {
                let u = [
                    (i[0] - corner[0]) as u64,
                    (i[1] - corner[1]) as u64,
                    (i[2] - corner[2]) as u64,
                ];
                (morton3_wide(u), k as u32)
            }));
        // Stable by code from index order: the order of (code, index).
        let bits = 128 - self.keys.iter().fold(0u128, |a, k| a | k.0).leading_zeros();
        super::radix::sort_by_low_bits(&mut self.keys, &mut self.spare_keys, bits, |k| k.0);
        let mut widest = 0u128;
        let mut prev_code = 0u128;
        for &(code, _) in &self.keys {
            widest |= code - prev_code;
            prev_code = code;
        }
        let width = (16 - widest.leading_zeros() as usize / 8).max(1);

        self.planes.clear();
        self.planes.resize(n * (width + PAYLOAD_BYTES), 0);
        let mut prev_code = 0u128;
        for (j, &(code, k)) in self.keys.iter().enumerate() {
            let p = &batch[k as usize].photon;
            let delta = (code - prev_code).to_le_bytes();
            prev_code = code;
            for (b, &byte) in delta[..width].iter().enumerate() {
                self.planes[b * n + j] = byte;
            }
            let mut payload = [0u8; PAYLOAD_BYTES];
            payload[0..2].copy_from_slice(&p.oct[0].to_le_bytes());
            payload[2..4].copy_from_slice(&p.oct[1].to_le_bytes());
            payload[4..6].copy_from_slice(&p.band_group.to_le_bytes());
            payload[6..10].copy_from_slice(&p.power.to_le_bytes());
            payload[10] = p.layer as u8;
            for (b, &byte) in payload.iter().enumerate() {
                self.planes[(width + b) * n + j] = byte;
            }
        }

        let start = out.len();
        out.push(width as u8);
        out.push(joined as u8);
        for c in corner {
            out.extend_from_slice(&c.to_le_bytes());
        }
        out.extend_from_slice(&[0; 4]);
        self.packed.clear();
        if joined {
            let all = self.planes.len();
            self.packed.reserve(zstd::zstd_safe::compress_bound(all));
            let packed = self
                .compressor
                .compress_to_buffer(&self.planes[..], &mut self.packed)?;
            if packed < all {
                out.extend_from_slice(&(packed as u32).to_le_bytes());
                out.extend_from_slice(&self.packed);
            } else {
                out.extend_from_slice(&RAW_JOINED.to_le_bytes());
                out.extend_from_slice(&self.planes);
            }
        } else {
            self.packed.reserve(zstd::zstd_safe::compress_bound(n));
            for plane in self.planes.chunks_exact(n) {
                let packed = self
                    .compressor
                    .compress_to_buffer(plane, &mut self.packed)?;
                if packed < n {
                    out.extend_from_slice(&(packed as u16).to_le_bytes());
                    out.extend_from_slice(&self.packed);
                } else {
                    out.extend_from_slice(&RAW_PLANE.to_le_bytes());
                    out.extend_from_slice(plane);
                }
            }
        }
        let crc = body_crc(&out[start..]);
        out[start + BODY_HEAD - 4..start + BODY_HEAD].copy_from_slice(&crc.to_le_bytes());
        Ok(())
    }

    /// Decode the body of `n` photons in `body` into `out` (cleared first);
    /// a damaged body is an error saying what is wrong, never a panic.
    pub fn decode(
        &mut self,
        body: &[u8],
        n: usize,
        out: &mut Vec<StagedPhoton>,
    ) -> std::result::Result<(), String> {
        if body.len() < BODY_HEAD || !(1..=FRAME_PHOTONS).contains(&n) {
            return Err(format!("frame too short or of {n} photons"));
        }
        let word = |at: usize| i64::from_le_bytes(body[at..at + 8].try_into().unwrap());
        let width = body[0] as usize;
        let corner = [word(2), word(10), word(18)];
        let crc = u32::from_le_bytes(body[26..30].try_into().unwrap());
        if crc != body_crc(body) {
            return Err("frame checksum mismatch".into());
        }
        if !(1..=16).contains(&width) {
            return Err(format!("frame delta width {width}"));
        }
        self.planes.clear();
        self.planes.resize(n * (width + PAYLOAD_BYTES), 0);
        let stored = &body[BODY_HEAD..];
        match body[1] {
            0 => unpack_planes(&mut self.decompressor, stored, &mut self.planes, n)?,
            1 => unpack_joined(&mut self.decompressor, stored, &mut self.planes)?,
            mode => return Err(format!("frame of plane mode {mode}")),
        }
        out.clear();
        out.reserve(n);
        let planes = &self.planes;
        let byte = |b: usize, j: usize| planes[b * n + j];
        let mut code = 0u128;
        for j in 0..n {
            let mut delta = [0u8; 16];
            for (b, d) in delta[..width].iter_mut().enumerate() {
                *d = byte(b, j);
            }
            code = code.wrapping_add(u128::from_le_bytes(delta));
            let u = demorton3_wide(code);
            let i = [
                corner[0].wrapping_add(u[0] as i64),
                corner[1].wrapping_add(u[1] as i64),
                corner[2].wrapping_add(u[2] as i64),
            ];
            let at = |b: usize| byte(width + b, j);
            let layer = at(10) as u16;
            if layer as usize >= LAYERS {
                return Err(format!("photon of layer {layer}"));
            }
            out.push(StagedPhoton {
                photon: PackedPhoton {
                    position: self.grid.position(i),
                    oct: [
                        u16::from_le_bytes([at(0), at(1)]),
                        u16::from_le_bytes([at(2), at(3)]),
                    ],
                    band_group: u16::from_le_bytes([at(4), at(5)]),
                    layer,
                    power: f32::from_le_bytes([at(6), at(7), at(8), at(9)]),
                },
            });
        }
        Ok(())
    }
}

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

/// CRC-32 of a body but for its CRC field.
fn body_crc(body: &[u8]) -> u32 {
    let mut h = crc32fast::Hasher::new();
    h.update(&body[..BODY_HEAD - 4]);
    h.update(&body[BODY_HEAD..]);
    h.finalize()
}

/// Fill `planes` (`n` bytes each) from a body's stored planes.
fn unpack_planes(
    decompressor: &mut zstd::bulk::Decompressor<'static>,
    stored: &[u8],
    planes: &mut [u8],
    n: usize,
) -> std::result::Result<(), String> {
    let mut at = 0;
    for plane in planes.chunks_exact_mut(n) {
        let short = || "frame length".to_string();
        let len = stored.get(at..at + 2).ok_or_else(short)?;
        let len = u16::from_le_bytes([len[0], len[1]]);
        at += 2;
        let size = if len == RAW_PLANE { n } else { len as usize };
        let bytes = stored.get(at..at + size).ok_or_else(short)?;
        at += size;
        if len == RAW_PLANE {
            plane.copy_from_slice(bytes);
        } else {
            let got = decompressor
                .decompress_to_buffer(bytes, plane)
                .map_err(|e| format!("frame plane: {e}"))?;
            if got != n {
                return Err(short());
            }
        }
    }
    if at != stored.len() {
        return Err("frame length".to_string());
    }
    Ok(())
}

/// Fill `planes` from a body whose planes are stored together.
fn unpack_joined(
    decompressor: &mut zstd::bulk::Decompressor<'static>,
    stored: &[u8],
    planes: &mut [u8],
) -> std::result::Result<(), String> {
    let short = || "frame length".to_string();
    let len = stored.get(..4).ok_or_else(short)?;
    let len = u32::from_le_bytes([len[0], len[1], len[2], len[3]]);
    let bytes = &stored[4..];
    if len == RAW_JOINED {
        if bytes.len() != planes.len() {
            return Err(short());
        }
        planes.copy_from_slice(bytes);
        return Ok(());
    }
    if bytes.len() != len as usize {
        return Err(short());
    }
    let got = decompressor
        .decompress_to_buffer(bytes, planes)
        .map_err(|e| format!("frame planes: {e}"))?;
    if got != planes.len() {
        return Err(short());
    }
    Ok(())
}

#[cfg(test)]
mod tests;
