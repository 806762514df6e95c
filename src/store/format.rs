//! The map file layout, version 5 (`FORMAT_VERSION`).
//!
//! ```text
//! offset 0   header   magic "LTRLMAP\0", version u32, header length u32,
//!                     body (photons, tiles, band grid, bounds, partition,
//!                     provenance digest [32], provenance record length u32
//!                     and UTF-8 JSON, metadata offset u64, length u64,
//!                     crc32), crc32 of everything before it
//!            blobs    one per tile: a plane table and 16 byte planes, each
//!                     zstd-compressed or raw (see `codec`)
//!            metadata UTF-8 JSON the producer reported at the end (for an
//!                     emitted map, the emission report)
//!            index    one 72-byte entry per tile (offset, length, count,
//!                     quantisation box, photon bounds, crc32 of the blob,
//!                     layer: 0 volume photons travelling down, 1 surface
//!                     photons, 2 volume photons travelling up)
//! end - 40   footer   index offset u64, index length u64, tile count u32,
//!                     index crc32, version u32, footer crc32, magic "LTRLEND\0"
//! ```
//! All integers and floats are little-endian. Every byte of the file is
//! covered by a checksum: the header and footer by their own, the index by the
//! footer's, each blob by its index entry's, the metadata by the header's.
//! A reader checks the length, both magics, the version, the footer, the
//! index, the header and the metadata before it touches any blob.
//!
//! Versions 1-4 are refused with a message to emit the map again: version
//! 4 compressed a tile as one zstd frame, 3 kept volume photons in one
//! layer, 2 recorded no photon groups, and 1 had no provenance (without
//! it a map cannot be safely reused).

use crate::bounds::Aabb;
use crate::error::{Error, Result};
use crate::provenance::Provenance;
use crate::spectral::BandGrid;
use glam::Vec3;
use std::path::Path;

/// Magic at the start of a map file.
pub const HEADER_MAGIC: [u8; 8] = *b"LTRLMAP\0";
/// Magic at the end of a map file.
pub const FOOTER_MAGIC: [u8; 8] = *b"LTRLEND\0";
/// The format version this build writes and the newest it reads.
pub const FORMAT_VERSION: u32 = 5;
/// Size of the footer in bytes.
pub const FOOTER_LEN: usize = 40;
/// Size of one index entry in bytes.
pub const INDEX_ENTRY_LEN: usize = 72;
/// Smallest possible header (magic, version, length, fixed body, crc).
pub const MIN_HEADER_LEN: usize = 16 + 8 + 4 + 4 + 8 + 24 + 4 + 32 + 4 + 20 + 4;

/// One node of the pilot k-d partition, stored in preorder.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PartitionNode {
    /// Points with `coord[axis] < value` go to the left subtree (next node),
    /// the rest to the right subtree.
    Split { axis: u8, value: f32 },
    /// A cell of the partition.
    Leaf,
}

/// What the header records about a map.
#[derive(Clone, Debug, PartialEq)]
pub struct Header {
    pub photons: u64,
    pub tiles: u32,
    pub bands: BandGrid,
    /// Bounds of the scene the photons were traced in.
    pub bounds: Aabb,
    /// The pilot partition (tiles are its cells, some split further).
    pub partition: Vec<PartitionNode>,
    /// What the photons were made from.
    pub provenance: Provenance,
    /// Where the metadata section lies.
    pub metadata: Section,
}

/// A checksummed byte range of the file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Section {
    pub offset: u64,
    pub length: u64,
    pub crc: u32,
}

/// The index entry of one tile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TileEntry {
    /// Byte offset of the blob in the file.
    pub offset: u64,
    /// Byte length of the blob.
    pub length: u32,
    /// Photons in the tile.
    pub count: u32,
    /// Box the positions were quantised in.
    pub quant: Aabb,
    /// Bounds of the decoded positions (used to prune queries).
    pub bounds: Aabb,
    /// CRC-32 of the blob bytes.
    pub crc: u32,
    /// The layer of every photon in the tile (`photon::LAYER_*`).
    pub layer: u32,
}

/// The trailing fixed-size record that locates the index.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Footer {
    pub index_offset: u64,
    pub index_length: u64,
    pub tiles: u32,
    pub index_crc: u32,
    pub version: u32,
}

/// Little-endian append-only byte sink.
#[derive(Default)]
pub struct ByteWriter(pub Vec<u8>);

impl ByteWriter {
    pub fn u8(&mut self, v: u8) {
        self.0.push(v);
    }
    pub fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub fn f32(&mut self, v: f32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub fn vec3(&mut self, v: Vec3) {
        self.f32(v.x);
        self.f32(v.y);
        self.f32(v.z);
    }
    pub fn aabb(&mut self, b: &Aabb) {
        self.vec3(b.min);
        self.vec3(b.max);
    }
}

/// Bounds-checked little-endian reader; running short is an error naming `what`.
pub struct ByteReader<'a> {
    bytes: &'a [u8],
    pos: usize,
    path: &'a Path,
    what: &'static str,
}

impl<'a> ByteReader<'a> {
    pub fn new(bytes: &'a [u8], path: &'a Path, what: &'static str) -> Self {
        ByteReader {
            bytes,
            pos: 0,
            path,
            what,
        }
    }
    fn take(&mut self, n: usize) -> Result<&'a [u8]> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.bytes.len());
        match end {
            Some(end) => {
                let s = &self.bytes[self.pos..end];
                self.pos = end;
                Ok(s)
            }
            None => Err(Error::format(
                self.path,
                format!("{} ends early at byte {}", self.what, self.pos),
            )),
        }
    }
    pub fn u8(&mut self) -> Result<u8> {
        Ok(self.take(1)?[0])
    }
    pub fn u32(&mut self) -> Result<u32> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().unwrap()))
    }
    pub fn u64(&mut self) -> Result<u64> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().unwrap()))
    }
    pub fn f32(&mut self) -> Result<f32> {
        Ok(f32::from_le_bytes(self.take(4)?.try_into().unwrap()))
    }
    pub fn vec3(&mut self) -> Result<Vec3> {
        Ok(Vec3::new(self.f32()?, self.f32()?, self.f32()?))
    }
    pub fn aabb(&mut self) -> Result<Aabb> {
        Ok(Aabb {
            min: self.vec3()?,
            max: self.vec3()?,
        })
    }
    pub fn bytes(&mut self, n: usize) -> Result<&'a [u8]> {
        self.take(n)
    }
    pub fn remaining(&self) -> usize {
        self.bytes.len() - self.pos
    }
}

impl Header {
    /// Serialise with magic, version, length and trailing checksum.
    pub fn encode(&self) -> Vec<u8> {
        let mut body = ByteWriter::default();
        body.u64(self.photons);
        body.u32(self.tiles);
        body.u32(self.bands.len() as u32);
        for (&c, &w) in self.bands.centers_nm().iter().zip(self.bands.fwhm_nm()) {
            body.f32(c);
            body.f32(w);
        }
        body.aabb(&self.bounds);
        body.u32(self.partition.len() as u32);
        for node in &self.partition {
            match *node {
                PartitionNode::Split { axis, value } => {
                    body.u8(axis);
                    body.f32(value);
                }
                PartitionNode::Leaf => {
                    body.u8(0xff);
                    body.f32(0.0);
                }
            }
        }
        body.0.extend_from_slice(&self.provenance.digest);
        body.u32(self.provenance.record.len() as u32);
        body.0.extend_from_slice(self.provenance.record.as_bytes());
        body.u64(self.metadata.offset);
        body.u64(self.metadata.length);
        body.u32(self.metadata.crc);
        let mut out = ByteWriter::default();
        out.0.extend_from_slice(&HEADER_MAGIC);
        out.u32(FORMAT_VERSION);
        out.u32((body.0.len() + 4) as u32);
        out.0.extend_from_slice(&body.0);
        let crc = crc32fast::hash(&out.0);
        out.u32(crc);
        out.0
    }

    /// Parse and check a header at the start of `bytes`; returns it and its length.
    pub fn decode(bytes: &[u8], path: &Path) -> Result<(Header, usize)> {
        let mut r = ByteReader::new(bytes, path, "header");
        if r.bytes(8)? != HEADER_MAGIC {
            return Err(Error::format(path, "wrong magic at the start of the file"));
        }
        let version = r.u32()?;
        let rest = r.u32()? as usize;
        let total = 16usize.saturating_add(rest);
        if rest < 4 || total > bytes.len() {
            return Err(Error::format(
                path,
                format!("header length {rest} does not fit in the file"),
            ));
        }
        let stored = u32::from_le_bytes(bytes[total - 4..total].try_into().unwrap());
        if crc32fast::hash(&bytes[..total - 4]) != stored {
            if version > FORMAT_VERSION {
                return Err(Error::Version {
                    path: path.to_path_buf(),
                    found: version,
                    supported: FORMAT_VERSION,
                });
            }
            return Err(Error::format(path, "header checksum mismatch"));
        }
        if version > FORMAT_VERSION {
            return Err(Error::Version {
                path: path.to_path_buf(),
                found: version,
                supported: FORMAT_VERSION,
            });
        }
        if version == 0 {
            return Err(Error::format(path, "format version 0 is not valid"));
        }
        if version < FORMAT_VERSION {
            return Err(Error::format(
                path,
                format!(
                    "format version {version} is older than this build's {FORMAT_VERSION} (version 4 compresses a tile as one zstd frame, version 3 keeps volume photons in one layer, version 2 records no photon groups, version 1 no provenance either): emit the map again"
                ),
            ));
        }
        let mut r = ByteReader::new(&bytes[16..total - 4], path, "header");
        let photons = r.u64()?;
        let tiles = r.u32()?;
        let nbands = r.u32()? as usize;
        if nbands.saturating_mul(8) > r.remaining() {
            return Err(Error::format(
                path,
                format!("header band count {nbands} is impossible"),
            ));
        }
        let mut centers = Vec::with_capacity(nbands);
        let mut fwhm = Vec::with_capacity(nbands);
        for _ in 0..nbands {
            centers.push(r.f32()?);
            fwhm.push(r.f32()?);
        }
        let bands = BandGrid::explicit(centers, fwhm)
            .map_err(|e| Error::format(path, format!("header band grid: {e}")))?;
        let bounds = r.aabb()?;
        if !bounds.is_valid() {
            return Err(Error::format(path, "header bounds are not a valid box"));
        }
        let nodes = r.u32()? as usize;
        if nodes.saturating_mul(5) > r.remaining() {
            return Err(Error::format(
                path,
                format!("header partition of {nodes} nodes does not match its length"),
            ));
        }
        let mut partition = Vec::with_capacity(nodes);
        for _ in 0..nodes {
            let axis = r.u8()?;
            let value = r.f32()?;
            partition.push(match axis {
                0..=2 => PartitionNode::Split { axis, value },
                0xff => PartitionNode::Leaf,
                _ => return Err(Error::format(path, format!("header partition axis {axis}"))),
            });
        }
        let digest: [u8; 32] = r.bytes(32)?.try_into().expect("32 bytes");
        let record_len = r.u32()? as usize;
        let record = std::str::from_utf8(r.bytes(record_len)?)
            .map_err(|_| Error::format(path, "header provenance record is not UTF-8"))?
            .to_string();
        let metadata = Section {
            offset: r.u64()?,
            length: r.u64()?,
            crc: r.u32()?,
        };
        if r.remaining() != 0 {
            return Err(Error::format(
                path,
                format!("header has {} unexpected trailing bytes", r.remaining()),
            ));
        }
        Ok((
            Header {
                photons,
                tiles,
                bands,
                bounds,
                partition,
                provenance: Provenance { digest, record },
                metadata,
            },
            total,
        ))
    }
}

impl TileEntry {
    pub fn encode(&self, w: &mut ByteWriter) {
        w.u64(self.offset);
        w.u32(self.length);
        w.u32(self.count);
        w.aabb(&self.quant);
        w.aabb(&self.bounds);
        w.u32(self.crc);
        w.u32(self.layer);
    }

    pub fn decode(r: &mut ByteReader) -> Result<TileEntry> {
        let e = TileEntry {
            offset: r.u64()?,
            length: r.u32()?,
            count: r.u32()?,
            quant: r.aabb()?,
            bounds: r.aabb()?,
            crc: r.u32()?,
            layer: r.u32()?,
        };
        Ok(e)
    }
}

impl Footer {
    pub fn encode(&self) -> [u8; FOOTER_LEN] {
        let mut w = ByteWriter::default();
        w.u64(self.index_offset);
        w.u64(self.index_length);
        w.u32(self.tiles);
        w.u32(self.index_crc);
        w.u32(self.version);
        let crc = crc32fast::hash(&w.0);
        w.u32(crc);
        w.0.extend_from_slice(&FOOTER_MAGIC);
        w.0.try_into().expect("footer is 40 bytes")
    }

    /// Parse the last [`FOOTER_LEN`] bytes of a file.
    pub fn decode(bytes: &[u8], path: &Path) -> Result<Footer> {
        debug_assert_eq!(bytes.len(), FOOTER_LEN);
        if bytes[32..40] != FOOTER_MAGIC {
            return Err(Error::format(
                path,
                "wrong magic at the end of the file (truncated or not a map)",
            ));
        }
        let mut r = ByteReader::new(bytes, path, "footer");
        let f = Footer {
            index_offset: r.u64()?,
            index_length: r.u64()?,
            tiles: r.u32()?,
            index_crc: r.u32()?,
            version: r.u32()?,
        };
        let stored = r.u32()?;
        if crc32fast::hash(&bytes[..28]) != stored {
            return Err(Error::format(path, "footer checksum mismatch"));
        }
        if f.version > FORMAT_VERSION {
            return Err(Error::Version {
                path: path.to_path_buf(),
                found: f.version,
                supported: FORMAT_VERSION,
            });
        }
        Ok(f)
    }
}

#[cfg(test)]
mod tests;
