//! Shard files: one machine's part of a sharded emission, the photons it
//! stored at full precision, waiting to be merged into one map.
//!
//! A sharded emission splits the source indices 0..N into equal contiguous
//! ranges; shard I traces range I and writes its staged photons (position
//! in f32, direction, band, power: exactly what the map writer takes)
//! with everything the merge needs: the pilot sample (the same in every
//! shard, a pure function of the source and the budget), the map's bands,
//! bounds and provenance, and a producer payload (for an emission: its
//! fixed-point totals and the report's inputs). Merging feeds the photons
//! of all shards to the map writer, whose result depends only on the
//! multiset of photons, so the merged map is byte-identical to a single
//! run's.
//!
//! Layout: `SHARD_MAGIC`, the staged photons (in index order, snapped to
//! the map's grid) as a stream of frames of up to `spill::FRAME_PHOTONS`,
//! each its photon count (u32 LE), body length (u32 LE) and a
//! `spill::FrameCodec` body (sorted grid deltas and byte planes, about 13
//! bytes a photon against 30 for zstd over raw records), then the header
//! as JSON, its length (u64 LE) and CRC-32 (u32 LE), `SHARD_END`. The
//! stream's CRC-32 and length are in the header and checked while it is
//! read. Written under a temporary name and renamed when complete.
//!
//! Not for: rendering (merge first: `littoral map merge`).

use super::build::{MapDescription, Pilot};
use super::codec::StagedPhoton;
use super::spill::{FrameCodec, SnapGrid, FRAME_PHOTONS};
use crate::bounds::Aabb;
use crate::error::{Error, Result};
use crate::provenance::Provenance;
use crate::spectral::BandGrid;
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// First bytes of a shard file. `LTSHARD3` frames may hold their byte
/// planes in one zstd frame (plane mode 1); `LTSHARD2` files are read as
/// well (the same layout; most hold each plane apart). (`LTSHARD1` files
/// held zstd over 32-byte records with an id; they are refused with a
/// message saying so.)
pub const SHARD_MAGIC: &[u8; 8] = b"LTSHARD3";
/// The magic of shards whose frames store each plane apart.
const SHARD_MAGIC_V2: &[u8; 8] = b"LTSHARD2";

/// Whether `magic` opens a shard file this build reads.
pub fn is_shard_magic(magic: &[u8]) -> bool {
    magic == SHARD_MAGIC || magic == SHARD_MAGIC_V2
}
/// The longest shard header read: mostly the pilot sample, about 10 MB at
/// 10^9 photons.
const MAX_HEADER_BYTES: u64 = 1 << 30;
/// Last bytes of a complete shard file.
const SHARD_END: &[u8; 8] = b"LTSHEND1";
const TRAILER: u64 = 8 + 4 + 8;
/// Bytes before a frame's body in the stream: photon count and body length.
const FRAME_HEAD: usize = 8;

/// Everything in a shard but its photons.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ShardHeader {
    /// This shard's number, 0-based, of `shards`.
    pub shard: u64,
    pub shards: u64,
    /// The source indices it traced, start..end.
    pub indices: [u64; 2],
    /// Source indices of the whole emission.
    pub total_indices: u64,
    /// The map's provenance: SHA-256 (hex) and its record.
    pub provenance_digest: String,
    pub provenance_record: String,
    pub bands_nm: Vec<f32>,
    pub fwhm_nm: Vec<f32>,
    pub bounds_min: [f32; 3],
    pub bounds_max: [f32; 3],
    /// The `--mem-budget` the shard was emitted with (bytes; 0 in shards
    /// that did not record it): the pilot depends on it, and a merge with
    /// the same budget writes the single run's map.
    #[serde(default)]
    pub mem_budget: u64,
    /// The pilot: indices traced and the positions they stored.
    pub pilot_indices: u64,
    pub pilot: Vec<[f32; 3]>,
    /// Staged photons in the stream, its compressed length and CRC-32.
    pub photons: u64,
    pub stream_bytes: u64,
    pub stream_crc32: u32,
    /// What the producer needs to finish the merge (an emission: totals
    /// and report inputs), as its JSON text: written and read without
    /// `serde_json::Value`, whose numbers stop at 64 bits, so the tallies'
    /// 128-bit fixed-point sums of a large shard fit.
    pub payload: Box<serde_json::value::RawValue>,
}

impl ShardHeader {
    /// The map this shard is part of.
    pub fn description(&self, path: &Path) -> Result<MapDescription> {
        let bands = BandGrid::explicit(self.bands_nm.clone(), self.fwhm_nm.clone())
            .map_err(|e| Error::data(path, None, "shard header", e.to_string()))?;
        let mut digest = [0u8; 32];
        let hex = self.provenance_digest.as_bytes();
        if hex.len() != 64 {
            return Err(Error::data(
                path,
                None,
                "shard header",
                "provenance digest is not 64 hex digits",
            ));
        }
        for (i, d) in digest.iter_mut().enumerate() {
            let pair = std::str::from_utf8(&hex[2 * i..2 * i + 2]).unwrap_or("zz");
            *d = u8::from_str_radix(pair, 16).map_err(|_| {
                Error::data(path, None, "shard header", "provenance digest is not hex")
            })?;
        }
        Ok(MapDescription {
            indices: self.total_indices,
            bands,
            bounds: Aabb {
                min: Vec3::from(self.bounds_min),
                max: Vec3::from(self.bounds_max),
            },
            provenance: Provenance {
                digest,
                record: self.provenance_record.clone(),
            },
        })
    }

    /// The pilot sample it carries.
    pub fn pilot(&self) -> Pilot {
        Pilot {
            positions: self.pilot.iter().map(|&p| Vec3::from(p)).collect(),
            indices: self.pilot_indices,
        }
    }
}

/// Source indices of shard `i` of `n` over `total`: equal contiguous ranges.
pub fn shard_range(total: u64, i: u64, n: u64) -> std::ops::Range<u64> {
    let at = |k: u64| (total as u128 * k as u128 / n.max(1) as u128) as u64;
    at(i)..at(i + 1)
}

/// Counts the bytes and CRC-32 of what passes through.
struct Counting<W> {
    inner: W,
    crc: crc32fast::Hasher,
    bytes: u64,
}

impl<W: Write> Write for Counting<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.crc.update(&buf[..n]);
        self.bytes += n as u64;
        Ok(n)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// Writes one shard file.
pub struct ShardWriter {
    path: PathBuf,
    temp: tempfile::NamedTempFile,
    out: Counting<BufWriter<File>>,
    codec: FrameCodec,
    batch: Vec<StagedPhoton>,
    frame: Vec<u8>,
    photons: u64,
}

impl ShardWriter {
    /// Start the shard at `path` (under a temporary name beside it) of a
    /// map with `bounds`.
    pub fn create(path: &Path, bounds: &Aabb) -> Result<ShardWriter> {
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let temp = crate::output::temp_in(dir, ".littoral-shard.", ".partial")
            .map_err(|e| Error::io(path, "create", e))?;
        let mut file = temp.reopen().map_err(|e| Error::io(path, "open", e))?;
        file.write_all(SHARD_MAGIC)
            .map_err(|e| Error::io(path, "write", e))?;
        let codec = FrameCodec::new(SnapGrid::new(bounds))
            .map_err(|e| Error::io(path, "start compression", e))?;
        Ok(ShardWriter {
            path: path.to_path_buf(),
            temp,
            out: Counting {
                inner: BufWriter::new(file),
                crc: crc32fast::Hasher::new(),
                bytes: 0,
            },
            codec,
            batch: Vec::with_capacity(FRAME_PHOTONS),
            frame: Vec::new(),
            photons: 0,
        })
    }

    /// Append staged photons (snapped to the map's grid on the way).
    pub fn push(&mut self, photons: &[StagedPhoton]) -> Result<()> {
        let grid = self.codec.grid();
        for p in photons {
            self.batch.push(grid.snapped(p)?);
            if self.batch.len() == FRAME_PHOTONS {
                self.write_frame()?;
            }
        }
        self.photons += photons.len() as u64;
        Ok(())
    }

    fn write_frame(&mut self) -> Result<()> {
        if self.batch.is_empty() {
            return Ok(());
        }
        self.frame.clear();
        self.frame
            .extend_from_slice(&(self.batch.len() as u32).to_le_bytes());
        self.frame.extend_from_slice(&[0; 4]);
        self.codec
            .encode(&self.batch, &mut self.frame)
            .map_err(|e| Error::io(&self.path, "compress", e))?;
        let body = (self.frame.len() - FRAME_HEAD) as u32;
        self.frame[4..8].copy_from_slice(&body.to_le_bytes());
        self.out
            .write_all(&self.frame)
            .map_err(|e| Error::io(&self.path, "write", e))?;
        self.batch.clear();
        Ok(())
    }

    /// Staged photons written so far.
    pub fn photons(&self) -> u64 {
        self.photons
    }

    /// Finish the stream, write `header` (its photon count and stream
    /// fields filled in here) and rename the file into place.
    pub fn finish(mut self, mut header: ShardHeader) -> Result<ShardHeader> {
        self.write_frame()?;
        let ShardWriter {
            path,
            temp,
            out: counting,
            photons,
            ..
        } = self;
        header.photons = photons;
        header.stream_bytes = counting.bytes;
        header.stream_crc32 = counting.crc.finalize();
        let mut out = counting.inner;
        let json = serde_json::to_vec(&header)
            .map_err(|e| Error::invalid("shard header", e.to_string()))?;
        let crc = crc32fast::hash(&json);
        let io = |e| Error::io(&path, "write", e);
        out.write_all(&json).map_err(io)?;
        out.write_all(&(json.len() as u64).to_le_bytes())
            .map_err(io)?;
        out.write_all(&crc.to_le_bytes()).map_err(io)?;
        out.write_all(SHARD_END).map_err(io)?;
        out.flush().map_err(io)?;
        drop(out);
        crate::output::publish(temp, &path)?;
        Ok(header)
    }
}

/// A shard file opened for merging.
pub struct ShardFile {
    path: PathBuf,
    header: ShardHeader,
}

impl ShardFile {
    /// Open `path` and read its header; a file that is not a complete
    /// shard gets an error naming it.
    pub fn open(path: &Path) -> Result<ShardFile> {
        let bad = |what: &str| Error::data(path, None, "shard", what.to_string());
        let mut f = File::open(path).map_err(|e| Error::io(path, "open", e))?;
        let len = f.metadata().map_err(|e| Error::io(path, "stat", e))?.len();
        let mut magic = [0u8; 8];
        let read_magic = len >= 8 + TRAILER && f.read_exact(&mut magic).is_ok();
        if read_magic && &magic == b"LTSHARD1" {
            return Err(bad(
                "a shard of an older littoral (32-byte records with ids): emit it again",
            ));
        }
        if !read_magic || !is_shard_magic(&magic) {
            return Err(bad("not a littoral shard file (or truncated)"));
        }
        let mut trailer = [0u8; TRAILER as usize];
        f.seek(SeekFrom::Start(len - TRAILER))
            .and_then(|_| f.read_exact(&mut trailer))
            .map_err(|e| Error::io(path, "read", e))?;
        if &trailer[12..] != SHARD_END {
            return Err(bad(
                "incomplete shard (no end marker): the emission did not finish",
            ));
        }
        let json_len = u64::from_le_bytes(trailer[..8].try_into().expect("8 bytes"));
        let crc = u32::from_le_bytes(trailer[8..12].try_into().expect("4 bytes"));
        if json_len > len - 8 - TRAILER {
            return Err(bad("corrupt shard trailer (header length)"));
        }
        // The length is outside the CRC: a damaged one the size of the
        // file must be an error, not an allocation that aborts or takes
        // the machine's memory (overcommit lets any reservation succeed).
        if json_len > MAX_HEADER_BYTES {
            return Err(bad("corrupt shard trailer (header length past 1 GiB)"));
        }
        let mut json = Vec::new();
        json.try_reserve_exact(json_len as usize)
            .map_err(|_| bad("corrupt shard trailer (header length beyond memory)"))?;
        json.resize(json_len as usize, 0);
        f.seek(SeekFrom::Start(len - TRAILER - json_len))
            .and_then(|_| f.read_exact(&mut json))
            .map_err(|e| Error::io(path, "read", e))?;
        if crc32fast::hash(&json) != crc {
            return Err(bad("corrupt shard header (CRC mismatch)"));
        }
        let header: ShardHeader = serde_json::from_slice(&json)
            .map_err(|e| bad(&format!("unreadable shard header: {e}")))?;
        if header.stream_bytes != len - 8 - TRAILER - json_len {
            return Err(bad(
                "corrupt shard (stream length does not match the header)",
            ));
        }
        Ok(ShardFile {
            path: path.to_path_buf(),
            header,
        })
    }

    pub fn header(&self) -> &ShardHeader {
        &self.header
    }

    /// Let go of the header's bulk once it has been checked and read (the
    /// pilot sample, up to an eighth of the budget, and the payload): a
    /// merge of many shards keeps one pilot, not one a shard.
    pub fn trim(&mut self) {
        self.header.pilot = Vec::new();
        self.header.payload =
            serde_json::value::RawValue::from_string("null".to_string()).expect("null is JSON");
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The staged photons, in batches of one frame; the last item is an
    /// error if the stream is corrupt (CRC, length or photon count).
    pub fn batches(&self) -> Result<ShardBatches> {
        let mut f = File::open(&self.path).map_err(|e| Error::io(&self.path, "open", e))?;
        f.seek(SeekFrom::Start(8))
            .map_err(|e| Error::io(&self.path, "read", e))?;
        let grid = SnapGrid::new(&Aabb {
            min: Vec3::from(self.header.bounds_min),
            max: Vec3::from(self.header.bounds_max),
        });
        let codec =
            FrameCodec::new(grid).map_err(|e| Error::io(&self.path, "start decompression", e))?;
        Ok(ShardBatches {
            path: self.path.clone(),
            reader: Some(CrcReader {
                inner: BufReader::new(f).take(self.header.stream_bytes),
                crc: crc32fast::Hasher::new(),
            }),
            codec,
            body: Vec::new(),
            expected: self.header.photons,
            crc: self.header.stream_crc32,
            read: 0,
        })
    }
}

struct CrcReader<R> {
    inner: R,
    crc: crc32fast::Hasher,
}

impl<R: Read> Read for CrcReader<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.crc.update(&buf[..n]);
        Ok(n)
    }
}

/// Iterator over a shard's staged photons.
pub struct ShardBatches {
    path: PathBuf,
    reader: Option<CrcReader<std::io::Take<BufReader<File>>>>,
    codec: FrameCodec,
    body: Vec<u8>,
    expected: u64,
    crc: u32,
    read: u64,
}

impl ShardBatches {
    /// The next frame's photons; `None` at the end of the stream.
    fn next_frame(&mut self) -> std::result::Result<Option<Vec<StagedPhoton>>, String> {
        let Some(reader) = self.reader.as_mut() else {
            return Ok(None);
        };
        let mut head = [0u8; FRAME_HEAD];
        let mut got = 0;
        while got < FRAME_HEAD {
            match reader.read(&mut head[got..]) {
                Ok(0) => break,
                Ok(n) => got += n,
                Err(e) => return Err(format!("corrupt photon stream: {e}")),
            }
        }
        if got == 0 {
            let crc = reader.crc.clone().finalize();
            self.reader = None;
            if crc != self.crc || self.read != self.expected {
                return Err(format!(
                    "corrupt photon stream: CRC {crc:08x} (header {:08x}), {} photons (header {})",
                    self.crc, self.read, self.expected
                ));
            }
            return Ok(None);
        }
        if got < FRAME_HEAD {
            return Err("truncated photon stream".into());
        }
        let count = u32::from_le_bytes(head[0..4].try_into().expect("4 bytes")) as usize;
        let len = u32::from_le_bytes(head[4..8].try_into().expect("4 bytes")) as usize;
        // A body is at most its raw planes, a few bytes of lengths, and the head.
        if count == 0 || count > FRAME_PHOTONS || len > count * 40 + 256 {
            return Err(format!(
                "corrupt photon frame ({count} photons, {len} bytes)"
            ));
        }
        self.body.resize(len, 0);
        reader
            .read_exact(&mut self.body)
            .map_err(|e| format!("truncated photon stream: {e}"))?;
        let mut photons = Vec::with_capacity(count);
        self.codec
            .decode(&self.body, count, &mut photons)
            .map_err(|e| format!("corrupt photon {e}"))?;
        self.read += count as u64;
        if self.read > self.expected {
            return Err("more photons than the header says".into());
        }
        Ok(Some(photons))
    }
}

impl Iterator for ShardBatches {
    type Item = Result<Vec<StagedPhoton>>;

    fn next(&mut self) -> Option<Self::Item> {
        match self.next_frame() {
            Ok(batch) => batch.map(Ok),
            Err(what) => {
                self.reader = None;
                Some(Err(Error::data(&self.path, None, "shard", what)))
            }
        }
    }
}
