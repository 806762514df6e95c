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
/// Fewest source indices sampled to build the partition.
const PILOT_INDICES: u64 = 32_768;
/// Pilot positions wanted per partition cell. A cell holds the photons of
/// the space around its share of pilot positions, so its count scatters
/// about the target tile by about one over the square root of that share:
/// at three (the 10^9-photon built-in scene with [`PILOT_INDICES`] alone),
/// 997 of its 18 500 cells a layer outgrew two tiles and were split at the
/// end; at 16 the chance a cell holds twice its expectation is below 1 %.
pub const PILOT_PER_CELL: u64 = 16;

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

/// The pilot sample of a source: the positions of the photons stored by
/// evenly strided source indices, and how many indices it traced. It fixes
/// the partition and the expected number of stored photons; a probe of the
/// first indices sizes it: at least [`PILOT_INDICES`], enough for
/// [`PILOT_PER_CELL`] positions in each cell of the writer's partition,
/// and at most an eighth of the budget in positions. A pure function of
/// the source, the budget and the tile size, so every shard of a sharded
/// emission computes the same one.
pub struct Pilot {
    pub positions: Vec<Vec3>,
    /// Source indices traced for it.
    pub indices: u64,
}

impl Pilot {
    pub fn trace(source: &dyn PhotonSource, options: &BuildOptions) -> Result<Pilot> {
        let n = source.indices();
        let mut staged = Vec::new();
        let probe = n.min(1024);
        source.sample(0..probe, &mut staged);
        let per_index = (staged.len() as f64 / probe.max(1) as f64).max(1.0 / 64.0);
        let cap = (options.mem_budget / 8 / std::mem::size_of::<Vec3>() as u64) as f64;
        // The writer's cells for the probe's estimate of the stored photons
        // (none when the budget is too small to write: the writer says so).
        let expected = (per_index * n as f64) as u64;
        let cells = WriterPlan::new(options.mem_budget, expected)
            .map(|plan| match options.tile_photons {
                Some(t) => plan.with_tile_photons(t),
                None => plan,
            })
            .map_or(0, |plan| plan.cells_for(expected) as u64);
        let wanted = ((cells * PILOT_PER_CELL) as f64 / per_index).ceil() as u64;
        let pilot_n = n
            .min(PILOT_INDICES.max(wanted))
            .min((cap / per_index) as u64)
            .max(probe.min(n));
        // Trace the pilot in parallel: for an emitter it is real transport work.
        use rayon::prelude::*;
        let pool = crate::parallel::pool(options.threads)?;
        let positions = pool.install(|| {
            (0..pilot_n)
                .into_par_iter()
                .map_init(Vec::new, |buf, j| {
                    let i = (j as u128 * n as u128 / pilot_n.max(1) as u128) as u64;
                    buf.clear();
                    source.sample(i..i + 1, buf);
                    buf.iter().map(|p| p.pos()).collect::<Vec<Vec3>>()
                })
                .flatten()
                .collect()
        });
        Ok(Pilot {
            positions,
            indices: pilot_n,
        })
    }

    /// Stored photons expected from `n` source indices.
    fn expected(&self, n: u64) -> u64 {
        if self.indices == 0 {
            0
        } else {
            (self.positions.len() as u128 * n as u128 / self.indices as u128) as u64
        }
    }
}

/// What a map is made of, apart from its photons.
pub struct MapDescription {
    /// Source indices the photons come from.
    pub indices: u64,
    pub bands: BandGrid,
    pub bounds: Aabb,
    pub provenance: Provenance,
}

/// The writer for a map of `description`, planned and partitioned from
/// `pilot` within `options`' budget.
fn planned_writer(
    path: &Path,
    description: &MapDescription,
    pilot: Pilot,
    options: &BuildOptions,
) -> Result<MapWriter> {
    let expected = pilot.expected(description.indices);
    let mut plan = WriterPlan::new(options.mem_budget, expected)?.with_threads(options.threads);
    if let Some(t) = options.tile_photons {
        plan = plan.with_tile_photons(t);
    }
    let mut positions = pilot.positions;
    let partition = Partition::from_pilot(&mut positions, plan.cells_for(expected));
    drop(positions);
    MapWriter::create(
        path,
        plan,
        partition,
        description.bands.clone(),
        description.bounds,
        description.provenance.clone(),
    )
}

/// Build the map at `path` from photons already traced: `batches` yields
/// them in any order, `pilot` is the source's [`Pilot`] and `metadata` the
/// bytes recorded after them. The map is byte-identical to [`build_map`]'s
/// from the same source and budget, since the writer's result depends only
/// on the set of photons.
pub fn build_map_from_batches(
    path: &Path,
    description: &MapDescription,
    pilot: Pilot,
    batches: &mut dyn Iterator<Item = Result<Vec<StagedPhoton>>>,
    metadata: &[u8],
    options: &BuildOptions,
    progress: &dyn Progress,
) -> Result<WriteSummary> {
    let mut writer = planned_writer(path, description, pilot, options)?;
    progress.stage("merge photons", description.indices);
    for batch in batches {
        writer.push(&batch?)?;
    }
    progress.finish();
    writer.finish(metadata, progress)
}

/// Build the map at `path` from `source`.
pub fn build_map(
    path: &Path,
    source: &dyn PhotonSource,
    options: &BuildOptions,
    progress: &dyn Progress,
) -> Result<WriteSummary> {
    let n = source.indices();
    let pilot = Pilot::trace(source, options)?;
    let description = MapDescription {
        indices: n,
        bands: source.bands(),
        bounds: source.bounds(),
        provenance: source.provenance(),
    };
    let mut writer = planned_writer(path, &description, pilot, options)?;

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
                if progress.cancelled() {
                    return Err(());
                }
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
    // The producers stop early only on a writer's error (reported above)
    // or when the run is cancelled: a short map is never finished.
    crate::progress::check(progress)?;
    writer.finish(&source.metadata(), progress)
}
