//! Georeferenced cubes, read by GDAL (installed by `.ci/run`): the map
//! transform, the CRS, the wavelengths, and north-up orientation.

use crate::common::{client, f32s, minimal, render_job, tempdir};
use littoral::scene::{Overrides, Scene};
use std::path::Path;
use std::process::Command;

/// 4 x 4 pixels of 5 m over a 20 m domain; a bright panel 1 m deep in the
/// north half (y 12-18 m) over a dark floor.
fn scene(georef: &str) -> String {
    minimal()
        .merge(
            r#"
name = "geo"
spectral = { start_nm = 450.0, end_nm = 600.0, bands = 2 }
sun = { zenith_deg = 20.0 }
domain = { size_m = [20.0, 20.0] }
water = { iop = { a = 0.1, b = 0.05 } }
bottom = { depth_m = 3.0, reflectance = 0.02 }
target = [{ kind = "panel", center_m = [10.0, 15.0, -1.0], size_m = [16.0, 6.0], reflectance = 0.8 }]
photons = { count = 100000 }
sensor = { pixels = [4, 4], gsd_m = 5.0 }
"#,
        )
        .and_then(|s| s.merge(georef))
        .unwrap()
        .text()
}

fn gdalinfo(path: &Path) -> serde_json::Value {
    let out = Command::new("gdalinfo")
        .arg("-json")
        .arg(path)
        .output()
        .expect("gdalinfo (GDAL) is installed by .ci/run");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// GDAL reads the UTM geotransform and EPSG code from the header, keeps
/// them and the wavelengths through `gdal_translate -of COG`, and the
/// report carries the same transform; a local frame has a transform and
/// no EPSG code; row 0 is the north edge (the panel's rows are bright).
#[test]
fn gdal_reads_the_map_grid_and_row_0_is_north() {
    if !client("GDAL (Debian's gdal-bin)", &["gdalinfo", "--version"]) {
        return;
    }
    let dir = tempdir();
    let text = scene("[georef]\norigin_m = [500000.0, 4100000.0]\nepsg = 32617");
    let s = Scene::parse(&text, Path::new("geo.toml"), &Overrides::default()).unwrap();
    let r = render_job(&s, &dir.path().join("utm"), 0);
    let want = [500000.0, 5.0, 0.0, 4100020.0, 0.0, -5.0];
    assert_eq!(r.sensor.geotransform, Some(want));
    let info = gdalinfo(Path::new(&r.outputs.bsq));
    let gt: Vec<f64> = serde_json::from_value(info["geoTransform"].clone()).unwrap();
    assert_eq!(gt, want);
    let wkt = info["coordinateSystem"]["wkt"].as_str().unwrap();
    assert!(wkt.contains("ID[\"EPSG\",32617]"), "{wkt}");
    assert_eq!(info["bands"][1]["metadata"][""]["wavelength"], "600");
    // Band units and names, from the sidecar NAME.bsq.aux.xml.
    for band in info["bands"].as_array().unwrap() {
        assert_eq!(band["unit"], "W m-2 sr-1 nm-1", "{band}");
    }
    assert_eq!(info["bands"][1]["description"], "600 nm (600 Nanometers)");
    let rrs = r
        .outputs
        .products
        .iter()
        .find(|p| p.product == "rrs")
        .unwrap();
    assert_eq!(gdalinfo(Path::new(&rrs.bsq))["bands"][0]["unit"], "sr-1");

    let cog = dir.path().join("geo.tif");
    let st = Command::new("gdal_translate")
        .args(["-q", "-of", "COG"])
        .arg(&r.outputs.bsq)
        .arg(&cog)
        .status()
        .unwrap();
    assert!(st.success());
    let info = gdalinfo(&cog);
    let gt: Vec<f64> = serde_json::from_value(info["geoTransform"].clone()).unwrap();
    assert_eq!(gt, want);
    assert!(info["coordinateSystem"]["wkt"]
        .as_str()
        .unwrap()
        .contains("32617"));
    assert_eq!(info["bands"][0]["metadata"][""]["wavelength"], "450");
    assert_eq!(info["bands"][0]["unit"], "W m-2 sr-1 nm-1");

    // North up: rows 0-1 (y 10-20 m) see the panel, rows 2-3 the dark floor.
    let v = f32s(&r.outputs.bsq);
    let row = |j: usize| (0..4).map(|i| v[j * 4 + i] as f64).sum::<f64>();
    assert!(
        row(0) > 3.0 * row(3) && row(1) > 3.0 * row(2),
        "rows {:?}",
        [row(0), row(1), row(2), row(3)]
    );

    let s = Scene::parse(&scene(""), Path::new("geo.toml"), &Overrides::default()).unwrap();
    let r = render_job(&s, &dir.path().join("local"), 0);
    let info = gdalinfo(Path::new(&r.outputs.bsq));
    let gt: Vec<f64> = serde_json::from_value(info["geoTransform"].clone()).unwrap();
    assert_eq!(gt, [0.0, 5.0, 0.0, 20.0, 0.0, -5.0]);
    let wkt = info["coordinateSystem"]["wkt"].as_str().unwrap_or("");
    assert!(
        !wkt.contains("EPSG"),
        "a local frame has no EPSG code: {wkt}"
    );
}

/// An EPSG code that is not a UTM zone is refused, naming the key.
#[test]
fn unsupported_crs_is_refused() {
    let e = Scene::parse(
        &scene("[georef]\nepsg = 4326"),
        Path::new("geo.toml"),
        &Overrides::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("georef.epsg") && e.contains("UTM"), "{e}");
}

/// A cube GDAL re-exports as 16-bit integers, band-interleaved by line
/// (`gdal_translate -of ENVI`), reads back in littoral-cube with the same
/// values, scaled as asked, and the wavelengths GDAL kept.
#[test]
fn littoral_cube_reads_what_gdal_writes() {
    if !client("GDAL (Debian's gdal-bin)", &["gdalinfo", "--version"]) {
        return;
    }
    let dir = tempdir();
    let s = Scene::parse(&scene(""), Path::new("geo.toml"), &Overrides::default()).unwrap();
    let r = render_job(&s, dir.path(), 0);
    let out = dir.path().join("gdal.img");
    let status = Command::new("gdal_translate")
        .args(["-q", "-of", "ENVI", "-ot", "Int16", "-co", "INTERLEAVE=BIL"])
        .args(["-scale", "0", "1", "0", "10000"])
        .arg(&r.outputs.bsq)
        .arg(&out)
        .status()
        .expect("gdal_translate (GDAL) is installed by .ci/run");
    assert!(status.success());
    let cube = littoral::cube::EnviCube::open(&out).unwrap();
    let ours = littoral::cube::EnviCube::open(Path::new(&r.outputs.hdr)).unwrap();
    assert_eq!(cube.interleave(), littoral::cube::envi::Interleave::Bil);
    assert_eq!(cube.data_type(), littoral::cube::envi::DataType::I16);
    assert_eq!(cube.wavelengths_nm(), ours.wavelengths_nm());
    for b in 0..ours.bands() {
        for (g, o) in cube.band(b).unwrap().iter().zip(ours.band(b).unwrap()) {
            assert!(
                (g - (o * 10000.0).round()).abs() <= 1.0,
                "band {b}: {g} vs {o}"
            );
        }
    }
}

/// Cubes derived with littoral-cube keep their place on the map: a window
/// at (1, 2) starts 1 pixel east and 2 south of the cube, and a resampled,
/// converted or band-subset cube has the cube's transform and CRS.
#[test]
fn derived_cubes_keep_the_map_grid() {
    if !client("GDAL (Debian's gdal-bin)", &["gdalinfo", "--version"]) {
        return;
    }
    let dir = tempdir();
    let text = scene("[georef]\norigin_m = [500000.0, 4100000.0]\nepsg = 32617");
    let s = Scene::parse(&text, Path::new("geo.toml"), &Overrides::default()).unwrap();
    let r = render_job(&s, &dir.path().join("utm"), 0);
    let tool = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_littoral-cube"))
            .args(args)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    let path = |name: &str| dir.path().join(name).display().to_string();
    tool(&[
        "window",
        &r.outputs.hdr,
        "1",
        "2",
        "2",
        "2",
        "--out",
        &path("win.hdr"),
    ]);
    tool(&[
        "subset",
        &r.outputs.hdr,
        "0",
        "0",
        "--out",
        &path("sub.hdr"),
    ]);
    tool(&[
        "convert",
        &r.outputs.hdr,
        "--interleave",
        "bip",
        "--out",
        &path("bip.hdr"),
    ]);
    let sensor = dir.path().join("g.csv");
    std::fs::write(&sensor, "band,center_nm,fwhm_nm\nb,500,20\n").unwrap();
    let sensor = format!("csv:{}", sensor.display());
    tool(&[
        "resample",
        &r.outputs.hdr,
        "--sensor",
        &sensor,
        "--out",
        &path("res.hdr"),
    ]);
    let cube = [500000.0, 5.0, 0.0, 4100020.0, 0.0, -5.0];
    let window = [500005.0, 5.0, 0.0, 4100010.0, 0.0, -5.0];
    for (data, want) in [
        ("win.bsq", window),
        ("sub.bsq", cube),
        ("bip.bip", cube),
        ("res.bsq", cube),
    ] {
        let info = gdalinfo(&dir.path().join(data));
        let gt: Vec<f64> = serde_json::from_value(info["geoTransform"].clone()).unwrap();
        assert_eq!(gt, want, "{data}");
        let wkt = info["coordinateSystem"]["wkt"].as_str().unwrap();
        assert!(wkt.contains("ID[\"EPSG\",32617]"), "{data}: {wkt}");
    }
}

/// The sun's azimuth goes into the ENVI header and the report as a compass
/// bearing (clockwise from north), whatever the scene's angle, which runs
/// counter-clockwise from east: a sun in the east (scene 0) is 90, in the
/// north (scene 90) 0, in the west 270, in the south-east (scene -45) 135.
#[test]
fn the_sun_azimuth_is_written_as_a_compass_bearing() {
    for (scene_deg, compass) in [(0.0, 90.0), (90.0, 0.0), (180.0, 270.0), (-45.0, 135.0)] {
        let dir = tempdir();
        let text = littoral::scene::text::SceneText::parse(&scene(""))
            .unwrap()
            .set("sun.azimuth_deg", scene_deg)
            .text();
        let s = Scene::parse(&text, Path::new("geo.toml"), &Overrides::default()).unwrap();
        assert_eq!(s.sun.compass_azimuth_deg(), compass);
        let r = render_job(&s, dir.path(), 0);
        assert_eq!(r.sensor.sun_azimuth_deg, compass);
        let header = std::fs::read_to_string(&r.outputs.hdr).unwrap();
        assert!(
            header.contains(&format!("\nsun azimuth = {compass}\n")),
            "{scene_deg}: {header}"
        );
    }
}
