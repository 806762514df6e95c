//! `littoral-cube` on a small cube written by the library: the exact output
//! forms scripts rely on, and one clean line with exit 1 on bad input.

use crate::common::*;
use littoral::cube::{CubeSpec, EnviWriter};
use littoral::BandGrid;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn cube_tool(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_littoral-cube"))
        .args(args)
        .output()
        .unwrap()
}

fn stdout(out: &Output) -> String {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout.clone()).unwrap()
}

/// `diff --tol`: exit 0 within the tolerance, one clean failure line (after
/// the JSON) beyond it; a NaN in one cube only is counted and fails any
/// tolerance, while the same NaN in both agrees.
#[test]
fn diff_tolerance_and_non_finite_values() {
    let dir = tempdir();
    let hdr = small_cube(dir.path());
    let sub = dir.path().join("nan");
    std::fs::create_dir(&sub).unwrap();
    let nan = small_cube_with(&sub, |x, y, b| {
        if (x, y, b) == (2, 1, 1) {
            f32::NAN
        } else {
            value(x, y, b) + 1e-4
        }
    });
    let d = cube_tool(&["diff", p(&hdr), p(&nan), "--tol", "1e-3"]);
    let said: serde_json::Value = serde_json::from_slice(&d.stdout).unwrap();
    assert_eq!(said["non_finite_differ"], 1);
    assert_eq!(said["bands"][1]["non_finite_differ"], 1);
    assert!(
        (said["max_abs"].as_f64().unwrap() - 1e-4).abs() < 1e-6,
        "{said}"
    );
    assert_clean_failure(&d, "--tol");
    // Within tolerance: the same cube, and the same NaN on both sides.
    assert!(cube_tool(&["diff", p(&hdr), p(&hdr), "--tol", "0"])
        .status
        .success());
    assert!(cube_tool(&["diff", p(&nan), p(&nan), "--tol", "0"])
        .status
        .success());
    let same: serde_json::Value =
        serde_json::from_slice(&cube_tool(&["diff", p(&nan), p(&nan)]).stdout).unwrap();
    assert_eq!(same["bands"][1]["non_finite_same"], 1);
    // A finite difference beyond the tolerance fails too.
    let sub2 = dir.path().join("off");
    std::fs::create_dir(&sub2).unwrap();
    let off = small_cube_with(&sub2, |x, y, b| value(x, y, b) + 0.01);
    assert!(cube_tool(&["diff", p(&hdr), p(&off), "--tol", "0.02"])
        .status
        .success());
    assert_clean_failure(
        &cube_tool(&["diff", p(&hdr), p(&off), "--tol", "0.005"]),
        "--tol",
    );
    assert_clean_failure(
        &cube_tool(&["diff", p(&hdr), p(&off), "--tol", "-1"]),
        "--tol",
    );
}

/// A wavelength no band covers, and an image name that is not .png, are
/// errors, not a silent nearest band or PNG bytes under another name.
#[test]
fn band_out_of_range_and_non_png_outputs_are_refused() {
    let dir = tempdir();
    let hdr = small_cube(dir.path());
    let png = dir.path().join("b.png");
    // Bands at 450, 550, 650 nm with FWHM 100 nm: 1200 nm is no band's.
    assert_clean_failure(
        &cube_tool(&["band", p(&hdr), "1200", "--out", p(&png)]),
        "1200 nm",
    );
    assert!(!png.exists());
    assert!(cube_tool(&["band", p(&hdr), "700", "--out", p(&png)])
        .status
        .success());
    let tif = dir.path().join("q.tif");
    for args in [
        &["band", p(&hdr), "550", "--out", p(&tif)][..],
        &["quicklook", p(&hdr), "--out", p(&tif)],
    ] {
        assert_clean_failure(&cube_tool(args), "q.tif");
        assert!(!tif.exists());
    }
}

/// Value of pixel (x, y) in band b of the test cube.
fn value(x: usize, y: usize, b: usize) -> f32 {
    0.001 * (x + 10 * y) as f32 + 0.25 * b as f32
}

/// A 6 x 4 cube with bands at 450, 550, 650 nm, written as two tiles.
fn small_cube(dir: &Path) -> PathBuf {
    small_cube_with(dir, value)
}

/// The 6 x 4, 3-band cube `small` in `dir` with `value(x, y, b)` per pixel.
fn small_cube_with(dir: &Path, value: impl Fn(usize, usize, usize) -> f32 + Copy) -> PathBuf {
    let (w, h) = (6, 4);
    let bands = BandGrid::explicit(vec![450.0, 550.0, 650.0], vec![100.0; 3]).unwrap();
    let writer = EnviWriter::create(
        dir,
        "small",
        CubeSpec {
            samples: w,
            lines: h,
            bands,
            description: "tool test".into(),
            data_units: "W m-2 sr-1 nm-1".into(),
            band_names: Vec::new(),
        },
    )
    .unwrap();
    for (x0, tw) in [(4, 2), (0, 4)] {
        let values: Vec<f32> = (0..h)
            .flat_map(|y| (x0..x0 + tw).flat_map(move |x| (0..3).map(move |b| value(x, y, b))))
            .collect();
        writer.write_tile(x0, 0, tw, h, &values).unwrap();
    }
    writer.finish().unwrap().hdr
}

#[test]
fn info_spectrum_band_and_quicklook() {
    let dir = tempdir();
    let hdr = small_cube(dir.path());

    let info: serde_json::Value =
        serde_json::from_str(&stdout(&cube_tool(&["info", p(&hdr)]))).unwrap();
    assert_eq!(info["samples"], 6);
    assert_eq!(info["lines"], 4);
    assert_eq!(info["bands"], 3);
    assert_eq!(info["wavelength_nm"]["min"], 450.0);
    assert_eq!(info["wavelength_nm"]["max"], 650.0);
    assert_eq!(info["data_units"], "W m-2 sr-1 nm-1");
    assert_eq!(info["value"]["non_finite"], 0);
    let (min, max) = (value(0, 0, 0), value(5, 3, 2));
    assert_eq!(info["value"]["min"].as_f64().unwrap() as f32, min);
    assert_eq!(info["value"]["max"].as_f64().unwrap() as f32, max);
    let mean: f64 = (0..3)
        .flat_map(|b| (0..4).flat_map(move |y| (0..6).map(move |x| f64::from(value(x, y, b)))))
        .sum::<f64>()
        / 72.0;
    assert!((info["value"]["mean"].as_f64().unwrap() - mean).abs() < 1e-9);

    // The data file works as well as the header; values print exactly.
    let csv = stdout(&cube_tool(&[
        "spectrum",
        p(&hdr.with_extension("bsq")),
        "5",
        "2",
    ]));
    let want = format!(
        "wavelength_nm,value\n450,{}\n550,{}\n650,{}\n",
        value(5, 2, 0),
        value(5, 2, 1),
        value(5, 2, 2)
    );
    assert_eq!(csv, want);

    let png = dir.path().join("band.png");
    let out: serde_json::Value = serde_json::from_str(&stdout(&cube_tool(&[
        "band",
        p(&hdr),
        "560",
        "--out",
        p(&png),
    ])))
    .unwrap();
    assert_eq!(out["band"], 1);
    assert_eq!(out["wavelength_nm"], 550.0);
    let (info, px) = decode_png(&png);
    assert_eq!(
        (info.width, info.height, info.color_type),
        (6, 4, png::ColorType::Grayscale)
    );
    assert_eq!((px[0], px[23]), (0, 255), "min black, max white");

    let ql = dir.path().join("ql.png");
    stdout(&cube_tool(&["quicklook", p(&hdr), "--out", p(&ql)]));
    let (info, px) = decode_png(&ql);
    assert_eq!(
        (info.width, info.height, info.color_type),
        (6, 4, png::ColorType::Rgb)
    );
    assert_eq!(px.len(), 6 * 4 * 3);

    // The spectral EXR copy has one channel per band, 6 x 4 pixels.
    let exr_path = dir.path().join("c.exr");
    stdout(&cube_tool(&["exr", p(&hdr), "--out", p(&exr_path)]));
    let image = exr::prelude::read_all_flat_layers_from_file(&exr_path).unwrap();
    let layer = &image.layer_data[0];
    assert_eq!((layer.size.width(), layer.size.height()), (6, 4));
    let cube = littoral::cube::EnviCube::open(&hdr).unwrap();
    assert_eq!(layer.channel_data.list.len(), cube.bands());
}

fn decode_png(path: &Path) -> (png::OutputInfo, Vec<u8>) {
    let bytes = std::fs::read(path).unwrap();
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes))
        .read_info()
        .unwrap();
    let (w, h) = (reader.info().width as usize, reader.info().height as usize);
    let mut buf = vec![0; w * h * reader.info().color_type.samples()];
    let info = reader.next_frame(&mut buf).unwrap();
    (info, buf)
}

#[test]
fn bad_cubes_and_arguments_fail_cleanly() {
    let dir = tempdir();
    let hdr = small_cube(dir.path());
    let missing = dir.path().join("none.hdr");
    assert_clean_failure(&cube_tool(&["info", p(&missing)]), "none.hdr");

    let text = std::fs::read_to_string(&hdr).unwrap();
    std::fs::write(&hdr, text.replace("data type = 4", "data type = 6")).unwrap();
    assert_clean_failure(
        &cube_tool(&["info", p(&hdr)]),
        "small.hdr: line 8: data type",
    );
    std::fs::write(&hdr, text).unwrap();

    assert_clean_failure(
        &cube_tool(&["spectrum", p(&hdr), "6", "0"]),
        "pixel: (6, 0)",
    );
    let png = dir.path().join("b.png");
    assert_clean_failure(
        &cube_tool(&["band", p(&hdr), "NaN", "--out", p(&png)]),
        "NM",
    );
    assert_clean_failure(
        &cube_tool(&[
            "band",
            p(&hdr),
            "500",
            "--out",
            p(&dir.path().join("no/b.png")),
        ]),
        "no/b.png",
    );
    assert!(!png.exists());

    let bsq = hdr.with_extension("bsq");
    let f = std::fs::OpenOptions::new().write(true).open(&bsq).unwrap();
    f.set_len(10).unwrap();
    assert_clean_failure(
        &cube_tool(&["info", p(&hdr)]),
        "small.bsq: size: holds 10 bytes",
    );
}

/// A window cut from the cube holds the same values; a cube differs from
/// itself by nothing and from a shifted copy by the known per-band RMSE;
/// mismatched cubes and windows out of range fail cleanly.
#[test]
fn window_and_diff() {
    let dir = tempdir();
    let hdr = small_cube(dir.path());
    let out = dir.path().join("win.hdr");
    let said: serde_json::Value = serde_json::from_str(&stdout(&cube_tool(&[
        "window",
        p(&hdr),
        "1",
        "2",
        "4",
        "2",
        "--out",
        p(&out),
    ])))
    .unwrap();
    // The summary names each file as what it is.
    assert_eq!(said["hdr"], p(&out));
    assert_eq!(said["bsq"], p(&out.with_extension("bsq")));
    let win = littoral::cube::EnviCube::open(&out).unwrap();
    assert_eq!((win.samples(), win.lines(), win.bands()), (4, 2, 3));
    for y in 0..2 {
        for x in 0..4 {
            let s = win.spectrum(x, y).unwrap();
            for (b, v) in s.iter().enumerate() {
                assert_eq!(*v, value(x + 1, y + 2, b));
            }
        }
    }
    let same: serde_json::Value =
        serde_json::from_str(&stdout(&cube_tool(&["diff", p(&hdr), p(&hdr)]))).unwrap();
    assert_eq!(same["rmse"], 0.0);
    // The window at (0, 0) against the one at (1, 2): b - a = 0.001 + 0.02
    // at every pixel and band.
    let out0 = dir.path().join("win0.hdr");
    stdout(&cube_tool(&[
        "window",
        p(&hdr),
        "0",
        "0",
        "4",
        "2",
        "--out",
        p(&out0),
    ]));
    let d: serde_json::Value =
        serde_json::from_str(&stdout(&cube_tool(&["diff", p(&out0), p(&out)]))).unwrap();
    for b in 0..3 {
        let rmse = d["bands"][b]["rmse"].as_f64().unwrap();
        assert!((rmse - 0.021).abs() < 1e-6, "band {b}: {rmse}");
    }
    assert_clean_failure(&cube_tool(&["diff", p(&hdr), p(&out)]), "win.hdr");
    assert_clean_failure(
        &cube_tool(&["window", p(&hdr), "4", "0", "4", "2", "--out", p(&out0)]),
        "window",
    );
}

/// `subset` keeps a band range with its wavelengths and values; `stats`
/// gives each band's statistics, worked by hand for the test cube; a band
/// range outside the cube and an --out that is not a header are refused.
#[test]
fn subset_and_stats() {
    let dir = tempdir();
    let hdr = small_cube(dir.path());
    let out = dir.path().join("sub.hdr");
    stdout(&cube_tool(&["subset", p(&hdr), "1", "2", "--out", p(&out)]));
    let sub = littoral::cube::EnviCube::open(&out).unwrap();
    assert_eq!(sub.wavelengths_nm(), &[550.0, 650.0]);
    for b in 0..2 {
        let band = sub.band(b).unwrap();
        for y in 0..4 {
            for x in 0..6 {
                assert_eq!(band[y * 6 + x], value(x, y, b + 1));
            }
        }
    }
    let stats: serde_json::Value =
        serde_json::from_str(&stdout(&cube_tool(&["stats", p(&hdr)]))).unwrap();
    for b in 0..3 {
        let vals: Vec<f64> = (0..4)
            .flat_map(|y| (0..6).map(move |x| value(x, y, b) as f64))
            .collect();
        let mean = vals.iter().sum::<f64>() / 24.0;
        let sd = (vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / 24.0).sqrt();
        let s = &stats[b];
        assert_eq!(s["finite"], 24);
        assert!((s["mean"].as_f64().unwrap() - mean).abs() < 1e-6, "{s}");
        assert!((s["sd"].as_f64().unwrap() - sd).abs() < 1e-6, "{s}");
        assert_eq!(s["min"].as_f64().unwrap() as f32, value(0, 0, b));
        assert_eq!(s["max"].as_f64().unwrap() as f32, value(5, 3, b));
    }
    let bad = cube_tool(&["subset", p(&hdr), "1", "3", "--out", p(&out)]);
    assert_clean_failure(&bad, "not a band range");
    let bad = cube_tool(&[
        "subset",
        p(&hdr),
        "0",
        "1",
        "--out",
        p(&dir.path().join("x.tif")),
    ]);
    assert_clean_failure(&bad, "NAME.hdr");
}

/// `resample` into Sentinel-2A's bands: a band that lies inside one of the
/// cube's bands reads that band (B3 at 560 nm inside 500-600 nm, B4 at 665
/// nm inside 600-700 nm), a flat spectrum reads itself in every band, the
/// bands beyond the cube's 400-700 nm are left out and listed, the bands
/// carry the sensor's names, and an unknown sensor is refused.
#[test]
fn resample_into_sentinel2_bands() {
    let dir = tempdir();
    let hdr = small_cube(dir.path());
    // Into a directory that does not exist yet: it is made.
    let out = dir.path().join("new").join("s2.hdr");
    let summary: serde_json::Value = serde_json::from_str(&stdout(&cube_tool(&[
        "resample",
        p(&hdr),
        "--sensor",
        "sentinel2a-msi",
        "--out",
        p(&out),
    ])))
    .unwrap();
    let names: Vec<&str> = summary["bands"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| b["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["B1", "B2", "B3", "B4"], "{summary}");
    let left_out = summary["left_out"].as_array().unwrap();
    assert!(left_out.iter().any(|b| b == "B8A") && left_out.len() == 9);
    // The header and GDAL's sidecar name the bands as the sensor does.
    let header = std::fs::read_to_string(&out).unwrap();
    assert!(
        header.contains("band names = {B1, B2, B3, B4}\n"),
        "{header}"
    );
    let sidecar = std::fs::read_to_string(out.with_extension("bsq.aux.xml")).unwrap();
    assert!(sidecar.contains("<Description>B1 ("), "{sidecar}");
    let s2 = littoral::cube::EnviCube::open(&out).unwrap();
    for (band, from) in [(2, 1), (3, 2)] {
        let got = s2.band(band).unwrap();
        for y in 0..4 {
            for x in 0..6 {
                let want = value(x, y, from);
                assert!((got[y * 6 + x] - want).abs() < 1e-6 * want, "band {band}");
            }
        }
    }
    let flat_dir = tempdir();
    let flat = small_cube_with(flat_dir.path(), |x, y, _| 0.5 + 0.01 * (x + y) as f32);
    let out = flat_dir.path().join("flat.hdr");
    let sensor = "csv:".to_string() + p(&flat_dir.path().join("g.csv"));
    std::fs::write(
        flat_dir.path().join("g.csv"),
        "band,center_nm,fwhm_nm\nblue,480,20\ngreen,551.5,10\n",
    )
    .unwrap();
    stdout(&cube_tool(&[
        "resample",
        p(&flat),
        "--sensor",
        &sensor,
        "--out",
        p(&out),
    ]));
    let cube = littoral::cube::EnviCube::open(&out).unwrap();
    assert_eq!(cube.bands(), 2);
    for b in 0..2 {
        for (i, v) in cube.band(b).unwrap().iter().enumerate() {
            let want = 0.5 + 0.01 * (i % 6 + i / 6) as f32;
            assert!((v - want).abs() < 1e-6, "band {b} pixel {i}: {v}");
        }
    }
    let bad = cube_tool(&[
        "resample",
        p(&hdr),
        "--sensor",
        "pace-oci",
        "--out",
        p(&out),
    ]);
    assert_clean_failure(&bad, "pace-oci");
}

/// `convert` rewrites the cube BIL and BIP with the same values (`diff`
/// reads both layouts: RMSE 0); `csv` prints a window with the
/// wavelengths as its header; `--wavelengths` replaces the header's and
/// must give one per band.
#[test]
fn convert_csv_and_given_wavelengths() {
    let dir = tempdir();
    let hdr = small_cube(dir.path());
    for layout in ["bil", "bip"] {
        let out = dir.path().join(format!("c{layout}.hdr"));
        let s: serde_json::Value = serde_json::from_str(&stdout(&cube_tool(&[
            "convert",
            p(&hdr),
            "--interleave",
            layout,
            "--out",
            p(&out),
        ])))
        .unwrap();
        assert!(s["data"]
            .as_str()
            .unwrap()
            .ends_with(&format!("c{layout}.{layout}")));
        let d: serde_json::Value =
            serde_json::from_str(&stdout(&cube_tool(&["diff", p(&hdr), p(&out)]))).unwrap();
        assert_eq!(d["rmse"], 0.0, "{layout}: {d}");
        assert!(std::fs::read_to_string(&out)
            .unwrap()
            .contains(&format!("interleave = {layout}")));
    }
    let csv = stdout(&cube_tool(&["csv", p(&hdr), "4", "1", "2", "2"]));
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], "x,y,450,550,650");
    assert_eq!(lines.len(), 5);
    let row: Vec<f32> = lines[4].split(',').map(|v| v.parse().unwrap()).collect();
    assert_eq!(
        row,
        [5.0, 2.0, value(5, 2, 0), value(5, 2, 1), value(5, 2, 2)]
    );
    let info: serde_json::Value = serde_json::from_str(&stdout(&cube_tool(&[
        "info",
        p(&hdr),
        "--wavelengths",
        "500,600,700",
    ])))
    .unwrap();
    assert_eq!(info["wavelength_nm"]["min"], 500.0);
    assert_clean_failure(
        &cube_tool(&["info", p(&hdr), "--wavelengths", "500,600"]),
        "--wavelengths",
    );
    assert_clean_failure(&cube_tool(&["csv", p(&hdr), "5", "0", "2", "1"]), "window");
}
