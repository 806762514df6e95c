//! The AFGL reference atmospheres (Anderson et al. 1986, AFGL-TR-86-0110):
//! pressure, temperature, air density and the ozone and water-vapour
//! mixing ratios at 50 levels from 0 to 120 km, embedded from
//! `data/afgl_profiles.csv` (see `data/README.md`). `us-standard-1976` is
//! the U.S. Standard Atmosphere 1976 as AFGL tabulates it.
//!
//! Columns between levels are trapezoid integrals of the number densities
//! over the tabulated levels (the U.S. Standard profile's ozone column
//! reads 345.6 DU, the figure the AFGL profile is known by).

use crate::error::{Error, Result};
use std::path::Path;
use std::sync::OnceLock;

const FILE: &str = "afgl_profiles.csv";
const CSV: &str = include_str!("../../../data/afgl_profiles.csv");

/// Molecules per cm^2 in one Dobson unit (Loschmidt's number x 10 µm).
pub const MOLECULES_PER_DU: f64 = 2.686_780_1e16;

/// The profiles' names, as `[atmosphere] profile` takes them.
pub const PROFILES: &[&str] = &[
    "tropical",
    "midlatitude-summer",
    "midlatitude-winter",
    "subarctic-summer",
    "subarctic-winter",
    "us-standard-1976",
];

/// One reference atmosphere, its levels from the ground up.
#[derive(Clone, Debug, PartialEq)]
pub struct Profile {
    pub name: &'static str,
    pub z_km: Vec<f64>,
    pub p_hpa: Vec<f64>,
    pub t_k: Vec<f64>,
    /// Air molecules per cm^3.
    pub air_cm3: Vec<f64>,
    /// Volume mixing ratios, ppmv.
    pub h2o_ppmv: Vec<f64>,
    pub o3_ppmv: Vec<f64>,
}

impl Profile {
    /// Ozone molecules per cm^3 at level `i`.
    pub fn ozone_cm3(&self, i: usize) -> f64 {
        self.air_cm3[i] * self.o3_ppmv[i] * 1e-6
    }

    /// The ozone column between each pair of adjacent levels (DU), by the
    /// trapezoid rule; their sum is the profile's column.
    pub fn ozone_layers_du(&self) -> Vec<f64> {
        (0..self.z_km.len() - 1)
            .map(|i| {
                let dz_cm = (self.z_km[i + 1] - self.z_km[i]) * 1e5;
                0.5 * (self.ozone_cm3(i) + self.ozone_cm3(i + 1)) * dz_cm / MOLECULES_PER_DU
            })
            .collect()
    }

    /// The profile's total ozone column (DU).
    pub fn ozone_du(&self) -> f64 {
        self.ozone_layers_du().iter().sum()
    }

    /// Pressure at `z_km` (hPa): log-linear between levels (exponential
    /// within each), the lowest level's below it.
    pub fn pressure_at(&self, z_km: f64) -> f64 {
        let z = &self.z_km;
        if z_km <= z[0] {
            return self.p_hpa[0];
        }
        let i = z.partition_point(|&v| v <= z_km).clamp(1, z.len() - 1);
        let f = ((z_km - z[i - 1]) / (z[i] - z[i - 1])).clamp(0.0, 1.0);
        let (lo, hi) = (self.p_hpa[i - 1].ln(), self.p_hpa[i].ln());
        (lo + f * (hi - lo)).exp()
    }

    /// Ozone molecules per cm^3 at `z_km`: linear between levels.
    pub fn ozone_cm3_at(&self, z_km: f64) -> f64 {
        let z = &self.z_km;
        let i = z.partition_point(|&v| v <= z_km).clamp(1, z.len() - 1);
        let f = ((z_km - z[i - 1]) / (z[i] - z[i - 1])).clamp(0.0, 1.0);
        self.ozone_cm3(i - 1) + f * (self.ozone_cm3(i) - self.ozone_cm3(i - 1))
    }
}

/// The profile named `name`, if there is one.
pub fn profile(name: &str) -> Option<&'static Profile> {
    profiles().iter().find(|p| p.name == name)
}

fn profiles() -> &'static [Profile] {
    static CELL: OnceLock<Vec<Profile>> = OnceLock::new();
    CELL.get_or_init(|| {
        parse(CSV).unwrap_or_else(|e| panic!("embedded table {FILE} is malformed: {e}"))
    })
}

fn parse(text: &str) -> Result<Vec<Profile>> {
    let t = crate::csv::parse(text, Path::new(FILE), FILE)?;
    let mut out: Vec<Profile> = PROFILES
        .iter()
        .map(|&name| Profile {
            name,
            z_km: Vec::new(),
            p_hpa: Vec::new(),
            t_k: Vec::new(),
            air_cm3: Vec::new(),
            h2o_ppmv: Vec::new(),
            o3_ppmv: Vec::new(),
        })
        .collect();
    for row in &t.rows {
        let Some(p) = out.iter_mut().find(|p| p.name == row.fields[0]) else {
            return Err(t.error(
                Some(row.line),
                format!("unknown profile '{}'", row.fields[0]),
            ));
        };
        let v: Vec<f64> = (1..7).map(|c| t.number(row, c)).collect::<Result<_>>()?;
        if p.z_km.last().is_some_and(|&z| v[0] <= z) || v[1..].iter().any(|&x| x < 0.0) {
            return Err(t.error(Some(row.line), "levels must rise and values be >= 0"));
        }
        p.z_km.push(v[0]);
        p.p_hpa.push(v[1]);
        p.t_k.push(v[2]);
        p.air_cm3.push(v[3]);
        p.h2o_ppmv.push(v[4]);
        p.o3_ppmv.push(v[5]);
    }
    if let Some(p) = out.iter().find(|p| p.z_km.len() < 2) {
        return Err(Error::invalid(
            FILE,
            format!("profile {} has no levels", p.name),
        ));
    }
    Ok(out)
}
