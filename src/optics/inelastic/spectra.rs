//! The emission spectra of the three inelastic processes: where light
//! absorbed (or Raman-scattered) at excitation wavelength λ' comes out.
//!
//! Each process gives, per event at λ', the expected number of photons
//! emitted into a wavelength interval and their mean energy relative to
//! the exciting photon's ([`Kind::into_interval`]), and draws one
//! emission ([`Kind::sample`]). As HydroLight does, light only moves to
//! longer wavelengths: an emission at or below λ' is not made (for
//! Raman it never is; the chlorophyll and CDOM Gaussians have a few per
//! cent of their spectra there, counted as absorbed).
//!
//! - **Raman** (water): the wavenumber shift 1/λ' − 1/λ is Walrafen's
//!   four Gaussians ([`WALRAFEN`]); one photon per event.
//! - **Chlorophyll fluorescence**: excited between 370 and 690 nm
//!   ([`CHL_EXCITATION_NM`]); emitted as a Gaussian in wavelength at 685
//!   nm with σ = 10.6 nm (25 nm FWHM); one photon per event (the quantum
//!   yield φ is the event's rate, `[water.fluorescence]
//!   chl_quantum_yield`). HydroLight's `wrfchl`, after Mobley (1994),
//!   Light and Water, Eq. 5.99.
//! - **CDOM fluorescence**: Hawes' (1992) quantum efficiency per nm of
//!   emission, η(λ', λ) = A0(λ') exp{−[(1/λ − A1/λ' − B1) / (0.6 (A2/λ' +
//!   B2))]²}, a Gaussian in wavenumber, with the constants of his fulvic
//!   acid FA7 ([`HAWES_A1`]…) and A0 from his table 310–490 nm, extended
//!   to 550 nm as HydroLight's `wrfcdom` does ([`HAWES_A0`]); zero outside
//!   310–550 nm. Its integral over emission, the quantum yield, is 1–2 %.

use crate::rng::Pcg32;

/// Walrafen's (1967) Gaussians of the wavenumber shift: (weight, centre
/// cm^-1, FWHM cm^-1). The weights sum to 1.
pub const WALRAFEN: [(f64, f64, f64); 4] = [
    (0.41, 3250.0, 210.0),
    (0.39, 3425.0, 175.0),
    (0.10, 3530.0, 140.0),
    (0.10, 3625.0, 140.0),
];

/// Excitation range of chlorophyll fluorescence (nm).
pub const CHL_EXCITATION_NM: (f64, f64) = (370.0, 690.0);
/// Centre and standard deviation of chlorophyll's emission (nm).
pub const CHL_EMISSION_NM: f64 = 685.0;
pub const CHL_SIGMA_NM: f64 = 10.6;

/// Hawes (1992) fulvic acid FA7: A1 and A2 (no unit), B1 and B2 (1/nm).
pub const HAWES_A1: f64 = 0.470;
pub const HAWES_A2: f64 = 0.407;
pub const HAWES_B1: f64 = 8.077e-4;
pub const HAWES_B2: f64 = -4.57e-4;
/// A0(λ') (1/nm) at 310, 330, ..., 550 nm: Hawes' table to 490 nm, then
/// HydroLight's extension to zero at 550 nm.
pub const HAWES_A0: [f64; 13] = [
    5.18e-5, 6.34e-5, 8.00e-5, 9.89e-5, 9.39e-5, 10.48e-5, 12.59e-5, 13.48e-5, 13.61e-5, 9.27e-5,
    4.00e-5, 1.00e-5, 0.0,
];
const HAWES_A0_FIRST_NM: f64 = 310.0;
const HAWES_A0_STEP_NM: f64 = 20.0;

/// nm · cm^-1 per 1: wavenumber (cm^-1) = 1e7 / wavelength (nm).
const NM_CM: f64 = 1.0e7;

/// Points of the Gauss–Legendre rule the fluorescence intervals use.
const GL_POINTS: usize = 8;

/// An inelastic process.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Raman,
    Chlorophyll,
    Cdom,
}

impl Kind {
    /// The scene key that turns the process on (errors and warnings).
    pub fn key(self) -> &'static str {
        match self {
            Kind::Raman => "water.raman",
            Kind::Chlorophyll => "water.fluorescence.chl_quantum_yield",
            Kind::Cdom => "water.fluorescence.cdom",
        }
    }

    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Raman => "Raman",
            Kind::Chlorophyll => "chlorophyll fluorescence",
            Kind::Cdom => "CDOM fluorescence",
        }
    }

    /// The excitation wavelengths (nm) that can emit.
    pub fn excitation_range(self) -> (f64, f64) {
        match self {
            // Light as short as 250 nm shifts to the visible only beyond 8
            // sd of the outer Gaussian.
            Kind::Raman => (250.0, f64::INFINITY),
            Kind::Chlorophyll => CHL_EXCITATION_NM,
            Kind::Cdom => (
                HAWES_A0_FIRST_NM,
                HAWES_A0_FIRST_NM + HAWES_A0_STEP_NM * (HAWES_A0.len() - 1) as f64,
            ),
        }
    }

    /// The wavelengths (nm) an event at excitation `nm` can emit into:
    /// outside them the emission is below 1e-14 of its peak.
    pub fn reach(self, nm: f64) -> (f64, f64) {
        let (lo, hi) = match self {
            Kind::Raman => {
                let (lo, hi) =
                    WALRAFEN
                        .iter()
                        .fold((f64::MAX, f64::MIN), |(lo, hi), &(_, mu, f)| {
                            let s = 8.0 * sigma_of(f);
                            (lo.min(mu - s), hi.max(mu + s))
                        });
                (emission_nm(nm, lo), emission_nm(nm, hi))
            }
            Kind::Chlorophyll => (
                CHL_EMISSION_NM - 8.0 * CHL_SIGMA_NM,
                CHL_EMISSION_NM + 8.0 * CHL_SIGMA_NM,
            ),
            Kind::Cdom => {
                let (_, mu, s) = hawes(nm);
                let far = (mu - 8.0 * s).max(1e-9);
                (1.0 / (mu + 8.0 * s), 1.0 / far)
            }
        };
        (lo.max(nm), hi)
    }

    /// Photons emitted per event at excitation `nm` when nothing is cut
    /// (the nominal yield the event's rate is scaled by): 1 for Raman and
    /// for chlorophyll within its excitation range (0 outside), Hawes'
    /// quantum yield for CDOM.
    pub fn photon_yield(self, nm: f64) -> f64 {
        match self {
            Kind::Raman => 1.0,
            Kind::Chlorophyll => chl_excites(nm) as u8 as f64,
            Kind::Cdom => {
                let (a0, mu, s) = hawes(nm);
                // ∫ η dλ = A0 ∫ G(k) / k^2 dk over the Gaussian G in
                // wavenumber k = 1/λ; 6 sd cover it.
                if a0 > 0.0 {
                    a0 * gauss_legendre(mu - 6.0 * s, mu + 6.0 * s, |k| {
                        gaussian(k, mu, s) / (k * k)
                    })
                } else {
                    0.0
                }
            }
        }
    }

    /// Per event at excitation `nm`: the expected number of photons
    /// emitted into [lo, hi] (nm) and the expected λ'/λ summed over them
    /// (their energy in units of the exciting photon's).
    pub fn into_interval(self, nm: f64, lo: f64, hi: f64) -> (f64, f64) {
        let lo = lo.max(nm);
        if hi <= lo {
            return (0.0, 0.0);
        }
        match self {
            Kind::Raman => {
                let k = NM_CM / nm;
                // λ in [lo, hi] <=> Δk in [k - 1e7/lo, k - 1e7/hi].
                let (u0, u1) = (k - NM_CM / lo, k - NM_CM / hi);
                let (mut count, mut energy) = (0.0, 0.0);
                for &(w, mu, fwhm) in &WALRAFEN {
                    let (p, mean) = gaussian_partial(mu, sigma_of(fwhm), u0, u1);
                    count += w * p;
                    // λ'/λ = (k - Δk) / k.
                    energy += w * (p - mean / k);
                }
                (count, energy)
            }
            Kind::Chlorophyll => {
                if !chl_excites(nm) {
                    return (0.0, 0.0);
                }
                let (mu, s) = (CHL_EMISSION_NM, CHL_SIGMA_NM);
                let (count, _) = gaussian_partial(mu, s, lo, hi);
                let norm = s * (2.0 * std::f64::consts::PI).sqrt();
                let energy = nm * gauss_legendre(lo, hi, |l| gaussian(l, mu, s) / l) / norm;
                (count, energy)
            }
            Kind::Cdom => {
                let (a0, mu, s) = hawes(nm);
                if a0 <= 0.0 {
                    return (0.0, 0.0);
                }
                // Per nm of λ the efficiency is A0 G(1/λ); over k = 1/λ,
                // dλ = dk / k^2.
                let (k0, k1) = (1.0 / hi, 1.0 / lo);
                let k0 = k0.max(mu - 8.0 * s);
                let k1 = k1.min(mu + 8.0 * s);
                if k1 <= k0 {
                    return (0.0, 0.0);
                }
                let count = a0 * gauss_legendre(k0, k1, |k| gaussian(k, mu, s) / (k * k));
                let energy = a0 * nm * gauss_legendre(k0, k1, |k| gaussian(k, mu, s) / k);
                (count, energy)
            }
        }
    }

    /// One emission of an event at excitation `nm`: the emitted
    /// wavelength and the photon count it carries (in expectation the
    /// counts of [`Self::into_interval`]), or None when nothing is
    /// emitted.
    pub fn sample(self, nm: f64, rng: &mut Pcg32) -> Option<(f64, f64)> {
        let (em, count) = match self {
            Kind::Raman => (
                emission_nm(nm, sample_shift(rng.uniform_f64(), rng.normal())),
                1.0,
            ),
            Kind::Chlorophyll => {
                if !chl_excites(nm) {
                    return None;
                }
                (CHL_EMISSION_NM + CHL_SIGMA_NM * rng.normal(), 1.0)
            }
            Kind::Cdom => {
                let (a0, mu, s) = hawes(nm);
                if a0 <= 0.0 {
                    return None;
                }
                // k from the Gaussian; its count A0 G(k) / k^2 over the
                // Gaussian's density G(k) / (s sqrt(2 pi)).
                let k = mu + s * rng.normal();
                if k <= 0.0 {
                    return None;
                }
                (
                    1.0 / k,
                    a0 * s * (2.0 * std::f64::consts::PI).sqrt() / (k * k),
                )
            }
        };
        (em > nm && em.is_finite()).then_some((em, count))
    }
}

/// Chlorophyll fluorescence is excited at `nm`.
fn chl_excites(nm: f64) -> bool {
    (CHL_EXCITATION_NM.0..=CHL_EXCITATION_NM.1).contains(&nm)
}

/// Hawes' efficiency at excitation `nm`: A0 (1/nm, linear in the table,
/// 0 outside it) and the emission Gaussian's mean and sd in wavenumber
/// (1/nm): exp(-[(k - μ) / (0.6 W)]^2) is a Gaussian of sd 0.6 W / √2.
fn hawes(nm: f64) -> (f64, f64, f64) {
    let t = (nm - HAWES_A0_FIRST_NM) / HAWES_A0_STEP_NM;
    let last = (HAWES_A0.len() - 1) as f64;
    let a0 = if !(0.0..=last).contains(&t) {
        0.0
    } else {
        let i = (t.floor() as usize).min(HAWES_A0.len() - 2);
        let f = t - i as f64;
        HAWES_A0[i] + (HAWES_A0[i + 1] - HAWES_A0[i]) * f
    };
    let mu = HAWES_A1 / nm + HAWES_B1;
    let w = HAWES_A2 / nm + HAWES_B2;
    (a0, mu, 0.6 * w / std::f64::consts::SQRT_2)
}

/// The unnormalised Gaussian exp(-((x - mu) / s)^2 / 2).
fn gaussian(x: f64, mu: f64, s: f64) -> f64 {
    (-0.5 * ((x - mu) / s).powi(2)).exp()
}

/// ∫ f over [a, b] by the Gauss–Legendre rule of [`GL_POINTS`] points on
/// each of 4 panels (the integrands are smooth on the scale of a band).
fn gauss_legendre(a: f64, b: f64, f: impl Fn(f64) -> f64) -> f64 {
    // Nodes and weights on [-1, 1].
    const X: [f64; GL_POINTS] = [
        -0.960_289_856_497_536_2,
        -0.796_666_477_413_626_7,
        -0.525_532_409_916_329,
        -0.183_434_642_495_649_8,
        0.183_434_642_495_649_8,
        0.525_532_409_916_329,
        0.796_666_477_413_626_7,
        0.960_289_856_497_536_2,
    ];
    const W: [f64; GL_POINTS] = [
        0.101_228_536_290_376_3,
        0.222_381_034_453_374_5,
        0.313_706_645_877_887_3,
        0.362_683_783_378_362,
        0.362_683_783_378_362,
        0.313_706_645_877_887_3,
        0.222_381_034_453_374_5,
        0.101_228_536_290_376_3,
    ];
    const PANELS: usize = 4;
    let h = (b - a) / PANELS as f64;
    let mut sum = 0.0;
    for p in 0..PANELS {
        let (c, r) = (a + h * (p as f64 + 0.5), 0.5 * h);
        sum += X.iter().zip(&W).map(|(x, w)| w * f(c + r * x)).sum::<f64>() * r;
    }
    sum
}

/// Standard deviation of a Gaussian of full width at half maximum `fwhm`.
fn sigma_of(fwhm: f64) -> f64 {
    fwhm / (2.0 * (2.0 * std::f64::consts::LN_2).sqrt())
}

/// The density of the Raman wavenumber shift Δk (per cm^-1).
pub fn shift_density(dk: f64) -> f64 {
    WALRAFEN
        .iter()
        .map(|&(w, mu, fwhm)| {
            let s = sigma_of(fwhm);
            w * gaussian(dk, mu, s) / (s * (2.0 * std::f64::consts::PI).sqrt())
        })
        .sum()
}

/// A Raman wavenumber shift (cm^-1) drawn from Walrafen's sum: `u` picks
/// the Gaussian, `z` is a standard normal deviate.
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

/// For one Gaussian (mean `mu`, sd `s`) and the interval [u0, u1]:
/// P(u0 <= X <= u1) and E[X; u0 <= X <= u1].
fn gaussian_partial(mu: f64, s: f64, u0: f64, u1: f64) -> (f64, f64) {
    let cdf = |u: f64| 0.5 * libm::erfc(-(u - mu) / (s * std::f64::consts::SQRT_2));
    let pdf = |u: f64| gaussian(u, mu, s) / (s * (2.0 * std::f64::consts::PI).sqrt());
    let p = cdf(u1) - cdf(u0);
    let tail = |u: f64| if u.is_finite() { pdf(u) } else { 0.0 };
    (p, mu * p - s * s * (tail(u1) - tail(u0)))
}
