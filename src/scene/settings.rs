//! The `[estimate]` settings of a scene: the photon-map search and the two
//! bias compensations, with their defaults. The numerical behaviour of the
//! modes lives with the estimator (`estimate::boundary`, `estimate::spectral`,
//! `estimate::peak`); what they are called and what they default to is
//! defined here, once, for the scene file, the command line and reports:
//! serde and clap take the names from the same kebab-case rule, and
//! `as_str` (for messages and reports) is tested against both.

use std::fmt;

/// Photons in the local search.
pub const DEFAULT_K: usize = 64;
/// The expanded search of the spectral compensation, in multiples of `k`.
pub const DEFAULT_K_EXPANDED_PER_K: usize = 8;
/// Largest radius of a k-nearest search (m).
pub const DEFAULT_MAX_RADIUS_M: f64 = 2.0;
/// Ray-marching step in water (m).
pub const DEFAULT_STEP_M: f64 = 0.5;
/// Half-angle of the truncated forward peak (degrees) along rays looking up
/// or sideways, into the downwelling light and the sun's aureole (see
/// `estimate::peak` for the measurements behind it).
pub const DEFAULT_FORWARD_PEAK_DEG: f64 = 10.0;
/// The same along rays looking down, into the smooth upwelling light.
pub const DEFAULT_FORWARD_PEAK_DOWN_DEG: f64 = 20.0;

/// How the density estimate treats boundaries inside the search sphere.
/// Named in scene files and on the command line as `none`, `ellipsoid` or
/// `clipped-sphere`.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum BoundaryMode {
    /// Jensen's plain estimate: the full sphere.
    None,
    /// The adaptive (ellipsoid) distance and the octant-ellipsoid volume.
    Ellipsoid,
    /// Euclidean search, the sphere's volume clipped by the axial planes
    /// (the default).
    #[default]
    ClippedSphere,
}

impl BoundaryMode {
    /// Every mode, for ablation loops.
    pub const ALL: [BoundaryMode; 3] = [
        BoundaryMode::None,
        BoundaryMode::Ellipsoid,
        BoundaryMode::ClippedSphere,
    ];

    /// The name used in scene files and on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            BoundaryMode::None => "none",
            BoundaryMode::Ellipsoid => "ellipsoid",
            BoundaryMode::ClippedSphere => "clipped-sphere",
        }
    }
}

impl std::fmt::Display for BoundaryMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// How per-band radiance is formed from band-tagged photons. Named in scene
/// files and on the command line as `naive` or `compensated`.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    Hash,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum SpectralMode {
    /// Jensen's per-band estimate from the local search alone.
    Naive,
    /// The poster's compensation: level from the local search, spectral shape
    /// from the expanded one.
    #[default]
    Compensated,
}

impl SpectralMode {
    /// Every mode, in the order help text lists them.
    pub const ALL: [SpectralMode; 2] = [SpectralMode::Naive, SpectralMode::Compensated];

    /// The name used in scene files and on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            SpectralMode::Naive => "naive",
            SpectralMode::Compensated => "compensated",
        }
    }
}

impl fmt::Display for SpectralMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Which integrator renders the cube and the radiometers. Named in scene
/// files (`[render] integrator`) and on the command line as `photon-map` or
/// `path`.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    Hash,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum IntegratorMode {
    /// Ray marching with photon-map in-scatter estimates (the default).
    #[default]
    PhotonMap,
    /// Unbiased spectral backward path tracing with next-event estimation of
    /// the sun: the reference (`render::path`). Needs no photon map.
    Path,
}

impl IntegratorMode {
    /// Every mode, in the order help text lists them.
    pub const ALL: [IntegratorMode; 2] = [IntegratorMode::PhotonMap, IntegratorMode::Path];

    /// The name used in scene files and on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            IntegratorMode::PhotonMap => "photon-map",
            IntegratorMode::Path => "path",
        }
    }
}

impl fmt::Display for IntegratorMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Paths per radiometer reading of the path integrator, per sample per
/// pixel of the sensor (`[sensor] samples_per_pixel`).
pub const PATH_RADIOMETER_PATHS_PER_SPP: u64 = 1024;

/// The `[render]` settings of a scene.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct RenderSettings {
    pub integrator: IntegratorMode,
}

/// Radiance-estimate settings.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EstimateSettings {
    /// Photons in the local search.
    pub k: usize,
    /// Fixed search radius instead of k nearest (m).
    pub radius_m: Option<f64>,
    /// Largest radius of a k-nearest search (m).
    pub max_radius_m: f64,
    /// Photons in the expanded search of the spectral compensation.
    pub k_expanded: usize,
    /// Boundary-bias compensation.
    pub boundary: BoundaryMode,
    /// Spectral-bias compensation.
    pub spectral: SpectralMode,
    /// Ray-marching step in water (m).
    pub step_m: f64,
    /// Half-angle (degrees) of the forward peak of the phase functions that
    /// is treated as a delta in photon estimates along rays looking up or
    /// sideways (0 = exact; see `estimate::peak`).
    pub forward_peak_deg: f64,
    /// The same along rays looking down (into upwelling light).
    pub forward_peak_down_deg: f64,
    /// Node spacing (m) of a precomputed boundary-distance grid for volume
    /// estimates, or None to trace six rays per estimate.
    pub boundary_grid_m: Option<f64>,
}

impl EstimateSettings {
    /// The largest radius a volume search can have (m).
    pub fn largest_radius_m(&self) -> f64 {
        match self.radius_m {
            Some(r) => r * (self.k_expanded.max(self.k) as f64 / self.k as f64).cbrt(),
            None => self.max_radius_m,
        }
    }
}

#[cfg(test)]
mod tests;
