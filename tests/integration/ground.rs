//! Land under the air: a Lambertian ground ([surface] kind = "lambertian")
//! and its exchange of light with the air against DISORT over the same
//! ground, surroundings beyond the domain, and the adjacency effect of
//! bright land beside water.

use crate::atmosphere::{disort, mean_se, refused, sky_against_disort, SkyCase};
use crate::common::*;
use littoral::scene::{Overrides, Scene};
use std::path::Path;

/// A Lambertian ground under the air: the sky at the surface (with the
/// light the ground reflects and the air returns, to every order), the
/// irradiances and the irradiance leaving the top against DISORT over the
/// same ground, as `the_sky_and_the_top_match_disort` does over a black
/// surface, within 3 sigma plus 1 % (Rayleigh) or 2 % (aerosol). Grounds
/// of reflectance 0.3 and 0.8.
#[test]
fn the_sky_over_a_lambertian_ground_matches_disort() {
    if !client("nanodisort (PyPI)", &["python3", "-c", "import nanodisort"]) {
        return;
    }
    let rayleigh = "atmosphere = { sky_photons = 20000 }";
    let aerosol = "atmosphere = { sky_photons = 20000, aerosol = { model = \"custom\", tau_550 = 0.3, angstrom = 1.0, ssa = 0.9, phase = { kind = \"henyey-greenstein\", g = 0.7 }, scale_height_km = 1.5 } }";
    let cases: Vec<SkyCase> = [
        (rayleigh, 0.3, 30.0, 0.01),
        (rayleigh, 0.8, 60.0, 0.01),
        (aerosol, 0.3, 30.0, 0.02),
    ]
    .into_iter()
    .map(|(a, r, sun, tol)| {
        let f: Box<dyn Fn(u64) -> Scene> = Box::new(move |seed| ground_scene(a, r, sun, seed, ""));
        (f, sun, tol)
    })
    .collect();
    sky_against_disort(&cases, false);
}

/// A four-band Lambertian ground of reflectance `r` (no water) under the
/// atmosphere `air` (a TOML line), the sun at `sun_deg`, with the TOML
/// lines `extra`.
fn ground_scene(air: &str, r: f64, sun_deg: f64, seed: u64, extra: &str) -> Scene {
    let text = minimal()
        .remove("water")
        .remove("photons")
        .remove("sun.irradiance")
        .merge(&format!(
            "seed = {seed}\nsun = {{ zenith_deg = {sun_deg:?}, spectrum = \"extraterrestrial\" }}\n\
             surface = {{ kind = \"lambertian\", reflectance = {r:?} }}\n{air}\n{extra}\n"
        ))
        .unwrap()
        .text();
    Scene::parse(&text, Path::new("ground.toml"), &Overrides::default()).unwrap()
}

/// A Lambertian ground seen through the air from 3 km and from above the
/// atmosphere, off nadir: every pixel's radiance at the sensor (the path
/// radiance, the ground's radiance through the air directly and scattered)
/// against DISORT's upward radiance at the sensor's level over the same
/// ground, within 3 sigma (the path radiance's) plus 1 % (Rayleigh) or 2 %
/// (aerosol: Henyey–Greenstein, and 6S's maritime model), with the domain
/// repeating and with the domain in its own mean (`[surroundings] kind =
/// "mean"`); the ground's own radiance is R E_d(0+) / pi and there is no
/// water-leaving radiance.
#[test]
fn a_lambertian_ground_seen_from_above_matches_disort() {
    if !client("nanodisort (PyPI)", &["python3", "-c", "import nanodisort"]) {
        return;
    }
    let dir = tempdir();
    let rayleigh = "atmosphere = { sky_photons = 20000 }";
    let aerosol = "atmosphere = { sky_photons = 20000, aerosol = { model = \"custom\", tau_550 = 0.3, angstrom = 1.0, ssa = 0.9, phase = { kind = \"henyey-greenstein\", g = 0.7 }, scale_height_km = 1.5 } }";
    let sensor = |alt: f64, vz: f64| {
        format!("sensor = {{ pixels = [4, 4], gsd_m = 1.0, altitude_m = {alt:?}, view_zenith_deg = {vz:?}, view_azimuth_deg = 120.0 }}")
    };
    let maritime = "atmosphere = { sky_photons = 20000, aerosol = { model = \"maritime\", tau_550 = 0.3, scale_height_km = 1.0 } }";
    let mean = "surroundings = { kind = \"mean\" }";
    let cases = [
        (rayleigh, 0.3, 700e3, 40.0, 0.01, ""),
        (aerosol, 0.5, 3e3, 30.0, 0.02, ""),
        (aerosol, 0.2, 700e3, 0.0, 0.02, ""),
        (maritime, 0.3, 700e3, 20.0, 0.02, ""),
        (aerosol, 0.5, 3e3, 30.0, 0.02, mean),
    ];
    let mut failures = Vec::new();
    for (k, (air, r, alt, vz, tol, around)) in cases.into_iter().enumerate() {
        let s = ground_scene(air, r, 30.0, 1, &format!("{}\n{around}", sensor(alt, vz)));
        let report = render_job(&s, &dir.path().join(format!("g{k}")), 0);
        let d = disort(&s.atmosphere_json(false).unwrap());
        let a = report.atmosphere.as_ref().unwrap();
        let open = |p: &str| littoral::cube::EnviCube::open(Path::new(p)).unwrap();
        let cube = open(&report.outputs.hdr);
        let product = |name: &str| {
            open(
                &report
                    .outputs
                    .products
                    .iter()
                    .find(|p| p.product == name)
                    .unwrap()
                    .hdr,
            )
        };
        let (lw, leaving) = (product("lw"), product("surface"));
        for (b, band) in d.iter().enumerate() {
            let want = band["at_sensor"].as_f64().unwrap();
            let se = a.L_path_stderr[b];
            for &got in &cube.band(b).unwrap() {
                let got = f64::from(got);
                if (got - want).abs() > 3.0 * se + tol * want {
                    failures.push(format!(
                        "case {k}, band {b}: {got} (L_path +- {se}) against {want}"
                    ));
                }
            }
            let ground = r * (a.Ed_direct[b] + a.Ed_diffuse[b]) / std::f64::consts::PI;
            assert!(lw.band(b).unwrap().iter().all(|&v| v == 0.0));
            for &v in &leaving.band(b).unwrap() {
                assert!(
                    (f64::from(v) / ground - 1.0).abs() < 1e-6,
                    "{v} against {ground}"
                );
            }
        }
        assert_eq!(a.spherical_albedo.len(), cube.bands());
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A dark ground 1 m across (R 0.05) in bright Lambertian surroundings
/// (R 0.4), seen from 3 km at nadir through an aerosol: its pixels read the
/// path radiance, the dark ground through the direct transmittance and
/// the surroundings through the rest of t_up (a path scattered in the air
/// lands within a metre of the pixel too rarely to count),
/// L_path + T R_d E / pi + (t_up - T) R_s E / pi, with E the irradiance
/// the surroundings' exchange with the air sets; within 3 sigma (the
/// pixels' spread over 16 pixels of 256 samples, L_path's and t_up's) plus 1
/// %. The same scene with periodic edges reads the dark ground alone.
#[test]
fn surroundings_light_the_view_through_the_air() {
    let dir = tempdir();
    let air = "atmosphere = { sky_photons = 20000, aerosol = { model = \"custom\", tau_550 = 0.3, angstrom = 1.0, ssa = 0.9, phase = { kind = \"henyey-greenstein\", g = 0.7 }, scale_height_km = 1.5 } }";
    let view = "domain = { size_m = [1.0, 1.0] }\n\
                sensor = { pixels = [4, 4], gsd_m = 0.25, samples_per_pixel = 256, altitude_m = 3000.0 }";
    let around = format!("{view}\nsurroundings = {{ kind = \"lambertian\", reflectance = 0.4 }}");
    let (r_d, r_s) = (0.05, 0.4);
    let open = |p: &str| littoral::cube::EnviCube::open(Path::new(p)).unwrap();
    let mut means = Vec::new();
    for (k, extra) in [around.as_str(), view].into_iter().enumerate() {
        let s = ground_scene(air, r_d, 30.0, 5, extra);
        let report = render_job(&s, &dir.path().join(format!("s{k}")), 0);
        let a = report.atmosphere.as_ref().unwrap();
        let cube = open(&report.outputs.hdr);
        let mut per_band = Vec::new();
        for b in 0..cube.bands() {
            let v: Vec<f64> = cube
                .band(b)
                .unwrap()
                .iter()
                .map(|&x| f64::from(x))
                .collect();
            let (m, se) = mean_se(&v);
            let e = a.Ed_direct[b] + a.Ed_diffuse[b];
            let (t, t_up) = (a.t_view[b], a.t_up[b]);
            let r_around = if k == 0 { r_s } else { r_d };
            let want = a.L_path[b]
                + t * r_d * e / std::f64::consts::PI
                + (t_up - t) * r_around * e / std::f64::consts::PI;
            let sigma = (se * se
                + a.L_path_stderr[b].powi(2)
                + (a.t_up_stderr[b] * r_around * e / std::f64::consts::PI).powi(2))
            .sqrt();
            assert!(
                (m - want).abs() <= 3.0 * sigma + 0.01 * want,
                "case {k}, band {b}: {m} +- {sigma} against {want}"
            );
            per_band.push(m);
        }
        means.push(per_band);
        if k == 0 {
            assert!(!a.spherical_albedo.is_empty());
        }
    }
    // The bright surroundings brighten the dark ground's pixels.
    assert!(means[0].iter().zip(&means[1]).all(|(a, b)| a > b));
}

/// The adjacency effect: a bay of deep water 800 m across in land of
/// reflectance 0.3, seen from 700 km through an aerosol 1 km high. At the
/// sensor the pixels by the shore read brighter than those 150 m or more
/// out by more than 3 sigma in every band, and the photon map and the path
/// integrator agree, band for band and ring by ring (0-50 m, 50-100 m,
/// 100-150 m, the rest), within 3 sigma (the rings' pixel spreads) plus 1
/// %.
#[test]
fn water_by_bright_land_reads_brighter_near_the_shore() {
    let dir = tempdir();
    let scene = |integrator: &str, spp: u32| {
        let text = format!(
            "name = \"bay\"\n[spectral]\ncenters_nm = [443.0, 555.0, 670.0]\nfwhm_nm = [10.0, 10.0, 10.0]\n\
             [sun]\nzenith_deg = 30.0\nspectrum = \"extraterrestrial\"\n[domain]\nsize_m = [800.0, 800.0]\n\
             [water]\niop = {{ a = 0.05, b = 0.3 }}\nphase = {{ kind = \"fournier-forand\", bb_ratio = 0.0183 }}\n\
             [photons]\ncount = 1000000\n\
             [sensor]\npixels = [16, 16]\ngsd_m = 50.0\nsamples_per_pixel = {spp}\naltitude_m = 700000.0\n\
             [render]\nintegrator = \"{integrator}\"\n\
             [atmosphere]\nsky_photons = 20000\n[atmosphere.aerosol]\nmodel = \"custom\"\ntau_550 = 0.2\n\
             angstrom = 0.5\nssa = 0.98\nphase = {{ kind = \"henyey-greenstein\", g = 0.75 }}\nscale_height_km = 1.0\n\
             [surroundings]\nkind = \"lambertian\"\nreflectance = 0.3\n"
        );
        Scene::parse(&text, Path::new("bay.toml"), &Overrides::default()).unwrap()
    };
    let open = |p: &str| littoral::cube::EnviCube::open(Path::new(p)).unwrap();
    let pm = render_job(&scene("photon-map", 4), &dir.path().join("pm"), 0);
    let path = render_job(&scene("path", 64), &dir.path().join("path"), 0);
    let (a, b) = (open(&pm.outputs.hdr), open(&path.outputs.hdr));
    // Rings by the distance from the pixel's centre to the nearest shore.
    let ring = |i: usize| -> usize {
        let (x, y) = ((i % 16) as f64 + 0.5, (i / 16) as f64 + 0.5);
        let d = 50.0 * x.min(16.0 - x).min(y).min(16.0 - y);
        (d / 50.0).floor().min(3.0) as usize
    };
    for band in 0..a.bands() {
        let rings = |c: &littoral::cube::EnviCube| -> Vec<(f64, f64)> {
            let v = c.band(band).unwrap();
            (0..4)
                .map(|r| {
                    let x: Vec<f64> = (0..v.len())
                        .filter(|&i| ring(i) == r)
                        .map(|i| f64::from(v[i]))
                        .collect();
                    mean_se(&x)
                })
                .collect()
        };
        let (ra, rb) = (rings(&a), rings(&b));
        for (name, r) in [("photon map", &ra), ("path", &rb)] {
            let (shore, out) = (r[0], r[3]);
            let se = shore.1.hypot(out.1);
            assert!(
                shore.0 - out.0 > 3.0 * se,
                "{name}, band {band}: by the shore {shore:?}, out {out:?}"
            );
        }
        for k in 0..4 {
            let (x, y) = (ra[k], rb[k]);
            assert!(
                (x.0 - y.0).abs() <= 3.0 * x.1.hypot(y.1) + 0.01 * y.0,
                "band {band}, ring {k}: photon map {x:?}, path {y:?}"
            );
        }
    }
}

/// A Lambertian ground refuses what belongs to water (the sea's surface
/// keys, a floor, targets, tallies, radiometers, `[water]`, `[photons]`,
/// a photon map) and needs its reflectance; a sea needs `[water]` and
/// `[photons]` and takes no ground reflectance; `emit` refuses a ground.
/// Each error names its key.
#[test]
fn lambertian_ground_keys_are_checked() {
    let dry = minimal().remove("water").remove("photons").text();
    let ground = "[surface]\nkind = \"lambertian\"\nreflectance = 0.3";
    let with = |extra: &str| format!("{ground}\n{extra}");
    refused(
        &dry,
        &[
            ("[surface]\nkind = \"lambertian\"", "surface.reflectance"),
            (&with("wind_speed = 3.0"), "surface.wind_speed"),
            (&with("[bottom]\ndepth_m = 3.0"), "bottom"),
            (
                &with("[[target]]\nkind = \"panel\"\ncenter_m = [5.0, 5.0, -1.0]\nsize_m = [1.0, 1.0]\nreflectance = 0.5"),
                "target",
            ),
            (&with("[tally]\ndepths_m = [1.0]"), "tally.depths_m"),
            (
                &with("[[radiometer]]\ndepth_m = 1.0\nview = \"nadir\"\nposition_m = [5.0, 5.0]"),
                "radiometer",
            ),
            (&with("[render]\nintegrator = \"photon-map\""), "render.integrator"),
            (&with("[photons]\ncount = 100"), "photons"),
            (&with("[water]\nchl = 1.0"), "water"),
            ("", "water"),
        ],
    );
    refused(
        MINIMAL_SCENE,
        &[("[surface]\nreflectance = 0.3", "surface.reflectance")],
    );
    // Surroundings: only under air, and Lambertian ones with a reflectance.
    let air = MINIMAL_SCENE.replace("irradiance = 1.0", "spectrum = \"extraterrestrial\"")
        + "[atmosphere]\nsky_photons = 1000\n";
    let lambertian = "[surroundings]\nkind = \"lambertian\"";
    refused(
        MINIMAL_SCENE,
        &[(
            &format!("{lambertian}\nreflectance = 0.3"),
            "surroundings.kind",
        )],
    );
    refused(
        &air,
        &[
            (lambertian, "surroundings.reflectance"),
            (
                "[surroundings]\nkind = \"periodic\"\nreflectance = 0.3",
                "surroundings.reflectance",
            ),
            (
                "[surroundings]\nkind = \"mean\"\nreflectance = 0.3",
                "surroundings.reflectance",
            ),
            (
                &format!("{lambertian}\nreflectance = 1.5"),
                "surroundings.reflectance",
            ),
            ("[surroundings]\nkind = \"water\"", "surroundings.water"),
            (
                "[surroundings]\nkind = \"mean\"\nwater = { chl = 1.0 }",
                "surroundings.water",
            ),
            (
                "[surroundings]\nkind = \"water\"\nwater = { chl = -1.0 }",
                "surroundings.water",
            ),
            (
                "[surroundings]\nkind = \"water\"\nwater = { chl = 1.0, depth = 3.0 }",
                "surroundings.water",
            ),
        ],
    );
    let s = Scene::parse(
        &format!("{dry}\n{ground}\n"),
        Path::new("g.toml"),
        &Overrides::default(),
    )
    .unwrap();
    assert_eq!(s.render.integrator, littoral::scene::IntegratorMode::Path);
    assert!(s.summary().contains("Lambertian ground"), "{}", s.summary());
    let e = littoral::emit::Emitter::new(&s)
        .err()
        .expect("nothing to emit")
        .to_string();
    assert!(e.contains("Lambertian ground"), "{e}");
}

/// `[surroundings] kind = "water"` puts deep water of its own IOPs around
/// the domain. With the domain's own water (deep, the same IOPs) around
/// it, a sensor at 700 km, where nearly all the light scattered into the
/// view comes from beyond a 10 m domain, reads the repeating domain's
/// scattered part (L_t less L_path and the direct transmittance times
/// the radiance leaving the pixel's ground) within 4 combined standard
/// errors per band (the pixels' spread, both by the path integrator, each
/// within 1 %); with ten times the scattering around it, more. The water
/// beyond is the scene's with its `[water]` replaced, under the same air
/// and surface.
#[test]
fn deep_water_surroundings_of_the_domain_s_own_water_read_as_the_repeating_domain() {
    let dir = tempdir();
    let base = MINIMAL_SCENE.replace("irradiance = 1.0", "spectrum = \"extraterrestrial\"");
    let air = "[surface]\nkind = \"cox-munk\"\nwind_speed = 5.0\n\
               [sensor]\npixels = [16, 16]\ngsd_m = 0.5\nsamples_per_pixel = 512\n\
               altitude_m = 700000.0\nview_zenith_deg = 20.0\n\
               [render]\nintegrator = \"path\"\n\
               [atmosphere]\nsky_photons = 4000\n[atmosphere.aerosol]\nmodel = \"custom\"\n\
               tau_550 = 0.4\nscale_height_km = 1.0\n";
    let read = |around: &str, k: &str| {
        let text = format!("{base}\n{air}{around}");
        let s = Scene::parse(&text, Path::new("sea.toml"), &Overrides::default()).unwrap();
        let report = render_job(&s, &dir.path().join(k), 0);
        let open = |p: &str| littoral::cube::EnviCube::open(Path::new(p)).unwrap();
        let cube = open(&report.outputs.hdr);
        let leaving = open(
            &report
                .outputs
                .products
                .iter()
                .find(|p| p.product == "surface")
                .unwrap()
                .hdr,
        );
        let a = report.atmosphere.as_ref().unwrap();
        (0..cube.bands())
            .map(|b| {
                let v: Vec<f64> = cube
                    .band(b)
                    .unwrap()
                    .iter()
                    .zip(leaving.band(b).unwrap())
                    .map(|(&t, l)| f64::from(t) - a.L_path[b] - a.t_view[b] * f64::from(l))
                    .collect();
                crate::atmosphere::mean_se(&v)
            })
            .collect::<Vec<_>>()
    };
    let repeating = read("", "periodic");
    let same = read(
        "[surroundings]\nkind = \"water\"\nwater = { iop = { a = 0.1, b = 0.2 } }\n",
        "same",
    );
    let brighter = read(
        "[surroundings]\nkind = \"water\"\nwater = { iop = { a = 0.1, b = 2.0 } }\n",
        "brighter",
    );
    for b in 0..repeating.len() {
        let ((m0, s0), (m1, s1), (m2, s2)) = (repeating[b], same[b], brighter[b]);
        let se = (s0 * s0 + s1 * s1).sqrt();
        assert!(
            (m1 - m0).abs() < 4.0 * se,
            "band {b}: {m1} +- {s1} against the repeating domain's {m0} +- {s0}"
        );
        assert!(se < 0.01 * m0, "band {b}: {se} against {m0}");
        assert!(
            m2 - m0 > 4.0 * (s0 * s0 + s2 * s2).sqrt(),
            "band {b}: {m2} against {m0}"
        );
    }
}
