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
    // A beach 1 m high at x = 0, the water line at 12.5 m, 15 m offshore.
    assert!((floor(0.0) + 1.0).abs() < 0.01 && (floor(200.0) - 15.0).abs() < 0.01);
    assert!(s.is_land(12.4, 100.0) && !s.is_land(12.6, 100.0));
    assert!(s.land.is_some() && s.land_warnings().is_empty());
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
        (MINIMAL_SCENE.replace("end_nm = 700.0", "end_nm = 1200.0").replace("iop = { a = 0.1, b = 0.2 }", "chl = 1.0"), "spectral.end_nm: "),
        (MINIMAL_SCENE.replace("[photons]", "[tally]\ndepths_m = [1.0, -2.0]\n[photons]"), "tally.depths_m[1]"),
        (MINIMAL_SCENE.replace("iop = { a = 0.1, b = 0.2 }", "iop = { a = 0.1, b = 0.2 }\nphase = { kind = \"fournier-forand\", bb_ratio = 0.5 }"), "water.phase.bb_ratio"),
        (format!("{MINIMAL_SCENE}\n[estimate]\nboundary_grid_m = 0.0\n"), "estimate.boundary_grid_m"),
        (format!("{MINIMAL_SCENE}\n[estimate]\nforward_peak_deg = 95.0\n"), "estimate.forward_peak_deg"),
        (format!("{MINIMAL_SCENE}\n[estimate]\nforward_peak_down_deg = -1.0\n"), "estimate.forward_peak_down_deg"),
        (format!("{MINIMAL_SCENE}\n[estimate]\nforward_peak_target_deg = 91.0\n"), "estimate.forward_peak_target_deg"),
        (format!("{MINIMAL_SCENE}\n[estimate]\nk = 10\nk_expanded = 5\n"), "estimate.k_expanded"),
        (format!("{MINIMAL_SCENE}\n[sensor]\nkind = \"pinhole\"\nposition_m = [5.0, 5.0, 10.0]\nlook_at_m = [5.0, 5.0, 0.0]\n[georef]\nepsg = 32617\n"), "georef: a pinhole camera's image has no map grid"),
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
    // Placement is checked too: a radiometer outside the domain.
    let outside = dir.path().join("outside.toml");
    let text =
        format!("{MINIMAL_SCENE}[[radiometer]]\ndepth_m = 1.0\nposition_m = [5200.0, 5.0]\n");
    std::fs::write(&outside, &text).unwrap();
    let out = littoral(&["scene", "check", outside.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    let line = text.lines().position(|l| l.contains("5200")).unwrap() + 1;
    assert!(
        err.contains(&format!("outside.toml:{line}: radiometer[0].position_m: ")),
        "{err}"
    );
}

/// `scene set` prints the scene with its changes, which `scene check`
/// then reads: a fragment merged, keys set (a new table made), the
/// values as given; a change that is not KEY=VALUE, a value that is not
/// TOML and an unreadable base are one clean error each.
#[test]
fn scene_set_changes_keys_and_merges_fragments() {
    let dir = tempdir();
    let base = dir.path().join("base.toml");
    std::fs::write(&base, MINIMAL_SCENE).unwrap();
    let fragment = dir.path().join("floor.toml");
    std::fs::write(&fragment, "[bottom]\ndepth_m = 4.0\nreflectance = 0.3\n").unwrap();
    let out = littoral(&[
        "scene",
        "set",
        p(&base),
        "spectral.bands=8",
        "sensor.pixels=[6, 2]",
        "water.iop={ a = 0.3, b = 0.1 }",
        "--merge",
        p(&fragment),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let made = dir.path().join("made.toml");
    std::fs::write(&made, &out.stdout).unwrap();
    let scene = Scene::load(&made, &Overrides::default()).unwrap();
    assert_eq!(scene.bands.len(), 8);
    assert_eq!(scene.sensor.pixels, [6, 2]);
    assert!(
        scene.summary().contains("2 triangles"),
        "{}",
        scene.summary()
    );
    assert_eq!(
        Scene::load(&base, &Overrides::default())
            .unwrap()
            .bands
            .len(),
        4,
        "the base is left as it was"
    );
    let out = littoral(&["scene", "set", "default", "photons.count=5000"]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("count = 5000"));
    assert_clean_failure(
        &littoral(&["scene", "set", p(&base), "sensor.pixels"]),
        "KEY=VALUE",
    );
    assert_clean_failure(
        &littoral(&["scene", "set", p(&base), "sensor.pixels=[6,"]),
        "sensor.pixels",
    );
    let missing = dir.path().join("missing.toml");
    assert_clean_failure(
        &littoral(&["scene", "set", p(&missing), "a=1"]),
        "missing.toml",
    );
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

/// `MINIMAL_SCENE` (10 x 10 m) over a flat floor 3 m deep, with `extra`
/// appended.
pub(crate) fn floored(extra: &str) -> String {
    format!("{MINIMAL_SCENE}[bottom]\ndepth_m = 3.0\n{extra}")
}

/// Asserts `text` is refused at the line of the first line containing
/// `at`, naming `key`, with every one of `says` in the message.
pub(crate) fn refused_at(text: &str, at: &str, key: &str, says: &[&str]) {
    let e = parse_err(text);
    let line = text.lines().position(|l| l.contains(at)).unwrap() + 1;
    assert!(
        e.starts_with(&format!("bad.toml:{line}: {key}: ")),
        "want line {line} ({at}) and key {key}: {e}"
    );
    for s in says {
        assert!(e.contains(s), "'{s}' not in: {e}");
    }
    assert!(!e.contains('\n'), "{e}");
}

pub(crate) fn accepted(text: &str) -> Scene {
    Scene::parse(text, Path::new("good.toml"), &Overrides::default())
        .unwrap_or_else(|e| panic!("refused: {e}\n{text}"))
}

fn target(kind: &str, center: &str, size: &str) -> String {
    format!(
        "[[target]]\nkind = \"{kind}\"\ncenter_m = {center}\nsize_m = {size}\nreflectance = 0.5\n"
    )
}

/// A target's whole extent is checked, not its centre: above the water,
/// outside the domain (with periodic edges too: targets are not repeated
/// across them) or entirely under the floor is refused; touching the
/// surface, the domain's edges or sinking partly into the floor is not.
#[test]
fn targets_lie_in_the_water_of_the_domain() {
    // The top of the box at z = +0.3.
    let t = floored(&target("box", "[5.0, 5.0, -0.2]", "[1.0, 1.0, 1.0]"));
    refused_at(
        &t,
        "size_m = [1.0, 1.0, 1.0]",
        "target[0].size_m",
        &["above the water"],
    );
    // Centre far outside, with the default (periodic) edges.
    let t = floored(&target("panel", "[5000.0, 5.0, -1.0]", "[1.0, 1.0]"));
    refused_at(
        &t,
        "center_m",
        "target[0].center_m",
        &["outside the domain", "periodic"],
    );
    // Crossing the high-x edge: the centre is inside.
    let t = floored(&target("panel", "[9.8, 5.0, -1.0]", "[1.0, 1.0]"));
    refused_at(
        &t,
        "center_m",
        "target[0].center_m",
        &["x 9.3", "10.3", "outside"],
    );
    // Larger than the domain: its size is at fault.
    let t = floored(&target("panel", "[5.0, 5.0, -1.0]", "[12.0, 1.0]"));
    refused_at(
        &t,
        "size_m = [12.0",
        "target[0].size_m",
        &["outside the domain"],
    );
    // Entirely below the 3 m floor.
    let t = floored(&target("panel", "[5.0, 5.0, -300.0]", "[1.0, 1.0]"));
    refused_at(
        &t,
        "center_m",
        "target[0].center_m",
        &["below the floor", "300.000 m deep"],
    );
    let t = floored(&target("box", "[5.0, 5.0, -4.0]", "[1.0, 1.0, 1.0]"));
    refused_at(&t, "center_m", "target[0].center_m", &["below the floor"]);
    // Under a slope, the floor under the target counts, not the deepest point.
    let slope = format!(
        "{MINIMAL_SCENE}[bottom]\nslope = {{ from_depth_m = 1.0, to_depth_m = 9.0 }}\n{}",
        target("panel", "[1.0, 5.0, -4.0]", "[1.0, 1.0]")
    );
    refused_at(
        &slope,
        "center_m",
        "target[0].center_m",
        &["below the floor"],
    );
    accepted(&slope.replace("[1.0, 5.0, -4.0]", "[9.0, 5.0, -4.0]"));
    // Partly sunk into the slope: the floor under its footprint runs from
    // 4.6 to 5.4 m, its top at 5 m. Buried everywhere below 5.4 m.
    accepted(&slope.replace("[1.0, 5.0, -4.0]", "[5.0, 5.0, -5.0]"));
    refused_at(
        &slope.replace("[1.0, 5.0, -4.0]", "[5.0, 5.0, -5.5]"),
        "center_m",
        "target[0].center_m",
        &["entirely below the floor", "at most 5.400 m"],
    );
    // Without a floor, any depth is water.
    accepted(&format!(
        "{MINIMAL_SCENE}{}",
        target("panel", "[5.0, 5.0, -300.0]", "[1.0, 1.0]")
    ));
    // Legitimate: touching the surface and the domain's edges, resting on
    // and sinking partly into the floor.
    for (c, s) in [
        ("[0.5, 9.5, -0.5]", "[1.0, 1.0, 1.0]"),
        ("[5.0, 5.0, -3.0]", "[10.0, 10.0, 0.4]"),
        ("[5.0, 5.0, -2.5]", "[1.0, 1.0, 1.0]"),
    ] {
        accepted(&floored(&target("box", c, s)));
    }
}

/// A mesh's bounds are checked like a box's, and a mesh without a
/// triangle of non-zero area is refused naming its file.
#[test]
fn meshes_are_placed_and_have_triangles() {
    let dir = tempdir();
    let scene = dir.path().join("s.toml");
    let mesh = |name: &str, obj: &str, z: f64| {
        std::fs::write(dir.path().join(name), obj).unwrap();
        floored(&format!(
            "[[target]]\nkind = \"mesh\"\nfile = \"{name}\"\ncenter_m = [5.0, 5.0, {z:?}]\nreflectance = 0.5\n"
        ))
    };
    let parse =
        |text: &str| Scene::parse(text, &scene, &Overrides::default()).map_err(|e| e.to_string());
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0.5\nf 1 2 3\n";
    assert!(parse(&mesh("tri.obj", tri, -1.0)).is_ok());
    let above = mesh("tri.obj", tri, -0.2);
    let e = parse(&above).unwrap_err();
    let line = above.lines().position(|l| l.contains("file =")).unwrap() + 1;
    assert!(
        e.contains(&format!(":{line}: target[0].file: ")) && e.contains("above the water"),
        "{e}"
    );
    let e = parse(&mesh("empty.obj", "v 0 0 0\nv 1 0 0\n", -1.0)).unwrap_err();
    assert!(
        e.contains("target[0].file") && e.contains("empty.obj") && e.contains("no triangles"),
        "{e}"
    );
    let flat = "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\n";
    let e = parse(&mesh("flat.obj", flat, -1.0)).unwrap_err();
    assert!(
        e.contains("target[0].file")
            && e.contains("flat.obj")
            && e.contains("all 2 triangles")
            && e.contains("zero area"),
        "{e}"
    );
    // A missing file names the scene's line and key.
    let missing = mesh("tri.obj", tri, -1.0).replace("tri.obj", "gone.obj");
    let e = parse(&missing).unwrap_err();
    let line = missing
        .lines()
        .position(|l| l.contains("gone.obj"))
        .unwrap()
        + 1;
    assert!(
        e.starts_with(&format!(
            "{}:{line}: target[0].file: cannot read",
            scene.display()
        )) && e.contains("gone.obj"),
        "{e}"
    );
}

/// A tally depth below the deepest point of the floor is refused (no light
/// ever reaches it); one between the shallowest and the deepest point is in
/// the water over part of the domain and allowed.
#[test]
fn tally_depths_lie_above_the_deepest_floor() {
    let t = floored("[tally]\ndepths_m = [0.0, 5.0]\n");
    refused_at(
        &t,
        "depths_m",
        "tally.depths_m[1]",
        &["5 m is below the floor everywhere", "deepest point 3 m"],
    );
    accepted(&floored("[tally]\ndepths_m = [0.0, 3.0]\n"));
    let slope = format!("{MINIMAL_SCENE}[bottom]\nslope = {{ from_depth_m = 1.0, to_depth_m = 6.0 }}\n[tally]\ndepths_m = [4.0]\n");
    accepted(&slope);
    refused_at(
        &slope.replace("[4.0]", "[6.5]"),
        "depths_m",
        "tally.depths_m[0]",
        &["deepest point 6 m"],
    );
    accepted(&format!("{MINIMAL_SCENE}[tally]\ndepths_m = [500.0]\n"));
}

/// Fixed-length arrays of any other length are refused naming the key and
/// the expected length (serde alone ignored extra values).
#[test]
fn fixed_length_arrays_have_their_length() {
    let m = MINIMAL_SCENE;
    let cases: Vec<(String, &str, &str, usize)> = vec![
        (format!("{m}[sensor]\npixels = [32, 32, 32]\n"), "pixels", "sensor.pixels", 2),
        (format!("{m}[sensor]\npixels = [32]\n"), "pixels", "sensor.pixels", 2),
        (m.replace("size_m = [10.0, 10.0]", "size_m = [200.0, 200.0, 5.0]"), "size_m", "domain.size_m", 2),
        (format!("{m}[sensor]\ncenter_m = [1.0, 2.0, 3.0]\n"), "center_m", "sensor.center_m", 2),
        (format!("{m}[sensor]\nkind = \"pinhole\"\nposition_m = [1.0, 2.0, 3.0, 4.0]\nlook_at_m = [1.0, 1.0, -1.0]\n"), "position_m", "sensor.position_m", 3),
        (format!("{m}[sensor]\nkind = \"pinhole\"\nposition_m = [1.0, 2.0, 3.0]\nlook_at_m = [1.0, 1.0]\n"), "look_at_m", "sensor.look_at_m", 3),
        (format!("{m}[[radiometer]]\ndepth_m = 1.0\nposition_m = [1.0, 2.0, 3.0]\n"), "position_m", "radiometer[0].position_m", 2),
        (format!("{m}[[target]]\nkind = \"panel\"\ncenter_m = [1.0, 1.0]\nsize_m = [1.0, 1.0]\nreflectance = 0.5\n"), "center_m", "target[0].center_m", 3),
        (format!("{m}[bottom]\ndepth_m = 3.0\n[[bottom.patch]]\nmin_m = [1.0, 1.0, 1.0]\nmax_m = [2.0, 2.0]\nreflectance = 0.5\n"), "min_m", "bottom.patch[0].min_m", 2),
        (format!("{m}[georef]\norigin_m = [1.0, 2.0, 3.0]\n"), "origin_m", "georef.origin_m", 2),
        (m.replace("iop = { a = 0.1, b = 0.2 }", "chl = 1.0\ngradient = { axis = \"x\", chl = [1.0, 2.0, 3.0] }"), "gradient", "water.gradient.chl", 2),
    ];
    for (text, at, key, n) in cases {
        refused_at(&text, at, key, &[&format!("expected exactly {n} values")]);
    }
    // A vector view is one of the untagged choices: a wrong length matches none.
    let e = parse_err(&format!(
        "{m}[[radiometer]]\ndepth_m = 1.0\nview = [0.0, 0.0, 1.0, 1.0]\n"
    ));
    assert!(e.contains("radiometer[0].view"), "{e}");
    accepted(&format!(
        "{m}[[radiometer]]\ndepth_m = 1.0\nview = [0.0, 0.5, 1.0]\n"
    ));
}

/// Overlapping water layers are refused naming both.
#[test]
fn water_layers_do_not_overlap() {
    let layers = |a: (f64, f64), b: (f64, f64)| {
        MINIMAL_SCENE.replace(
            "iop = { a = 0.1, b = 0.2 }",
            &format!(
                "chl = 1.0\n[[water.layer]]\ntop_m = {:?}\nbottom_m = {:?}\nchl = 2.0\n[[water.layer]]\ntop_m = {:?}\nbottom_m = {:?}\nchl = 3.0",
                a.0, a.1, b.0, b.1
            ),
        )
    };
    refused_at(
        &layers((0.0, 3.0), (2.0, 4.0)),
        "top_m = 2.0",
        "water.layer[1].top_m",
        &["water.layer[1] (2 to 4 m) overlaps water.layer[0] (0 to 3 m)"],
    );
    refused_at(
        &layers((2.0, 4.0), (0.0, 5.0)),
        "top_m = 0.0",
        "water.layer[1].top_m",
        &["overlaps water.layer[0]"],
    );
    accepted(&layers((0.0, 2.0), (2.0, 4.0)));
    accepted(&layers((3.0, 4.0), (0.0, 1.0)));
}

/// Spectra with a negative value are refused naming the file, line and
/// value; a scene whose sun and sky are zero names the sun's key.
#[test]
fn spectra_are_not_negative_and_the_scene_emits_light() {
    let dir = tempdir();
    let scene = dir.path().join("s.toml");
    std::fs::write(
        dir.path().join("neg.csv"),
        "nm,value\n400,1.0\n550,-1.5\n700,1.0\n",
    )
    .unwrap();
    let parse =
        |text: &str| Scene::parse(text, &scene, &Overrides::default()).map_err(|e| e.to_string());
    let sun = MINIMAL_SCENE.replace("irradiance = 1.0", "spectrum = \"neg.csv\"");
    let e = parse(&sun).unwrap_err();
    assert!(
        e.contains("neg.csv: line 3: sun.spectrum: value -1.5 at 550 is negative"),
        "{e}"
    );
    let sky = format!("{MINIMAL_SCENE}[sky]\nspectrum = \"neg.csv\"\n");
    assert!(parse(&sky)
        .unwrap_err()
        .contains("neg.csv: line 3: sky.spectrum"));
    let refl = format!("{MINIMAL_SCENE}[bottom]\ndepth_m = 3.0\nreflectance = \"neg.csv\"\n");
    assert!(parse(&refl)
        .unwrap_err()
        .contains("neg.csv: line 3: bottom.reflectance"));
    // A missing spectrum names the scene's line and key.
    let gone = sun.replace("neg.csv", "gone.csv");
    let e = parse(&gone).unwrap_err();
    let line = gone.lines().position(|l| l.contains("gone.csv")).unwrap() + 1;
    assert!(
        e.starts_with(&format!(
            "{}:{line}: sun.spectrum: cannot read",
            scene.display()
        )),
        "{e}"
    );
    // No light at all.
    let dark = MINIMAL_SCENE.replace("irradiance = 1.0", "irradiance = 0.0");
    refused_at(
        &dark,
        "irradiance",
        "sun.irradiance",
        &["emits no light", "no sky"],
    );
    refused_at(
        &format!("{dark}[sky]\nradiance = 0.0\n"),
        "irradiance",
        "sun.irradiance",
        &["sky.radiance is zero too"],
    );
    accepted(&format!("{dark}[sky]\nradiance = 0.1\n"));
}

/// A photon count that would never finish is refused; range errors say
/// which bound is broken; a name that cannot name the output files is
/// refused at check time.
#[test]
fn counts_ranges_and_names() {
    let m = MINIMAL_SCENE;
    refused_at(
        &m.replace("count = 1000", "count = 9223372036854775807"),
        "count",
        "photons.count",
        &["never finish", "at most 1000000000000"],
    );
    accepted(&m.replace("count = 1000", "count = 1000000000000"));
    // The command-line override is checked too, and blamed, not the file.
    let o = Overrides {
        photons: Some(u64::MAX),
        ..Overrides::default()
    };
    let e = Scene::parse(m, Path::new("bad.toml"), &o)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("--photons") && e.contains("split the work") && !e.contains("bad.toml"),
        "{e}"
    );
    let water = |v: &str| m.replace("iop = { a = 0.1, b = 0.2 }", v);
    refused_at(
        &water("chl = 1e6"),
        "chl",
        "water.chl",
        &["must be at most 10000, not 1000000"],
    );
    refused_at(
        &water("chl = -1.0"),
        "chl",
        "water.chl",
        &["must be >= 0, not -1"],
    );
    refused_at(&water("chl = nan"), "chl", "water.chl", &["not a number"]);
    refused_at(
        &water("iop = { a = 0.1, b = 1e9 }"),
        "iop",
        "water.iop.b",
        &["at most 10000 1/m"],
    );
    refused_at(
        &m.replace("size_m = [10.0, 10.0]", "size_m = [1e9, 10.0]"),
        "size_m",
        "domain.size_m",
        &["at most 10000000 m"],
    );
    refused_at(
        &m.replace("irradiance = 1.0", "irradiance = inf"),
        "irradiance",
        "sun.irradiance",
        &["must be finite"],
    );
    refused_at(
        &format!("{m}[bottom]\ndepth_m = 1e6\n"),
        "depth_m",
        "bottom.depth_m",
        &["at most 100000 m"],
    );
    let named = |n: &str| format!("name = \"{n}\"\n{m}");
    refused_at(
        &named(&"x".repeat(300)),
        "name",
        "name",
        &["300 bytes is too long", "at most 200"],
    );
    refused_at(&named("a/b"), "name", "name", &["path separators"]);
    refused_at(&named(".."), "name", "name", &["path separators"]);
    accepted(&named(&"x".repeat(200)));
}
