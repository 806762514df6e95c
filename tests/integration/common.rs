//! Helpers shared by the integration tests: synthetic maps and brute force.

use glam::Vec3;
use littoral::photon::Photon;
use littoral::progress::Silent;
use littoral::store::codec::TileDecoder;
use littoral::store::{build_map, BuildOptions, MapFile, WriteSummary};
use littoral::synth::{Distribution, SynthSource};
use std::path::{Path, PathBuf};

pub const MIB: u64 = 1 << 20;

/// Build a synthetic map in `dir`.
pub fn synth_map(
    dir: &Path,
    name: &str,
    source: &SynthSource,
    tile_photons: Option<u32>,
    threads: usize,
    budget: u64,
) -> (PathBuf, WriteSummary) {
    let path = dir.join(name);
    let options = BuildOptions {
        threads,
        mem_budget: budget,
        tile_photons,
    };
    let summary = build_map(&path, source, &options, &Silent).expect("build map");
    (path, summary)
}

pub fn source(photons: u64, bands: usize, seed: u64, d: Distribution) -> SynthSource {
    SynthSource::new(photons, bands, seed, d).unwrap()
}

/// Every photon of a map, decoded tile by tile.
pub fn all_photons(map: &MapFile) -> Vec<Photon> {
    let mut dec = TileDecoder::default();
    let mut all = Vec::new();
    let mut tile = Vec::new();
    for t in 0..map.tiles().len() as u32 {
        map.decode_tile(t, &mut dec, &mut tile).unwrap();
        all.extend(tile.iter().map(|p| p.unpack()));
    }
    all
}

/// Squared distance computed the way a k-d tree over f32 points does.
pub fn dist_sq(a: Vec3, b: Vec3) -> f32 {
    let d = a - b;
    d.x * d.x + d.y * d.y + d.z * d.z
}

/// Brute-force squared distances of all photons, ascending.
pub fn brute_sorted(photons: &[Photon], at: Vec3) -> Vec<f32> {
    let mut d: Vec<f32> = photons.iter().map(|p| dist_sq(p.position, at)).collect();
    d.sort_by(f32::total_cmp);
    d
}

/// Temporary directory for a test.
pub fn tempdir() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

/// Run the `littoral` binary.
pub fn littoral(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_littoral"))
        .args(args)
        .output()
        .unwrap()
}

/// A path as a command-line argument.
pub fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// The failure is one line on stderr that mentions `needle`, with exit
/// code 1 (an error, not a signal or a panic).
pub fn assert_clean_failure(out: &std::process::Output, needle: &str) {
    assert_eq!(
        out.status.code(),
        Some(1),
        "exit by error, not by signal or panic"
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    assert!(err.contains(needle), "'{needle}' not in: {err}");
    assert!(!err.contains("panicked"), "{err}");
}

/// The smallest valid scene (`tests/scenes/minimal.toml`): four bands, a
/// constant sun, 10 m of explicit IOPs and no floor. Tests add tables or
/// replace lines.
pub const MINIMAL_SCENE: &str = include_str!("../scenes/minimal.toml");

/// [`MINIMAL_SCENE`] with the TOML `fragment` merged in table by table
/// (`SceneText::merge`), as scene text. Written with inline tables, one
/// line per table, a fragment says only how a test's scene differs.
pub fn minimal_with(fragment: &str) -> String {
    minimal().merge(fragment).unwrap().text()
}

/// [`MINIMAL_SCENE`] as a scene text to change.
pub fn minimal() -> littoral::scene::text::SceneText {
    littoral::scene::text::SceneText::parse(MINIMAL_SCENE).unwrap()
}

/// Render `scene` through the library into `out` on `threads` threads
/// (0 = all) within 256 MiB, with a scratch map; the typed report.
pub fn render_job(
    scene: &littoral::scene::Scene,
    out: &Path,
    threads: usize,
) -> littoral::job::report::RunReport {
    littoral::job::RenderJob {
        scene,
        out_dir: out.to_path_buf(),
        map: None,
        threads,
        budget: littoral::job::MemoryBudget::new(256 * MIB),
        scene_seconds: 0.0,
    }
    .run(&littoral::progress::Silent)
    .unwrap()
}

/// The little-endian float32 values of a cube's data file.
pub fn f32s(path: impl AsRef<Path>) -> Vec<f32> {
    std::fs::read(path)
        .unwrap()
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

/// Whether the client program a test reads littoral's outputs with is
/// installed: `probe` (a command and its arguments) succeeds. Without it
/// the test says what it skipped and passes, so that a plain `cargo test`
/// works on a machine without the clients; with LITTORAL_REQUIRE_CLIENTS
/// set (`tools/test.sh` sets it once it has installed them) it fails.
pub fn client(what: &str, probe: &[&str]) -> bool {
    let found = std::process::Command::new(probe[0])
        .args(&probe[1..])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !found {
        assert!(
            std::env::var_os("LITTORAL_REQUIRE_CLIENTS").is_none(),
            "LITTORAL_REQUIRE_CLIENTS is set but {what} is not installed (tools/test.sh installs it)"
        );
        eprintln!("skipped: {what} is not installed (tools/test.sh installs it)");
    }
    found
}

/// `text` parsed for the path integrator at `spp` samples per pixel (a
/// radiometer traces `spp` x 1024 paths).
pub fn path_scene(text: &str, spp: u32) -> littoral::scene::Scene {
    let o = littoral::scene::Overrides {
        samples_per_pixel: Some(spp),
        integrator: Some(littoral::scene::IntegratorMode::Path),
        ..littoral::scene::Overrides::default()
    };
    littoral::scene::Scene::parse(text, Path::new("path.toml"), &o).unwrap()
}

/// The photon map's radiometer readings `pm` against the path
/// integrator's `path` in a scene of bands `nm`: every band within 3
/// sigma plus 2 %, and the mean over the bands in `window` (nm) within 3
/// sigma plus 1 % (its sigma the plain mean of the bands' errors, which
/// are not independent). What fails, each line led by `label`; both are
/// printed.
pub fn photon_map_against_path(
    label: &str,
    pm: &[littoral::render::RadiometerReading],
    path: &[littoral::render::RadiometerReading],
    nm: &[f32],
    window: (f32, f32),
) -> Vec<String> {
    let within: Vec<usize> = (0..nm.len())
        .filter(|&b| (window.0..=window.1).contains(&nm[b]))
        .collect();
    let mut failures = Vec::new();
    for (a, b) in pm.iter().zip(path) {
        for (i, w) in nm.iter().enumerate() {
            let sigma = a.stderr[i].hypot(b.stderr[i]);
            eprintln!(
                "{label}, {} m, {w:.0} nm: photon map {:.4e} +- {:.1e}, path {:.4e} +- {:.1e} ({:+.1} %)",
                a.depth_m,
                a.L[i],
                a.stderr[i],
                b.L[i],
                b.stderr[i],
                (a.L[i] / b.L[i] - 1.0) * 100.0
            );
            if (a.L[i] - b.L[i]).abs() > 3.0 * sigma + 0.02 * b.L[i] {
                failures.push(format!("{label}, {} m, band {i}", a.depth_m));
            }
        }
        let mean = |v: &[f64]| within.iter().map(|&i| v[i]).sum::<f64>() / within.len() as f64;
        let (m_a, m_b) = (mean(&a.L), mean(&b.L));
        let sigma = mean(&a.stderr).hypot(mean(&b.stderr));
        let span = format!("{:.0}-{:.0} nm", window.0, window.1);
        eprintln!(
            "{label}, {} m, {span}: {:+.2} % +- {:.2} %",
            a.depth_m,
            (m_a / m_b - 1.0) * 100.0,
            sigma / m_b * 100.0
        );
        if (m_a - m_b).abs() > 3.0 * sigma + 0.01 * m_b {
            failures.push(format!(
                "{label}, {} m, {span}: {m_a:.4e} against {m_b:.4e} +- {sigma:.1e}",
                a.depth_m
            ));
        }
    }
    failures
}
