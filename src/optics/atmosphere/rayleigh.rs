//! Rayleigh scattering by air: optical depth and depolarisation after
//! Bodhaine, Wood, Dutton & Slusser (1999), "On Rayleigh optical depth
//! calculations", J. Atmos. Oceanic Technol. 16:1854.
//!
//! - Optical depth of the whole atmosphere at sea level (1013.25 hPa, 45°
//!   latitude, 360 ppm CO2): their eq. 30, their fit to the full
//!   calculation; it scales with the surface pressure.
//! - The King factor of air from those of N2 (Bates 1984), O2 (Bates 1984),
//!   Ar (1) and CO2 (1.15), weighted by their volume fractions (78.084,
//!   20.946, 0.934 and 0.036 %): Bodhaine et al. eqs. 5, 6 and 23.
//! - The depolarisation ratio rho = 6 (F - 1) / (3 + 7 F), and the phase
//!   function p(mu) = 3 / (4 pi (3 + q)) (1 + q mu^2) with q = (1 - rho) /
//!   (1 + rho) (Chandrasekhar 1950; [`crate::optics::phase::PhaseFunction::rayleigh`]).

/// Bodhaine et al.'s reference surface pressure (hPa).
pub const REFERENCE_PRESSURE_HPA: f64 = 1013.25;

/// Rayleigh optical depth of the whole atmosphere at `nm`, at the
/// reference surface pressure (Bodhaine et al. 1999, eq. 30; lambda in µm).
pub fn optical_depth(nm: f64) -> f64 {
    let l2 = (nm * 1e-3) * (nm * 1e-3);
    let il2 = 1.0 / l2;
    0.002_152_0 * (1.045_599_6 - 341.290_61 * il2 - 0.902_308_50 * l2)
        / (1.0 + 0.002_705_988_9 * il2 - 85.968_563 * l2)
}

/// The King factor of dry air with 360 ppm CO2 at `nm`.
pub fn king_factor(nm: f64) -> f64 {
    let il2 = 1.0 / ((nm * 1e-3) * (nm * 1e-3));
    let n2 = 1.034 + 3.17e-4 * il2;
    let o2 = 1.096 + 1.385e-3 * il2 + 1.448e-4 * il2 * il2;
    let (ar, co2) = (1.0, 1.15);
    let (fn2, fo2, far, fco2) = (78.084, 20.946, 0.934, 0.036);
    (fn2 * n2 + fo2 * o2 + far * ar + fco2 * co2) / (fn2 + fo2 + far + fco2)
}

/// The depolarisation ratio of air at `nm`.
pub fn depolarisation(nm: f64) -> f64 {
    let f = king_factor(nm);
    6.0 * (f - 1.0) / (3.0 + 7.0 * f)
}

/// q of the phase function 1 + q mu^2 at `nm`.
pub fn phase_q(nm: f64) -> f64 {
    let rho = depolarisation(nm);
    (1.0 - rho) / (1.0 + rho)
}
