//! A run's files as one set: published together (a signal waits for the
//! renames), never mixed by two runs at once, never written through links
//! or special files nor over the run's own inputs, and what killed runs
//! left behind is swept at the next run.

use crate::common::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// The minimal scene named "m" with an 8 x 8 image and `seed`.
fn scene_text(seed: u64) -> String {
    format!("name = \"m\"\nseed = {seed}\n{MINIMAL_SCENE}[sensor]\npixels = [8, 8]\n")
}

fn write_scene(dir: &Path, seed: u64) -> PathBuf {
    let path = dir.join(format!("m{seed}.toml"));
    std::fs::write(&path, scene_text(seed)).unwrap();
    path
}

fn render(scene: &Path, out: &Path) -> Output {
    littoral(&["render", p(scene), "--out", p(out), "--quiet"])
}

fn ok(out: &Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Every visible file in `dir` with its bytes.
fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap())
        .filter(|e| e.file_type().unwrap().is_file())
        .map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            (name, std::fs::read(e.path()).unwrap())
        })
        .filter(|(n, _)| !n.starts_with('.'))
        .collect()
}

/// Hidden entries in `dir`: temporaries, staging directories, lock files.
fn hidden(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect()
}

/// The report without what differs between two runs of one scene.
fn report_values(json: &[u8]) -> serde_json::Value {
    let mut v: serde_json::Value = serde_json::from_slice(json).unwrap();
    for key in ["timings_s", "peak_memory", "peak_rss_bytes", "cache"] {
        v.as_object_mut().unwrap().remove(key);
    }
    v
}

/// Which run the set in `dir` belongs to: "old" or "new" when every file
/// is that run's (the cubes byte for byte, the report but for timings, the
/// page by the quicklook it embeds), else a description of the mix.
fn whose(dir: &Path, old: &BTreeMap<String, Vec<u8>>, new: &BTreeMap<String, Vec<u8>>) -> String {
    use base64::Engine;
    let now = files(dir);
    let mut owners = BTreeMap::new();
    for (name, bytes) in &now {
        let of = |set: &BTreeMap<String, Vec<u8>>| -> bool {
            let Some(theirs) = set.get(name) else {
                return false;
            };
            if name.ends_with(".json") {
                report_values(bytes) == report_values(theirs)
            } else if name.ends_with(".html") {
                let png = base64::engine::general_purpose::STANDARD.encode(&set["m.png"]);
                String::from_utf8_lossy(bytes).contains(&png)
            } else {
                bytes == theirs
            }
        };
        let owner = match (of(old), of(new)) {
            (true, false) => "old",
            (false, true) => "new",
            (true, true) => "both",
            (false, false) => "neither",
        };
        owners.insert(name.clone(), owner);
    }
    let kinds: std::collections::BTreeSet<&str> =
        owners.values().copied().filter(|o| *o != "both").collect();
    match (kinds.len(), now.len() == old.len()) {
        (1, true) => kinds.into_iter().next().unwrap().to_string(),
        _ => format!("a mixed set: {owners:?}"),
    }
}

/// A SIGINT at every moment of the renames that publish a render (paused
/// before each one) leaves the set whole: the earlier run's files
/// untouched, or every file of the new run; never some of each, and no
/// temporary.
#[test]
fn a_signal_during_publication_leaves_one_whole_set() {
    let dir = tempdir();
    let (old_scene, new_scene) = (write_scene(dir.path(), 1), write_scene(dir.path(), 2));
    // Both runs' sets, made where the test's runs write (the report names
    // its files by path).
    let out = dir.path().join("out");
    let set_of = |scene: &Path| {
        ok(&render(scene, &out));
        let set = files(&out);
        std::fs::remove_dir_all(&out).unwrap();
        set
    };
    let (old, new) = (set_of(&old_scene), set_of(&new_scene));
    assert_eq!(old.len(), new.len());
    assert_ne!(
        old["m.bsq"], new["m.bsq"],
        "the seeds must tell the runs apart"
    );
    const PAUSE_MS: u64 = 20;
    let mut seen = BTreeMap::new();
    for k in 0..=old.len() as u64 + 1 {
        let _ = std::fs::remove_dir_all(&out);
        std::fs::create_dir(&out).unwrap();
        for (name, bytes) in &old {
            std::fs::write(out.join(name), bytes).unwrap();
        }
        let mut child = Command::new(env!("CARGO_BIN_EXE_littoral"))
            .args(["render", p(&new_scene), "--out", p(&out), "--quiet"])
            .env("LITTORAL_PUBLISH_PAUSE_MS", PAUSE_MS.to_string())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // The report is the last file staged before the renames begin.
        let start = Instant::now();
        let staged_report = || {
            hidden(&out)
                .iter()
                .any(|n| n.starts_with(".littoral-stage.") && out.join(n).join("m.json").exists())
        };
        while !staged_report() {
            assert!(start.elapsed() < Duration::from_secs(60), "never staged");
            if child.try_wait().unwrap().is_some() {
                break;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        std::thread::sleep(Duration::from_millis(k * PAUSE_MS + PAUSE_MS / 2));
        let _ = Command::new("kill")
            .args(["-INT", &child.id().to_string()])
            .status();
        let output = child.wait_with_output().unwrap();
        assert!(
            matches!(output.status.code(), Some(0) | Some(130)),
            "{output:?}"
        );
        let owner = whose(&out, &old, &new);
        assert!(
            owner == "old" || owner == "new",
            "signal at step {k}: {owner}"
        );
        assert_eq!(hidden(&out), Vec::<String>::new(), "step {k}");
        *seen.entry(owner).or_insert(0) += 1;
    }
    // The signals arrived during the publication (each waited for it).
    assert!(seen.get("new").copied().unwrap_or(0) > 0, "{seen:?}");
}

/// A run whose EXR meets a full disk publishes nothing: the earlier run's
/// set stays whole, and nothing is left behind.
#[test]
fn a_full_disk_publishes_nothing() {
    let dir = tempdir();
    let (old_scene, new_scene) = (write_scene(dir.path(), 1), write_scene(dir.path(), 2));
    let out = dir.path().join("out");
    ok(&render(&old_scene, &out));
    let before = files(&out);
    // The map is emitted first, so that the render writes only its set.
    let map = dir.path().join("w.map");
    ok(&littoral(&[
        "emit",
        p(&new_scene),
        "--map",
        p(&map),
        "--quiet",
    ]));
    // 4 blocks of 512 bytes (or 1 KiB): the 1 KiB cubes fit, the 7 KB EXR
    // does not.
    let script = format!(
        "trap '' XFSZ; ulimit -f 4; exec '{}' render '{}' --map '{}' --out '{}' --quiet",
        env!("CARGO_BIN_EXE_littoral"),
        p(&new_scene),
        p(&map),
        p(&out)
    );
    let output = Command::new("sh").arg("-c").arg(&script).output().unwrap();
    assert_clean_failure(&output, "m.exr");
    assert_eq!(files(&out), before);
    assert_eq!(hidden(&out), Vec::<String>::new());
}

/// Two runs writing one render or one map: the second fails at once,
/// naming the lock, and touches nothing; renders reading a map share it.
#[test]
fn concurrent_runs_do_not_mix() {
    use littoral::output::set::RunLock;
    let dir = tempdir();
    let scene = write_scene(dir.path(), 1);
    let out = dir.path().join("out");
    ok(&render(&scene, &out));
    let before = files(&out);
    {
        let _held = RunLock::exclusive(&out.join("m.render")).unwrap();
        assert_clean_failure(&render(&scene, &out), "another littoral run");
        assert_eq!(files(&out), before);
    }
    let map = dir.path().join("w.map");
    ok(&littoral(&["emit", p(&scene), "--map", p(&map), "--quiet"]));
    let map_bytes = std::fs::read(&map).unwrap();
    {
        let _reader = RunLock::shared(&map).unwrap();
        let again = littoral(&[
            "emit",
            p(&scene),
            "--map",
            p(&map),
            "--report",
            p(&dir.path().join("r.json")),
            "--quiet",
        ]);
        assert_clean_failure(&again, "another littoral run");
        assert_eq!(std::fs::read(&map).unwrap(), map_bytes);
        assert!(!dir.path().join("r.json").exists());
        // Another render reading the same map is not held up.
        let other = dir.path().join("other");
        ok(&littoral(&[
            "render",
            p(&scene),
            "--map",
            p(&map),
            "--out",
            p(&other),
            "--quiet",
        ]));
    }
    // Finished runs leave no lock file.
    ok(&render(&scene, &out));
    assert_eq!(hidden(&out), Vec::<String>::new());
    assert_eq!(hidden(dir.path()), Vec::<String>::new());
}

/// Links, FIFOs and devices named as outputs are refused, not replaced.
#[test]
fn links_and_special_files_are_not_replaced() {
    let dir = tempdir();
    let scene = write_scene(dir.path(), 1);
    let target = dir.path().join("real.map");
    std::fs::write(&target, b"").unwrap();
    let link = dir.path().join("link.map");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let out = littoral(&["emit", p(&scene), "--map", p(&link), "--quiet"]);
    assert_clean_failure(&out, "symbolic link");
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());

    let fifo = dir.path().join("report.fifo");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let map = dir.path().join("w.map");
    let out = littoral(&[
        "emit",
        p(&scene),
        "--map",
        p(&map),
        "--report",
        p(&fifo),
        "--quiet",
    ]);
    assert_clean_failure(&out, "not a regular file");
    assert!(!map.exists());
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::symlink_metadata(&fifo)
        .unwrap()
        .file_type()
        .is_fifo());

    // A render's output name that is a link.
    let render_dir = dir.path().join("out");
    std::fs::create_dir(&render_dir).unwrap();
    let hdr_link = render_dir.join("m.hdr");
    std::os::unix::fs::symlink(&target, &hdr_link).unwrap();
    assert_clean_failure(&render(&scene, &render_dir), "m.hdr");
    assert!(std::fs::symlink_metadata(&hdr_link)
        .unwrap()
        .file_type()
        .is_symlink());
    assert_eq!(files(&render_dir).len(), 0);
}

/// An output that is one of the run's inputs is refused, and the input
/// stays as it was.
#[test]
fn inputs_are_not_overwritten() {
    let dir = tempdir();
    let scene = write_scene(dir.path(), 1);
    let text = std::fs::read(&scene).unwrap();
    let out = littoral(&["emit", p(&scene), "--map", p(&scene), "--quiet"]);
    assert_clean_failure(&out, "m1.toml");
    let map = dir.path().join("w.map");
    let out = littoral(&[
        "emit",
        p(&scene),
        "--map",
        p(&map),
        "--report",
        p(&scene),
        "--quiet",
    ]);
    assert_clean_failure(&out, "scene file");
    assert_eq!(std::fs::read(&scene).unwrap(), text);
    assert!(!map.exists());

    // A map path holding someone's file.
    let notes = dir.path().join("notes.txt");
    std::fs::write(&notes, "field notes\n").unwrap();
    let out = littoral(&[
        "render",
        p(&scene),
        "--map",
        p(&notes),
        "--out",
        p(&dir.path().join("o")),
        "--quiet",
    ]);
    assert_clean_failure(&out, "not a littoral photon map");
    assert_eq!(std::fs::read(&notes).unwrap(), b"field notes\n");

    // A scene file where the render would write its report.
    let out_dir = dir.path().join("o2");
    std::fs::create_dir(&out_dir).unwrap();
    let inside = out_dir.join("m.json");
    std::fs::write(&inside, scene_text(1)).unwrap();
    let out = render(&inside, &out_dir);
    assert_clean_failure(&out, "scene file");
    assert_eq!(std::fs::read(&inside).unwrap(), scene_text(1).as_bytes());

    // The cube tool's outputs over its input cube.
    let cubes = dir.path().join("c");
    ok(&render(&scene, &cubes));
    let (hdr, bsq) = (cubes.join("m.hdr"), cubes.join("m.bsq"));
    let (hdr_bytes, bsq_bytes) = (std::fs::read(&hdr).unwrap(), std::fs::read(&bsq).unwrap());
    let tool = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_littoral-cube"))
            .args(args)
            .output()
            .unwrap()
    };
    for args in [
        vec!["exr", p(&hdr), "--out", p(&hdr)],
        vec!["exr", p(&hdr), "--out", p(&bsq)],
        vec!["window", p(&hdr), "0", "0", "2", "2", "--out", p(&hdr)],
        vec!["window", p(&hdr), "0", "0", "2", "2", "--out", p(&bsq)],
        vec!["subset", p(&hdr), "0", "1", "--out", p(&hdr)],
        vec!["convert", p(&hdr), "--interleave", "bsq", "--out", p(&hdr)],
    ] {
        let out = tool(&args);
        assert_clean_failure(&out, "--out");
        assert_eq!(std::fs::read(&hdr).unwrap(), hdr_bytes, "{args:?}");
        assert_eq!(std::fs::read(&bsq).unwrap(), bsq_bytes, "{args:?}");
    }
    // A data file longer than its header says.
    let mut longer = bsq_bytes.clone();
    longer.extend_from_slice(&[0; 4]);
    std::fs::write(&bsq, &longer).unwrap();
    assert_clean_failure(&tool(&["info", p(&hdr)]), "m.bsq");
}

/// What runs killed on this host left in the output directory is removed
/// at the next run there, with a warning; temporaries of live processes
/// and of other hosts stay.
#[test]
fn killed_runs_leftovers_are_swept() {
    let dir = tempdir();
    let scene = write_scene(dir.path(), 1);
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let host = littoral::output::set::host_name();
    // Above any pid_max Linux allows (2^22): no such process.
    let dead = 4_194_400u32;
    let alive = std::process::id();
    let stale = [
        format!(".littoral-map.{host}_{dead}.AbC123"),
        format!(".m.hdr.{host}_{dead}.XyZ789.partial"),
    ];
    for n in &stale {
        std::fs::write(out.join(n), b"partial").unwrap();
    }
    let stage = out.join(format!(".littoral-stage.{host}_{dead}.Qq1234"));
    std::fs::create_dir(&stage).unwrap();
    std::fs::write(stage.join("m.bsq"), b"partial").unwrap();
    let kept = [
        format!(".littoral-map.{host}_{alive}.AbC123"),
        format!(".littoral-map.othernode_{dead}.AbC123"),
        ".notes".to_string(),
    ];
    for n in &kept {
        std::fs::write(out.join(n), b"keep").unwrap();
    }
    let run = render(&scene, &out);
    ok(&run);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(stderr.contains("removed 3 temporary file(s)"), "{stderr}");
    let mut left = hidden(&out);
    left.sort();
    let mut expected = kept.to_vec();
    expected.sort();
    assert_eq!(left, expected);
}

/// `--threads` beyond the machine's cap is a usage error naming its cores.
#[test]
fn absurd_thread_counts_are_refused() {
    let dir = tempdir();
    let scene = write_scene(dir.path(), 1);
    let out = littoral(&[
        "render",
        p(&scene),
        "--out",
        p(&dir.path().join("o")),
        "--threads",
        "100000",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("cores"), "{err}");
    assert!(!dir.path().join("o").exists());
}
