//! Spectral OpenEXR export of a radiance cube, in the layout of Fichet,
//! Pacanowski and Wilkie (2021, "An OpenEXR Layout for Spectral Images",
//! JCGT 10(3)): one 32-bit float channel per band, named `S0.` plus the
//! band centre in nm with a comma as the decimal mark and `nm`
//! (`S0.550,000000nm`; S0 is the unpolarised emissive component), and the
//! string attributes `spectralLayoutVersion` = "1.0" and `emissiveUnits`
//! (the cube's data units, W.m^-2.sr^-1.nm^-1). A layer that is not a
//! radiance (R_rs, in sr^-1) is reflective in the layout's terms: its
//! channels are `T.550,000000nm` and it carries no `emissiveUnits`, but a
//! `units` attribute with its data units. EXR requires channels in
//! byte order of their names, which is wavelength order while every centre
//! has the same number of digits; the mapping is computed, not assumed.
//!
//! A file may carry several such cubes as named layers (parts of a
//! multi-part file): the renderer adds the standard error ("stderr") to
//! the radiance ("radiance") when it has one.
//!
//! The file is tiled in 16 x 16 pixel tiles, the renderer's own
//! (`render::TILE_PX`), or 32 x 32 with PIZ, whose wavelet gains nothing
//! on 16 x 16 blocks ([`tile_px`]); it is written tile by tile as the
//! pixels arrive ([`ExrWriter`]): a renderer hands it each finished image
//! tile from any thread, a cube tool the windows of an ENVI cube. A tile
//! complete in every layer is compressed by the thread that completed it
//! and written by one writer thread in a fixed order (the tiles' Morton
//! order, the renderer's, layer by layer within a tile; the header's line
//! order is "unspecified", which the format allows for tiled files), so
//! the bytes are a pure function of the pixels whatever the threads'
//! timing. Memory holds the tiles in progress and those finished ahead of
//! a slower one: the renderer hands image tiles out at most
//! `render::dispatch_window` past the oldest unfinished one, which bounds
//! them (128 KiB a layer each at 128 bands and 16 pixels). Small tiles keep
//! that small at a small cost in ZIP's ratio (a rendered 40 x 36 pixel,
//! 24-band cube set: 677 kB in 16-pixel tiles, 646 kB in 64-pixel ones).
//! The file is //! written under a temporary name and renamed when complete.

use super::envi::EnviCube;
use crate::error::{Error, Result};
use crate::output::{publish, temp_beside};
use exr::block::chunk::{Chunk, CompressedBlock, CompressedTileBlock, TileCoordinates};
use exr::block::writer::ChunksWriter;
use exr::block::UncompressedBlock;
use exr::math::RoundingMode;
use exr::meta::attribute::LevelMode;
use exr::meta::header::Header;
use exr::meta::BlockDescription;
use exr::prelude::{
    AttributeValue, ChannelDescription, Compression, LineOrder, SampleType, SmallVec, Text,
    TileDescription, Vec2,
};
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::thread::JoinHandle;

/// Tile side (pixels) with ZIP or no compression: the renderer's tile
/// (`render::TILE_PX`, which asserts that the two agree).
pub const TILE: usize = 16;

/// Tile side (pixels) for `compression`: [`TILE`], or twice that with PIZ
/// (aligned groups of 2 x 2 image tiles, which finish in the same Morton
/// order as the image tiles).
pub fn tile_px(compression: ExrCompression) -> usize {
    match compression {
        ExrCompression::Piz => 2 * TILE,
        ExrCompression::None | ExrCompression::Zip => TILE,
    }
}

/// The spectral-layout channel name of an emissive band centred at `nm`.
pub fn channel_name(nm: f64) -> String {
    channel_name_with("S0", nm)
}

/// The channel name of a band centred at `nm` under `prefix` (`S0`
/// emissive, `T` reflective).
fn channel_name_with(prefix: &str, nm: f64) -> String {
    format!("{prefix}.{}nm", format!("{nm:.6}").replace('.', ","))
}

pub use crate::scene::settings::ExrCompression;

/// One layer (part) of a spectral EXR: its name, its bands' centres and
/// the data units of its values.
#[derive(Clone, Copy, Debug)]
pub struct ExrLayer<'a> {
    pub name: &'a str,
    pub wavelengths_nm: &'a [f64],
    pub units: Option<&'a str>,
}

impl<'a> ExrLayer<'a> {
    /// True for a layer that is not a radiance (no units, or units
    /// without W: R_rs in sr^-1): the layout's reflective channels.
    pub fn reflective(&self) -> bool {
        self.units.is_some_and(|u| !u.contains('W'))
    }

    /// The layer `name` holding `cube`.
    pub fn of_cube(name: &'a str, cube: &'a EnviCube) -> Self {
        ExrLayer {
            name,
            wavelengths_nm: cube.wavelengths_nm(),
            units: cube.data_units(),
        }
    }
}

/// Write `cube` as a spectral OpenEXR file at `path` (one layer, "radiance"),
/// ZIP-compressed.
pub fn write_spectral_exr(cube: &EnviCube, path: &Path) -> Result<()> {
    write_spectral_exr_layers(&[("radiance", cube)], path)
}

/// One layer's header and the bands of its channels, in channel order.
fn layer_header(
    layer: &ExrLayer,
    (w, h): (usize, usize),
    compression: ExrCompression,
) -> Result<(Header, Vec<usize>)> {
    let tile = tile_px(compression);
    let nb = layer.wavelengths_nm.len();
    let invalid = |what: String| Error::invalid("spectral EXR", what);
    if w == 0 || h == 0 || nb == 0 {
        return Err(invalid(format!(
            "cannot write an empty {w} x {h} x {nb} cube"
        )));
    }
    // Channels sorted by name; order[i] is the band of channel i.
    let mut named: Vec<(String, usize)> = layer
        .wavelengths_nm
        .iter()
        .enumerate()
        .map(|(b, &nm)| {
            let prefix = if layer.reflective() { "T" } else { "S0" };
            (channel_name_with(prefix, nm), b)
        })
        .collect();
    named.sort();
    if named.windows(2).any(|p| p[0].0 == p[1].0) {
        return Err(invalid("two bands share a centre wavelength".into()));
    }
    let order: Vec<usize> = named.iter().map(|(_, b)| *b).collect();
    let text =
        |s: &str| Text::new_or_none(s).ok_or_else(|| invalid(format!("'{s}' is not EXR text")));
    let channels: SmallVec<[ChannelDescription; 5]> = named
        .iter()
        .map(|(name, _)| Ok(ChannelDescription::new(text(name)?, SampleType::F32, false)))
        .collect::<Result<_>>()?;
    let mut header = Header::new(text(layer.name)?, Vec2(w, h), channels).with_encoding(
        match compression {
            ExrCompression::None => Compression::Uncompressed,
            ExrCompression::Zip => Compression::ZIP16,
            ExrCompression::Piz => Compression::PIZ,
        },
        BlockDescription::Tiles(TileDescription {
            tile_size: Vec2(tile, tile),
            level_mode: LevelMode::Singular,
            rounding_mode: RoundingMode::Down,
        }),
        LineOrder::Unspecified,
    );
    // The layout spells units with dots and carets.
    let units = match layer.units {
        None | Some("W m-2 sr-1 nm-1") => "W.m^-2.sr^-1.nm^-1".to_string(),
        Some(other) => other.to_string(),
    };
    // One custom attribute per map: the exr crate keeps them in hash maps
    // and writes each map in its (per-process random) order, own then
    // shared, so two in one map would make the bytes differ between runs.
    header.shared_attributes.other.insert(
        text("spectralLayoutVersion")?,
        AttributeValue::Text(text("1.0")?),
    );
    let key = if layer.reflective() {
        "units"
    } else {
        "emissiveUnits"
    };
    header
        .own_attributes
        .other
        .insert(text(key)?, AttributeValue::Text(text(&units)?));
    Ok((header, order))
}

/// Write cubes of the same size as the named layers (parts) of one
/// spectral OpenEXR file at `path`, e.g. the radiance and its standard
/// error.
pub fn write_spectral_exr_layers(layers: &[(&str, &EnviCube)], path: &Path) -> Result<()> {
    write_spectral_exr_layers_with(layers, path, ExrCompression::default())
}

/// [`write_spectral_exr_layers`] with the given (lossless) compression,
/// one EXR tile of all layers read from the cubes at a time. The bytes are
/// a pure function of the cubes and the compression.
pub fn write_spectral_exr_layers_with(
    layers: &[(&str, &EnviCube)],
    path: &Path,
    compression: ExrCompression,
) -> Result<()> {
    let Some((_, first)) = layers.first() else {
        return Err(Error::invalid("spectral EXR", "no layers to write"));
    };
    let (w, h) = (first.samples(), first.lines());
    if layers
        .iter()
        .any(|(_, c)| (c.samples(), c.lines()) != (w, h))
    {
        return Err(Error::invalid("spectral EXR", "layers of different sizes"));
    }
    let described: Vec<ExrLayer> = layers
        .iter()
        .map(|(name, cube)| ExrLayer::of_cube(name, cube))
        .collect();
    let writer = ExrWriter::create(path, &described, (w, h), compression)?;
    let tile = tile_px(compression);
    for (x0, y0) in writer.tile_origins() {
        let (tw, th) = (tile.min(w - x0), tile.min(h - y0));
        let values = layers
            .iter()
            .map(|(_, cube)| pixels_of(cube, (x0, y0, tw, th)))
            .collect::<Result<Vec<_>>>()?;
        let slices: Vec<&[f32]> = values.iter().map(Vec::as_slice).collect();
        writer.write_tile(x0, y0, tw, th, &slices)?;
    }
    writer.finish()
}

/// The `tw` x `th` pixels of `cube` at (`x0`, `y0`), bands innermost.
fn pixels_of(cube: &EnviCube, (x0, y0, tw, th): (usize, usize, usize, usize)) -> Result<Vec<f32>> {
    let nb = cube.bands();
    let mut out = vec![0.0; tw * th * nb];
    for b in 0..nb {
        for (i, v) in cube.window(b, x0, y0, tw, th)?.into_iter().enumerate() {
            out[i * nb + b] = v;
        }
    }
    Ok(out)
}

/// Complete tiles waiting for the writer thread at most.
pub const CHANNEL_TILES: usize = 2;

/// The chunks of one complete EXR tile (each with its index in its
/// layer's offset table), tagged with the tile's place in the write order.
type TileChunks = (usize, Vec<(usize, Chunk)>);

/// An EXR tile whose pixels are arriving: per layer the block's data
/// (per line, per channel, the line's samples), and the pixels still
/// missing.
struct Pending {
    layers: Vec<Vec<f32>>,
    missing: usize,
}

/// A spectral OpenEXR file being written tile by tile, from any thread, in
/// any order (see the module docs).
pub struct ExrWriter {
    path: PathBuf,
    headers: Vec<Header>,
    /// Per layer, the channel of each band.
    channel_of: Vec<Vec<usize>>,
    size: (usize, usize),
    /// Tile side (pixels).
    tile: usize,
    tiles_x: usize,
    /// Per EXR tile (row-major), its place in the write order.
    rank: Vec<usize>,
    pending: Mutex<HashMap<usize, Pending>>,
    sender: Option<crossbeam_channel::Sender<TileChunks>>,
    thread: Option<JoinHandle<Result<tempfile::NamedTempFile>>>,
}

impl ExrWriter {
    /// Start a `w` x `h` file at `path` with `layers` (under a temporary
    /// name until [`ExrWriter::finish`]).
    pub fn create(
        path: &Path,
        layers: &[ExrLayer],
        (w, h): (usize, usize),
        compression: ExrCompression,
    ) -> Result<ExrWriter> {
        if layers.is_empty() {
            return Err(Error::invalid("spectral EXR", "no layers to write"));
        }
        let mut headers: SmallVec<[Header; 3]> = SmallVec::new();
        let mut channel_of = Vec::new();
        for layer in layers {
            let (header, order) = layer_header(layer, (w, h), compression)?;
            let mut of = vec![0; order.len()];
            for (c, &b) in order.iter().enumerate() {
                of[b] = c;
            }
            headers.push(header);
            channel_of.push(of);
        }
        let tile = tile_px(compression);
        let (tiles_x, tiles_y) = (w.div_ceil(tile), h.div_ceil(tile));
        let mut order: Vec<(u128, usize)> = (0..tiles_y)
            .flat_map(|ty| {
                (0..tiles_x).map(move |tx| {
                    let morton = crate::morton::morton3_wide([tx as u64, ty as u64, 0]);
                    (morton, ty * tiles_x + tx)
                })
            })
            .collect();
        order.sort_unstable();
        let mut rank = vec![0; order.len()];
        for (place, &(_, tile)) in order.iter().enumerate() {
            rank[tile] = place;
        }
        let tmp = temp_beside(path)?;
        // Bounded: a thread whose tile is ready waits while the writer is behind.
        let (sender, receiver) = crossbeam_channel::bounded::<TileChunks>(CHANNEL_TILES);
        let tiles = order.len();
        let file_headers = headers.clone();
        let thread_path = path.to_path_buf();
        let thread = std::thread::Builder::new()
            .name("exr-writer".into())
            .spawn(move || write_in_order(tmp, file_headers, receiver, tiles, &thread_path))
            .map_err(|e| Error::io(path, "start a writer thread for", e))?;
        Ok(ExrWriter {
            path: path.to_path_buf(),
            headers: headers.into_vec(),
            channel_of,
            size: (w, h),
            tile,
            tiles_x,
            rank,
            pending: Mutex::new(HashMap::new()),
            sender: Some(sender),
            thread: Some(thread),
        })
    }

    /// The pixel origins of the file's tiles, in its write order (the
    /// order in which one caller fills them best).
    pub fn tile_origins(&self) -> Vec<(usize, usize)> {
        let mut by_rank = vec![(0, 0); self.rank.len()];
        for (tile, &place) in self.rank.iter().enumerate() {
            by_rank[place] = (
                (tile % self.tiles_x) * self.tile,
                (tile / self.tiles_x) * self.tile,
            );
        }
        by_rank
    }

    /// Write the `tw` x `th` pixels at (`x0`, `y0`) of every layer: one
    /// slice per layer, pixel by pixel with the layer's bands innermost.
    /// Each pixel is written once.
    pub fn write_tile(
        &self,
        x0: usize,
        y0: usize,
        tw: usize,
        th: usize,
        layers: &[&[f32]],
    ) -> Result<()> {
        let (w, h) = self.size;
        let sizes_fit = layers.len() == self.headers.len()
            && layers
                .iter()
                .zip(&self.channel_of)
                .all(|(v, of)| v.len() == tw * th * of.len());
        if !sizes_fit || x0 + tw > w || y0 + th > h {
            return Err(Error::invalid(
                format!("spectral EXR {}", self.path.display()),
                format!("a {tw} x {th} tile at ({x0}, {y0}) does not fit the layers"),
            ));
        }
        let t = self.tile;
        for ty in y0 / t..(y0 + th).div_ceil(t) {
            for tx in x0 / t..(x0 + tw).div_ceil(t) {
                self.fill(tx, ty, (x0, y0, tw, th), layers)?;
            }
        }
        Ok(())
    }

    /// Copy the part of a rectangle of pixels that falls in EXR tile
    /// (`tx`, `ty`); send the tile to the writer once it is complete.
    fn fill(
        &self,
        tx: usize,
        ty: usize,
        (x0, y0, tw, th): (usize, usize, usize, usize),
        layers: &[&[f32]],
    ) -> Result<()> {
        let (w, h) = self.size;
        let (bx, by) = (tx * self.tile, ty * self.tile);
        let (bw, bh) = (self.tile.min(w - bx), self.tile.min(h - by));
        let (xa, xb) = (x0.max(bx), (x0 + tw).min(bx + bw));
        let (ya, yb) = (y0.max(by), (y0 + th).min(by + bh));
        let tile = ty * self.tiles_x + tx;
        let complete = {
            let mut pending = self.pending.lock().unwrap_or_else(|e| e.into_inner());
            let p = pending.entry(tile).or_insert_with(|| Pending {
                layers: self
                    .channel_of
                    .iter()
                    .map(|of| vec![0.0; bw * bh * of.len()])
                    .collect(),
                missing: bw * bh,
            });
            for ((data, values), of) in p.layers.iter_mut().zip(layers).zip(&self.channel_of) {
                let nb = of.len();
                for y in ya..yb {
                    for x in xa..xb {
                        let src = ((y - y0) * tw + (x - x0)) * nb;
                        for (b, &c) in of.iter().enumerate() {
                            data[((y - by) * nb + c) * bw + (x - bx)] = values[src + b];
                        }
                    }
                }
            }
            p.missing = p.missing.saturating_sub((xb - xa) * (yb - ya));
            if p.missing == 0 {
                pending.remove(&tile)
            } else {
                None
            }
        };
        let Some(done) = complete else {
            return Ok(());
        };
        let mut chunks = Vec::with_capacity(done.layers.len());
        for (layer, data) in done.layers.into_iter().enumerate() {
            if self.headers[layer].compression == Compression::ZIP16 {
                let chunk = Chunk {
                    layer_index: layer,
                    compressed_block: CompressedBlock::Tile(CompressedTileBlock {
                        coordinates: TileCoordinates {
                            tile_index: Vec2(tx, ty),
                            level_index: Vec2(0, 0),
                        },
                        compressed_pixels_le: zip_block(&data),
                    }),
                };
                chunks.push((tile, chunk));
                continue;
            }
            let block = UncompressedBlock {
                index: exr::block::BlockIndex {
                    layer,
                    pixel_position: Vec2(bx, by),
                    pixel_size: Vec2(bw, bh),
                    level: Vec2(0, 0),
                },
                data: data.iter().flat_map(|v| v.to_ne_bytes()).collect(),
            };
            let chunk = block
                .compress_to_chunk(&self.headers)
                .map_err(|e| self.exr_error(e))?;
            chunks.push((tile, chunk));
        }
        let sent = self
            .sender
            .as_ref()
            .is_some_and(|s| s.send((self.rank[tile], chunks)).is_ok());
        if sent {
            Ok(())
        } else {
            // The writer thread stopped: `finish` reports why.
            Err(self.stopped())
        }
    }

    fn exr_error(&self, e: exr::error::Error) -> Error {
        Error::io(&self.path, "write", std::io::Error::other(e.to_string()))
    }

    /// The writer thread's own error, once it has stopped.
    fn stopped(&self) -> Error {
        Error::io(
            &self.path,
            "write",
            std::io::Error::other("the EXR writer stopped"),
        )
    }

    /// Wait for every tile to be written, complete the file and rename it
    /// into place. A pixel never written is an error.
    pub fn finish(mut self) -> Result<()> {
        drop(self.sender.take());
        let thread = self.thread.take().ok_or_else(|| self.stopped())?;
        let tmp = thread.join().map_err(|_| self.stopped())??;
        publish(tmp, &self.path)
    }
}

/// The deflate level of ZIP blocks. A float sample's low mantissa bytes
/// are noise that no level compresses: on the built-in scene's cubes
/// level 1 (miniz's fast greedy matcher) leaves the radiance 98.2 % of its
/// size against 93.6 % at level 4 (what the exr crate writes), in about a
/// quarter of the CPU time (`benches/README.md`, "Rendering").
const ZIP_LEVEL: u8 = 1;

/// One tile's pixels (`f32` samples, laid out as the file stores them)
/// as a ZIP block of OpenEXR: the little-endian bytes split into those at
/// even and at odd offsets, each byte replaced by its difference from the
/// one before plus 128 (mod 256), deflated in a zlib stream; the raw
/// bytes where that is no smaller, as the format says.
fn zip_block(samples: &[f32]) -> Vec<u8> {
    let raw: Vec<u8> = samples.iter().flat_map(|v| v.to_le_bytes()).collect();
    let half = raw.len().div_ceil(2);
    let mut split = vec![0u8; raw.len()];
    for (i, &b) in raw.iter().enumerate() {
        split[(i % 2) * half + i / 2] = b;
    }
    let mut previous = split.first().copied().unwrap_or(0);
    for b in split.iter_mut().skip(1) {
        let here = *b;
        *b = here.wrapping_sub(previous).wrapping_add(128);
        previous = here;
    }
    let deflated = miniz_oxide::deflate::compress_to_vec_zlib(&split, ZIP_LEVEL);
    if deflated.len() < raw.len() {
        deflated
    } else {
        raw
    }
}

impl Drop for ExrWriter {
    /// An unfinished file is abandoned: the writer thread sees the channel
    /// close early and stops; its temporary file is removed.
    fn drop(&mut self) {
        drop(self.sender.take());
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// The writer thread: write each tile's chunks in the order of their
/// places (holding those that arrive early), then complete the file.
fn write_in_order(
    tmp: tempfile::NamedTempFile,
    headers: SmallVec<[Header; 3]>,
    receiver: crossbeam_channel::Receiver<TileChunks>,
    tiles: usize,
    path: &Path,
) -> Result<tempfile::NamedTempFile> {
    let exr_error =
        |e: exr::error::Error| Error::io(path, "write", std::io::Error::other(e.to_string()));
    let mut missing = false;
    let written = {
        let out = std::io::BufWriter::new(tmp.as_file());
        exr::block::write(out, headers, true, |_, writer| {
            let mut early: BTreeMap<usize, Vec<(usize, Chunk)>> = BTreeMap::new();
            let mut next = 0;
            for (place, chunks) in receiver.iter() {
                early.insert(place, chunks);
                while let Some(chunks) = early.remove(&next) {
                    for (index, chunk) in chunks {
                        writer.write_chunk(index, chunk)?;
                    }
                    next += 1;
                }
            }
            if next < tiles {
                missing = true;
                return Err(exr::error::Error::Aborted);
            }
            Ok(())
        })
    };
    if missing {
        return Err(Error::invalid(
            format!("spectral EXR {}", path.display()),
            "some pixels were never written",
        ));
    }
    written.map_err(exr_error)?;
    Ok(tmp)
}

#[cfg(test)]
mod tests;
