//! The map-building pipeline: parallel producers, one writer thread.
//!
//! Producers (rayon workers) turn fixed chunks of source indices into staged
//! photons and send each chunk's photons as one batch over a bounded
//! crossbeam channel; a dedicated writer thread owns the [`MapWriter`]. A
//! pilot sample taken from the same source first fixes the partition. The
//! channel bound keeps producers from running ahead of the writer, so memory
//! is bounded by the writer's budget plus a few batches.

use super::codec::StagedPhoton;
use super::partition::Partition;
use super::writer::{MapWriter, WriteSummary, WriterPlan};
use crate::bounds::Aabb;
use crate::error::Result;
use crate::progress::Progress;
use crate::provenance::Provenance;
use crate::spectral::BandGrid;
use glam::Vec3;
use rayon::prelude::*;
use std::ops::Range;
use std::path::Path;

/// Source indices per producer batch.
pub const BATCH_INDICES: u64 = 4096;
/// Batches that may wait in the channel.
const CHANNEL_BATCHES: usize = 4;
/// Source indices sampled to build the partition.
const PILOT_INDICES: u64 = 32_768;

/// Anything that produces photons for a map from numbered source indices.
///
/// `generate` must be a pure function of the range: the photons of index
/// `i` may not depend on which thread runs it or on what ran before, and
/// every staged photon's `id` must be unique across the map.
pub trait PhotonSource: Sync {
    /// Number of source indices (e.g. photon paths traced).
    fn indices(&self) -> u64;
    /// Append the photons stored by source indices `range` to `out`.
    fn generate(&self, range: Range<u64>, out: &mut Vec<StagedPhoton>);
    /// As `generate`, for the pilot sample only: a source that keeps
    /// statistics of its run must not count these.
    fn sample(&self, range: Range<u64>, out: &mut Vec<StagedPhoton>) {
        self.generate(range, out)
    }
    /// The spectral bands of the photons.
    fn bands(&self) -> BandGrid;
    /// Bounds of the scene.
    fn bounds(&self) -> Aabb;
    /// What the photons are made from, recorded in the map's header.
    fn provenance(&self) -> Provenance {
        Provenance::unrecorded()
    }
    /// Bytes recorded in the map after every photon was generated (an
    /// emitter's report); called once, after the last `generate`.
    fn metadata(&self) -> Vec<u8> {
        Vec::new()
    }
}

/// How to build a map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildOptions {
    /// Producer threads (0 = one per core).
    pub threads: usize,
    /// Memory budget in bytes for the whole build.
    pub mem_budget: u64,
    /// Photons per tile to aim for instead of the budget's choice (tests use
    /// small tiles to exercise many tile borders); capped by the budget.
    pub tile_photons: Option<u32>,
}

impl BuildOptions {
    /// Default threads and tiles with the given budget.
    pub fn with_budget(mem_budget: u64) -> Self {
        BuildOptions {
            threads: 0,
            mem_budget,
            tile_photons: None,
        }
    }
}

/// Build the map at `path` from `source`.
pub fn build_map(
    path: &Path,
    source: &dyn PhotonSource,
    options: &BuildOptions,
    progress: &dyn Progress,
) -> Result<WriteSummary> {
    let n = source.indices();
    // Pilot: evenly strided indices; its photons give the partition and the
    // expected number of stored photons. A probe of the first indices sizes
    // it so the pilot's positions take at most an eighth of the budget.
    let mut staged = Vec::new();
    let probe = n.min(1024);
    source.sample(0..probe, &mut staged);
    let per_index = (staged.len() as f64 / probe.max(1) as f64).max(1.0 / 64.0);
    let cap = (options.mem_budget / 8 / std::mem::size_of::<Vec3>() as u64) as f64;
    let pilot_n = n
        .min(PILOT_INDICES)
        .min((cap / per_index) as u64)
        .max(probe.min(n));
    // Trace the pilot in parallel: for an emitter it is real transport work.
    let pilot: Vec<Vec3> = {
        use rayon::prelude::*;
        let pool = crate::parallel::pool(options.threads)?;
        pool.install(|| {
            (0..pilot_n)
                .into_par_iter()
                .map_init(Vec::new, |buf, j| {
                    let i = j * n / pilot_n.max(1);
                    buf.clear();
                    source.sample(i..i + 1, buf);
                    buf.iter().map(|p| p.pos()).collect::<Vec<Vec3>>()
                })
                .flatten()
                .collect()
        })
    };
    let mut pilot = pilot;
    drop(staged);
    let expected = if pilot_n == 0 {
        0
    } else {
        (pilot.len() as u128 * n as u128 / pilot_n as u128) as u64
    };
    let mut plan = WriterPlan::new(options.mem_budget, expected)?;
    if let Some(t) = options.tile_photons {
        plan = plan.with_tile_photons(t);
    }
    let partition = Partition::from_pilot(&mut pilot, plan.cells_for(expected));
    drop(pilot);
    let mut writer = MapWriter::create(
        path,
        plan,
        partition,
        source.bands(),
        source.bounds(),
        source.provenance(),
    )?;

    let pool = crate::parallel::pool(options.threads)?;
    let (tx, rx) = crossbeam_channel::bounded::<Vec<StagedPhoton>>(CHANNEL_BATCHES);
    progress.stage("trace photons", n);
    let (write_result, _) = std::thread::scope(|scope| {
        let handle = scope.spawn(move || -> Result<MapWriter> {
            for batch in rx {
                writer.push(&batch)?;
            }
            Ok(writer)
        });
        let batches = n.div_ceil(BATCH_INDICES);
        // A send fails only when the writer stopped on an error; its error is
        // the one reported, so producers just stop.
        let produced = pool.install(|| {
            (0..batches).into_par_iter().try_for_each(|b| {
                let range = b * BATCH_INDICES..((b + 1) * BATCH_INDICES).min(n);
                let len = range.end - range.start;
                let mut out = Vec::with_capacity(len as usize);
                source.generate(range, &mut out);
                progress.advance(len);
                tx.send(out).map_err(|_| ())
            })
        });
        drop(tx);
        (handle.join().expect("writer thread panicked"), produced)
    });
    progress.finish();
    let writer = write_result?;
    writer.finish(&source.metadata(), progress)
}
