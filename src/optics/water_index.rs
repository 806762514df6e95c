//! Refractive index of seawater (real part, relative to air) as a function of
//! wavelength, temperature and salinity, after Quan & Fry (1995).
//!
//! Units and conventions: wavelength in nm, temperature in °C, salinity in
//! PSU. The source data use ‰ by weight, which is numerically the same for
//! this purpose. The index is relative to air at atmospheric pressure, like
//! the Austin & Halikas (1976) data it was fitted to. To get the index
//! relative to vacuum, multiply by the index of air (about 1.00028 at 550 nm,
//! Ciddor 1996), as Zhang, Hu & He (2009) do. The source data are at spectral
//! lines, conventionally quoted as wavelengths in air. If `wavelength_nm` is
//! taken as the wavelength in vacuum instead, n changes by at most about 1e-5
//! (at 400 nm), which is within the fit's accuracy. The model has no pressure
//! term.
//!
//! Source: X. Quan and E. S. Fry, "Empirical equation for the index of
//! refraction of seawater", Appl. Opt. 34(18), 3477–3480 (1995). It is a
//! ten-term fit to the data compiled by R. W. Austin and G. Halikas, "The
//! index of refraction of seawater", SIO Ref. 76-1 (1976):
//!
//! ```text
//! n(S, T, λ) = n0 + (n1 + n2 T + n3 T²) S + n4 T² + (n5 + n6 S + n7 T)/λ
//!              + n8/λ² + n9/λ³
//! ```
//!
//! The coefficients below match several independent implementations: the
//! seawater-scattering code of Zhang, Hu & He (2009, Opt. Express 17,
//! 5698), the `seawater_nsw` routine of NASA's ocean-colour processing code,
//! and the ocean-colour model `twright1521/OceanColorPolarizationModel_V2`.
//! One widely copied rendering implementation has n1 = 1.799e-4, a typo: the
//! Millard & Seaver salinity test below confirms 1.779e-4 independently.
//!
//! Validity: 400–700 nm, 0–30 °C, 0–35 PSU, at atmospheric pressure. Quan &
//! Fry state that the equation reproduces the original data within their
//! experimental error. One later implementation gives that error as about
//! 3e-5. The tests below check the formula against independent data. For
//! pure water, the index stays within 3.5e-5 of IAPWS R9-97 across 400–700
//! nm and 0–30 °C (converted from vacuum to air with Ciddor 1996). For
//! salinity, the change in n from 0 to 35 PSU stays within 3.5e-5 of Millard
//! & Seaver (1990) at 500–700 nm.
//!
//! Outside that range the formula is still evaluated as written, with no
//! clamping or error, so the result is an extrapolation. For pure water at
//! 20 °C it reads higher than IAPWS R9-97 and Daimon & Masumura (2007), and
//! the gap grows with distance from the range:
//!
//! | wavelength | too high by        |
//! |------------|--------------------|
//! | 350 nm     | about 1.8–1.9e-4   |
//! | 800 nm     | about 1.2e-4       |
//! | 900 nm     | about 3.2–3.3e-4   |
//! | 1000 nm    | about 6.7–7.1e-4   |
//! | 1100 nm    | about 1.2–1.3e-3   |
//!
//! For scale, the true index falls by about 5.1e-3 from 700 to 1000 nm,
//! and the formula gives only 4.4e-3 of that fall. Huibers (1997, Appl.
//! Opt. 36, 3785) extends the range to 200–1100 nm, but with a refitted
//! three-term model derived from this one, not with these coefficients.
//! Temperatures below 0 °C and salinities above 35 PSU are also
//! extrapolations.
//!
//! Other properties of the formula: n falls steadily as wavelength rises, at
//! every positive wavelength. For 0–30 °C and S ≥ 0, it also falls steadily as
//! temperature rises. IAPWS R9-97 at 1 atm does the same: the index of water
//! has no maximum at 4 °C, unlike its density. A wavelength that is zero or
//! negative gives a non-finite or meaningless value.
//!
//! Not for: absorption (the imaginary part), the effect of pressure, or the
//! group index.

/// Constant term.
const N0: f64 = 1.31405;
/// Salinity term (per PSU).
const N1: f64 = 1.779e-4;
/// Salinity × temperature term (per PSU per °C).
const N2: f64 = -1.05e-6;
/// Salinity × temperature² term (per PSU per °C²).
const N3: f64 = 1.6e-8;
/// Temperature² term (per °C²).
const N4: f64 = -2.02e-6;
/// 1/λ term (nm).
const N5: f64 = 15.868;
/// Salinity / λ term (nm per PSU).
const N6: f64 = 0.01155;
/// Temperature / λ term (nm per °C).
const N7: f64 = -0.00423;
/// 1/λ² term (nm²).
const N8: f64 = -4382.0;
/// 1/λ³ term (nm³).
const N9: f64 = 1.1455e6;

/// Real refractive index of seawater relative to air (Quan & Fry 1995) at
/// `wavelength_nm` (nm), `temperature_c` (°C) and `salinity_psu` (PSU).
/// Valid for 400–700 nm, 0–30 °C and 0–35 PSU at atmospheric pressure,
/// where it is accurate to about 3e-5. Outside that range the formula is
/// still evaluated as written, so the value is an extrapolation (see the
/// module doc for the errors at 800–1000 nm). Multiply by the index of air
/// to get the index relative to vacuum.
pub fn quan_fry(wavelength_nm: f64, temperature_c: f64, salinity_psu: f64) -> f64 {
    let t = temperature_c;
    let s = salinity_psu;
    let x = 1.0 / wavelength_nm;
    let salt = (N1 + N2 * t + N3 * t * t) * s;
    let dispersion = x * ((N5 + N6 * s + N7 * t) + x * (N8 + x * N9));
    N0 + salt + N4 * t * t + dispersion
}

#[cfg(test)]
mod tests;
