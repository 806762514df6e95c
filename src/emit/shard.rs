//! Emission split over machines: shard `I` of `N` of a scene's photon
//! indices traced into a shard file (`store::shard`), and the shards merged
//! into the map one emission would have written, byte for byte.
//!
//! Not for: the jobs and their reports (`job::distributed`), the shard
//! file format (`store::shard`).

use super::report;
use super::tally::Totals;
use super::{Emission, Emitter};
use crate::error::Result;
use crate::progress::Progress;
use crate::provenance::Provenance;
use crate::scene::Scene;
use crate::store::{BuildOptions, PhotonSource, StagedPhoton};
use std::path::Path;

/// The payload an emission shard carries for the merge.
#[derive(serde::Serialize, serde::Deserialize)]
pub(super) struct ShardEmission {
    pub(super) totals: Totals,
    pub(super) report_inputs: report::ReportInputs,
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
pub(super) fn shard_payload(payload: &ShardEmission) -> Result<Box<serde_json::value::RawValue>> {
    serde_json::value::to_raw_value(payload)
        .map_err(|e| crate::Error::invalid("shard payload", e.to_string()))
}

/// The merge's budget for shards that do not say what theirs was.
pub const DEFAULT_MERGE_BUDGET: u64 = 256 << 20;

/// What in shard header `h` differs from the first shard's `head`, if
/// anything: then they are not shards of one emission.
fn differs(
    head: &crate::store::shard::ShardHeader,
    h: &crate::store::shard::ShardHeader,
) -> Option<&'static str> {
    if h.shards != head.shards {
        Some("the shard count")
    } else if h.provenance_digest != head.provenance_digest || h.total_indices != head.total_indices
    {
        Some("the scene (provenance)")
    } else if h.mem_budget != head.mem_budget {
        Some("the --mem-budget it was emitted with")
    } else if h.pilot_indices != head.pilot_indices || h.pilot != head.pilot {
        Some("the pilot sample (was it emitted with another --mem-budget?)")
    } else {
        None
    }
}

/// Whether a shard's index range is the one its shard number gives.
fn range_matches(h: &crate::store::shard::ShardHeader) -> bool {
    let r = crate::store::shard::shard_range(h.total_indices, h.shard, h.shards);
    h.indices == [r.start, r.end]
}

/// The shard files at `paths`, each checked against the first (one
/// emission: provenance, pilot, budget, shard count) and all of its shards
/// once, sorted by shard; with the first's header and the summed totals
/// and shard 0's report inputs.
#[allow(clippy::type_complexity)]
fn open_shards(
    paths: &[std::path::PathBuf],
) -> Result<(
    Vec<crate::store::shard::ShardFile>,
    crate::store::shard::ShardHeader,
    Totals,
    report::ReportInputs,
)> {
    use crate::store::shard::ShardFile;
    let Some(first_path) = paths.first() else {
        return Err(crate::Error::invalid("map merge", "no shard files given"));
    };
    let first = ShardFile::open(first_path)?;
    let head = first.header().clone();
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
        if let Some(what) = differs(&head, s.header()) {
            return Err(mismatch(&s, what));
        }
        if !range_matches(s.header()) {
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
    Ok((
        shards,
        head,
        totals.expect("one shard"),
        inputs.expect("one shard"),
    ))
}

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
    let Some(first_path) = paths.first() else {
        return Err(crate::Error::invalid("map merge", "no shard files given"));
    };
    let (shards, head, totals, inputs) = open_shards(paths)?;
    let budget = budget.unwrap_or(match head.mem_budget {
        0 => DEFAULT_MERGE_BUDGET,
        recorded => recorded,
    });
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
