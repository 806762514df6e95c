//! The render and emit jobs through the library API: map reuse decided by
//! the provenance recorded in the map (both directions), and the typed
//! report, which is exactly what the JSON file holds.

use crate::common::*;
use littoral::job::report::RunReport;
use littoral::job::{EmitJob, MemoryBudget, RenderJob};
use littoral::progress::Silent;
use littoral::scene::{Overrides, Scene};
use littoral::store::{MapFile, PhotonMap};
use std::path::{Path, PathBuf};

/// A small shallow scene whose floor reflectance is a CSV file beside it.
fn scene_text(estimate: &str, extra: &str) -> String {
    let base = MINIMAL_SCENE
        .replace("start_nm = 400.0", "start_nm = 450.0")
        .replace("end_nm = 700.0", "end_nm = 550.0")
        .replace("bands = 4", "bands = 3")
        .replace("count = 1000", "count = 20000")
        .replace("a = 0.1, b = 0.2", "a = 0.2, b = 0.4");
    format!(
        r#"name = "reuse"
{base}
[bottom]
depth_m = 3.0
reflectance = "floor.csv"
[tally]
depths_m = [0.0, 1.0]
[sensor]
pixels = [4, 4]
gsd_m = 2.0
[[radiometer]]
depth_m = 1.0
[estimate]
{estimate}
{extra}
"#
    )
}

const FLOOR_CSV: &str = "nm,reflectance\n400,0.2\n600,0.3\n";

struct Setup {
    dir: tempfile::TempDir,
}

impl Setup {
    fn new() -> Setup {
        let dir = tempdir();
        std::fs::write(dir.path().join("floor.csv"), FLOOR_CSV).unwrap();
        Setup { dir }
    }

    fn scene(&self, text: &str) -> Scene {
        let path = self.dir.path().join("scene.toml");
        std::fs::write(&path, text).unwrap();
        Scene::load(&path, &Overrides::default()).unwrap()
    }

    fn map(&self) -> PathBuf {
        self.dir.path().join("kept.map")
    }

    /// Emit `scene` into the map, on one thread.
    fn emit(&self, scene: &Scene) -> littoral::job::report::EmitReport {
        EmitJob {
            scene,
            map: self.map(),
            report: None,
            threads: 1,
            budget: MemoryBudget::new(64 * MIB),
            scene_seconds: 0.0,
        }
        .run(&Silent)
        .unwrap()
    }

    fn render(&self, scene: &Scene) -> RunReport {
        RenderJob {
            scene,
            out_dir: self.dir.path().join("out"),
            map: Some(self.map()),
            threads: 2,
            budget: MemoryBudget::new(64 * MIB),
            scene_seconds: 0.0,
        }
        .run(&Silent)
        .unwrap()
    }
}

fn digest(path: &Path) -> [u8; 32] {
    MapFile::open(path).unwrap().header().provenance.digest
}

/// Editing the estimate, the sensor or the radiometers reuses the map;
/// spelling a default out reuses it too (provenance is taken after
/// defaults are applied).
#[test]
fn render_settings_never_re_emit() {
    let s = Setup::new();
    let first = s.render(&s.scene(&scene_text("k = 50", "")));
    assert!(!first.reused_map);
    let bytes = std::fs::read(s.map()).unwrap();
    let d = digest(&s.map());
    assert_eq!(first.map.as_ref().unwrap().provenance.len(), 64);

    let changes = [
        scene_text("k = 80\nk_expanded = 400\nspectral = \"naive\"", ""),
        scene_text("k = 50", "").replace("pixels = [4, 4]", "pixels = [2, 3]"),
        scene_text("k = 50", "").replace(
            "[[radiometer]]\ndepth_m = 1.0",
            "[[radiometer]]\ndepth_m = 2.0\nview = \"zenith\"",
        ),
        scene_text(
            "k = 50",
            "[surface]\nrefractive_index = 1.34\nkind = \"flat\"",
        ),
    ];
    for (i, text) in changes.iter().enumerate() {
        let r = s.render(&s.scene(text));
        assert!(r.reused_map, "change {i} re-emitted");
        assert_eq!(std::fs::read(s.map()).unwrap(), bytes, "change {i}");
        // The reused report carries the emission exactly as recorded.
        assert_eq!(r.emission, first.emission, "change {i}");
        assert_eq!(
            r.map.as_ref().unwrap().provenance,
            first.map.as_ref().unwrap().provenance
        );
    }
    assert_eq!(digest(&s.map()), d);
}

/// Editing a file the scene names, or an emission key, or overriding the
/// photon count, always re-emits, and the new map records a new digest.
#[test]
fn emission_inputs_always_re_emit() {
    let s = Setup::new();
    let text = scene_text("k = 50", "");
    let first = s.render(&s.scene(&text));
    assert!(!first.reused_map);
    let d0 = digest(&s.map());

    // The floor CSV changes by one value.
    std::fs::write(
        s.dir.path().join("floor.csv"),
        FLOOR_CSV.replace("0.3", "0.31"),
    )
    .unwrap();
    let r = s.render(&s.scene(&text));
    assert!(!r.reused_map, "an edited CSV was not noticed");
    let d1 = digest(&s.map());
    assert_ne!(d1, d0);
    // A comment in the CSV changes its bytes but no value: still re-emitted.
    std::fs::write(
        s.dir.path().join("floor.csv"),
        format!("# measured 2026\n{}", FLOOR_CSV.replace("0.3", "0.31")),
    )
    .unwrap();
    let r = s.render(&s.scene(&text));
    assert!(!r.reused_map);
    let d2 = digest(&s.map());
    assert_ne!(d2, d1);
    // Unchanged now: reused.
    assert!(s.render(&s.scene(&text)).reused_map);

    // An emission key (the sun), and the seed.
    let r = s.render(&s.scene(&text.replace("zenith_deg = 30.0", "zenith_deg = 31.0")));
    assert!(!r.reused_map);
    let r = s.render(&s.scene(&format!("seed = 5\n{text}")));
    assert!(!r.reused_map);
    // The photon count, through an override.
    let path = s.dir.path().join("scene.toml");
    let o = Overrides {
        photons: Some(21_000),
        ..Overrides::default()
    };
    let more = Scene::load(&path, &o).unwrap();
    let r = s.render(&more);
    assert!(!r.reused_map);
    assert_eq!(r.emission.as_ref().unwrap().photons.traced, 21_000);
    let info = MapFile::open(s.map()).unwrap().info();
    assert_eq!(info.provenance["photons"], 21_000);
    assert_eq!(
        info.provenance["digest"],
        r.map.as_ref().unwrap().provenance
    );
}

/// A map made by `EmitJob` is reused by a render of the same scene; its
/// report equals the emit report's physics.
#[test]
fn emit_job_then_render_reuses() {
    let s = Setup::new();
    let scene = s.scene(&scene_text("k = 50", ""));
    let emitted = s.emit(&scene);
    assert_eq!(emitted.map.path.as_deref(), s.map().to_str());
    let r = s.render(&scene);
    assert!(r.reused_map);
    assert_eq!(r.emission.as_ref(), Some(&emitted.emission));
    assert_eq!(r.map.as_ref().unwrap().provenance, emitted.map.provenance);
    assert_eq!(r.map.as_ref().unwrap().photons, emitted.map.photons);
}

/// The JSON report is the typed report: it parses back into `RunReport`
/// and equals what the job returned; its shares add up to the budget; the
/// radiometers read alone from the kept map equal the render's.
#[test]
fn typed_report_round_trips() {
    let s = Setup::new();
    let scene = s.scene(&scene_text("k = 50", ""));
    let r = s.render(&scene);
    // Radiometers alone, from the kept map, read what the render reported.
    let map = PhotonMap::new(MapFile::open(s.map()).unwrap(), 64 * MIB).unwrap();
    assert_eq!(
        littoral::render::radiometers(&scene, &map).unwrap(),
        r.radiometers
    );
    let text = std::fs::read_to_string(&r.outputs.json).unwrap();
    let back: RunReport = serde_json::from_str(&text).unwrap();
    assert_eq!(back, r);
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    // The emission report's keys sit at the top level, as before.
    for key in [
        "tally",
        "energy",
        "photons",
        "above_surface",
        "radiometers",
        "cache",
    ] {
        assert!(v.get(key).is_some(), "{key}");
    }
    assert_eq!(r.radiometers.len(), 1);
    // Ed_above_surface is the exact E_d(0+) (the sun's horizontal
    // irradiance plus the sky's), the one the R_rs cube divides by; the
    // emission's tally of it, noisy, is `above_surface.Ed`.
    let exact: Vec<f64> = (0..3).map(|b| scene.incident_irradiance(b)).collect();
    assert_eq!(r.Ed_above_surface, exact);
    assert_ne!(
        r.Ed_above_surface,
        r.emission.as_ref().unwrap().above_surface.Ed
    );
    let cube = |product: &str| {
        let f = r
            .outputs
            .products
            .iter()
            .find(|p| p.product == product)
            .unwrap();
        littoral::cube::EnviCube::open(Path::new(&f.hdr)).unwrap()
    };
    let (lw, rrs) = (cube("lw"), cube("rrs"));
    for (b, ed) in exact.iter().enumerate() {
        for (l, q) in lw.band(b).unwrap().iter().zip(rrs.band(b).unwrap().iter()) {
            // The README's recipe, R_rs = L_w / Ed_above_surface, to float rounding.
            assert!((*l as f64 / ed - *q as f64).abs() <= 1e-6 * (*q as f64).abs() + 1e-12);
        }
    }
    let m = r.memory;
    assert_eq!(
        m.reserve_bytes + m.boundary_grid_bytes + m.band_shape_grid_bytes + m.tile_cache_bytes,
        64 * MIB
    );
    assert!(r.cache.peak_resident_bytes <= m.tile_cache_bytes);
    // The default spectral mode builds the band-shape grid, charged to the budget.
    assert!(m.band_shape_grid_bytes > 0);
    for f in [
        &r.outputs.hdr,
        &r.outputs.bsq,
        &r.outputs.png,
        &r.outputs.exr,
    ] {
        assert!(Path::new(f).is_file(), "{f}");
    }
}

/// Every number an emission report and a render report hold (photon map
/// and path integrator, the latter with an atmosphere) has its unit in the report's `units`, keyed by the
/// field's path (`[]` for an element of a list of records).
#[test]
fn every_number_in_a_report_has_a_unit() {
    fn numeric_paths(v: &serde_json::Value, path: &str, out: &mut Vec<String>) {
        let join = |k: &str| {
            if path.is_empty() {
                k.to_string()
            } else {
                format!("{path}.{k}")
            }
        };
        match v {
            serde_json::Value::Object(m) => {
                for (k, x) in m {
                    if k != "units" {
                        numeric_paths(x, &join(k), out);
                    }
                }
            }
            // An empty array (no warnings) holds no number.
            serde_json::Value::Array(a)
                if !a.is_empty() && a.iter().all(|x| x.is_number() || x.is_null()) =>
            {
                out.push(path.to_string())
            }
            serde_json::Value::Array(a) => {
                for x in a {
                    numeric_paths(x, &format!("{path}[]"), out);
                }
            }
            serde_json::Value::Number(_) | serde_json::Value::Null => out.push(path.to_string()),
            _ => {}
        }
    }
    let s = Setup::new();
    let scene = s.scene(&scene_text("k = 50", ""));
    let emitted = s.emit(&scene);
    let photon_map = s.render(&scene);
    // The path integrator's scene has an atmosphere, so that its block's
    // numbers are checked too.
    let air = "[render]\nintegrator = \"path\"\n[atmosphere]\nsky_photons = 1000";
    let path = s
        .scene(&scene_text("", air).replace("irradiance = 1.0", "spectrum = \"extraterrestrial\""));
    let traced = render_job(&path, &s.dir.path().join("path"), 0);
    let reports = [
        serde_json::to_value(&emitted).unwrap(),
        serde_json::to_value(&photon_map).unwrap(),
        serde_json::to_value(&traced).unwrap(),
    ];
    for report in &reports {
        let units = report["units"].as_object().unwrap();
        let mut paths = Vec::new();
        numeric_paths(report, "", &mut paths);
        assert!(paths.len() > 30, "{paths:?}");
        for p in paths {
            assert!(units.contains_key(&p), "no unit for {p}");
        }
    }
}

/// Asks a run to stop once `after` units of any stage are done.
struct CancelAfter {
    after: u64,
    done: std::sync::atomic::AtomicU64,
}

impl littoral::progress::Progress for CancelAfter {
    fn stage(&self, _: &str, _: u64) {}
    fn advance(&self, n: u64) {
        self.done.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
    }
    fn finish(&self) {}
    fn cancelled(&self) -> bool {
        self.done.load(std::sync::atomic::Ordering::Relaxed) >= self.after
    }
}

/// A run its caller cancels (`Progress::cancelled`, what Ctrl-C does in
/// Python) stops with `Error::Cancelled` and leaves nothing behind: while
/// tracing photons into a kept map, while encoding its tiles, and while
/// rendering. The kept map and the output directory hold no file, and a
/// map that was already there is left as it was.
#[test]
fn a_cancelled_run_stops_and_leaves_nothing() {
    let s = Setup::new();
    let scene = s.scene(&scene_text("k = 50", ""));
    let files = |dir: &Path| -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .map(|d| {
                d.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                    .collect()
            })
            .unwrap_or_default();
        v.sort();
        v
    };
    let before = files(s.dir.path());
    // 20 000 photons: tracing reports them in batches, the tiles after.
    for after in [1, 20_001] {
        let e = EmitJob {
            scene: &scene,
            map: s.map(),
            report: None,
            threads: 2,
            budget: MemoryBudget::new(64 * MIB),
            scene_seconds: 0.0,
        }
        .run(&CancelAfter {
            after,
            done: 0.into(),
        })
        .unwrap_err();
        assert!(matches!(e, littoral::Error::Cancelled), "{e}");
        assert_eq!(files(s.dir.path()), before, "after {after}");
    }
    let out = s.dir.path().join("out");
    // A render cancelled after `after` units, keeping its map at `map`.
    let cancelled_render = |map: Option<PathBuf>, after: u64| {
        let e = RenderJob {
            scene: &scene,
            out_dir: out.clone(),
            map,
            threads: 2,
            budget: MemoryBudget::new(64 * MIB),
            scene_seconds: 0.0,
        }
        .run(&CancelAfter {
            after,
            done: 0.into(),
        })
        .unwrap_err();
        assert!(matches!(e, littoral::Error::Cancelled), "{e}");
    };
    cancelled_render(None, 20_000 + 1);
    assert_eq!(files(&out), Vec::<String>::new());
    // A kept map is not touched by a render cancelled while it reads it
    // (the scene's one image tile).
    s.emit(&scene);
    let kept = digest(&s.map());
    cancelled_render(Some(s.map()), 0);
    assert_eq!(digest(&s.map()), kept);
    assert_eq!(files(&out), Vec::<String>::new());
}
