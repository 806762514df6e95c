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
pub mod html;
pub mod parts;
pub mod plan;
pub mod report;
pub mod units;

use crate::emit::report::EmissionReport;
use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::provenance::Provenance;
use crate::scene::{IntegratorMode, Scene};
use crate::store::{MapFile, PhotonMap};
pub use budget::{MemoryBudget, RenderShares};
use report::{
    EmitReport, EmitTimings, MapSummary, Outputs, RenderTimings, RunReport, SensorSummary,
};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Trace a scene's photons into a map file.
pub struct EmitJob<'a> {
    pub scene: &'a Scene,
    /// The map to write (under a temporary name until complete).
    pub map: PathBuf,
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
        Ok(EmitReport {
            emission: em.report,
            map: MapSummary::written(&em.map, provenance.digest_hex(), Some(&self.map)),
            timings_s: EmitTimings {
                scene: self.scene_seconds,
                emit_and_store: emit_s,
                total: self.scene_seconds + emit_s,
            },
            peak_memory: peaks,
            mem_budget_bytes: self.budget.total(),
            peak_rss_bytes: peaks.rss_bytes,
            units: units::report_units(),
        })
    }
}

/// Merge the shard files of a sharded emission into one map, with the
/// emission report of the whole (byte-identical to a single [`EmitJob`]'s
/// map and report with the same budget).
pub struct MergeJob<'a> {
    pub parts: &'a [PathBuf],
    pub map: PathBuf,
    /// The budget; `None` takes the one the shards were emitted with (so
    /// the map is the single run's; see [`crate::emit::merge_shards`]).
    pub budget: Option<MemoryBudget>,
}

impl MergeJob<'_> {
    pub fn run(&self, progress: &dyn Progress) -> Result<EmitReport> {
        let start = Instant::now();
        crate::mem::tune_allocator();
        let sampler = crate::mem::PeakSampler::start();
        let (em, budget) = crate::emit::merge_shards(
            self.parts,
            &self.map,
            self.budget.map(|b| b.total()),
            progress,
        )?;
        let provenance = MapFile::open(&self.map)?.header().provenance.digest_hex();
        let seconds = start.elapsed().as_secs_f64();
        let peaks = sampler.finish();
        Ok(EmitReport {
            emission: em.report,
            map: MapSummary::written(&em.map, provenance, Some(&self.map)),
            timings_s: EmitTimings {
                scene: 0.0,
                emit_and_store: seconds,
                total: seconds,
            },
            peak_memory: peaks,
            mem_budget_bytes: budget,
            peak_rss_bytes: peaks.rss_bytes,
            units: units::report_units(),
        })
    }
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
        create_dir(&self.out_dir)?;
        let integrator = scene.render.integrator;
        let (rendered, stage, t_emit) = match integrator {
            IntegratorMode::PhotonMap => {
                let (rendered, stage, t_emit) = self.photon_map(&mut shares, start, progress)?;
                (rendered, Some(stage), t_emit)
            }
            IntegratorMode::Path => (
                crate::render::render_path(scene, &self.out_dir, self.threads, progress)?,
                None,
                0.0,
            ),
        };
        let t_render = start.elapsed().as_secs_f64();
        let peaks = sampler.finish();
        publish_run(
            scene,
            &self.out_dir,
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
        )
    }

    fn photon_map(
        &self,
        shares: &mut RenderShares,
        start: Instant,
        progress: &dyn Progress,
    ) -> Result<(crate::render::Rendered, MapStage, f64)> {
        let (map, stage, t_emit, scratch) = self.open_map(shares, start, progress)?;
        let rendered =
            crate::render::render(self.scene, &map, &self.out_dir, self.threads, progress)?;
        drop(map);
        drop(scratch);
        Ok((rendered, stage, t_emit))
    }

    /// The photon map of the render: reused when its provenance matches,
    /// else emitted (into a scratch file in the output directory without
    /// `map`), with the band-shape grid's share taken from the budget.
    fn open_map(
        &self,
        shares: &mut RenderShares,
        start: Instant,
        progress: &dyn Progress,
    ) -> Result<(PhotonMap, MapStage, f64, Option<tempfile::NamedTempFile>)> {
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
        let reused = kept.and_then(|p| reusable(p, &provenance));
        let reused_map = reused.is_some();
        let (file, emission, summary) = match reused {
            Some((file, emission)) => {
                let summary = MapSummary::existing(&file, kept);
                (file, emission, summary)
            }
            None => {
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
        Ok((map, stage, t_emit, scratch))
    }
}

/// With `[sensor] response`: the radiance and the product cubes integrated
/// over that sensor's bands (`cube::ops::resample`), as
/// `NAME[.product].SENSOR.{hdr,bsq}` beside them.
fn sensor_cubes(
    scene: &Scene,
    out_dir: &Path,
    rendered: &crate::render::Rendered,
) -> Result<Vec<report::ProductFiles>> {
    let Some(sensor) = &scene.sensor.response else {
        return Ok(Vec::new());
    };
    let tag = Path::new(&sensor.name)
        .file_stem()
        .map_or_else(|| sensor.name.clone(), |s| s.to_string_lossy().into_owned());
    let mut cubes = vec![("radiance", rendered.hdr.clone())];
    cubes.extend(
        crate::render::PRODUCTS
            .iter()
            .zip(&rendered.products)
            .map(|(p, f)| (p.suffix, f.hdr.clone())),
    );
    let mut out = Vec::with_capacity(cubes.len());
    for (product, hdr) in cubes {
        let cube = crate::cube::EnviCube::open(&hdr)?;
        let stem = hdr
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let (files, _) =
            crate::cube::ops::resample(&cube, sensor, out_dir, &format!("{stem}.{tag}"))?;
        out.push(report::ProductFiles {
            product: product.into(),
            units: cube.data_units().unwrap_or("unknown").into(),
            hdr: files.hdr.display().to_string(),
            bsq: files.bsq.display().to_string(),
        });
    }
    Ok(out)
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

/// The files and the report of a finished render in `out_dir`: depth
/// profiles and Kd as CSV (photon map), the sensor-band cubes, the HTML
/// page and the JSON report.
fn publish_run(
    scene: &Scene,
    out_dir: &Path,
    rendered: crate::render::Rendered,
    stage: Option<MapStage>,
    shares: RenderShares,
    timings: RenderTimings,
    peaks: crate::mem::MemoryPeaks,
) -> Result<RunReport> {
    let integrator = scene.render.integrator;
    let json = out_dir.join(format!("{}.json", scene.name));
    let html = out_dir.join(format!("{}.html", scene.name));
    let ed_above = match &stage {
        Some(s) => s.emission.above_surface.Ed.clone(),
        None => (0..scene.bands.len())
            .map(|b| scene.incident_irradiance(b))
            .collect(),
    };
    let (emission, map, reused_map) = match stage {
        Some(s) => (Some(s.emission), Some(s.summary), s.reused),
        None => (None, None, false),
    };
    // Depth profiles and Kd, as CSV, from the emission's tallies.
    let mut profiles = None;
    if let Some(e) = &emission {
        let p = out_dir.join(format!("{}.profiles.csv", scene.name));
        let k = out_dir.join(format!("{}.kd.csv", scene.name));
        crate::output::write_atomic(&p, e.profiles_csv().as_bytes())?;
        crate::output::write_atomic(&k, e.kd_csv().as_bytes())?;
        profiles = Some((p.display().to_string(), k.display().to_string()));
    }
    let sensor_cubes = sensor_cubes(scene, out_dir, &rendered)?;
    let report = RunReport {
        integrator,
        Ed_above_surface: ed_above,
        emission,
        map,
        reused_map,
        warnings: report::radiometer_warnings(&rendered.radiometers)
            .into_iter()
            .chain(rendered.warnings.iter().cloned())
            .collect(),
        radiometers: rendered.radiometers,
        estimate: scene.estimate.clone(),
        sensor: SensorSummary {
            pixels: scene.sensor.pixels,
            samples_per_pixel: scene.sensor.samples_per_pixel,
            bands: scene.bands.len(),
            georef: scene.georef,
            geotransform: crate::cube::georef::geotransform(scene),
            sun_zenith_deg: scene.sun.zenith_rad.to_degrees(),
            sun_azimuth_deg: scene.sun.azimuth_rad.to_degrees(),
        },
        cache: rendered.cache,
        memory: shares,
        outputs: Outputs {
            hdr: rendered.hdr.display().to_string(),
            bsq: rendered.bsq.display().to_string(),
            png: rendered.png.display().to_string(),
            exr: rendered.exr.display().to_string(),
            json: json.display().to_string(),
            html: html.display().to_string(),
            stderr_hdr: rendered
                .stderr
                .as_ref()
                .map(|c| c.hdr.display().to_string()),
            stderr_bsq: rendered
                .stderr
                .as_ref()
                .map(|c| c.bsq.display().to_string()),
            profiles_csv: profiles.as_ref().map(|p| p.0.clone()),
            kd_csv: profiles.map(|p| p.1),
            products: crate::render::PRODUCTS
                .iter()
                .zip(&rendered.products)
                .map(|(p, f)| report::ProductFiles {
                    product: p.suffix.into(),
                    units: p.units.into(),
                    hdr: f.hdr.display().to_string(),
                    bsq: f.bsq.display().to_string(),
                })
                .collect(),
            sensor_cubes,
        },
        timings_s: timings,
        peak_memory: peaks,
        peak_rss_bytes: peaks.rss_bytes,
        units: units::report_units(),
    };
    let text = serde_json::to_string_pretty(&report)
        .map_err(|e| Error::invalid("report", e.to_string()))?
        + "\n";
    html::write(scene, &report, &html)?;
    crate::output::write_atomic(&json, text.as_bytes())?;
    Ok(report)
}
