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
        band_names: Vec::new(),
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
    assert_eq!(
        names_in(dir.path()),
        ["cube.bsq", "cube.bsq.aux.xml", "cube.hdr"]
    );
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
            band_names: Vec::new(),
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
    let text = spec(3, 2, 2).header_text(Interleave::Bsq);
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
        ("data type = 4", "data type = 3", "data type: is '3'"),
        (
            "interleave = bsq",
            "interleave = bsx",
            "interleave: is 'bsx'",
        ),
        ("byte order = 0", "byte order = 2", "byte order: is '2'"),
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
        (
            "wavelength = {400, 700}\nfwhm = {300, 300}\nband names = {400 nm, 700 nm}",
            "band names = {Band 1, Band 2}",
            "wavelength: missing",
        ),
        (
            "wavelength = {400, 700}\nfwhm = {300, 300}\nband names = {400 nm, 700 nm}",
            "band names = {400 nm}",
            "band names: has 1 names but bands = 2",
        ),
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
fn short_long_or_missing_data_files_are_refused() {
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

    // Longer than the header says is as wrong: another file's header, or
    // data appended.
    let (_dir, result) = open_edited(|t| t, 3 * 2 * 2 * 4 + 1);
    let e = result.unwrap_err().to_string();
    assert!(e.contains("holds 49 bytes") && e.contains("need 48"), "{e}");

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

/// A 3 x 2 x 2 cube written by hand in `layout` as `data_type` (2, 12, 4
/// or 5) in either byte order, under `data_name`, with `extra` header
/// lines: (dir, header path).
fn foreign(
    layout: Interleave,
    data_type: u32,
    big_endian: bool,
    data_name: &str,
    wavelengths: &str,
) -> (tempfile::TempDir, PathBuf) {
    let (samples, lines, bands) = (3usize, 2usize, 2usize);
    let dir = tempfile::tempdir().unwrap();
    let mut data = vec![0u8; 0];
    let mut values = vec![0f64; samples * lines * bands];
    for b in 0..bands {
        for y in 0..lines {
            for x in 0..samples {
                let e = layout.element([samples, lines, bands], b, y, x) as usize;
                values[e] = (10 * b + 3 * y + x) as f64 - 4.0;
            }
        }
    }
    for v in values {
        let bytes: Vec<u8> = match (data_type, big_endian) {
            (2, false) => (v as i16).to_le_bytes().to_vec(),
            (2, true) => (v as i16).to_be_bytes().to_vec(),
            (12, false) => ((v + 4.0) as u16).to_le_bytes().to_vec(),
            (12, true) => ((v + 4.0) as u16).to_be_bytes().to_vec(),
            (4, false) => (v as f32).to_le_bytes().to_vec(),
            (4, true) => (v as f32).to_be_bytes().to_vec(),
            (5, false) => v.to_le_bytes().to_vec(),
            _ => v.to_be_bytes().to_vec(),
        };
        data.extend(bytes);
    }
    std::fs::write(dir.path().join(data_name), data).unwrap();
    let hdr = dir.path().join("f.hdr");
    std::fs::write(
        &hdr,
        format!(
            "ENVI\nsamples = 3\nlines = 2\nbands = 2\nheader offset = 0\ndata type = {data_type}\ninterleave = {}\nbyte order = {}\n{wavelengths}\n",
            layout.extension(),
            u8::from(big_endian)
        ),
    )
    .unwrap();
    (dir, hdr)
}

/// Cubes other software writes read back the same values whatever their
/// interleave, data type and byte order, with the data file under another
/// name; wavelengths come from `band names` when there is no
/// `wavelength` list, or from the caller.
#[test]
fn foreign_layouts_types_and_byte_orders_read_back() {
    let layouts = [Interleave::Bsq, Interleave::Bil, Interleave::Bip];
    for layout in layouts {
        for data_type in [2, 12, 4, 5] {
            for big_endian in [false, true] {
                let name = if big_endian { "f.img" } else { "f" };
                let (_dir, hdr) = foreign(
                    layout,
                    data_type,
                    big_endian,
                    name,
                    "wavelength = {450, 550}",
                );
                let cube = EnviCube::open(&hdr).unwrap();
                let shift = if data_type == 12 { 4.0 } else { 0.0 };
                let want = |x: usize, y: usize, b: usize| (10 * b + 3 * y + x) as f32 - 4.0 + shift;
                let what = format!("{layout:?} type {data_type} big-endian {big_endian}");
                assert_eq!(
                    cube.spectrum(2, 1).unwrap(),
                    [want(2, 1, 0), want(2, 1, 1)],
                    "{what}"
                );
                for b in 0..2 {
                    let band: Vec<f32> = (0..6).map(|i| want(i % 3, i / 3, b)).collect();
                    assert_eq!(cube.band(b).unwrap(), band, "{what}");
                    assert_eq!(
                        cube.window(b, 1, 1, 2, 1).unwrap(),
                        [want(1, 1, b), want(2, 1, b)],
                        "{what}"
                    );
                }
            }
        }
    }
    let (_dir, hdr) = foreign(
        Interleave::Bil,
        4,
        false,
        "f.dat",
        "band names = {450.5 nm, 0.5505 um}",
    );
    assert_eq!(
        EnviCube::open(&hdr).unwrap().wavelengths_nm(),
        [450.5, 550.5]
    );
    let (_dir, hdr) = foreign(
        Interleave::Bil,
        4,
        false,
        "f.bil",
        "band names = {Band 1, Band 2}",
    );
    let e = EnviCube::open(&hdr).unwrap_err().to_string();
    assert!(e.contains("wavelength: missing"), "{e}");
    let given = EnviCube::open_with(&hdr, Some(&[500.0, 600.0])).unwrap();
    assert_eq!(given.wavelengths_nm(), [500.0, 600.0]);
    let e = EnviCube::open_with(&hdr, Some(&[500.0]))
        .unwrap_err()
        .to_string();
    assert!(e.contains("--wavelengths") && e.contains("2 bands"), "{e}");
    let (dir, hdr) = foreign(
        Interleave::Bsq,
        4,
        false,
        "elsewhere.bin",
        "wavelength = {450, 550}",
    );
    let e = EnviCube::open(&hdr).unwrap_err().to_string();
    assert!(
        e.contains("data file: none beside the header")
            && e.contains(&dir.path().join("f.bsq").display().to_string()),
        "{e}"
    );
}

/// The writer lays data out BIL or BIP too; the reader reads them back.
#[test]
fn bil_and_bip_writers_round_trip() {
    for layout in [Interleave::Bil, Interleave::Bip] {
        let dir = tempfile::tempdir().unwrap();
        let (samples, lines, bands) = (70, 5, 3);
        let w = EnviWriter::create_interleaved(
            dir.path(),
            "c",
            spec(samples, lines, bands),
            &[],
            layout,
        )
        .unwrap();
        for t in tiles(samples, lines, 64) {
            w.write_tile(t.0, t.1, t.2, t.3, &tile_values(bands, t))
                .unwrap();
        }
        let files = w.finish().unwrap();
        assert_eq!(files.bsq.extension().unwrap(), layout.extension());
        let cube = EnviCube::open(&files.hdr).unwrap();
        assert_eq!(cube.interleave(), layout);
        assert_whole_cube(&cube);
    }
}
