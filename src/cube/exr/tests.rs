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
    let hdr = writer.finish().unwrap().hdr;
    let cube = EnviCube::open(&hdr).unwrap();
    let target = dir.path().join("missing").join("c.exr");
    let e = write_spectral_exr(&cube, &target).unwrap_err().to_string();
    assert!(e.contains("c.exr"), "{e}");
    let as_dir = dir.path().join("d.exr");
    std::fs::create_dir(&as_dir).unwrap();
    assert!(write_spectral_exr(&cube, &as_dir).is_err());
}
