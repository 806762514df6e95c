//! Tile blob codec: sorted, quantised, byte-shuffled, zstd-compressed records.
//!
//! A tile's photons are quantised to 16 bits per axis inside the tile's box,
//! sorted by the Morton code of the quantised position (ties by the rest of
//! the staged record, so the order — and the blob — is a pure function of
//! the multiset of photons), and laid out as 16-byte records:
//!
//! | bytes | field |
//! |---|---|
//! | 0..6  | Morton code delta from the previous record (48 bits) |
//! | 6..10 | octahedral direction (2 x u16) |
//! | 10..12 | band index (low 12 bits) and photon group (high 4 bits), u16 |
//! | 12..16 | power (f32 bits) |
//!
//! The records are then byte-shuffled (byte k of every record forms plane k)
//! and each plane is compressed as its own zstd frame, or stored raw when
//! that is no smaller. Sorting makes the deltas small and the shuffle puts
//! their zero high bytes — and the few distinct band and power values —
//! into long runs that zstd removes; a frame per plane gives each plane its
//! own entropy table (zstd keeps one per block, and one frame for all 16
//! planes made the maps 10 % larger), and the noise planes (the low bytes
//! of the deltas and directions) decode as a copy.
//!
//! Blob layout (format 5): a u16 mask of the planes stored raw, the stored
//! length of each of the 16 planes (u32), then the planes in order.
//! Format 4 compressed all 16 planes as one zstd frame.

use super::format::TileEntry;
use crate::bounds::Aabb;
use crate::morton::{demorton3, morton3};
use crate::photon::{AxisQuantizer, PackedPhoton, Photon};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// Bytes per record before compression.
pub const RECORD_BYTES: usize = 16;

/// zstd level for tile blobs and spill runs: higher levels gain little on
/// MB-sized tiles of shuffled records and cost compression speed.
pub const ZSTD_LEVEL: i32 = 1;

/// A photon on its way from the emitter to the map: f32 position (snapped
/// by the map writer to the map's spill grid, see `spill::SnapGrid`),
/// encoded direction, band and group, layer and power. Nothing else: the
/// map is a function of the multiset of these records, whatever order or
/// thread they came from.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct StagedPhoton {
    pub photon: PackedPhoton,
}

const _: () = assert!(std::mem::size_of::<StagedPhoton>() == 24);

impl StagedPhoton {
    /// Stage a photon of `layer`.
    pub fn new(p: &Photon, layer: u16) -> Self {
        StagedPhoton {
            photon: PackedPhoton::pack(p, layer),
        }
    }

    #[inline]
    pub fn pos(&self) -> Vec3 {
        self.photon.pos()
    }

    /// The record as three words: a total order on records (position bits
    /// first) that tells apart any two that differ.
    #[inline]
    pub fn key(&self) -> [u64; 3] {
        bytemuck::cast(self.photon)
    }

    /// The record's fields other than position, as one sort key.
    #[inline]
    fn payload_key(&self) -> u64 {
        let p = &self.photon;
        (p.oct[0] as u64) << 48 | (p.oct[1] as u64) << 32 | p.power.to_bits() as u64
    }
}

/// A tile sort key: the 48-bit Morton code, then direction and power (64
/// bits), then band and group (16 bits), in one integer of 16 bytes (a
/// tuple of the three took 24), radix-sorted by its top 48 bits. It holds
/// the whole record, so records are written from the sorted keys without
/// going back to the photons (a random gather over a tile larger than the
/// cache); photons with equal keys have equal records, so their order does
/// not matter.
type EncodeKey = u128;

/// Bytes of working memory the encoder needs per photon (staged record, sort
/// key and the radix sort's copy of it, raw record, compressed output bound
/// and slack), used for budgeting merges.
pub const ENCODE_BYTES_PER_PHOTON: usize = std::mem::size_of::<StagedPhoton>()
    + 2 * std::mem::size_of::<EncodeKey>()
    + RECORD_BYTES
    + RECORD_BYTES
    + 16;

const MORTON_MASK: u64 = (1 << 48) - 1;

/// The records of the 16 photons from `base` on, out of the byte planes
/// of `raw` (plane `k` is `raw[k n..(k + 1) n]`): record `j`'s byte `k` is
/// `raw[k n + base + j]`, a 16 × 16 byte transpose
/// ([`crate::simd::transpose16`]: SSE2 unpacks on x86-64).
#[inline]
fn unshuffle16(raw: &[u8], n: usize, base: usize, out: &mut [[u8; RECORD_BYTES]]) {
    const _: () = assert!(RECORD_BYTES == 16);
    let out: &mut [[u8; 16]; 16] = out.try_into().expect("16 records");
    let rows: [&[u8; 16]; 16] = std::array::from_fn(|k| {
        raw[k * n + base..k * n + base + 16]
            .try_into()
            .expect("16 bytes")
    });
    crate::simd::transpose16(rows, out);
}

/// The records of the `out.len()` photons from `base` on, out of the byte
/// planes of `raw`, a byte at a time (what [`unshuffle16`] does for 16).
fn unshuffle(raw: &[u8], n: usize, base: usize, out: &mut [[u8; RECORD_BYTES]]) {
    let len = out.len();
    for (k, plane) in raw.chunks_exact(n).enumerate() {
        for (rec, &byte) in out.iter_mut().zip(&plane[base..base + len]) {
            rec[k] = byte;
        }
    }
}

/// The quantisers of a tile box, one per axis.
#[derive(Clone, Copy, Debug)]
pub struct BoxQuantizer([AxisQuantizer; 3]);

impl BoxQuantizer {
    /// Decoded value of code `q` on `axis` (what [`BoxQuantizer::decode`]
    /// gives for that axis).
    #[inline(always)]
    pub fn decode_axis(&self, axis: usize, q: u16) -> f32 {
        self.0[axis].decode(q)
    }

    /// Cell size on `axis` (m).
    pub fn step(&self, axis: usize) -> f32 {
        self.0[axis].step()
    }

    pub fn new(b: &Aabb) -> Self {
        BoxQuantizer([
            AxisQuantizer::new(b.min.x, b.max.x),
            AxisQuantizer::new(b.min.y, b.max.y),
            AxisQuantizer::new(b.min.z, b.max.z),
        ])
    }
    #[inline]
    pub fn encode(&self, p: [f32; 3]) -> [u16; 3] {
        [
            self.0[0].encode(p[0]),
            self.0[1].encode(p[1]),
            self.0[2].encode(p[2]),
        ]
    }
    #[inline]
    pub fn decode(&self, q: [u16; 3]) -> Vec3 {
        Vec3::new(
            self.0[0].decode(q[0]),
            self.0[1].decode(q[1]),
            self.0[2].decode(q[2]),
        )
    }
}

/// An encoded tile, ready to append to a map file.
#[derive(Clone, Debug)]
pub struct EncodedTile {
    pub blob: Vec<u8>,
    pub count: u32,
    pub layer: u16,
    pub quant: Aabb,
    pub bounds: Aabb,
    pub crc: u32,
}

impl EncodedTile {
    /// The index entry of this tile with its blob at `offset` in the file.
    pub fn entry(&self, offset: u64) -> TileEntry {
        TileEntry {
            offset,
            length: self.blob.len() as u32,
            count: self.count,
            quant: self.quant,
            bounds: self.bounds,
            crc: self.crc,
            layer: self.layer as u32,
        }
    }
}

/// Bytes of a blob's plane table: the raw-plane mask and 16 lengths.
const PLANE_TABLE: usize = 2 + 4 * RECORD_BYTES;

/// Reusable scratch for [`encode_tile`] (keeps allocations out of the loop).
#[derive(Default)]
pub struct TileEncoder {
    keys: Vec<EncodeKey>,
    /// The radix sort's second buffer.
    spare: Vec<EncodeKey>,
    raw: Vec<u8>,
    packed: Vec<u8>,
    zstd: Option<zstd::bulk::Compressor<'static>>,
}

impl TileEncoder {
    /// Encode `photons` (any order) as one tile blob.
    pub fn encode(&mut self, photons: &[StagedPhoton]) -> std::io::Result<EncodedTile> {
        let n = photons.len();
        assert!(n > 0 && n <= u32::MAX as usize, "tile of {n} photons");
        let layer = photons[0].photon.layer;
        debug_assert!(photons.iter().all(|p| p.photon.layer == layer));
        let mut quant = Aabb::EMPTY;
        for p in photons {
            quant.grow(p.pos());
        }
        let q = BoxQuantizer::new(&quant);
        self.keys.clear();
        self.keys.extend(photons.iter().map(|p| {
            (morton3(q.encode(p.photon.position)) as u128) << 80
                | (p.payload_key() as u128) << 16
                | p.photon.band_group as u128
        }));
        // By Morton code (radix), then runs of equal codes by the rest of
        // the key: the order of `sort_unstable` on the whole key.
        super::radix::sort_by_low_bits(&mut self.keys, &mut self.spare, 48, |k| k >> 80);
        for run in self.keys.chunk_by_mut(|a, b| a >> 80 == b >> 80) {
            if run.len() > 1 {
                run.sort_unstable();
            }
        }

        self.raw.clear();
        self.raw.resize(n * RECORD_BYTES, 0);
        let mut bounds = Aabb::EMPTY;
        let mut prev = 0u64;
        for (i, &key) in self.keys.iter().enumerate() {
            let (m, payload, band_group) = ((key >> 80) as u64, (key >> 16) as u64, key as u16);
            bounds.grow(q.decode(demorton3(m)));
            let mut rec = [0u8; RECORD_BYTES];
            rec[0..6].copy_from_slice(&(m - prev).to_le_bytes()[..6]);
            prev = m;
            // payload_key: direction u, direction v, power bits.
            rec[6..8].copy_from_slice(&((payload >> 48) as u16).to_le_bytes());
            rec[8..10].copy_from_slice(&((payload >> 32) as u16).to_le_bytes());
            rec[10..12].copy_from_slice(&band_group.to_le_bytes());
            rec[12..16].copy_from_slice(&(payload as u32).to_le_bytes());
            for (k, &b) in rec.iter().enumerate() {
                self.raw[k * n + i] = b;
            }
        }
        let zstd = match &mut self.zstd {
            Some(c) => c,
            none => none.insert(zstd::bulk::Compressor::new(ZSTD_LEVEL)?),
        };
        let mut blob = vec![0u8; PLANE_TABLE];
        let mut raw_planes = 0u16;
        for (k, plane) in self.raw.chunks_exact(n).enumerate() {
            self.packed.clear();
            self.packed.reserve(zstd::zstd_safe::compress_bound(n));
            let packed = zstd.compress_to_buffer(plane, &mut self.packed)?;
            let stored = if packed < n {
                blob.extend_from_slice(&self.packed);
                packed
            } else {
                raw_planes |= 1 << k;
                blob.extend_from_slice(plane);
                n
            };
            blob[2 + 4 * k..6 + 4 * k].copy_from_slice(&(stored as u32).to_le_bytes());
        }
        blob[0..2].copy_from_slice(&raw_planes.to_le_bytes());
        // The blob grew by doubling; a finished tile may wait in memory,
        // charged at its length, behind the tiles before it.
        blob.shrink_to_fit();
        let crc = crc32fast::hash(&blob);
        Ok(EncodedTile {
            blob,
            count: n as u32,
            layer,
            quant,
            bounds,
            crc,
        })
    }
}

/// Why a blob could not be decoded (the caller adds file and tile).
#[derive(Debug, thiserror::Error)]
pub enum DecodeError {
    #[error("checksum mismatch (stored {stored:08x}, computed {computed:08x})")]
    Checksum { stored: u32, computed: u32 },
    #[error("zstd frame is corrupt: {0}")]
    Zstd(std::io::Error),
    #[error("a plane decompressed to {got} bytes, expected {expected} for {count} photons")]
    Length {
        got: usize,
        expected: usize,
        count: u32,
    },
    #[error("position codes run past 48 bits")]
    Order,
    #[error("plane table does not match the blob")]
    Table,
}

/// Reusable scratch for [`TileDecoder::decode`].
#[derive(Default)]
pub struct TileDecoder {
    raw: Vec<u8>,
    codes: Vec<u64>,
    cells: Vec<[u16; 3]>,
    zstd: Option<zstd::bulk::Decompressor<'static>>,
}

impl TileDecoder {
    /// Check `blob` against its index entry's checksum and decode its
    /// photons into `out` (cleared first), in stored (Morton) order.
    pub fn decode(
        &mut self,
        blob: &[u8],
        entry: &TileEntry,
        out: &mut Vec<PackedPhoton>,
    ) -> Result<(), DecodeError> {
        let computed = crc32fast::hash(blob);
        if computed != entry.crc {
            return Err(DecodeError::Checksum {
                stored: entry.crc,
                computed,
            });
        }
        self.decode_unchecked(blob, entry, out)
    }

    /// As [`TileDecoder::decode`] without the checksum (for benchmarks of the codec alone).
    pub fn decode_unchecked(
        &mut self,
        blob: &[u8],
        entry: &TileEntry,
        out: &mut Vec<PackedPhoton>,
    ) -> Result<(), DecodeError> {
        let (count, quant, layer) = (entry.count, &entry.quant, entry.layer as u16);
        let n = count as usize;
        let expected = n * RECORD_BYTES;
        if blob.len() < PLANE_TABLE || n == 0 {
            return Err(DecodeError::Table);
        }
        let raw_planes = u16::from_le_bytes([blob[0], blob[1]]);
        let stored = |k: usize| {
            u32::from_le_bytes(blob[2 + 4 * k..6 + 4 * k].try_into().expect("4 bytes")) as usize
        };
        let total = (0..RECORD_BYTES).try_fold(PLANE_TABLE, |t: usize, k| t.checked_add(stored(k)));
        if total != Some(blob.len()) {
            return Err(DecodeError::Table);
        }
        // Only the growth is zeroed; every byte is written below.
        self.raw.resize(expected, 0);
        let zstd = match &mut self.zstd {
            Some(d) => d,
            none => none.insert(zstd::bulk::Decompressor::new().map_err(DecodeError::Zstd)?),
        };
        let mut at = PLANE_TABLE;
        for (k, plane) in self.raw.chunks_exact_mut(n).enumerate() {
            let src = &blob[at..at + stored(k)];
            at += stored(k);
            // zstd writes at most the plane's length: a longer frame fails.
            let got = if raw_planes & (1 << k) != 0 {
                if src.len() == n {
                    plane.copy_from_slice(src);
                }
                src.len()
            } else {
                zstd.decompress_to_buffer(src, plane)
                    .map_err(DecodeError::Zstd)?
            };
            if got != n {
                return Err(DecodeError::Length {
                    got,
                    expected: n,
                    count,
                });
            }
        }
        let q = BoxQuantizer::new(quant);
        let raw = &self.raw[..];
        out.clear();
        out.reserve_exact(n);
        let codes = &mut self.codes;
        codes.clear();
        codes.reserve(n);
        let cells = &mut self.cells;
        cells.clear();
        cells.reserve(n);
        // Deltas are below 2^48, so while the running code stays below 2^48
        // no sum can overflow; `high` remembers any excursion above it.
        let mut m = 0u64;
        let mut high = 0u64;
        // Un-shuffle a block at a time into a small record array (contiguous
        // reads from each plane), then decode records from it.
        const BLOCK: usize = 64;
        let mut recs = [[0u8; RECORD_BYTES]; BLOCK];
        let mut base = 0;
        while base < n {
            let len = BLOCK.min(n - base);
            if len == BLOCK {
                for (i, sub) in recs.chunks_exact_mut(RECORD_BYTES).enumerate() {
                    unshuffle16(raw, n, base + RECORD_BYTES * i, sub);
                }
            } else {
                unshuffle(raw, n, base, &mut recs[..len]);
            }
            out.extend(recs[..len].iter().map(|r| {
                let delta = u64::from_le_bytes([r[0], r[1], r[2], r[3], r[4], r[5], 0, 0]);
                m += delta;
                high |= m;
                codes.push(m);
                let cell = demorton3(m & MORTON_MASK);
                cells.push(cell);
                PackedPhoton {
                    position: q.decode(cell).to_array(),
                    oct: [
                        u16::from_le_bytes([r[6], r[7]]),
                        u16::from_le_bytes([r[8], r[9]]),
                    ],
                    band_group: u16::from_le_bytes([r[10], r[11]]),
                    layer,
                    power: f32::from_le_bytes([r[12], r[13], r[14], r[15]]),
                }
            }));
            base += len;
        }
        if high > MORTON_MASK {
            out.clear();
            self.codes.clear();
            self.cells.clear();
            return Err(DecodeError::Order);
        }
        Ok(())
    }

    /// The Morton codes of the photons last decoded, in the same (sorted)
    /// order: what [`super::tiletree::TileTree::from_morton`] builds on.
    pub fn codes(&self) -> &[u64] {
        &self.codes
    }

    /// The 16-bit cells of the photons last decoded (their codes
    /// un-interleaved), in the same order.
    pub fn cells(&self) -> &[[u16; 3]] {
        &self.cells
    }
}

#[cfg(test)]
mod tests;
