//! The scene file as written: TOML deserialised by serde, every table
//! closed to unknown keys. `scene::Scene::parse` turns it into a validated
//! scene; this module only describes the syntax. Every choice among names is
//! an enum, so a misspelt value is refused by the parser with the allowed
//! names listed. Spectra and reflectances stay strings: each is a built-in
//! name or the path of a CSV file.

use crate::geometry::Axis;
use crate::scene::settings::{BoundaryMode, IntegratorMode, SpectralMode};
use serde::Deserialize;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    #[serde(default = "default_name")]
    pub name: String,
    #[serde(default = "default_seed")]
    pub seed: u64,
    pub spectral: SpectralFile,
    pub sun: SunFile,
    #[serde(default)]
    pub sky: SkyFile,
    #[serde(default)]
    pub surface: SurfaceFile,
    pub domain: DomainFile,
    /// Required but for a Lambertian ground (`[surface] kind =
    /// "lambertian"`), which refuses it: the scene's parse fills it then
    /// (see [`SceneFile::water`]).
    pub water: Option<WaterFile>,
    pub bottom: Option<BottomFile>,
    /// The land where the floor rises above the water line.
    pub land: Option<LandFile>,
    #[serde(default)]
    pub target: Vec<TargetFile>,
    /// As `water`.
    pub photons: Option<PhotonsFile>,
    #[serde(default)]
    pub tally: TallyFile,
    pub sensor: Option<SensorFile>,
    #[serde(default)]
    pub radiometer: Vec<RadiometerFile>,
    #[serde(default)]
    pub estimate: EstimateFile,
    #[serde(default)]
    pub render: RenderFile,
    #[serde(default)]
    pub georef: GeorefFile,
    pub atmosphere: Option<AtmosphereFile>,
    pub surroundings: Option<SurroundingsFile>,
}

/// `[surroundings]`: the surface beyond the domain, as the air sees it.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurroundingsFile {
    pub kind: SurroundingsKind,
    /// For `kind = "lambertian"`.
    pub reflectance: Option<Reflectance>,
    /// For `kind = "water"`: the water beyond the domain, as a `[water]`
    /// table.
    pub water: Option<toml::Table>,
}

/// `[surroundings] kind`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SurroundingsKind {
    /// The domain repeats (the default without the table).
    Periodic,
    /// Land of one reflectance all around the domain.
    Lambertian,
    /// The domain's own mean radiance per direction all around it.
    Mean,
    /// Deep water of its own IOPs all around the domain.
    Water,
}

impl SceneFile {
    /// `[water]`, present after the scene's parse (which fills it for a
    /// Lambertian ground, where nothing reads it).
    pub fn water(&self) -> &WaterFile {
        self.water.as_ref().expect("the parse fills [water]")
    }

    /// `[photons]`, present after the scene's parse, as `water`.
    pub fn photons(&self) -> &PhotonsFile {
        self.photons.as_ref().expect("the parse fills [photons]")
    }

    /// True for `[surface] kind = "lambertian"`: a ground and no water.
    pub fn lambertian_ground(&self) -> bool {
        self.surface.kind == Some(SurfaceKind::Lambertian)
    }
}

/// `[atmosphere]`: plane-parallel layers over the sea
/// (`optics::atmosphere`).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AtmosphereFile {
    /// An AFGL reference atmosphere (`optics::atmosphere::profile::PROFILES`).
    pub profile: Option<String>,
    pub surface_pressure_hpa: Option<f64>,
    pub ozone_du: Option<f64>,
    pub rayleigh: Option<RayleighFile>,
    /// Other gases' absorption: a CSV of wavelength (nm) and optical depth.
    pub gas_tau_file: Option<String>,
    /// Photons per band for the sky at the surface.
    pub sky_photons: Option<u64>,
    /// The light the sea sends up that the air returns to it, in the sky
    /// (default true; false: the sky over a black surface).
    pub sea_coupling: Option<bool>,
    pub aerosol: Option<AerosolFile>,
}

/// `[atmosphere] rayleigh`: `true`, `false` or `{ tau = X }`.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
pub enum RayleighFile {
    On(bool),
    Tau(RayleighTau),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RayleighTau {
    pub tau: f64,
}

/// `[atmosphere.aerosol]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AerosolFile {
    pub model: AerosolModel,
    pub tau_550: f64,
    pub angstrom: Option<f64>,
    pub ssa: Option<f64>,
    pub phase: Option<AerosolPhaseFile>,
    pub scale_height_km: Option<f64>,
    pub top_km: Option<f64>,
}

/// `[atmosphere.aerosol] model`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum AerosolModel {
    Custom,
    /// 6S's models (`optics::atmosphere::aerosol`).
    Continental,
    Maritime,
    Urban,
}

/// `[atmosphere.aerosol] phase`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AerosolPhaseFile {
    pub kind: AerosolPhaseKind,
    pub g: f64,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum AerosolPhaseKind {
    HenyeyGreenstein,
}

/// `[georef]`: where the scene's frame sits on a map.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GeorefFile {
    /// Map coordinates (easting, northing, m) of the scene's origin (x = 0, y = 0).
    #[serde(default, deserialize_with = "exact::opt")]
    pub origin_m: Option<[f64; 2]>,
    /// EPSG code of the map's CRS: a WGS 84 / UTM zone (32601-32660 north,
    /// 32701-32760 south). None: a local metric frame.
    pub epsg: Option<u32>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderFile {
    pub integrator: Option<IntegratorMode>,
    pub exr_compression: Option<crate::scene::settings::ExrCompression>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorFile {
    pub kind: Option<SensorKindName>,
    #[serde(default, deserialize_with = "exact::opt")]
    pub pixels: Option<[usize; 2]>,
    pub gsd_m: Option<f64>,
    pub samples_per_pixel: Option<u32>,
    /// Orthographic: centre of the image on the surface (default: domain centre).
    #[serde(default, deserialize_with = "exact::opt")]
    pub center_m: Option<[f64; 2]>,
    #[serde(default, deserialize_with = "exact::opt")]
    pub position_m: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "exact::opt")]
    pub look_at_m: Option<[f64; 3]>,
    pub fov_deg: Option<f64>,
    /// A real sensor's bands to write the cubes in as well
    /// (`spectral::response::SpectralResponse::named`).
    pub response: Option<String>,
    /// With an `[atmosphere]`: the sensor's height above the sea (m); at or
    /// above the atmosphere's top (120 km) it sees the top of the
    /// atmosphere.
    pub altitude_m: Option<f64>,
    /// Orthographic: the angle of the view from the vertical and its
    /// azimuth (toward the sensor, counter-clockwise from +x).
    pub view_zenith_deg: Option<f64>,
    pub view_azimuth_deg: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RadiometerFile {
    pub depth_m: f64,
    pub view: Option<View>,
    /// Horizontal position (default: domain centre).
    #[serde(default, deserialize_with = "exact::opt")]
    pub position_m: Option<[f64; 2]>,
    /// Half-angle of the field of view around `view` (degrees; default 0,
    /// a single direction).
    pub half_angle_deg: Option<f64>,
}

/// A viewing direction: "nadir", "zenith" or a vector.
#[derive(Clone, Debug, Deserialize)]
#[serde(untagged)]
pub enum View {
    Named(String),
    Vector(#[serde(deserialize_with = "exact::array")] [f64; 3]),
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EstimateFile {
    pub k: Option<usize>,
    pub radius_m: Option<f64>,
    pub max_radius_m: Option<f64>,
    pub k_expanded: Option<usize>,
    pub boundary: Option<BoundaryMode>,
    pub spectral: Option<SpectralMode>,
    pub step_m: Option<f64>,
    pub forward_peak_deg: Option<f64>,
    pub forward_peak_down_deg: Option<f64>,
    pub forward_peak_target_deg: Option<f64>,
    pub boundary_grid_m: Option<f64>,
    pub shape_photons_per_band: Option<usize>,
    pub gather_rays: Option<u32>,
}

/// `[spectral] out_of_range`: what to do with a band centre outside a data
/// table's range.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OutOfRange {
    /// Refuse the scene (the default).
    #[default]
    Error,
    /// Use the table's nearest value.
    Clamp,
}

/// `[surface] kind`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SurfaceKind {
    #[default]
    Flat,
    CoxMunk,
    /// No water: a Lambertian ground of `[surface] reflectance` at z = 0
    /// (for comparisons with codes over land).
    Lambertian,
}

/// `[domain] edges`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Edges {
    /// Photons leaving one side come back on the other (the default).
    #[default]
    Periodic,
    /// Photons leaving the domain are lost.
    Open,
}

/// `[water] phase.kind`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PhaseKind {
    FournierForand,
    Petzold,
    Rayleigh,
    Isotropic,
    HenyeyGreenstein,
    Table,
}

/// `[[target]] kind`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TargetKind {
    Box,
    Panel,
    Mesh,
}

/// `[sensor] kind`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SensorKindName {
    #[default]
    Orthographic,
    Pinhole,
}

fn default_name() -> String {
    "scene".into()
}
fn default_seed() -> u64 {
    1
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpectralFile {
    pub start_nm: Option<f64>,
    pub end_nm: Option<f64>,
    pub bands: Option<usize>,
    pub centers_nm: Option<Vec<f64>>,
    pub fwhm_nm: Option<Vec<f64>>,
    /// "error" (default) or "clamp": what to do with a band whose centre lies
    /// outside a data table's range.
    pub out_of_range: Option<OutOfRange>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SunFile {
    pub zenith_deg: f64,
    #[serde(default)]
    pub azimuth_deg: f64,
    pub spectrum: Option<String>,
    pub irradiance: Option<f64>,
    /// With an atmosphere: the day of the year, for the Earth–Sun distance.
    pub day_of_year: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SkyFile {
    pub spectrum: Option<String>,
    pub radiance: Option<f64>,
    /// How the radiance spreads over the sky (`optics::sky`; default
    /// isotropic).
    pub distribution: Option<SkyDistribution>,
}

/// `[sky] distribution`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SkyDistribution {
    #[default]
    Isotropic,
    CieClear,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceFile {
    pub kind: Option<SurfaceKind>,
    pub wind_speed: Option<f64>,
    pub refractive_index: Option<RefractiveIndex>,
    /// Water temperature (°C) for `refractive_index = "quan-fry"`.
    pub temperature_c: Option<f64>,
    /// Salinity (PSU) for `refractive_index = "quan-fry"`.
    pub salinity_psu: Option<f64>,
    /// The ground's reflectance for `kind = "lambertian"`.
    pub reflectance: Option<Reflectance>,
}

/// `[surface] refractive_index`: a number, the same in every band, or a
/// named model of n(wavelength, temperature, salinity).
#[derive(Clone, Debug, Deserialize)]
#[serde(untagged)]
pub enum RefractiveIndex {
    Constant(f64),
    Named(String),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DomainFile {
    #[serde(deserialize_with = "exact::array")]
    pub size_m: [f64; 2],
    pub edges: Option<Edges>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WaterFile {
    pub iop: Option<IopFile>,
    /// CSV of explicit IOPs per wavelength: `wavelength_nm,a,b[,bb_ratio]`.
    pub iop_file: Option<String>,
    pub phase: Option<PhaseFile>,
    pub chl: Option<f64>,
    pub cdom_440: Option<f64>,
    pub cdom_slope: Option<f64>,
    pub nap_440: Option<f64>,
    pub nap_slope: Option<f64>,
    /// Particle scattering at 550 nm (1/m); default 0.30 Chl^0.62 (case-1 water).
    pub bp_550: Option<f64>,
    /// Spectral slope n of particle scattering, b_p ~ (550/l)^n; default 1.
    pub bp_slope: Option<f64>,
    pub gradient: Option<GradientFile>,
    #[serde(default)]
    pub layer: Vec<LayerFile>,
    /// CSV of a regular 3-D grid of constituents.
    pub grid: Option<String>,
    /// Water Raman scattering (`optics::inelastic`); default true for
    /// water given by its constituents, false for water given by its IOPs.
    pub raman: Option<bool>,
    /// Chlorophyll and CDOM fluorescence (`optics::inelastic`); none
    /// without the table.
    pub fluorescence: Option<FluorescenceFile>,
}

/// `[water.fluorescence]`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FluorescenceFile {
    /// Quantum yield of chlorophyll fluorescence; default 0.01 (0: none).
    pub chl_quantum_yield: Option<f64>,
    /// CDOM fluorescence after Hawes (1992); default false.
    pub cdom: Option<bool>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IopFile {
    pub a: f64,
    pub b: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhaseFile {
    pub kind: PhaseKind,
    pub bb_ratio: Option<f64>,
    pub q: Option<f64>,
    pub g: Option<f64>,
    pub file: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GradientFile {
    pub axis: Axis,
    #[serde(default, deserialize_with = "exact::opt")]
    pub chl: Option<[f64; 2]>,
    #[serde(default, deserialize_with = "exact::opt")]
    pub cdom_440: Option<[f64; 2]>,
    #[serde(default, deserialize_with = "exact::opt")]
    pub nap_440: Option<[f64; 2]>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LayerFile {
    pub top_m: f64,
    pub bottom_m: f64,
    pub chl: Option<f64>,
    pub cdom_440: Option<f64>,
    pub nap_440: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BottomFile {
    pub depth_m: Option<f64>,
    pub slope: Option<SlopeFile>,
    pub heightfield: Option<String>,
    pub reflectance: Option<Reflectance>,
    /// Areas of a second bottom type (e.g. a seagrass meadow) as boxes in x, y.
    #[serde(default)]
    pub patch: Vec<PatchFile>,
}

/// `[land]`: the floor above the water line (a `[bottom]` slope or
/// heightfield whose depths go negative), a Lambertian surface.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LandFile {
    pub reflectance: Reflectance,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SlopeFile {
    pub from_depth_m: f64,
    pub to_depth_m: f64,
    pub axis: Option<Axis>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PatchFile {
    #[serde(deserialize_with = "exact::array")]
    pub min_m: [f64; 2],
    #[serde(deserialize_with = "exact::array")]
    pub max_m: [f64; 2],
    pub reflectance: Reflectance,
}

/// A reflectance: a constant, a name from the bottom table, or a CSV path.
#[derive(Clone, Debug, Deserialize)]
#[serde(untagged)]
pub enum Reflectance {
    Constant(f64),
    Named(String),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TargetFile {
    pub kind: TargetKind,
    #[serde(deserialize_with = "exact::array")]
    pub center_m: [f64; 3],
    pub size_m: Option<Vec<f64>>,
    pub file: Option<String>,
    pub scale: Option<f64>,
    pub reflectance: Reflectance,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhotonsFile {
    pub count: u64,
    /// Store the first scattering of unscattered sunlight too (the renderer
    /// computes it directly, so by default it is not stored).
    #[serde(default)]
    pub store_direct: bool,
    /// Copies a path of full weight splits into when it turns upward
    /// (`emit::trace`): a power of two, 1 (no splitting) to 64.
    #[serde(default = "default_upward_split")]
    pub upward_split: u32,
    /// Copies a path splits into where it enters the water over a target
    /// (`emit::trace`): a power of two, 1 (no splitting, the default) to 64.
    #[serde(default = "default_target_split")]
    pub target_split: u32,
}

fn default_upward_split() -> u32 {
    crate::scene::settings::DEFAULT_UPWARD_SPLIT
}

fn default_target_split() -> u32 {
    crate::scene::settings::DEFAULT_TARGET_SPLIT
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TallyFile {
    #[serde(default)]
    pub depths_m: Vec<f64>,
}

/// Fixed-length arrays read exactly: serde's own array impl takes the first
/// N values of a longer TOML array and ignores the rest, so `pixels = [32,
/// 32, 32]` would pass. These refuse any other length, naming the expected
/// one (the parser's error points at the value, so the key and line are
/// reported like every type error).
mod exact {
    use serde::de::{Deserialize, Deserializer, Error, Expected};
    use std::fmt;

    struct Values(usize);

    impl Expected for Values {
        fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
            write!(f, "exactly {} values", self.0)
        }
    }

    pub fn array<'de, D, T, const N: usize>(d: D) -> Result<[T; N], D::Error>
    where
        D: Deserializer<'de>,
        T: Deserialize<'de>,
    {
        let v = Vec::<T>::deserialize(d)?;
        let n = v.len();
        v.try_into()
            .map_err(|_| D::Error::invalid_length(n, &Values(N)))
    }

    pub fn opt<'de, D, T, const N: usize>(d: D) -> Result<Option<[T; N]>, D::Error>
    where
        D: Deserializer<'de>,
        T: Deserialize<'de>,
    {
        array(d).map(Some)
    }
}
