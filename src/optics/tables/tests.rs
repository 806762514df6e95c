//! Tests of the parent module.
use super::*;
use crate::testing::rel;

/// A table sampling `f` on an irregular grid (so breakpoints never sit
/// symmetrically about a band centre).
fn sampled(name: &str, lo: f64, hi: f64, f: impl Fn(f64) -> f64) -> Table {
    let mut x = Vec::new();
    let mut v = lo;
    let mut k = 0;
    while v < hi {
        x.push(v);
        v += [0.7, 1.3, 2.9, 0.4][k % 4];
        k += 1;
    }
    x.push(hi);
    let y = x.iter().map(|&x| f(x)).collect();
    Table::new(name, x, y).unwrap()
}

fn write(dir: &tempfile::TempDir, name: &str, text: &str) -> std::path::PathBuf {
    let path = dir.path().join(name);
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn fwhm_per_sigma_is_2_sqrt_2_ln_2() {
    assert!((FWHM_PER_SIGMA - 2.0 * (2.0 * std::f64::consts::LN_2).sqrt()).abs() < 1e-15);
}

#[test]
fn embedded_tables_parse_with_documented_ranges() {
    let (a_phi, e_phi) = bricaud_a_phi();
    let (a_p, e_p) = bricaud_a_p();
    let (xbar, ybar, zbar) = cie_1931();
    let mut all: Vec<(&Table, (f64, f64), usize)> = vec![
        (water_absorption(), (380.0, 1000.0), 413),
        (seawater_scattering(), (350.0, 850.0), 501),
        (a_phi, (400.0, 700.0), 151),
        (e_phi, (400.0, 700.0), 151),
        (a_p, (400.0, 700.0), 151),
        (e_p, (400.0, 700.0), 151),
        (
            solar(SolarSpectrum::Extraterrestrial),
            (280.0, 4000.0),
            2002,
        ),
        (solar(SolarSpectrum::GlobalTilt), (280.0, 4000.0), 2002),
        (
            solar(SolarSpectrum::DirectCircumsolar),
            (280.0, 4000.0),
            2002,
        ),
        (sky_diffuse_irradiance(), (280.0, 4000.0), 2002),
        (xbar, (360.0, 830.0), 471),
        (ybar, (360.0, 830.0), 471),
        (zbar, (360.0, 830.0), 471),
    ];
    for kind in BOTTOM_TYPES {
        all.push((bottom_reflectance(kind).unwrap(), (400.0, 800.0), 401));
    }
    for (t, range, rows) in all {
        assert_eq!(t.range_nm(), range, "{}", t.name());
        assert_eq!(t.x_nm().len(), rows, "{}", t.name());
        // Every value in these tables is physically non-negative.
        assert!(t.y().iter().all(|&v| v >= 0.0), "{}", t.name());
    }
    assert_eq!(
        water_absorption().name(),
        "aw_composite_380_1000.csv:aw_per_m"
    );
}

#[test]
fn water_absorption_spot_values_match_the_file() {
    let aw = water_absorption();
    assert_eq!(aw.at(440.0), Some(0.00635));
    assert_eq!(aw.at(700.0), Some(0.624));
    // Either side of the Pope & Fry / Kou junction.
    assert_eq!(aw.at(727.5), Some(1.678));
    assert_eq!(aw.at(728.0), Some(1.7607));
    // Linear between samples: midway between 440 (0.00635) and 442.5 (0.00696).
    assert!((aw.at(441.25).unwrap() - 0.006655).abs() < 1e-12);
    assert_eq!(aw.at(379.9), None);
    assert_eq!(aw.at(1000.1), None);
    assert_eq!(aw.at(f64::NAN), None);
}

#[test]
fn seawater_scattering_follows_morel() {
    let bw = seawater_scattering();
    assert!(rel(bw.at(500.0).unwrap(), 0.00288) < 0.05);
    // Morel (1974) b_w(l) = 0.00288 (l/500)^-4.32 within 5 % over the table.
    for nm in (350..=850).step_by(10) {
        let nm = f64::from(nm);
        let morel = 0.00288 * (nm / 500.0).powf(-4.32);
        assert!(rel(bw.at(nm).unwrap(), morel) < 0.05, "{nm} nm");
    }
}

#[test]
fn bricaud_columns_are_coefficient_and_exponent() {
    let (a, e) = bricaud_a_phi();
    assert_eq!(a.at(440.0), Some(0.037824));
    assert_eq!(e.at(440.0), Some(0.626633));
    let (a_p, e_p) = bricaud_a_p();
    assert_eq!(a_p.at(440.0), Some(0.052019));
    assert_eq!(e_p.at(440.0), Some(0.634965));
    // E is the exponent itself: a_phi(440) at Chl 1 is A, at Chl 10 about 0.16 1/m.
    let a10 = a.at(440.0).unwrap() * 10f64.powf(e.at(440.0).unwrap());
    assert!((a10 - 0.1601).abs() < 1e-3, "{a10}");
}

#[test]
fn astm_g173_integrals_match_the_header() {
    let et = solar(SolarSpectrum::Extraterrestrial).integral();
    let global = solar(SolarSpectrum::GlobalTilt).integral();
    let direct = solar(SolarSpectrum::DirectCircumsolar).integral();
    assert!((et - 1348.0).abs() < 0.5, "{et}");
    assert!((global - 1000.4).abs() < 0.1, "{global}");
    assert!((direct - 900.1).abs() < 0.1, "{direct}");
    let sky = sky_diffuse_irradiance();
    let diffuse = sky.integral();
    assert!((diffuse - 100.29).abs() < 0.05, "{diffuse}");
    // The diffuse sky is bluer than the direct beam.
    let d = solar(SolarSpectrum::DirectCircumsolar);
    let ratio = |t: &Table| t.at(450.0).unwrap() / t.at(650.0).unwrap();
    assert!(ratio(sky) > 1.5 * ratio(d));
}

#[test]
fn cie_ybar_peaks_at_555_nm() {
    let (_, ybar, _) = cie_1931();
    let (i, &peak) = ybar
        .y()
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .unwrap();
    assert_eq!(ybar.x_nm()[i], 555.0);
    assert!((peak - 1.0).abs() < 1e-9);
}

#[test]
fn bottom_types_are_the_file_columns() {
    let header = BOTTOM_CSV
        .lines()
        .find(|l| !l.starts_with('#'))
        .unwrap()
        .to_string();
    assert_eq!(header, format!("wavelength_nm,{}", BOTTOM_TYPES.join(",")));
    for kind in BOTTOM_TYPES {
        let t = bottom_reflectance(kind).unwrap();
        assert!(t.y().iter().all(|&r| r > 0.0 && r < 1.0), "{kind}");
    }
    let sand = bottom_reflectance("Sand").unwrap();
    assert_eq!(sand.at(400.0), Some(0.14803));
    let e = bottom_reflectance("mud").unwrap_err().to_string();
    assert!(
        e.contains("mud") && e.contains("sand, coral, cca, macroalgae, seagrass"),
        "{e}"
    );
}

#[test]
fn band_average_of_linear_is_value_at_centre() {
    let t = sampled("linear", 300.0, 900.0, |x| 3.0 + 0.02 * x);
    for (c, w) in [
        (500.0, 10.0),
        (431.37, 3.3),
        (612.9, 47.0),
        (700.0, 0.9),
        (600.0, 80.0),
    ] {
        let avg = t.band_average(c, w).unwrap();
        assert!((avg - (3.0 + 0.02 * c)).abs() < 1e-9, "{c} {w}: {avg}");
    }
}

#[test]
fn band_average_of_constant_is_the_constant() {
    let t = sampled("constant", 300.0, 900.0, |_| 0.25);
    for (c, w) in [(500.0, 10.0), (301.0, 40.0), (899.5, 5.0), (300.0, 20.0)] {
        assert!((t.band_average(c, w).unwrap() - 0.25).abs() < 1e-14);
    }
}

/// For y = (x - c)^2 the average is the variance of a Gaussian truncated
/// at ±3 sigma, sigma^2 (1 - 6 phi(3) / (2 Phi(3) - 1)): checks the
/// quadrature and the truncation, not just symmetry. The table's linear
/// interpolation of the parabola adds at most h^2/4 = 2.5e-5 nm^2.
#[test]
fn band_average_of_quadratic_is_truncated_gaussian_variance() {
    let c = 550.0;
    let x: Vec<f64> = (0..=40000).map(|i| 450.0 + 0.005 * f64::from(i)).collect();
    let y = x.iter().map(|v| (v - c) * (v - c)).collect();
    let t = Table::new("parabola", x, y).unwrap();
    let fwhm = 20.0;
    let sigma = fwhm / FWHM_PER_SIGMA;
    let phi3 = (-4.5f64).exp() / (2.0 * std::f64::consts::PI).sqrt();
    let variance = sigma * sigma * (1.0 - 6.0 * phi3 / 0.997_300_203_936_740);
    let avg = t.band_average(c, fwhm).unwrap();
    assert!((avg - variance).abs() < 3e-5, "{avg} vs {variance}");
}

/// A band centred on the table's first sample keeps only the upper half
/// of its response: on y = x the average is c + sigma m, with m the mean
/// of a unit half-Gaussian truncated at 3: (1 - e^-4.5) / (sqrt(2 pi) (Phi(3) - 1/2)).
#[test]
fn edge_band_averages_over_the_overlap() {
    let t = sampled("ramp", 400.0, 800.0, |x| x);
    let fwhm = 20.0;
    let sigma = fwhm / FWHM_PER_SIGMA;
    let m = (1.0 - (-4.5f64).exp()) / ((2.0 * std::f64::consts::PI).sqrt() * 0.498_650_101_968_370);
    let avg = t.band_average(400.0, fwhm).unwrap();
    assert!((avg - (400.0 + sigma * m)).abs() < 1e-9, "{avg}");
    let avg = t.band_average(800.0, fwhm).unwrap();
    assert!((avg - (800.0 - sigma * m)).abs() < 1e-9, "{avg}");
    assert!((t.band_coverage(400.0, fwhm) - 0.5).abs() < 1e-12);
    assert!((t.band_coverage(600.0, fwhm) - 1.0).abs() < 1e-12);
    assert_eq!(t.band_coverage(300.0, fwhm), 0.0);
}

/// Inside a segment y is linear, so a narrow band returns the point value
/// to rounding. On a breakpoint the slope changes by ds and the average
/// moves by ds sigma E[max(u, 0)], with E[max(u, 0)] = (phi(0) - phi(3)) /
/// (2 Phi(3) - 1) = 0.395578 for the truncated response (728 nm, the Pope &
/// Fry / Kou junction, has ds = -0.081 nm^-1: a 1.4e-5 shift).
#[test]
fn narrow_band_equals_point_value() {
    let aw = water_absorption();
    let fwhm = 1e-3;
    for c in [441.3, 555.55, 728.6] {
        let avg = aw.band_average(c, fwhm).unwrap();
        assert!(rel(avg, aw.at(c).unwrap()) < 1e-12, "{c}: {avg}");
    }
    let sigma = fwhm / FWHM_PER_SIGMA;
    for c in [440.0, 728.0] {
        let slope = |a: f64, b: f64| (aw.at(b).unwrap() - aw.at(a).unwrap()) / (b - a);
        let ds = slope(c, c + 0.1) - slope(c - 0.1, c);
        let avg = aw.band_average(c, fwhm).unwrap();
        let expect = aw.at(c).unwrap() + 0.395_578 * ds * sigma;
        assert!(
            (avg - expect).abs() < 1e-4 * (ds * sigma).abs() + 1e-15,
            "{c}: {avg}"
        );
    }
    // So narrow it underflows: falls back to the point value.
    assert_eq!(
        aw.band_average(500.0, 1e-300).unwrap(),
        aw.at(500.0).unwrap()
    );
}

#[test]
fn band_centre_outside_range_is_an_error_naming_the_table() {
    let e = water_absorption()
        .band_average(350.0, 10.0)
        .unwrap_err()
        .to_string();
    assert!(e.contains("aw_composite_380_1000.csv:aw_per_m"), "{e}");
    assert!(e.contains("350") && e.contains("380..1000"), "{e}");
    let e = seawater_scattering()
        .band_average(500.0, 0.0)
        .unwrap_err()
        .to_string();
    assert!(e.contains("bw_per_m") && e.contains("FWHM"), "{e}");
    assert!(seawater_scattering().band_average(f64::NAN, 10.0).is_err());
}

#[test]
fn band_averages_cover_the_grid_and_name_the_failing_band() {
    let bands = BandGrid::even(400.0, 700.0, 31).unwrap();
    let aw = water_absorption();
    let avgs = aw.band_averages(&bands).unwrap();
    assert_eq!(avgs.len(), 31);
    for (i, &c) in bands.centers_nm().iter().enumerate() {
        let one = aw
            .band_average(f64::from(c), f64::from(bands.fwhm_nm()[i]))
            .unwrap();
        assert_eq!(avgs[i], one);
    }
    // A 10 nm band smooths a_w but stays near the point value in the blue.
    assert!(rel(avgs[4], aw.at(440.0).unwrap()) < 0.1);
    let wide = BandGrid::even(800.0, 1100.0, 4).unwrap();
    let e = aw.band_averages(&wide).unwrap_err().to_string();
    assert!(e.contains("band 3") && e.contains("aw_per_m"), "{e}");
}

#[test]
fn table_new_rejects_bad_samples_naming_the_table() {
    let cases = [
        (vec![400.0], vec![1.0]),
        (vec![400.0, 500.0], vec![1.0]),
        (vec![400.0, 400.0], vec![1.0, 2.0]),
        (vec![500.0, 400.0], vec![1.0, 2.0]),
        (vec![400.0, 500.0], vec![1.0, f64::NAN]),
        (vec![-1.0, 500.0], vec![1.0, 2.0]),
        (vec![400.0, f64::INFINITY], vec![1.0, 2.0]),
    ];
    for (x, y) in cases {
        let e = Table::new("a_cdom", x.clone(), y).unwrap_err().to_string();
        assert!(e.starts_with("a_cdom:"), "{x:?}: {e}");
    }
}

#[test]
fn user_csv_with_comments_header_and_blank_lines_parses() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(
        &dir,
        "cdom.csv",
        "# measured 2024\r\n# units 1/m\r\nwavelength_nm, a\r\n400,0.5\r\n\r\n 450 , 0.25 \r\n500,0.125\r\n",
    );
    let t = Table::from_csv_file(&path, "water.a_cdom_file").unwrap();
    assert_eq!(t.x_nm(), &[400.0, 450.0, 500.0]);
    assert_eq!(t.y(), &[0.5, 0.25, 0.125]);
    assert!(t.name().contains("water.a_cdom_file"));
    // No header at all is fine too.
    let path = write(&dir, "bare.csv", "400,1\n500,2");
    assert_eq!(
        Table::from_csv_file(&path, "f").unwrap().at(450.0),
        Some(1.5)
    );
}

#[test]
fn user_csv_errors_name_file_line_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let check = |name: &str, text: &str, needles: &[&str]| {
        let path = write(&dir, name, text);
        let e = Table::from_csv_file(&path, "bottom.file").unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains(&path.display().to_string()), "{msg}");
        assert!(msg.contains("bottom.file"), "{msg}");
        for n in needles {
            assert!(msg.contains(n), "{name}: missing '{n}' in: {msg}");
        }
    };
    check(
        "badnum.csv",
        "# c\nnm,R\n400,0.1\n410,0.x2\n",
        &["line 4:", "'0.x2'"],
    );
    // A typo in the first row is an error, not a header.
    check("typo.csv", "4OO,0.1\n410,0.2\n", &["line 1:", "'4OO'"]);
    check("nan.csv", "400,0.1\n410,NaN\n", &["line 2:", "finite"]);
    check(
        "order.csv",
        "400,0.1\n420,0.2\n410,0.3\n",
        &["line 3:", "increase"],
    );
    check("dup.csv", "400,0.1\n400,0.2\n", &["line 2:", "increase"]);
    check("cols.csv", "400,0.1\n410,0.2,7\n", &["line 2:", "2 fields"]);
    check(
        "short.csv",
        "# only one\nnm,R\n400,0.1\n",
        &["at least 2 data rows, found 1"],
    );
    check("empty.csv", "", &["found 0"]);
    check(
        "neg.csv",
        "-400,0.1\n410,0.2\n",
        &["line 1:", "not positive"],
    );
    let missing = dir.path().join("missing.csv");
    let e = Table::from_csv_file(&missing, "bottom.file").unwrap_err();
    assert!(matches!(e, Error::Io { .. }), "{e}");
    assert!(e.to_string().contains("missing.csv"));
}

#[test]
fn embedded_parser_requires_its_header() {
    let path = Path::new("x.csv");
    let e = parse_csv("400,1\n500,2\n", path, "x", "x", Columns::Named(&["a"]))
        .unwrap_err()
        .to_string();
    assert!(e.contains("line 1") && e.contains("header"), "{e}");
    let e = parse_csv(
        "nm,b\n400,1\n500,2\n",
        path,
        "x",
        "x",
        Columns::Named(&["a"]),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("no column 'a'"), "{e}");
}
