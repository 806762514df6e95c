use super::*;

/// 5 nm bands across the whole CMF range.
fn visible() -> BandGrid {
    BandGrid::even(360.0, 830.0, 95).unwrap()
}

fn single_band(grid: &BandGrid, nm: f32) -> Vec<f32> {
    grid.centers_nm()
        .iter()
        .map(|&c| if (c - nm).abs() < 1e-3 { 1.0 } else { 0.0 })
        .collect()
}

/// A flat spectrum of 1 integrates to Y = the integral of ybar over
/// wavelength (106.86 nm for the CIE 1931 observer): the weights are a
/// quadrature of the colour-matching integral, not just a colour ratio.
#[test]
fn flat_unit_spectrum_integrates_to_the_cmf_integrals() {
    let grid = visible();
    let q = Quicklook::new(&grid);
    let xyz = q.xyz(&vec![1.0; grid.len()]);
    let (xbar, ybar, zbar) = cie_1931();
    for (got, table) in xyz.iter().zip([xbar, ybar, zbar]) {
        let want = table.integral();
        assert!(
            (f64::from(*got) / want - 1.0).abs() < 5e-3,
            "{} {got} vs {want}",
            table.name()
        );
    }
    assert!((xyz[1] - 106.86).abs() < 0.6, "{xyz:?}");
}

/// Equal-energy light is CIE illuminant E, XYZ = (1, 1, 1) once
/// normalised; its linear sRGB (D65 white) is the matrix's row sums,
/// (1.2048, 0.9483, 0.9088) — a known pinkish white, not neutral grey.
#[test]
fn equal_energy_spectrum_is_illuminant_e() {
    let grid = visible();
    let q = Quicklook::new(&grid);
    let spectrum = vec![0.02; grid.len()];
    let xyz = q.xyz(&spectrum);
    let rgb = q.rgb(&spectrum);
    for (k, want) in [1.204_784_3f32, 0.948_300_8, 0.908_842_7]
        .iter()
        .enumerate()
    {
        let got = rgb[k] / xyz[1];
        assert!(
            (got / want - 1.0).abs() < 0.02,
            "channel {k}: {got} vs {want}"
        );
    }
    // The same with a coarse 10 nm grid over 400-700 nm only.
    let coarse = BandGrid::even(400.0, 700.0, 31).unwrap();
    let q = Quicklook::new(&coarse);
    let rgb = q.rgb(&vec![1.0; coarse.len()]);
    let y = q.xyz(&vec![1.0; coarse.len()])[1];
    assert!((rgb[0] / y / 1.2048 - 1.0).abs() < 0.05, "{rgb:?}");
    assert!((rgb[2] / y / 0.9088 - 1.0).abs() < 0.05, "{rgb:?}");
}

/// Monochromatic light: 450 nm lies in the blue corner of the gamut,
/// 610 nm in the red, 530 nm in the green.
#[test]
fn narrow_bands_take_their_colour() {
    let grid = visible();
    let q = Quicklook::new(&grid);
    let blue = q.rgb(&single_band(&grid, 450.0));
    assert!(blue[2] > 4.0 * blue[0].max(blue[1]), "{blue:?}");
    let red = q.rgb(&single_band(&grid, 610.0));
    assert!(red[0] > 4.0 * red[1].max(red[2]), "{red:?}");
    let green = q.rgb(&single_band(&grid, 530.0));
    assert!(green[1] > 2.0 * green[0].max(green[2]), "{green:?}");
}

#[test]
fn invisible_bands_contribute_nothing() {
    let grid = BandGrid::explicit(vec![300.0, 550.0, 900.0, 1200.0], vec![10.0; 4]).unwrap();
    let q = Quicklook::new(&grid);
    assert!(q.has_visible_bands());
    assert_eq!(q.band_weights(0), [0.0; 3]);
    assert_ne!(q.band_weights(1), [0.0; 3]);
    assert_eq!(q.band_weights(2), [0.0; 3]);
    assert_eq!(q.band_weights(99), [0.0; 3]);
    let nir = BandGrid::even(900.0, 1000.0, 5).unwrap();
    let q = Quicklook::new(&nir);
    assert!(!q.has_visible_bands());
    assert_eq!(q.rgb(&[7.0; 5]), [0.0; 3]);
}

#[test]
fn axis_shares_split_the_gaps() {
    assert_eq!(
        axis_shares(&[400.0, 410.0, 430.0], None),
        [10.0, 15.0, 20.0]
    );
    assert_eq!(
        axis_shares(&[430.0, 400.0, 410.0], None),
        [20.0, 10.0, 15.0]
    );
    assert_eq!(axis_shares(&[500.0], Some(&[8.0])), [8.0]);
    assert_eq!(axis_shares(&[500.0], None), [1.0]);
}

fn decode(path: &Path) -> (png::OutputInfo, Vec<u8>) {
    let bytes = std::fs::read(path).unwrap();
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes))
        .read_info()
        .unwrap();
    let (w, h) = (reader.info().width as usize, reader.info().height as usize);
    let channels = reader.info().color_type.samples();
    let mut buf = vec![0; w * h * channels];
    let info = reader.next_frame(&mut buf).unwrap();
    (info, buf)
}

#[test]
fn rgb_png_decodes_with_its_size_and_exposure() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("q.png");
    let (w, h) = (7, 5);
    // Grey ramp 0..34 (luminance = value for neutral pixels), one NaN.
    let mut rgb: Vec<f32> = (0..w * h).flat_map(|i| [i as f32; 3]).collect();
    rgb[3] = f32::NAN;
    write_png(&path, w, h, &rgb, None).unwrap();
    let (info, px) = decode(&path);
    assert_eq!((info.width, info.height), (7, 5));
    assert_eq!(info.color_type, png::ColorType::Rgb);
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    assert_eq!(&px[0..3], [0, 0, 0]);
    assert_eq!(px[3], 0, "NaN is black");
    // 99th percentile of 35 values is the brightest: it maps to white.
    assert_eq!(&px[px.len() - 3..], [255, 255, 255]);
    let mid = 17 * 3;
    assert!(px[mid] == px[mid + 1] && px[mid + 1] == px[mid + 2]);

    write_png(&path, 1, 1, &[0.5, 0.5, 0.5], Some(1.0)).unwrap();
    assert_eq!(decode(&path).1, [188, 188, 188], "sRGB curve of 0.5");
    write_png(&path, 1, 1, &[-1.0, 2.0, 0.0], Some(1.0)).unwrap();
    assert_eq!(decode(&path).1, [0, 255, 0], "clipped");
}

#[test]
fn grey_png_spans_min_to_max() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g.png");
    let values = [2.0, 4.0, 3.0, f32::NAN, 6.0, 2.0];
    let range = write_grey_png(&path, 3, 2, &values).unwrap();
    assert_eq!(range, Some((2.0, 6.0)));
    let (info, px) = decode(&path);
    assert_eq!(
        (info.width, info.height, info.color_type),
        (3, 2, png::ColorType::Grayscale)
    );
    assert_eq!(px, [0, 128, 64, 0, 255, 0]);
    assert_eq!(write_grey_png(&path, 1, 1, &[f32::NAN]).unwrap(), None);
}

#[test]
fn bad_images_are_refused_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("x.png");
    assert!(write_png(&path, 2, 2, &[0.0; 11], None).is_err());
    assert!(write_png(&path, 0, 2, &[], None).is_err());
    assert!(write_png(&path, 1, 1, &[0.0; 3], Some(0.0)).is_err());
    assert!(write_png(&path, 1, 1, &[0.0; 3], Some(f32::NAN)).is_err());
    assert!(write_grey_png(&path, usize::MAX, 2, &[0.0]).is_err());
    assert!(write_grey_png(&path, 3, 1, &[0.0; 2]).is_err());
    assert!(std::fs::read_dir(dir.path()).unwrap().next().is_none());
    let e = write_png(&dir.path().join("no/such.png"), 1, 1, &[0.0; 3], None).unwrap_err();
    assert!(e.to_string().contains("no/such.png"), "{e}");
}

/// The band-at-a-time image of a cube equals the per-pixel colours.
#[test]
fn cube_rgb_matches_per_pixel_spectra() {
    use crate::cube::envi::{CubeSpec, EnviWriter};
    let dir = tempfile::tempdir().unwrap();
    let grid = BandGrid::even(420.0, 680.0, 14).unwrap();
    let (w, h, n) = (5, 3, grid.len());
    let values: Vec<f32> = (0..w * h * n)
        .map(|i| ((i * 37) % 11) as f32 * 0.01)
        .collect();
    let spec = CubeSpec {
        samples: w,
        lines: h,
        bands: grid.clone(),
        description: String::new(),
        data_units: "W m-2 sr-1 nm-1".into(),
        band_names: Vec::new(),
    };
    let writer = EnviWriter::create(dir.path(), "c", spec).unwrap();
    writer.write_tile(0, 0, w, h, &values).unwrap();
    let hdr = writer.finish().unwrap().hdr;
    let cube = EnviCube::open(&hdr).unwrap();
    let q = Quicklook::for_cube(&cube);
    assert_eq!(q, Quicklook::new(&grid));
    let image = q.cube_rgb(&cube).unwrap();
    assert_eq!(image.len(), w * h * 3);
    for (p, spectrum) in values.chunks_exact(n).enumerate() {
        let want = q.rgb(spectrum);
        for (got, want) in image[3 * p..3 * p + 3].iter().zip(want) {
            assert!(
                (got - want).abs() <= 1e-5 * want.abs().max(1.0),
                "{got} vs {want}"
            );
        }
    }
    let other = Quicklook::new(&BandGrid::even(420.0, 680.0, 3).unwrap());
    assert!(other.cube_rgb(&cube).is_err());
}

#[test]
fn auto_exposure_ignores_the_brightest_percent() {
    let mut rgb: Vec<f32> = (0..1000).flat_map(|_| [0.5; 3]).collect();
    for p in rgb.chunks_exact_mut(3).take(5) {
        p.fill(1000.0); // glints
    }
    assert!((auto_exposure(&rgb) - 2.0).abs() < 1e-4);
    assert_eq!(auto_exposure(&[0.0; 6]), 1.0);
    let sparse: Vec<f32> = (0..1000)
        .flat_map(|i| [if i == 0 { 4.0 } else { 0.0 }; 3])
        .collect();
    assert!((auto_exposure(&sparse) - 0.25).abs() < 1e-4);
}
