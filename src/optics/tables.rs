//! Embedded spectral data tables and their average over a sensor band.
//!
//! Design note: every optical input that is a measured function of
//! wavelength (pure-water absorption and scattering, phytoplankton
//! coefficients, the solar spectrum, bottom albedo, colour-matching
//! functions) is a [`Table`]: samples linear between breakpoints. The CSVs in
//! `data/` are compiled in with `include_str!` and parsed once on first use,
//! so a run needs no external files; users may supply their own spectra with
//! [`Table::from_csv_file`]. The simulation never looks a table up at a
//! single wavelength: it asks for [`Table::band_averages`] over the
//! [`BandGrid`], once, when a scene is set up. This module is not for the
//! parametric models built on these tables (IOP mixing, phase functions).
//!
//! Units: wavelength in nm everywhere; values in the units of the source:
//!
//! | accessor | quantity | units | range (nm) | source |
//! |---|---|---|---|---|
//! | [`water_absorption`] | a_w | 1/m | 380–1000 | Pope & Fry 1997 to 727.5 nm, Kou et al. 1993 above |
//! | [`seawater_scattering`] | b_w | 1/m | 350–850 | Smith & Baker 1981 (Morel 1974 seawater) |
//! | [`bricaud_a_phi`], [`bricaud_a_p`] | A, E with a = A Chl^E | 1/m, – | 400–700 | Bricaud et al. 1998 |
//! | [`solar`], [`sky_diffuse_irradiance`] | spectral irradiance | W m^-2 nm^-1 | 280–4000 | ASTM G173-03 |
//! | [`cie_1931`] | xbar, ybar, zbar | – | 360–830 | CIE 1931 2° observer |
//! | [`bottom_reflectance`] | irradiance reflectance R | 0–1 | 400–800 | ASU (G. Asner) / WASI6 seagrass |
//!
//! Full citations and licence notes are in each CSV's `#` header and in
//! `data/README.md`.
//!
//! **Out-of-range policy: refuse, never extrapolate.** [`Table::at`] returns
//! `None` outside the tabulated range, and [`Table::band_average`] returns an
//! error naming the table and the band when the band centre lies outside it.
//! A band whose centre is inside but whose response (truncated at ±3 sigma)
//! runs past an end is averaged over the overlap only, renormalised by the
//! response over that same overlap; [`Table::band_coverage`] reports the
//! fraction of the response that was kept, so a caller can warn (once) when
//! it is small. Extrapolating measured spectra (water absorption rises
//! steeply past 700 nm, the bottom spectra are noisy past their ends) would
//! invent data; a truncated average stays within the measurements.
//! This module never prints: warning is the caller's decision.

use std::path::Path;
use std::sync::OnceLock;

use crate::error::{Error, Result};
use crate::spectral::BandGrid;

/// FWHM of a Gaussian in units of its standard deviation, 2 sqrt(2 ln 2).
pub const FWHM_PER_SIGMA: f64 = 2.354_820_045_030_949_4;

/// The Gaussian band response is truncated at this many standard deviations
/// either side of the centre (it keeps 99.73 % of the weight).
pub const RESPONSE_HALF_WIDTH_SIGMA: f64 = 3.0;

/// Quadrature sub-steps are at most this many sigma wide. With 5-point
/// Gauss–Legendre on each, the Gaussian x linear product is integrated to
/// about machine precision (the rule is exact for degree-9 polynomials and
/// the Gaussian varies little across sigma/4).
const MAX_STEP_SIGMA: f64 = 0.25;

/// 5-point Gauss–Legendre nodes and weights on [-1, 1].
const GL_NODES: [f64; 5] = [
    -0.906_179_845_938_664,
    -0.538_469_310_105_683_1,
    0.0,
    0.538_469_310_105_683_1,
    0.906_179_845_938_664,
];
const GL_WEIGHTS: [f64; 5] = [
    0.236_926_885_056_189_1,
    0.478_628_670_499_366_5,
    0.568_888_888_888_888_9,
    0.478_628_670_499_366_5,
    0.236_926_885_056_189_1,
];

/// A tabulated function of wavelength (nm), linear between samples.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    x_nm: Vec<f64>,
    y: Vec<f64>,
    name: String,
}

impl Table {
    /// A table from samples: at least two points, wavelengths finite, positive
    /// and strictly increasing, values finite. Errors name `name`.
    pub fn new(name: &str, x_nm: Vec<f64>, y: Vec<f64>) -> Result<Table> {
        if x_nm.len() != y.len() {
            return Err(Error::invalid(
                name,
                format!("{} wavelengths but {} values", x_nm.len(), y.len()),
            ));
        }
        if x_nm.len() < 2 {
            return Err(Error::invalid(
                name,
                format!("needs at least 2 samples, got {}", x_nm.len()),
            ));
        }
        if let Some(i) = x_nm.iter().position(|x| !(x.is_finite() && *x > 0.0)) {
            return Err(Error::invalid(
                name,
                format!(
                    "wavelength #{i} ({}) is not a positive number of nm",
                    x_nm[i]
                ),
            ));
        }
        if let Some(i) = x_nm.windows(2).position(|w| w[1] <= w[0]) {
            return Err(Error::invalid(
                name,
                format!(
                    "wavelengths must increase strictly: #{} ({} nm) follows {} nm",
                    i + 1,
                    x_nm[i + 1],
                    x_nm[i]
                ),
            ));
        }
        if let Some(i) = y.iter().position(|v| !v.is_finite()) {
            return Err(Error::invalid(
                name,
                format!("value #{i} at {} nm is not finite ({})", x_nm[i], y[i]),
            ));
        }
        Ok(Table {
            x_nm,
            y,
            name: name.to_string(),
        })
    }

    /// A user-supplied spectrum: a CSV file of optional `#` comment lines, an
    /// optional header line (one with no numeric field), then `nm,value` rows.
    /// Blank lines are skipped. `field` is the configuration field that named
    /// the file; it becomes part of the table's name and of every error, which
    /// also carries the path and, where there is one, the 1-based line.
    pub fn from_csv_file(path: &Path, field: &str) -> Result<Table> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, "read", e))?;
        let name = format!("{field} ({})", path.display());
        let mut tables = parse_csv(&text, path, field, &name, Columns::UserPair)?;
        // UserPair always yields exactly one table.
        Ok(tables.remove(0))
    }

    /// The table's name (embedded tables: `file.csv:column`).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// First and last tabulated wavelength, nm.
    pub fn range_nm(&self) -> (f64, f64) {
        (self.x_nm[0], self.x_nm[self.x_nm.len() - 1])
    }

    /// Tabulated wavelengths, nm.
    pub fn x_nm(&self) -> &[f64] {
        &self.x_nm
    }

    /// Tabulated values.
    pub fn y(&self) -> &[f64] {
        &self.y
    }

    /// The value at `nm`, linear between samples; `None` outside the range
    /// (or for NaN) — see the module's out-of-range policy.
    pub fn at(&self, nm: f64) -> Option<f64> {
        let (lo, hi) = self.range_nm();
        if !(lo..=hi).contains(&nm) {
            return None;
        }
        Some(self.lerp(self.segment(nm), nm))
    }

    /// Integral of the (piecewise-linear) table over its whole range, i.e.
    /// the trapezoid rule on the samples; units of y times nm.
    pub fn integral(&self) -> f64 {
        self.x_nm
            .windows(2)
            .zip(self.y.windows(2))
            .map(|(x, y)| 0.5 * (x[1] - x[0]) * (y[0] + y[1]))
            .sum()
    }

    /// Average of the table weighted by a Gaussian band response of centre
    /// `center_nm` and full width at half maximum `fwhm_nm`
    /// (sigma = FWHM / 2.3548), truncated at ±3 sigma.
    ///
    /// The integrals run over the overlap of the truncated response with the
    /// table, split at the table's breakpoints (where y is linear) and into
    /// sub-steps of at most sigma/4, each by 5-point Gauss–Legendre; the
    /// result is normalised by the response's integral over the same overlap.
    /// Errors, naming the table and the band, if the centre lies outside the
    /// table's range or the FWHM is not a positive number.
    pub fn band_average(&self, center_nm: f64, fwhm_nm: f64) -> Result<f64> {
        self.band_average_inner(center_nm, fwhm_nm, None)
    }

    /// [`Table::band_average`] for every band of `bands`, in band order.
    pub fn band_averages(&self, bands: &BandGrid) -> Result<Vec<f64>> {
        bands
            .centers_nm()
            .iter()
            .zip(bands.fwhm_nm())
            .enumerate()
            .map(|(i, (&c, &w))| self.band_average_inner(f64::from(c), f64::from(w), Some(i)))
            .collect()
    }

    /// Fraction (0..=1) of the band's truncated response that lies inside the
    /// table's range: 1 for a band well inside, about 0.5 for a band centred
    /// on an end, 0 for a band wholly outside. Lets callers warn about edge
    /// bands averaged over a partial overlap. Invalid FWHM gives 0.
    pub fn band_coverage(&self, center_nm: f64, fwhm_nm: f64) -> f64 {
        if !(center_nm.is_finite() && fwhm_nm.is_finite() && fwhm_nm > 0.0) {
            return 0.0;
        }
        let sigma = fwhm_nm / FWHM_PER_SIGMA;
        let half = RESPONSE_HALF_WIDTH_SIGMA * sigma;
        let (lo, hi) = self.range_nm();
        let (a, b) = (lo.max(center_nm - half), hi.min(center_nm + half));
        if b <= a {
            return 0.0;
        }
        let full = gaussian_integral(center_nm - half, center_nm + half, center_nm, sigma);
        if full > 0.0 {
            (gaussian_integral(a, b, center_nm, sigma) / full).clamp(0.0, 1.0)
        } else {
            1.0
        }
    }

    fn band_average_inner(&self, center_nm: f64, fwhm_nm: f64, band: Option<usize>) -> Result<f64> {
        let band_text = || {
            let index = band.map(|i| format!("band {i} ")).unwrap_or_default();
            // The grid's centres are f32: printed as such (852.7559 nm, not
            // the f64 852.7559204101563).
            format!(
                "{index}(centre {} nm, FWHM {} nm)",
                center_nm as f32, fwhm_nm as f32
            )
        };
        let (lo, hi) = self.range_nm();
        if !(fwhm_nm.is_finite() && fwhm_nm > 0.0) {
            return Err(Error::invalid(
                &self.name,
                format!("{}: FWHM must be a positive number of nm", band_text()),
            ));
        }
        if !(lo..=hi).contains(&center_nm) {
            return Err(Error::invalid(
                &self.name,
                format!(
                    "{}: centre lies outside the tabulated range {lo}..{hi} nm",
                    band_text()
                ),
            ));
        }
        let sigma = fwhm_nm / FWHM_PER_SIGMA;
        let half = RESPONSE_HALF_WIDTH_SIGMA * sigma;
        let (a, b) = (lo.max(center_nm - half), hi.min(center_nm + half));
        let max_step = MAX_STEP_SIGMA * sigma;

        let (mut weighted, mut weight) = (0.0, 0.0);
        let mut j = self.segment(a);
        while j + 1 < self.x_nm.len() && self.x_nm[j] < b {
            let (s0, s1) = (self.x_nm[j].max(a), self.x_nm[j + 1].min(b));
            if s1 > s0 {
                let steps = ((s1 - s0) / max_step).ceil().max(1.0);
                let h = (s1 - s0) / steps;
                for k in 0..steps as usize {
                    let mid = s0 + (k as f64 + 0.5) * h;
                    for (t, w) in GL_NODES.iter().zip(GL_WEIGHTS) {
                        let x = mid + 0.5 * h * t;
                        let g = w * 0.5 * h * gaussian(x, center_nm, sigma);
                        weighted += g * self.lerp(j, x);
                        weight += g;
                    }
                }
            }
            j += 1;
        }
        if weight > 0.0 {
            Ok(weighted / weight)
        } else {
            // The response is too narrow to resolve next to the centre (it
            // underflowed): the limit of a vanishing band is the point value.
            Ok(self.lerp(self.segment(center_nm), center_nm))
        }
    }

    /// Index j of the segment [x_j, x_j+1] holding `nm` (clamped to the ends).
    fn segment(&self, nm: f64) -> usize {
        let n = self.x_nm.len();
        self.x_nm
            .partition_point(|&x| x <= nm)
            .saturating_sub(1)
            .min(n - 2)
    }

    fn lerp(&self, j: usize, nm: f64) -> f64 {
        let (x0, x1) = (self.x_nm[j], self.x_nm[j + 1]);
        let (y0, y1) = (self.y[j], self.y[j + 1]);
        y0 + (y1 - y0) * ((nm - x0) / (x1 - x0))
    }
}

/// The unnormalised Gaussian response at `x`.
fn gaussian(x: f64, center: f64, sigma: f64) -> f64 {
    let u = (x - center) / sigma;
    (-0.5 * u * u).exp()
}

/// Integral of [`gaussian`] over [a, b] by the same quadrature as the band
/// average (std has no erf).
fn gaussian_integral(a: f64, b: f64, center: f64, sigma: f64) -> f64 {
    let steps = ((b - a) / (MAX_STEP_SIGMA * sigma)).ceil().max(1.0);
    let h = (b - a) / steps;
    (0..steps as usize)
        .map(|k| {
            let mid = a + (k as f64 + 0.5) * h;
            GL_NODES
                .iter()
                .zip(GL_WEIGHTS)
                .map(|(t, w)| w * 0.5 * h * gaussian(mid + 0.5 * h * t, center, sigma))
                .sum::<f64>()
        })
        .sum()
}

/// Which value columns of a CSV to read.
enum Columns<'a> {
    /// A user file: exactly `nm,value`; the header line is optional.
    UserPair,
    /// An embedded file: the header is required and names these columns
    /// (the first column is always the wavelength); other columns are ignored.
    Named(&'a [&'a str]),
}

/// Parses CSV `text` (read from `path`) into one table per value column.
/// Errors carry `path`, the 1-based line and `field` (the configuration field
/// for a user file, the file name for an embedded one). Table names are
/// `name` for a user file and `name:column` for an embedded one.
fn parse_csv(
    text: &str,
    path: &Path,
    field: &str,
    name: &str,
    columns: Columns,
) -> Result<Vec<Table>> {
    let csv = crate::csv::parse(text, path, field)?;
    // Value columns, and the fields a row has.
    let wanted: Vec<usize> = match columns {
        Columns::UserPair => {
            csv.expect_width(2, "2 fields (nm,value)")?;
            vec![1]
        }
        Columns::Named(names) => names.iter().map(|n| csv.column(n)).collect::<Result<_>>()?,
    };
    let mut ys: Vec<Vec<f64>> = vec![Vec::with_capacity(csv.rows.len()); wanted.len()];
    let mut x_nm: Vec<f64> = Vec::with_capacity(csv.rows.len());
    for row in &csv.rows {
        let x = csv.number(row, 0)?;
        if x <= 0.0 {
            return Err(csv.error(Some(row.line), format!("wavelength {x} nm is not positive")));
        }
        if let Some(&prev) = x_nm.last() {
            if x <= prev {
                return Err(csv.error(
                    Some(row.line),
                    format!("wavelengths must increase strictly: {x} nm follows {prev} nm"),
                ));
            }
        }
        for (k, &col) in wanted.iter().enumerate() {
            let y = csv.number(row, col)?;
            // A spectrum, a reflectance or a phase function: never negative
            // (a negative spectrum would otherwise surface only as a scene
            // that emits no light).
            if matches!(columns, Columns::UserPair) && y < 0.0 {
                return Err(csv.error(Some(row.line), format!("value {y} at {x} is negative")));
            }
            ys[k].push(y);
        }
        x_nm.push(x);
    }
    if x_nm.len() < 2 {
        return Err(csv.error(
            None,
            format!("needs at least 2 data rows, found {}", x_nm.len()),
        ));
    }
    let names: Vec<String> = match columns {
        Columns::UserPair => vec![name.to_string()],
        Columns::Named(cols) => cols.iter().map(|c| format!("{name}:{c}")).collect(),
    };
    names
        .iter()
        .zip(ys)
        .map(|(n, y)| Table::new(n, x_nm.clone(), y))
        .collect()
}

/// Parses an embedded file once. The files are compiled in and checked by
/// this module's tests, so a parse failure is a build defect, not bad input.
fn embedded(
    cell: &'static OnceLock<Vec<Table>>,
    file: &str,
    text: &str,
    columns: &[&str],
) -> &'static [Table] {
    cell.get_or_init(|| {
        parse_csv(text, Path::new(file), file, file, Columns::Named(columns))
            .unwrap_or_else(|e| panic!("embedded table {file} is malformed: {e}"))
    })
}

const AW_FILE: &str = "aw_composite_380_1000.csv";
const AW_CSV: &str = include_str!("../../data/aw_composite_380_1000.csv");
const BW_FILE: &str = "bw_seawater_smith_baker_1981.csv";
const BW_CSV: &str = include_str!("../../data/bw_seawater_smith_baker_1981.csv");
const APH_FILE: &str = "aph_bricaud1998.csv";
const APH_CSV: &str = include_str!("../../data/aph_bricaud1998.csv");
const SOLAR_FILE: &str = "astm_g173_solar.csv";
const SOLAR_CSV: &str = include_str!("../../data/astm_g173_solar.csv");
const BOTTOM_FILE: &str = "bottom_reflectance_asu_wasi.csv";
const BOTTOM_CSV: &str = include_str!("../../data/bottom_reflectance_asu_wasi.csv");
const OZONE_FILE: &str = "ozone_leckner1978.csv";
const OZONE_CSV: &str = include_str!("../../data/ozone_leckner1978.csv");
const CIE_FILE: &str = "cie1931_2deg_cmf.csv";
const CIE_CSV: &str = include_str!("../../data/cie1931_2deg_cmf.csv");

/// Pure-water absorption a_w, 1/m, 380–1000 nm: Pope & Fry (1997) to
/// 727.5 nm, Kou et al. (1993) above (junction smooth to ~5 %).
pub fn water_absorption() -> &'static Table {
    static CELL: OnceLock<Vec<Table>> = OnceLock::new();
    &embedded(&CELL, AW_FILE, AW_CSV, &["aw_per_m"])[0]
}

/// Pure-seawater scattering b_w, 1/m, 350–850 nm (Smith & Baker 1981,
/// following Morel 1974). Backscattering is b_w / 2.
pub fn seawater_scattering() -> &'static Table {
    static CELL: OnceLock<Vec<Table>> = OnceLock::new();
    &embedded(&CELL, BW_FILE, BW_CSV, &["bw_per_m"])[0]
}

fn bricaud() -> &'static [Table] {
    static CELL: OnceLock<Vec<Table>> = OnceLock::new();
    embedded(&CELL, APH_FILE, APH_CSV, &["A_phi", "E_phi", "A_p", "E_p"])
}

/// Bricaud et al. (1998) phytoplankton absorption, 400–700 nm:
/// (A_phi, E_phi) with a_phi(l) = A_phi(l) Chl^E_phi(l) in 1/m, Chl in
/// mg m^-3. E_phi is the exponent itself, not 1 - E.
pub fn bricaud_a_phi() -> (&'static Table, &'static Table) {
    let t = bricaud();
    (&t[0], &t[1])
}

/// Bricaud et al. (1998) total particulate absorption, 400–700 nm:
/// (A_p, E_p) with a_p = A_p Chl^E_p in 1/m.
pub fn bricaud_a_p() -> (&'static Table, &'static Table) {
    let t = bricaud();
    (&t[2], &t[3])
}

/// Ozone absorption per atm-cm of ozone (1/cm at STP), 300–800 nm: Bird &
/// Riordan (1986) after Leckner (1978).
pub fn ozone_absorption() -> &'static Table {
    static CELL: OnceLock<Vec<Table>> = OnceLock::new();
    &embedded(&CELL, OZONE_FILE, OZONE_CSV, &["k_o3_per_atm_cm"])[0]
}

/// The three ASTM G173-03 spectra.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SolarSpectrum {
    /// Top of atmosphere (AM0).
    Extraterrestrial,
    /// AM1.5 hemispherical on a 37° tilted surface facing the sun.
    GlobalTilt,
    /// AM1.5 direct normal, including circumsolar.
    DirectCircumsolar,
}

fn solar_tables() -> &'static [Table] {
    static CELL: OnceLock<Vec<Table>> = OnceLock::new();
    embedded(
        &CELL,
        SOLAR_FILE,
        SOLAR_CSV,
        &[
            "extraterrestrial_W_m2_nm",
            "global_tilt_W_m2_nm",
            "direct_circumsolar_W_m2_nm",
        ],
    )
}

/// An ASTM G173-03 solar spectrum, W m^-2 nm^-1, 280–4000 nm.
pub fn solar(which: SolarSpectrum) -> &'static Table {
    let t = solar_tables();
    match which {
        SolarSpectrum::Extraterrestrial => &t[0],
        SolarSpectrum::GlobalTilt => &t[1],
        SolarSpectrum::DirectCircumsolar => &t[2],
    }
}

/// A diffuse-sky irradiance proxy, W m^-2 nm^-1, 280–4000 nm: ASTM G173
/// global-tilt minus direct+circumsolar, clamped at >= 0.
///
/// Chosen because G173 is the one reference that gives both components from
/// the same atmosphere, so the proxy has a consistent sky-blue spectral
/// shape. It is not an exact horizontal diffuse irradiance: the global
/// spectrum is on a 37° tilt facing the sun (direct incidence ~11°, so the
/// tilted plane receives ~0.98 of the direct normal beam and the difference
/// removes ~2 % of the direct too much) and the tilted plane also sees some
/// ground-reflected light. The clamp removes tiny negative differences where
/// both spectra are ~0 in the deep water-vapour bands (254 samples above
/// 2700 nm). Integral 280–4000 nm: ~100.3 W m^-2. Scale it to the scene's
/// sky irradiance rather than treating the magnitude as exact.
pub fn sky_diffuse_irradiance() -> &'static Table {
    static CELL: OnceLock<Table> = OnceLock::new();
    CELL.get_or_init(|| {
        let global = solar(SolarSpectrum::GlobalTilt);
        let direct = solar(SolarSpectrum::DirectCircumsolar);
        // Both columns come from one file, so they share the wavelength grid.
        let y = global
            .y()
            .iter()
            .zip(direct.y())
            .map(|(g, d)| (g - d).max(0.0))
            .collect();
        Table::new(
            "astm_g173_solar.csv:global_tilt-direct_circumsolar",
            global.x_nm().to_vec(),
            y,
        )
        .unwrap_or_else(|e| panic!("sky diffuse proxy: {e}"))
    })
}

/// CIE 1931 2° colour-matching functions (xbar, ybar, zbar), dimensionless,
/// 360–830 nm; ybar is the photopic luminous efficiency V(l).
pub fn cie_1931() -> (&'static Table, &'static Table, &'static Table) {
    static CELL: OnceLock<Vec<Table>> = OnceLock::new();
    let t = embedded(&CELL, CIE_FILE, CIE_CSV, &["xbar", "ybar", "zbar"]);
    (&t[0], &t[1], &t[2])
}

/// The bottom types of [`bottom_reflectance`], as named in the data file:
/// sand, coral, cca (crustose coralline algae), macroalgae, seagrass
/// (Zostera marina).
pub const BOTTOM_TYPES: &[&str] = &["sand", "coral", "cca", "macroalgae", "seagrass"];

/// Bottom irradiance reflectance (albedo, 0–1), 400–800 nm, of one of
/// [`BOTTOM_TYPES`] (matched case-insensitively). Lambertian BRDF: R / pi.
/// Above ~750 nm the in-water spectra are less reliable.
pub fn bottom_reflectance(kind: &str) -> Result<&'static Table> {
    static CELL: OnceLock<Vec<Table>> = OnceLock::new();
    let tables = embedded(&CELL, BOTTOM_FILE, BOTTOM_CSV, BOTTOM_TYPES);
    BOTTOM_TYPES
        .iter()
        .position(|k| k.eq_ignore_ascii_case(kind.trim()))
        .map(|i| &tables[i])
        .ok_or_else(|| {
            Error::invalid(
                "bottom type",
                format!(
                    "unknown kind '{kind}'; known kinds: {}",
                    BOTTOM_TYPES.join(", ")
                ),
            )
        })
}

#[cfg(test)]
mod tests;
