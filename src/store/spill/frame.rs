//! Frame bodies: sorted grid deltas of snapped photons, byte-shuffled
//! planes, each compressed on its own or all together (see `store::spill`).

use super::SnapGrid;
use crate::morton::{demorton3_wide, morton3_wide};
use crate::photon::{PackedPhoton, LAYERS};
use crate::store::codec::{StagedPhoton, ZSTD_LEVEL};

/// Most photons in one spilled frame: bounds the sort keys and frame
/// buffers (about 1 MiB together) and still sorts runs long enough that
/// their deltas are small.
pub const FRAME_PHOTONS: usize = 8192;

/// A plane's length field when it is stored uncompressed.
const RAW_PLANE: u16 = u16::MAX;
const _: () = assert!(FRAME_PHOTONS < RAW_PLANE as usize);

/// Frames of fewer photons than this store their planes as one zstd frame
/// (mode 1) rather than one each (mode 0).
pub(super) const JOINED_BELOW: usize = 1024;

/// The length field of joined planes stored uncompressed.
const RAW_JOINED: u32 = u32::MAX;

/// Bytes of a record besides its Morton delta.
pub(super) const PAYLOAD_BYTES: usize = 11;

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
pub(super) const BODY_HEAD: usize = 2 + 24 + 4;

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
    pub(super) fn encode_as(
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
        crate::store::radix::sort_by_low_bits(&mut self.keys, &mut self.spare_keys, bits, |k| k.0);
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

/// CRC-32 of a body but for its CRC field.
pub(super) fn body_crc(body: &[u8]) -> u32 {
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
