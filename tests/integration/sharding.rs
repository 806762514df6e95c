//! Sharded production: `emit --shard I/N` on several machines, `map merge`
//! into one map, byte-identical to a single `emit`; shard files that are
//! a pure function of scene, shard and budget; and merges refused, with
//! the file named, for a missing, repeated, foreign, truncated or corrupt
//! shard.

use crate::common::{assert_clean_failure, littoral, minimal, p, tempdir};
use std::path::{Path, PathBuf};

/// A small floor-and-target scene with a sky, so every photon kind occurs.
fn scene_text() -> String {
    minimal()
        .remove("water.iop")
        .merge(
            r#"
name = "shards"
seed = 7
spectral = { start_nm = 420.0, end_nm = 680.0, bands = 6 }
sun = { zenith_deg = 35.0 }
sky = { radiance = 0.03 }
domain = { size_m = [30.0, 30.0] }
water = { chl = 1.0 }
bottom = { depth_m = 6.0, reflectance = "sand" }
target = [{ kind = "panel", center_m = [15.0, 15.0, -3.0], size_m = [4.0, 4.0], reflectance = 0.4 }]
photons = { count = 120000 }
tally = { depths_m = [0.0, 2.0] }
"#,
        )
        .unwrap()
        .text()
}

fn ok(out: std::process::Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// `littoral emit SCENE --shard SHARD --map PATH EXTRA...`, which must succeed.
fn emit_shard(scene: &Path, shard: &str, path: &Path, extra: &[&str]) {
    let mut args = vec![
        "emit",
        p(scene),
        "--shard",
        shard,
        "--map",
        p(path),
        "--quiet",
    ];
    args.extend_from_slice(extra);
    ok(littoral(&args));
}

fn shards(dir: &Path, scene: &Path, n: u64, extra: &[&str]) -> Vec<PathBuf> {
    (0..n)
        .map(|i| {
            let part = dir.join(format!("part{i}.shard"));
            emit_shard(scene, &format!("{i}/{n}"), &part, extra);
            part
        })
        .collect()
}

#[test]
fn merged_shards_are_the_single_run_map_byte_for_byte() {
    let dir = tempdir();
    let scene = dir.path().join("s.toml");
    std::fs::write(&scene, scene_text()).unwrap();
    let single = dir.path().join("single.map");
    ok(littoral(&[
        "emit",
        p(&scene),
        "--map",
        p(&single),
        "--mem-budget",
        "64MiB",
        "--quiet",
    ]));
    let single_bytes = std::fs::read(&single).unwrap();
    for n in [1u64, 3] {
        let sub = dir.path().join(format!("n{n}"));
        std::fs::create_dir(&sub).unwrap();
        let parts = shards(&sub, &scene, n, &["--mem-budget", "64MiB"]);
        // Any order.
        let mut args = vec!["map", "merge"];
        let rev: Vec<&str> = parts.iter().rev().map(|x| p(x)).collect();
        args.extend(rev);
        let merged = sub.join("merged.map");
        let report = sub.join("merged.json");
        args.extend([
            "--out",
            p(&merged),
            "--report",
            p(&report),
            "--mem-budget",
            "64MiB",
            "--quiet",
        ]);
        ok(littoral(&args));
        assert!(
            std::fs::read(&merged).unwrap() == single_bytes,
            "{n} shards: the merged map differs from the single run's"
        );
        let r: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
        assert_eq!(r["photons"]["traced"], 120000);
        // Shards under the previous magic (frames with each byte plane
        // compressed apart, which this build still reads) merge as well.
        for part in &parts {
            let mut bytes = std::fs::read(part).unwrap();
            assert_eq!(&bytes[..8], b"LTSHARD3");
            bytes[..8].copy_from_slice(b"LTSHARD2");
            std::fs::write(part, bytes).unwrap();
        }
        // Without --mem-budget the merge takes the shards' own.
        let again = sub.join("again.map");
        let again_report = sub.join("again.json");
        let mut args = vec!["map", "merge"];
        args.extend(parts.iter().map(|x| p(x)));
        args.extend(["--out", p(&again), "--report", p(&again_report), "--quiet"]);
        ok(littoral(&args));
        assert!(std::fs::read(&again).unwrap() == single_bytes);
        let r: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&again_report).unwrap()).unwrap();
        assert_eq!(r["mem_budget_bytes"], 64 << 20);
    }
    // A shard file is the same for any number of threads.
    let a = dir.path().join("t1.shard");
    let b = dir.path().join("t2.shard");
    for (path, threads) in [(&a, "1"), (&b, "2")] {
        emit_shard(&scene, "1/3", path, &["--threads", threads]);
    }
    assert!(std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap());
}

#[test]
fn bad_shard_sets_are_refused_naming_the_file() {
    let dir = tempdir();
    let scene = dir.path().join("s.toml");
    std::fs::write(
        &scene,
        scene_text().replace("count = 120000", "count = 20000"),
    )
    .unwrap();
    let parts = shards(dir.path(), &scene, 3, &[]);
    let out = dir.path().join("m.map");
    let merge = |files: &[&Path]| {
        let mut args = vec!["map", "merge"];
        args.extend(files.iter().map(|f| p(f)));
        args.extend(["--out", p(&out)]);
        littoral(&args)
    };
    assert_clean_failure(&merge(&[&parts[0], &parts[2]]), "shards missing: 1 of 3");
    assert_clean_failure(&merge(&[&parts[0], &parts[1], &parts[1]]), "given twice");
    // Another scene's shard.
    let other = dir.path().join("o.toml");
    std::fs::write(
        &other,
        scene_text()
            .replace("count = 120000", "count = 20000")
            .replace("seed = 7", "seed = 8"),
    )
    .unwrap();
    let foreign = dir.path().join("foreign.shard");
    emit_shard(&other, "1/3", &foreign, &[]);
    assert_clean_failure(&merge(&[&parts[0], &foreign, &parts[2]]), "foreign.shard");
    // The same emission's shard at another budget (its pilot is the same
    // at this count, its tiles would not be).
    let budget = dir.path().join("budget.shard");
    emit_shard(&scene, "1/3", &budget, &["--mem-budget", "64MiB"]);
    assert_clean_failure(&merge(&[&parts[0], &budget, &parts[2]]), "--mem-budget");
    // Truncated and corrupted files.
    let bytes = std::fs::read(&parts[1]).unwrap();
    let cut = dir.path().join("cut.shard");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    assert_clean_failure(&merge(&[&parts[0], &cut, &parts[2]]), "cut.shard");
    let mut flipped = bytes.clone();
    flipped[100] ^= 0x40;
    let bad = dir.path().join("bad.shard");
    std::fs::write(&bad, &flipped).unwrap();
    assert_clean_failure(&merge(&[&parts[0], &bad, &parts[2]]), "bad.shard");
    assert!(
        !out.exists(),
        "nothing under the final name after a failed merge"
    );
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(left.is_empty(), "temporaries left: {left:?}");
    // A shard is not a map.
    let info = littoral(&["map", "info", p(&parts[0])]);
    assert_clean_failure(&info, "littoral map merge");
    // Shard numbers are checked on the command line.
    let e = littoral(&["emit", p(&scene), "--shard", "3/3", "--map", p(&out)]);
    assert_eq!(e.status.code(), Some(2));
}

/// `littoral render SCENE --tiles TILES --map MAP --out OUT`, which must
/// succeed.
fn render_part(scene: &Path, tiles: &str, map: &Path, out: &Path) {
    ok(littoral(&[
        "render",
        p(scene),
        "--tiles",
        tiles,
        "--map",
        p(map),
        "--out",
        p(out),
        "--quiet",
    ]));
}

/// The sharding scene with a small image (3 x 2 tiles of 16 px) and a
/// radiometer.
fn render_scene() -> String {
    scene_text().replace("count = 120000", "count = 60000")
        + "[sensor]\npixels = [40, 24]\ngsd_m = 0.6\n[[radiometer]]\ndepth_m = 1.0\nview = \"nadir\"\nposition_m = [15.0, 15.0]\n"
}

/// Every file a render writes that must be byte-identical between a whole
/// render and an assembled one (the JSON and HTML carry timings and paths).
fn same_outputs(a: &Path, b: &Path) {
    let mut names: Vec<String> = std::fs::read_dir(a)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !n.ends_with(".json") && !n.ends_with(".html") && !n.starts_with('.'))
        .collect();
    names.sort();
    assert!(names.len() >= 15, "{names:?}");
    for n in &names {
        assert!(
            std::fs::read(a.join(n)).unwrap() == std::fs::read(b.join(n)).unwrap(),
            "{n} differs"
        );
    }
    let ra: serde_json::Value =
        serde_json::from_slice(&std::fs::read(a.join("shards.json")).unwrap()).unwrap();
    let rb: serde_json::Value =
        serde_json::from_slice(&std::fs::read(b.join("shards.json")).unwrap()).unwrap();
    assert_eq!(ra["radiometers"], rb["radiometers"]);
    assert_eq!(ra["emission"], rb["emission"]);
    assert!(b.join("shards.html").exists());
}

/// `render --tiles I/N` parts assembled by `littoral assemble` write
/// the whole render's cubes, EXR, quicklook and CSVs byte for byte, with
/// the photon map and with the path integrator; a part started again
/// keeps the tiles it finished; bad part sets are refused.
#[test]
fn assembled_parts_are_the_whole_render_byte_for_byte() {
    let dir = tempdir();
    let scene = dir.path().join("s.toml");
    std::fs::write(&scene, render_scene()).unwrap();
    let map = dir.path().join("s.map");
    ok(littoral(&["emit", p(&scene), "--map", p(&map), "--quiet"]));
    for extra in [&[][..], &["--integrator", "path", "--spp", "2"][..]] {
        let tag = if extra.is_empty() { "pm" } else { "path" };
        let whole = dir.path().join(format!("{tag}-whole"));
        let mut args = vec![
            "render",
            p(&scene),
            "--map",
            p(&map),
            "--out",
            p(&whole),
            "--quiet",
        ];
        args.extend_from_slice(extra);
        ok(littoral(&args));
        let parts: Vec<PathBuf> = (0..3)
            .map(|i| {
                let part = dir.path().join(format!("{tag}-part{i}"));
                let tiles = format!("{i}/3");
                let mut args = vec![
                    "render",
                    p(&scene),
                    "--map",
                    p(&map),
                    "--tiles",
                    &tiles,
                    "--out",
                    p(&part),
                    "--quiet",
                ];
                args.extend_from_slice(extra);
                ok(littoral(&args));
                part
            })
            .collect();
        let out = dir.path().join(format!("{tag}-assembled"));
        // `littoral assemble`, and its alias `littoral-cube assemble`.
        let program = if tag == "pm" {
            env!("CARGO_BIN_EXE_littoral")
        } else {
            env!("CARGO_BIN_EXE_littoral-cube")
        };
        let cube = std::process::Command::new(program)
            .args([
                "assemble",
                p(&parts[2]),
                p(&parts[0]),
                p(&parts[1]),
                "--out",
                p(&out),
            ])
            .output()
            .unwrap();
        ok(cube);
        same_outputs(&whole, &out);
    }

    // A part started again keeps its finished tiles (same inode) and
    // renders the ones that are gone.
    let part = dir.path().join("pm-part1");
    let tiles: Vec<PathBuf> = std::fs::read_dir(part.join("tiles"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(tiles.len(), 2, "part 1 of 3 of 6 tiles");
    use std::os::unix::fs::MetadataExt;
    let kept_inode = std::fs::metadata(&tiles[0]).unwrap().ino();
    let redo = std::fs::read(&tiles[1]).unwrap();
    std::fs::remove_file(&tiles[1]).unwrap();
    ok(littoral(&[
        "render",
        p(&scene),
        "--map",
        p(&map),
        "--tiles",
        "1/3",
        "--out",
        p(&part),
        "--quiet",
    ]));
    assert_eq!(std::fs::metadata(&tiles[0]).unwrap().ino(), kept_inode);
    assert!(
        std::fs::read(&tiles[1]).unwrap() == redo,
        "the tile rendered again is the same"
    );

    // Bad sets: a missing part, a corrupt tile, a part without a map.
    let run_cube = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_littoral-cube"))
            .args(args)
            .output()
            .unwrap()
    };
    let out = dir.path().join("bad");
    let p0 = dir.path().join("pm-part0");
    let p2 = dir.path().join("pm-part2");
    assert_clean_failure(
        &run_cube(&["assemble", p(&p0), p(&p2), "--out", p(&out)]),
        "parts missing: 1 of 3",
    );
    // A manifest whose part number is past its count (damaged, or edited).
    let manifest = p2.join("part.json");
    let good = std::fs::read(&manifest).unwrap();
    let mut m: serde_json::Value = serde_json::from_slice(&good).unwrap();
    m["part"] = serde_json::json!(7);
    std::fs::write(&manifest, serde_json::to_vec(&m).unwrap()).unwrap();
    assert_clean_failure(
        &run_cube(&["assemble", p(&p0), p(&part), p(&p2), "--out", p(&out)]),
        "part 7 of 3",
    );
    std::fs::write(&manifest, good).unwrap();
    let mut bytes = std::fs::read(&tiles[0]).unwrap();
    let k = bytes.len() / 2;
    bytes[k] ^= 1;
    std::fs::write(&tiles[0], &bytes).unwrap();
    assert_clean_failure(
        &run_cube(&["assemble", p(&p0), p(&part), p(&p2), "--out", p(&out)]),
        "CRC",
    );
    assert_clean_failure(
        &littoral(&["render", p(&scene), "--tiles", "0/2", "--out", p(&out)]),
        "--map",
    );
}

/// A sensor above the atmosphere, rendered in parts and assembled: the
/// cubes with the reflectance at the sensor and the path radiance, and the
/// atmosphere's table, byte for byte those of the whole render.
#[test]
fn assembled_parts_above_the_atmosphere_are_the_whole_render() {
    let dir = tempdir();
    let scene = dir.path().join("s.toml");
    let text = littoral::scene::text::SceneText::parse(&render_scene())
        .unwrap()
        .remove("sky")
        .remove("sun.irradiance")
        .merge(
            r#"
sun = { spectrum = "extraterrestrial" }
atmosphere = { sky_photons = 2000 }
sensor = { altitude_m = 700000.0, view_zenith_deg = 20.0 }
"#,
        )
        .unwrap()
        .text();
    std::fs::write(&scene, text).unwrap();
    let map = dir.path().join("s.map");
    ok(littoral(&["emit", p(&scene), "--map", p(&map), "--quiet"]));
    let whole = dir.path().join("whole");
    ok(littoral(&[
        "render",
        p(&scene),
        "--map",
        p(&map),
        "--out",
        p(&whole),
        "--quiet",
    ]));
    let parts: Vec<PathBuf> = (0..2)
        .map(|i| {
            let part = dir.path().join(format!("part{i}"));
            let tiles = format!("{i}/2");
            ok(littoral(&[
                "render",
                p(&scene),
                "--map",
                p(&map),
                "--tiles",
                &tiles,
                "--out",
                p(&part),
                "--quiet",
            ]));
            part
        })
        .collect();
    let out = dir.path().join("assembled");
    ok(littoral(&[
        "assemble",
        p(&parts[1]),
        p(&parts[0]),
        "--out",
        p(&out),
    ]));
    for name in [
        "shards.rhot.hdr",
        "shards.lpath.bsq",
        "shards.tdown.hdr",
        "shards.tup.bsq",
        "shards.atmosphere.csv",
    ] {
        assert!(whole.join(name).exists(), "{name}");
    }
    same_outputs(&whole, &out);
}

/// `render --resume` after an interruption: the tiles a killed run left
/// in OUT/.NAME.parts are kept, the rest rendered, and the outputs are the
/// uninterrupted render's; the parts directory is gone afterwards.
#[test]
fn a_resumed_render_is_the_uninterrupted_one() {
    let dir = tempdir();
    let scene = dir.path().join("s.toml");
    std::fs::write(&scene, render_scene()).unwrap();
    let whole = dir.path().join("whole");
    ok(littoral(&[
        "render",
        p(&scene),
        "--out",
        p(&whole),
        "--quiet",
    ]));
    // What a killed --resume run leaves: some tiles, no part.json.
    let out = dir.path().join("resumed");
    let parts = out.join(".shards.parts");
    render_part(&scene, "0/1", &parts.join("map.map"), &parts);
    std::fs::remove_file(parts.join("part.json")).unwrap();
    let tiles: Vec<PathBuf> = std::fs::read_dir(parts.join("tiles"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    for t in tiles.iter().step_by(2) {
        std::fs::remove_file(t).unwrap();
    }
    ok(littoral(&[
        "render",
        p(&scene),
        "--out",
        p(&out),
        "--resume",
        "--quiet",
    ]));
    same_outputs(&whole, &out);
    assert!(!parts.exists(), "the parts directory is removed");
}

/// Finished tiles are stamped with the scene and the bytes of the files it
/// reads: after the floor's reflectance file changes, a part render with
/// the same command line renders every tile again instead of keeping the
/// old ones (each tile's stamp is new).
#[test]
fn tiles_are_not_kept_when_a_file_the_scene_reads_changed() {
    let dir = tempdir();
    let scene = dir.path().join("s.toml");
    let floor = dir.path().join("floor.csv");
    std::fs::write(&floor, "nm,reflectance\n400,0.2\n700,0.3\n").unwrap();
    std::fs::write(
        &scene,
        render_scene().replace("reflectance = \"sand\"", "reflectance = \"floor.csv\""),
    )
    .unwrap();
    let part = dir.path().join("part");
    let render = || render_part(&scene, "0/1", &dir.path().join("m.map"), &part);
    let stamps = || -> Vec<Vec<u8>> {
        let mut tiles: Vec<PathBuf> = std::fs::read_dir(part.join("tiles"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        tiles.sort();
        tiles
            .iter()
            .map(|t| std::fs::read(t).unwrap()[..80].to_vec())
            .collect()
    };
    render();
    let before = stamps();
    render();
    assert_eq!(stamps(), before, "unchanged inputs keep the tiles");
    std::fs::write(&floor, "nm,reflectance\n400,0.25\n700,0.3\n").unwrap();
    render();
    let after = stamps();
    assert_eq!(after.len(), before.len());
    assert!(
        after.iter().zip(&before).all(|(a, b)| a != b),
        "every tile is rendered again"
    );
}

/// `littoral plan` writes the four batch scripts and submit.sh (two for
/// the path integrator: no map to emit), each valid shell, with the array
/// size, memory and the task id in the commands, chained by afterok.
#[test]
fn plan_writes_chained_batch_scripts() {
    let dir = tempdir();
    let scene = dir.path().join("s.toml");
    std::fs::write(&scene, render_scene()).unwrap();
    let plan = dir.path().join("plan");
    ok(littoral(&[
        "plan",
        p(&scene),
        "--shards",
        "4",
        "--out",
        p(&plan),
        "--mem-budget",
        "128MiB",
        "--cpus-per-task",
        "3",
        "--time",
        "1:00:00",
    ]));
    let read = |n: &str| std::fs::read_to_string(plan.join(n)).unwrap();
    for n in [
        "emit.sbatch",
        "merge.sbatch",
        "render.sbatch",
        "assemble.sbatch",
        "submit.sh",
    ] {
        let st = std::process::Command::new("bash")
            .args(["-n", p(&plan.join(n))])
            .status()
            .unwrap();
        assert!(st.success(), "{n} is not valid bash");
    }
    let emit = read("emit.sbatch");
    assert!(
        emit.contains("#SBATCH --array=0-3") && emit.contains("--shard \"$SLURM_ARRAY_TASK_ID\"/4")
    );
    // 128 MiB + a quarter + 256 MiB.
    assert!(emit.contains("#SBATCH --mem=416M") && emit.contains("#SBATCH --cpus-per-task=3"));
    assert!(emit.contains("#SBATCH --time=1:00:00"));
    let merge = read("merge.sbatch");
    assert!((0..4).all(|i| merge.contains(&format!("part-{i}.shard"))));
    let render = read("render.sbatch");
    assert!(render.contains("--tiles \"$SLURM_ARRAY_TASK_ID\"/4") && render.contains("--map"));
    let submit = read("submit.sh");
    let order: Vec<usize> = ["emit=", "merge=", "render=", "assemble="]
        .iter()
        .map(|k| submit.find(k).unwrap())
        .collect();
    assert!(order.windows(2).all(|w| w[0] < w[1]), "{submit}");
    assert_eq!(submit.matches("--dependency=afterok:").count(), 3);

    let path_plan = dir.path().join("path-plan");
    ok(littoral(&[
        "plan",
        p(&scene),
        "--shards",
        "2",
        "--out",
        p(&path_plan),
        "--integrator",
        "path",
    ]));
    assert!(!path_plan.join("emit.sbatch").exists() && !path_plan.join("merge.sbatch").exists());
    let render = std::fs::read_to_string(path_plan.join("render.sbatch")).unwrap();
    assert!(render.contains("--integrator path") && !render.contains("--map"));
}
