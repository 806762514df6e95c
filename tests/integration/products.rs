//! The products beside the total radiance: water-leaving radiance,
//! surface-reflected radiance and remote-sensing reflectance.

use crate::common::{f32s, minimal_with, render_job, tempdir};
use littoral::optics::surface::fresnel_reflectance;
use littoral::scene::{IntegratorMode, Overrides, Scene};
use std::path::Path;

const N_WATER: f64 = 1.34;
const SKY: f64 = 0.05;
const SUN_ZENITH_DEG: f64 = 30.0;

/// Deep enough water over a black floor, flat surface, isotropic sky,
/// three bands; `b` the scattering coefficient.
fn scene(b: f64) -> String {
    minimal_with(&format!(
        r#"
name = "prod"
spectral = {{ start_nm = 450.0, end_nm = 650.0, bands = 3 }}
sun = {{ zenith_deg = {SUN_ZENITH_DEG} }}
sky = {{ radiance = {SKY} }}
surface = {{ refractive_index = {N_WATER} }}
domain = {{ size_m = [20.0, 20.0] }}
water = {{ iop = {{ a = 0.2, b = {b} }} }}
bottom = {{ depth_m = 5.0, reflectance = 0.0 }}
photons = {{ count = 200000 }}
sensor = {{ pixels = [6, 6] }}
"#
    ))
}

/// L_t, L_w, surface-reflected and R_rs cubes of a render.
fn render(text: &str, integrator: IntegratorMode, dir: &Path) -> [Vec<f64>; 4] {
    let o = Overrides {
        integrator: Some(integrator),
        samples_per_pixel: Some(2),
        ..Overrides::default()
    };
    let s = Scene::parse(text, Path::new("prod.toml"), &o).unwrap();
    let r = render_job(&s, dir, 0);
    let names: Vec<&str> = r
        .outputs
        .products
        .iter()
        .map(|p| p.product.as_str())
        .collect();
    assert_eq!(names, ["lw", "surface", "rrs"]);
    assert_eq!(r.outputs.products[2].units, "sr-1");
    let read = |f: &str| f32s(f).into_iter().map(f64::from).collect::<Vec<_>>();
    let exr = exr::prelude::read_all_flat_layers_from_file(&r.outputs.exr).unwrap();
    let layers: Vec<String> = exr
        .layer_data
        .iter()
        .map(|l| l.attributes.layer_name.as_ref().unwrap().to_string())
        .collect();
    for want in ["radiance", "lw", "surface", "rrs"] {
        assert!(layers.iter().any(|l| l == want), "EXR layers {layers:?}");
    }
    [
        read(&r.outputs.bsq),
        read(&r.outputs.products[0].bsq),
        read(&r.outputs.products[1].bsq),
        read(&r.outputs.products[2].bsq),
    ]
}

/// With a flat surface the surface-reflected radiance is the sky times
/// the Fresnel reflectance at the (near-nadir) view; with clear,
/// non-scattering water over a black floor nothing leaves the water, and
/// with scattering water L_t = L_w + surface to float rounding and R_rs =
/// L_w / (E_sun cos(theta_s) + pi L_sky). Both integrators.
#[test]
fn total_radiance_is_water_leaving_plus_surface_reflected() {
    let dir = tempdir();
    let rho = fresnel_reflectance(1.0, 1.0, N_WATER);
    let ed = SUN_ZENITH_DEG.to_radians().cos() + std::f64::consts::PI * SKY;
    for integrator in [IntegratorMode::PhotonMap, IntegratorMode::Path] {
        for b in [0.0, 0.5] {
            let out = dir.path().join(format!("{integrator:?}-{b}"));
            let [lt, lw, surface, rrs] = render(&scene(b), integrator, &out);
            for i in 0..lt.len() {
                let want = rho * SKY;
                assert!(
                    (surface[i] - want).abs() <= 1e-4 * want,
                    "{integrator:?} b {b}: surface {} against rho L_sky {want}",
                    surface[i]
                );
                assert!(
                    (lt[i] - lw[i] - surface[i]).abs() <= 1e-6 * lt[i],
                    "L_t {} != L_w {} + surface {}",
                    lt[i],
                    lw[i],
                    surface[i]
                );
                assert!((rrs[i] - lw[i] / ed).abs() <= 1e-6 * rrs[i].abs().max(1e-12));
                if b == 0.0 {
                    assert_eq!(
                        lw[i], 0.0,
                        "{integrator:?}: no light leaves clear water over black"
                    );
                } else {
                    assert!(lw[i] > 0.0);
                }
            }
        }
    }
}

/// With the water's index after Quan & Fry (1995), each band's
/// surface-reflected sky is the Fresnel reflectance at that band's own
/// index (flat surface, nadir view), for both integrators, and L_t = L_w +
/// surface still holds term by term.
#[test]
fn surface_reflectance_follows_each_bands_refractive_index() {
    let dir = tempdir();
    let text = scene(0.5).replace(
        &format!("refractive_index = {N_WATER}"),
        "refractive_index = \"quan-fry\"\ntemperature_c = 15.0\nsalinity_psu = 30.0",
    );
    let nm = [450.0, 550.0, 650.0];
    let n: Vec<f64> = nm
        .iter()
        .map(|&l| littoral::optics::water_index::quan_fry(l, 15.0, 30.0))
        .collect();
    assert!(n[0] - n[2] > 5e-3, "dispersion across the bands: {n:?}");
    for integrator in [IntegratorMode::PhotonMap, IntegratorMode::Path] {
        let out = dir.path().join(format!("qf-{integrator:?}"));
        let [lt, lw, surface, _] = render(&text, integrator, &out);
        let pixels = lt.len() / 3;
        for i in 0..lt.len() {
            let want = fresnel_reflectance(1.0, 1.0, n[i / pixels]) * SKY;
            assert!(
                (surface[i] - want).abs() <= 1e-4 * want,
                "{integrator:?} band {}: surface {} against rho(n_b) L_sky {want}",
                i / pixels,
                surface[i]
            );
            assert!((lt[i] - lw[i] - surface[i]).abs() <= 1e-6 * lt[i]);
        }
        // The 450 nm band reflects more than the 650 nm one (n 1.3409 against 1.3365).
        assert!(surface[0] > surface[2 * pixels] * 1.005);
    }
}

/// The depth profiles and Kd as CSV beside the report: one row per tally
/// depth and band with the report's values, and Kd = ln(Ed(z1) / Ed(z2)) /
/// (z2 - z1) from those rows.
#[test]
fn profiles_and_kd_are_written_as_csv() {
    let dir = tempdir();
    let text = scene(0.5).replace("[sensor]", "[tally]\ndepths_m = [0.0, 1.0, 2.5]\n[sensor]");
    let s = Scene::parse(&text, Path::new("prod.toml"), &Overrides::default()).unwrap();
    let r = render_job(&s, &dir.path().join("out"), 0);
    let emission = r.emission.as_ref().unwrap();
    let table = |path: &str| -> Vec<Vec<f64>> {
        let text = std::fs::read_to_string(path).unwrap();
        let mut lines = text.lines();
        let cols = lines.next().unwrap().split(',').count();
        lines
            .map(|l| {
                let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
                assert_eq!(v.len(), cols, "{l}");
                v
            })
            .collect()
    };
    let rows = table(r.outputs.profiles_csv.as_deref().unwrap());
    assert_eq!(rows.len(), 3 * 3);
    for (d, t) in emission.tally.iter().enumerate() {
        for b in 0..3 {
            let row = &rows[d * 3 + b];
            assert_eq!(row[0], t.depth_m);
            assert_eq!(row[1], emission.bands_nm[b] as f64);
            assert_eq!([row[2], row[6], row[10]], [t.Ed[b], t.Eod[b], t.Lu[b]]);
            // A flat floor at 3 m: all water at every tally depth.
            assert_eq!((row[14], t.water_fraction), (1.0, 1.0));
        }
    }
    let kd = table(r.outputs.kd_csv.as_deref().unwrap());
    assert_eq!(kd.len(), 2 * 3);
    for row in &kd {
        let ed = |z: f64, nm: f64| {
            rows.iter()
                .find(|r| r[0] == z && r[1] == nm)
                .map(|r| r[2])
                .unwrap()
        };
        let want = (ed(row[0], row[2]) / ed(row[1], row[2])).ln() / (row[1] - row[0]);
        assert!(
            (row[3] - want).abs() <= 1e-9 * want.abs().max(1e-9),
            "{row:?} against {want}"
        );
    }
}

/// `[sensor] response` writes the radiance and every product in the
/// sensor's bands beside them (here two Gaussian bands from a CSV named
/// relative to the scene): each sensor band of each cube is the
/// response-weighted sum of that cube's bands. An unknown sensor is an
/// error naming the key.
#[test]
fn sensor_response_writes_the_cubes_in_the_sensor_bands() {
    let dir = tempdir();
    std::fs::write(
        dir.path().join("two.csv"),
        "band,center_nm,fwhm_nm\nblue,480,30\ngreen,560,30\n",
    )
    .unwrap();
    let text = scene(0.8).replace(
        "pixels = [6, 6]",
        "pixels = [6, 6]\nresponse = \"csv:two.csv\"",
    );
    let s = Scene::parse(&text, &dir.path().join("prod.toml"), &Overrides::default()).unwrap();
    let r = render_job(&s, &dir.path().join("out"), 0);
    let products: Vec<&str> = r
        .outputs
        .sensor_cubes
        .iter()
        .map(|c| c.product.as_str())
        .collect();
    assert_eq!(products, ["radiance", "lw", "surface", "rrs"]);
    assert!(r.outputs.sensor_cubes[0].hdr.ends_with("prod.two.hdr"));
    let sensor = s.sensor.response.as_ref().unwrap();
    let weights = sensor.weights(&s.bands);
    assert_eq!(weights.len(), 2);
    let pixels = 36;
    let sources = std::iter::once(&r.outputs.bsq).chain(r.outputs.products.iter().map(|p| &p.bsq));
    for (source, files) in sources.zip(&r.outputs.sensor_cubes) {
        let (c, got) = (f32s(source), f32s(&files.bsq));
        for (o, w) in weights.iter().enumerate() {
            for i in 0..pixels {
                let want: f64 = w
                    .weights
                    .iter()
                    .map(|(b, w)| w * c[b * pixels + i] as f64)
                    .sum();
                let v = got[o * pixels + i] as f64;
                let what = &files.product;
                assert!(
                    (v - want).abs() <= 1e-6 * want.abs().max(1e-12),
                    "{what} band {o} pixel {i}"
                );
            }
        }
    }
    let bad = text.replace("csv:two.csv", "pace-oci");
    let e = Scene::parse(&bad, &dir.path().join("prod.toml"), &Overrides::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("response") && e.contains("pace-oci"), "{e}");
}

/// Profiles are means over the water present at each depth: over the
/// built-in scene's floor, sloping from a beach 1 m above the water to
/// 15 m deep along x, the share of the domain that is water at depth d is
/// (15 - d) / 16 (the beach is none of it), to the sampling grid's 1/256;
/// and a tally's irradiance is that
/// of the water there. Two scenes over the same deep water, one whose
/// floor rises to 1 m over the east half (a step), read the same E_d at
/// 3 m within their standard errors (5 sigma), where the domain mean of
/// the stepped scene would read it near half.
#[test]
fn profiles_are_means_over_the_water_present() {
    let s = Scene::coastal(&Overrides::default()).unwrap();
    for (d, want) in [
        (0.0, 15.0 / 16.0),
        (0.3, 14.7 / 16.0),
        (1.0, 14.0 / 16.0),
        (5.0, 10.0 / 16.0),
        (14.0, 1.0 / 16.0),
    ] {
        let got = littoral::emit::report::water_fraction(&s, d);
        assert!(
            (got - want).abs() <= 1.0 / 256.0 + 1e-12,
            "{d} m: {got} against {want}"
        );
    }
    let dir = tempdir();
    let grid = |step: bool| {
        let mut rows = Vec::new();
        for _ in 0..9 {
            let row: Vec<&str> = (0..9)
                .map(|i| if step && i >= 5 { "1.0" } else { "20.0" })
                .collect();
            rows.push(row.join(","));
        }
        rows.join("\n") + "\n"
    };
    let ed_at_3 = |step: bool| {
        let name = if step { "step" } else { "flat" };
        std::fs::write(dir.path().join(format!("{name}.csv")), grid(step)).unwrap();
        let text = minimal_with(&format!(
            "name = \"{name}\"\n[domain]\nsize_m = [40.0, 40.0]\n[bottom]\nheightfield = \"{name}.csv\"\nreflectance = 0.0\n\
             [tally]\ndepths_m = [0.5, 3.0]\n[photons]\ncount = 200000\n[sensor]\npixels = [2, 2]\n"
        ));
        let s = Scene::parse(
            &text,
            &dir.path().join(format!("{name}.toml")),
            &Overrides::default(),
        )
        .unwrap();
        let r = render_job(&s, &dir.path().join(name), 0);
        let t = r.emission.unwrap().tally[1].clone();
        (t.water_fraction, t.Ed, t.Ed_stderr)
    };
    let (w_flat, ed_flat, se_flat) = ed_at_3(false);
    let (w_step, ed_step, se_step) = ed_at_3(true);
    assert_eq!(w_flat, 1.0);
    // Columns 0-4 of 9 grid points deep: the floor rises between x = 20
    // and 25 m, crossing 3 m at x = 20 + 5 * 17 / 19 m.
    let want = (20.0 + 5.0 * 17.0 / 19.0) / 40.0;
    assert!(
        (w_step - want).abs() <= 1.0 / 256.0 + 1e-12,
        "{w_step} against {want}"
    );
    for b in 0..ed_flat.len() {
        let se = (se_flat[b].powi(2) + se_step[b].powi(2)).sqrt();
        assert!(
            (ed_step[b] - ed_flat[b]).abs() <= 5.0 * se,
            "band {b}: {} against {} (se {se})",
            ed_step[b],
            ed_flat[b]
        );
    }
}
