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
pub mod shard;
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
use tally::{PathTally, Totals};
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
        if scene.ground.is_some() {
            return Err(crate::Error::invalid(
                "emit",
                format!(
                    "scene '{}' is a Lambertian ground ([surface] kind = \"lambertian\"): no water, no photons to emit; render it",
                    scene.name
                ),
            ));
        }
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

    /// Trace photon `i`; appends what it stores to `out`, its tallies
    /// and fates to `tallies`.
    fn trace_one(
        &self,
        i: u64,
        tallies: &mut PathTally,
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
        tallies.clear();
        let t = trace::trace(
            self.scene,
            &self.grid,
            i,
            &mut rng,
            source,
            band,
            &self.photon_power,
            tallies,
            out,
        );
        (band, t)
    }

    /// Trace indices `range`, adding to the run totals.
    fn run(&self, range: Range<u64>, out: &mut Vec<StagedPhoton>) {
        let mut local = Totals::new(self.scene.bands.len(), self.scene.tally_depths.len());
        let mut tallies = PathTally::new(self.scene.tally_depths.len());
        for i in range {
            let (band, t) = self.trace_one(i, &mut tallies, out);
            local.record_path(band, &tallies);
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
        let mut tallies = PathTally::new(self.scene.tally_depths.len());
        for i in range {
            self.trace_one(i, &mut tallies, out);
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

#[cfg(test)]
mod tests;
