//! Tile blob codec: sorted, quantised, byte-shuffled, zstd-compressed records.
//!
//! A tile's photons are quantised to 16 bits per axis inside the tile's box,
//! sorted by the Morton code of the quantised position (ties by photon id, so
//! the order — and the blob — is a pure function of the photon set), and laid
//! out as 16-byte records:
//!
//! | bytes | field |
//! |---|---|
//! | 0..6  | Morton code delta from the previous record (48 bits) |
//! | 6..10 | octahedral direction (2 x u16) |
//! | 10..12 | band index (u16) |
//! | 12..16 | power (f32 bits) |
//!
//! The records are then byte-shuffled (byte k of every record forms plane k)
//! and the 16 planes compressed as one zstd frame. Sorting makes the deltas
//! small and the shuffle puts their zero high bytes — and the few distinct
//! band and power values — into long runs that zstd removes.

use super::format::TileEntry;
use crate::bounds::Aabb;
use crate::photon::{AxisQuantizer, PackedPhoton, Photon};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// Bytes per record before compression.
pub const RECORD_BYTES: usize = 16;

/// zstd level for tile blobs and spill runs: higher levels gain little on
/// MB-sized tiles of shuffled records and cost compression speed.
pub const ZSTD_LEVEL: i32 = 1;

/// A photon on its way from the emitter to the map: full-precision position,
/// encoded direction, and the id that breaks ties in the tile sort.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct StagedPhoton {
    pub photon: PackedPhoton,
    /// Unique within a map; photons are sorted by it where positions tie.
    pub id: u64,
}

const _: () = assert!(std::mem::size_of::<StagedPhoton>() == 32);

impl StagedPhoton {
    /// Stage a photon of `layer` with its unique id.
    pub fn new(p: &Photon, layer: u16, id: u64) -> Self {
        StagedPhoton {
            photon: PackedPhoton::pack(p, layer),
            id,
        }
    }

    #[inline]
    pub fn pos(&self) -> Vec3 {
        self.photon.pos()
    }
}

/// Bytes of working memory the encoder needs per photon (staged record, sort
/// key, raw record, compressed output bound), used for budgeting merges.
pub const ENCODE_BYTES_PER_PHOTON: usize = 32 + 24 + RECORD_BYTES + RECORD_BYTES + 8;

/// Spread the bits of `v` to every third bit (21-bit to 63-bit Morton spread).
#[inline]
fn part1by2(v: u16) -> u64 {
    let mut x = v as u64;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

/// Inverse of [`part1by2`].
#[inline]
fn compact1by2(mut x: u64) -> u16 {
    x &= 0x1249_2492_4924_9249;
    x = (x ^ (x >> 2)) & 0x10c3_0c30_c30c_30c3;
    x = (x ^ (x >> 4)) & 0x100f_00f0_0f00_f00f;
    x = (x ^ (x >> 8)) & 0x001f_0000_ff00_00ff;
    x = (x ^ (x >> 16)) & 0x001f_0000_0000_ffff;
    x = (x ^ (x >> 32)) & 0x001f_ffff;
    x as u16
}

/// 48-bit Morton code of a quantised position (x in the lowest bit).
#[inline]
pub fn morton3(q: [u16; 3]) -> u64 {
    part1by2(q[0]) | (part1by2(q[1]) << 1) | (part1by2(q[2]) << 2)
}

/// Inverse of [`morton3`].
#[inline]
pub fn demorton3(m: u64) -> [u16; 3] {
    [compact1by2(m), compact1by2(m >> 1), compact1by2(m >> 2)]
}

const MORTON_MASK: u64 = (1 << 48) - 1;

/// The quantisers of a tile box, one per axis.
#[derive(Clone, Copy, Debug)]
pub struct BoxQuantizer([AxisQuantizer; 3]);

impl BoxQuantizer {
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

/// Reusable scratch for [`encode_tile`] (keeps allocations out of the loop).
#[derive(Default)]
pub struct TileEncoder {
    keys: Vec<(u64, u64, u32)>,
    raw: Vec<u8>,
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
        self.keys.extend(
            photons
                .iter()
                .enumerate()
                .map(|(i, p)| (morton3(q.encode(p.photon.position)), p.id, i as u32)),
        );
        self.keys.sort_unstable();

        self.raw.clear();
        self.raw.resize(n * RECORD_BYTES, 0);
        let mut bounds = Aabb::EMPTY;
        let mut prev = 0u64;
        for (i, &(m, _, idx)) in self.keys.iter().enumerate() {
            let p = &photons[idx as usize].photon;
            bounds.grow(q.decode(demorton3(m)));
            let mut rec = [0u8; RECORD_BYTES];
            rec[0..6].copy_from_slice(&(m - prev).to_le_bytes()[..6]);
            prev = m;
            rec[6..8].copy_from_slice(&p.oct[0].to_le_bytes());
            rec[8..10].copy_from_slice(&p.oct[1].to_le_bytes());
            rec[10..12].copy_from_slice(&p.band.to_le_bytes());
            rec[12..16].copy_from_slice(&p.power.to_le_bytes());
            for (k, &b) in rec.iter().enumerate() {
                self.raw[k * n + i] = b;
            }
        }
        let zstd = match &mut self.zstd {
            Some(c) => c,
            none => none.insert(zstd::bulk::Compressor::new(ZSTD_LEVEL)?),
        };
        let blob = zstd.compress(&self.raw)?;
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
    #[error("decompressed to {got} bytes, expected {expected} for {count} photons")]
    Length {
        got: usize,
        expected: usize,
        count: u32,
    },
    #[error("position codes run past 48 bits")]
    Order,
}

/// Reusable scratch for [`TileDecoder::decode`].
#[derive(Default)]
pub struct TileDecoder {
    raw: Vec<u8>,
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
        self.raw.clear();
        // zstd writes at most `capacity()` bytes; a frame longer than
        // expected fails here or below, never overruns.
        self.raw.reserve_exact(expected.max(1));
        let zstd = match &mut self.zstd {
            Some(d) => d,
            none => none.insert(zstd::bulk::Decompressor::new().map_err(DecodeError::Zstd)?),
        };
        // One spare byte of capacity tells "exactly expected" from "more".
        let got = zstd
            .decompress_to_buffer(blob, &mut self.raw)
            .map_err(DecodeError::Zstd)?;
        if got != expected {
            return Err(DecodeError::Length {
                got,
                expected,
                count,
            });
        }
        let q = BoxQuantizer::new(quant);
        let raw = &self.raw[..];
        out.clear();
        out.reserve_exact(n);
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
            for k in 0..RECORD_BYTES {
                let plane = &raw[k * n + base..k * n + base + len];
                for (rec, &byte) in recs.iter_mut().zip(plane) {
                    rec[k] = byte;
                }
            }
            out.extend(recs[..len].iter().map(|r| {
                let delta = u64::from_le_bytes([r[0], r[1], r[2], r[3], r[4], r[5], 0, 0]);
                m += delta;
                high |= m;
                PackedPhoton {
                    position: q.decode(demorton3(m & MORTON_MASK)).to_array(),
                    oct: [
                        u16::from_le_bytes([r[6], r[7]]),
                        u16::from_le_bytes([r[8], r[9]]),
                    ],
                    band: u16::from_le_bytes([r[10], r[11]]),
                    layer,
                    power: f32::from_le_bytes([r[12], r[13], r[14], r[15]]),
                }
            }));
            base += len;
        }
        if high > MORTON_MASK {
            out.clear();
            return Err(DecodeError::Order);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;

    #[test]
    fn morton_round_trips() {
        let mut rng = Pcg32::new(1, 2);
        for _ in 0..10_000 {
            let q = [
                rng.next_u32() as u16,
                rng.next_u32() as u16,
                rng.next_u32() as u16,
            ];
            assert_eq!(demorton3(morton3(q)), q);
        }
        assert_eq!(morton3([1, 0, 0]), 1);
        assert_eq!(morton3([0, 1, 0]), 2);
        assert_eq!(morton3([0, 0, 1]), 4);
        assert_eq!(morton3([0xffff; 3]), (1u64 << 48) - 1);
    }

    fn staged(n: usize, seed: u64) -> Vec<StagedPhoton> {
        (0..n)
            .map(|i| {
                let mut r = Pcg32::new(seed, i as u64);
                let p = Photon {
                    position: Vec3::new(
                        r.uniform_f32() * 10.0,
                        r.uniform_f32() * 10.0,
                        -r.uniform_f32() * 3.0,
                    ),
                    direction: Vec3::new(r.uniform_f32() - 0.5, 0.3, -1.0).normalize(),
                    band: r.below(128) as u16,
                    power: 0.25,
                };
                StagedPhoton::new(&p, 0, i as u64)
            })
            .collect()
    }

    fn entry(t: &EncodedTile) -> TileEntry {
        TileEntry {
            offset: 0,
            length: t.blob.len() as u32,
            count: t.count,
            quant: t.quant,
            bounds: t.bounds,
            crc: t.crc,
            layer: t.layer as u32,
        }
    }

    #[test]
    fn tile_round_trips_within_quantisation_error() {
        let photons = staged(5000, 3);
        let t = TileEncoder::default().encode(&photons).unwrap();
        let mut out = Vec::new();
        TileDecoder::default()
            .decode(&t.blob, &entry(&t), &mut out)
            .unwrap();
        assert_eq!(out.len(), photons.len());
        let step = (t.quant.max - t.quant.min) / 65535.0;
        // Match decoded photons to inputs by band, power and nearest position.
        let mut used = vec![false; photons.len()];
        for d in out.iter().map(|p| p.unpack()) {
            assert!(t.bounds.distance_sq(d.position) == 0.0);
            let j = (0..photons.len())
                .filter(|&j| !used[j] && photons[j].photon.band == d.band)
                .min_by(|&a, &b| {
                    let da = photons[a].pos().distance_squared(d.position);
                    let db = photons[b].pos().distance_squared(d.position);
                    da.total_cmp(&db)
                })
                .unwrap();
            used[j] = true;
            let err = (photons[j].pos() - d.position).abs();
            assert!(err.cmple(step * 0.5 + Vec3::splat(1e-5)).all(), "{err}");
            assert_eq!(photons[j].photon.unpack().direction, d.direction);
            assert_eq!(d.power, photons[j].photon.power);
        }
    }

    #[test]
    fn blob_is_independent_of_input_order() {
        let mut photons = staged(3000, 4);
        let a = TileEncoder::default().encode(&photons).unwrap();
        photons.reverse();
        let b = TileEncoder::default().encode(&photons).unwrap();
        assert_eq!(a.blob, b.blob);
        assert_eq!(a.crc, b.crc);
    }

    #[test]
    fn corrupt_blobs_are_rejected() {
        let photons = staged(2000, 5);
        let t = TileEncoder::default().encode(&photons).unwrap();
        let mut dec = TileDecoder::default();
        let mut out = Vec::new();
        let mut bad = t.blob.clone();
        bad[t.blob.len() / 2] ^= 0x40;
        assert!(matches!(
            dec.decode(&bad, &entry(&t), &mut out),
            Err(DecodeError::Checksum { .. })
        ));
        // A valid frame with the wrong count is caught by its length.
        let e = entry(&t);
        let fewer = TileEntry {
            count: t.count - 1,
            ..e
        };
        assert!(dec.decode(&t.blob, &fewer, &mut out).is_err());
        let more = TileEntry {
            count: t.count + 1,
            ..e
        };
        assert!(matches!(
            dec.decode(&t.blob, &more, &mut out),
            Err(DecodeError::Length { .. })
        ));
        // A truncated frame (with a matching checksum) is caught by zstd.
        let short = &t.blob[..t.blob.len() - 3];
        let short_entry = TileEntry {
            crc: crc32fast::hash(short),
            ..e
        };
        assert!(dec.decode(short, &short_entry, &mut out).is_err());
    }
}
