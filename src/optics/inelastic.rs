//! Inelastic scattering by water: Raman scattering of the O–H stretch band
//! (about 3400 cm^-1), which moves light from a shorter (excitation)
//! wavelength λ' to a longer (emission) one λ.
//!
//! - **Coefficient.** b_R(λ') = 2.6e-4 (488 / λ')^5.5 m^-1: the value
//!   HydroLight uses at 488 nm (Bartlett et al. 1998, Applied Optics 37,
//!   3324, measured (2.7 ± 0.2) × 10^-4) and Bartlett's λ'^-5.5 ± 0.4 for
//!   the excitation wavelength, normalised to energy.
//! - **Loss (littoral's choice).** The light Raman scattering removes at
//!   λ' is taken to be part of the water's absorption a(λ'), not added to
//!   its extinction: the pure-water absorption tables are measured losses
//!   of light at the excitation wavelength. A Raman event is drawn as the
//!   share b_R / a of the light the water absorbs, so turning Raman on does
//!   not change the elastic transport, and a band's extinction is the same
//!   with and without it. (Added to the extinction instead, b_R would raise
//!   pure water's c by about 12 % at 400 nm.) A scene whose absorption
//!   falls below b_R somewhere is refused.
//! - **Photons are conserved.** A Raman-scattered photon's energy scales by
//!   λ' / λ.
//! - **Phase function.** (3 / 16π) (1 + 3ρ) / (1 + 2ρ) [1 + (1 − ρ) / (1 +
//!   3ρ) cos²ψ] with depolarisation ρ = 0.17 (Ge et al. 1993): the
//!   Rayleigh-like form with q = (1 − ρ) / (1 + 3ρ).
//! - **Redistribution.** The wavenumber shift Δk = 1/λ' − 1/λ is the sum
//!   of four Gaussians after Walrafen (1967), as HydroLight has it
//!   (weights 0.41, 0.39, 0.10, 0.10 at 3250, 3425, 3530 and 3625 cm^-1,
//!   FWHM 210, 175, 140 and 140 cm^-1).
//!
//! **On the band grid.** Each band stands for the spectral cell of its
//! FWHM around its centre (cut at the midpoint with a neighbour where two
//! overlap), with the radiance flat across it. [`RamanBands`] gives, for
//! each pair of bands, the spectral radiance that reaches band m per unit
//! Raman-scattered in band e: (Δ_e / Δ_m) E[(λ' / λ) 1(λ in m)] over λ'
//! uniform in e's cell and Δk from the Walrafen sum, in closed form per
//! Gaussian. Light shifted beyond the grid's last band is lost (counted in
//! `lost`); light a band would receive from excitation wavelengths below
//! the grid's first band is missing, and `missing` says how much of each
//! band's Raman source that is (for a flat excitation spectrum).

use crate::optics::phase::PhaseFunction;
use crate::spectral::BandGrid;

/// b_R at [`RAMAN_REFERENCE_NM`] (1/m).
pub const RAMAN_B_REFERENCE: f64 = 2.6e-4;
/// The excitation wavelength of [`RAMAN_B_REFERENCE`] (nm).
pub const RAMAN_REFERENCE_NM: f64 = 488.0;
/// b_R ~ λ'^-[`RAMAN_EXPONENT`] (energy normalisation, Bartlett et al. 1998).
pub const RAMAN_EXPONENT: f64 = 5.5;
/// Depolarisation ratio of water's Raman band (Ge et al. 1993).
pub const RAMAN_DEPOLARISATION: f64 = 0.17;

/// Walrafen's (1967) Gaussians of the wavenumber shift: (weight, centre
/// cm^-1, FWHM cm^-1). The weights sum to 1.
pub const WALRAFEN: [(f64, f64, f64); 4] = [
    (0.41, 3250.0, 210.0),
    (0.39, 3425.0, 175.0),
    (0.10, 3530.0, 140.0),
    (0.10, 3625.0, 140.0),
];

/// Spectral points per band cell in the closed-form transfer.
const CELL_POINTS: usize = 16;

/// nm · cm^-1 per 1: wavenumber (cm^-1) = 1e7 / wavelength (nm).
const NM_CM: f64 = 1.0e7;

/// The Raman scattering coefficient at excitation wavelength `nm` (1/m).
pub fn raman_coefficient(nm: f64) -> f64 {
    RAMAN_B_REFERENCE * (RAMAN_REFERENCE_NM / nm).powf(RAMAN_EXPONENT)
}

/// The Raman phase function (normalised over the sphere).
pub fn raman_phase() -> PhaseFunction {
    let rho = RAMAN_DEPOLARISATION;
    PhaseFunction::rayleigh((1.0 - rho) / (1.0 + 3.0 * rho)).expect("q lies in [0, 1]")
}

/// Standard deviation of a Gaussian of full width at half maximum `fwhm`.
fn sigma_of(fwhm: f64) -> f64 {
    fwhm / (2.0 * (2.0 * std::f64::consts::LN_2).sqrt())
}

/// The density of the wavenumber shift Δk (per cm^-1).
pub fn shift_density(dk: f64) -> f64 {
    WALRAFEN
        .iter()
        .map(|&(w, mu, fwhm)| {
            let s = sigma_of(fwhm);
            w * (-0.5 * ((dk - mu) / s).powi(2)).exp() / (s * (2.0 * std::f64::consts::PI).sqrt())
        })
        .sum()
}

/// A wavenumber shift (cm^-1) drawn from Walrafen's sum: `u` picks the
/// Gaussian, `z` is a standard normal deviate.
pub fn sample_shift(u: f64, z: f64) -> f64 {
    let mut acc = 0.0;
    for &(w, mu, fwhm) in &WALRAFEN {
        acc += w;
        if u < acc {
            return mu + sigma_of(fwhm) * z;
        }
    }
    let (_, mu, fwhm) = WALRAFEN[WALRAFEN.len() - 1];
    mu + sigma_of(fwhm) * z
}

/// The emission wavelength (nm) of excitation `nm` shifted by `dk` cm^-1.
pub fn emission_nm(nm: f64, dk: f64) -> f64 {
    NM_CM / (NM_CM / nm - dk)
}

/// The spectral cell (nm) each band of `bands` stands for: its FWHM
/// around its centre, cut at the midpoint with a neighbour it overlaps.
pub fn band_cells(bands: &BandGrid) -> Vec<(f64, f64)> {
    let c: Vec<f64> = bands.centers_nm().iter().map(|&x| x as f64).collect();
    let w: Vec<f64> = bands.fwhm_nm().iter().map(|&x| x as f64).collect();
    (0..c.len())
        .map(|i| {
            let mut lo = c[i] - 0.5 * w[i];
            let mut hi = c[i] + 0.5 * w[i];
            if i > 0 {
                lo = lo.max(0.5 * (c[i - 1] + c[i]));
            }
            if i + 1 < c.len() {
                hi = hi.min(0.5 * (c[i] + c[i + 1]));
            }
            (lo, hi)
        })
        .collect()
}

/// For one Gaussian (mean `mu`, sd `s`) and the interval [u0, u1]:
/// P(u0 <= X <= u1) and E[X; u0 <= X <= u1].
fn gaussian_partial(mu: f64, s: f64, u0: f64, u1: f64) -> (f64, f64) {
    let cdf = |u: f64| 0.5 * libm::erfc(-(u - mu) / (s * std::f64::consts::SQRT_2));
    let pdf =
        |u: f64| (-0.5 * ((u - mu) / s).powi(2)).exp() / (s * (2.0 * std::f64::consts::PI).sqrt());
    let p = cdf(u1) - cdf(u0);
    (p, mu * p - s * s * (pdf(u1) - pdf(u0)))
}

/// Raman scattering between the bands of a grid (see the module's notes).
#[derive(Clone, Debug)]
pub struct RamanBands {
    bands: usize,
    /// b_R at each band's centre (1/m).
    pub coefficient: Vec<f64>,
    /// `transfer[e * bands + m]`: spectral radiance reaching band m per
    /// unit Raman-scattered in band e, (Δ_e / Δ_m) E[(λ'/λ) 1(λ in m)].
    transfer: Vec<f64>,
    /// Per emission band m: sum over e of b_R(e) `transfer[e][m]` (1/m),
    /// the coefficient that turns a flat spectral radiance into m's
    /// Raman source.
    pub gain: Vec<f64>,
    /// Per excitation band: the share of its Raman-scattered photons
    /// shifted beyond the grid's last band.
    pub lost: Vec<f64>,
    /// Per emission band: the share of its Raman source (for a flat
    /// excitation spectrum) that comes from below the grid's first band
    /// and is missing.
    pub missing: Vec<f64>,
    /// Each band's spectral cell (nm).
    pub cells: Vec<(f64, f64)>,
}

impl RamanBands {
    /// The transfer on `bands`.
    pub fn new(bands: &BandGrid) -> Self {
        let nb = bands.len();
        let cells = band_cells(bands);
        let width = |i: usize| cells[i].1 - cells[i].0;
        let coefficient: Vec<f64> = bands
            .centers_nm()
            .iter()
            .map(|&c| raman_coefficient(c as f64))
            .collect();
        // Shifts beyond 8 sd of the outer Gaussians carry nothing.
        let (dk_lo, dk_hi) = WALRAFEN
            .iter()
            .fold((f64::MAX, f64::MIN), |(lo, hi), &(_, mu, f)| {
                let s = 8.0 * sigma_of(f);
                (lo.min(mu - s), hi.max(mu + s))
            });
        let mut transfer = vec![0.0; nb * nb];
        let mut lost = vec![0.0; nb];
        for e in 0..nb {
            let (lo, hi) = cells[e];
            for p in 0..CELL_POINTS {
                let nm = lo + (hi - lo) * (p as f64 + 0.5) / CELL_POINTS as f64;
                let k = NM_CM / nm;
                let (reach_lo, reach_hi) = (emission_nm(nm, dk_lo), emission_nm(nm, dk_hi));
                let mut inside = 0.0;
                for m in 0..nb {
                    let (mlo, mhi) = cells[m];
                    if mhi <= reach_lo || mlo >= reach_hi {
                        continue;
                    }
                    // λ in [mlo, mhi] <=> Δk in [k - 1e7/mlo, k - 1e7/mhi].
                    let (u0, u1) = (k - NM_CM / mlo, k - NM_CM / mhi);
                    let mut t = 0.0;
                    for &(w, mu, fwhm) in &WALRAFEN {
                        let (pr, mean) = gaussian_partial(mu, sigma_of(fwhm), u0, u1);
                        inside += w * pr;
                        // λ'/λ = (k - Δk) / k.
                        t += w * (pr - mean / k);
                    }
                    transfer[e * nb + m] += t / CELL_POINTS as f64 * width(e) / width(m);
                }
                // Shifted beyond the last band's cell (gaps between cells
                // of an explicit grid count as lost too).
                lost[e] += (1.0 - inside).max(0.0) / CELL_POINTS as f64;
            }
        }
        let gain = (0..nb)
            .map(|m| (0..nb).map(|e| coefficient[e] * transfer[e * nb + m]).sum())
            .collect();
        // What each band would receive from below the grid: Δk above
        // 1e7/λ_min - 1e7/λ... excitation below λ_min = the first cell's
        // lower edge.
        let first = cells[0].0;
        let missing = (0..nb)
            .map(|m| {
                let (mlo, mhi) = cells[m];
                (0..CELL_POINTS)
                    .map(|p| {
                        let nm = mlo + (mhi - mlo) * (p as f64 + 0.5) / CELL_POINTS as f64;
                        // Excitation at 1e7 / (1e7/nm + Δk) < first <=> Δk > 1e7/first - 1e7/nm.
                        let threshold = NM_CM / first - NM_CM / nm;
                        WALRAFEN
                            .iter()
                            .map(|&(w, mu, f)| {
                                w * gaussian_partial(mu, sigma_of(f), threshold, f64::INFINITY).0
                            })
                            .sum::<f64>()
                    })
                    .sum::<f64>()
                    / CELL_POINTS as f64
            })
            .collect();
        RamanBands {
            bands: nb,
            coefficient,
            transfer,
            gain,
            lost,
            missing,
            cells,
        }
    }

    /// Number of bands.
    pub fn len(&self) -> usize {
        self.bands
    }

    /// Always false: a grid holds at least one band.
    pub fn is_empty(&self) -> bool {
        self.bands == 0
    }

    /// A warning naming the bands that lack more than 1 % of their Raman
    /// light because its excitation lies below the grid's first band, or
    /// None; `centers_nm` are the bands' centres.
    pub fn missing_warning(&self, centers_nm: &[f32]) -> Option<String> {
        let short: Vec<usize> = (0..self.bands)
            .filter(|&m| self.missing[m] > 0.01)
            .collect();
        let (&first, &last) = (short.first()?, short.last()?);
        let (lo, hi) = short.iter().fold((f64::MAX, 0.0f64), |(lo, hi), &m| {
            (lo.min(self.missing[m]), hi.max(self.missing[m]))
        });
        Some(format!(
            "water.raman: {} bands from {:.1} to {:.1} nm lack {:.0}-{:.0} % of their Raman light (for a flat excitation spectrum): it is excited below the grid's first band, at {:.1} nm; start the grid lower to include it",
            short.len(),
            centers_nm[first],
            centers_nm[last],
            lo * 100.0,
            hi * 100.0,
            self.cells[0].0
        ))
    }

    /// Spectral radiance reaching band `m` per unit Raman-scattered in band `e`.
    #[inline]
    pub fn transfer(&self, e: usize, m: usize) -> f64 {
        self.transfer[e * self.bands + m]
    }
}

#[cfg(test)]
mod tests;
