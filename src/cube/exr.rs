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

/// Write `cube` as a spectral OpenEXR file at `path`.
pub fn write_spectral_exr(cube: &EnviCube, path: &Path) -> Result<()> {
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
    let mut header = exr::meta::header::Header::new(text("radiance")?, Vec2(w, h), channels)
        .with_encoding(
            Compression::Uncompressed,
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
    let attrs = &mut header.own_attributes.other;
    attrs.insert(
        text("spectralLayoutVersion")?,
        AttributeValue::Text(text("1.0")?),
    );
    attrs.insert(text("emissiveUnits")?, AttributeValue::Text(text(&units)?));

    let tmp = temp_beside(path)?;
    let exr_error =
        |e: exr::error::Error| Error::io(path, "write", std::io::Error::other(e.to_string()));
    let mut failure: Option<Error> = None;
    {
        let out = std::io::BufWriter::new(tmp.as_file());
        let tiles: Vec<_> = header.blocks_increasing_y_order().collect();
        let headers: SmallVec<[exr::meta::header::Header; 3]> = SmallVec::from_elem(header, 1);
        exr::block::write(out, headers, true, |meta, writer| {
            use exr::block::writer::ChunksWriter;
            let mut compressor = writer.sequential_blocks_compressor(&meta);
            for (index, tile) in tiles.iter().enumerate() {
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
                        layer: 0,
                        pixel_position: Vec2(x0, y0),
                        pixel_size: Vec2(tw, th),
                        level: Vec2(0, 0),
                    },
                    data,
                };
                compressor.compress_block(index, block)?;
            }
            Ok(())
        })
        .map_err(|e| failure.take().unwrap_or_else(|| exr_error(e)))?;
    }
    publish(tmp, path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cube::envi::{CubeSpec, EnviWriter};
    use crate::spectral::BandGrid;
    use exr::prelude::{read_all_flat_layers_from_file, FlatSamples};

    /// A cube whose value encodes (x, y, band), with band centres of three
    /// and four digits (so name order is not band order) and a size that is
    /// not a multiple of the tile: every channel reads back under its
    /// spectral name with every value, and the layout attributes are set.
    #[test]
    fn round_trips_through_an_exr_reader() {
        let dir = tempfile::tempdir().unwrap();
        let centres = vec![450.0f32, 550.5, 1000.0];
        let bands = BandGrid::explicit(centres.clone(), vec![10.0; 3]).unwrap();
        let (w, h) = (70usize, 5usize);
        let spec = CubeSpec {
            samples: w,
            lines: h,
            bands,
            description: "test".into(),
            data_units: "W m-2 sr-1 nm-1".into(),
        };
        let value = |x: usize, y: usize, b: usize| (x + 100 * y) as f32 + 0.25 * b as f32;
        let writer = EnviWriter::create(dir.path(), "c", spec).unwrap();
        let mut tile = Vec::new();
        for y in 0..h {
            for x in 0..w {
                for b in 0..3 {
                    tile.push(value(x, y, b));
                }
            }
        }
        writer.write_tile(0, 0, w, h, &tile).unwrap();
        let (hdr, _) = writer.finish().unwrap();
        let path = dir.path().join("c.exr");
        write_spectral_exr(&EnviCube::open(&hdr).unwrap(), &path).unwrap();

        let image = read_all_flat_layers_from_file(&path).unwrap();
        let layer = &image.layer_data[0];
        assert_eq!((layer.size.width(), layer.size.height()), (w, h));
        let text = |s: &str| Text::new_or_none(s).unwrap();
        let attr = |k: &str| layer.attributes.other.get(&text(k)).cloned();
        assert_eq!(
            attr("spectralLayoutVersion"),
            Some(AttributeValue::Text(text("1.0")))
        );
        assert_eq!(
            attr("emissiveUnits"),
            Some(AttributeValue::Text(text("W.m^-2.sr^-1.nm^-1")))
        );
        assert_eq!(layer.channel_data.list.len(), 3);
        for (b, nm) in centres.iter().enumerate() {
            let name = channel_name(*nm as f64);
            let channel = layer
                .channel_data
                .list
                .iter()
                .find(|c| c.name == text(&name))
                .unwrap_or_else(|| panic!("no channel {name}"));
            let FlatSamples::F32(samples) = &channel.sample_data else {
                panic!("{name} is not f32");
            };
            for y in 0..h {
                for x in 0..w {
                    assert_eq!(samples[y * w + x], value(x, y, b), "{name} at ({x}, {y})");
                }
            }
        }
        assert_eq!(channel_name(550.5), "S0.550,500000nm");
        assert!(std::fs::read_dir(dir.path()).unwrap().all(|e| !e
            .unwrap()
            .file_name()
            .to_string_lossy()
            .ends_with(".partial")));
    }

    /// An unwritable destination is one error naming the file, and nothing
    /// is left behind.
    #[test]
    fn unwritable_destination_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let spec = CubeSpec {
            samples: 2,
            lines: 2,
            bands: BandGrid::even(500.0, 510.0, 2).unwrap(),
            description: "test".into(),
            data_units: "W m-2 sr-1 nm-1".into(),
        };
        let writer = EnviWriter::create(dir.path(), "c", spec).unwrap();
        writer.write_tile(0, 0, 2, 2, &[1.0; 8]).unwrap();
        let (hdr, _) = writer.finish().unwrap();
        let cube = EnviCube::open(&hdr).unwrap();
        let target = dir.path().join("missing").join("c.exr");
        let e = write_spectral_exr(&cube, &target).unwrap_err().to_string();
        assert!(e.contains("c.exr"), "{e}");
        let as_dir = dir.path().join("d.exr");
        std::fs::create_dir(&as_dir).unwrap();
        assert!(write_spectral_exr(&cube, &as_dir).is_err());
    }
}
