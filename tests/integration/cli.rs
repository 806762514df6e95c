//! The command line: the exact forms scripts rely on, and one clear line
//! with a non-zero exit for every kind of bad input or output.

use crate::common::*;
use std::path::Path;
use std::process::{Command, Output};

fn json(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// No final file and no temporary left behind in `dir`.
fn assert_nothing_written(dir: &Path) {
    let left: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}");
}

#[test]
fn synth_info_verify_query_dump() {
    let dir = tempdir();
    let map = dir.path().join("w.map");
    let out = littoral(&[
        "map",
        "synth",
        "--photons",
        "50000",
        "--bands",
        "16",
        "--seed",
        "3",
        "--distribution",
        "water",
        "--mem-budget",
        "64MiB",
        "--out",
        p(&map),
        "--quiet",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.stderr.is_empty(), "--quiet prints nothing");

    let info = json(&littoral(&["map", "info", p(&map)]));
    assert_eq!(info["photons"], 50_000);
    let (vol, surf) = (
        info["volume_photons"].as_u64().unwrap(),
        info["surface_photons"].as_u64().unwrap(),
    );
    assert_eq!(vol + surf, 50_000);
    assert!(
        surf > 10_000 && surf < 15_000,
        "a quarter on the floor: {surf}"
    );
    assert_eq!(info["bands"], 16);
    assert_eq!(
        info["format_version"],
        littoral::store::format::FORMAT_VERSION
    );
    assert_eq!(info["provenance"]["source"], "synthetic");
    assert_eq!(info["provenance"]["photons"], 50_000);
    assert_eq!(info["provenance"]["digest"].as_str().unwrap().len(), 64);
    assert!(info["tiles"].as_u64().unwrap() >= 1);
    let bytes = std::fs::metadata(&map).unwrap().len();
    assert_eq!(info["file_bytes"], bytes);
    assert!((info["bytes_per_photon"].as_f64().unwrap() - bytes as f64 / 50_000.0).abs() < 1e-9);
    assert_eq!(info["bounds"]["min"][2], -10.0);

    let verify = littoral(&["map", "verify", p(&map), "--quiet"]);
    assert!(verify.status.success());

    let knn = json(&littoral(&[
        "map",
        "query",
        p(&map),
        "--at",
        "50,50,-1",
        "--k",
        "7",
    ]));
    let arr = knn.as_array().unwrap();
    assert_eq!(arr.len(), 7);
    let d: Vec<f64> = arr
        .iter()
        .map(|n| n["distance"].as_f64().unwrap())
        .collect();
    assert!(d.windows(2).all(|w| w[0] <= w[1]), "nearest first: {d:?}");
    for key in ["x", "y", "z", "band", "power", "distance"] {
        assert!(arr[0].get(key).is_some(), "missing {key}");
    }
    let within = json(&littoral(&[
        "map",
        "query",
        p(&map),
        "--at",
        "50,50,-10",
        "--radius",
        "0.5",
    ]));
    for n in within.as_array().unwrap() {
        assert!(n["distance"].as_f64().unwrap() <= 0.5 + 1e-6);
    }
    let capped = json(&littoral(&[
        "map",
        "query",
        p(&map),
        "--at",
        "50,50,-5",
        "--k",
        "500",
        "--max-radius",
        "0.3",
    ]));
    assert!(capped.as_array().unwrap().len() < 500);

    let dump = littoral(&["map", "dump", p(&map)]);
    assert!(dump.status.success());
    assert_eq!(
        String::from_utf8_lossy(&dump.stdout).lines().count(),
        50_001
    );
}

#[test]
fn sizes_and_arguments_are_validated() {
    let dir = tempdir();
    let map = dir.path().join("m.map");
    for (budget, ok) in [
        ("64MiB", true),
        ("500MB", true),
        ("67108864", true),
        ("lots", false),
        ("1KiB", false),
    ] {
        let out = littoral(&[
            "map",
            "synth",
            "--photons",
            "1000",
            "--mem-budget",
            budget,
            "--out",
            p(&map),
            "--quiet",
        ]);
        if ok {
            assert!(
                out.status.success(),
                "{budget}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        } else {
            assert_clean_failure(&out, "budget");
        }
    }
    assert_clean_failure(
        &littoral(&["map", "query", p(&map), "--at", "1,2", "--k", "3"]),
        "--at",
    );
    assert_clean_failure(
        &littoral(&["map", "query", p(&map), "--at", "1,2,3", "--radius", "-1"]),
        "--radius",
    );
    // Counts out of range, negative ones included, are usage errors (exit 2)
    // naming the flag, and nothing is written.
    let z = dir.path().join("z");
    for args in [
        &["map", "synth", "--out", p(&z), "--photons", "0"][..],
        &["map", "synth", "--out", p(&z), "--photons", "-5"],
        &[
            "map",
            "synth",
            "--out",
            p(&z),
            "--photons",
            "10",
            "--bands",
            "0",
        ],
        &["render", "--out", p(&z), "--photons", "-5"],
        &["render", "--out", p(&z), "--bands", "0"],
        &["emit", "scene.toml", "--map", p(&z), "--photons", "0"],
    ] {
        let out = littoral(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        let flag = args[args.len() - 2];
        assert!(
            err.contains(flag) && err.contains(args[args.len() - 1]),
            "{args:?}: {err}"
        );
        assert!(!z.exists());
    }
    // Neither --k nor --radius: a usage error from the parser (exit 2).
    assert_eq!(
        littoral(&["map", "query", p(&map), "--at", "1,2,3"])
            .status
            .code(),
        Some(2)
    );
}

#[test]
fn bad_maps_fail_cleanly() {
    let dir = tempdir();
    let src = source(20_000, 8, 1, littoral::synth::Distribution::Uniform);
    let (good, _) = synth_map(dir.path(), "good.map", &src, Some(4_000), 1, 64 * MIB);
    let bytes = std::fs::read(&good).unwrap();
    let bad = dir.path().join("bad.map");

    let mut flipped = bytes.clone();
    flipped[bytes.len() / 2] ^= 0x04;
    std::fs::write(&bad, &flipped).unwrap();
    let out = littoral(&["map", "verify", p(&bad), "--quiet"]);
    assert_clean_failure(&out, "bad.map");
    assert!(String::from_utf8_lossy(&out.stderr).contains("tile "));
    assert_clean_failure(&littoral(&["map", "dump", p(&bad)]), "tile ");

    std::fs::write(&bad, &bytes[..bytes.len() - 10]).unwrap();
    for cmd in ["info", "verify", "dump"] {
        assert_clean_failure(&littoral(&["map", cmd, p(&bad)]), "bad.map");
    }
    assert_clean_failure(
        &littoral(&["map", "query", p(&bad), "--at", "0,0,0", "--k", "1"]),
        "bad.map",
    );
    assert_clean_failure(&littoral(&["map", "info", p(dir.path())]), "directory");
    assert_clean_failure(
        &littoral(&["map", "info", p(&dir.path().join("nope.map"))]),
        "nope.map",
    );
}

#[test]
fn unwritable_outputs_fail_cleanly() {
    let dir = tempdir();
    let out_dir = dir.path().join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let synth = |out: &str| {
        littoral(&[
            "map",
            "synth",
            "--photons",
            "20000",
            "--out",
            out,
            "--quiet",
        ])
    };
    // A missing directory, a file used as a directory, a directory as the output.
    assert_clean_failure(&synth(p(&out_dir.join("missing/x.map"))), "x.map");
    let file = out_dir.join("plain");
    std::fs::write(&file, b"x").unwrap();
    assert_clean_failure(&synth(p(&file.join("x.map"))), "x.map");
    std::fs::remove_file(&file).unwrap();
    assert_clean_failure(&synth(p(&out_dir)), "directory");
    assert_nothing_written(&out_dir);

    // `emit --report` to a place that cannot be written fails before any
    // photon is traced: no map either.
    let scene = dir.path().join("scene.toml");
    std::fs::write(&scene, MINIMAL_SCENE).unwrap();
    let emit = littoral(&[
        "emit",
        p(&scene),
        "--map",
        p(&out_dir.join("e.map")),
        "--report",
        p(&out_dir.join("missing/r.json")),
        "--quiet",
    ]);
    assert_clean_failure(&emit, "r.json");
    assert_nothing_written(&out_dir);
}

/// A full disk, simulated with a file-size limit (the write fails with
/// EFBIG once the limit is hit): one clear line, and neither the final file
/// nor a temporary is left behind.
#[test]
fn full_disk_leaves_nothing_behind() {
    let dir = tempdir();
    let out_dir = dir.path().join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let target = out_dir.join("full.map");
    let script = format!(
        "trap '' XFSZ; ulimit -f 512; exec '{}' map synth --photons 2000000 --mem-budget 16MiB --out '{}' --quiet",
        env!("CARGO_BIN_EXE_littoral"),
        p(&target)
    );
    let out = Command::new("sh").arg("-c").arg(&script).output().unwrap();
    assert_clean_failure(&out, "full.map");
    assert_nothing_written(&out_dir);
}

/// SIGTERM or SIGINT mid-run removes the run's temporary files: the
/// partial map of `emit`, and the scratch map and partial cubes of
/// `render`; the exit status is 130 and nothing is left under a final name.
/// The handler pauses before it exits (`LITTORAL_EXIT_PAUSE_MS`), so that
/// the run's other threads, still going, would leave a temporary they make
/// or publish after the removal.
#[test]
fn signals_leave_no_temporary_files() {
    use std::process::{Command, Stdio};
    use std::time::{Duration, Instant};
    let dir = tempdir();
    let scene = dir.path().join("c.toml");
    std::fs::write(&scene, include_str!("../../src/scene/coastal.toml")).unwrap();
    let runs: [(&str, Vec<String>); 2] = [
        (
            "TERM",
            vec![
                "emit".into(),
                p(&scene).into(),
                "--photons".into(),
                "50000000".into(),
                "--map".into(),
                p(&dir.path().join("out/big.map")).into(),
                "--quiet".into(),
            ],
        ),
        (
            "INT",
            vec![
                "render".into(),
                p(&scene).into(),
                "--photons".into(),
                "50000000".into(),
                "--out".into(),
                p(&dir.path().join("out")).into(),
                "--quiet".into(),
            ],
        ),
    ];
    for (signal, args) in runs {
        let out = dir.path().join("out");
        std::fs::create_dir_all(&out).unwrap();
        let mut child = Command::new(env!("CARGO_BIN_EXE_littoral"))
            .args(&args)
            .env("LITTORAL_EXIT_PAUSE_MS", "300")
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let names = || -> Vec<String> {
            std::fs::read_dir(&out)
                .unwrap()
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect()
        };
        // Wait until the run has a temporary file to lose.
        let start = Instant::now();
        while !names().iter().any(|n| n.starts_with('.')) {
            assert!(
                start.elapsed() < Duration::from_secs(120),
                "no temporary file appeared"
            );
            assert!(child.try_wait().unwrap().is_none(), "{args:?} ended early");
            std::thread::sleep(Duration::from_millis(50));
        }
        let killed = Command::new("kill")
            .args([format!("-{signal}"), child.id().to_string()])
            .status()
            .unwrap();
        assert!(killed.success());
        let output = child.wait_with_output().unwrap();
        assert_eq!(output.status.code(), Some(130), "{args:?}");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(stderr.contains("interrupted"), "{stderr}");
        assert_eq!(names(), Vec::<String>::new(), "{args:?} left files behind");
    }
}

/// `--bands N` spreads N bands over the scene's own range: the built-in
/// scene's 400-800 nm, or the span of a scene's explicit centres; 400-700
/// nm only where the scene gives neither.
#[test]
fn a_band_count_override_keeps_the_scenes_range() {
    let bands = |s: &littoral::scene::Scene| s.bands.centers_nm().to_vec();
    let o = littoral::scene::Overrides {
        bands: Some(5),
        ..Default::default()
    };
    let c = bands(&littoral::scene::Scene::coastal(&o).unwrap());
    assert_eq!((c.len(), c[0], c[4]), (5, 400.0, 800.0));
    let explicit = littoral::scene::text::SceneText::parse(crate::common::MINIMAL_SCENE)
        .unwrap()
        .remove("spectral")
        .merge("[spectral]\ncenters_nm = [443.0, 490.0, 560.0, 665.0]\nfwhm_nm = [10.0, 10.0, 10.0, 10.0]\n")
        .unwrap()
        .text();
    let s = littoral::scene::Scene::parse(&explicit, std::path::Path::new("x.toml"), &o).unwrap();
    let c = bands(&s);
    assert_eq!((c.len(), c[0], c[4]), (5, 443.0, 665.0));
}
