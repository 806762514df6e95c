//! Real sensors' bands: relative spectral responses (RSR), and a cube's
//! spectra integrated over them.
//!
//! A sensor band reads sum_b w_b L_b, where L_b is the cube's band b and
//! w_b the share of the band's response R(lambda) that falls in the
//! wavelength interval cube band b covers:
//!
//! ```text
//! w_b = integral over band b of R  /  sum over bands of the same
//! ```
//!
//! i.e. the cube's spectrum is taken as constant across each of its bands
//! (which is what a band's value is: its mean over the band), and the
//! intervals tile the spectrum without overlap: each band reaches halfway
//! to its neighbours' centres, and the outer bands half their FWHM beyond
//! their centres. A sensor band whose response falls less than
//! [`MIN_COVERAGE`] inside the cube's spectral range is not made (it would
//! need light the cube does not have); the caller is told which.
//!
//! The shipped responses (`data/srf`, taken from PyPI packages; sources and
//! licences in `data/srf/README.md`) are compiled in: tables on a 1 nm grid
//! (linear between samples), or Gaussian centres and FWHMs. `csv:FILE`
//! reads either format from a file of the user's.
//!
//! Not for: writing cubes (`cube::ops::resample` does that), or the
//! camera's geometry (`scene::Sensor`).

use crate::csv::{self, CsvTable};
use crate::error::{Error, Result};
use crate::spectral::BandGrid;
use std::path::Path;

/// Least share of a sensor band's response that must fall inside the
/// cube's spectral range.
pub const MIN_COVERAGE: f64 = 0.99;

/// The sensors whose responses are shipped, and their tables.
const SHIPPED: [(&str, &str); 7] = [
    (
        "sentinel2a-msi",
        include_str!("../../data/srf/sentinel2a-msi.csv"),
    ),
    (
        "sentinel2b-msi",
        include_str!("../../data/srf/sentinel2b-msi.csv"),
    ),
    (
        "landsat8-oli",
        include_str!("../../data/srf/landsat8-oli.csv"),
    ),
    (
        "landsat9-oli",
        include_str!("../../data/srf/landsat9-oli.csv"),
    ),
    ("aviris-ng", include_str!("../../data/srf/aviris-ng.csv")),
    ("enmap", include_str!("../../data/srf/enmap.csv")),
    ("prisma", include_str!("../../data/srf/prisma.csv")),
];

/// Sensors asked for by users whose responses no reachable package
/// publishes; named so that the error can say so.
const NOT_SHIPPED: [&str; 1] = ["pace-oci"];

/// Integration step over a response (nm).
const STEP_NM: f64 = 0.05;

/// How one band responds to wavelength.
#[derive(Clone, Debug, PartialEq)]
enum Response {
    /// Samples from `start_nm` every `step_nm`, linear between them, zero
    /// outside.
    Table {
        start_nm: f64,
        step_nm: f64,
        values: Vec<f64>,
    },
    /// exp(-4 ln 2 (lambda - centre)^2 / fwhm^2).
    Gaussian { centre_nm: f64, fwhm_nm: f64 },
}

impl Response {
    fn at(&self, nm: f64) -> f64 {
        match self {
            Response::Table {
                start_nm,
                step_nm,
                values,
            } => {
                let t = (nm - start_nm) / step_nm;
                if !(t >= 0.0 && t <= (values.len() - 1) as f64) {
                    return 0.0;
                }
                let i = (t.floor() as usize).min(values.len().saturating_sub(2));
                let f = t - i as f64;
                let next = values.get(i + 1).copied().unwrap_or(values[i]);
                values[i] * (1.0 - f) + next * f
            }
            Response::Gaussian { centre_nm, fwhm_nm } => {
                let x = (nm - centre_nm) / fwhm_nm;
                (-4.0 * std::f64::consts::LN_2 * x * x).exp()
            }
        }
    }

    /// The wavelengths outside which the response is zero (a Gaussian's
    /// beyond 3 FWHM, below 1e-10 of its peak).
    fn support(&self) -> (f64, f64) {
        match self {
            Response::Table {
                start_nm,
                step_nm,
                values,
            } => (*start_nm, start_nm + step_nm * (values.len() - 1) as f64),
            Response::Gaussian { centre_nm, fwhm_nm } => {
                (centre_nm - 3.0 * fwhm_nm, centre_nm + 3.0 * fwhm_nm)
            }
        }
    }

    /// Integral of the response over [lo, hi] (midpoint rule at
    /// [`STEP_NM`]).
    fn integral(&self, lo: f64, hi: f64) -> f64 {
        let (s0, s1) = self.support();
        let (lo, hi) = (lo.max(s0), hi.min(s1));
        if hi <= lo {
            return 0.0;
        }
        let n = ((hi - lo) / STEP_NM).ceil().max(1.0) as usize;
        let h = (hi - lo) / n as f64;
        (0..n)
            .map(|i| self.at(lo + (i as f64 + 0.5) * h))
            .sum::<f64>()
            * h
    }
}

/// One band of a sensor.
#[derive(Clone, Debug, PartialEq)]
pub struct ResponseBand {
    pub name: String,
    /// Response-weighted mean wavelength (nm).
    pub centre_nm: f64,
    /// Width where the response is at least half its peak (nm).
    pub fwhm_nm: f64,
    response: Response,
}

/// A sensor's bands.
#[derive(Clone, Debug, PartialEq)]
pub struct SpectralResponse {
    pub name: String,
    pub bands: Vec<ResponseBand>,
}

/// How a sensor band is made from a cube's bands.
#[derive(Clone, Debug, PartialEq)]
pub struct BandWeights {
    /// Index into [`SpectralResponse::bands`].
    pub band: usize,
    /// (cube band, weight), weights summing to 1.
    pub weights: Vec<(usize, f64)>,
}

impl SpectralResponse {
    /// The names `named` accepts, for help texts.
    pub fn names() -> Vec<&'static str> {
        SHIPPED.iter().map(|(n, _)| *n).collect()
    }

    /// A shipped sensor by name, or `csv:FILE`.
    pub fn named(name: &str) -> Result<SpectralResponse> {
        if let Some(file) = name.strip_prefix("csv:") {
            let path = Path::new(file);
            let table = csv::read(path, "sensor")?;
            return SpectralResponse::from_table(&table, path.display().to_string());
        }
        if let Some((n, text)) = SHIPPED.iter().find(|(n, _)| *n == name) {
            let path = Path::new("data/srf").join(format!("{n}.csv"));
            let table = csv::parse(text, &path, "sensor")?;
            return SpectralResponse::from_table(&table, n.to_string());
        }
        let why = if NOT_SHIPPED.contains(&name) {
            "no response table for it is published in a package littoral can ship (see data/srf/README.md); give one as csv:FILE"
        } else {
            "unknown sensor"
        };
        Err(Error::invalid(
            "--sensor",
            format!(
                "{name}: {why}; the shipped sensors are {}, or csv:FILE",
                SpectralResponse::names().join(", ")
            ),
        ))
    }

    /// A sensor from a table: either `wavelength_nm,<band>,...` (responses
    /// on an even wavelength grid) or `band,center_nm,fwhm_nm` (Gaussians).
    pub fn from_table(t: &CsvTable, name: String) -> Result<SpectralResponse> {
        let header = t.header.as_ref().map(|(_, h)| h.clone()).ok_or_else(|| {
            t.error(
                None,
                "needs a header: wavelength_nm,<band>,... or band,center_nm,fwhm_nm",
            )
        })?;
        if t.rows.is_empty() {
            return Err(t.error(None, "has no rows"));
        }
        let bands = if header.first().map(String::as_str) == Some("wavelength_nm") {
            Self::tabulated(t, &header)?
        } else if header == ["band", "center_nm", "fwhm_nm"] {
            Self::gaussians(t)?
        } else {
            return Err(t.error(
                t.header.as_ref().map(|(l, _)| *l),
                format!(
                    "header {header:?} is neither wavelength_nm,<band>,... nor band,center_nm,fwhm_nm"
                ),
            ));
        };
        Ok(SpectralResponse { name, bands })
    }

    fn tabulated(t: &CsvTable, header: &[String]) -> Result<Vec<ResponseBand>> {
        let nm: Vec<f64> = t
            .rows
            .iter()
            .map(|r| t.number(r, 0))
            .collect::<Result<_>>()?;
        let step = if nm.len() > 1 { nm[1] - nm[0] } else { 1.0 };
        for (w, r) in nm.windows(2).zip(&t.rows[1..]) {
            if !(step > 0.0 && ((w[1] - w[0]) - step).abs() <= 1e-6 * step) {
                return Err(t.error(
                    Some(r.line),
                    format!("wavelengths must rise in even steps of {step} nm"),
                ));
            }
        }
        let mut bands = Vec::with_capacity(header.len() - 1);
        for (col, name) in header.iter().enumerate().skip(1) {
            let mut values = Vec::with_capacity(t.rows.len());
            for r in &t.rows {
                let v = t.number(r, col)?;
                if v < 0.0 {
                    return Err(
                        t.error(Some(r.line), format!("band {name}: negative response {v}"))
                    );
                }
                values.push(v);
            }
            let peak = values.iter().cloned().fold(0.0, f64::max);
            if peak <= 0.0 {
                return Err(t.error(None, format!("band {name} has no response")));
            }
            let (sum, moment) = values
                .iter()
                .zip(&nm)
                .fold((0.0, 0.0), |(s, m), (v, l)| (s + v, m + v * l));
            let half: Vec<f64> = nm
                .iter()
                .zip(&values)
                .filter(|(_, v)| **v >= 0.5 * peak)
                .map(|(l, _)| *l)
                .collect();
            bands.push(ResponseBand {
                name: name.clone(),
                centre_nm: moment / sum,
                fwhm_nm: half.last().unwrap_or(&0.0) - half.first().unwrap_or(&0.0) + step,
                response: Response::Table {
                    start_nm: nm[0],
                    step_nm: step,
                    values,
                },
            });
        }
        Ok(bands)
    }

    fn gaussians(t: &CsvTable) -> Result<Vec<ResponseBand>> {
        t.rows
            .iter()
            .map(|r| {
                let (centre_nm, fwhm_nm) = (t.number(r, 1)?, t.number(r, 2)?);
                if !(centre_nm > 0.0 && fwhm_nm > 0.0) {
                    return Err(t.error(Some(r.line), "centre and FWHM must be positive"));
                }
                Ok(ResponseBand {
                    name: r.fields[0].clone(),
                    centre_nm,
                    fwhm_nm,
                    response: Response::Gaussian { centre_nm, fwhm_nm },
                })
            })
            .collect()
    }

    /// The weights of every sensor band the cube's `grid` covers (at least
    /// [`MIN_COVERAGE`] of its response), in sensor order; the others are
    /// left out.
    pub fn weights(&self, grid: &BandGrid) -> Vec<BandWeights> {
        let edges = band_edges(grid);
        self.bands
            .iter()
            .enumerate()
            .filter_map(|(s, band)| {
                let (lo, hi) = band.response.support();
                let total = band.response.integral(lo, hi);
                let mut weights = Vec::new();
                let mut covered = 0.0;
                for (b, e) in edges.windows(2).enumerate() {
                    if e[1] <= lo || e[0] >= hi {
                        continue;
                    }
                    let w = band.response.integral(e[0], e[1]);
                    if w > 0.0 {
                        weights.push((b, w));
                        covered += w;
                    }
                }
                (total > 0.0 && covered >= MIN_COVERAGE * total).then(|| {
                    weights.iter_mut().for_each(|(_, w)| *w /= covered);
                    BandWeights { band: s, weights }
                })
            })
            .collect()
    }
}

/// The wavelength intervals of a band grid's bands: edges halfway between
/// neighbouring centres, the outer ones half a FWHM beyond the outer
/// centres (nm; one more edge than bands).
fn band_edges(grid: &BandGrid) -> Vec<f64> {
    let c: Vec<f64> = grid.centers_nm().iter().map(|&v| v as f64).collect();
    let f: Vec<f64> = grid.fwhm_nm().iter().map(|&v| v as f64).collect();
    let n = c.len();
    let mut edges = Vec::with_capacity(n + 1);
    edges.push(c[0] - 0.5 * f[0]);
    edges.extend(c.windows(2).map(|w| 0.5 * (w[0] + w[1])));
    edges.push(c[n - 1] + 0.5 * f[n - 1]);
    edges
}

#[cfg(test)]
mod tests;
