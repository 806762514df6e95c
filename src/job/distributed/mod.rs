//! A run split over machines, in one place: emission in shards and their
//! merge ([`ShardJob`], [`MergeJob`]; the tracing itself is
//! `emit::shard`), a render in parts and their assembly ([`parts`]; a
//! part's tile files, their layout, writer and reader, in `tile_file`),
//! and the Slurm batch scripts that chain them ([`plan`]).
//!
//! Every job here returns a typed report and writes its own files (under
//! the lock of what it writes, `output::set::RunLock`); the binary only
//! parses and prints.
//!
//! Not for: the shard file format (`store::shard`), a run on one machine
//! (`job::RenderJob`).

pub mod parts;
pub mod plan;
mod tile_file;

use super::report::{EmitReport, EmitTimings, MapSummary};
use super::{check_map_target, units, MemoryBudget};
use crate::error::Result;
use crate::mem::MemoryPeaks;
use crate::output::set::RunLock;
use crate::progress::Progress;
use crate::scene::Scene;
use crate::store::MapFile;
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

/// Trace shard `shard.0` of `shard.1` of a scene's photons into a shard
/// file (`littoral emit --shard I/N`).
pub struct ShardJob<'a> {
    pub scene: &'a Scene,
    /// The shard file to write.
    pub path: PathBuf,
    pub shard: (u64, u64),
    /// Where to write the JSON report too (under the shard's lock).
    pub report: Option<PathBuf>,
    pub threads: usize,
    pub budget: MemoryBudget,
}

/// What a shard emission did (fields in the order the JSON has always
/// listed them).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ShardReport {
    pub file_bytes: u64,
    /// The photon indices traced, `[start, end)`.
    pub indices: [u64; 2],
    pub mem_budget_bytes: u64,
    pub path: String,
    pub peak_memory: MemoryPeaks,
    /// Photons stored.
    pub photons: u64,
    pub seconds: f64,
    pub shard: u64,
    pub shards: u64,
}

impl ShardReport {
    /// The report as `littoral emit --shard` writes it.
    pub fn json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a report serialises") + "\n"
    }

    /// The line `littoral emit --shard` prints.
    pub fn summary(&self) -> String {
        format!(
            "emitted shard {}/{}: photon indices {}..{}, {} photons stored in {}",
            self.shard, self.shards, self.indices[0], self.indices[1], self.photons, self.path
        )
    }
}

impl ShardJob<'_> {
    pub fn run(&self, progress: &dyn Progress) -> Result<ShardReport> {
        let start = Instant::now();
        crate::mem::tune_allocator();
        let _lock =
            super::prepare_map_outputs(self.scene, &self.path, self.report.as_deref(), false)?;
        let report_file = crate::output::LateFile::create(self.report.as_deref())?;
        let sampler = crate::mem::PeakSampler::start();
        let provenance = crate::emit::emission_provenance(self.scene)?;
        let h = crate::emit::shard::emit_shard(
            self.scene,
            &provenance,
            &self.path,
            self.shard,
            &self.budget.emission(self.threads),
            progress,
        )?;
        let report = ShardReport {
            file_bytes: std::fs::metadata(&self.path).map(|m| m.len()).unwrap_or(0),
            indices: h.indices,
            mem_budget_bytes: self.budget.total(),
            path: self.path.display().to_string(),
            peak_memory: sampler.finish(),
            photons: h.photons,
            seconds: start.elapsed().as_secs_f64(),
            shard: h.shard,
            shards: h.shards,
        };
        report_file.write(&report.json())?;
        Ok(report)
    }
}

/// Merge the shard files of a sharded emission into one map, with the
/// emission report of the whole (byte-identical to a single
/// [`super::EmitJob`]'s map and report with the same budget).
pub struct MergeJob<'a> {
    pub parts: &'a [PathBuf],
    pub map: PathBuf,
    /// Where to write the JSON report too (under the map's lock).
    pub report: Option<PathBuf>,
    /// The budget; `None` takes the one the shards were emitted with (so
    /// the map is the single run's; see [`crate::emit::shard::merge_shards`]).
    pub budget: Option<MemoryBudget>,
}

impl MergeJob<'_> {
    pub fn run(&self, progress: &dyn Progress) -> Result<EmitReport> {
        use crate::output::set::{check_target, refuse_input};
        let start = Instant::now();
        crate::mem::tune_allocator();
        check_map_target(&self.map)?;
        for part in self.parts {
            refuse_input(&self.map, "--out", part, "shard file")?;
        }
        if let Some(r) = &self.report {
            check_target(r)?;
            refuse_input(r, "--report", &self.map, "map (--out)")?;
            for part in self.parts {
                refuse_input(r, "--report", part, "shard file")?;
            }
        }
        let _lock = RunLock::exclusive(&self.map)?;
        let report_file = crate::output::LateFile::create(self.report.as_deref())?;
        let sampler = crate::mem::PeakSampler::start();
        let (em, budget) = crate::emit::shard::merge_shards(
            self.parts,
            &self.map,
            self.budget.map(|b| b.total()),
            progress,
        )?;
        let provenance = MapFile::open(&self.map)?.header().provenance.digest_hex();
        let seconds = start.elapsed().as_secs_f64();
        let peaks = sampler.finish();
        let report = EmitReport {
            emission: em.report,
            map: MapSummary::written(&em.map, provenance, Some(&self.map)),
            atmosphere: None,
            timings_s: EmitTimings {
                scene: 0.0,
                emit_and_store: seconds,
                total: seconds,
            },
            peak_memory: peaks,
            mem_budget_bytes: budget,
            peak_rss_bytes: peaks.rss_bytes,
            units: units::report_units(),
            warnings: Vec::new(),
        };
        report_file.write(&report.json())?;
        Ok(report)
    }
}
