use super::*;

/// These values come from evaluating the formula term by term in plain
/// Python (`n0 + (n1 + n2*T + n3*T**2)*S + n4*T**2 + (n5 + n6*S +
/// n7*T)/l + n8/l**2 + n9/l**3`), with the coefficients as printed in
/// Zhang, Hu & He's (2009) `RInw`. So the test catches a coefficient
/// copied wrongly into this file or a term misplaced. It is not evidence
/// that the formula is accurate: the next tests check that.
#[test]
fn formula_regression_values() {
    let cases = [
        (400.0, 20.0, 35.0, 1.3499375625),
        (550.0, 20.0, 35.0, 1.3407886893),
        (700.0, 20.0, 35.0, 1.3364795073),
        (900.0, 20.0, 35.0, 1.3331052318),
        (400.0, 20.0, 0.0, 1.3432114375),
        (550.0, 20.0, 0.0, 1.3343381893),
        (700.0, 20.0, 0.0, 1.3301865073),
        (900.0, 20.0, 0.0, 1.3269405652),
        (480.0, 5.0, 10.0, 1.3403236907),
        (632.8, 28.0, 33.0, 1.3368492996),
    ];
    for (l, t, s, want) in cases {
        let got = quan_fry(l, t, s);
        assert!(
            (got - want).abs() < 1e-9,
            "{l} nm {t} C {s} PSU: {got} vs {want}"
        );
    }
}

/// Pure water against an independent formulation. The reference is
/// IAPWS R9-97 (Release on the Refractive Index of Ordinary Water
/// Substance), which gives the index relative to vacuum, divided by the
/// index of standard dry air (Ciddor 1996, Appl. Opt. 35, 1566). The
/// density at 1 atm comes from Tanaka et al. (2001, Metrologia 38, 301).
/// All of this was computed in Python. That IAPWS code reproduces the
/// R9-97 check values 1.39277824 (997.047435 kg/m³, 298.15 K, 226.5 nm)
/// and 1.00949307 (30.4758534 kg/m³, 773.15 K, 589.3 nm). The values are
/// rounded to 6 decimals. The tolerance of 5e-5 allows for Quan & Fry's
/// accuracy of about 3e-5 plus the IAPWS uncertainty and rounding. The
/// largest difference on a 25 nm by 5 °C grid over 400–700 nm and
/// 0–30 °C is 3.5e-5. If the index were treated as relative to vacuum,
/// it would be off by about 3.7e-4, and this test would fail.
#[test]
fn pure_water_matches_iapws_r9_97_relative_to_air() {
    let cases = [
        (400.0, 0.0, 1.344208),
        (400.0, 20.0, 1.343180),
        (450.0, 30.0, 1.338145),
        (500.0, 5.0, 1.337350),
        (550.0, 10.0, 1.335030),
        (550.0, 20.0, 1.334312),
        (589.3, 20.0, 1.332980),
        (600.0, 25.0, 1.332164),
        (650.0, 15.0, 1.331701),
        (700.0, 5.0, 1.331048),
        (700.0, 30.0, 1.329110),
    ];
    for (l, t, want) in cases {
        let got = quan_fry(l, t, 0.0);
        assert!((got - want).abs() < 5e-5, "{l} nm {t} C: {got} vs {want}");
    }
}

/// A published reference value: pure water at 20 °C and the sodium D
/// line (589.3 nm) has n = 1.33299 relative to air. This is the 0 °Brix
/// entry of the ICUMSA (1974) refractometer table, as tabulated in the
/// `thermo` Python package. For comparison, IAPWS R9-97 gives 1.33335
/// relative to vacuum, which is 1.33298 relative to air. The formula gives
/// 1.33300. The tolerance of 3e-5 is Quan & Fry's accuracy.
#[test]
fn pure_water_sodium_d_line_at_20_c() {
    let got = quan_fry(589.3, 20.0, 0.0);
    assert!((got - 1.33299).abs() < 3e-5, "{got}");
}

/// A published table of pure water relative to air at 10, 20 and 30 °C,
/// with values to 4 decimals: Table 1 of the "www.h2o" article on
/// scubageek.com (its wavelengths are in Å, given here in nm). The
/// tolerance of 1e-4 allows for 4-decimal rounding (5e-5) plus the fit's accuracy.
/// The largest difference is 7e-5, at 404.7 nm and 20 °C, where IAPWS
/// agrees with the formula rather than the table.
#[test]
fn pure_water_matches_handbook_table() {
    let table = [
        (706.5, [1.3307, 1.3300, 1.3290]),
        (589.3, [1.3337, 1.3330, 1.3319]),
        (501.6, [1.3371, 1.3364, 1.3353]),
        (404.7, [1.3435, 1.3427, 1.3417]),
    ];
    for (l, row) in table {
        for (t, want) in [10.0, 20.0, 30.0].into_iter().zip(row) {
            let got = quan_fry(l, t, 0.0);
            assert!((got - want).abs() < 1e-4, "{l} nm {t} C: {got} vs {want}");
        }
    }
}

/// The salinity terms against an independent fit. The reference is
/// Millard & Seaver (1990, Deep-Sea Res. 37, 1909), a separate 27-term
/// fit whose region II covers salinity at 1 atm and 500–700 nm. Its
/// values are also relative to air: for pure water at 589.3 nm and 20 °C
/// it gives 1.332986. Its coefficients were taken from Zhang & Hu's
/// `RIsw_MS`, and the value was computed in Python as n_MS(S = 35) −
/// n_MS(S = 0). Only region II enters this difference. The largest disagreement
/// is 3.5e-5, at 500 nm and 0 °C. The tolerance of 5e-5 covers Quan &
/// Fry's accuracy of about 3e-5 plus Millard & Seaver's region II
/// standard deviation of 4.7e-6. The n1 = 1.799e-4 typo would shift
/// every increment by 7e-5, which this test would catch.
#[test]
fn salinity_increment_matches_millard_seaver_1990() {
    let cases = [
        (500.0, 0.0, 0.006999547),
        (600.0, 0.0, 0.006895855),
        (700.0, 0.0, 0.006833332),
        (500.0, 10.0, 0.006713534),
        (600.0, 10.0, 0.006597279),
        (700.0, 10.0, 0.006522193),
        (500.0, 20.0, 0.006515759),
        (600.0, 20.0, 0.006386941),
        (700.0, 20.0, 0.006299292),
        (500.0, 30.0, 0.006431588),
        (600.0, 30.0, 0.006290207),
        (700.0, 30.0, 0.006189994),
    ];
    for (l, t, want) in cases {
        let got = quan_fry(l, t, 35.0) - quan_fry(l, t, 0.0);
        assert!((got - want).abs() < 5e-5, "{l} nm {t} C: {got} vs {want}");
    }
}

/// Checks the extrapolation error stated in the module doc. Pure water
/// at 20 °C and 900 nm, relative to air, is 1.326610 by IAPWS R9-97 with
/// Ciddor air, and 1.326621 by Daimon & Masumura (2007, Appl. Opt. 46,
/// 3811; 20 °C Sellmeier fit, also divided by the index of air). The
/// formula gives 1.326941, about 3.3e-4 higher. The test fails if the
/// formula changes, or if the doc's figure stops being true.
#[test]
fn extrapolation_error_at_900_nm_is_as_documented() {
    let err = quan_fry(900.0, 20.0, 0.0) - 1.326610;
    assert!((2.5e-4..4.0e-4).contains(&err), "{err}");
}

#[test]
fn decreases_with_wavelength_across_400_to_700_nm() {
    for t in [0.0, 5.0, 10.0, 15.0, 20.0, 25.0, 30.0] {
        for s in [0.0, 10.0, 20.0, 30.0, 35.0] {
            let mut prev = quan_fry(400.0, t, s);
            for l in 401..=700 {
                let n = quan_fry(f64::from(l), t, s);
                assert!(n < prev, "{l} nm {t} C {s} PSU");
                prev = n;
            }
        }
    }
}

#[test]
fn increases_with_salinity() {
    for l in [400.0, 450.0, 500.0, 550.0, 600.0, 650.0, 700.0] {
        for t in [0.0, 10.0, 20.0, 30.0] {
            let mut prev = quan_fry(l, t, 0.0);
            for s in 1..=35 {
                let n = quan_fry(l, t, f64::from(s));
                assert!(n > prev, "{l} nm {t} C {s} PSU");
                prev = n;
            }
        }
    }
}

/// The formula falls steadily from 0 °C, and so does IAPWS R9-97 at 1 atm
/// (at 589.3 nm it gives 1.333965 at 0 °C and 1.333893 at 5 °C, relative
/// to air). So the check covers the whole range 0–30 °C, not only
/// temperatures above 4 °C.
#[test]
fn decreases_with_temperature() {
    for l in [400.0, 500.0, 600.0, 700.0] {
        for s in [0.0, 20.0, 35.0] {
            let mut prev = quan_fry(l, 0.0, s);
            for t in 1..=30 {
                let n = quan_fry(l, f64::from(t), s);
                assert!(n < prev, "{l} nm {t} C {s} PSU");
                prev = n;
            }
        }
    }
}
