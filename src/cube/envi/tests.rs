//! Tests of the ENVI writer and reader: exact round trips from tiles in any
//! order and from several threads, header fields, and clean refusals of bad
//! tiles, bad headers and short data files.

use super::*;
use crate::rng::Pcg32;

fn spec(samples: usize, lines: usize, bands: usize) -> CubeSpec {
    CubeSpec {
        samples,
        lines,
        bands: BandGrid::even(400.0, 700.0, bands).unwrap(),
        description: "littoral test cube".into(),
        data_units: "W m-2 sr-1 nm-1".into(),
    }
}

/// A value unique to (x, y, b), including some that need every bit.
fn value(x: usize, y: usize, b: usize) -> f32 {
    (x as f32 + 1000.0 * y as f32) * 1.000_123 + b as f32 * 0.001_7 - 3.3
}

/// Tiles of `tile` x `tile` pixels (smaller at the right and bottom
/// edges) covering the cube.
fn tiles(samples: usize, lines: usize, tile: usize) -> Vec<(usize, usize, usize, usize)> {
    let mut all = Vec::new();
    for y0 in (0..lines).step_by(tile) {
        for x0 in (0..samples).step_by(tile) {
            all.push((x0, y0, tile.min(samples - x0), tile.min(lines - y0)));
        }
    }
    all
}

fn tile_values(bands: usize, (x0, y0, w, h): (usize, usize, usize, usize)) -> Vec<f32> {
    let mut v = Vec::with_capacity(w * h * bands);
    for y in y0..y0 + h {
        for x in x0..x0 + w {
            v.extend((0..bands).map(|b| value(x, y, b)));
        }
    }
    v
}

fn names_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

fn write_cube(
    dir: &Path,
    samples: usize,
    lines: usize,
    bands: usize,
    tile: usize,
    seed: u64,
) -> PathBuf {
    let writer = EnviWriter::create(dir, "cube", spec(samples, lines, bands)).unwrap();
    let mut order = tiles(samples, lines, tile);
    // Fisher-Yates with a seeded stream: the order is random but repeatable.
    let mut rng = Pcg32::new(seed, 0);
    for i in (1..order.len()).rev() {
        order.swap(i, rng.below(i as u32 + 1) as usize);
    }
    for t in order {
        writer
            .write_tile(t.0, t.1, t.2, t.3, &tile_values(bands, t))
            .unwrap();
    }
    writer.finish().unwrap().hdr
}

fn assert_whole_cube(cube: &EnviCube) {
    for b in 0..cube.bands() {
        let band = cube.band(b).unwrap();
        for y in 0..cube.lines() {
            for x in 0..cube.samples() {
                let got = band[y * cube.samples() + x];
                assert_eq!(
                    got.to_bits(),
                    value(x, y, b).to_bits(),
                    "({x}, {y}) band {b}"
                );
            }
        }
    }
}

#[test]
fn tiles_in_random_order_read_back_exactly() {
    let dir = tempfile::tempdir().unwrap();
    // 23 x 17 in 8-pixel tiles: edge tiles are 7 wide and 1 high.
    let hdr = write_cube(dir.path(), 23, 17, 5, 8, 1);
    assert_eq!(names_in(dir.path()), ["cube.bsq", "cube.hdr"]);
    let cube = EnviCube::open(&hdr).unwrap();
    assert_eq!((cube.samples(), cube.lines(), cube.bands()), (23, 17, 5));
    assert_whole_cube(&cube);
    for (x, y) in [(0, 0), (22, 16), (7, 8), (8, 7)] {
        let s = cube.spectrum(x, y).unwrap();
        let want: Vec<u32> = (0..5).map(|b| value(x, y, b).to_bits()).collect();
        assert_eq!(s.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), want);
    }
    let rows = cube.band_rows(3, 5, 2).unwrap();
    assert_eq!(rows.len(), 2 * 23);
    assert_eq!(rows[23 + 4].to_bits(), value(4, 6, 3).to_bits());
    // The data file is exactly the cube: little-endian float32, BSQ.
    let bytes = std::fs::read(dir.path().join("cube.bsq")).unwrap();
    assert_eq!(bytes.len(), 23 * 17 * 5 * 4);
    let at = ((2 * 17 + 9) * 23 + 11) * 4;
    assert_eq!(bytes[at..at + 4], value(11, 9, 2).to_le_bytes());
}

#[test]
fn whole_line_tiles_and_single_pixels_read_back_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a");
    let b = dir.path().join("b");
    std::fs::create_dir_all(&a).unwrap();
    std::fs::create_dir_all(&b).unwrap();
    // Tiles as wide as the cube take the one-run-per-band path.
    assert_whole_cube(&EnviCube::open(&write_cube(&a, 6, 9, 3, 6, 2)).unwrap());
    assert_whole_cube(&EnviCube::open(&write_cube(&b, 5, 4, 2, 1, 3)).unwrap());
}

#[test]
fn threads_share_one_writer() {
    let dir = tempfile::tempdir().unwrap();
    let (samples, lines, bands) = (40, 30, 4);
    let writer = EnviWriter::create(dir.path(), "cube", spec(samples, lines, bands)).unwrap();
    let all = tiles(samples, lines, 7);
    std::thread::scope(|s| {
        for part in all.chunks(all.len().div_ceil(3)) {
            let writer = &writer;
            s.spawn(move || {
                for &t in part {
                    writer
                        .write_tile(t.0, t.1, t.2, t.3, &tile_values(bands, t))
                        .unwrap();
                }
            });
        }
    });
    let bsq = writer.finish().unwrap().bsq;
    assert_whole_cube(&EnviCube::open(&bsq).unwrap());
}

#[test]
fn header_parses_back() {
    let dir = tempfile::tempdir().unwrap();
    let bands = BandGrid::explicit(vec![412.5, 443.0, 490.25], vec![10.0, 12.5, 7.75]).unwrap();
    let writer = EnviWriter::create(
        dir.path(),
        "scene",
        CubeSpec {
            samples: 3,
            lines: 2,
            bands,
            description: "coastal radiance".into(),
            data_units: "W m-2 sr-1 nm-1".into(),
        },
    )
    .unwrap();
    let files = writer.finish().unwrap();
    let (bsq, hdr) = (files.bsq, files.hdr);
    assert_eq!(bsq, dir.path().join("scene.bsq"));
    assert_eq!(hdr, dir.path().join("scene.hdr"));
    let text = std::fs::read_to_string(&hdr).unwrap();
    for line in [
        "ENVI\n",
        "\nsamples = 3\n",
        "\nlines = 2\n",
        "\nbands = 3\n",
        "\nheader offset = 0\n",
        "\nfile type = ENVI Standard\n",
        "\ndata type = 4\n",
        "\ninterleave = bsq\n",
        "\nbyte order = 0\n",
        "\nwavelength units = Nanometers\n",
        "\nwavelength = {412.5, 443, 490.25}\n",
        "\nfwhm = {10, 12.5, 7.75}\n",
        "\ndata units = W m-2 sr-1 nm-1\n",
        "\nband names = {412.5 nm, 443 nm, 490.25 nm}\n",
        "\nsensor type = littoral simulation\n",
        "\ndescription = {coastal radiance}\n",
    ] {
        assert!(text.contains(line), "{line:?} not in:\n{text}");
    }
    let cube = EnviCube::open(&hdr).unwrap();
    assert_eq!(cube.wavelengths_nm(), [412.5, 443.0, 490.25]);
    assert_eq!(cube.fwhm_nm().unwrap(), [10.0, 12.5, 7.75]);
    assert_eq!(cube.description(), "coastal radiance");
    assert_eq!(cube.data_units(), Some("W m-2 sr-1 nm-1"));
    assert_eq!(cube.band_index_nearest(400.0), 0);
    assert_eq!(cube.band_index_nearest(470.0), 2);
    assert_eq!(cube.band_index_nearest(1e9), 2);
    // An unwritten (pre-sized) cube reads as zeros.
    assert!(cube.band(1).unwrap().iter().all(|&v| v == 0.0));
}

#[test]
fn foreign_headers_with_comments_multiline_lists_and_micrometres_parse() {
    let dir = tempfile::tempdir().unwrap();
    let hdr = dir.path().join("x.hdr");
    std::fs::write(
        &hdr,
        "ENVI\n; a comment\nSamples = 2\nlines=1\nbands = 2\nheader offset = 8\n\
         data type = 4\ninterleave = BSQ\nbyte order = 0\n\
         wavelength units = Micrometers\nwavelength = {\n 0.45,\n 0.55 }\n",
    )
    .unwrap();
    let mut data = vec![0u8; 8];
    for v in [1.0f32, 2.0, 3.0, 4.0] {
        data.extend(v.to_le_bytes());
    }
    std::fs::write(dir.path().join("x.bsq"), data).unwrap();
    let cube = EnviCube::open(&dir.path().join("x.bsq")).unwrap();
    assert_eq!(cube.wavelengths_nm(), [450.0, 550.0]);
    assert_eq!(cube.fwhm_nm(), None);
    assert_eq!(cube.spectrum(1, 0).unwrap(), [2.0, 4.0]);
}

#[test]
fn dropped_writer_leaves_no_files() {
    let dir = tempfile::tempdir().unwrap();
    {
        let writer = EnviWriter::create(dir.path(), "cube", spec(8, 8, 3)).unwrap();
        writer
            .write_tile(0, 0, 4, 4, &tile_values(3, (0, 0, 4, 4)))
            .unwrap();
        assert_eq!(
            names_in(dir.path()).len(),
            2,
            "two temporaries while writing"
        );
        assert!(!dir.path().join("cube.hdr").exists());
    }
    assert!(
        names_in(dir.path()).is_empty(),
        "{:?}",
        names_in(dir.path())
    );
}

#[test]
fn bad_tiles_and_specs_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let writer = EnviWriter::create(dir.path(), "cube", spec(10, 6, 2)).unwrap();
    let ok = |w: usize, h: usize| vec![0f32; w * h * 2];
    for (x0, y0, w, h) in [
        (8, 0, 3, 1),
        (0, 5, 1, 2),
        (0, 0, 0, 1),
        (usize::MAX, 0, 2, 1),
    ] {
        let e = writer
            .write_tile(x0, y0, w, h, &ok(w.min(4), h))
            .unwrap_err();
        assert!(e.to_string().starts_with("tile: "), "{e}");
    }
    let e = writer.write_tile(0, 0, 2, 2, &ok(2, 1)).unwrap_err();
    assert!(e.to_string().contains("needs 8 values, got 4"), "{e}");

    let mut s = spec(0, 4, 2);
    assert!(EnviWriter::create(dir.path(), "a", s.clone()).is_err());
    s.samples = 4;
    s.description = "a {brace}".into();
    let e = EnviWriter::create(dir.path(), "a", s.clone()).unwrap_err();
    assert!(e.to_string().starts_with("description"), "{e}");
    s.description.clear();
    for name in ["", "a/b", ".hidden", ".."] {
        assert!(
            EnviWriter::create(dir.path(), name, s.clone()).is_err(),
            "{name}"
        );
    }
    let e = EnviWriter::create(&dir.path().join("missing"), "a", s).unwrap_err();
    assert!(e.to_string().contains("missing"), "{e}");
}

/// A valid header with `edit` applied, beside a data file of `data_bytes`.
fn open_edited(
    edit: impl Fn(String) -> String,
    data_bytes: usize,
) -> (tempfile::TempDir, Result<EnviCube>) {
    let dir = tempfile::tempdir().unwrap();
    let text = spec(3, 2, 2).header_text();
    let hdr = dir.path().join("c.hdr");
    std::fs::write(&hdr, edit(text)).unwrap();
    std::fs::write(dir.path().join("c.bsq"), vec![0u8; data_bytes]).unwrap();
    let result = EnviCube::open(&hdr);
    (dir, result)
}

/// Each case replaces the first text with the second in a valid header
/// (an empty first text replaces the whole header; an empty second deletes).
#[test]
fn bad_headers_name_the_file_and_the_field() {
    const END: &str = "data units = W m-2 sr-1 nm-1\n";
    let cases = [
        ("ENVI", "NOPE", "header: does not start with 'ENVI'"),
        ("", "", "header: does not start"),
        (
            "samples = 3",
            "samples = three",
            "line 3: samples: expected a whole number",
        ),
        ("lines = 2", "lines = 0", "lines: must be at least 1"),
        ("bands = 2\n", "", "bands: missing"),
        ("data type = 4", "data type = 5", "data type: is '5'"),
        (
            "interleave = bsq",
            "interleave = bip",
            "interleave: is 'bip'",
        ),
        ("byte order = 0", "byte order = 1", "byte order: is '1'"),
        ("byte order = 0\n", "", "byte order: missing"),
        (
            "{400, 700}",
            "{400}",
            "wavelength: has 1 values but bands = 2",
        ),
        ("{400, 700}", "{400, x}", "wavelength[1]: expected a number"),
        ("{400, 700}", "{400, 700", "wavelength: '{' is never closed"),
        (
            "data units = W",
            "data units = {W",
            "data units: '{' is never closed",
        ),
        ("wavelength = {400, 700}\n", "", "wavelength: missing"),
        (
            "= Nanometers",
            "= Index",
            "wavelength units: 'Index' is not Nanometers",
        ),
        (END, "samples = 3\n", "samples: appears twice"),
        (END, "what is this\n", "header: expected 'key = value'"),
        ("{300, 300}", "{300, 300} x", "fwhm: unexpected 'x'"),
        ("samples", " = 3\nsamples", "header: a value has no key"),
    ];
    for (from, to, needle) in cases {
        let edit = |t: String| {
            if from.is_empty() {
                to.to_string()
            } else {
                let to = if from == END {
                    format!("{END}{to}")
                } else {
                    to.to_string()
                };
                t.replacen(from, &to, 1)
            }
        };
        let (dir, result) = open_edited(edit, 3 * 2 * 2 * 4);
        let e = result.unwrap_err().to_string();
        let hdr = dir.path().join("c.hdr");
        assert!(e.starts_with(&format!("{}: ", hdr.display())), "{e}");
        assert!(e.contains(needle), "'{needle}' not in: {e}");
    }
}

#[test]
fn short_or_missing_data_files_are_refused() {
    let (dir, result) = open_edited(|t| t, 3 * 2 * 2 * 4 - 1);
    let e = result.unwrap_err().to_string();
    assert!(
        e.starts_with(&format!(
            "{}: size: holds 47 bytes",
            dir.path().join("c.bsq").display()
        )),
        "{e}"
    );
    assert!(e.contains("need 48"), "{e}");

    let (_dir, result) = open_edited(|t| t.replace("header offset = 0", "header offset = 4"), 48);
    assert!(result.unwrap_err().to_string().contains("need 52"));

    let (_dir, result) = open_edited(
        |t| t.replace("samples = 3", &format!("samples = {}", usize::MAX)),
        48,
    );
    assert!(result.unwrap_err().to_string().contains("overflow"));

    let dir = tempfile::tempdir().unwrap();
    let e = EnviCube::open(&dir.path().join("none.hdr")).unwrap_err();
    assert!(e.to_string().contains("none.hdr: open"), "{e}");
}

#[test]
fn out_of_range_requests_are_errors() {
    let (_dir, result) = open_edited(|t| t, 48);
    let cube = result.unwrap();
    assert!(cube
        .spectrum(3, 0)
        .unwrap_err()
        .to_string()
        .contains("pixel: (3, 0) lies outside"));
    assert!(cube.spectrum(0, 2).is_err());
    assert!(cube.band(2).is_err());
    assert!(cube.band_rows(0, 1, 2).is_err());
    assert!(cube.band_rows(0, usize::MAX, 2).is_err());
    assert_eq!(cube.band_rows(0, 1, 1).unwrap().len(), 3);
}
