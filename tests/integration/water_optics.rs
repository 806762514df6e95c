//! Explicit IOPs per band from a table (`[water] iop_file`): band-averaged
//! like every spectrum, each band attenuating by its own a (Beer–Lambert),
//! identical to `iop = { a, b }` when the table is flat, and scattering
//! split to the table's backscatter fraction; and the errors a bad table
//! gets. The water's refractive index per band (Quan & Fry 1995): emission
//! transmits each band by its own Fresnel factor.

use crate::common::minimal;
use littoral::emit::tally::{Totals, ED, EU};
use littoral::emit::Emitter;
use littoral::scene::{Overrides, Scene};
use std::path::Path;

/// A one-file scene in `dir` with `water` as its `[water]` table body.
fn scene_in(dir: &Path, bands: &str, water: &str, photons: u64) -> littoral::Result<Scene> {
    let text = minimal()
        .remove("spectral")
        .remove("water")
        .merge(&format!(
            r#"
sun = {{ zenith_deg = 0.0 }}
photons = {{ count = {photons} }}
tally = {{ depths_m = [0.0, 1.0, 3.0] }}
[spectral]
{bands}
[water]
{water}
"#
        ))
        .unwrap()
        .text();
    let path = dir.join("scene.toml");
    std::fs::write(&path, &text).unwrap();
    Scene::parse(&text, &path, &Overrides::default())
}

fn run(s: &Scene) -> Totals {
    Emitter::new(s).unwrap().trace_all(0).unwrap()
}

/// With b = 0 each band's downwelling irradiance falls as exp(-a z) with
/// that band's a (sun at the zenith, flat surface), a read from a table
/// linear in wavelength (so a band's average is its centre's value, to
/// the quadrature's rounding).
#[test]
fn each_band_attenuates_by_its_own_absorption() {
    let dir = tempfile::tempdir().unwrap();
    let mut csv = String::from("# a ramp, no scattering\nwavelength_nm,a,b\n");
    // Wide enough for the bands' responses (FWHM 100 nm, to 3 sigma).
    for nm in (100..=1000).step_by(50) {
        csv.push_str(&format!("{nm},{},0\n", 0.1 + 0.002 * (nm - 100) as f64));
    }
    std::fs::write(dir.path().join("iops.csv"), csv).unwrap();
    let s = scene_in(
        dir.path(),
        "start_nm = 400.0\nend_nm = 700.0\nbands = 4",
        "iop_file = \"iops.csv\"",
        400_000,
    )
    .unwrap();
    let t = run(&s);
    for (band, nm) in [400.0, 500.0, 600.0, 700.0].iter().enumerate() {
        let a = 0.1 + 0.002 * (nm - 100.0);
        let (e0, _) = t.mean_and_stderr(t.slot(0, ED), band);
        let n0 = e0 * t.traced as f64 / 4.0;
        for (d, z) in [(1, 1.0f64), (2, 3.0)] {
            let (ez, _) = t.mean_and_stderr(t.slot(d, ED), band);
            let want = (-a * z).exp();
            // Of the n0 photons of this band entering, each survives to z
            // independently.
            let se = (want * (1.0 - want) / n0).sqrt();
            let got = ez / e0;
            assert!(
                (got - want).abs() < 4.0 * se,
                "band {band} ({nm} nm) z {z}: {got} vs {want} (se {se})"
            );
            assert_eq!(t.mean_and_stderr(t.slot(d, EU), band).0, 0.0);
        }
    }
}

/// A flat table without bb_ratio is `iop = { a, b }`: the same IOPs in
/// every band (to the band average's rounding), and, traced with the same
/// seed, the same tallies bit for bit.
#[test]
fn a_flat_table_is_the_explicit_iop() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("flat.csv"),
        "wavelength_nm,a,b\n350,0.1,0.3\n750,0.1,0.3\n",
    )
    .unwrap();
    let bands = "start_nm = 450.0\nend_nm = 650.0\nbands = 3";
    let table = scene_in(dir.path(), bands, "iop_file = \"flat.csv\"", 20_000).unwrap();
    let explicit = scene_in(dir.path(), bands, "iop = { a = 0.1, b = 0.3 }", 20_000).unwrap();
    let p = glam::Vec3::new(1.0, 2.0, -3.0);
    for band in 0..3 {
        let (x, y) = (table.water.iop(p, band), explicit.water.iop(p, band));
        assert!(
            (x.a - y.a).abs() < 1e-12 && (x.b_p - y.b_p).abs() < 1e-12,
            "{x:?} {y:?}"
        );
        assert_eq!(x.b_w, 0.0);
    }
    let (a, b) = (run(&table), run(&explicit));
    for d in 0..3 {
        for q in [ED, EU] {
            for band in 0..3 {
                let (x, y) = (
                    a.mean_and_stderr(a.slot(d, q), band),
                    b.mean_and_stderr(b.slot(d, q), band),
                );
                assert_eq!(
                    x.0.to_bits(),
                    y.0.to_bits(),
                    "depth {d} quantity {q} band {band}"
                );
            }
        }
    }
}

/// With a bb_ratio column, each band's scattering is split between pure
/// water's phase function and the particles' so that the mixture's
/// backscatter fraction is the table's (linear in wavelength here, so a
/// band's is its centre's) and b is the table's.
#[test]
fn scattering_is_split_to_the_tables_backscatter_fraction() {
    let dir = tempfile::tempdir().unwrap();
    let r = |nm: f64| 0.1 + 0.0001 * (nm - 400.0);
    let mut csv = String::from("wavelength_nm,a,b,bb_ratio\n");
    for nm in (100..=1000).step_by(25) {
        csv.push_str(&format!("{nm},0.2,0.5,{}\n", r(nm as f64)));
    }
    std::fs::write(dir.path().join("bb.csv"), csv).unwrap();
    let s = scene_in(
        dir.path(),
        "start_nm = 450.0\nend_nm = 650.0\nbands = 3",
        "iop_file = \"bb.csv\"",
        1000,
    )
    .unwrap();
    let r_w = s.water_phase.backscatter_fraction();
    let r_p = s.particle_phase.backscatter_fraction();
    assert!(
        (r_w - 0.5).abs() < 1e-3 && (r_p - 0.0183).abs() < 1e-3,
        "{r_w} {r_p}"
    );
    for (band, nm) in [450.0, 550.0, 650.0].iter().enumerate() {
        let iop = s.water.iop(glam::Vec3::new(0.0, 0.0, -1.0), band);
        assert!((iop.a - 0.2).abs() < 1e-12 && (iop.b() - 0.5).abs() < 1e-12);
        let mix = (iop.b_w * r_w + iop.b_p * r_p) / iop.b();
        assert!(
            (mix - r(*nm)).abs() < 1e-9,
            "band {band}: {mix} vs {}",
            r(*nm)
        );
    }
}

/// Bad tables: a backscatter fraction no mixture reaches, a missing
/// column, a negative coefficient, bands outside the table, and both
/// `iop` and `iop_file`, each naming the file or the key.
#[test]
fn bad_iop_tables_are_refused_with_the_file_and_band() {
    let dir = tempfile::tempdir().unwrap();
    let bands = "start_nm = 450.0\nend_nm = 650.0\nbands = 3";
    let cases = [
        (
            "wavelength_nm,a,b,bb_ratio\n350,0.1,0.3,0.001\n750,0.1,0.3,0.001\n",
            "band 0",
        ),
        ("wavelength_nm,a\n350,0.1\n750,0.1\n", "b"),
        ("wavelength_nm,a,b\n350,-0.1,0.3\n750,0.1,0.3\n", "line 2"),
        ("wavelength_nm,a,b\n500,0.1,0.3\n750,0.1,0.3\n", "iop_file"),
    ];
    for (i, (csv, needle)) in cases.iter().enumerate() {
        let name = format!("bad{i}.csv");
        std::fs::write(dir.path().join(&name), csv).unwrap();
        let e = scene_in(dir.path(), bands, &format!("iop_file = \"{name}\""), 1000)
            .unwrap_err()
            .to_string();
        assert!(e.contains(needle), "case {i}: {e}");
        assert!(e.contains(&name) || e.contains("iop_file"), "case {i}: {e}");
    }
    std::fs::write(
        dir.path().join("ok.csv"),
        "wavelength_nm,a,b\n350,0.1,0.3\n750,0.1,0.3\n",
    )
    .unwrap();
    let e = scene_in(
        dir.path(),
        bands,
        "iop = { a = 0.1, b = 0.2 }\niop_file = \"ok.csv\"",
        1000,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("iop_file") && e.contains("not both"), "{e}");
}

/// With `refractive_index = "quan-fry"` the photons of each band cross a
/// flat surface with that band's Fresnel transmittance (sun at 75 degrees,
/// where R is about 0.18 and its spread over 400-700 nm several standard
/// errors), and the index is recorded per band.
#[test]
fn each_band_crosses_the_surface_at_its_own_index() {
    let dir = tempfile::tempdir().unwrap();
    let text = |extra: &str| {
        minimal()
            .merge(&format!(
                r#"
spectral = {{ start_nm = 400.0, end_nm = 700.0, bands = 3 }}
sun = {{ zenith_deg = 75.0 }}
water = {{ iop = {{ a = 0.1, b = 0.0 }} }}
photons = {{ count = 1500000 }}
tally = {{ depths_m = [0.0] }}
[surface]
{extra}
"#
            ))
            .unwrap()
            .text()
    };
    let path = dir.path().join("s.toml");
    let s = Scene::parse(
        &text("refractive_index = \"quan-fry\"\ntemperature_c = 10.0\nsalinity_psu = 0.0"),
        &path,
        &Overrides::default(),
    )
    .unwrap();
    let cos = 75f64.to_radians().cos();
    let t = run(&s);
    let mut through = Vec::new();
    for (band, nm) in [400.0, 550.0, 700.0].iter().enumerate() {
        let n = littoral::optics::water_index::quan_fry(*nm, 10.0, 0.0);
        assert!((s.water_index[band] - n).abs() < 1e-12);
        let want = 1.0 - littoral::optics::surface::fresnel_reflectance(cos, 1.0, n);
        // Transmitted over arriving, this band's photons only.
        let (down, _) = t.mean_and_stderr(t.above_slots().0, band);
        let photons = down * t.traced as f64;
        let (got, _) = t.mean_and_stderr(t.slot(0, ED), band);
        let got = got / down;
        let se = (want * (1.0 - want) / photons).sqrt();
        assert!(
            (got - want).abs() < 4.0 * se,
            "band {band}: {got} vs {want} (se {se})"
        );
        through.push((want, se));
    }
    // The test can tell the bands apart.
    assert!(
        through[2].0 - through[0].0 > 6.0 * through[0].1,
        "{through:?}"
    );
    // A name that is not a model, and temperature without the model.
    for (extra, needle) in [
        ("refractive_index = \"seawater\"", "quan-fry"),
        ("temperature_c = 10.0", "temperature_c"),
    ] {
        let e = Scene::parse(&text(extra), &path, &Overrides::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains(needle), "{e}");
    }
}
