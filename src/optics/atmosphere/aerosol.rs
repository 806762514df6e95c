//! The named aerosol models of 6S (`[atmosphere.aerosol] model =
//! "continental" | "maritime" | "urban"`): external mixtures of the
//! dust-like, water-soluble, oceanic and soot components (Vermote et al.
//! 1997, 6SV1.0B; component data after d'Almeida, Koepke & Shettle 1991),
//! their extinction spectrum, single-scattering albedo and phase function
//! computed by Mie theory by `tools/aerosol_tables.py` and shipped as
//! `data/aerosol_models.csv` and `data/aerosol_phase.csv` (sources, method
//! and the component parameters in their headers and the script's).
//!
//! The tables hold the 6S wavelengths from 350 to 860 nm; a band between
//! two of them takes the linear interpolation in wavelength of the
//! extinction relative to 550 nm, the albedo and the phase function angle
//! by angle (each a mean over the sphere of 1). Outside that range there
//! is nothing to interpolate: [`NamedAerosol::at`] says so, and the scene
//! refuses or clamps as `[spectral] out_of_range` says.

use crate::error::{Error, Result};
use std::path::Path;
use std::sync::OnceLock;

const MODELS_FILE: &str = "data/aerosol_models.csv";
const PHASE_FILE: &str = "data/aerosol_phase.csv";
const MODELS_CSV: &str = include_str!("../../../data/aerosol_models.csv");
const PHASE_CSV: &str = include_str!("../../../data/aerosol_phase.csv");

/// The named models, in the order the scene lists them.
pub const MODELS: [&str; 3] = ["continental", "maritime", "urban"];

/// One named model's optical properties at the tabulated wavelengths.
#[derive(Debug)]
pub struct NamedAerosol {
    pub name: &'static str,
    /// Tabulated wavelengths (nm), rising.
    pub nm: Vec<f64>,
    /// Extinction relative to 550 nm, single-scattering albedo and the
    /// asymmetry parameter (Mie's), per wavelength.
    pub ext_rel: Vec<f64>,
    pub ssa: Vec<f64>,
    pub g: Vec<f64>,
    /// Scattering angles of the phase table (degrees).
    pub angles_deg: Vec<f64>,
    /// The phase function per wavelength at `angles_deg` (mean 1 over the
    /// sphere).
    pub phase: Vec<Vec<f64>>,
}

/// The model's properties at one wavelength.
#[derive(Clone, Debug, PartialEq)]
pub struct AerosolAt {
    pub ext_rel: f64,
    pub ssa: f64,
    /// At the model's `angles_deg`.
    pub phase: Vec<f64>,
}

impl NamedAerosol {
    /// The properties at `nm`, none outside the tabulated range.
    pub fn at(&self, nm: f64) -> Option<AerosolAt> {
        let (lo, hi) = (self.nm[0], self.nm[self.nm.len() - 1]);
        if !(lo..=hi).contains(&nm) {
            return None;
        }
        let i = self
            .nm
            .partition_point(|&v| v < nm)
            .clamp(1, self.nm.len() - 1);
        let f = (nm - self.nm[i - 1]) / (self.nm[i] - self.nm[i - 1]);
        let mix = |v: &[f64]| v[i - 1] + f * (v[i] - v[i - 1]);
        Some(AerosolAt {
            ext_rel: mix(&self.ext_rel),
            ssa: mix(&self.ssa),
            phase: self.phase[i - 1]
                .iter()
                .zip(&self.phase[i])
                .map(|(a, b)| a + f * (b - a))
                .collect(),
        })
    }

    /// The tabulated range (nm).
    pub fn range_nm(&self) -> (f64, f64) {
        (self.nm[0], self.nm[self.nm.len() - 1])
    }
}

/// The model named `name`, if there is one.
pub fn named(name: &str) -> Option<&'static NamedAerosol> {
    models().iter().find(|m| m.name == name)
}

fn models() -> &'static [NamedAerosol] {
    static CELL: OnceLock<Vec<NamedAerosol>> = OnceLock::new();
    CELL.get_or_init(|| {
        parse(MODELS_CSV, PHASE_CSV)
            .unwrap_or_else(|e| panic!("embedded aerosol tables are malformed: {e}"))
    })
}

fn parse(models: &str, phase: &str) -> Result<Vec<NamedAerosol>> {
    let t = crate::csv::parse(models, Path::new(MODELS_FILE), MODELS_FILE)?;
    let p = crate::csv::parse(phase, Path::new(PHASE_FILE), PHASE_FILE)?;
    let mut out: Vec<NamedAerosol> = MODELS
        .iter()
        .map(|&name| NamedAerosol {
            name,
            nm: Vec::new(),
            ext_rel: Vec::new(),
            ssa: Vec::new(),
            g: Vec::new(),
            angles_deg: Vec::new(),
            phase: Vec::new(),
        })
        .collect();
    let model_of = |out: &mut Vec<NamedAerosol>, name: &str| -> Option<usize> {
        out.iter().position(|m| m.name == name)
    };
    for row in &t.rows {
        let Some(m) = model_of(&mut out, &row.fields[0]) else {
            return Err(t.error(Some(row.line), format!("unknown model '{}'", row.fields[0])));
        };
        let v: Vec<f64> = (1..5).map(|c| t.number(row, c)).collect::<Result<_>>()?;
        let m = &mut out[m];
        if m.nm.last().is_some_and(|&w| v[0] <= w) || v[1] <= 0.0 || !(0.0..=1.0).contains(&v[2]) {
            return Err(t.error(
                Some(row.line),
                "wavelengths must rise, extinction be > 0 and the albedo within [0, 1]",
            ));
        }
        m.nm.push(v[0]);
        m.ext_rel.push(v[1]);
        m.ssa.push(v[2]);
        m.g.push(v[3]);
        m.phase.push(Vec::new());
    }
    for row in &p.rows {
        let Some(k) = model_of(&mut out, &row.fields[0]) else {
            return Err(p.error(Some(row.line), format!("unknown model '{}'", row.fields[0])));
        };
        let v: Vec<f64> = (1..4).map(|c| p.number(row, c)).collect::<Result<_>>()?;
        let m = &mut out[k];
        let Some(w) = m.nm.iter().position(|&nm| nm == v[0]) else {
            return Err(p.error(
                Some(row.line),
                format!("{} nm is not a wavelength of {MODELS_FILE}", v[0]),
            ));
        };
        // The first wavelength's rows set the angles; the others repeat them.
        if w == 0 {
            m.angles_deg.push(v[1]);
        } else if m.angles_deg.get(m.phase[w].len()) != Some(&v[1]) {
            return Err(p.error(Some(row.line), "angles differ from the first wavelength's"));
        }
        if v[2] < 0.0 {
            return Err(p.error(Some(row.line), "phase values must be >= 0"));
        }
        m.phase[w].push(v[2]);
    }
    for m in &out {
        if m.nm.len() < 2 || m.phase.iter().any(|ph| ph.len() != m.angles_deg.len()) {
            return Err(Error::invalid(
                PHASE_FILE,
                format!("model {} lacks wavelengths or phase rows", m.name),
            ));
        }
    }
    Ok(out)
}
