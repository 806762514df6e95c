//! Scene files and the `scene` and `emit` commands.

use crate::common::*;
use littoral::scene::{Overrides, Scene, COASTAL_TOML};
use std::path::Path;

fn parse_err(text: &str) -> String {
    match Scene::parse(text, Path::new("bad.toml"), &Overrides::default()) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn the_builtin_scene_is_valid_and_as_described() {
    let s = Scene::coastal(&Overrides::default()).unwrap();
    assert!(s.bands.len() >= 128);
    assert_eq!(s.bands.centers_nm()[0], 400.0);
    assert!((s.bands.centers_nm()[s.bands.len() - 1] - 800.0).abs() < 1e-3);
    assert_eq!(s.domain.size_m, [200.0, 200.0]);
    let floor = |x: f32| s.geometry.floor_depth_at(x, 100.0).unwrap();
    assert!((floor(0.0) - 0.5).abs() < 0.01 && (floor(200.0) - 15.0).abs() < 0.01);
    assert_eq!(s.target_reflectance.len(), 2);
    assert!((s.sun.zenith_rad.to_degrees() - 35.0).abs() < 1e-9);
    assert!(s.sky.irradiance.iter().all(|&e| e > 0.0));
    // Chlorophyll rises toward the shore: more absorption at x = 0 than offshore.
    let near = s.water.iop(glam::Vec3::new(1.0, 100.0, -0.2), 10).a;
    let far = s.water.iop(glam::Vec3::new(199.0, 100.0, -0.2), 10).a;
    assert!(near > 2.0 * far, "{near} vs {far}");
    // Overrides apply before validation.
    let o = Overrides {
        photons: Some(5),
        bands: Some(16),
        seed: Some(9),
        ..Overrides::default()
    };
    let s = Scene::coastal(&o).unwrap();
    assert_eq!((s.photons, s.bands.len(), s.seed), (5, 16, 9));
}

#[test]
fn bad_scenes_name_the_key_and_line() {
    let cases: Vec<(String, &str)> = vec![
        (MINIMAL_SCENE.replace("count = 1000", "count = 1000\ncolour = 3"), "unknown field"),
        (MINIMAL_SCENE.replace("zenith_deg = 30.0", "zenith_deg = \"high\""), "invalid type"),
        (MINIMAL_SCENE.replace("count = 1000", "count = 0"), "photons.count"),
        (MINIMAL_SCENE.replace("zenith_deg = 30.0", "zenith_deg = 95.0"), "sun.zenith_deg"),
        (MINIMAL_SCENE.replace("iop = { a = 0.1, b = 0.2 }", "iop = { a = -0.1, b = 0.2 }"), "water.iop.a"),
        (MINIMAL_SCENE.replace("iop = { a = 0.1, b = 0.2 }", "chl = -1.0"), "water.chl"),
        (MINIMAL_SCENE.replace("size_m = [10.0, 10.0]", "size_m = [10.0, 0.0]"), "domain.size_m"),
        (format!("{MINIMAL_SCENE}\n[bottom]\ndepth_m = -3.0\n"), "bottom.depth_m"),
        (format!("{MINIMAL_SCENE}\n[bottom]\ndepth_m = 3.0\nreflectance = \"marble\"\n"), "bottom.reflectance"),
        (format!("{MINIMAL_SCENE}\n[[target]]\nkind = \"box\"\ncenter_m = [1.0, 1.0, -1.0]\nsize_m = [1.0, 1.0]\nreflectance = 0.5\n"), "target[0].size_m"),
        (format!("{MINIMAL_SCENE}\n[[target]]\nkind = \"panel\"\ncenter_m = [1.0, 1.0, -1.0]\nsize_m = [1.0, 1.0]\nreflectance = 1.5\n"), "target[0].reflectance"),
        (MINIMAL_SCENE.replace("end_nm = 700.0", "end_nm = 1200.0").replace("iop = { a = 0.1, b = 0.2 }", "chl = 1.0"), "out_of_range"),
        (MINIMAL_SCENE.replace("[photons]", "[tally]\ndepths_m = [1.0, -2.0]\n[photons]"), "tally.depths_m[1]"),
        (MINIMAL_SCENE.replace("iop = { a = 0.1, b = 0.2 }", "iop = { a = 0.1, b = 0.2 }\nphase = { kind = \"fournier-forand\", bb_ratio = 0.5 }"), "water.phase.bb_ratio"),
        (format!("{MINIMAL_SCENE}\n[estimate]\nboundary_grid_m = 0.0\n"), "estimate.boundary_grid_m"),
        (format!("{MINIMAL_SCENE}\n[estimate]\nforward_peak_deg = 95.0\n"), "estimate.forward_peak_deg"),
        (format!("{MINIMAL_SCENE}\n[estimate]\nforward_peak_down_deg = -1.0\n"), "estimate.forward_peak_down_deg"),
        (format!("{MINIMAL_SCENE}\n[estimate]\nk = 10\nk_expanded = 5\n"), "estimate.k_expanded"),
    ];
    for (text, needle) in cases {
        let e = parse_err(&text);
        assert!(e.starts_with("bad.toml:"), "{e}");
        assert!(e.contains(needle), "'{needle}' not in: {e}");
        let line: usize = e.split(':').nth(1).unwrap().parse().unwrap();
        assert!(line >= 1 && line <= text.lines().count() + 1, "{e}");
    }
    // The line points at the offending key.
    let text = MINIMAL_SCENE.replace("zenith_deg = 30.0", "zenith_deg = 95.0");
    let want = text.lines().position(|l| l.contains("zenith_deg")).unwrap() + 1;
    assert!(parse_err(&text).starts_with(&format!("bad.toml:{want}:")));
}

/// Every choice among names is typed: a misspelt value is refused naming the
/// file, the line of the value, the key, and the allowed values. Type errors
/// name their key too.
#[test]
fn misspelt_choices_list_the_allowed_values() {
    let m = MINIMAL_SCENE;
    let target =
        "[[target]]\ncenter_m = [1.0, 1.0, -1.0]\nsize_m = [1.0, 1.0]\nreflectance = 0.5\n";
    let cases: Vec<(String, &str, &str, &[&str])> = vec![
        (
            m.replace("bands = 4", "bands = 4\nout_of_range = \"wrap\""),
            "wrap",
            "spectral.out_of_range",
            &["error", "clamp"],
        ),
        (
            format!("{m}[surface]\nkind = \"wavy\"\n"),
            "wavy",
            "surface.kind",
            &["flat", "cox-munk"],
        ),
        (
            m.replace(
                "size_m = [10.0, 10.0]",
                "size_m = [10.0, 10.0]\nedges = \"closed\"",
            ),
            "closed",
            "domain.edges",
            &["periodic", "open"],
        ),
        (
            m.replace(
                "iop = { a = 0.1, b = 0.2 }",
                "iop = { a = 0.1, b = 0.2 }\nphase = { kind = \"mie\" }",
            ),
            "mie",
            "water.phase.kind",
            &["fournier-forand", "petzold", "henyey-greenstein", "table"],
        ),
        (
            m.replace(
                "iop = { a = 0.1, b = 0.2 }",
                "chl = 1.0\ngradient = { axis = \"z\", chl = [1.0, 2.0] }",
            ),
            "axis = \"z\"",
            "water.gradient.axis",
            &["x", "y"],
        ),
        (
            format!(
                "{m}[bottom]\nslope = {{ from_depth_m = 1.0, to_depth_m = 5.0, axis = \"q\" }}\n"
            ),
            "axis = \"q\"",
            "bottom.slope.axis",
            &["x", "y"],
        ),
        (
            format!(
                "{m}{}",
                target.replace("[[target]]", "[[target]]\nkind = \"sphere\"")
            ),
            "sphere",
            "target[0].kind",
            &["box", "panel", "mesh"],
        ),
        (
            format!("{m}[sensor]\nkind = \"fisheye\"\n"),
            "fisheye",
            "sensor.kind",
            &["orthographic", "pinhole"],
        ),
        (
            format!("{m}[estimate]\nboundary = \"cube\"\n"),
            "cube",
            "estimate.boundary",
            &["none", "ellipsoid", "clipped-sphere"],
        ),
        (
            format!("{m}[estimate]\nspectral = \"smart\"\n"),
            "smart",
            "estimate.spectral",
            &["naive", "compensated"],
        ),
        (
            m.replace("zenith_deg = 30.0", "zenith_deg = \"high\""),
            "high",
            "sun.zenith_deg",
            &["invalid type"],
        ),
    ];
    for (text, value, key, allowed) in cases {
        let e = parse_err(&text);
        let want_line = text.lines().position(|l| l.contains(value)).unwrap() + 1;
        assert!(
            e.starts_with(&format!("bad.toml:{want_line}: {key}: ")),
            "want line {want_line} and key {key}: {e}"
        );
        for a in allowed {
            assert!(e.contains(a), "'{a}' not in: {e}");
        }
        assert!(!e.contains('\n'), "{e}");
    }
}

#[test]
fn scene_commands() {
    let out = littoral(&["scene", "default"]);
    assert!(out.status.success());
    assert_eq!(String::from_utf8(out.stdout).unwrap(), COASTAL_TOML);
    let dir = tempdir();
    let good = dir.path().join("good.toml");
    std::fs::write(&good, MINIMAL_SCENE).unwrap();
    let out = littoral(&["scene", "check", good.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, MINIMAL_SCENE.replace("count = 1000", "count = -5")).unwrap();
    let out = littoral(&["scene", "check", bad.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("bad.toml:"), "{err}");
    let out = littoral(&[
        "scene",
        "check",
        dir.path().join("missing.toml").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
}

/// `emit` on the built-in scene: report fields, a valid map, and the same
/// map bytes for 1 and 2 threads.
#[test]
fn emit_builtin_scene() {
    let dir = tempdir();
    let scene = dir.path().join("coastal.toml");
    std::fs::write(&scene, COASTAL_TOML).unwrap();
    let mut maps = Vec::new();
    for threads in ["1", "2"] {
        let map = dir.path().join(format!("m{threads}.map"));
        let report = dir.path().join(format!("r{threads}.json"));
        let out = littoral(&[
            "emit",
            scene.to_str().unwrap(),
            "--map",
            map.to_str().unwrap(),
            "--report",
            report.to_str().unwrap(),
            "--photons",
            "20000",
            "--threads",
            threads,
            "--mem-budget",
            "64MiB",
            "--quiet",
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let r: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
        assert_eq!(r["bands_nm"].as_array().unwrap().len(), 128);
        assert_eq!(r["tally"].as_array().unwrap().len(), 4);
        assert_eq!(r["tally"][0]["depth_m"], 0.0);
        for key in ["Ed", "Eu", "Eod", "Eou", "Ed_stderr"] {
            assert_eq!(r["tally"][1][key].as_array().unwrap().len(), 128, "{key}");
        }
        assert_eq!(r["above_surface"]["Ed"].as_array().unwrap().len(), 128);
        assert_eq!(r["photons"]["traced"], 20_000);
        assert!(r["energy"]["closure_sigma"].as_f64().unwrap() < 5.0);
        assert!(r["peak_rss_bytes"].as_u64().unwrap() > 0);
        let info = littoral(&["map", "verify", map.to_str().unwrap(), "--quiet"]);
        assert!(info.status.success());
        maps.push(std::fs::read(&map).unwrap());
    }
    assert!(
        maps[0] == maps[1],
        "emitted maps differ between 1 and 2 threads"
    );
}
