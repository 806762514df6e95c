//! Synthetic photon maps for tests, benchmarks and low-memory CI runs.
//!
//! Not physics: positions, directions and bands are drawn from simple
//! distributions, keyed to the photon index so that a map is a pure function
//! of (seed, count, bands, distribution).
//!
//! - `uniform`: positions uniform in the domain box, directions uniform on
//!   the sphere.
//! - `water`: what a coastal map looks like — 75 % of photons in the water
//!   column with depth exponential (scale 2 m) below the surface, directions
//!   leaning downward (volume layer); 25 % on a flat floor at the domain's
//!   bottom, arriving from above (surface layer). Powers take the two values a Russian-roulette emission from
//!   sun and sky gives (equal power per source).

use crate::bounds::Aabb;
use crate::photon::{volume_layer, Photon, LAYER_SURFACE};
use crate::rng::Pcg32;
use crate::spectral::BandGrid;
use crate::store::{PhotonSource, StagedPhoton};
use glam::Vec3;
use std::ops::Range;

/// Spatial distribution of synthetic photons.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Distribution {
    Uniform,
    Water,
}

/// A synthetic photon source.
#[derive(Clone, Debug)]
pub struct SynthSource {
    pub photons: u64,
    pub bands: BandGrid,
    pub seed: u64,
    pub distribution: Distribution,
    pub domain: Aabb,
}

/// Depth scale of the `water` distribution (m).
pub const WATER_DEPTH_SCALE_M: f32 = 2.0;
/// Share of `water` photons on the floor.
pub const WATER_FLOOR_SHARE: f32 = 0.25;
/// Share of `water` photons that came from the sky rather than the sun.
pub const WATER_SKY_SHARE: f32 = 0.15;

impl SynthSource {
    /// The default synthetic domain: 100 m x 100 m, 10 m deep, surface at z = 0.
    pub fn new(
        photons: u64,
        bands: usize,
        seed: u64,
        distribution: Distribution,
    ) -> crate::Result<Self> {
        Ok(SynthSource {
            photons,
            bands: BandGrid::even(400.0, 700.0, bands)?,
            seed,
            distribution,
            domain: Aabb {
                min: Vec3::new(0.0, 0.0, -10.0),
                max: Vec3::new(100.0, 100.0, 0.0),
            },
        })
    }

    /// Photon `i`, as stored.
    pub fn photon(&self, i: u64) -> Photon {
        self.photon_and_layer(i).0
    }

    /// Photon `i` and its layer: floor photons of `water` are surface photons.
    pub fn photon_and_layer(&self, i: u64) -> (Photon, u16) {
        let mut rng = Pcg32::new(self.seed, i);
        let d = &self.domain;
        let ext = d.max - d.min;
        let x = d.min.x + ext.x * rng.uniform_f32();
        let y = d.min.y + ext.y * rng.uniform_f32();
        let band = rng.below(self.bands.len() as u32) as u16;
        let nb = self.bands.len() as f32 / self.photons.max(1) as f32;
        let group = crate::photon::group_of_path(i);
        match self.distribution {
            Distribution::Uniform => {
                let position = Vec3::new(x, y, d.min.z + ext.z * rng.uniform_f32());
                let direction = uniform_sphere(&mut rng);
                (
                    Photon {
                        position,
                        direction,
                        band,
                        power: nb,
                        group,
                    },
                    volume_layer(direction),
                )
            }
            Distribution::Water => {
                let on_floor = rng.uniform_f32() < WATER_FLOOR_SHARE;
                let from_sky = rng.uniform_f32() < WATER_SKY_SHARE;
                let (z, mut dir) = if on_floor {
                    let mut w = uniform_sphere(&mut rng);
                    w.z = -w.z.abs();
                    (d.min.z, w)
                } else {
                    let depth = -(1.0 - rng.uniform_f32()).ln() * WATER_DEPTH_SCALE_M;
                    let z = (d.max.z - depth).max(d.min.z + 1e-3);
                    (z, uniform_sphere(&mut rng))
                };
                if !on_floor && dir.z > 0.0 && rng.uniform_f32() < 0.6 {
                    dir.z = -dir.z; // downwelling light dominates
                }
                let layer = if on_floor {
                    LAYER_SURFACE
                } else {
                    volume_layer(dir)
                };
                (
                    Photon {
                        position: Vec3::new(x, y, z),
                        direction: dir,
                        band,
                        power: if from_sky { 0.4 * nb } else { nb },
                        group,
                    },
                    layer,
                )
            }
        }
    }
}

fn uniform_sphere(rng: &mut Pcg32) -> Vec3 {
    let z = 1.0 - 2.0 * rng.uniform_f32();
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * rng.uniform_f32();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

impl PhotonSource for SynthSource {
    fn indices(&self) -> u64 {
        self.photons
    }

    fn generate(&self, range: Range<u64>, out: &mut Vec<StagedPhoton>) {
        out.extend(range.map(|i| {
            let (photon, layer) = self.photon_and_layer(i);
            StagedPhoton::new(&photon, layer)
        }));
    }

    fn bands(&self) -> BandGrid {
        self.bands.clone()
    }

    fn bounds(&self) -> Aabb {
        self.domain
    }

    fn provenance(&self) -> crate::provenance::Provenance {
        let mut b = crate::provenance::ProvenanceBuilder::new();
        b.value("source", "synthetic")
            .value("photons", self.photons)
            .value("bands", self.bands.len())
            .value("seed", self.seed)
            .value("distribution", format!("{:?}", self.distribution))
            .part("band_grid", format!("{:?}", self.bands).as_bytes())
            .part("domain", format!("{:?}", self.domain).as_bytes());
        b.finish()
    }

    /// A description of the synthetic source, as JSON.
    fn metadata(&self) -> Vec<u8> {
        serde_json::json!({
            "source": "synthetic",
            "distribution": format!("{:?}", self.distribution).to_lowercase(),
            "photons": self.photons,
            "bands": self.bands.len(),
            "seed": self.seed,
        })
        .to_string()
        .into_bytes()
    }
}
