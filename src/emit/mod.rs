//! Photon emission: sun and sky light traced in parallel through the scene
//! and streamed into the photon store, with irradiance tallies and energy
//! accounting.
//!
//! Photon `i` owns the random stream (scene seed, i): it picks its source
//! and band jointly in proportion to the horizontal spectral irradiance
//! times the band width, so every photon of a band carries the same power
//! P_b = A sum(E w) / (N w_b) (W nm^-1; A the domain area, w_b the FWHM).
//! The map is therefore a pure function of the scene and the seed, whatever
//! the thread count (see `store::build`), and so is the report: tallies are
//! summed as integers.
//!
//! Not for: rendering (the map and report are this stage's outputs).

pub mod report;
pub mod tally;
pub mod trace;

use crate::bounds::Aabb;
use crate::error::Result;
use crate::optics::majorant::MajorantGrid;
use crate::progress::Progress;
use crate::provenance::Provenance;
use crate::rng::Pcg32;
use crate::scene::Scene;
use crate::spectral::BandGrid;
use crate::store::{build_map, BuildOptions, PhotonSource, StagedPhoton, WriteSummary};
use glam::Vec3;
use std::ops::Range;
use std::path::Path;
use std::sync::{Mutex, OnceLock};
use tally::{PhotonTally, Totals};
use trace::Source;

/// Emits the photons of a scene.
pub struct Emitter<'s> {
    scene: &'s Scene,
    /// Cumulative distribution over (source, band): sun bands then sky bands.
    cdf: Vec<f64>,
    /// Where to start looking in `cdf` for u in [i/n, (i+1)/n), n its length.
    cdf_guide: Vec<u32>,
    /// Power per photon of each band (W nm^-1).
    photon_power: Vec<f64>,
    /// The water's local majorants and IOP bounds for delta tracking.
    grid: MajorantGrid,
    totals: Mutex<Totals>,
    /// Recorded in the map's header ([`emit`] sets it).
    provenance: Provenance,
    /// The emission report, made once when the last photon is traced.
    report: OnceLock<report::EmissionReport>,
}

impl<'s> Emitter<'s> {
    pub fn new(scene: &'s Scene) -> Result<Self> {
        let nb = scene.bands.len();
        let w: Vec<f64> = scene.bands.fwhm_nm().iter().map(|&f| f as f64).collect();
        let mut weights = Vec::with_capacity(2 * nb);
        weights.extend((0..nb).map(|b| scene.sun.horizontal_irradiance(b) * w[b]));
        weights.extend((0..nb).map(|b| scene.sky.irradiance[b] * w[b]));
        let total: f64 = weights.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return Err(crate::Error::invalid(
                "sun/sky",
                "the scene emits no light in any band (all irradiances are zero)",
            ));
        }
        let mut acc = 0.0;
        let cdf = weights
            .iter()
            .map(|x| {
                acc += x / total;
                acc
            })
            .collect::<Vec<f64>>();
        let cdf_guide = (0..cdf.len())
            .map(|i| cdf.partition_point(|&c| c <= i as f64 / cdf.len() as f64) as u32)
            .collect();
        let n = scene.photons as f64;
        let area = scene.domain.area_m2();
        let photon_power = w.iter().map(|wb| area * total / (n * wb)).collect();
        Ok(Emitter {
            scene,
            cdf,
            cdf_guide,
            photon_power,
            grid: MajorantGrid::new(&scene.water, nb),
            totals: Mutex::new(Totals::new(nb, scene.tally_depths.len())),
            provenance: Provenance::unrecorded(),
            report: OnceLock::new(),
        })
    }

    /// The report of the photons traced (call once tracing is done: it is
    /// made on the first call and kept).
    pub fn report(&self) -> &report::EmissionReport {
        self.report.get_or_init(|| {
            report::EmissionReport::new(self.scene, &self.totals(), &self.photon_power)
        })
    }

    /// Power carried by each photon of `band` (W nm^-1).
    pub fn photon_power(&self, band: usize) -> f64 {
        self.photon_power[band]
    }

    /// The (source, band) index of `u`: the first with `cdf > u` (the
    /// last if none), found from the guide by a short walk either way.
    fn pick(&self, u: f64) -> usize {
        let n = self.cdf.len();
        let mut k = self.cdf_guide[((u * n as f64) as usize).min(n - 1)] as usize;
        while k > 0 && self.cdf[k - 1] > u {
            k -= 1;
        }
        while k < n && self.cdf[k] <= u {
            k += 1;
        }
        k.min(n - 1)
    }

    /// Trace photon `i`; appends what it stores to `out`.
    fn trace_one(
        &self,
        i: u64,
        tally: &mut PhotonTally,
        out: &mut Vec<StagedPhoton>,
    ) -> (usize, trace::Traced) {
        let mut rng = Pcg32::new(self.scene.seed, i);
        let u = rng.uniform_f64();
        let k = self.pick(u);
        let nb = self.scene.bands.len();
        let (source, band) = if k < nb {
            (Source::Sun, k)
        } else {
            (Source::Sky, k - nb)
        };
        tally.clear();
        let t = trace::trace(
            self.scene,
            &self.grid,
            i,
            &mut rng,
            source,
            band,
            self.photon_power[band] as f32,
            tally,
            out,
        );
        (band, t)
    }

    /// Trace indices `range`, adding to the run totals.
    fn run(&self, range: Range<u64>, out: &mut Vec<StagedPhoton>) {
        let mut local = Totals::new(self.scene.bands.len(), self.scene.tally_depths.len());
        let mut tally = PhotonTally::new(self.scene.tally_depths.len());
        for i in range {
            let (band, t) = self.trace_one(i, &mut tally, out);
            local.record(band, &t.fates, &tally);
            local.stored_volume += t.stored_volume as u64;
            local.stored_surface += t.stored_surface as u64;
            local.truncated += t.truncated as u64;
        }
        self.totals
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .merge(&local);
    }

    /// The totals so far.
    pub fn totals(&self) -> Totals {
        self.totals
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clone()
    }

    /// Trace every photon without storing any (validation runs and tallies).
    pub fn trace_all(&self, threads: usize) -> Result<Totals> {
        use rayon::prelude::*;
        let pool = crate::parallel::pool(threads)?;
        let n = self.scene.photons;
        let batch = crate::store::build::BATCH_INDICES;
        pool.install(|| {
            (0..n.div_ceil(batch)).into_par_iter().for_each(|b| {
                let mut sink = Vec::new();
                self.run(b * batch..((b + 1) * batch).min(n), &mut sink);
            })
        });
        Ok(self.totals())
    }
}

impl PhotonSource for Emitter<'_> {
    fn indices(&self) -> u64 {
        self.scene.photons
    }

    fn generate(&self, range: Range<u64>, out: &mut Vec<StagedPhoton>) {
        self.run(range, out);
    }

    fn sample(&self, range: Range<u64>, out: &mut Vec<StagedPhoton>) {
        let mut tally = PhotonTally::new(self.scene.tally_depths.len());
        for i in range {
            self.trace_one(i, &mut tally, out);
        }
    }

    fn bands(&self) -> BandGrid {
        self.scene.bands.clone()
    }

    fn provenance(&self) -> Provenance {
        self.provenance.clone()
    }

    /// The emission report, as JSON.
    fn metadata(&self) -> Vec<u8> {
        serde_json::to_vec(self.report()).expect("the report serialises")
    }

    fn bounds(&self) -> Aabb {
        let d = &self.scene.domain;
        let g = self.scene.geometry.bounds();
        let deepest = if g.is_valid() {
            g.min.z.min(-1.0)
        } else {
            -1.0
        };
        Aabb {
            min: Vec3::new(0.0, 0.0, deepest),
            max: Vec3::new(d.size_m[0] as f32, d.size_m[1] as f32, 0.0),
        }
    }
}

/// The provenance of the photon maps of `scene`: its emission inputs
/// (`Scene::emission_inputs`) and the map format version.
pub fn emission_provenance(scene: &Scene) -> Result<Provenance> {
    let mut b = scene.emission_inputs()?;
    b.value("format_version", crate::store::format::FORMAT_VERSION);
    Ok(b.finish())
}

/// What `emit` produced.
pub struct Emission {
    pub map: WriteSummary,
    /// The emission report, as recorded in the map.
    pub report: report::EmissionReport,
}

/// Trace the scene's photons into the map at `map_path`, recording
/// `provenance` (from [`emission_provenance`]) and the emission report in it.
pub fn emit(
    scene: &Scene,
    provenance: &Provenance,
    map_path: &Path,
    options: &BuildOptions,
    progress: &dyn Progress,
) -> Result<Emission> {
    let mut emitter = Emitter::new(scene)?;
    emitter.provenance = provenance.clone();
    let map = build_map(map_path, &emitter, options, progress)?;
    let report = emitter.report().clone();
    Ok(Emission { map, report })
}

/// The payload an emission shard carries for the merge.
#[derive(serde::Serialize, serde::Deserialize)]
struct ShardEmission {
    totals: Totals,
    report_inputs: report::ReportInputs,
}

/// Batches of source indices traced in parallel before the ordered write.
const SHARD_BATCHES_AT_ONCE: u64 = 16;

/// Trace shard `shard` of `shards` of the scene's photon indices (equal
/// contiguous ranges, `store::shard::shard_range`) into the shard file at
/// `path`, with the pilot, totals and report inputs the merge needs. The
/// file is a pure function of the scene, the shard and the budget: batches
/// are traced in parallel and written in index order.
pub fn emit_shard(
    scene: &Scene,
    provenance: &Provenance,
    path: &Path,
    (shard, shards): (u64, u64),
    options: &BuildOptions,
    progress: &dyn Progress,
) -> Result<crate::store::shard::ShardHeader> {
    use crate::store::shard::{shard_range, ShardHeader, ShardWriter};
    use rayon::prelude::*;
    if shards == 0 || shard >= shards {
        return Err(crate::Error::invalid(
            "--shard",
            format!("{shard}/{shards}: give I/N with 0 <= I < N"),
        ));
    }
    let mut emitter = Emitter::new(scene)?;
    emitter.provenance = provenance.clone();
    let pilot = crate::store::build::Pilot::trace(&emitter, options)?;
    let range = shard_range(emitter.indices(), shard, shards);
    let mut writer = ShardWriter::create(path, &emitter.bounds())?;
    let pool = crate::parallel::pool(options.threads)?;
    let batch = crate::store::build::BATCH_INDICES;
    let batches = (range.end - range.start).div_ceil(batch);
    progress.stage("trace photons", range.end - range.start);
    let mut b = 0;
    while b < batches {
        let upto = (b + SHARD_BATCHES_AT_ONCE).min(batches);
        let traced: Vec<Vec<StagedPhoton>> = pool.install(|| {
            (b..upto)
                .into_par_iter()
                .map(|k| {
                    let lo = range.start + k * batch;
                    let hi = (lo + batch).min(range.end);
                    let mut out = Vec::new();
                    emitter.generate(lo..hi, &mut out);
                    progress.advance(hi - lo);
                    out
                })
                .collect()
        });
        for t in &traced {
            writer.push(t)?;
        }
        b = upto;
    }
    progress.finish();
    let bounds = emitter.bounds();
    let payload = ShardEmission {
        totals: emitter.totals(),
        report_inputs: report::ReportInputs::new(scene, &emitter.photon_power),
    };
    let header = ShardHeader {
        shard,
        shards,
        indices: [range.start, range.end],
        total_indices: emitter.indices(),
        provenance_digest: provenance.digest_hex(),
        provenance_record: provenance.record.clone(),
        bands_nm: scene.bands.centers_nm().to_vec(),
        fwhm_nm: scene.bands.fwhm_nm().to_vec(),
        bounds_min: bounds.min.to_array(),
        bounds_max: bounds.max.to_array(),
        mem_budget: options.mem_budget,
        pilot_indices: pilot.indices,
        pilot: pilot.positions.iter().map(|p| p.to_array()).collect(),
        photons: 0,
        stream_bytes: 0,
        stream_crc32: 0,
        payload: shard_payload(&payload)?,
    };
    writer.finish(header)
}

/// The JSON text of a shard's payload.
fn shard_payload(payload: &ShardEmission) -> Result<Box<serde_json::value::RawValue>> {
    serde_json::value::to_raw_value(payload)
        .map_err(|e| crate::Error::invalid("shard payload", e.to_string()))
}

/// The merge's budget for shards that do not say what theirs was.
pub const DEFAULT_MERGE_BUDGET: u64 = 256 << 20;

/// Merge the shard files of one sharded emission into the map at `out`:
/// byte-identical to the map a single `emit` of the scene writes with the
/// same budget. The shards must be all of one emission (same provenance,
/// pilot, budget and shard count, each shard once), in any order; the
/// merge reads them one after another, within `budget` bytes, or when
/// `None` the budget the shards were emitted with (so the map is the
/// single run's; [`DEFAULT_MERGE_BUDGET`] for shards that did not record
/// it). Returns the map and the budget it was written within.
pub fn merge_shards(
    paths: &[std::path::PathBuf],
    out: &Path,
    budget: Option<u64>,
    progress: &dyn Progress,
) -> Result<(Emission, u64)> {
    use crate::store::shard::{shard_range, ShardFile};
    let Some(first_path) = paths.first() else {
        return Err(crate::Error::invalid("map merge", "no shard files given"));
    };
    let first = ShardFile::open(first_path)?;
    let head = first.header().clone();
    let budget = budget.unwrap_or(match head.mem_budget {
        0 => DEFAULT_MERGE_BUDGET,
        recorded => recorded,
    });
    let n = head.shards;
    let mismatch = |s: &ShardFile, what: &str| {
        crate::Error::data(
            s.path(),
            None,
            "shard",
            format!(
                "{what} differs from {}'s: not a shard of the same emission",
                first_path.display()
            ),
        )
    };
    // Each shard is checked against the first as it is opened, and only
    // the first's pilot is kept.
    let mut shards = Vec::with_capacity(paths.len());
    let mut totals: Option<Totals> = None;
    let mut inputs = None;
    let rest = paths[1..].iter().map(|p| ShardFile::open(p));
    for s in std::iter::once(Ok(first)).chain(rest) {
        let mut s = s?;
        let h = s.header();
        if h.shards != n {
            return Err(mismatch(&s, "the shard count"));
        }
        if h.provenance_digest != head.provenance_digest || h.total_indices != head.total_indices {
            return Err(mismatch(&s, "the scene (provenance)"));
        }
        if h.mem_budget != head.mem_budget {
            return Err(mismatch(&s, "the --mem-budget it was emitted with"));
        }
        if h.pilot_indices != head.pilot_indices || h.pilot != head.pilot {
            return Err(mismatch(
                &s,
                "the pilot sample (was it emitted with another --mem-budget?)",
            ));
        }
        if h.indices != {
            let r = shard_range(h.total_indices, h.shard, n);
            [r.start, r.end]
        } {
            return Err(crate::Error::data(
                s.path(),
                None,
                "shard",
                "its index range does not match its shard number",
            ));
        }
        let payload: ShardEmission =
            serde_json::from_str(s.header().payload.get()).map_err(|e| {
                crate::Error::data(
                    s.path(),
                    None,
                    "shard",
                    format!("not an emission shard: {e}"),
                )
            })?;
        // The report from the summed fixed-point totals: the same numbers
        // a single run's totals give, in any order.
        match &mut totals {
            None => totals = Some(payload.totals),
            Some(t) => {
                if t.bands != payload.totals.bands || t.depths != payload.totals.depths {
                    return Err(mismatch(&s, "the tallies' shape"));
                }
                t.merge(&payload.totals)
            }
        }
        // The report's scene inputs are shard 0's, whatever the order given.
        if s.header().shard == 0 {
            inputs = Some(payload.report_inputs);
        }
        s.trim();
        shards.push(s);
    }
    shards.sort_by_key(|s| s.header().shard);
    if let Some(w) = shards
        .windows(2)
        .find(|w| w[0].header().shard == w[1].header().shard)
    {
        return Err(crate::Error::invalid(
            "map merge",
            format!(
                "shard {} is given twice ({} and {})",
                w[0].header().shard,
                w[0].path().display(),
                w[1].path().display()
            ),
        ));
    }
    for (k, s) in shards.iter().enumerate() {
        if s.header().shard != k as u64 {
            let missing = (0..n)
                .filter(|i| !shards.iter().any(|s| s.header().shard == *i))
                .map(|i| i.to_string())
                .collect::<Vec<_>>();
            let what = if missing.is_empty() {
                format!("shard {} is given twice", s.header().shard)
            } else {
                format!("shards missing: {} of {n}", missing.join(", "))
            };
            return Err(crate::Error::invalid("map merge", what));
        }
    }
    if shards.len() as u64 != n {
        return Err(crate::Error::invalid(
            "map merge",
            format!("{} shard files given, the emission has {n}", shards.len()),
        ));
    }
    let (totals, inputs) = (totals.expect("one shard"), inputs.expect("one shard"));
    let report = report::EmissionReport::from_inputs(&inputs, &totals);
    let metadata = serde_json::to_vec(&report).expect("the report serialises");
    let description = head.description(first_path)?;
    // Only the pilot's positions go on to the writer (which drops them once
    // the partition is made), not the header they came in.
    let pilot = head.pilot();
    drop(head);
    // One shard open at a time.
    let mut batches = shards
        .iter()
        .flat_map(|s| -> Box<dyn Iterator<Item = Result<Vec<StagedPhoton>>>> {
            match s.batches() {
                Ok(b) => Box::new(b),
                Err(e) => Box::new(std::iter::once(Err(e))),
            }
        })
        .inspect(|b| {
            if let Ok(b) = b {
                progress.advance(b.len() as u64);
            }
        });
    let map = crate::store::build::build_map_from_batches(
        out,
        &description,
        pilot,
        &mut batches,
        &metadata,
        &BuildOptions::with_budget(budget),
        progress,
    )?;
    Ok((Emission { map, report }, budget))
}

#[cfg(test)]
mod tests;
