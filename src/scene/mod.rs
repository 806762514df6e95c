//! The scene: what is simulated, read from TOML and validated.
//!
//! `Scene::parse` checks every value and resolves spectra to the band grid
//! (band averages with each band's Gaussian response), so the transport code
//! sees only per-band numbers. Errors name the file, the line and the key.
//! Relative file names (CSV spectra, height fields, meshes, grids) are
//! resolved against the scene file's directory.
//!
//! Conventions: metres, z up, mean sea surface at z = 0, depths positive
//! downward; x east and y north. The sun's azimuth (`[sun] azimuth_deg`) is
//! the direction *toward* the sun as a mathematical angle, counter-clockwise
//! from +x (east) toward +y (north), not a compass bearing: its compass
//! azimuth (clockwise from north, what ENVI headers and the report's
//! `sensor.sun_azimuth_deg` give) is 90 degrees minus it
//! ([`Sun::compass_azimuth_deg`]). Spectral irradiance in W m^-2 nm^-1.
//!
//! Not for: tracing light (see `emit`).

mod build;
mod land;
mod reflected_sky;
pub use land::Land;
mod emission_inputs;
pub mod file;
pub mod locate;
pub mod settings;
pub mod text;

pub use reflected_sky::{ReflectedSky, REFLECTED_SKY_FACETS};

pub use settings::{BoundaryMode, EstimateSettings, IntegratorMode, RenderSettings, SpectralMode};

use crate::error::Result;
use crate::geometry::{Geometry, SurfaceId};
use crate::optics::iop::WaterModel;
use crate::optics::phase::PhaseFunction;
use crate::optics::surface::SeaSurface;
use crate::spectral::BandGrid;
use glam::Vec3;
use std::path::{Path, PathBuf};

/// The built-in coastal scene (TOML).
pub const COASTAL_TOML: &str = include_str!("coastal.toml");

/// The sun: a collimated beam.
#[derive(Clone, Debug)]
pub struct Sun {
    pub zenith_rad: f64,
    pub azimuth_rad: f64,
    /// Direction of travel of sunlight (unit, pointing down).
    pub direction: Vec3,
    /// Direct normal spectral irradiance per band, W m^-2 nm^-1.
    pub irradiance: Vec<f64>,
}

impl Sun {
    /// Irradiance on a horizontal plane per band.
    pub fn horizontal_irradiance(&self, band: usize) -> f64 {
        self.irradiance[band] * self.zenith_rad.cos()
    }

    /// The compass azimuth of the direction toward the sun (degrees
    /// clockwise from north, in [0, 360)): 90 degrees minus the scene's
    /// angle, which runs counter-clockwise from east.
    pub fn compass_azimuth_deg(&self) -> f64 {
        (90.0 - self.azimuth_rad.to_degrees()).rem_euclid(360.0)
    }
}

/// The sky: isotropic diffuse radiance.
#[derive(Clone, Debug)]
pub struct Sky {
    /// Horizontal spectral irradiance from the sky per band (pi x the
    /// radiance of an isotropic sky of that irradiance).
    pub irradiance: Vec<f64>,
    /// The radiance's distribution over the sky: L(s) = irradiance / pi x
    /// `model.relative(s)`.
    pub model: crate::optics::sky::SkyModel,
}

/// An `[atmosphere]` and the light it brings to the surface.
#[derive(Clone, Debug)]
pub struct AtmosphereLight {
    pub spec: crate::optics::atmosphere::AtmosphereSpec,
    /// `[sun] day_of_year`, if given (the top's irradiance is scaled by its
    /// Earth–Sun distance).
    pub day_of_year: Option<f64>,
    /// Photons per band traced for the sky, and the seed of their streams.
    pub sky_photons: u64,
    pub sky_seed: u64,
    /// `[atmosphere] sea_coupling`: the sky holds the light the sea sends
    /// up that the air returns (`render::sea_air`).
    pub sea_coupling: bool,
    /// Per band.
    pub bands: Vec<BandAtmosphere>,
    /// The sky's mean radiance per band and cell of the sky grid
    /// (`optics::atmosphere::transport`), W m^-2 sr^-1 nm^-1.
    pub sky_radiance: Vec<Vec<f64>>,
    /// Each band's column, for the renderers' paths through the air.
    pub columns: Vec<crate::optics::atmosphere::Column>,
    /// With `[sensor] altitude_m`: the air between the ground and the
    /// sensor.
    pub view: Option<ViewLight>,
}

impl AtmosphereLight {
    /// The bytes it holds on the heap: the sky per band, and each band's
    /// column with its phase functions' tables.
    pub fn heap_bytes(&self) -> u64 {
        let f = std::mem::size_of::<f64>() as u64;
        let sky: u64 = self.sky_radiance.iter().map(|s| s.len() as u64 * f).sum();
        let columns: u64 = self
            .columns
            .iter()
            .map(|c| {
                (c.layers.len() * std::mem::size_of::<crate::optics::atmosphere::Layer>()) as u64
                    + c.depth.len() as u64 * f
                    + c.phase_bytes()
            })
            .sum();
        let bands = (self.bands.len() * std::mem::size_of::<BandAtmosphere>()) as u64;
        sky + columns + bands
    }
}

/// What the air between the ground and a sensor above it does, per band,
/// along the sensor's view.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewLight {
    pub altitude_m: f64,
    /// Direct transmittance from the ground to the sensor.
    pub transmittance: Vec<f64>,
    /// Path radiance at the sensor (light scattered into the view that
    /// never reached the surface; W m^-2 sr^-1 nm^-1) and its standard
    /// error.
    pub path_radiance: Vec<f64>,
    pub path_radiance_se: Vec<f64>,
    /// Total transmittance from a Lambertian ground to the sensor along
    /// its view, direct and scattered (t_up), and its standard error.
    pub transmittance_up: Vec<f64>,
    pub transmittance_up_se: Vec<f64>,
}

/// The surface beyond the domain (`[surroundings]`).
#[derive(Clone, Debug)]
pub enum Surroundings {
    /// Land of this reflectance per band (`kind = "lambertian"`), with
    /// which the sky also exchanges light.
    Lambertian(Vec<f64>),
    /// The domain's own mean radiance per direction (`kind = "mean"`): the
    /// domain sits in a surface that looks like its average.
    Mean,
    /// Deep water of its own IOPs (`kind = "water"`): this scene with its
    /// `[water]` replaced and its floor, land, targets and radiometers
    /// taken out, whose radiance leaving the surface per direction the
    /// air sees beyond the domain (`render::air`).
    Water(std::sync::Arc<Scene>),
}

impl PartialEq for Surroundings {
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (Surroundings::Lambertian(a), Surroundings::Lambertian(b)) => a == b,
            (Surroundings::Mean, Surroundings::Mean) => true,
            (Surroundings::Water(a), Surroundings::Water(b)) => std::sync::Arc::ptr_eq(a, b),
            _ => false,
        }
    }
}

impl Surroundings {
    /// The land's reflectance per band, for Lambertian surroundings.
    pub fn reflectance(&self) -> Option<&[f64]> {
        match self {
            Surroundings::Lambertian(r) => Some(r),
            Surroundings::Mean | Surroundings::Water(_) => None,
        }
    }
}

/// One band of an atmosphere: its optical depths and the light at the
/// surface and the top (irradiances in W m^-2 nm^-1, on a horizontal
/// plane, over a black surface).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BandAtmosphere {
    pub nm: f64,
    pub tau: crate::optics::atmosphere::Totals,
    /// exp(-tau / mu0).
    pub direct_transmittance: f64,
    /// Beam-normal irradiance at the top.
    pub toa_irradiance: f64,
    /// E_d(0+): the sun's beam and the sky.
    pub direct: f64,
    pub diffuse: f64,
    /// The sky's irradiance counted by the photons reaching the surface
    /// (an independent estimate of `diffuse`) and its standard error.
    pub diffuse_flux: f64,
    pub diffuse_flux_se: f64,
    /// Leaving the top of the atmosphere, and absorbed in the air.
    pub up_at_top: f64,
    pub absorbed: f64,
    /// Over a Lambertian ground (`Scene::ground`) or land all around, and
    /// over the sea with `sea_coupling`: the air's spherical albedo s for
    /// the light the surface sends up, the share of its upward irradiance
    /// the air sends back down (from the photons that return), with its
    /// standard error. The irradiances above then hold every order of
    /// reflection between the surface and the air; 0 over a black
    /// surface.
    #[serde(default)]
    pub spherical_albedo: f64,
    #[serde(default)]
    pub spherical_albedo_se: f64,
    /// Over the sea with `sea_coupling`: the sea's albedo, the share of
    /// E_d(0+) over a black surface that its surface sends up (sun glint,
    /// reflected sky and water-leaving light; 0 otherwise).
    #[serde(default)]
    pub surface_albedo: f64,
    /// Over the sea with `sea_coupling`: the irradiance the sea sends up
    /// into the air, every order (A E_d(0+)), and its standard error.
    #[serde(default)]
    pub surface_up: f64,
    #[serde(default)]
    pub surface_up_se: f64,
}

impl BandAtmosphere {
    /// The total transmittance from the top of the atmosphere to the
    /// surface, direct and diffuse: E_d(0+) / (E_0 mu0), with `mu0` the
    /// cosine of the sun's zenith (0 where no sunlight arrives at the top).
    pub fn t_down(&self, mu0: f64) -> f64 {
        let top = self.toa_irradiance * mu0;
        if top > 0.0 {
            (self.direct + self.diffuse) / top
        } else {
            0.0
        }
    }
}

/// A horizontal rectangle (m) over the domain: where paths entering the
/// water over a target split.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Footprint {
    pub min: [f64; 2],
    pub max: [f64; 2],
}

impl Footprint {
    /// Its area within `domain` (m^2).
    pub fn area_in(&self, domain: &Domain) -> f64 {
        let side = |i: usize| (self.max[i] - self.min[i]).clamp(0.0, domain.size_m[i]);
        if domain.periodic {
            side(0) * side(1)
        } else {
            let clip =
                |i: usize| (self.max[i].min(domain.size_m[i]) - self.min[i].max(0.0)).max(0.0);
            clip(0) * clip(1)
        }
    }

    /// Whether the surface point (x, y) of `domain` lies within it; across
    /// periodic edges, also where one of its images does.
    pub fn contains(&self, domain: &Domain, x: f64, y: f64) -> bool {
        let axis = |v: f64, lo: f64, hi: f64, size: f64| {
            if !domain.periodic {
                (lo..=hi).contains(&v)
            } else if hi - lo >= size {
                true
            } else {
                (v - lo).rem_euclid(size) <= hi - lo
            }
        };
        axis(x, self.min[0], self.max[0], domain.size_m[0])
            && axis(y, self.min[1], self.max[1], domain.size_m[1])
    }
}

/// The horizontal domain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Domain {
    pub size_m: [f64; 2],
    /// Periodic edges wrap photons around; open edges lose them.
    pub periodic: bool,
}

impl Domain {
    pub fn area_m2(&self) -> f64 {
        self.size_m[0] * self.size_m[1]
    }

    /// Distance along `dir` from `p` (inside) to the domain's side walls.
    pub fn edge_distance(&self, p: Vec3, dir: Vec3) -> f64 {
        let along = |x: f32, d: f32, size: f64| -> f64 {
            if d > 0.0 {
                (size - x as f64) / d as f64
            } else if d < 0.0 {
                -(x as f64) / d as f64
            } else {
                f64::INFINITY
            }
        };
        along(p.x, dir.x, self.size_m[0])
            .min(along(p.y, dir.y, self.size_m[1]))
            .max(0.0)
    }

    /// Distance along `dir` from `p` (in the water) up to the mean surface
    /// z = 0 (infinite for a ray not going up).
    pub fn surface_distance(p: Vec3, dir: Vec3) -> f64 {
        if dir.z > 0.0 {
            (-p.z / dir.z) as f64
        } else {
            f64::INFINITY
        }
    }

    /// Move a point that reached a side wall, travelling along `dir`, to the
    /// opposite wall.
    pub fn wrap(&self, p: Vec3, dir: Vec3) -> Vec3 {
        let w = |x: f32, d: f32, size: f64| -> f32 {
            let s = size as f32;
            if d > 0.0 && x >= s * (1.0 - 1e-6) {
                0.0
            } else if d < 0.0 && x <= s * 1e-6 {
                s
            } else {
                x.clamp(0.0, s)
            }
        };
        Vec3::new(
            w(p.x, dir.x, self.size_m[0]),
            w(p.y, dir.y, self.size_m[1]),
            p.z,
        )
    }

    /// The point of the domain that `p` stands for: `p` itself inside,
    /// its periodic image when edges are periodic, `None` outside an open
    /// domain.
    pub fn image(&self, p: Vec3) -> Option<Vec3> {
        let [sx, sy] = self.size_m;
        let inside = |x: f32, s: f64| (0.0..=s).contains(&(x as f64));
        if inside(p.x, sx) && inside(p.y, sy) {
            return Some(p);
        }
        if !self.periodic {
            return None;
        }
        let m = |x: f32, s: f64| (x as f64).rem_euclid(s) as f32;
        Some(Vec3::new(m(p.x, sx), m(p.y, sy), p.z))
    }
}

/// A rectangle of the floor with its own reflectance.
#[derive(Clone, Debug)]
pub struct Patch {
    pub min_m: [f64; 2],
    pub max_m: [f64; 2],
    pub reflectance: Vec<f64>,
}

/// The sea floor's reflectance (its shape is in the geometry).
#[derive(Clone, Debug)]
pub struct Bottom {
    pub reflectance: Vec<f64>,
    pub patches: Vec<Patch>,
}

/// Reflecting surface id of the floor in the geometry.
pub const FLOOR: SurfaceId = 0;

/// The camera.
#[derive(Clone, Debug, PartialEq)]
pub enum SensorKind {
    /// Looking straight down; pixel (0, 0) is at the low-x, high-y corner.
    Orthographic { gsd_m: f64, center_m: [f64; 2] },
    /// A pinhole camera above the water.
    Pinhole {
        position: Vec3,
        look_at: Vec3,
        fov_deg: f64,
    },
}

/// The imaging sensor.
#[derive(Clone, Debug, PartialEq)]
pub struct Sensor {
    pub kind: SensorKind,
    /// Image size [samples (x), lines (y)].
    pub pixels: [usize; 2],
    pub samples_per_pixel: u32,
    /// A real sensor whose bands the cubes are also written in
    /// (`[sensor] response`).
    pub response: Option<crate::spectral::response::SpectralResponse>,
    /// Orthographic: the unit direction from the ground toward the sensor
    /// (+z: nadir view).
    pub toward: Vec3,
    /// Height of the sensor above the sea (m), seeing through the
    /// `[atmosphere]`; none: just above the surface.
    pub altitude_m: Option<f64>,
}

/// An in-water (or above-water, at negative depth) radiance meter.
#[derive(Clone, Debug, PartialEq)]
pub struct Radiometer {
    pub depth_m: f64,
    /// "nadir", "zenith" or "x,y,z".
    pub view_name: String,
    /// Unit direction the instrument looks along (it measures light
    /// travelling the opposite way).
    pub view: Vec3,
    pub position_m: [f64; 2],
    /// Half-angle of the field of view around `view` (degrees; 0: one
    /// direction). The reading is the field's radiance averaged with the
    /// weight cos(angle from `view`), as a flat detector behind a circular
    /// aperture sees it and as the emission's Lu and Ld tallies count it.
    pub half_angle_deg: f64,
}

/// A validated scene.
#[derive(Debug)]
pub struct Scene {
    pub name: String,
    pub seed: u64,
    pub bands: BandGrid,
    pub sun: Sun,
    pub sky: Sky,
    /// The atmosphere and what it did to the light (`[atmosphere]`); the
    /// sun and sky above are then the light at the surface.
    pub atmosphere: Option<std::sync::Arc<AtmosphereLight>>,
    /// The facets' mean reflected sky along an orthographic sensor's view
    /// over a rough sea, per band, computed on first use
    /// ([`Scene::reflected_sky`]).
    pub reflected_sky: std::sync::OnceLock<Option<ReflectedSky>>,
    /// The sea surface, its index the reference the renderers trace
    /// geometry with (the mean of `water_index`).
    pub surface: SeaSurface,
    /// `[surface] kind = "lambertian"`: no water, a Lambertian ground at
    /// z = 0 of this reflectance per band (`render::ground`).
    pub ground: Option<Vec<f64>>,
    /// `[surroundings]`: the surface all around the domain, as the air
    /// sees it (adjoint paths that meet the ground beyond the domain);
    /// none: the domain repeats.
    pub surroundings: Option<Surroundings>,
    /// Refractive index of the water per band (`[surface]
    /// refractive_index`: constant, or Quan & Fry 1995).
    pub water_index: Vec<f64>,
    pub domain: Domain,
    pub water: WaterModel,
    /// Phase function of particle scattering (all scattering in explicit-IOP mode).
    pub particle_phase: PhaseFunction,
    /// Phase function of pure-water scattering.
    pub water_phase: PhaseFunction,
    /// Inelastic light between the bands (`[water] raman`,
    /// `[water.fluorescence]`), or None.
    pub inelastic: Option<crate::optics::inelastic::Inelastic>,
    pub bottom: Option<Bottom>,
    /// The floor above the water line, if it rises above it.
    pub land: Option<Land>,
    /// Lambertian reflectance per band of each target (surface id 1 + index).
    pub target_reflectance: Vec<Vec<f64>>,
    /// The bounds of each target's triangles (surface id 1 + index).
    pub target_extents: Vec<crate::bounds::Aabb>,
    /// Copies a path splits into where it enters the water within one of
    /// [`Scene::split_footprints`] (1: no splitting; see `emit::trace`).
    pub target_split: usize,
    /// The footprints over the targets where entering paths split (empty
    /// without targets or splitting).
    pub split_footprints: Vec<Footprint>,
    pub geometry: Geometry,
    pub photons: u64,
    pub store_direct: bool,
    /// Copies a photon path splits into when it first turns upward (1: no
    /// splitting; see `emit::trace`).
    pub upward_split: usize,
    /// Depths (m, >= 0) of the irradiance tallies; 0 is just below the surface.
    pub tally_depths: Vec<f64>,
    pub sensor: Sensor,
    pub radiometers: Vec<Radiometer>,
    pub estimate: EstimateSettings,
    /// `[render]`: which integrator renders.
    pub render: RenderSettings,
    /// `[georef]`: the scene's frame on a map.
    pub georef: Georef,
    /// Every file the scene names (spectra, meshes, height fields, grids,
    /// phase tables), sorted: inputs of the emission's provenance.
    pub inputs: Vec<PathBuf>,
    /// The text, path and overrides it was built from, to build it again
    /// elsewhere (the parts of a render split over machines).
    pub origin: SceneOrigin,
}

/// What a scene was built from: [`Scene::parse`]'s arguments.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SceneOrigin {
    pub text: String,
    pub path: PathBuf,
    pub overrides: Overrides,
}

impl SceneOrigin {
    /// Build the scene again (relative file names resolve as they did).
    pub fn build(&self) -> Result<Scene> {
        Scene::parse(&self.text, &self.path, &self.overrides)
    }
}

/// Where the scene's frame (x east, y north, m) sits on a map: the map
/// coordinates of its origin, and the map's CRS.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Georef {
    /// Easting and northing (m) of scene x = 0, y = 0.
    pub origin_m: [f64; 2],
    /// EPSG code of a WGS 84 / UTM zone, or None for a local metric frame.
    pub epsg: Option<u32>,
}

impl Georef {
    /// The UTM zone and hemisphere (true: north) of the EPSG code.
    pub fn utm_zone(&self) -> Option<(u32, bool)> {
        match self.epsg? {
            c @ 32601..=32660 => Some((c - 32600, true)),
            c @ 32701..=32760 => Some((c - 32700, false)),
            _ => None,
        }
    }
}

/// Values the command line may override before validation.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Overrides {
    pub photons: Option<u64>,
    pub bands: Option<usize>,
    pub seed: Option<u64>,
    pub boundary: Option<BoundaryMode>,
    pub spectral: Option<SpectralMode>,
    pub integrator: Option<IntegratorMode>,
    /// `[sensor] samples_per_pixel`.
    pub samples_per_pixel: Option<u32>,
    /// Inelastic light on or off (`--inelastic`): on turns on Raman
    /// scattering and, in water given by its constituents, chlorophyll
    /// (at the scene's quantum yield, or 0.01) and CDOM fluorescence; off
    /// turns them all off.
    #[serde(default)]
    pub inelastic: Option<bool>,
    /// The sensor sees from just above the surface (`--no-atmosphere`):
    /// `[sensor] altitude_m` is dropped, and an `[atmosphere]` still
    /// lights the sea. Nothing changes for a scene without one.
    #[serde(default)]
    pub no_atmosphere: bool,
}

impl Scene {
    /// The scene's atmosphere as JSON (`littoral scene atmosphere`), none
    /// without one: per band the layers, the light at the surface and the
    /// sky per cell (over a Lambertian ground its reflectance, and the sky
    /// with the light it returns); with `toa` also the radiance leaving
    /// the top over a black surface (the sky's photons traced again, from
    /// the same streams).
    pub fn atmosphere_json(&self, toa: bool) -> Option<serde_json::Value> {
        use crate::optics::atmosphere::{transport, RayleighSetting};
        let a = self.atmosphere.as_ref()?;
        let spec = &a.spec;
        let bands: Vec<serde_json::Value> = a
            .bands
            .iter()
            .enumerate()
            .map(|(b, band)| {
                let column = &a.columns[b];
                let toa_radiance = toa.then(|| {
                    let l = transport::band_light(
                        column,
                        self.sun.zenith_rad,
                        a.sky_photons,
                        a.sky_seed,
                        b as u64,
                        true,
                    );
                    let f0 = band.toa_irradiance;
                    l.toa
                        .unwrap_or_default()
                        .iter()
                        .map(|v| v * f0)
                        .collect::<Vec<_>>()
                });
                let layers: Vec<serde_json::Value> = column
                    .layers
                    .iter()
                    .map(|l| {
                        serde_json::json!({
                            "bottom_km": l.bottom_km, "top_km": l.top_km,
                            "rayleigh": l.rayleigh,
                            "aerosol_scattering": l.aerosol_scattering,
                            "aerosol_absorption": l.aerosol_absorption,
                            "ozone": l.ozone, "gas": l.gas,
                        })
                    })
                    .collect();
                let q = match column.rayleigh_phase {
                    crate::optics::phase::PhaseFunction::Rayleigh { q } => q,
                    _ => 1.0,
                };
                serde_json::json!({
                    "band": band,
                    "rayleigh_q": q,
                    "layers": layers,
                    "sky_radiance": a.sky_radiance[b],
                    "toa_radiance": toa_radiance,
                    "ground_reflectance": self.ground.as_ref().map(|g| g[b]),
                    "aerosol_phase": spec.aerosol.and_then(|x| {
                        let m = x.named?;
                        let (lo, hi) = m.range_nm();
                        let at = m.at(column.nm.clamp(lo, hi))?;
                        Some(serde_json::json!({ "angles_deg": m.angles_deg, "values": at.phase }))
                    }),
                })
            })
            .collect();
        let rayleigh = match spec.rayleigh {
            RayleighSetting::Standard => serde_json::json!("standard"),
            RayleighSetting::Tau(t) => serde_json::json!({ "tau": t }),
            RayleighSetting::Off => serde_json::json!("off"),
        };
        let aerosol = spec.aerosol.map(|x| {
            let (scale_height_km, top_km) = match x.height {
                crate::optics::atmosphere::AerosolHeight::ScaleHeight(h) => (Some(h), None),
                crate::optics::atmosphere::AerosolHeight::Top(t) => (None, Some(t)),
            };
            serde_json::json!({
                "model": x.named.map_or("custom", |m| m.name),
                "tau_550": x.tau_550, "angstrom": x.angstrom, "ssa": x.ssa, "g": x.g,
                "scale_height_km": scale_height_km, "top_km": top_km,
            })
        });
        Some(serde_json::json!({
            "profile": spec.profile.name,
            "surface_pressure_hpa": spec.surface_pressure_hpa,
            "ozone_du": spec.ozone_du,
            "rayleigh": rayleigh,
            "aerosol": aerosol,
            "sun_zenith_deg": self.sun.zenith_rad.to_degrees(),
            "day_of_year": a.day_of_year,
            "sky_photons": a.sky_photons,
            "sky_grid": {
                "zenith_bins": transport::ZENITH_BINS,
                "azimuth_bins": transport::AZIMUTH_BINS,
                "zenith_step_deg": 90.0 / transport::ZENITH_BINS as f64,
                "azimuth_step_deg": 180.0 / transport::AZIMUTH_BINS as f64,
                "cells": "zenith-major; sky: the zenith angle of the sky element and its azimuth from the sun's; top: the zenith angle of the travel direction and its azimuth from the direction toward the sun",
            },
            "bands": bands,
            "view": a.view.as_ref().map(|v| {
                let toward = self.sensor.toward.as_dvec3();
                let phi = (toward.y.atan2(toward.x) - self.sun.azimuth_rad).to_degrees();
                serde_json::json!({
                    "altitude_m": v.altitude_m,
                    "view_zenith_deg": toward.z.clamp(-1.0, 1.0).acos().to_degrees(),
                    "view_azimuth_from_sun_deg": phi.rem_euclid(360.0),
                    "depth": a.columns.iter().map(|c| c.depth_at(v.altitude_m * 1e-3)).collect::<Vec<_>>(),
                    "transmittance": v.transmittance,
                    "path_radiance": v.path_radiance,
                    "path_radiance_se": v.path_radiance_se,
                    "transmittance_up": v.transmittance_up,
                    "transmittance_up_se": v.transmittance_up_se,
                })
            }),
        }))
    }

    /// Paths traced per path emitted, on average, from splitting over the
    /// targets: 1 + (target_split - 1) x the share of the domain their
    /// footprints cover (overlapping footprints counted twice, at most the
    /// whole domain).
    pub fn target_split_gain(&self) -> f64 {
        let covered: f64 = self
            .split_footprints
            .iter()
            .map(|f| f.area_in(&self.domain))
            .sum();
        let share = (covered / self.domain.area_m2()).min(1.0);
        1.0 + (self.target_split.max(1) - 1) as f64 * share
    }

    /// Parse and validate scene `text`; `path` names it in errors and
    /// anchors relative file names.
    pub fn parse(text: &str, path: &Path, overrides: &Overrides) -> Result<Scene> {
        let mut scene = build::build(text, path, overrides)?;
        // The sky over the sea: the light it sends up that the air returns.
        crate::render::sea_air::couple(&mut scene)?;
        Ok(scene)
    }

    /// Read, parse and validate the scene file at `path`.
    pub fn load(path: &Path, overrides: &Overrides) -> Result<Scene> {
        let text = std::fs::read_to_string(path).map_err(|e| crate::Error::io(path, "read", e))?;
        Scene::parse(&text, path, overrides)
    }

    /// The built-in coastal scene.
    pub fn coastal(overrides: &Overrides) -> Result<Scene> {
        Scene::parse(
            COASTAL_TOML,
            Path::new("<built-in coastal scene>"),
            overrides,
        )
    }

    /// One line for `littoral scene check`: bands, photons, triangles, tallies.
    pub fn summary(&self) -> String {
        let c = self.bands.centers_nm();
        if self.ground.is_some() {
            return format!(
                "scene '{}' is valid: {} bands {:.1}-{:.1} nm, a Lambertian ground (no water)",
                self.name,
                c.len(),
                c[0],
                c[c.len() - 1],
            );
        }
        format!(
            "scene '{}' is valid: {} bands {:.1}-{:.1} nm, {} photons, {} triangles, {} tally depths",
            self.name,
            c.len(),
            c[0],
            c[c.len() - 1],
            self.photons,
            self.geometry.triangle_count(),
            self.tally_depths.len()
        )
    }

    /// True when nothing in the scene varies across the domain: periodic
    /// edges, no floor and no target, and water whose IOPs vary with depth
    /// alone. The light field then depends on depth alone (the band-shape
    /// grid resolves only depth).
    pub fn horizontally_uniform(&self) -> bool {
        self.domain.periodic
            && self.bottom.is_none()
            && self.target_reflectance.is_empty()
            && self.water.is_horizontally_uniform()
    }

    /// Lambertian reflectance of `surface` at `p` in `band`.
    pub fn reflectance(&self, surface: SurfaceId, p: Vec3, band: usize) -> f64 {
        if surface == FLOOR {
            if let Some(land) = self.land.as_ref().filter(|_| p.z > 0.0) {
                return land.reflectance[band];
            }
            let Some(b) = &self.bottom else { return 0.0 };
            let (x, y) = (p.x as f64, p.y as f64);
            b.patches
                .iter()
                .find(|q| x >= q.min_m[0] && x < q.max_m[0] && y >= q.min_m[1] && y < q.max_m[1])
                .map_or(b.reflectance[band], |q| q.reflectance[band])
        } else {
            self.target_reflectance
                .get(surface as usize - 1)
                .map_or(0.0, |r| r[band])
        }
    }

    /// Total horizontal spectral irradiance (sun + sky) per band above the surface.
    /// The sea surface as light of `band` meets it: its own refractive index.
    pub fn surface_in(&self, band: usize) -> SeaSurface {
        SeaSurface {
            n_water: self.water_index[band],
            ..self.surface
        }
    }

    /// True when the refractive index varies between bands.
    pub fn dispersive(&self) -> bool {
        self.water_index.iter().any(|&n| n != self.surface.n_water)
    }

    pub fn incident_irradiance(&self, band: usize) -> f64 {
        self.sun.horizontal_irradiance(band) + self.sky.irradiance[band]
    }
}
