//! Land in the domain: a floor that rises above the water line (`[land]`).
//! Level land against its exact radiance, sloping land against a
//! quadrature of the sky and the sea it sees, shadows cast by land on
//! land, emission's share of light falling on land, the water by the shore
//! by both integrators, and the keys.

use crate::common::*;
use littoral::scene::{IntegratorMode, Overrides, Scene};
use littoral::store::MapFile;
use std::f64::consts::PI;
use std::path::Path;

/// `fragment` merged into the minimal scene, parsed for `integrator` at
/// `spp` samples per pixel.
fn land_scene(fragment: &str, integrator: IntegratorMode, spp: u32) -> Scene {
    let o = Overrides {
        integrator: Some(integrator),
        samples_per_pixel: Some(spp),
        ..Overrides::default()
    };
    Scene::parse(&minimal_with(fragment), Path::new("land.toml"), &o).unwrap()
}

/// A heightfield of `columns` depths along x (two identical rows), written
/// into `dir`; its path.
fn heightfield(dir: &Path, columns: &[f64]) -> String {
    let row = columns
        .iter()
        .map(|d| format!("{d:?}"))
        .collect::<Vec<_>>()
        .join(", ");
    let path = dir.join("hf.csv");
    std::fs::write(&path, format!("{row}\n{row}\n")).unwrap();
    path.to_str().unwrap().to_string()
}

/// The total radiance, water-leaving radiance and R_rs cubes of a render
/// of `scene` (band-major: [band][line][sample]).
fn cubes(scene: &Scene) -> [Vec<f32>; 3] {
    let dir = tempdir();
    render_job(scene, dir.path(), 0);
    let name = &scene.name;
    ["bsq", "lw.bsq", "rrs.bsq"].map(|s| f32s(dir.path().join(format!("{name}.{s}"))))
}

/// Level land reads exactly R / pi (E_sun cos(theta_s) + E_sky), band by
/// band, under a CIE clear sky, by both integrators (the sun's part is a
/// shadow ray, the sky's a control variate exact where nothing hides the
/// sky), with no water-leaving radiance and no R_rs; the water beside it
/// reads light.
#[test]
fn level_land_reads_its_exact_radiance() {
    let dir = tempdir();
    // 4 m of water to x = 10 m, a ramp up to a level plateau 1 m above the
    // water from x = 20 m to the domain's edge (40 m).
    let hf = heightfield(dir.path(), &[4.0, 4.0, -1.0, -1.0, -1.0]);
    let fragment = format!(
        "sun = {{ zenith_deg = 40.0, azimuth_deg = 30.0 }}\n\
         sky = {{ radiance = 0.05, distribution = \"cie-clear\" }}\n\
         domain = {{ size_m = [40.0, 10.0] }}\n\
         bottom = {{ heightfield = \"{hf}\", reflectance = 0.2 }}\n\
         land = {{ reflectance = 0.3 }}\n\
         photons = {{ count = 20000 }}\n\
         sensor = {{ pixels = [40, 10], gsd_m = 1.0 }}\n"
    );
    for integrator in [IntegratorMode::PhotonMap, IntegratorMode::Path] {
        let scene = land_scene(&fragment, integrator, 2);
        // The ramp (27 degrees) is lower than the sun (50 degrees).
        assert!(scene.land_warnings().is_empty());
        let nb = scene.bands.len();
        let [l, lw, rrs] = cubes(&scene);
        for b in 0..nb {
            let exact = 0.3 / PI * scene.incident_irradiance(b);
            for y in 0..10 {
                // On the plateau, clear of its edge.
                for x in 21..40 {
                    let i = (b * 10 + y) * 40 + x;
                    let v = f64::from(l[i]);
                    assert!(
                        (v / exact - 1.0).abs() < 1e-5,
                        "{integrator:?} band {b} ({x}, {y}): {v} against {exact}"
                    );
                    assert_eq!((lw[i], rrs[i]), (0.0, 0.0), "({x}, {y})");
                }
                // Over 4 m of water.
                let i = (b * 10 + y) * 40 + 5;
                assert!(lw[i] > 0.0 && rrs[i] > 0.0, "{integrator:?} water ({y})");
            }
        }
    }
}

/// Land sloping 14 degrees toward the sea, under an isotropic sky, beside
/// black water over a black floor: every land pixel's radiance is R / pi
/// (E_sun n.s + L_sky Q), with Q the sky's share of the land's hemisphere,
/// pi (1 + cos alpha) / 2, plus the flat sea's Fresnel reflection of the
/// sky below the horizon, by a quadrature. The mean over the land pixels
/// within 4 standard errors of their spread plus 0.1 % (the quadrature),
/// by both integrators.
#[test]
fn sloping_land_sees_the_sky_and_the_sea() {
    let fragment = "sun = { zenith_deg = 30.0, azimuth_deg = 160.0 }\n\
                    sky = { radiance = 0.05, distribution = \"isotropic\" }\n\
                    domain = { size_m = [40.0, 10.0] }\n\
                    water = { iop = { a = 100.0, b = 0.0 } }\n\
                    bottom = { slope = { from_depth_m = 5.0, to_depth_m = -5.0 }, reflectance = 0.0 }\n\
                    land = { reflectance = 0.4 }\n\
                    photons = { count = 2000 }\n\
                    sensor = { pixels = [40, 10], gsd_m = 1.0 }\n";
    for (integrator, spp) in [(IntegratorMode::PhotonMap, 16), (IntegratorMode::Path, 16)] {
        let scene = land_scene(fragment, integrator, spp);
        let nb = scene.bands.len();
        // The floor z = -5 + x / 4: its normal, up and toward -x.
        let n = glam::DVec3::new(-0.25, 0.0, 1.0).normalize();
        let s = -scene.sun.direction.as_dvec3();
        let [l, _, _] = cubes(&scene);
        for b in 0..nb {
            let q = sky_share(n, scene.water_index[b]);
            let exact = 0.4 / PI * (scene.sun.irradiance[b] * n.dot(s).max(0.0) + 0.05 * q);
            // Land from x = 20 m; the pixel there holds the shore.
            let v: Vec<f64> = (0..10)
                .flat_map(|y| (21..40).map(move |x| (y, x)))
                .map(|(y, x)| f64::from(l[(b * 10 + y) * 40 + x]))
                .collect();
            let (m, se) = mean_and_se(&v);
            eprintln!(
                "{integrator:?} band {b}: {m:.6} +- {se:.1e} against {exact:.6} ({:+.3} %)",
                (m / exact - 1.0) * 100.0
            );
            assert!(
                (m - exact).abs() < 4.0 * se + 1e-3 * exact,
                "{integrator:?} band {b}: {m} +- {se} against {exact}"
            );
        }
    }
}

/// Q = the integral over the hemisphere around `n` of L(w) / L_sky (n.w):
/// the sky above the horizon, the flat sea's Fresnel reflection of it
/// below (water of index `n_water` under it black), by the midpoint rule.
fn sky_share(n: glam::DVec3, n_water: f64) -> f64 {
    let (nt, np) = (2000, 4000);
    let mut q = 0.0;
    for i in 0..nt {
        let t = (i as f64 + 0.5) / nt as f64 * PI;
        for j in 0..np {
            let p = (j as f64 + 0.5) / np as f64 * 2.0 * PI;
            let w = glam::DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos());
            let c = n.dot(w);
            if c <= 0.0 {
                continue;
            }
            let l = if w.z > 0.0 {
                1.0
            } else {
                littoral::optics::surface::fresnel_reflectance(-w.z, 1.0, n_water)
            };
            q += l * c * t.sin();
        }
    }
    q * (PI / nt as f64) * (2.0 * PI / np as f64)
}

/// Mean and standard error of `v`.
fn mean_and_se(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

/// A ridge 6 m high at the far end of a level plateau 1 m above the water
/// shades it from a sun 60 degrees from the zenith beyond the ridge (and
/// the scene warns that land that steep could shade the water): the
/// plateau within (6 - 1) tan 60 degrees = 8.7 m of the ridge's crest
/// reads less than its sky's part alone, the plateau farther out more
/// than the sun's part alone.
#[test]
fn land_shades_land() {
    let dir = tempdir();
    // x = 0, 4, ..., 40: water to x = 8, the plateau from 12 to 32, the
    // ridge's crest at 36.
    let hf = heightfield(
        dir.path(),
        &[
            3.0, 3.0, 3.0, -1.0, -1.0, -1.0, -1.0, -1.0, -1.0, -6.0, -6.0,
        ],
    );
    let fragment = format!(
        "sun = {{ zenith_deg = 60.0, azimuth_deg = 0.0 }}\n\
         sky = {{ radiance = 0.05, distribution = \"isotropic\" }}\n\
         domain = {{ size_m = [40.0, 10.0] }}\n\
         bottom = {{ heightfield = \"{hf}\", reflectance = 0.2 }}\n\
         land = {{ reflectance = 0.3 }}\n\
         photons = {{ count = 2000 }}\n\
         sensor = {{ pixels = [40, 10], gsd_m = 1.0 }}\n"
    );
    let scene = land_scene(&fragment, IntegratorMode::Path, 4);
    // The ridge's face, 5 m up over 4 m (51 degrees), is steeper than the
    // sun stands (30 degrees): it could shade water, which is not
    // simulated, and the report says so.
    let warnings = scene.land_warnings();
    assert!(
        warnings.len() == 1 && warnings[0].contains("51 degrees"),
        "{warnings:?}"
    );
    let [l, _, _] = cubes(&scene);
    let b = 0;
    let sky = 0.3 / PI * scene.sky.irradiance[b];
    let sun = 0.3 / PI * scene.sun.horizontal_irradiance(b);
    for y in 0..10 {
        let at = |x: usize| f64::from(l[(b * 10 + y) * 40 + x]);
        // The shadow's edge: 32 - (5 tan 60 - 4) = 27.3 m.
        for x in 28..32 {
            assert!(at(x) < sky && at(x) > 0.0, "shaded ({x}, {y}): {}", at(x));
        }
        for x in 13..26 {
            assert!(at(x) > sun, "sunlit ({x}, {y}): {} against {sun}", at(x));
        }
    }
}

/// Light from the sky falls on land in the share of the domain the land
/// covers (half, within 4 binomial standard errors), is not traced on,
/// and the energy budget still closes; no photon is stored above the
/// water or under the land.
#[test]
fn light_falling_on_land_stays_there() {
    let fragment = "domain = { size_m = [40.0, 10.0] }\n\
                    bottom = { slope = { from_depth_m = 5.0, to_depth_m = -5.0 }, reflectance = 0.2 }\n\
                    land = { reflectance = 0.3 }\n\
                    photons = { count = 100000 }\n";
    let scene = land_scene(fragment, IntegratorMode::PhotonMap, 1);
    let dir = tempdir();
    let map = dir.path().join("land.map");
    littoral::job::RenderJob {
        scene: &scene,
        out_dir: dir.path().to_path_buf(),
        map: Some(map.clone()),
        threads: 0,
        budget: littoral::job::MemoryBudget::new(256 * MIB),
        scene_seconds: 0.0,
    }
    .run(&littoral::progress::Silent)
    .unwrap();
    let report: littoral::job::report::RunReport = serde_json::from_slice(
        &std::fs::read(dir.path().join(format!("{}.json", scene.name))).unwrap(),
    )
    .unwrap();
    let emission = report.emission.expect("a photon map's report");
    let en = &emission.energy;
    assert!(
        en.closure_sigma < 4.0,
        "closure {:?}",
        en.closure_sigma_per_band
    );
    for b in 0..scene.bands.len() {
        let share = en.on_land[b] / en.emitted[b];
        let photons = en.emitted[b] / emission.photon_power[b];
        let se = (0.25 / photons).sqrt();
        assert!((share - 0.5).abs() < 4.0 * se, "band {b}: {share} +- {se}");
    }
    let file = MapFile::open(&map).unwrap();
    let photons = all_photons(&file);
    assert!(!photons.is_empty());
    for ph in &photons {
        let p = ph.position;
        // The shore is at x = 20 m; the floor z = -5 + x / 4.
        assert!(p.z < 1e-4 && p.x < 20.001, "{p:?}");
        assert!(p.z > -5.0 + p.x / 4.0 - 1e-3, "under the floor: {p:?}");
    }
}

/// By the shore, within 4 m of the water line, where the floor rises to
/// it: the photon map against the path integrator, pixel by pixel pooled
/// over the shallows, each band within 3 sigma plus 2 % (sigma the pixels'
/// mean standard error, as if they were fully correlated).
#[test]
fn the_shallows_by_the_shore_agree_between_integrators() {
    let fragment = "sun = { zenith_deg = 30.0, azimuth_deg = 160.0 }\n\
                    domain = { size_m = [40.0, 10.0] }\n\
                    bottom = { slope = { from_depth_m = 5.0, to_depth_m = -5.0 }, reflectance = 0.2 }\n\
                    land = { reflectance = 0.3 }\n\
                    photons = { count = 1000000 }\n\
                    sensor = { pixels = [40, 10], gsd_m = 1.0 }\n";
    let pm = land_scene(fragment, IntegratorMode::PhotonMap, 4);
    let path = land_scene(fragment, IntegratorMode::Path, 512);
    let pooled = |scene: &Scene, b: usize| {
        let dir = tempdir();
        render_job(scene, dir.path(), 0);
        let l = f32s(dir.path().join(format!("{}.bsq", scene.name)));
        let se = f32s(dir.path().join(format!("{}.stderr.bsq", scene.name)));
        let cells: Vec<usize> = (0..10)
            .flat_map(|y| (16..20).map(move |x| (b * 10 + y) * 40 + x))
            .collect();
        let n = cells.len() as f64;
        let m = cells.iter().map(|&i| f64::from(l[i])).sum::<f64>() / n;
        let s = cells.iter().map(|&i| f64::from(se[i])).sum::<f64>() / n;
        (m, s)
    };
    let mut failures = Vec::new();
    for b in 0..pm.bands.len() {
        let ((a, sa), (p, sp)) = (pooled(&pm, b), pooled(&path, b));
        let sigma = sa.hypot(sp);
        eprintln!(
            "band {b}: photon map {a:.5} +- {sa:.1e}, path {p:.5} +- {sp:.1e} ({:+.2} %)",
            (a / p - 1.0) * 100.0
        );
        if (a - p).abs() > 3.0 * sigma + 0.02 * p {
            failures.push(format!("band {b}: {a} +- {sa} against {p} +- {sp}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A floor above the water line without `[land]`, `[land]` without one, a
/// floor above the water everywhere, a pinhole camera lower than the land,
/// and land under a Lambertian ground: each refused naming its key.
#[test]
fn land_keys_are_checked() {
    let slope = "bottom = { slope = { from_depth_m = 5.0, to_depth_m = -2.0 } }\n";
    let cases = [
        (slope.to_string(), "[land] reflectance"),
        (
            "bottom = { depth_m = 5.0 }\nland = { reflectance = 0.3 }\n".into(),
            "land",
        ),
        (
            "bottom = { slope = { from_depth_m = -1.0, to_depth_m = -2.0 } }\nland = { reflectance = 0.3 }\n".into(),
            "bottom.slope.to_depth_m",
        ),
        (
            format!("{slope}land = {{ reflectance = 1.5 }}\n"),
            "land.reflectance",
        ),
        (
            format!("{slope}land = {{ reflectance = 0.3 }}\nsensor = {{ kind = \"pinhole\", position_m = [5.0, 5.0, 1.5], look_at_m = [5.0, 6.0, 0.0] }}\n"),
            "sensor.position_m",
        ),
    ];
    for (fragment, key) in &cases {
        let e = Scene::parse(
            &minimal_with(fragment),
            Path::new("bad.toml"),
            &Overrides::default(),
        )
        .err()
        .unwrap_or_else(|| panic!("accepted: {fragment}"))
        .to_string();
        assert!(e.contains(key), "{fragment}: {e}");
    }
    let ground = minimal()
        .remove("water")
        .remove("photons")
        .merge("surface = { kind = \"lambertian\", reflectance = 0.3 }\nland = { reflectance = 0.3 }\n")
        .unwrap()
        .text();
    let e = Scene::parse(&ground, Path::new("bad.toml"), &Overrides::default())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("land"), "{e}");
}
