use super::*;
use crate::cube::envi::{CubeSpec, EnviWriter};
use crate::spectral::BandGrid;
use exr::prelude::{read_all_flat_layers_from_file, AnyChannels, FlatSamples, Layer};

/// The f32 samples of the channel of the band centred at `nm` in `layer`.
fn band_samples(layer: &Layer<AnyChannels<FlatSamples>>, nm: f64) -> &[f32] {
    let name = channel_name(nm);
    let channel = layer
        .channel_data
        .list
        .iter()
        .find(|c| c.name == Text::new_or_none(&name).unwrap())
        .unwrap_or_else(|| panic!("no channel {name}"));
    let FlatSamples::F32(samples) = &channel.sample_data else {
        panic!("{name} is not f32");
    };
    samples
}

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
        band_names: Vec::new(),
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
    let hdr = writer.finish().unwrap().hdr;
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
        let samples = band_samples(layer, *nm as f64);
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
        band_names: Vec::new(),
    };
    let writer = EnviWriter::create(dir.path(), "c", spec).unwrap();
    writer.write_tile(0, 0, 2, 2, &[1.0; 8]).unwrap();
    let hdr = writer.finish().unwrap().hdr;
    let cube = EnviCube::open(&hdr).unwrap();
    let target = dir.path().join("missing").join("c.exr");
    let e = write_spectral_exr(&cube, &target).unwrap_err().to_string();
    assert!(e.contains("c.exr"), "{e}");
    let as_dir = dir.path().join("d.exr");
    std::fs::create_dir(&as_dir).unwrap();
    assert!(write_spectral_exr(&cube, &as_dir).is_err());
}

/// Two cubes as two named layers of one file: each reads back under its
/// layer name with its own values; cubes of different sizes are refused.
#[test]
fn layers_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let bands = BandGrid::explicit(vec![500.0, 600.0], vec![10.0; 2]).unwrap();
    let (w, h) = (67usize, 3usize);
    let cube = |name: &str, scale: f32, w: usize| {
        let spec = CubeSpec {
            samples: w,
            lines: h,
            bands: bands.clone(),
            description: "test".into(),
            data_units: "W m-2 sr-1 nm-1".into(),
            band_names: Vec::new(),
        };
        let writer = EnviWriter::create(dir.path(), name, spec).unwrap();
        let tile: Vec<f32> = (0..w * h * 2).map(|i| scale * i as f32).collect();
        writer.write_tile(0, 0, w, h, &tile).unwrap();
        EnviCube::open(&writer.finish().unwrap().hdr).unwrap()
    };
    let (a, b) = (cube("a", 1.0, w), cube("b", -2.0, w));
    let path = dir.path().join("two.exr");
    write_spectral_exr_layers(&[("radiance", &a), ("stderr", &b)], &path).unwrap();
    let image = read_all_flat_layers_from_file(&path).unwrap();
    assert_eq!(image.layer_data.len(), 2);
    for (layer, (name, scale)) in image
        .layer_data
        .iter()
        .zip([("radiance", 1.0f32), ("stderr", -2.0)])
    {
        assert_eq!(
            layer.attributes.layer_name,
            Some(Text::new_or_none(name).unwrap())
        );
        let channel = &layer.channel_data.list[1]; // S0.600,000000nm: band 1
        let FlatSamples::F32(samples) = &channel.sample_data else {
            panic!("not f32");
        };
        for y in 0..h {
            for x in 0..w {
                // BSQ tile order above: index (y * w + x) * 2 + band.
                let want = scale * ((y * w + x) * 2 + 1) as f32;
                assert_eq!(samples[y * w + x], want, "{name} at ({x}, {y})");
            }
        }
    }
    let c = cube("c", 1.0, w + 1);
    assert!(write_spectral_exr_layers(&[("radiance", &a), ("stderr", &c)], &path).is_err());
}

/// Every compression is lossless and reads back; ZIP and PIZ shrink a
/// smooth cube, and each gives the same bytes twice.
#[test]
fn compressions_are_lossless() {
    let dir = tempfile::tempdir().unwrap();
    let bands = BandGrid::even(400.0, 700.0, 8).unwrap();
    let (w, h) = (96usize, 80usize);
    let spec = CubeSpec {
        samples: w,
        lines: h,
        bands,
        description: "test".into(),
        data_units: "W m-2 sr-1 nm-1".into(),
        band_names: Vec::new(),
    };
    let value = |x: usize, y: usize, b: usize| 0.01 + 1e-4 * (x + y) as f32 + 1e-3 * b as f32;
    let writer = EnviWriter::create(dir.path(), "c", spec).unwrap();
    let tile: Vec<f32> = (0..h)
        .flat_map(|y| (0..w).flat_map(move |x| (0..8).map(move |b| value(x, y, b))))
        .collect();
    writer.write_tile(0, 0, w, h, &tile).unwrap();
    let cube = EnviCube::open(&writer.finish().unwrap().hdr).unwrap();
    let mut sizes = Vec::new();
    for c in [
        ExrCompression::None,
        ExrCompression::Zip,
        ExrCompression::Piz,
    ] {
        let path = dir.path().join(format!("{c:?}.exr"));
        write_spectral_exr_layers_with(&[("radiance", &cube)], &path, c).unwrap();
        let again = dir.path().join(format!("{c:?}-again.exr"));
        write_spectral_exr_layers_with(&[("radiance", &cube)], &again, c).unwrap();
        assert_eq!(
            std::fs::read(&path).unwrap(),
            std::fs::read(&again).unwrap()
        );
        sizes.push(std::fs::metadata(&path).unwrap().len());
        let image = read_all_flat_layers_from_file(&path).unwrap();
        let layer = &image.layer_data[0];
        for (b, nm) in cube.wavelengths_nm().iter().enumerate() {
            let s = band_samples(layer, *nm);
            for y in 0..h {
                for x in 0..w {
                    assert_eq!(s[y * w + x], value(x, y, b), "{c:?} band {b} at ({x}, {y})");
                }
            }
        }
    }
    assert!(
        sizes[1] < sizes[0] && sizes[2] < sizes[0],
        "sizes {sizes:?}"
    );
}

/// Two layers of a 150 x 70 image streamed as 16 x 16 tiles from four
/// threads in reverse order, with ZIP (16-pixel EXR tiles) and PIZ (32,
/// filled by four image tiles each): the bytes equal those of the same
/// pixels written by one thread in order, and every value reads back
/// under its layer and band.
#[test]
fn tiles_in_any_order_from_any_thread_give_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (150usize, 70usize);
    let nm = [450.0, 550.0, 650.0];
    let layers = [
        ExrLayer {
            name: "radiance",
            wavelengths_nm: &nm,
            units: None,
        },
        ExrLayer {
            name: "stderr",
            wavelengths_nm: &nm,
            units: None,
        },
    ];
    let value = |l: usize, x: usize, y: usize, b: usize| {
        (l * 100_000 + y * 1000 + x) as f32 + 0.25 * b as f32
    };
    let tiles: Vec<(usize, usize)> = (0..h.div_ceil(16))
        .flat_map(|j| (0..w.div_ceil(16)).map(move |i| (i * 16, j * 16)))
        .collect();
    let write = |path: &std::path::Path, order: &[(usize, usize)], threads: usize, c| {
        let writer = ExrWriter::create(path, &layers, (w, h), c).unwrap();
        let chunk = order.len().div_ceil(threads);
        std::thread::scope(|s| {
            for part in order.chunks(chunk) {
                let writer = &writer;
                s.spawn(move || {
                    for &(x0, y0) in part {
                        let (tw, th) = (16.min(w - x0), 16.min(h - y0));
                        let values: Vec<Vec<f32>> = (0..2)
                            .map(|l| {
                                (0..th)
                                    .flat_map(|y| {
                                        (0..tw).flat_map(move |x| {
                                            (0..3).map(move |b| value(l, x0 + x, y0 + y, b))
                                        })
                                    })
                                    .collect()
                            })
                            .collect();
                        writer
                            .write_tile(x0, y0, tw, th, &[&values[0], &values[1]])
                            .unwrap();
                    }
                });
            }
        });
        writer.finish().unwrap();
        std::fs::read(path).unwrap()
    };
    for c in [ExrCompression::Zip, ExrCompression::Piz] {
        let in_order = write(&dir.path().join("a.exr"), &tiles, 1, c);
        let reversed: Vec<_> = tiles.iter().rev().copied().collect();
        let shuffled = write(&dir.path().join("b.exr"), &reversed, 4, c);
        assert!(
            in_order == shuffled,
            "{c:?}: the bytes depend on the write order"
        );

        let image = read_all_flat_layers_from_file(dir.path().join("b.exr")).unwrap();
        assert_eq!(image.layer_data.len(), 2);
        for (l, layer) in image.layer_data.iter().enumerate() {
            for (b, &nm) in nm.iter().enumerate() {
                let s = band_samples(layer, nm);
                for y in 0..h {
                    for x in 0..w {
                        let want = value(l, x, y, b);
                        assert_eq!(s[y * w + x], want, "{c:?} layer {l} band {b} at ({x}, {y})");
                    }
                }
            }
        }
    }
}

/// A file with pixels never written is refused at `finish`, naming the
/// file, and leaves nothing under its name or a temporary one; a tile
/// that does not fit is refused as it is written.
#[test]
fn unwritten_pixels_and_misfit_tiles_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("part.exr");
    let nm = [500.0];
    let layer = ExrLayer {
        name: "radiance",
        wavelengths_nm: &nm,
        units: None,
    };
    let writer = ExrWriter::create(&path, &[layer], (100, 10), ExrCompression::None).unwrap();
    writer.write_tile(0, 0, 64, 10, &[&[1.0; 640]]).unwrap();
    assert!(writer.write_tile(90, 0, 16, 10, &[&[1.0; 160]]).is_err());
    assert!(writer.write_tile(64, 0, 36, 10, &[&[1.0; 10]]).is_err());
    let e = writer.finish().unwrap_err().to_string();
    assert!(e.contains("part.exr") && e.contains("never written"), "{e}");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

/// A ZIP block that deflate cannot shrink (float noise down to the
/// exponent) is stored raw, as OpenEXR requires: readers take a block of
/// the raw size for an uncompressed one. A smooth one is deflated and
/// reads back through miniz's inflate and the inverse of the byte split
/// and differences.
#[test]
fn zip_blocks_are_raw_where_deflate_does_not_shrink_them() {
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let noise: Vec<f32> = (0..16 * 16 * 8)
        .map(|_| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            f32::from_bits((state >> 32) as u32)
        })
        .collect();
    let raw: Vec<u8> = noise.iter().flat_map(|v| v.to_le_bytes()).collect();
    assert_eq!(zip_block(&noise), raw);

    let smooth: Vec<f32> = (0..16 * 16 * 8).map(|i| 0.01 + 1e-6 * i as f32).collect();
    let block = zip_block(&smooth);
    let raw: Vec<u8> = smooth.iter().flat_map(|v| v.to_le_bytes()).collect();
    assert!(
        block.len() < raw.len() / 2,
        "{} of {} bytes",
        block.len(),
        raw.len()
    );
    let mut split = miniz_oxide::inflate::decompress_to_vec_zlib(&block).unwrap();
    for i in 1..split.len() {
        split[i] = split[i].wrapping_add(split[i - 1]).wrapping_sub(128);
    }
    let half = raw.len().div_ceil(2);
    let back: Vec<u8> = (0..raw.len())
        .map(|i| split[(i % 2) * half + i / 2])
        .collect();
    assert_eq!(back, raw);
}
