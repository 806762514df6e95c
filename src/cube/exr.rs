//! Spectral OpenEXR export of a radiance cube, in the layout of Fichet,
//! Pacanowski and Wilkie (2021, "An OpenEXR Layout for Spectral Images",
//! JCGT 10(3)): one 32-bit float channel per band, named `S0.` plus the
//! band centre in nm with a comma as the decimal mark and `nm`
//! (`S0.550,000000nm`; S0 is the unpolarised emissive component), and the
//! string attributes `spectralLayoutVersion` = "1.0" and `emissiveUnits`
//! (the cube's data units, W.m^-2.sr^-1.nm^-1). EXR requires channels in
//! byte order of their names, which is wavelength order while every centre
//! has the same number of digits; the mapping is computed, not assumed.
//!
//! A file may carry several such cubes as named layers (parts of a
//! multi-part file): the renderer adds the standard error ("stderr") to
//! the radiance ("radiance") when it has one.
//!
//! The file is tiled (64 x 64 pixels, uncompressed: noisy float radiance
//! barely compresses) and written tile by tile from the ENVI cube with
//! positioned reads, so memory holds one tile of all bands (2 MiB at 128
//! bands) whatever the cube's size. It is written under a temporary name
//! and renamed when complete.

use super::envi::EnviCube;
use crate::error::{Error, Result};
use crate::output::{publish, temp_beside};
use exr::block::UncompressedBlock;
use exr::math::RoundingMode;
use exr::meta::attribute::LevelMode;
use exr::meta::BlockDescription;
use exr::prelude::{
    AttributeValue, ChannelDescription, Compression, LineOrder, SampleType, SmallVec, Text,
    TileDescription, Vec2,
};
use std::path::Path;

/// Tile side (pixels).
pub const TILE: usize = 64;

/// The spectral-layout channel name of a band centred at `nm`.
pub fn channel_name(nm: f64) -> String {
    format!("S0.{}nm", format!("{nm:.6}").replace('.', ","))
}

pub use crate::scene::settings::ExrCompression;

/// Write `cube` as a spectral OpenEXR file at `path` (one layer, "radiance"),
/// ZIP-compressed.
pub fn write_spectral_exr(cube: &EnviCube, path: &Path) -> Result<()> {
    write_spectral_exr_layers(&[("radiance", cube)], path)
}

/// One layer's header and the bands of its channels, in channel order.
fn layer_header(
    name: &str,
    cube: &EnviCube,
    compression: ExrCompression,
) -> Result<(exr::meta::header::Header, Vec<usize>)> {
    let (w, h, nb) = (cube.samples(), cube.lines(), cube.bands());
    let invalid = |what: String| Error::invalid("spectral EXR", what);
    if w == 0 || h == 0 || nb == 0 {
        return Err(invalid(format!(
            "cannot write an empty {w} x {h} x {nb} cube"
        )));
    }
    // Channels sorted by name; order[i] is the band of channel i.
    let mut named: Vec<(String, usize)> = cube
        .wavelengths_nm()
        .iter()
        .enumerate()
        .map(|(b, &nm)| (channel_name(nm), b))
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
    let mut header = exr::meta::header::Header::new(text(name)?, Vec2(w, h), channels)
        .with_encoding(
            match compression {
                ExrCompression::None => Compression::Uncompressed,
                ExrCompression::Zip => Compression::ZIP16,
                ExrCompression::Piz => Compression::PIZ,
            },
            BlockDescription::Tiles(TileDescription {
                tile_size: Vec2(TILE, TILE),
                level_mode: LevelMode::Singular,
                rounding_mode: RoundingMode::Down,
            }),
            LineOrder::Increasing,
        );
    // The layout spells units with dots and carets.
    let units = match cube.data_units() {
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
    header
        .own_attributes
        .other
        .insert(text("emissiveUnits")?, AttributeValue::Text(text(&units)?));
    Ok((header, order))
}

/// Write cubes of the same size as the named layers (parts) of one
/// spectral OpenEXR file at `path`, e.g. the radiance and its standard
/// error.
pub fn write_spectral_exr_layers(layers: &[(&str, &EnviCube)], path: &Path) -> Result<()> {
    write_spectral_exr_layers_with(layers, path, ExrCompression::default())
}

/// [`write_spectral_exr_layers`] with the given (lossless) compression.
/// The bytes are a pure function of the cubes and the compression.
pub fn write_spectral_exr_layers_with(
    layers: &[(&str, &EnviCube)],
    path: &Path,
    compression: ExrCompression,
) -> Result<()> {
    let invalid = |what: String| Error::invalid("spectral EXR", what);
    let Some((_, first)) = layers.first() else {
        return Err(invalid("no layers to write".into()));
    };
    let (w, h) = (first.samples(), first.lines());
    if layers
        .iter()
        .any(|(_, c)| (c.samples(), c.lines()) != (w, h))
    {
        return Err(invalid("layers of different sizes".into()));
    }
    let mut headers: SmallVec<[exr::meta::header::Header; 3]> = SmallVec::new();
    let mut orders = Vec::new();
    for (name, cube) in layers {
        let (header, order) = layer_header(name, cube, compression)?;
        headers.push(header);
        orders.push(order);
    }
    let tiles: Vec<Vec<_>> = headers
        .iter()
        .map(|h| h.blocks_increasing_y_order().collect())
        .collect();

    let tmp = temp_beside(path)?;
    let exr_error =
        |e: exr::error::Error| Error::io(path, "write", std::io::Error::other(e.to_string()));
    let mut failure: Option<Error> = None;
    {
        let out = std::io::BufWriter::new(tmp.as_file());
        exr::block::write(out, headers, true, |meta, writer| {
            use exr::block::writer::ChunksWriter;
            let mut compressor = writer.sequential_blocks_compressor(&meta);
            for (layer, ((_, cube), order)) in layers.iter().zip(&orders).enumerate() {
                for (index, tile) in tiles[layer].iter().enumerate() {
                    let (x0, y0) = (
                        tile.location.tile_index.x() * TILE,
                        tile.location.tile_index.y() * TILE,
                    );
                    let (tw, th) = (TILE.min(w - x0), TILE.min(h - y0));
                    let bands: Vec<Vec<f32>> = match order
                        .iter()
                        .map(|&b| cube.window(b, x0, y0, tw, th))
                        .collect::<Result<_>>()
                    {
                        Ok(v) => v,
                        Err(e) => {
                            failure = Some(e);
                            return Err(exr::error::Error::Aborted);
                        }
                    };
                    // Per line, per channel, the line's samples (native endian).
                    let mut data = Vec::with_capacity(tw * th * bands.len() * 4);
                    for row in 0..th {
                        for band in &bands {
                            for v in &band[row * tw..(row + 1) * tw] {
                                data.extend_from_slice(&v.to_ne_bytes());
                            }
                        }
                    }
                    let block = UncompressedBlock {
                        index: exr::block::BlockIndex {
                            layer,
                            pixel_position: Vec2(x0, y0),
                            pixel_size: Vec2(tw, th),
                            level: Vec2(0, 0),
                        },
                        data,
                    };
                    compressor.compress_block(index, block)?;
                }
            }
            Ok(())
        })
        .map_err(|e| failure.take().unwrap_or_else(|| exr_error(e)))?;
    }
    publish(tmp, path)
}

#[cfg(test)]
mod tests;
