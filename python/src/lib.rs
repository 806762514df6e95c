//! `littoral._littoral`: the Python bindings' native module, a thin layer
//! over `littoral::job` and `littoral::scene`. Everything a user calls is
//! in the pure-Python package beside it (`python/littoral`), which turns
//! what this module returns (TOML text, JSON reports, output directories)
//! into `Scene` objects and xarray Datasets.
//!
//! - Scenes travel as TOML text plus the path that names them in errors
//!   and anchors their relative file names; validation is
//!   `littoral::scene::Scene::parse`, edits `littoral::scene::text::SceneText`.
//! - Runs ([`render`], [`emit`]) go on a worker thread without the GIL.
//!   The calling thread wakes every 100 ms, with the GIL, to run Python's
//!   signal handlers (Ctrl-C) and the progress callback; a
//!   `KeyboardInterrupt` (or an exception from the callback) cancels the
//!   run through `Progress::cancelled`, the job's staging directory and
//!   scratch map are removed as it unwinds, and the exception is raised.
//! - Errors become `LittoralError` (and `SceneError` for scene faults,
//!   with `path`, `line` and `key`), with the messages the CLI prints.

use littoral::cube::ops::Resampler;
use littoral::job::{EmitJob, MemoryBudget, RenderJob};
use littoral::progress::Progress;
use littoral::scene::text::SceneText;
use littoral::scene::{Overrides, Scene};
use littoral::spectral::response::SpectralResponse;
use littoral::spectral::BandGrid;
use littoral::Error;
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::Duration;

create_exception!(
    littoral,
    LittoralError,
    PyException,
    "An error from littoral, with the message its command line prints."
);
create_exception!(
    littoral,
    SceneError,
    LittoralError,
    "A scene that cannot be used: `key` names the scene key (dotted), `path` and `line` where it is when known."
);

/// The Python exception for a littoral error.
fn to_py(py: Python<'_>, e: Error) -> PyErr {
    let message = e.to_string();
    let (err, path, line, key) = match &e {
        Error::Scene {
            path, line, key, ..
        } => (
            SceneError::new_err(message),
            Some(path.display().to_string()),
            Some(*line),
            Some(key.clone()),
        ),
        Error::Data {
            path, line, field, ..
        } => (
            SceneError::new_err(message),
            Some(path.display().to_string()),
            *line,
            Some(field.clone()),
        ),
        Error::Invalid { field, .. } => (
            SceneError::new_err(message),
            None,
            None,
            Some(field.clone()),
        ),
        _ => (LittoralError::new_err(message), None, None, None),
    };
    let value = err.value(py);
    // Best effort: an attribute that cannot be set leaves the message.
    let _ = value.setattr("path", path);
    let _ = value.setattr("line", line);
    let _ = value.setattr("key", key);
    err
}

/// The overrides a call passes, from their JSON (`{"photons": 1000,
/// "integrator": "path", ...}`, names as on the command line).
fn overrides(py: Python<'_>, json: &str) -> PyResult<Overrides> {
    serde_json::from_str(json)
        .map_err(|e| to_py(py, Error::invalid("overrides", format!("{e} (in {json})"))))
}

/// The built-in coastal scene's TOML text, comments and all.
#[pyfunction]
fn scene_default_text() -> &'static str {
    littoral::scene::COASTAL_TOML
}

/// `text` with the dotted `key` set to the JSON value `value` (tables on
/// the way made as needed); the TOML comes back with each table's keys
/// sorted and no comments.
#[pyfunction]
fn scene_set(py: Python<'_>, text: &str, key: &str, value: &str) -> PyResult<String> {
    let value: toml::Value = serde_json::from_str(value).map_err(|e| {
        to_py(
            py,
            Error::invalid(key, format!("not a value a scene can hold: {e}")),
        )
    })?;
    let scene = SceneText::parse(text).map_err(|e| to_py(py, e))?;
    Ok(scene.set(key, value).text())
}

/// `text` without the dotted `key`.
#[pyfunction]
fn scene_remove(py: Python<'_>, text: &str, key: &str) -> PyResult<String> {
    let scene = SceneText::parse(text).map_err(|e| to_py(py, e))?;
    Ok(scene.remove(key).text())
}

/// The value at the dotted `key` of `text` as JSON, or `None`.
#[pyfunction]
fn scene_get(py: Python<'_>, text: &str, key: &str) -> PyResult<Option<String>> {
    let scene = SceneText::parse(text).map_err(|e| to_py(py, e))?;
    Ok(scene
        .get(key)
        .map(|v| serde_json::to_string(v).expect("a TOML value is JSON")))
}

/// The scene text as a JSON object.
#[pyfunction]
fn scene_to_json(py: Python<'_>, text: &str) -> PyResult<String> {
    let table: toml::Table = text
        .parse()
        .map_err(|e: toml::de::Error| to_py(py, Error::invalid("scene text", e.message())))?;
    Ok(serde_json::to_string(&table).expect("a TOML table is JSON"))
}

/// The JSON object `json` as scene TOML text.
#[pyfunction]
fn scene_from_json(py: Python<'_>, json: &str) -> PyResult<String> {
    let table: toml::Table = serde_json::from_str(json).map_err(|e| {
        to_py(
            py,
            Error::invalid("scene", format!("not a table a scene can be: {e}")),
        )
    })?;
    toml::to_string(&table).map_err(|e| to_py(py, Error::invalid("scene", e.to_string())))
}

/// Validate the scene `text` (named `origin`, which anchors its relative
/// file names) with `overrides`; its one-line summary, or `SceneError`.
#[pyfunction]
fn scene_check(py: Python<'_>, text: &str, origin: PathBuf, overrides: &str) -> PyResult<String> {
    let o = self::overrides(py, overrides)?;
    let scene = py
        .detach(|| Scene::parse(text, &origin, &o))
        .map_err(|e| to_py(py, e))?;
    Ok(scene.summary())
}

/// The scene's band centres and FWHM (nm), after `overrides`.
#[pyfunction]
fn scene_bands(
    py: Python<'_>,
    text: &str,
    origin: PathBuf,
    overrides: &str,
) -> PyResult<(Vec<f64>, Vec<f64>)> {
    let o = self::overrides(py, overrides)?;
    let scene = py
        .detach(|| Scene::parse(text, &origin, &o))
        .map_err(|e| to_py(py, e))?;
    let centres: Vec<f64> = scene.bands.centers_nm().iter().map(|&c| c as f64).collect();
    let fwhm: Vec<f64> = scene.bands.fwhm_nm().iter().map(|&c| c as f64).collect();
    Ok((centres, fwhm))
}

/// What the worker thread reports and the Python thread reads: every
/// stage begun (so that one begun and ended between two polls is still
/// reported) and the units done in the latest.
struct Shared {
    stages: Mutex<Vec<(String, u64)>>,
    done: AtomicU64,
    cancelled: AtomicBool,
}

impl Progress for Shared {
    fn stage(&self, name: &str, total: u64) {
        let mut stages = self.stages.lock().unwrap_or_else(|e| e.into_inner());
        self.done.store(0, Ordering::Relaxed);
        stages.push((name.to_string(), total));
    }
    fn advance(&self, n: u64) {
        self.done.fetch_add(n, Ordering::Relaxed);
    }
    fn finish(&self) {}
    fn cancelled(&self) -> bool {
        self.cancelled.load(Ordering::Relaxed)
    }
}

/// Run `work` on a worker thread without the GIL, polling Python's
/// signals and calling `callback(stage, done, total)` every 100 ms.
fn run_detached<T: Send>(
    py: Python<'_>,
    callback: Option<Py<PyAny>>,
    work: impl FnOnce(&dyn Progress) -> littoral::Result<T> + Send,
) -> PyResult<T> {
    let shared = Shared {
        stages: Mutex::new(Vec::new()),
        done: AtomicU64::new(0),
        cancelled: AtomicBool::new(false),
    };
    let mut raised: Option<PyErr> = None;
    // Stages before this index were reported as complete.
    let mut reported = 0;
    let result = std::thread::scope(|s| {
        let worker = s.spawn(|| work(&shared));
        loop {
            let finished = py.detach(|| {
                for _ in 0..10 {
                    if worker.is_finished() {
                        return true;
                    }
                    std::thread::sleep(Duration::from_millis(10));
                }
                worker.is_finished()
            });
            if raised.is_none() {
                let mut step = py.check_signals();
                if step.is_ok() {
                    if let Some(cb) = &callback {
                        let (stages, done) = {
                            let s = shared.stages.lock().unwrap_or_else(|e| e.into_inner());
                            (s.clone(), shared.done.load(Ordering::Relaxed))
                        };
                        let last = stages.len().saturating_sub(1);
                        for (i, (name, total)) in stages.iter().enumerate().skip(reported) {
                            // A stage that ended since the last poll, as
                            // complete; the latest as it stands.
                            let now = if i < last {
                                (name.as_str(), *total, *total, false)
                            } else {
                                (name.as_str(), done, *total, finished)
                            };
                            step = step.and_then(|()| cb.call1(py, now).map(|_| ()));
                        }
                        reported = last;
                    }
                }
                if let Err(e) = step {
                    shared.cancelled.store(true, Ordering::Relaxed);
                    raised = Some(e);
                }
            }
            if finished {
                break;
            }
        }
        worker.join()
    });
    let result = match result {
        Ok(r) => r,
        Err(_) => return Err(LittoralError::new_err("the run's worker thread panicked")),
    };
    match (result, raised) {
        (_, Some(e)) => Err(e),
        (r, None) => r.map_err(|e| to_py(py, e)),
    }
}

/// Render the scene `text` into `out_dir` (the CLI's `littoral render`):
/// the JSON report (`littoral::job::report::RunReport`).
#[pyfunction]
#[pyo3(signature = (text, origin, out_dir, overrides, mem_budget, threads, map=None, progress=None))]
#[allow(clippy::too_many_arguments)]
fn render(
    py: Python<'_>,
    text: &str,
    origin: PathBuf,
    out_dir: PathBuf,
    overrides: &str,
    mem_budget: &str,
    threads: usize,
    map: Option<PathBuf>,
    progress: Option<Py<PyAny>>,
) -> PyResult<String> {
    let (scene, budget, scene_seconds) =
        run_inputs(py, text, &origin, overrides, mem_budget, threads)?;
    let report = run_detached(py, progress, |p| {
        RenderJob {
            scene: &scene,
            out_dir: out_dir.clone(),
            map: map.clone(),
            threads,
            budget,
            scene_seconds,
        }
        .run(p)
    })?;
    Ok(serde_json::to_string(&report).expect("the report serialises"))
}

/// Trace the scene's photons into the map file `map` (the CLI's `littoral
/// emit`): the JSON emission report, also written to `report` if given.
#[pyfunction]
#[pyo3(signature = (text, origin, map, overrides, mem_budget, threads, report=None, progress=None))]
#[allow(clippy::too_many_arguments)]
fn emit(
    py: Python<'_>,
    text: &str,
    origin: PathBuf,
    map: PathBuf,
    overrides: &str,
    mem_budget: &str,
    threads: usize,
    report: Option<PathBuf>,
    progress: Option<Py<PyAny>>,
) -> PyResult<String> {
    let (scene, budget, scene_seconds) =
        run_inputs(py, text, &origin, overrides, mem_budget, threads)?;
    let r = run_detached(py, progress, |p| {
        EmitJob {
            scene: &scene,
            map: map.clone(),
            report: report.clone(),
            threads,
            budget,
            scene_seconds,
        }
        .run(p)
    })?;
    Ok(r.json())
}

/// What a run needs before it starts, checked as the command line checks
/// it: the scene (parsed without the GIL) with its overrides, the memory
/// budget, `threads` within the machine's cap, and the seconds the scene
/// took to load.
fn run_inputs(
    py: Python<'_>,
    text: &str,
    origin: &std::path::Path,
    overrides: &str,
    mem_budget: &str,
    threads: usize,
) -> PyResult<(Scene, MemoryBudget, f64)> {
    let o = self::overrides(py, overrides)?;
    let budget = MemoryBudget::parse("mem_budget", mem_budget).map_err(|e| to_py(py, e))?;
    check_threads(py, threads)?;
    let started = std::time::Instant::now();
    let scene = py
        .detach(|| Scene::parse(text, origin, &o))
        .map_err(|e| to_py(py, e))?;
    Ok((scene, budget, started.elapsed().as_secs_f64()))
}

/// `threads` within the machine's cap, as `--threads` checks it.
fn check_threads(py: Python<'_>, threads: usize) -> PyResult<()> {
    match littoral::parallel::too_many_threads(threads) {
        Some(what) => Err(to_py(py, Error::invalid("threads", what))),
        None => Ok(()),
    }
}

/// The names of the sensors `resample` knows (besides `csv:FILE`).
#[pyfunction]
fn sensor_names() -> Vec<&'static str> {
    SpectralResponse::names()
}

/// How sensor `name`'s bands are made from a cube with band centres
/// `centres` and widths `fwhm` (nm), as `littoral-cube resample` makes
/// them (`littoral::cube::ops::Resampler`): the bands made, by wavelength,
/// as (names, centres nm, FWHM nm) and a row-major matrix of weights,
/// sensor bands x cube bands.
#[pyfunction]
#[allow(clippy::type_complexity)]
fn sensor_weights(
    py: Python<'_>,
    name: &str,
    centres: Vec<f32>,
    fwhm: Vec<f32>,
) -> PyResult<(Vec<String>, Vec<f64>, Vec<f64>, Vec<f64>)> {
    let made = (|| {
        let sensor = SpectralResponse::named(name)?;
        let grid = BandGrid::explicit(centres.clone(), fwhm)?;
        let r = Resampler::new(&grid, &sensor, std::path::Path::new("dataset"))?;
        Ok::<_, Error>((sensor, r))
    })()
    .map_err(|e| to_py(py, e))?;
    let (sensor, r) = made;
    let n = centres.len();
    let mut matrix = vec![0.0; r.made.len() * n];
    for (row, m) in r.made.iter().enumerate() {
        for &(b, w) in &m.weights {
            matrix[row * n + b] = w;
        }
    }
    let bands = || r.made.iter().map(|m| &sensor.bands[m.band]);
    Ok((
        r.names.clone(),
        bands().map(|b| b.centre_nm).collect(),
        bands().map(|b| b.fwhm_nm).collect(),
        matrix,
    ))
}

/// The version of littoral this module was built from.
#[pyfunction]
fn version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

#[pymodule]
fn _littoral(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("LittoralError", py.get_type::<LittoralError>())?;
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add_function(wrap_pyfunction!(scene_default_text, m)?)?;
    m.add_function(wrap_pyfunction!(scene_set, m)?)?;
    m.add_function(wrap_pyfunction!(scene_remove, m)?)?;
    m.add_function(wrap_pyfunction!(scene_get, m)?)?;
    m.add_function(wrap_pyfunction!(scene_to_json, m)?)?;
    m.add_function(wrap_pyfunction!(scene_from_json, m)?)?;
    m.add_function(wrap_pyfunction!(scene_check, m)?)?;
    m.add_function(wrap_pyfunction!(scene_bands, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(emit, m)?)?;
    m.add_function(wrap_pyfunction!(sensor_names, m)?)?;
    m.add_function(wrap_pyfunction!(sensor_weights, m)?)?;
    m.add_function(wrap_pyfunction!(version, m)?)?;
    Ok(())
}
