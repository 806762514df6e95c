//! Memory: `littoral map synth` of 20 M photons, `emit`, `render` and the
//! stages of a sharded run (shard emission, merge, render parts) under
//! `--mem-budget 64MiB` stay under the budget plus a fixed overhead, judged
//! by VmHWM and, for emit and render, by the sampled anonymous peak their
//! reports give apart from the mapped file pages.
//!
//! The child reports its own peak resident set (VmHWM, read at the end of
//! its run) on stderr. getrusage on the child would not do: Linux carries
//! the parent's resident size into a freshly spawned child's maximum, and
//! the test process is large. VmHWM counts anonymous memory plus resident
//! file pages (binary text, libraries); synth maps no data files, so it
//! bounds the anonymous peak from above. The fixed overhead allowed beyond
//! the budget is 16 MiB: about 3 MiB of process baseline (binary, libc,
//! allocator), thread stacks and per-thread allocator arenas of the
//! producers and the writer, and slack for allocator fragmentation. The
//! writer's own fixed needs (zstd contexts, I/O buffers, channel, spill
//! metadata) are inside the budget (`WRITER_FIXED_BYTES`).

use crate::common::*;
use littoral::job::report::{EmitReport, RunReport};
use littoral::mem::MemoryPeaks;
use std::path::Path;

const OVERHEAD: u64 = 16 * MIB;

/// The typed report a successful run wrote to `path`.
fn report_of<T: serde::de::DeserializeOwned>(run: &std::process::Output, path: &Path) -> T {
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

/// The built-in scene imaged with `pixels` x `pixels` pixels of `gsd_m`,
/// written into `dir`.
fn coarse_builtin_scene(dir: &Path, pixels: usize, gsd_m: f64) -> std::path::PathBuf {
    let scene = dir.join("coastal.toml");
    let text = littoral::scene::COASTAL_TOML
        .replace(
            "pixels = [256, 256]",
            &format!("pixels = [{pixels}, {pixels}]"),
        )
        .replace("gsd_m = 0.75", &format!("gsd_m = {gsd_m:?}"));
    std::fs::write(&scene, text).unwrap();
    scene
}

/// Both the sampled anonymous peak (what the budget bounds) and VmHWM
/// (anonymous plus file pages: the map here is small) within 64 MiB plus
/// the overhead; the anonymous peak is at most VmHWM.
fn assert_peak_within_64mib(stage: &str, peaks: MemoryPeaks) {
    let m = |b: u64| b as f64 / MIB as f64;
    eprintln!(
        "{stage}: peak anonymous {:.1} MiB, file pages {:.1} MiB, VmHWM {:.1} MiB",
        m(peaks.anon_bytes),
        m(peaks.file_bytes),
        m(peaks.rss_bytes)
    );
    for peak in [peaks.anon_bytes, peaks.rss_bytes] {
        assert!(
            peak > MIB && peak <= 64 * MIB + OVERHEAD,
            "{stage}: {peaks:?}"
        );
    }
    assert!(peaks.anon_bytes <= peaks.rss_bytes, "{stage}: {peaks:?}");
}

#[test]
fn synth_20m_photons_within_64mib() {
    let dir = tempdir();
    let out = dir.path().join("big.map");
    let budget = 64 * MIB;
    let run = littoral(&[
        "map",
        "synth",
        "--photons",
        "20000000",
        "--bands",
        "64",
        "--distribution",
        "water",
        "--mem-budget",
        "64MiB",
        "--out",
        p(&out),
    ]);
    assert!(run.status.success());
    let stderr = String::from_utf8_lossy(&run.stderr);
    let line = stderr
        .lines()
        .find(|l| l.contains("peak memory"))
        .expect("summary line");
    let peak: u64 = line
        .rsplit_once('(')
        .and_then(|(_, b)| b.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no peak in: {line}"));
    eprintln!("{line}");
    assert!(peak > MIB, "implausible peak {peak}");
    assert!(
        peak <= budget + OVERHEAD,
        "peak {peak} > budget {budget} + overhead {OVERHEAD}"
    );
    let map = littoral::store::MapFile::open(&out).unwrap();
    assert_eq!(map.header().photons, 20_000_000);
}

/// `littoral emit` of the built-in scene (128 bands, 1 M photons, about
/// 1.5 M stored) under 64 MiB, judged by the peak the report records.
#[test]
fn emit_builtin_scene_within_64mib() {
    let dir = tempdir();
    let scene = dir.path().join("coastal.toml");
    std::fs::write(&scene, littoral::scene::COASTAL_TOML).unwrap();
    let report = dir.path().join("r.json");
    let map = dir.path().join("c.map");
    let run = littoral(&[
        "emit",
        p(&scene),
        "--map",
        p(&map),
        "--report",
        p(&report),
        "--photons",
        "1000000",
        "--mem-budget",
        "64MiB",
        "--quiet",
    ]);
    let r: EmitReport = report_of(&run, &report);
    assert_peak_within_64mib("emit", r.peak_memory);
    assert_eq!(r.mem_budget_bytes, 64 * MIB);
}

/// A reduced render of the built-in scene (300 k photons, 64 x 64 pixels,
/// 128 bands) under `--mem-budget 64MiB`: emission, the tile cache and the
/// cube writer all stay inside the budget plus the fixed overhead.
#[test]
fn render_builtin_scene_within_64mib() {
    let dir = tempdir();
    let scene = coarse_builtin_scene(dir.path(), 64, 3.0);
    let out = dir.path().join("out");
    let run = littoral(&[
        "render",
        p(&scene),
        "--out",
        p(&out),
        "--photons",
        "300000",
        "--mem-budget",
        "64MiB",
        "--quiet",
    ]);
    let r: RunReport = report_of(&run, &out.join("coastal.json"));
    assert_peak_within_64mib("render", r.peak_memory);
    assert!(r.cache.peak_resident_bytes <= r.memory.tile_cache_bytes);
}

/// A render whose tile cache keeps evicting and decoding (32 x 32 pixels
/// from a 300 k-photon map under `--mem-budget 28MiB`: about 5.5 MiB of
/// cache for 15 MiB of decoded tiles, beside 17 MiB of the renderer's
/// own, the air view's tables and the aerosol's phase lookups among
/// them) stays inside the budget plus the fixed overhead. Tile
/// buffers freed by eviction go back to the system
/// (`mem::tune_allocator`); with glibc's sliding threshold they
/// fragmented the heap (47 M photons under 256 MiB peaked at 333 MiB
/// anonymous, see benches/README.md).
#[test]
fn render_with_a_churning_cache_within_its_budget() {
    let dir = tempdir();
    let scene = coarse_builtin_scene(dir.path(), 32, 6.0);
    let map = dir.path().join("c.map");
    let out = dir.path().join("out");
    let render = |budget: &str| {
        littoral(&[
            "render",
            p(&scene),
            "--map",
            p(&map),
            "--out",
            p(&out),
            "--photons",
            "300000",
            "--mem-budget",
            budget,
            "--quiet",
        ])
    };
    let _: RunReport = report_of(&render("64MiB"), &out.join("coastal.json"));
    let r: RunReport = report_of(&render("28MiB"), &out.join("coastal.json"));
    assert!(r.reused_map);
    assert!(r.cache.evictions > 50, "{:?}", r.cache);
    let m = |b: u64| b as f64 / MIB as f64;
    eprintln!(
        "churning render: peak anonymous {:.1} MiB, cache {:.1} MiB, {} evictions",
        m(r.peak_memory.anon_bytes),
        m(r.memory.tile_cache_bytes),
        r.cache.evictions
    );
    assert!(
        r.peak_memory.anon_bytes <= 28 * MIB + OVERHEAD,
        "{:?}",
        r.peak_memory
    );
}

/// The stages of a sharded run under `--mem-budget 64MiB`, built-in scene
/// at 1 M photons (64 x 64 pixels): each shard's emission, the merge and
/// each render part, judged by the anonymous peak each records.
#[test]
fn sharded_stages_within_64mib() {
    let dir = tempdir();
    let scene = coarse_builtin_scene(dir.path(), 64, 3.0);
    let map = dir.path().join("m.map");
    let mut parts = Vec::new();
    for i in 0..2 {
        let part = dir.path().join(format!("p{i}.shard"));
        let report = dir.path().join(format!("p{i}.json"));
        let shard = format!("{i}/2");
        let run = littoral(&[
            "emit",
            p(&scene),
            "--shard",
            &shard,
            "--map",
            p(&part),
            "--report",
            p(&report),
            "--photons",
            "1000000",
            "--mem-budget",
            "64MiB",
            "--quiet",
        ]);
        let r: serde_json::Value = report_of(&run, &report);
        let peaks: MemoryPeaks = serde_json::from_value(r["peak_memory"].clone()).unwrap();
        assert_peak_within_64mib(&format!("emit shard {i}"), peaks);
        parts.push(part);
    }
    let report = dir.path().join("merge.json");
    let run = littoral(&[
        "map",
        "merge",
        p(&parts[0]),
        p(&parts[1]),
        "--out",
        p(&map),
        "--report",
        p(&report),
        "--mem-budget",
        "64MiB",
        "--quiet",
    ]);
    let r: EmitReport = report_of(&run, &report);
    assert_peak_within_64mib("merge", r.peak_memory);
    let map_bytes = std::fs::metadata(&map).unwrap().len();
    for i in 0..2 {
        let out = dir.path().join(format!("part{i}"));
        let tiles = format!("{i}/2");
        let run = littoral(&[
            "render",
            p(&scene),
            "--photons",
            "1000000",
            "--map",
            p(&map),
            "--tiles",
            &tiles,
            "--out",
            p(&out),
            "--mem-budget",
            "64MiB",
            "--quiet",
        ]);
        let m: littoral::job::distributed::parts::PartManifest =
            report_of(&run, &out.join("part.json"));
        assert_peak_within_64mib(&format!("render part {i}"), m.peak_memory);
        // A decoded tile's pages leave the resident set: the file pages
        // resident at once (the binary, its libraries and the tiles being
        // decoded) stay below the map's size, which every tile was read from.
        assert!(
            m.peak_memory.file_bytes < map_bytes,
            "render part {i}: {} bytes of file pages resident, the map is {map_bytes}",
            m.peak_memory.file_bytes
        );
    }
}
