//! Opening a map file: memory-mapped, fully validated before any blob is used.
//!
//! `open` checks, in order: that the path is a regular file long enough to
//! hold a header and a footer; the header magic; the footer (magic,
//! checksum, version); that the index lies exactly between the blobs and the
//! footer and matches its checksum; the header (checksum, version); and that
//! the tile entries tile the blob region exactly, with photon counts adding
//! up. Blob checksums are checked when a tile is decoded.
//!
//! The mapping is read-only; littoral never modifies a published map (a map
//! truncated by another process while mapped would raise SIGBUS — maps are
//! written under a temporary name and renamed, so littoral itself never
//! does that).

use super::codec::{TileDecoder, RECORD_BYTES};
use super::format::*;
use crate::bounds::Aabb;
use crate::error::{Error, Result};
use crate::photon::{PackedPhoton, LAYERS};
use memmap2::Mmap;
use std::fs::File;
use std::path::{Path, PathBuf};

/// An open, validated map file.
pub struct MapFile {
    path: PathBuf,
    mmap: Mmap,
    header: Header,
    tiles: Vec<TileEntry>,
}

impl std::fmt::Debug for MapFile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MapFile")
            .field("path", &self.path)
            .field("photons", &self.header.photons)
            .field("tiles", &self.tiles.len())
            .finish()
    }
}

impl MapFile {
    /// Open and validate the map at `path`.
    pub fn open(path: impl AsRef<Path>) -> Result<MapFile> {
        let path = path.as_ref();
        let meta = std::fs::metadata(path).map_err(|e| Error::io(path, "open", e))?;
        if meta.is_dir() {
            return Err(Error::format(path, "is a directory"));
        }
        let len = meta.len();
        let min = (MIN_HEADER_LEN + FOOTER_LEN) as u64;
        if len < min {
            return Err(Error::format(
                path,
                format!("file is {len} bytes, shorter than the smallest map ({min} bytes)"),
            ));
        }
        let file = File::open(path).map_err(|e| Error::io(path, "open", e))?;
        // SAFETY: the map is opened read-only and littoral never writes to a
        // published map (it writes new files under temporary names). Another
        // process truncating the file while mapped is outside what we guard.
        let mmap = unsafe { Mmap::map(&file) }.map_err(|e| Error::io(path, "map", e))?;
        let bytes = &mmap[..];
        if bytes.len() as u64 != len {
            return Err(Error::format(path, "file changed size while opening"));
        }
        if super::shard::is_shard_magic(&bytes[..8]) {
            return Err(Error::format(
                path,
                "this is one shard of a sharded emission, not a map: merge the shards with `littoral map merge`",
            ));
        }
        if bytes[..8] != HEADER_MAGIC {
            return Err(Error::format(path, "wrong magic at the start of the file"));
        }
        let footer = Footer::decode(&bytes[bytes.len() - FOOTER_LEN..], path)?;
        let footer_start = len - FOOTER_LEN as u64;
        if footer.index_length != footer.tiles as u64 * INDEX_ENTRY_LEN as u64
            || footer.index_offset.checked_add(footer.index_length) != Some(footer_start)
        {
            return Err(Error::format(
                path,
                format!(
                    "footer places an index of {} tiles at {}+{} in a file of {len} bytes",
                    footer.tiles, footer.index_offset, footer.index_length
                ),
            ));
        }
        let index = &bytes[footer.index_offset as usize..footer_start as usize];
        if crc32fast::hash(index) != footer.index_crc {
            return Err(Error::format(path, "index checksum mismatch"));
        }
        let (header, header_len) = Header::decode(&bytes[..footer.index_offset as usize], path)?;
        if header.tiles != footer.tiles {
            return Err(Error::format(
                path,
                format!(
                    "header says {} tiles, footer {}",
                    header.tiles, footer.tiles
                ),
            ));
        }
        let (tiles, expect, photons) = read_index(index, path, footer.tiles, header_len as u64)?;
        let meta = header.metadata;
        if expect != meta.offset
            || meta.offset.checked_add(meta.length) != Some(footer.index_offset)
        {
            return Err(Error::format(
                path,
                format!(
                    "tile blobs end at {expect}, the metadata lies at {}+{} and the index starts at {}",
                    meta.offset, meta.length, footer.index_offset
                ),
            ));
        }
        if crc32fast::hash(&bytes[meta.offset as usize..footer.index_offset as usize]) != meta.crc {
            return Err(Error::format(path, "metadata checksum mismatch"));
        }
        if photons != header.photons {
            return Err(Error::format(
                path,
                format!(
                    "tiles hold {photons} photons, header says {}",
                    header.photons
                ),
            ));
        }
        // Queries touch tiles in no particular order; read-ahead would waste I/O.
        let _ = mmap.advise(memmap2::Advice::Random);
        Ok(MapFile {
            path: path.to_path_buf(),
            mmap,
            header,
            tiles,
        })
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The header.
    pub fn header(&self) -> &Header {
        &self.header
    }

    /// The index, one entry per tile.
    pub fn tiles(&self) -> &[TileEntry] {
        &self.tiles
    }

    /// Size of the file in bytes.
    pub fn file_bytes(&self) -> u64 {
        self.mmap.len() as u64
    }

    /// What the producer recorded at the end of the build (for an emitted
    /// map, the emission report as JSON); empty if nothing.
    pub fn metadata(&self) -> &[u8] {
        let m = self.header.metadata;
        &self.mmap[m.offset as usize..(m.offset + m.length) as usize]
    }

    /// The compressed bytes of tile `t`.
    pub fn blob(&self, t: u32) -> &[u8] {
        let e = &self.tiles[t as usize];
        &self.mmap[e.offset as usize..e.offset as usize + e.length as usize]
    }

    /// Check and decode tile `t` into `out`; photon bands are checked
    /// against the band grid.
    pub fn decode_tile(
        &self,
        t: u32,
        decoder: &mut TileDecoder,
        out: &mut Vec<PackedPhoton>,
    ) -> Result<()> {
        let e = &self.tiles[t as usize];
        // The map is mapped for random access (no read-ahead), so a tile
        // whose pages are not resident would be read a page per fault, each
        // waiting on the disk in turn; asking for the whole blob first
        // makes that one read. Advice only: failure changes nothing.
        #[cfg(unix)]
        let _ = self.mmap.advise_range(
            memmap2::Advice::WillNeed,
            e.offset as usize,
            e.length as usize,
        );
        let decoded = decoder
            .decode(self.blob(t), e, out)
            .map_err(|err| Error::tile(&self.path, t, err.to_string()));
        self.release_pages(e.offset as usize, e.length as usize);
        decoded?;
        let nbands = self.header.bands.len();
        if let Some(p) = out.iter().find(|p| p.band() as usize >= nbands) {
            return Err(Error::tile(
                &self.path,
                t,
                format!("photon band {} outside the {nbands}-band grid", p.band()),
            ));
        }
        Ok(())
    }

    /// Drop the pages wholly inside `len` bytes at `offset` from the
    /// process's mapping, once a tile there is decoded: they stay in the
    /// page cache (a tile decoded again faults them back in without a disk
    /// read), but no longer count in the process's resident set. Without
    /// this a render's resident set grows by every tile it has ever
    /// decoded, the whole map in the end, over the anonymous memory the
    /// budget bounds: a scheduler that enforces memory by RSS would kill a
    /// run that keeps its budget. Pages shared with a neighbouring tile stay.
    fn release_pages(&self, offset: usize, len: usize) {
        #[cfg(target_os = "linux")]
        {
            // SAFETY: sysconf has no preconditions.
            let page = match unsafe { libc::sysconf(libc::_SC_PAGESIZE) } {
                p if p > 0 => p as usize,
                _ => return,
            };
            let start = offset.next_multiple_of(page);
            let end = (offset + len) / page * page;
            if end > start {
                // SAFETY: the map is a read-only shared mapping of a file
                // that no one writes while it is open (its checksums are
                // checked on every decode): pages dropped here read back
                // the same bytes on the next access, so a slice borrowed
                // from them elsewhere sees no change. Advice only: failure
                // changes nothing.
                let _ = unsafe {
                    self.mmap.unchecked_advise_range(
                        memmap2::UncheckedAdvice::DontNeed,
                        start,
                        end - start,
                    )
                };
            }
        }
        #[cfg(not(target_os = "linux"))]
        let _ = (offset, len);
    }
}

/// What `littoral map info` prints.
#[derive(Clone, Debug, serde::Serialize)]
pub struct MapInfo {
    pub path: String,
    pub format_version: u32,
    pub photons: u64,
    /// Photons stored at scattering events in the water.
    pub volume_photons: u64,
    /// Photons stored on the floor and targets.
    pub surface_photons: u64,
    pub tiles: u32,
    pub bands: usize,
    pub bands_nm: Vec<f32>,
    pub file_bytes: u64,
    pub bytes_per_photon: f64,
    pub bounds: Aabb,
    pub partition_cells: usize,
    pub largest_tile_photons: u32,
    pub smallest_tile_photons: u32,
    /// What the photons were made from (the digest and the inputs).
    pub provenance: serde_json::Value,
    /// Bytes of metadata the producer recorded (the emission report).
    pub metadata_bytes: u64,
}

/// What `littoral map verify` found.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct VerifyReport {
    pub tiles: u32,
    pub photons: u64,
    pub decoded_bytes: u64,
}

impl MapFile {
    /// Photons in tiles of `layer`.
    pub fn layer_photons(&self, layer: u16) -> u64 {
        self.tiles
            .iter()
            .filter(|t| t.layer == layer as u32)
            .map(|t| t.count as u64)
            .sum()
    }

    /// Summary of the map for `map info`.
    pub fn info(&self) -> MapInfo {
        let h = &self.header;
        MapInfo {
            path: self.path.display().to_string(),
            format_version: FORMAT_VERSION,
            photons: h.photons,
            volume_photons: crate::photon::VOLUME_LAYERS
                .iter()
                .map(|&l| self.layer_photons(l))
                .sum(),
            surface_photons: self.layer_photons(crate::photon::LAYER_SURFACE),
            tiles: h.tiles,
            bands: h.bands.len(),
            bands_nm: h.bands.centers_nm().to_vec(),
            file_bytes: self.file_bytes(),
            bytes_per_photon: self.file_bytes() as f64 / h.photons.max(1) as f64,
            bounds: h.bounds,
            partition_cells: h
                .partition
                .iter()
                .filter(|n| matches!(n, PartitionNode::Leaf))
                .count(),
            largest_tile_photons: self.tiles.iter().map(|t| t.count).max().unwrap_or(0),
            smallest_tile_photons: self.tiles.iter().map(|t| t.count).min().unwrap_or(0),
            provenance: h.provenance.record_json(),
            metadata_bytes: h.metadata.length,
        }
    }

    /// Decode every tile (in parallel) and check every checksum and every
    /// decoded position against its tile's bounds; the first bad tile (by
    /// index) is the error.
    pub fn verify(&self, progress: &dyn crate::progress::Progress) -> Result<VerifyReport> {
        use rayon::prelude::*;
        progress.stage("verify tiles", self.header.photons);
        let results: Vec<Result<u64>> = (0..self.tiles.len() as u32)
            .into_par_iter()
            .map_init(
                || (TileDecoder::default(), Vec::new()),
                |(dec, out), t| {
                    self.decode_tile(t, dec, out)?;
                    let e = &self.tiles[t as usize];
                    if let Some(p) = out.iter().find(|p| e.bounds.distance_sq(p.pos()) > 0.0) {
                        return Err(Error::tile(
                            &self.path,
                            t,
                            format!("photon at {} lies outside the tile bounds", p.pos()),
                        ));
                    }
                    progress.advance(out.len() as u64);
                    Ok(out.len() as u64)
                },
            )
            .collect();
        progress.finish();
        let mut report = VerifyReport {
            tiles: self.tiles.len() as u32,
            ..Default::default()
        };
        for r in results {
            report.photons += r?;
        }
        report.decoded_bytes = report.photons * std::mem::size_of::<PackedPhoton>() as u64;
        Ok(report)
    }

    /// Write every photon as CSV `x,y,z,dx,dy,dz,band,power`, tile by tile.
    pub fn dump_csv(&self, out: &mut dyn std::io::Write) -> std::io::Result<()> {
        writeln!(out, "x,y,z,dx,dy,dz,band,power")?;
        let mut dec = TileDecoder::default();
        let mut photons = Vec::new();
        for t in 0..self.tiles.len() as u32 {
            self.decode_tile(t, &mut dec, &mut photons)
                .map_err(std::io::Error::other)?;
            for p in photons.iter().map(PackedPhoton::unpack) {
                let (x, d) = (p.position, p.direction);
                writeln!(
                    out,
                    "{},{},{},{},{},{},{},{:e}",
                    x.x, x.y, x.z, d.x, d.y, d.z, p.band, p.power
                )?;
            }
        }
        Ok(())
    }
}

/// The map's tile index: each entry checked (blobs back to back from
/// `first_offset`, non-empty, a known layer, valid boxes, a plausible
/// size); the entries, where the last blob ends and the photons they hold.
fn read_index(
    index: &[u8],
    path: &Path,
    count: u32,
    first_offset: u64,
) -> Result<(Vec<TileEntry>, u64, u64)> {
    let mut r = ByteReader::new(index, path, "index");
    let mut tiles = Vec::with_capacity(count as usize);
    let mut expect = first_offset;
    let mut photons = 0u64;
    for t in 0..count {
        let e = TileEntry::decode(&mut r)?;
        let bad = |what: String| Error::tile(path, t, format!("index entry: {what}"));
        if e.offset != expect {
            return Err(bad(format!(
                "blob at {} where {} was expected",
                e.offset, expect
            )));
        }
        if e.count == 0 || e.length == 0 {
            return Err(bad("empty tile".into()));
        }
        if e.layer as usize >= LAYERS {
            return Err(bad(format!("layer {} is not a known layer", e.layer)));
        }
        if !e.quant.is_valid() || !e.bounds.is_valid() {
            return Err(bad("box is not valid".into()));
        }
        // A zstd frame expands at most ~128x; larger claims are corrupt.
        if e.count as u64 * RECORD_BYTES as u64 > e.length as u64 * 1024 + 4096 {
            return Err(bad(format!(
                "{} photons cannot fit in {} bytes",
                e.count, e.length
            )));
        }
        expect = e.offset + e.length as u64;
        photons += e.count as u64;
        tiles.push(e);
    }
    Ok((tiles, expect, photons))
}
