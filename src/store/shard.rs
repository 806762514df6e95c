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
//! Layout: `SHARD_MAGIC`, the staged photons as one zstd stream of 24-byte
//! records (index order within the shard), the header as JSON, its length
//! (u64 LE) and CRC-32 (u32 LE), `SHARD_END`. The stream's CRC-32 and length
//! are in the header and checked while it is read. Written under a
//! temporary name and renamed when complete.
//!
//! Not for: rendering (merge first: `littoral map merge`).

use super::build::{MapDescription, Pilot};
use super::codec::StagedPhoton;
use crate::bounds::Aabb;
use crate::error::{Error, Result};
use crate::provenance::Provenance;
use crate::spectral::BandGrid;
use bytemuck::Zeroable;
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// First bytes of a shard file.
/// (`LTSHARD1` files held 32-byte records with an id; they are refused as
/// not being shard files of this version.)
pub const SHARD_MAGIC: &[u8; 8] = b"LTSHARD2";
/// Last bytes of a complete shard file.
const SHARD_END: &[u8; 8] = b"LTSHEND1";
const TRAILER: u64 = 8 + 4 + 8;
/// Staged photons per batch read back.
const READ_BATCH: usize = 1 << 16;
const STAGED: usize = std::mem::size_of::<StagedPhoton>();

/// Everything in a shard but its photons.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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
    /// The pilot: indices traced and the positions they stored.
    pub pilot_indices: u64,
    pub pilot: Vec<[f32; 3]>,
    /// Staged photons in the stream, its compressed length and CRC-32.
    pub photons: u64,
    pub stream_bytes: u64,
    pub stream_crc32: u32,
    /// What the producer needs to finish the merge (an emission: totals
    /// and report inputs).
    pub payload: serde_json::Value,
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
    encoder: zstd::stream::write::Encoder<'static, Counting<BufWriter<File>>>,
    photons: u64,
}

impl ShardWriter {
    /// Start the shard at `path` (under a temporary name beside it).
    pub fn create(path: &Path) -> Result<ShardWriter> {
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let temp = crate::output::temp_in(dir, ".littoral-shard.", ".partial")
            .map_err(|e| Error::io(path, "create", e))?;
        let mut file = temp.reopen().map_err(|e| Error::io(path, "open", e))?;
        file.write_all(SHARD_MAGIC)
            .map_err(|e| Error::io(path, "write", e))?;
        let counting = Counting {
            inner: BufWriter::new(file),
            crc: crc32fast::Hasher::new(),
            bytes: 0,
        };
        let encoder = zstd::stream::write::Encoder::new(counting, super::codec::ZSTD_LEVEL)
            .map_err(|e| Error::io(path, "start compression", e))?;
        Ok(ShardWriter {
            path: path.to_path_buf(),
            temp,
            encoder,
            photons: 0,
        })
    }

    /// Append staged photons.
    pub fn push(&mut self, photons: &[StagedPhoton]) -> Result<()> {
        self.encoder
            .write_all(bytemuck::cast_slice(photons))
            .map_err(|e| Error::io(&self.path, "write", e))?;
        self.photons += photons.len() as u64;
        Ok(())
    }

    /// Staged photons written so far.
    pub fn photons(&self) -> u64 {
        self.photons
    }

    /// Finish the stream, write `header` (its photon count and stream
    /// fields filled in here) and rename the file into place.
    pub fn finish(self, mut header: ShardHeader) -> Result<ShardHeader> {
        let ShardWriter {
            path,
            temp,
            encoder,
            photons,
        } = self;
        let counting = encoder
            .finish()
            .map_err(|e| Error::io(&path, "finish compression", e))?;
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
        crate::output::finalize(&temp, &path)?;
        temp.persist(&path)
            .map_err(|e| Error::io(&path, "rename into place", e.error))?;
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
        if !read_magic || &magic != SHARD_MAGIC {
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
        let mut json = vec![0u8; json_len as usize];
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

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The staged photons, in batches; the last item is an error if the
    /// stream is corrupt (CRC, length or photon count).
    pub fn batches(&self) -> Result<ShardBatches> {
        let mut f = File::open(&self.path).map_err(|e| Error::io(&self.path, "open", e))?;
        f.seek(SeekFrom::Start(8))
            .map_err(|e| Error::io(&self.path, "read", e))?;
        let reader = CrcReader {
            inner: BufReader::new(f).take(self.header.stream_bytes),
            crc: crc32fast::Hasher::new(),
        };
        let decoder = zstd::stream::read::Decoder::with_buffer(std::io::BufReader::new(reader))
            .map_err(|e| Error::io(&self.path, "start decompression", e))?;
        Ok(ShardBatches {
            path: self.path.clone(),
            decoder: Some(decoder),
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

type ShardDecoder =
    zstd::stream::read::Decoder<'static, BufReader<CrcReader<std::io::Take<BufReader<File>>>>>;

/// Iterator over a shard's staged photons.
pub struct ShardBatches {
    path: PathBuf,
    decoder: Option<ShardDecoder>,
    expected: u64,
    crc: u32,
    read: u64,
}

impl Iterator for ShardBatches {
    type Item = Result<Vec<StagedPhoton>>;

    fn next(&mut self) -> Option<Self::Item> {
        let decoder = self.decoder.as_mut()?;
        let bad = |path: &Path, what: String| Error::data(path, None, "shard", what);
        let mut buf = vec![StagedPhoton::zeroed(); READ_BATCH];
        let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut buf);
        let mut filled = 0;
        while filled < bytes.len() {
            match decoder.read(&mut bytes[filled..]) {
                Ok(0) => break,
                Ok(n) => filled += n,
                Err(e) => {
                    self.decoder = None;
                    return Some(Err(bad(&self.path, format!("corrupt photon stream: {e}"))));
                }
            }
        }
        if filled % STAGED != 0 {
            self.decoder = None;
            return Some(Err(bad(&self.path, "truncated photon record".into())));
        }
        buf.truncate(filled / STAGED);
        self.read += buf.len() as u64;
        if buf.is_empty() {
            // The end: every compressed byte was read; check the CRC.
            let mut decoder = self.decoder.take()?;
            let mut rest = Vec::new();
            // Bytes below the decoder's buffer not read yet (the frame's
            // end): read them through the CRC too.
            let inner = decoder.get_mut().get_mut();
            let _ = inner.read_to_end(&mut rest);
            let crc = inner.crc.clone().finalize();
            if crc != self.crc || self.read != self.expected {
                return Some(Err(bad(
                    &self.path,
                    format!(
                        "corrupt photon stream: CRC {crc:08x} (header {:08x}), {} photons (header {})",
                        self.crc, self.read, self.expected
                    ),
                )));
            }
            return None;
        }
        if self.read > self.expected {
            self.decoder = None;
            return Some(Err(bad(
                &self.path,
                "more photons than the header says".into(),
            )));
        }
        Some(Ok(buf))
    }
}
