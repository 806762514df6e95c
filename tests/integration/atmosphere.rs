//! The atmosphere against DISORT (nanodisort from PyPI, libRadtran's C
//! DISORT, installed by `tools/test.sh`): the sun's beam, the sky at the
//! surface and the light leaving the top, band by band, over a black
//! surface; and the scene keys that set it.

use crate::common::*;
use littoral::scene::{Overrides, Scene};
use std::path::Path;
use std::process::Command;

const SEEDS: u64 = 16;

/// A four-band scene under `atmosphere` (TOML of the section and its
/// aerosol) with the sun at `sun_deg`, seed `seed`.
pub(crate) fn scene(atmosphere: &str, sun_deg: f64, seed: u64) -> Scene {
    let text = format!(
        "seed = {seed}\n{}\n{atmosphere}\n",
        MINIMAL_SCENE
            .replace("zenith_deg = 30.0", &format!("zenith_deg = {sun_deg:?}"))
            .replace("irradiance = 1.0", "spectrum = \"extraterrestrial\"")
    );
    Scene::parse(&text, Path::new("air.toml"), &Overrides::default()).unwrap()
}

pub(crate) fn mean_se(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

/// Per band of DISORT's answer: direct, diffuse, up at the top, and the
/// sky's and the top's cells.
pub(crate) fn disort(json: &serde_json::Value) -> Vec<serde_json::Value> {
    let dir = tempdir();
    let file = dir.path().join("air.json");
    std::fs::write(&file, serde_json::to_vec(json).unwrap()).unwrap();
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/clients/disort_atmosphere.py"
    );
    let out = Command::new("python3")
        .args([script, p(&file)])
        .output()
        .expect("python3");
    assert!(
        out.status.success(),
        "DISORT failed (nanodisort comes from PyPI, installed by .ci/run):\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// Each band's irradiances and, over sun and view zenith angles up to 60
/// degrees, the sky's and the top's radiance in sectors of 5 degrees of
/// zenith by 30 of azimuth, against DISORT within 3 sigma plus 1 % for air
/// alone and 2 % with an aerosol (sigma from 16 seeds' spread); the direct
/// beam to 1e-9. Cases: Rayleigh at sun 0, 30 and 60 degrees; Rayleigh and
/// a maritime-like aerosol (tau 0.3, g 0.7, albedo 0.9) at 30 and 60; 6S's
/// maritime model (its Mie phase function, tau 0.3) at 30. DISORT's ground
/// is black, so the sky leaves out what the sea returns (`sea_coupling =
/// false`).
#[test]
fn the_sky_and_the_top_match_disort() {
    if !client("nanodisort (PyPI)", &["python3", "-c", "import nanodisort"]) {
        return;
    }
    let rayleigh = "[atmosphere]\nsky_photons = 20000\nsea_coupling = false";
    let aerosol = "[atmosphere]\nsky_photons = 20000\nsea_coupling = false\n[atmosphere.aerosol]\nmodel = \"custom\"\ntau_550 = 0.3\nangstrom = 1.0\nssa = 0.9\nphase = { kind = \"henyey-greenstein\", g = 0.7 }\nscale_height_km = 1.5";
    let maritime = "[atmosphere]\nsky_photons = 20000\nsea_coupling = false\n[atmosphere.aerosol]\nmodel = \"maritime\"\ntau_550 = 0.3\nscale_height_km = 1.0";
    let cases = [
        (rayleigh, 0.0, 0.01),
        (rayleigh, 30.0, 0.01),
        (rayleigh, 60.0, 0.01),
        (aerosol, 30.0, 0.02),
        (aerosol, 60.0, 0.02),
        (maritime, 30.0, 0.02),
    ];
    let cases: Vec<SkyCase> = cases
        .into_iter()
        .map(|(a, sun, tol)| {
            let f: Box<dyn Fn(u64) -> Scene> = Box::new(move |seed| scene(a, sun, seed));
            (f, sun, tol)
        })
        .collect();
    sky_against_disort(&cases, true);
}

/// A case of [`sky_against_disort`]: its scene for a seed, the sun's
/// zenith angle (degrees) and the relative tolerance.
pub(crate) type SkyCase = (Box<dyn Fn(u64) -> Scene>, f64, f64);

/// Each case's sky at the surface, irradiances and irradiance leaving the
/// top (and with `toa`, the radiance leaving the top) over [`SEEDS`]
/// seeds, against DISORT within 3 sigma plus the case's tolerance.
pub(crate) fn sky_against_disort(cases: &[SkyCase], toa: bool) {
    let mut failures = Vec::new();
    let mut worst = (0.0, String::new());
    for (make, sun, tol) in cases {
        let (sun, tol) = (*sun, *tol);
        let runs: Vec<serde_json::Value> = (1..=SEEDS)
            .map(|seed| make(seed).atmosphere_json(toa).unwrap())
            .collect();
        let reference = disort(&runs[0]);
        let nb = reference.len();
        for b in 0..nb {
            let d = &reference[b];
            let nm = d["nm"].as_f64().unwrap();
            let case = format!("sun {sun}, {nm} nm, tol {tol}");
            let field = |k: &str| -> Vec<f64> {
                runs.iter()
                    .map(|r| r["bands"][b]["band"][k].as_f64().unwrap())
                    .collect()
            };
            let direct = field("direct")[0];
            let want = d["direct"].as_f64().unwrap();
            if (direct / want - 1.0).abs() > 1e-9 {
                failures.push(format!("{case}: direct {direct} against {want}"));
            }
            let mut check = |what: String, got: &[f64], want: f64| {
                let (m, se) = mean_se(got);
                let r = (m - want).abs() / (3.0 * se + tol * want);
                if r > worst.0 {
                    worst = (r, format!("{case} {what}: {m} +- {se} against {want}"));
                }
                if (m - want).abs() > 3.0 * se + tol * want {
                    failures.push(format!("{case}: {what} {m} +- {se} against {want}"));
                }
            };
            check(
                "diffuse".into(),
                &field("diffuse"),
                d["diffuse"].as_f64().unwrap(),
            );
            check(
                "diffuse flux".into(),
                &field("diffuse_flux"),
                d["diffuse"].as_f64().unwrap(),
            );
            check(
                "up at the top".into(),
                &field("up_at_top"),
                d["up_at_top"].as_f64().unwrap(),
            );
            let surfaces: &[(&str, &str)] = if toa {
                &[("sky", "sky_radiance"), ("toa", "toa_radiance")]
            } else {
                &[("sky", "sky_radiance")]
            };
            for &(key, ours) in surfaces {
                let cells = |r: &serde_json::Value| -> Vec<f64> {
                    r["bands"][b][ours]
                        .as_array()
                        .unwrap()
                        .iter()
                        .map(|v| v.as_f64().unwrap())
                        .collect()
                };
                let all: Vec<Vec<f64>> = runs.iter().map(cells).collect();
                let theirs: Vec<f64> = d[key]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|v| v.as_f64().unwrap())
                    .collect();
                // Rows of 5 degrees to 60 degrees; sectors of 3 cells.
                for row in 0..12 {
                    for sector in 0..6 {
                        let idx: Vec<usize> = (0..3).map(|k| row * 18 + sector * 3 + k).collect();
                        let sum = |v: &[f64]| idx.iter().map(|&i| v[i]).sum::<f64>() / 3.0;
                        let got: Vec<f64> = all.iter().map(|v| sum(v)).collect();
                        let what = format!(
                            "{key} {}-{} deg zenith, {}-{} deg azimuth",
                            row * 5,
                            row * 5 + 5,
                            sector * 30,
                            sector * 30 + 30
                        );
                        check(what, &got, sum(&theirs));
                    }
                }
            }
        }
    }
    eprintln!("worst against its allowance: {:.2}, {}", worst.0, worst.1);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Each of `bad` (a TOML fragment added to `base`, and the key its error
/// must name) is refused, naming the key.
pub(crate) fn refused(base: &str, bad: &[(&str, &str)]) {
    for (extra, key) in bad {
        let text = format!("{base}\n{extra}\n");
        let e = Scene::parse(&text, Path::new("bad.toml"), &Overrides::default())
            .err()
            .unwrap_or_else(|| panic!("accepted: {extra}"))
            .to_string();
        assert!(e.contains(key), "{extra}: {e}");
    }
}

/// The keys: a profile that does not exist, a sky given as well, a
/// surface spectrum for the sun, a day without an atmosphere, a bad
/// aerosol; each refused naming its key.
#[test]
fn atmosphere_keys_are_checked() {
    let base = MINIMAL_SCENE.replace("irradiance = 1.0", "spectrum = \"extraterrestrial\"");
    let bad = [
        ("[atmosphere]\nprofile = \"mars\"", "atmosphere.profile"),
        (
            "[atmosphere]\n[sky]\nradiance = 0.1",
            "sky.radiance",
        ),
        ("[atmosphere]\nozone_du = -3.0", "atmosphere.ozone_du"),
        ("[atmosphere]\nrayleigh = { tau = -1.0 }", "atmosphere.rayleigh"),
        ("[atmosphere]\nsky_photons = 5", "atmosphere.sky_photons"),
        (
            "[atmosphere]\n[atmosphere.aerosol]\nmodel = \"custom\"\ntau_550 = 0.1\nssa = 1.5",
            "atmosphere.aerosol.ssa",
        ),
        (
            "[atmosphere]\n[atmosphere.aerosol]\nmodel = \"custom\"\ntau_550 = 0.1\nscale_height_km = 1.0\ntop_km = 2.0",
            "atmosphere.aerosol.top_km",
        ),
        (
            "[atmosphere]\n[atmosphere.aerosol]\nmodel = \"maritime\"\ntau_550 = 0.1\nangstrom = 1.0",
            "atmosphere.aerosol.angstrom",
        ),
        (
            "[atmosphere]\n[atmosphere.aerosol]\nmodel = \"urban\"\ntau_550 = 0.1\nphase = { kind = \"henyey-greenstein\", g = 0.7 }",
            "atmosphere.aerosol.phase",
        ),
        (
            "[atmosphere]\n[atmosphere.aerosol]\nmodel = \"smoke\"\ntau_550 = 0.1",
            "model",
        ),
    ];
    refused(&base, &bad);
    // A named model is tabulated from 350 to 860 nm: a band at 900 nm is
    // refused unless the scene clamps.
    let named = "[atmosphere]\n[atmosphere.aerosol]\nmodel = \"continental\"\ntau_550 = 0.1";
    let wide = base.replace("end_nm = 700.0", "end_nm = 900.0");
    refused(&wide, &[(named, "atmosphere.aerosol.model")]);
    let clamped = wide.replace("bands = 4", "bands = 4\nout_of_range = \"clamp\"");
    Scene::parse(
        &format!("{clamped}\n{named}\n"),
        Path::new("c.toml"),
        &Overrides::default(),
    )
    .unwrap();
    let direct = MINIMAL_SCENE.replace("irradiance = 1.0", "spectrum = \"astm-g173-direct\"");
    let e = Scene::parse(
        &format!("{direct}\n[atmosphere]\n"),
        Path::new("bad.toml"),
        &Overrides::default(),
    )
    .err()
    .unwrap()
    .to_string();
    assert!(
        e.contains("sun.spectrum") && e.contains("extraterrestrial"),
        "{e}"
    );
    let day = MINIMAL_SCENE.replace("irradiance = 1.0", "irradiance = 1.0\nday_of_year = 10");
    let e = Scene::parse(&day, Path::new("bad.toml"), &Overrides::default())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("sun.day_of_year"), "{e}");
}

/// With an atmosphere the sun at the surface is the top's beam times its
/// direct transmittance and the Earth–Sun distance, the sky's irradiance
/// is the atmosphere's, and its shape changes with the band: the blue sky
/// is the more diffuse (brighter at the zenith relative to the
/// irradiance than the red, whose sky is the aureole's).
#[test]
fn the_atmosphere_sets_the_sun_and_sky_at_the_surface() {
    let air = "[atmosphere]\n[atmosphere.aerosol]\nmodel = \"custom\"\ntau_550 = 0.2";
    let s = scene(air, 30.0, 1);
    let a = s.atmosphere.as_ref().unwrap();
    let again = scene(air, 30.0, 1);
    for (b, band) in a.bands.iter().enumerate() {
        let e = s.sun.irradiance[b];
        assert!((e / (band.toa_irradiance * band.direct_transmittance) - 1.0).abs() < 1e-12);
        assert!((s.sky.irradiance[b] / band.diffuse - 1.0).abs() < 1e-12);
        assert_eq!(
            again.sky.irradiance[b], s.sky.irradiance[b],
            "deterministic"
        );
    }
    // 60 degrees from the zenith, opposite the sun: 90 degrees from it.
    let away = glam::Vec3::new(-(60f32.to_radians().sin()), 0.0, 0.5);
    let g = |b: usize| s.sky.model.relative(b, away);
    assert!(g(0) > 1.2 * g(3), "{} {}", g(0), g(3));
    let text = format!(
        "{}\n{air}\n",
        MINIMAL_SCENE.replace(
            "irradiance = 1.0",
            "spectrum = \"extraterrestrial\"\nday_of_year = 3"
        )
    );
    let perihelion = Scene::parse(&text, Path::new("air.toml"), &Overrides::default()).unwrap();
    let f = perihelion.sun.irradiance[0] / s.sun.irradiance[0];
    assert!(
        (f - littoral::optics::atmosphere::earth_sun_factor(3.0)).abs() < 1e-12,
        "{f}"
    );
}

/// The path radiance a sensor above the surface sees, against DISORT's
/// upward radiance at the sensor's level in its exact direction over a
/// black surface, and the total transmittance from a Lambertian ground to
/// it (t_up, from DISORT over a white ground), each within 3 sigma plus
/// 1 % (Rayleigh) or 2 % (aerosol): at 3 km and above the atmosphere, at
/// nadir and off nadir.
#[test]
fn the_path_radiance_matches_disort() {
    if !client("nanodisort (PyPI)", &["python3", "-c", "import nanodisort"]) {
        return;
    }
    let rayleigh = "[atmosphere]\nsky_photons = 20000";
    let aerosol = "[atmosphere]\nsky_photons = 20000\n[atmosphere.aerosol]\nmodel = \"custom\"\ntau_550 = 0.3\nangstrom = 1.0\nssa = 0.9\nphase = { kind = \"henyey-greenstein\", g = 0.7 }\nscale_height_km = 1.5";
    let sensor = |alt: f64, vz: f64, va: f64| {
        format!("[sensor]\npixels = [4, 4]\ngsd_m = 1.0\naltitude_m = {alt:?}\nview_zenith_deg = {vz:?}\nview_azimuth_deg = {va:?}")
    };
    let cases = [
        (rayleigh, 60.0, sensor(700e3, 40.0, 180.0), 0.01),
        (rayleigh, 30.0, sensor(3e3, 0.0, 0.0), 0.01),
        (aerosol, 30.0, sensor(3e3, 30.0, 120.0), 0.02),
        (aerosol, 45.0, sensor(700e3, 50.0, 0.0), 0.02),
    ];
    let mut failures = Vec::new();
    for (air, sun, view, tol) in cases {
        let s = scene(&format!("{air}\n{view}"), sun, 1);
        let json = s.atmosphere_json(false).unwrap();
        let d = disort(&json);
        let v = &json["view"];
        for (b, band) in d.iter().enumerate() {
            let want = band["path_radiance"].as_f64().unwrap();
            let got = v["path_radiance"][b].as_f64().unwrap();
            let se = v["path_radiance_se"][b].as_f64().unwrap();
            if (got - want).abs() > 3.0 * se + tol * want {
                failures.push(format!(
                    "sun {sun}, {view:?}, band {b}: {got} +- {se} against {want}"
                ));
            }
            let want = band["t_up"].as_f64().unwrap();
            let got = v["transmittance_up"][b].as_f64().unwrap();
            let se = v["transmittance_up_se"][b].as_f64().unwrap();
            if (got - want).abs() > 3.0 * se + tol * want {
                failures.push(format!(
                    "t_up, sun {sun}, {view:?}, band {b}: {got} +- {se} against {want}"
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Through air that only absorbs (ozone, no Rayleigh, no aerosol) a
/// sensor above the atmosphere sees each pixel's radiance leaving the
/// surface times the direct transmittance exp(-tau / mu_v), exactly,
/// off nadir too; the water-leaving radiance and R_rs are the surface's.
#[test]
fn a_sensor_above_absorbing_air_sees_the_surface_attenuated() {
    let dir = tempdir();
    let air = "[atmosphere]\nrayleigh = false\nozone_du = 400.0\nsky_photons = 1000";
    let view = "[sensor]\npixels = [3, 2]\ngsd_m = 1.0\nsamples_per_pixel = 2\nview_zenith_deg = 35.0\nview_azimuth_deg = 60.0";
    let at_surface = scene(&format!("{air}\n{view}"), 30.0, 3);
    let above = scene(&format!("{air}\n{view}\naltitude_m = 800000.0"), 30.0, 3);
    let t = above
        .atmosphere
        .as_ref()
        .unwrap()
        .view
        .as_ref()
        .unwrap()
        .transmittance
        .clone();
    let mu_v = 35f64.to_radians().cos();
    for (b, band) in above.atmosphere.as_ref().unwrap().bands.iter().enumerate() {
        // The view direction is held in f32.
        let want = (-band.tau.extinction() / mu_v).exp();
        assert!((t[b] / want - 1.0).abs() < 1e-6, "{} {want}", t[b]);
        assert!(band.tau.ozone > 0.0 || band.nm < 450.0);
    }
    let r0 = render_job(&at_surface, &dir.path().join("surface"), 0);
    let r1 = render_job(&above, &dir.path().join("above"), 0);
    let open = |p: &str| littoral::cube::EnviCube::open(Path::new(p)).unwrap();
    let (c0, c1) = (open(&r0.outputs.hdr), open(&r1.outputs.hdr));
    assert_eq!(c0.bands(), t.len());
    for (b, tb) in t.iter().enumerate() {
        let (v0, v1) = (c0.band(b).unwrap(), c1.band(b).unwrap());
        for (x0, x1) in v0.iter().zip(&v1) {
            let want = f64::from(*x0) * tb;
            assert!(
                (f64::from(*x1) - want).abs() <= 1e-6 * want.abs() + 1e-12,
                "band {b}: {x1} against {want}"
            );
        }
    }
    let lw = |r: &littoral::job::report::RunReport| open(&r.outputs.products[0].hdr);
    let (l0, l1) = (lw(&r0), lw(&r1));
    for b in 0..l0.bands() {
        assert_eq!(l0.band(b).unwrap(), l1.band(b).unwrap(), "L_w, band {b}");
    }
    let a = r1.atmosphere.clone().unwrap();
    assert_eq!(a.altitude_m, Some(800000.0));
    assert!(a.L_path.iter().all(|&l| l == 0.0), "{:?}", a.L_path);
    // From the surface: the three surface products; from above: rho_t and
    // L_path too, rho_t = pi L_t / (E_0 mu_0) in every pixel and band.
    let suffixes = |r: &littoral::job::report::RunReport| -> Vec<String> {
        r.outputs
            .products
            .iter()
            .map(|p| p.product.clone())
            .collect()
    };
    assert_eq!(suffixes(&r0), ["lw", "surface", "rrs"]);
    assert_eq!(
        suffixes(&r1),
        ["lw", "surface", "rrs", "rhot", "lpath", "tdown", "tup"]
    );
    let product = |r: &littoral::job::report::RunReport, name: &str| {
        open(
            &r.outputs
                .products
                .iter()
                .find(|p| p.product == name)
                .unwrap()
                .hdr,
        )
    };
    let (rho, path) = (product(&r1, "rhot"), product(&r1, "lpath"));
    let mu0 = 30f64.to_radians().cos();
    for b in 0..c1.bands() {
        let scale = std::f64::consts::PI / (a.toa_irradiance[b] * mu0);
        for (l, r) in c1.band(b).unwrap().iter().zip(rho.band(b).unwrap()) {
            let want = f64::from(*l) * scale;
            assert!(
                (f64::from(r) - want).abs() <= 1e-6 * want,
                "band {b}: {r} against {want}"
            );
        }
        assert!(path.band(b).unwrap().iter().all(|&v| v == 0.0));
    }
    // Air that only absorbs scatters nothing toward the sensor: t_up is
    // the direct transmittance along the view.
    assert_eq!(a.t_up, a.t_view);
    // The per-band table, with the view's columns only from above, and the
    // page's section at the sensor.
    let table = |r: &littoral::job::report::RunReport| {
        let text = std::fs::read_to_string(r.outputs.atmosphere_csv.as_ref().unwrap()).unwrap();
        let lines: Vec<Vec<String>> = text
            .lines()
            .map(|l| l.split(',').map(str::to_string).collect())
            .collect();
        lines
    };
    let (t0, t1) = (table(&r0), table(&r1));
    assert_eq!((t0.len(), t1.len()), (c1.bands() + 1, c1.bands() + 1));
    assert!(!t0[0].contains(&"t_up".to_string()));
    let col = |name: &str| t1[0].iter().position(|h| h == name).unwrap();
    for b in 0..c1.bands() {
        let v = |name: &str| t1[b + 1][col(name)].parse::<f64>().unwrap();
        assert_eq!(v("t_up"), a.t_up[b]);
        assert_eq!(v("E0"), a.toa_irradiance[b]);
        assert_eq!(v("rho_path"), 0.0);
    }
    let page =
        |r: &littoral::job::report::RunReport| std::fs::read_to_string(&r.outputs.html).unwrap();
    assert!(!page(&r0).contains("At the sensor"));
    for section in [
        "At the sensor, 800000 m up",
        "Reflectance at the sensor",
        "Transmittances of the air",
    ] {
        assert!(page(&r1).contains(section), "{section}");
    }
    // Under an atmosphere, seen from above or not, the emission's budget of
    // the air.
    for r in [&r0, &r1] {
        assert!(page(r).contains("The air over the domain"));
    }
}

/// The sensor above the surface is refused without an atmosphere and for
/// a pinhole camera; view angles only for an orthographic sensor.
#[test]
fn sensor_altitude_keys_are_checked() {
    let base = MINIMAL_SCENE.replace("irradiance = 1.0", "spectrum = \"extraterrestrial\"");
    let bad = [
        ("[sensor]\naltitude_m = 3000.0", "sensor.altitude_m"),
        (
            "[atmosphere]\n[sensor]\naltitude_m = 0.5",
            "sensor.altitude_m",
        ),
        (
            "[atmosphere]\n[sensor]\nview_zenith_deg = 80.0",
            "sensor.view_zenith_deg",
        ),
        (
            "[atmosphere]\n[sensor]\nkind = \"pinhole\"\nposition_m = [5.0, 5.0, 20.0]\nlook_at_m = [5.0, 5.0, 0.0]\nfov_deg = 10.0\naltitude_m = 3000.0",
            "sensor.altitude_m",
        ),
    ];
    refused(&base, &bad);
}

/// Deep water under an aerosol, seen from above the atmosphere 20 degrees
/// off nadir: the photon map (with the domain repeating, and in its own
/// mean) and the path integrator agree band for band
/// on the radiance at the sensor within 3 sigma + 2 % (sigma from their
/// standard-error cubes; the photon map's pixels share photons, so its
/// error of the mean is taken as its pixels' mean error, as if they were
/// fully correlated).
#[test]
fn the_photon_map_and_the_path_integrator_agree_at_the_top() {
    let dir = tempdir();
    let text = |integrator: &str, spp: u32, around: &str| {
        format!(
            "name = \"deep\"\n[spectral]\ncenters_nm = [443.0, 560.0, 670.0]\nfwhm_nm = [10.0, 10.0, 10.0]\n\
             [sun]\nzenith_deg = 30.0\nspectrum = \"extraterrestrial\"\n\
             [domain]\nsize_m = [20.0, 20.0]\n\
             [water]\niop = {{ a = 0.05, b = 0.3 }}\nphase = {{ kind = \"fournier-forand\", bb_ratio = 0.0183 }}\n\
             [photons]\ncount = 1000000\n\
             [sensor]\npixels = [4, 4]\ngsd_m = 2.0\nsamples_per_pixel = {spp}\naltitude_m = 800000.0\n\
             view_zenith_deg = 20.0\nview_azimuth_deg = 90.0\n\
             [render]\nintegrator = \"{integrator}\"\n\
             [atmosphere]\nsky_photons = 20000\n[atmosphere.aerosol]\nmodel = \"custom\"\ntau_550 = 0.1\n\
             angstrom = 0.5\nssa = 0.98\nphase = {{ kind = \"henyey-greenstein\", g = 0.75 }}\nscale_height_km = 1.0\n{around}\n"
        )
    };
    let parse = |t: &str| Scene::parse(t, Path::new("deep.toml"), &Overrides::default()).unwrap();
    let pm = render_job(
        &parse(&text("photon-map", 4, "")),
        &dir.path().join("pm"),
        0,
    );
    let path = render_job(&parse(&text("path", 256, "")), &dir.path().join("path"), 0);
    // Uniform water in its own mean looks the same from above.
    let mean = "[surroundings]\nkind = \"mean\"";
    let pm_mean = render_job(
        &parse(&text("photon-map", 4, mean)),
        &dir.path().join("pm-mean"),
        0,
    );
    let open = |p: &str| littoral::cube::EnviCube::open(Path::new(p)).unwrap();
    let mean = |c: &littoral::cube::EnviCube, b: usize| {
        let v = c.band(b).unwrap();
        v.iter().map(|&x| f64::from(x)).sum::<f64>() / v.len() as f64
    };
    // The air's cubes hold the report's L_path, t_down and t_up in every
    // pixel.
    let air = pm.atmosphere.as_ref().unwrap();
    for (name, reported) in [
        ("lpath", &air.L_path),
        ("tdown", &air.t_down),
        ("tup", &air.t_up),
    ] {
        let cube = pm.outputs.products.iter().find(|p| p.product == name);
        let cube = open(&cube.unwrap().hdr);
        assert_eq!(cube.bands(), reported.len(), "{name}");
        for (b, want) in reported.iter().enumerate() {
            assert!(*want > 0.0, "{name}, band {b}");
            assert!(
                cube.band(b).unwrap().iter().all(|&v| v == *want as f32),
                "{name}, band {b}"
            );
        }
    }
    let l_path = open(&path.outputs.hdr);
    let se_path = open(path.outputs.stderr_hdr.as_ref().unwrap());
    for (run, b) in [&pm, &pm_mean]
        .into_iter()
        .flat_map(|r| (0..l_path.bands()).map(move |b| (r, b)))
    {
        let (l_pm, se_pm) = (
            open(&run.outputs.hdr),
            open(run.outputs.stderr_hdr.as_ref().unwrap()),
        );
        let (a, p) = (mean(&l_pm, b), mean(&l_path, b));
        let sa = mean(&se_pm, b);
        let sp = {
            let v = se_path.band(b).unwrap();
            (v.iter().map(|&x| f64::from(x) * f64::from(x)).sum::<f64>()).sqrt() / v.len() as f64
        };
        let sigma = (sa * sa + sp * sp).sqrt();
        assert!(
            (a - p).abs() < 3.0 * sigma + 0.02 * p,
            "band {b}: photon map {a} +- {sa}, path {p} +- {sp}"
        );
    }
}

/// `render --no-atmosphere` sees the sea from just above the surface
/// through a scene whose sensor flies above it: from the same photon map
/// (reused, not emitted again) the water-leaving radiance, R_rs and the
/// radiance leaving the surface are byte for byte the airborne render's,
/// the cube is that radiance leaving the surface (not the darker one
/// through the air), and the products of the air are not written.
#[test]
fn no_atmosphere_sees_the_airborne_scene_from_the_surface() {
    let dir = tempdir();
    let text = littoral::scene::text::SceneText::parse(
        &MINIMAL_SCENE.replace("irradiance = 1.0", "spectrum = \"extraterrestrial\""),
    )
    .unwrap()
    .merge(
        "name = \"air\"\n\
         sensor = { pixels = [4, 4], gsd_m = 1.0, altitude_m = 3000.0 }\n\
         atmosphere = { sky_photons = 2000, aerosol = { model = \"custom\", tau_550 = 0.3 } }",
    )
    .unwrap()
    .text();
    let scene = dir.path().join("air.toml");
    std::fs::write(&scene, text).unwrap();
    let map = dir.path().join("air.map");
    let (up, down) = (dir.path().join("up"), dir.path().join("down"));
    for (out, flag) in [(&up, None), (&down, Some("--no-atmosphere"))] {
        let mut args = vec![
            "render",
            p(&scene),
            "--out",
            p(out),
            "--map",
            p(&map),
            "--quiet",
        ];
        args.extend(flag);
        let run = littoral(&args);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
    }
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(down.join("air.json")).unwrap()).unwrap();
    assert_eq!(report["reused_map"], true);
    assert!(report["atmosphere"]["altitude_m"].is_null());
    for product in ["lw", "rrs", "surface"] {
        let name = format!("air.{product}.bsq");
        assert_eq!(
            std::fs::read(up.join(&name)).unwrap(),
            std::fs::read(down.join(&name)).unwrap(),
            "{name}"
        );
    }
    assert!(up.join("air.rhot.bsq").exists() && up.join("air.lpath.bsq").exists());
    assert!(!down.join("air.rhot.bsq").exists() && !down.join("air.lpath.bsq").exists());
    // The surface's radiance at the surface; through the air, L_path plus
    // the attenuated surface: different.
    assert_ne!(
        std::fs::read(up.join("air.bsq")).unwrap(),
        std::fs::read(down.join("air.bsq")).unwrap()
    );
}

/// The air's budget over the domain closes from the top of the
/// atmosphere: the sun's power at the top plus what the surface sends up
/// (the photons' E_u(0+)) is what reaches the surface, leaves the top and
/// is absorbed in the air, band by band within 4 standard errors. The sky
/// over the sea holds what the air returns of the sea's light, found from
/// path-integrator calls (`render::sea_air`); the photons' E_u(0+) is an
/// independent measure of the light it was found from. A bright sea
/// (a sand floor 2 m down under clear water, Cox–Munk 5 m/s, sun at 30°)
/// under an aerosol that does not absorb: E_d(0+) is 3.3-8.8 % above the
/// sky over a black surface's. With `sea_coupling = false` the sea's light
/// is taken to leave the top, and the budget closes too; counted as
/// returned instead, it misses the sea's E_u(0+) whole (75 to 90 standard
/// errors, tried).
#[test]
fn the_air_s_budget_closes_from_the_top() {
    let air = "[atmosphere]\nsky_photons = 100000\n[atmosphere.aerosol]\nmodel = \"custom\"\n\
               tau_550 = 0.5\nangstrom = 1.0\nssa = 1.0\nphase = { kind = \"henyey-greenstein\", g = 0.7 }\n\
               scale_height_km = 1.0";
    let text = format!(
        "seed = 3\n{}\n{air}\n[bottom]\ndepth_m = 2.0\nreflectance = 0.6\n[surface]\nkind = \"cox-munk\"\nwind_speed = 5.0\n",
        MINIMAL_SCENE
            .replace("irradiance = 1.0", "spectrum = \"extraterrestrial\"")
            .replace("count = 1000", "count = 400000")
    );
    for coupling in ["", "sea_coupling = false"] {
        let text = text.replace("[atmosphere]\n", &format!("[atmosphere]\n{coupling}\n"));
        let scene = Scene::parse(&text, Path::new("budget.toml"), &Overrides::default()).unwrap();
        let emitter = littoral::emit::Emitter::new(&scene).unwrap();
        emitter.trace_all(0).unwrap();
        let report = emitter.report();
        let budget = report.air.as_ref().expect("an atmosphere's budget");
        for b in 0..budget.top.len() {
            eprintln!(
                "{coupling:?} band {b}: top {:.4} + up {:.4} = surface {:.4} + space {:.4} + absorbed {:.4}: {:+.2} sigma",
                budget.top[b],
                budget.surface_up[b],
                budget.to_surface[b],
                budget.to_space[b],
                budget.absorbed_air[b],
                budget.closure_sigma_per_band[b]
            );
        }
        assert!(
            budget.closure_sigma < 4.0,
            "{coupling:?}: the air's budget is off by {:?} standard errors",
            budget.closure_sigma_per_band
        );
        assert!(report.energy.closure_sigma < 4.0);
    }
}
