//! The `[estimate]` settings of a scene: the photon-map search and the two
//! bias compensations, with their defaults. The numerical behaviour of the
//! modes lives with the estimator (`estimate::boundary`, `estimate::spectral`,
//! `estimate::peak`); what they are called and what they default to is
//! defined here, once, for the scene file, the command line and reports:
//! serde and clap take the names from the same kebab-case rule, and
//! `as_str` (for messages and reports) is tested against both.

use std::fmt;

/// Photons in the local search at [`POLICY_PHOTONS`] traced photons (see
/// [`policy_k`]).
pub const DEFAULT_K: usize = 200;
/// The expanded search, in multiples of `k`, when not set.
pub const DEFAULT_K_EXPANDED_PER_K: usize = 10;
/// The traced photon count at which the search-size policy gives
/// [`DEFAULT_K`].
pub const POLICY_PHOTONS: f64 = 4.0e6;

/// The search-size policy: photons in the local search for `photons`
/// traced photons when `[estimate] k` is not given,
/// `k = DEFAULT_K (photons / POLICY_PHOTONS)^(4/7)`, within 16..=100000.
/// A k-nearest estimate's bias grows with its radius (as h^2) and its
/// variance falls with its count (as 1 / k, k ~ N h^3): balancing the two
/// gives h ~ N^(-1/7), so k ~ N^(4/7) photons. Both errors then fall as
/// photons are added; a fixed k would leave the variance where it is.
pub fn policy_k(photons: u64) -> usize {
    let k = DEFAULT_K as f64 * (photons as f64 / POLICY_PHOTONS).powf(4.0 / 7.0);
    (k.round() as usize).clamp(POLICY_K_MIN, 100_000)
}
/// The fewest photons the search-size policy gives a local search.
pub const POLICY_K_MIN: usize = 16;
/// Copies a photon path splits into when it first turns upward
/// (`[photons] upward_split`; see `emit::trace`).
pub const DEFAULT_UPWARD_SPLIT: u32 = 4;
/// Copies a photon path splits into where it enters the water over a
/// target (`[photons] target_split`; see `emit::trace`).
pub const DEFAULT_TARGET_SPLIT: u32 = 16;
/// The footprint over a target where entering paths split reaches this far
/// beyond the target's horizontal extent, plus the depth of its top (m).
pub const TARGET_SPLIT_MARGIN_M: f64 = 1.0;
/// Largest radius of a k-nearest search (m).
pub const DEFAULT_MAX_RADIUS_M: f64 = 2.0;
/// Ray-marching step in water (m).
pub const DEFAULT_STEP_M: f64 = 0.5;
/// Photons per band in a band-shape voxel at [`POLICY_PHOTONS`] traced
/// photons (`spectral = "grid"`; see `estimate::shape`, which grows it
/// with the photon count).
pub const DEFAULT_SHAPE_PHOTONS_PER_BAND: usize = 400;
/// Half-angle of the truncated forward peak (degrees) along rays looking up
/// or sideways, into the downwelling light and the sun's aureole (see
/// `estimate::peak` for the measurements behind it).
pub const DEFAULT_FORWARD_PEAK_DEG: f64 = 10.0;
/// The same along rays looking down, into the smooth upwelling light.
pub const DEFAULT_FORWARD_PEAK_DOWN_DEG: f64 = 20.0;
/// The same along rays looking down at a target (see
/// [`TARGET_PEAK_MARGIN_M`]): the light rising off a small target is not
/// smooth on the scale of the search that counts it, and a wider peak
/// leaves more of its in-scatter to the march's exact turns. 30 rather
/// than 40: over 1 and 2 m boxes at 1.5–5.5 m in Chl 10 water, against a
/// path reference of 0.2–0.6 % per band, 40 degrees read the band means
/// +3.7, +1.3 and −1.0 % and the deep box's red bands 6 % low (4–5
/// standard errors), 30 degrees +1.7, 0.0 and −1.6 % with no band outside
/// 3 sigma + 2 %, 20 degrees −1.7, −2.2 and −5.1 % (benches/README.md).
pub const DEFAULT_FORWARD_PEAK_TARGET_DEG: f64 = 30.0;
/// A ray looking down is "at a target" when, at the depth of a target's
/// top, it passes within this horizontal distance of the target's extent.
pub const TARGET_PEAK_MARGIN_M: f32 = 1.0;

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
/// files and on the command line as `naive`, `compensated` or `grid`.
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
    Compensated,
    /// Level from the local search, band shape of the in-scatter from a
    /// grid over every volume photon (`estimate::shape`; the default);
    /// surfaces as `compensated`.
    #[default]
    Grid,
}

impl SpectralMode {
    /// Every mode, in the order help text lists them.
    pub const ALL: [SpectralMode; 3] = [
        SpectralMode::Naive,
        SpectralMode::Compensated,
        SpectralMode::Grid,
    ];

    /// The name used in scene files and on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            SpectralMode::Naive => "naive",
            SpectralMode::Compensated => "compensated",
            SpectralMode::Grid => "grid",
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

/// Compression of the spectral OpenEXR files (all lossless).
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
pub enum ExrCompression {
    /// Uncompressed.
    None,
    /// zlib over 16 scanlines per block (the default; OpenEXR's ZIP).
    #[default]
    Zip,
    /// Wavelet (OpenEXR's PIZ).
    Piz,
}

/// The `[render]` settings of a scene.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct RenderSettings {
    pub integrator: IntegratorMode,
    /// `[render] exr_compression`.
    #[serde(default)]
    pub exr_compression: ExrCompression,
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
    /// The same along rays looking down at a target (`render::march`).
    pub forward_peak_target_deg: f64,
    /// Node spacing (m) of a precomputed boundary-distance grid for volume
    /// estimates, or None to trace six rays per estimate.
    pub boundary_grid_m: Option<f64>,
    /// Photons per band in a band-shape voxel (`spectral = "grid"`).
    #[serde(default = "default_shape_photons_per_band")]
    pub shape_photons_per_band: usize,
    /// Final-gather rays per target hit (0: targets read the surface
    /// photon map, like the floor).
    #[serde(default = "default_gather_rays")]
    pub gather_rays: u32,
}

/// Final-gather rays per target hit unless `[estimate] gather_rays` says.
pub const DEFAULT_GATHER_RAYS: u32 = 32;

fn default_gather_rays() -> u32 {
    DEFAULT_GATHER_RAYS
}

fn default_shape_photons_per_band() -> usize {
    DEFAULT_SHAPE_PHOTONS_PER_BAND
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
