//! A render split over machines, and a render that survives being killed.
//!
//! - [`RenderPartJob`] (`littoral render --tiles I/N --out PARTDIR`):
//!   renders part I of the image tiles (N equal runs of the Morton order)
//!   into PARTDIR, one file per finished tile (`tiles/CCCCC-RRRRR.tile`,
//!   each written whole under a temporary name, with the scene's digest
//!   and a CRC-32), then `part.json` (what the part measured, and for part
//!   0 the radiometers and the emission report). A part started again
//!   skips the tiles already there.
//! - [`assemble`] (`littoral assemble PARTDIR... --out DIR`): checks
//!   that the parts are all of one render, builds the scene again from
//!   the text, path and overrides recorded with it, and writes every file a
//!   whole render writes. The cubes are byte-identical to a whole render's:
//!   every pixel draws from its own random stream, so a tile's values do
//!   not depend on which machine rendered it.
//! - [`render_resumable`] (`littoral render --resume`): part 0 of 1 in
//!   `DIR/.NAME.parts` (with the photon map there unless `--map` names
//!   one), then assembly into DIR; killed and started again, it renders
//!   only the tiles that were not finished.
//!
//! With the photon-map integrator a part of several renders from a map it
//! is given and does not emit one (parts running at once would race to
//! write it): `littoral emit`, or `emit --shard` and `map merge`, first.
//!
//! Not for: the whole render in one process (`RenderJob`).

use super::tile_file::{read_tile, tile_path, tile_size, TileFiles, TILES_DIR};
use crate::emit::report::EmissionReport;
use crate::error::{Error, Result};
use crate::job::report::{MapSummary, RenderTimings, RunReport};
use crate::job::{MapStage, MemoryBudget, RenderJob, RenderShares};
use crate::mem::MemoryPeaks;
use crate::progress::Progress;
use crate::render::RadiometerReading;
use crate::scene::{IntegratorMode, Scene, SceneOrigin};
use crate::store::cache::CacheStats;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::Instant;

const MANIFEST: &str = "part.json";

/// What a finished part recorded (`PARTDIR/part.json`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PartManifest {
    /// This part, 0-based, of `parts`.
    pub part: u64,
    pub parts: u64,
    /// SHA-256 of the scene's origin: parts of one render share it.
    pub scene_digest: String,
    pub origin: SceneOrigin,
    /// Image tiles of this part, (column, row).
    pub tiles: Vec<[usize; 2]>,
    /// The photon map's emission report and summary (photon-map renders).
    pub emission: Option<EmissionReport>,
    pub map: Option<MapSummary>,
    pub reused_map: bool,
    pub shares: RenderShares,
    pub cache: CacheStats,
    pub timings_s: RenderTimings,
    pub peak_memory: MemoryPeaks,
    /// The radiometer readings (part 0 only).
    pub radiometers: Option<Vec<RadiometerReading>>,
}

/// The digest parts of one render agree on, and finished tiles are
/// stamped with: the scene's text, path and overrides, the bytes of every
/// file it reads (through the emission's `provenance`, which hashes them),
/// and the version of littoral. A tile finished before a geometry or table
/// file changed, or by another version, is not taken up by `--resume` or
/// `assemble`.
fn scene_digest(scene: &Scene, provenance: &crate::provenance::Provenance) -> Result<String> {
    let origin = &scene.origin;
    let mut json =
        serde_json::to_vec(origin).map_err(|e| Error::invalid("scene", e.to_string()))?;
    json.extend_from_slice(provenance.digest_hex().as_bytes());
    json.extend_from_slice(env!("CARGO_PKG_VERSION").as_bytes());
    Ok(crate::provenance::sha256_hex(&json))
}

/// The image tiles of part `part` of `parts`.
pub fn part_tiles(scene: &Scene, part: u64, parts: u64) -> Vec<(usize, usize)> {
    let all = crate::render::image_tiles(scene);
    let r = crate::store::shard::shard_range(all.len() as u64, part, parts);
    all[r.start as usize..r.end as usize].to_vec()
}

/// Render part `tiles.0` of `tiles.1` of a scene's image tiles into
/// `part_dir`.
pub struct RenderPartJob<'a> {
    pub scene: &'a Scene,
    pub part_dir: PathBuf,
    /// The photon map (photon-map integrator): reused when it matches the
    /// scene; emitted there only when `emit_map` allows it.
    pub map: Option<PathBuf>,
    pub emit_map: bool,
    pub tiles: (u64, u64),
    pub threads: usize,
    pub budget: MemoryBudget,
}

impl RenderPartJob<'_> {
    pub fn run(&self, progress: &dyn Progress) -> Result<PartManifest> {
        let start = Instant::now();
        crate::mem::tune_allocator();
        let sampler = crate::mem::PeakSampler::start();
        let scene = self.scene;
        let (part, parts) = self.tiles;
        if parts == 0 || part >= parts {
            return Err(Error::invalid(
                "--tiles",
                format!("{part}/{parts}: give I/N with 0 <= I < N"),
            ));
        }
        let provenance = crate::emit::emission_provenance(scene)?;
        let digest = scene_digest(scene, &provenance)?;
        let job = RenderJob {
            scene,
            out_dir: self.part_dir.clone(),
            map: self.map.clone(),
            threads: self.threads,
            budget: self.budget,
            scene_seconds: 0.0,
        };
        let mut shares = self.budget.render(scene, self.threads)?;
        crate::job::create_dir(&self.part_dir.join(TILES_DIR))?;
        let mine = part_tiles(scene, part, parts);
        let bands = scene.bands.len();
        let errors = crate::render::stderr_description(scene).is_some();
        let products = crate::render::products(scene).len();
        // Tiles a previous run finished (and that read back whole) are kept.
        let todo: Vec<(usize, usize)> = mine
            .iter()
            .copied()
            .filter(|&t| {
                let p = tile_path(&self.part_dir, t);
                !(p.exists()
                    && read_tile(&p, &digest, t, tile_size(scene, t), bands, errors, products)
                        .is_ok())
            })
            .collect();
        let (stage, t_emit, cache, radiometers) = match scene.render.integrator {
            IntegratorMode::PhotonMap => {
                let Some(map_path) = &self.map else {
                    return Err(Error::invalid(
                        "--map",
                        "a part of a render reads an emitted photon map: give --map FILE (littoral emit, or emit --shard and map merge)",
                    ));
                };
                if !self.emit_map && crate::job::reusable(map_path, &provenance).is_none() {
                    return Err(Error::invalid(
                        "--map",
                        format!(
                            "{} is not a photon map of this scene (missing, another scene, or unreadable): emit it first; parts do not emit, since several would write it at once",
                            map_path.display()
                        ),
                    ));
                }
                crate::job::check_map_target(map_path)?;
                let (map, stage, t_emit, _scratch, _map_lock) =
                    job.open_map(&mut shares, start, progress)?;
                let light = crate::render::march::RayMarcher::new(
                    scene,
                    crate::estimate::Estimator::new(scene, &map)?,
                );
                let radiometers = self.render_tiles(&light, &todo, &digest, progress)?;
                use crate::store::PhotonQuery;
                (Some(stage), t_emit, map.cache_stats(), radiometers)
            }
            IntegratorMode::Path => {
                let light = crate::render::path::PathTracer::new(scene);
                let radiometers = self.render_tiles(&light, &todo, &digest, progress)?;
                (None, 0.0, CacheStats::default(), radiometers)
            }
        };
        let total = start.elapsed().as_secs_f64();
        let (emission, map, reused_map) = match stage {
            Some(s) => (Some(s.emission), Some(s.summary), s.reused),
            None => (None, None, false),
        };
        let manifest = PartManifest {
            part,
            parts,
            scene_digest: digest,
            origin: scene.origin.clone(),
            tiles: mine.iter().map(|&(i, j)| [i, j]).collect(),
            emission,
            map,
            reused_map,
            shares,
            cache,
            timings_s: RenderTimings {
                scene: 0.0,
                emit: t_emit,
                render: total - t_emit,
                total,
            },
            peak_memory: sampler.finish(),
            radiometers,
        };
        let text = serde_json::to_string_pretty(&manifest)
            .map_err(|e| Error::invalid("part manifest", e.to_string()))?;
        crate::output::write_atomic(&self.part_dir.join(MANIFEST), text.as_bytes())?;
        Ok(manifest)
    }

    /// Render the tiles `todo` into tile files; part 0 also reads the
    /// radiometers.
    fn render_tiles(
        &self,
        light: &dyn crate::render::Integrator,
        todo: &[(usize, usize)],
        digest: &str,
        progress: &dyn Progress,
    ) -> Result<Option<Vec<RadiometerReading>>> {
        let sink = TileFiles {
            dir: &self.part_dir,
            digest,
            bands: self.scene.bands.len(),
        };
        crate::render::render_tiles(self.scene, light, todo, &sink, self.threads, progress)?;
        if self.tiles.0 == 0 {
            Ok(Some(crate::render::read_radiometers(
                self.scene,
                light,
                self.threads,
            )?))
        } else {
            Ok(None)
        }
    }
}

/// Read `PARTDIR/part.json`.
pub fn read_manifest(part_dir: &Path) -> Result<PartManifest> {
    let path = part_dir.join(MANIFEST);
    let text = std::fs::read(&path).map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            Error::data(
                &path,
                None,
                "part",
                "missing: the part has not finished (render it, or again with the same --tiles)",
            )
        } else {
            Error::io(&path, "read", e)
        }
    })?;
    serde_json::from_slice(&text).map_err(|e| {
        Error::data(
            &path,
            None,
            "part",
            format!("unreadable part manifest: {e}"),
        )
    })
}

/// Parts of a render a manifest may claim beyond the directories given
/// (they are listed as missing); more is a damaged manifest.
const MAX_MISSING_LISTED: u64 = 1 << 16;

/// The manifests of `part_dirs`, checked to be every part of one render,
/// each once, sorted by part.
fn parts_of_one_render(part_dirs: &[PathBuf]) -> Result<Vec<(PathBuf, PartManifest)>> {
    let mut parts = part_dirs
        .iter()
        .map(|d| read_manifest(d).map(|m| (d.clone(), m)))
        .collect::<Result<Vec<_>>>()?;
    let Some((first_dir, first)) = parts.first().cloned() else {
        return Err(Error::invalid("assemble", "no part directories given"));
    };
    for (dir, m) in &parts {
        let damaged = if m.part >= m.parts {
            Some(format!("part {} of {}: past the count", m.part, m.parts))
        } else if m.parts > part_dirs.len() as u64 + MAX_MISSING_LISTED {
            Some(format!(
                "{} parts, against the {} directories given",
                m.parts,
                part_dirs.len()
            ))
        } else {
            None
        };
        if let Some(what) = damaged {
            return Err(Error::data(
                dir.join(MANIFEST),
                None,
                "part",
                format!("a damaged part manifest: {what}"),
            ));
        }
        if m.scene_digest != first.scene_digest || m.parts != first.parts {
            return Err(Error::data(
                dir.join(MANIFEST),
                None,
                "part",
                format!("not a part of the same render as {}", first_dir.display()),
            ));
        }
    }
    parts.sort_by_key(|(_, m)| m.part);
    for w in parts.windows(2) {
        if w[0].1.part == w[1].1.part {
            return Err(Error::invalid(
                "assemble",
                format!(
                    "part {} is given twice ({} and {})",
                    w[0].1.part,
                    w[0].0.display(),
                    w[1].0.display()
                ),
            ));
        }
    }
    if parts.len() as u64 != first.parts {
        let missing: Vec<String> = (0..first.parts)
            .filter(|k| !parts.iter().any(|(_, m)| m.part == *k))
            .map(|k| k.to_string())
            .collect();
        return Err(Error::invalid(
            "assemble",
            format!("parts missing: {} of {}", missing.join(", "), first.parts),
        ));
    }
    Ok(parts)
}

/// Assemble the parts of one render into `out_dir`: the files a whole
/// render writes, the cubes byte-identical to its.
pub fn assemble(part_dirs: &[PathBuf], out_dir: &Path, threads: usize) -> Result<RunReport> {
    let start = Instant::now();
    let parts = parts_of_one_render(part_dirs)?;
    let first = &parts[0].1;
    let scene = first.origin.build()?;
    let provenance = crate::emit::emission_provenance(&scene)?;
    if scene_digest(&scene, &provenance)? != first.scene_digest {
        return Err(Error::invalid(
            "assemble",
            "the scene does not build as it did",
        ));
    }
    let (_lock, staging, warnings) = crate::job::prepare_outputs(&scene, out_dir, None)?;
    let outputs = crate::job::outputs::CubeSet::create(&scene, staging.dir())?;
    let bands = scene.bands.len();
    let errors = crate::render::stderr_description(&scene).is_some();
    let products = crate::render::products(&scene).len();
    let pool = crate::parallel::pool(threads)?;
    let jobs: Vec<(PathBuf, (usize, usize))> = parts
        .iter()
        .flat_map(|(dir, m)| {
            part_tiles(&scene, m.part, m.parts)
                .into_iter()
                .map(move |t| (dir.clone(), t))
        })
        .collect();
    pool.install(|| {
        jobs.par_iter().try_for_each(|(dir, tile)| -> Result<()> {
            let path = tile_path(dir, *tile);
            if !path.exists() {
                return Err(Error::data(
                    &path,
                    None,
                    "tile",
                    "missing: the part did not finish this tile",
                ));
            }
            let t = read_tile(
                &path,
                &first.scene_digest,
                *tile,
                tile_size(&scene, *tile),
                bands,
                errors,
                products,
            )?;
            crate::render::TileSink::write(&outputs, &t)
        })
    })?;
    let files = outputs.finish(&scene)?;
    let mut rendered = crate::render::Rendered {
        radiometers: parts[0].1.radiometers.clone().unwrap_or_default(),
        ..Default::default()
    };
    let mut cache = CacheStats::default();
    let mut peaks = MemoryPeaks::default();
    let mut render_s = 0.0;
    for (_, m) in &parts {
        cache += &m.cache;
        peaks.max_with(&m.peak_memory);
        render_s += m.timings_s.render;
    }
    rendered.cache = cache;
    let p0 = &parts[0].1;
    let stage = match (&p0.emission, &p0.map) {
        (Some(e), Some(s)) => Some(MapStage {
            emission: e.clone(),
            summary: s.clone(),
            reused: p0.reused_map,
        }),
        _ => None,
    };
    let assemble_s = start.elapsed().as_secs_f64();
    crate::job::outputs::publish_run(
        &scene,
        staging,
        files,
        rendered,
        stage,
        p0.shares,
        RenderTimings {
            scene: 0.0,
            emit: p0.timings_s.emit,
            render: render_s + assemble_s,
            total: p0.timings_s.emit + render_s + assemble_s,
        },
        peaks,
        warnings,
    )
}

/// A whole render that keeps its finished tiles in `DIR/.NAME.parts` and,
/// started again after being killed, renders only the rest; the parts
/// directory is removed once the outputs are written.
pub fn render_resumable(job: &RenderJob, progress: &dyn Progress) -> Result<RunReport> {
    let scene = job.scene;
    crate::job::create_dir(&job.out_dir)?;
    let parts_dir = job.out_dir.join(format!(".{}.parts", scene.name));
    let map = job.map.clone().or_else(|| {
        (scene.render.integrator == IntegratorMode::PhotonMap).then(|| parts_dir.join("map.map"))
    });
    let part = RenderPartJob {
        scene,
        part_dir: parts_dir.clone(),
        map,
        emit_map: true,
        tiles: (0, 1),
        threads: job.threads,
        budget: job.budget,
    };
    crate::job::create_dir(&parts_dir)?;
    part.run(progress)?;
    let report = assemble(std::slice::from_ref(&parts_dir), &job.out_dir, job.threads)?;
    std::fs::remove_dir_all(&parts_dir).map_err(|e| Error::io(&parts_dir, "remove", e))?;
    Ok(report)
}
