//! The jobs, as a library: what `littoral emit` and `littoral render` do,
//! callable from tests and tools without a process.
//!
//! - [`EmitJob`]: a scene's photons into a map file, with the emission
//!   report ([`report::EmitReport`]).
//! - [`RenderJob`]: scene → photon map (reused when its provenance matches,
//!   else emitted) → render → outputs (ENVI cube, spectral EXR, quicklook,
//!   JSON report), returning the typed [`report::RunReport`].
//! - [`budget::MemoryBudget`]: one `--mem-budget` shared out between the
//!   sort writer, the tile cache, the boundary grid and a reserve.
//! - [`outputs`]: the render's files, staged and published as one set
//!   (`output::set`); [`html`] the page, [`report`] and [`units`] the JSON.
//! - [`distributed`]: emission in shards and their merge, a render in parts
//!   and their assembly, and the Slurm plan that chains them.
//!
//! **Map reuse.** A map records the SHA-256 of exactly the emission inputs
//! of the scene it was traced from (`Scene::emission_inputs`, plus the map
//! format version) and the emission report. `RenderJob` with a `map` path
//! reuses the file there when, and only when, its digest equals the
//! scene's; otherwise (no file, another scene, a corrupt or older map, a
//! report that does not parse) it emits again and replaces the file. Edits
//! to `[estimate]`, `[sensor]` or `[[radiometer]]` therefore never re-emit,
//! and edits to any file the scene names always do.
//!
//! Not for: argument parsing, progress bars or exit codes (`main`).

pub mod budget;
pub mod distributed;
pub mod html;
pub mod outputs;
pub mod report;
pub mod units;

use crate::emit::report::EmissionReport;
use crate::error::{Error, Result};
use crate::output::set::{RunLock, Staging};
use crate::progress::Progress;
use crate::provenance::Provenance;
use crate::scene::{IntegratorMode, Scene};
use crate::store::{MapFile, PhotonMap};
pub use budget::{MemoryBudget, RenderShares};
use report::{EmitReport, EmitTimings, MapSummary, RenderTimings, RunReport};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Trace a scene's photons into a map file.
pub struct EmitJob<'a> {
    pub scene: &'a Scene,
    /// The map to write (under a temporary name until complete).
    pub map: PathBuf,
    /// Where to write the JSON report too (after the map, under the map's
    /// lock, so that two runs cannot leave one's map beside the other's
    /// report).
    pub report: Option<PathBuf>,
    /// Worker threads (0 = one per core); the map is identical for any number.
    pub threads: usize,
    pub budget: MemoryBudget,
    /// Seconds spent loading the scene, for the report.
    pub scene_seconds: f64,
}

impl EmitJob<'_> {
    pub fn run(&self, progress: &dyn Progress) -> Result<EmitReport> {
        let start = Instant::now();
        crate::mem::tune_allocator();
        let _lock = prepare_map_outputs(self.scene, &self.map, self.report.as_deref(), true)?;
        let swept = crate::output::set::sweep_stale(crate::output::parent_dir(&self.map));
        // The report's file is made now, so that an unwritable path fails
        // before the photons are traced rather than after.
        let report_file = crate::output::LateFile::create(self.report.as_deref())?;
        let sampler = crate::mem::PeakSampler::start();
        let provenance = crate::emit::emission_provenance(self.scene)?;
        let em = crate::emit::emit(
            self.scene,
            &provenance,
            &self.map,
            &self.budget.emission(self.threads),
            progress,
        )?;
        let emit_s = start.elapsed().as_secs_f64();
        let peaks = sampler.finish();
        let report = EmitReport {
            emission: em.report,
            map: MapSummary::written(&em.map, provenance.digest_hex(), Some(&self.map)),
            atmosphere: report::AtmosphereReport::of(self.scene),
            timings_s: EmitTimings {
                scene: self.scene_seconds,
                emit_and_store: emit_s,
                total: self.scene_seconds + emit_s,
            },
            peak_memory: peaks,
            mem_budget_bytes: self.budget.total(),
            peak_rss_bytes: peaks.rss_bytes,
            units: units::report_units(),
            warnings: crate::output::set::sweep_warning(&swept)
                .into_iter()
                .collect(),
        };
        report_file.write(&report.json())?;
        Ok(report)
    }
}

/// Before a run writes the map (or shard) file `map` and its JSON report
/// `report`: refuse names that are links or special files, a `map` that
/// holds something other than a littoral map (`is_map`), and outputs that
/// are the scene file or each other; then take the map's lock for
/// writing (another run writing or reading it fails at once).
pub fn prepare_map_outputs(
    scene: &Scene,
    map: &Path,
    report: Option<&Path>,
    is_map: bool,
) -> Result<RunLock> {
    use crate::output::set;
    if is_map {
        check_map_target(map)?;
    } else {
        set::check_target(map)?;
    }
    set::refuse_input(map, "--map", &scene.origin.path, "scene file")?;
    if let Some(r) = report {
        set::check_target(r)?;
        set::refuse_input(r, "--report", &scene.origin.path, "scene file")?;
        set::refuse_input(r, "--report", map, "map (--map)")?;
    }
    RunLock::exclusive(map)
}

/// Render a scene: photon map (reused or emitted), cube, quicklook, EXR and
/// the JSON report, all in `out_dir`.
pub struct RenderJob<'a> {
    pub scene: &'a Scene,
    pub out_dir: PathBuf,
    /// Keep the photon map here, and reuse the one there when its
    /// provenance matches the scene; `None` traces into a scratch file in
    /// `out_dir` that is removed at the end.
    pub map: Option<PathBuf>,
    /// Worker threads (0 = one per core); outputs are identical for any number.
    pub threads: usize,
    pub budget: MemoryBudget,
    /// Seconds spent loading the scene, for the report.
    pub scene_seconds: f64,
}

/// A map that can be reused for a scene, with the report it recorded.
fn reusable(path: &Path, provenance: &Provenance) -> Option<(MapFile, EmissionReport)> {
    let map = MapFile::open(path).ok()?;
    if map.header().provenance.digest != provenance.digest {
        return None;
    }
    let report = serde_json::from_slice(map.metadata()).ok()?;
    Some((map, report))
}

/// The photon map a render used: what it reported and how long it took.
struct MapStage {
    emission: EmissionReport,
    summary: MapSummary,
    reused: bool,
}

impl RenderJob<'_> {
    pub fn run(&self, progress: &dyn Progress) -> Result<RunReport> {
        let start = Instant::now();
        crate::mem::tune_allocator();
        let sampler = crate::mem::PeakSampler::start();
        let scene = self.scene;
        // Everything that can be refused is refused before any photon is traced.
        let mut shares = self.budget.render(scene, self.threads)?;
        let (_lock, staging, mut warnings) =
            prepare_outputs(scene, &self.out_dir, self.map.as_deref())?;
        if let Some(r) = &scene.inelastic {
            warnings.extend(r.missing_warnings(scene.bands.centers_nm()));
        }
        let sink = outputs::CubeSet::create(scene, staging.dir())?;
        let (rendered, stage, t_emit) = match scene.render.integrator {
            IntegratorMode::PhotonMap => {
                let (map, stage, t_emit, _scratch, _map_lock) =
                    self.open_map(&mut shares, start, progress)?;
                let rendered = crate::render::render(scene, &map, &sink, self.threads, progress)?;
                (rendered, Some(stage), t_emit)
            }
            IntegratorMode::Path => (
                crate::render::render_path(scene, &sink, self.threads, progress)?,
                None,
                0.0,
            ),
        };
        let files = sink.finish(scene)?;
        let t_render = start.elapsed().as_secs_f64();
        let peaks = sampler.finish();
        outputs::publish_run(
            scene,
            staging,
            files,
            rendered,
            stage,
            shares,
            RenderTimings {
                scene: self.scene_seconds,
                emit: t_emit,
                render: t_render - t_emit,
                total: self.scene_seconds + t_render,
            },
            peaks,
            warnings,
        )
    }

    /// The photon map of the render: reused when its provenance matches,
    /// else emitted (into a scratch file in the output directory without
    /// `map`), with the band-shape grid's share taken from the budget. A
    /// kept map is locked for reading while the render runs, and for
    /// writing while it is emitted.
    #[allow(clippy::type_complexity)]
    fn open_map(
        &self,
        shares: &mut RenderShares,
        start: Instant,
        progress: &dyn Progress,
    ) -> Result<(
        PhotonMap,
        MapStage,
        f64,
        Option<tempfile::NamedTempFile>,
        Option<RunLock>,
    )> {
        let scene = self.scene;
        let provenance = crate::emit::emission_provenance(scene)?;
        let scratch = match &self.map {
            Some(_) => None,
            None => Some(
                crate::output::temp_in(&self.out_dir, ".littoral-map.", "")
                    .map_err(|e| Error::io(&self.out_dir, "create", e))?,
            ),
        };
        let kept = self.map.as_deref();
        let map_path = kept
            .or(scratch.as_ref().map(|s| s.path()))
            .expect("a map path");
        let lock = kept.map(RunLock::shared).transpose()?;
        let reused = kept.and_then(|p| reusable(p, &provenance));
        let reused_map = reused.is_some();
        let (file, emission, summary) = match reused {
            Some((file, emission)) => {
                let summary = MapSummary::existing(&file, kept);
                (file, emission, summary)
            }
            None => {
                if let Some(l) = &lock {
                    l.upgrade()?;
                }
                let em = crate::emit::emit(
                    scene,
                    &provenance,
                    map_path,
                    &self.budget.emission(self.threads),
                    progress,
                )?;
                let summary = MapSummary::written(&em.map, provenance.digest_hex(), kept);
                (MapFile::open(map_path)?, em.report, summary)
            }
        };
        let t_emit = start.elapsed().as_secs_f64();
        crate::mem::release_free_memory();

        let volume_photons = crate::photon::VOLUME_LAYERS.map(|l| file.layer_photons(l));
        shares.take_band_shape_grid(crate::estimate::Estimator::shape_grid_bytes(
            scene,
            volume_photons,
        ))?;
        let map = PhotonMap::new(file, shares.tile_cache_bytes)?;
        let stage = MapStage {
            emission,
            summary,
            reused: reused_map,
        };
        Ok((map, stage, t_emit, scratch, lock))
    }
}

/// Before a render writes anything into `out_dir`: create it, take the
/// render's lock there (another run writing the same scene's files fails
/// at once), remove what killed runs left, and refuse output names that
/// are links or special files, or that name the scene file or the map
/// (`map`). Returns the lock, the staging directory of the run's files
/// and what to warn about.
pub(crate) fn prepare_outputs(
    scene: &Scene,
    out_dir: &Path,
    map: Option<&Path>,
) -> Result<(RunLock, Staging, Vec<String>)> {
    use crate::output::set;
    create_dir(out_dir)?;
    let lock = RunLock::exclusive(&out_dir.join(format!("{}.render", scene.name)))?;
    let mut swept = set::sweep_stale(out_dir);
    if let Some(m) = map {
        let dir = crate::output::parent_dir(m);
        if !set::same_file(dir, out_dir) {
            swept.extend(set::sweep_stale(dir));
        }
        check_map_target(m)?;
        set::refuse_input(m, "--map", &scene.origin.path, "scene file")?;
    }
    for name in outputs::run_file_names(scene) {
        let path = out_dir.join(&name);
        set::check_target(&path)?;
        set::refuse_input(&path, "--out", &scene.origin.path, "scene file")?;
        if let Some(m) = map {
            set::refuse_input(m, "--map", &path, "render's output")?;
        }
    }
    let staging = Staging::new(out_dir)?;
    Ok((
        lock,
        staging,
        set::sweep_warning(&swept).into_iter().collect(),
    ))
}

/// A map path may be written when it is absent, or a regular file that is
/// empty or begins as a littoral map does (a corrupt or older map is
/// replaced; anything else is someone's file, and refused).
pub(crate) fn check_map_target(path: &Path) -> Result<()> {
    crate::output::set::check_target(path)?;
    let Ok(f) = std::fs::File::open(path) else {
        return Ok(());
    };
    let mut head = Vec::with_capacity(8);
    std::io::Read::read_to_end(&mut std::io::Read::take(f, 8), &mut head)
        .map_err(|e| Error::io(path, "read", e))?;
    if head[..] == crate::store::format::HEADER_MAGIC[..head.len()] {
        return Ok(());
    }
    Err(Error::io(
        path,
        "write the photon map",
        std::io::Error::new(
            std::io::ErrorKind::AlreadyExists,
            "the file there is not a littoral photon map: refusing to replace it",
        ),
    ))
}

/// Create `dir` (and its parents) and check that it is a directory.
fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, "create directory", e))?;
    if !dir.is_dir() {
        return Err(Error::io(
            dir,
            "create directory",
            std::io::Error::other("not a directory"),
        ));
    }
    Ok(())
}
