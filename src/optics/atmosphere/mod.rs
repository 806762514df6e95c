//! The atmosphere over the sea: plane-parallel layers from the surface to
//! 120 km, horizontally uniform, and the light they bring to the surface.
//!
//! Each band's column ([`Column`]) is built on the levels of an AFGL
//! reference atmosphere ([`profile`]) from:
//! - **Rayleigh scattering** ([`rayleigh`]): the optical depth of Bodhaine
//!   et al. (1999) scaled by the surface pressure, spread over the layers in
//!   proportion to the pressure drop across each (air mass), with the
//!   depolarised Rayleigh phase function; or a fixed optical depth in every
//!   band (`rayleigh = { tau = X }`, for comparisons with monochromatic
//!   codes), or none.
//! - **Ozone absorption**: the Leckner (1978) coefficients of Bird &
//!   Riordan (1986) (`data/ozone_leckner1978.csv`, per atm-cm, averaged over
//!   each band's response; 0 beyond the table's 800 nm) times the layer's
//!   ozone, the profile's shape scaled to `ozone_du`.
//! - **Other absorbing gases**: a per-band optical depth from a user CSV
//!   (`gas_tau_file`), spread like the air (in proportion to the pressure
//!   drop). Water vapour lies lower than the air as a whole; where the
//!   coupling of an absorber with scattering matters, give it as part of
//!   the aerosol's absorption instead.
//! - **An aerosol** (`[atmosphere.aerosol]`, model `custom`): tau(550)
//!   with an Ångström exponent, a single-scattering albedo and a
//!   Henyey–Greenstein phase function, spread with a scale height
//!   (exponential in height) or uniformly from the ground to a top.
//!
//! Each layer is homogeneous: its extinction, its single-scattering
//! albedo and the Rayleigh share of its scattering. The light at the
//! surface comes from [`transport`].
//!
//! Not for (yet): named aerosol models from Mie theory, the sensor above
//! the surface (path radiance), light the surface sends back up and the
//! air scatters down again, polarisation, the sphericity of the Earth.

pub mod aerosol;
pub mod profile;
pub mod rayleigh;
pub mod transport;

use crate::optics::phase::{PhaseFunction, PhaseLookup};
use profile::Profile;

/// (r0 / r)^2, the Sun's irradiance at the Earth over its value at the
/// mean distance, on day `day` of the year (1 = 1 January): Spencer
/// (1971), "Fourier series representation of the position of the sun",
/// Search 2:172.
pub fn earth_sun_factor(day: f64) -> f64 {
    let g = 2.0 * std::f64::consts::PI * (day - 1.0) / 365.0;
    1.000_110
        + 0.034_221 * g.cos()
        + 0.001_280 * g.sin()
        + 0.000_719 * (2.0 * g).cos()
        + 0.000_077 * (2.0 * g).sin()
}

/// How Rayleigh scattering enters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RayleighSetting {
    /// Bodhaine et al.'s optical depth at each band's centre.
    Standard,
    /// This optical depth in every band.
    Tau(f64),
    /// None.
    Off,
}

/// How an aerosol's optical depth is spread with height.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AerosolHeight {
    /// Exponential with this scale height (km).
    ScaleHeight(f64),
    /// Uniform from the ground to this height (km).
    Top(f64),
}

/// An aerosol: a user's (Ångström law, one albedo, Henyey–Greenstein) or
/// a named 6S model's (`named`: its tabulated spectrum, albedo and Mie
/// phase function per wavelength; `angstrom`, `ssa` and `g` then hold the
/// model's values at 550 nm and between 443 and 860 nm, for reports).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aerosol {
    pub tau_550: f64,
    pub angstrom: f64,
    pub ssa: f64,
    pub g: f64,
    pub height: AerosolHeight,
    pub named: Option<&'static aerosol::NamedAerosol>,
}

impl PartialEq for aerosol::NamedAerosol {
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name
    }
}

impl Aerosol {
    /// A named model's properties at `nm`, clamped into its tables (the
    /// scene refuses bands outside them unless told to clamp).
    fn named_at(&self, nm: f64) -> Option<aerosol::AerosolAt> {
        let m = self.named?;
        let (lo, hi) = m.range_nm();
        m.at(nm.clamp(lo, hi))
    }

    /// Extinction optical depth at `nm`.
    pub fn tau(&self, nm: f64) -> f64 {
        match self.named_at(nm) {
            Some(a) => self.tau_550 * a.ext_rel,
            None => self.tau_550 * (nm / 550.0).powf(-self.angstrom),
        }
    }

    /// Single-scattering albedo at `nm`.
    pub fn ssa_at(&self, nm: f64) -> f64 {
        self.named_at(nm).map_or(self.ssa, |a| a.ssa)
    }

    /// Phase function at `nm`: the model's Mie table, or Henyey–Greenstein.
    pub fn phase_at(&self, nm: f64) -> PhaseFunction {
        match (self.named, self.named_at(nm)) {
            (Some(m), Some(a)) => {
                crate::optics::phase::TabulatedPhase::new(&m.angles_deg, &a.phase, m.name)
                    .map(PhaseFunction::Tabulated)
                    .unwrap_or_else(|e| panic!("embedded aerosol phase table is invalid: {e}"))
            }
            _ => PhaseFunction::HenyeyGreenstein { g: self.g },
        }
    }
}

/// Everything an `[atmosphere]` section fixes.
#[derive(Clone, Debug, PartialEq)]
pub struct AtmosphereSpec {
    pub profile: &'static Profile,
    pub surface_pressure_hpa: f64,
    pub ozone_du: f64,
    pub rayleigh: RayleighSetting,
    pub aerosol: Option<Aerosol>,
    /// Other gases' absorption optical depth per band.
    pub gas_tau: Option<Vec<f64>>,
    /// Ozone absorption per atm-cm per band.
    pub ozone_per_atm_cm: Vec<f64>,
}

/// One homogeneous layer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layer {
    /// Its bottom and top (km).
    pub bottom_km: f64,
    pub top_km: f64,
    pub rayleigh: f64,
    pub aerosol_scattering: f64,
    pub aerosol_absorption: f64,
    pub ozone: f64,
    pub gas: f64,
}

impl Layer {
    /// Extinction optical depth.
    pub fn tau(&self) -> f64 {
        self.rayleigh + self.aerosol_scattering + self.aerosol_absorption + self.ozone + self.gas
    }

    /// Single-scattering albedo (1 for an empty layer).
    pub fn ssa(&self) -> f64 {
        let t = self.tau();
        if t > 0.0 {
            (self.rayleigh + self.aerosol_scattering) / t
        } else {
            1.0
        }
    }

    /// Rayleigh's share of the scattering.
    pub fn rayleigh_share(&self) -> f64 {
        let s = self.rayleigh + self.aerosol_scattering;
        if s > 0.0 {
            self.rayleigh / s
        } else {
            1.0
        }
    }
}

/// One band's column: its layers from the top down.
#[derive(Clone, Debug)]
pub struct Column {
    pub nm: f64,
    pub layers: Vec<Layer>,
    /// Optical depth from the top of the atmosphere to the top of each
    /// layer, then to the ground (`layers.len() + 1` values).
    pub depth: Vec<f64>,
    pub rayleigh_phase: PhaseFunction,
    pub aerosol_phase: PhaseFunction,
    /// A tabulated aerosol phase function read from a fine table
    /// (`PhaseLookup`): the local estimates evaluate it toward every sky
    /// cell at every collision, and its inverse sine took 40 % of the
    /// scene's reading.
    aerosol_lookup: Option<std::sync::Arc<PhaseLookup>>,
}

/// Optical depths of a whole column by component.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Totals {
    pub rayleigh: f64,
    pub aerosol_scattering: f64,
    pub aerosol_absorption: f64,
    pub ozone: f64,
    pub gas: f64,
}

impl Totals {
    pub fn extinction(&self) -> f64 {
        self.rayleigh + self.aerosol_scattering + self.aerosol_absorption + self.ozone + self.gas
    }
}

impl Column {
    /// The column at `nm` of `spec`, band `band`.
    pub fn new(spec: &AtmosphereSpec, band: usize, nm: f64) -> Column {
        let p = spec.profile;
        let mut z: Vec<f64> = p.z_km.clone();
        if let Some(Aerosol {
            height: AerosolHeight::Top(top),
            ..
        }) = spec.aerosol
        {
            let i = z.partition_point(|&v| v < top);
            if z.get(i) != Some(&top) && i < z.len() {
                z.insert(i, top);
            }
        }
        let p0 = p.p_hpa[0];
        let tau_r = match spec.rayleigh {
            RayleighSetting::Standard => {
                rayleigh::optical_depth(nm) * spec.surface_pressure_hpa
                    / rayleigh::REFERENCE_PRESSURE_HPA
            }
            RayleighSetting::Tau(t) => t,
            RayleighSetting::Off => 0.0,
        };
        let gas = spec.gas_tau.as_ref().map_or(0.0, |g| g[band]);
        let ozone_scale = spec.ozone_du / p.ozone_du() * spec.ozone_per_atm_cm[band] * 1e-3;
        let (tau_a, ssa) = spec
            .aerosol
            .map_or((0.0, 1.0), |a| (a.tau(nm), a.ssa_at(nm)));
        let ztop = *z.last().unwrap_or(&0.0);
        let mut layers = Vec::with_capacity(z.len() - 1);
        for w in z.windows(2) {
            let (lo, hi) = (w[0], w[1]);
            let air = (p.pressure_at(lo) - p.pressure_at(hi)) / (p0 - p.pressure_at(ztop));
            let ozone_du = 0.5 * (p.ozone_cm3_at(lo) + p.ozone_cm3_at(hi)) * (hi - lo) * 1e5
                / profile::MOLECULES_PER_DU;
            let aerosol_share = match spec.aerosol.map(|a| a.height) {
                None => 0.0,
                Some(AerosolHeight::ScaleHeight(h)) => {
                    ((-lo / h).exp() - (-hi / h).exp()) / (1.0 - (-ztop / h).exp())
                }
                Some(AerosolHeight::Top(t)) => ((hi.min(t) - lo).max(0.0)) / t,
            };
            layers.push(Layer {
                bottom_km: lo,
                top_km: hi,
                rayleigh: tau_r * air,
                aerosol_scattering: tau_a * ssa * aerosol_share,
                aerosol_absorption: tau_a * (1.0 - ssa) * aerosol_share,
                ozone: ozone_scale * ozone_du,
                gas: gas * air,
            });
        }
        layers.reverse();
        let mut depth = Vec::with_capacity(layers.len() + 1);
        let mut d = 0.0;
        depth.push(d);
        for l in &layers {
            d += l.tau();
            depth.push(d);
        }
        let aerosol_phase = spec
            .aerosol
            .map_or(PhaseFunction::HenyeyGreenstein { g: 0.0 }, |a| {
                a.phase_at(nm)
            });
        let aerosol_lookup = matches!(aerosol_phase, PhaseFunction::Tabulated(_))
            .then(|| std::sync::Arc::new(PhaseLookup::new(&aerosol_phase)));
        Column {
            nm,
            layers,
            depth,
            rayleigh_phase: PhaseFunction::Rayleigh {
                q: rayleigh::phase_q(nm),
            },
            aerosol_phase,
            aerosol_lookup,
        }
    }

    /// The aerosol's phase function at `cos` (sr^-1), a tabulated one
    /// from its lookup table.
    #[inline]
    pub fn aerosol_density(&self, cos: f64) -> f64 {
        match &self.aerosol_lookup {
            Some(l) => l.eval(cos),
            None => self.aerosol_phase.eval(cos),
        }
    }

    /// The bytes of its phase functions' tables.
    pub fn phase_bytes(&self) -> u64 {
        self.rayleigh_phase.heap_bytes()
            + self.aerosol_phase.heap_bytes()
            + self.aerosol_lookup.as_ref().map_or(0, |l| l.heap_bytes())
    }

    /// Optical depth from the top of the atmosphere to the ground.
    pub fn total(&self) -> f64 {
        *self.depth.last().unwrap_or(&0.0)
    }

    /// The column's optical depths by component.
    pub fn totals(&self) -> Totals {
        let mut t = Totals::default();
        for l in &self.layers {
            t.rayleigh += l.rayleigh;
            t.aerosol_scattering += l.aerosol_scattering;
            t.aerosol_absorption += l.aerosol_absorption;
            t.ozone += l.ozone;
            t.gas += l.gas;
        }
        t
    }

    /// Optical depth from the top down to height `z_km` (0 above the top,
    /// the whole column at and below the ground).
    pub fn depth_at(&self, z_km: f64) -> f64 {
        let i = self.layers.partition_point(|l| l.bottom_km >= z_km);
        match self.layers.get(i) {
            None => self.total(),
            Some(l) => {
                let f = ((l.top_km - z_km) / (l.top_km - l.bottom_km)).clamp(0.0, 1.0);
                self.depth[i] + f * l.tau()
            }
        }
    }

    /// The height (km) at optical depth `depth` from the top: the inverse
    /// of [`Self::depth_at`] (the top of the first layer for 0).
    pub fn height_at(&self, depth: f64) -> f64 {
        let i = self.depth[1..]
            .partition_point(|&d| d < depth)
            .min(self.layers.len() - 1);
        let l = &self.layers[i];
        let t = l.tau();
        let f = if t > 0.0 {
            ((depth - self.depth[i]) / t).clamp(0.0, 1.0)
        } else {
            0.0
        };
        l.top_km - f * (l.top_km - l.bottom_km)
    }

    /// The mean of `columns` (one per band, on the same layers): each
    /// layer's optical depths averaged over the bands, the phase functions
    /// the first column's.
    pub fn mean(columns: &[Column]) -> Column {
        let n = columns.len() as f64;
        let mut c = columns[0].clone();
        for (i, l) in c.layers.iter_mut().enumerate() {
            let avg = |f: &dyn Fn(&Layer) -> f64| {
                columns.iter().map(|c| f(&c.layers[i])).sum::<f64>() / n
            };
            l.rayleigh = avg(&|l| l.rayleigh);
            l.aerosol_scattering = avg(&|l| l.aerosol_scattering);
            l.aerosol_absorption = avg(&|l| l.aerosol_absorption);
            l.ozone = avg(&|l| l.ozone);
            l.gas = avg(&|l| l.gas);
        }
        let mut d = 0.0;
        for (i, l) in c.layers.iter().enumerate() {
            c.depth[i] = d;
            d += l.tau();
        }
        let last = c.layers.len();
        c.depth[last] = d;
        c
    }

    /// The index of the layer holding height `z_km`.
    pub fn layer_index(&self, z_km: f64) -> usize {
        self.layers
            .partition_point(|l| l.bottom_km >= z_km)
            .min(self.layers.len() - 1)
    }

    /// The layer at optical depth `tau` from the top (the last one at and
    /// below the ground).
    pub fn layer_at(&self, tau: f64) -> &Layer {
        let i = self.depth[1..].partition_point(|&d| d < tau);
        &self.layers[i.min(self.layers.len() - 1)]
    }
}

#[cfg(test)]
mod tests;
