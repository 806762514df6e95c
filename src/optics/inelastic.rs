//! Inelastic light: water Raman scattering, and chlorophyll and CDOM
//! fluorescence, which move light from a shorter (excitation) wavelength
//! λ' to a longer (emission) one λ. The emission spectra are in
//! [`spectra`]; this module puts them on the band grid.
//!
//! - **Raman coefficient.** b_R(λ') = 2.6e-4 (488 / λ')^5.5 m^-1: the
//!   value HydroLight uses at 488 nm (Bartlett et al. 1998, Applied
//!   Optics 37, 3324, measured (2.7 ± 0.2) × 10^-4) and Bartlett's λ'^-5.5
//!   ± 0.4 for the excitation wavelength, normalised to energy.
//! - **Fluorescence coefficients.** Chlorophyll: φ a_φ(x, λ'), the light
//!   phytoplankton absorb times the quantum yield φ (`[water.fluorescence]
//!   chl_quantum_yield`, default 0.01). CDOM: a_g(x, λ'), the light CDOM
//!   absorbs, with Hawes' quantum efficiency (1–2 %) in its spectrum.
//! - **Loss (littoral's choice).** Every process is part of the water's
//!   absorption a(λ'), not added to its extinction: the pure-water
//!   absorption tables are measured losses of light at the excitation
//!   wavelength, and fluorescence is the re-emission of light phytoplankton
//!   or CDOM absorbed. An event is drawn as the share c_k / a of the light
//!   the water absorbs, so turning inelastic light on does not change the
//!   elastic transport. (Added to the extinction instead, b_R would raise
//!   pure water's c by about 12 % at 400 nm.) A scene whose absorption
//!   falls below b_R somewhere is refused.
//! - **Photons are conserved** (times the quantum yield for
//!   fluorescence): an emitted photon's energy is λ' / λ of the exciting
//!   one's.
//! - **Phase functions.** Raman: (3 / 16π) (1 + 3ρ) / (1 + 2ρ) [1 + (1 −
//!   ρ) / (1 + 3ρ) cos²ψ] with depolarisation ρ = 0.17 (Ge et al. 1993),
//!   the Rayleigh-like form with q = (1 − ρ) / (1 + 3ρ). Fluorescence is
//!   isotropic.
//!
//! **On the band grid.** Each band stands for the spectral cell of its
//! FWHM around its centre (cut at the midpoint with a neighbour where two
//! overlap), with the radiance flat across it. A process's coefficient in
//! band e at x is `scale[e]` times its strength there (Raman 1, chlorophyll
//! a_φ(x, e), CDOM a_g(x, e); [`Process::strength`]), `scale` being b_R,
//! φ, or the band's mean CDOM quantum yield. [`Process::transfer`] gives,
//! per unit of that coefficient, the spectral radiance reaching band m
//! per unit of light the process takes from band e: (Δ_e / Δ_m) E[(λ' / λ)
//! 1(λ in m)] over λ' uniform in e's cell, divided by the nominal yield.
//! Light emitted beyond the grid's last band is lost (`lost`); light a
//! band would receive from excitation wavelengths below the grid's first
//! band is missing, and `missing` says how much of each band's source that
//! is (for a flat excitation spectrum and a flat strength).

pub mod spectra;

pub use spectra::{emission_nm, sample_shift, shift_density, Kind, WALRAFEN};

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
/// Default quantum yield of chlorophyll fluorescence (photons emitted per
/// photon phytoplankton absorb between 370 and 690 nm).
pub const CHL_QUANTUM_YIELD: f64 = 0.01;

/// Spectral points per band cell in the transfer.
const CELL_POINTS: usize = 16;

/// Excitation step (nm) of the `missing` shares.
const MISSING_STEP_NM: f64 = 1.0;

/// The Raman scattering coefficient at excitation wavelength `nm` (1/m).
pub fn raman_coefficient(nm: f64) -> f64 {
    RAMAN_B_REFERENCE * (RAMAN_REFERENCE_NM / nm).powf(RAMAN_EXPONENT)
}

/// The Raman phase function (normalised over the sphere).
pub fn raman_phase() -> PhaseFunction {
    let rho = RAMAN_DEPOLARISATION;
    PhaseFunction::rayleigh((1.0 - rho) / (1.0 + 3.0 * rho)).expect("q lies in [0, 1]")
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

/// What the water's absorption is made of at a point, in one band (1/m):
/// the strengths of the fluorescence processes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Absorbers {
    /// Absorption by phytoplankton, a_φ.
    pub a_phi: f64,
    /// Absorption by CDOM, a_g.
    pub a_g: f64,
}

/// One inelastic process on a band grid (see the module's notes).
#[derive(Clone, Debug)]
pub struct Process {
    pub kind: Kind,
    bands: usize,
    /// Per excitation band: the coefficient per unit strength (b_R in
    /// 1/m for Raman; φ times the share of the band's cell within
    /// 370-690 nm for chlorophyll; the mean quantum yield over the cell
    /// for CDOM): the base coefficient times `nominal`.
    pub scale: Vec<f64>,
    /// Per excitation band: the photons an event emits (before the cut
    /// at the excitation wavelength), averaged over the band's cell
    /// ([`Kind::photon_yield`]). An event's drawn count is divided by it.
    pub nominal: Vec<f64>,
    /// `transfer[e * bands + m]` (see [`Process::transfer`]).
    transfer: Vec<f64>,
    /// Per emission band m: (e, scale[e] transfer(e, m)) for the bands
    /// that feed it.
    pub rows: Vec<Vec<(usize, f64)>>,
    /// Per emission band: sum over e of scale[e] transfer(e, m) times the
    /// largest strength anywhere in the water (1/m; set by
    /// [`Inelastic::bound_gains`]): the coefficient that turns a flat
    /// spectral radiance into m's source, at its largest.
    pub gain_bound: Vec<f64>,
    /// Per excitation band: the share of its emitted photons that land
    /// beyond the grid's last band (or in a gap between cells).
    pub lost: Vec<f64>,
    /// Per emission band: the share of its source (for a flat excitation
    /// spectrum and strength) excited below the grid's first band.
    pub missing: Vec<f64>,
    pub phase: PhaseFunction,
}

impl Process {
    /// The process `kind` on a grid of `cells` centred at `centers` (nm),
    /// with the quantum yield `chl_yield` for chlorophyll.
    fn new(kind: Kind, cells: &[(f64, f64)], centers: &[f32], chl_yield: f64) -> Self {
        let nb = cells.len();
        let width = |i: usize| cells[i].1 - cells[i].0;
        // Excitation wavelengths are spread over the part of each cell the
        // process is excited in, weighted by that part's share of the cell.
        let (r0, r1) = kind.excitation_range();
        let part = |(lo, hi): (f64, f64)| {
            let (a, b) = (lo.max(r0), hi.min(r1));
            let share = ((b - a) / (hi - lo)).max(0.0);
            let points =
                (0..CELL_POINTS).map(move |p| a + (b - a) * (p as f64 + 0.5) / CELL_POINTS as f64);
            (share, points)
        };
        // The nominal yield per band: the event rate's scale.
        let nominal: Vec<f64> = cells
            .iter()
            .map(|&c| {
                let (share, points) = part(c);
                if share > 0.0 {
                    share * points.map(|nm| kind.photon_yield(nm)).sum::<f64>() / CELL_POINTS as f64
                } else {
                    0.0
                }
            })
            .collect();
        let scale: Vec<f64> = centers
            .iter()
            .zip(&nominal)
            .map(|(&c, &y)| match kind {
                Kind::Raman => raman_coefficient(c as f64),
                Kind::Chlorophyll => chl_yield * y,
                Kind::Cdom => y,
            })
            .collect();
        let mut transfer = vec![0.0; nb * nb];
        let mut lost = vec![0.0; nb];
        for e in 0..nb {
            if nominal[e] <= 0.0 {
                continue;
            }
            let mut landed = 0.0;
            let mut emitted = 0.0;
            let (share, points) = part(cells[e]);
            for nm in points {
                let (reach_lo, reach_hi) = kind.reach(nm);
                emitted += kind.into_interval(nm, reach_lo, reach_hi).0.max(0.0);
                for m in 0..nb {
                    let (mlo, mhi) = cells[m];
                    if mhi <= reach_lo || mlo >= reach_hi {
                        continue;
                    }
                    let (count, energy) = kind.into_interval(nm, mlo, mhi);
                    if count > 0.0 {
                        landed += count;
                        transfer[e * nb + m] += energy;
                    }
                }
            }
            for m in 0..nb {
                transfer[e * nb + m] *=
                    share * width(e) / width(m) / (CELL_POINTS as f64 * nominal[e]);
            }
            lost[e] = if emitted > 0.0 {
                ((emitted - landed) / emitted).max(0.0)
            } else {
                0.0
            };
        }
        let rows = (0..nb)
            .map(|m| {
                (0..nb)
                    .filter_map(|e| {
                        let c = scale[e] * transfer[e * nb + m];
                        (c > 0.0).then_some((e, c))
                    })
                    .collect()
            })
            .collect();
        let missing = missing_shares(kind, cells);
        Process {
            kind,
            bands: nb,
            gain_bound: vec![0.0; nb],
            scale,
            nominal,
            transfer,
            rows,
            lost,
            missing,
            phase: match kind {
                Kind::Raman => raman_phase(),
                Kind::Chlorophyll | Kind::Cdom => PhaseFunction::isotropic(),
            },
        }
    }

    /// Spectral radiance reaching band `m` per unit of light the process
    /// takes from band `e`, per unit of its nominal yield.
    #[inline]
    pub fn transfer(&self, e: usize, m: usize) -> f64 {
        self.transfer[e * self.bands + m]
    }

    /// The process's strength in a band where the water's absorbers are
    /// `parts` (its coefficient is `scale` times this).
    #[inline]
    pub fn strength(&self, parts: &Absorbers) -> f64 {
        match self.kind {
            Kind::Raman => 1.0,
            Kind::Chlorophyll => parts.a_phi,
            Kind::Cdom => parts.a_g,
        }
    }

    /// Its coefficient in band `e` where the absorbers are `parts` (1/m).
    #[inline]
    pub fn coefficient(&self, e: usize, parts: &Absorbers) -> f64 {
        self.scale[e] * self.strength(parts)
    }
}

/// For a flat excitation spectrum and strength: the share of each
/// band's source that `kind` excites below the first cell, by the
/// excitation rule of [`MISSING_STEP_NM`]; 0 for bands whose whole
/// source is below 1 % of the largest band's (the far tails of an
/// emission spectrum, where a share says nothing).
fn missing_shares(kind: Kind, cells: &[(f64, f64)]) -> Vec<f64> {
    let first = cells[0].0;
    let last = cells[cells.len() - 1].1;
    let start = kind.excitation_range().0;
    // Raman's own coefficient varies with λ'; fluorescence's strength is
    // taken flat.
    let weight = |nm: f64| match kind {
        Kind::Raman => raman_coefficient(nm),
        _ => 1.0,
    };
    let parts: Vec<(f64, f64)> = cells
        .iter()
        .map(|&(lo, hi)| {
            let (mut below, mut within) = (0.0, 0.0);
            let mut nm = start + 0.5 * MISSING_STEP_NM;
            while nm < hi.min(last) {
                let (reach_lo, reach_hi) = kind.reach(nm);
                if hi > reach_lo && lo < reach_hi {
                    // Per unit width of the band, as its radiance reads.
                    let energy = kind.into_interval(nm, lo, hi).1 * weight(nm) / (hi - lo);
                    if nm < first {
                        below += energy;
                    } else {
                        within += energy;
                    }
                }
                nm += MISSING_STEP_NM;
            }
            (below, within)
        })
        .collect();
    let largest = parts.iter().fold(0.0f64, |m, (b, w)| m.max(b + w));
    parts
        .iter()
        .map(|&(below, within)| {
            let total = below + within;
            if total > 0.01 * largest {
                below / total
            } else {
                0.0
            }
        })
        .collect()
}

/// The inelastic processes of a scene on its band grid.
#[derive(Clone, Debug)]
pub struct Inelastic {
    /// Each band's spectral cell (nm).
    pub cells: Vec<(f64, f64)>,
    pub processes: Vec<Process>,
}

impl Inelastic {
    /// The processes `kinds` on `bands`, chlorophyll's with quantum yield
    /// `chl_yield`. The fluorescence processes' gain bounds are zero until
    /// [`Self::bound_gains`].
    pub fn new(bands: &BandGrid, kinds: &[Kind], chl_yield: f64) -> Self {
        let cells = band_cells(bands);
        let processes = kinds
            .iter()
            .map(|&k| Process::new(k, &cells, bands.centers_nm(), chl_yield))
            .collect();
        let mut inelastic = Inelastic { cells, processes };
        inelastic.bound_gains(&vec![Absorbers::default(); bands.len()]);
        inelastic
    }

    /// Water Raman scattering alone.
    pub fn raman(bands: &BandGrid) -> Self {
        Self::new(bands, &[Kind::Raman], CHL_QUANTUM_YIELD)
    }

    /// Set each process's gain bound from the water's largest absorbers
    /// per band, `max_parts`.
    pub fn bound_gains(&mut self, max_parts: &[Absorbers]) {
        for p in &mut self.processes {
            let gains = p
                .rows
                .iter()
                .map(|row| {
                    row.iter()
                        .map(|&(e, c)| c * p.strength(&max_parts[e]))
                        .sum()
                })
                .collect();
            p.gain_bound = gains;
        }
    }

    /// Number of bands.
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    /// Always false: a grid holds at least one band.
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// Some process draws on the water's absorbers (fluorescence).
    pub fn fluoresces(&self) -> bool {
        self.processes.iter().any(|p| p.kind != Kind::Raman)
    }

    /// The process of `kind`, if the scene has it.
    pub fn process(&self, kind: Kind) -> Option<&Process> {
        self.processes.iter().find(|p| p.kind == kind)
    }

    /// Warnings naming, per process, the bands that lack more than 1 % of
    /// their source because it is excited below the grid's first band;
    /// `centers_nm` are the bands' centres.
    pub fn missing_warnings(&self, centers_nm: &[f32]) -> Vec<String> {
        self.processes
            .iter()
            .filter_map(|p| {
                let short: Vec<usize> = (0..self.len()).filter(|&m| p.missing[m] > 0.01).collect();
                let (&first, &last) = (short.first()?, short.last()?);
                let (lo, hi) = short.iter().fold((f64::MAX, 0.0f64), |(lo, hi), &m| {
                    (lo.min(p.missing[m]), hi.max(p.missing[m]))
                });
                Some(format!(
                    "{}: {} bands from {:.1} to {:.1} nm lack {:.0}-{:.0} % of their {} light (for a flat excitation spectrum): it is excited below the grid's first band, at {:.1} nm; start the grid lower to include it",
                    p.kind.key(),
                    short.len(),
                    centers_nm[first],
                    centers_nm[last],
                    lo * 100.0,
                    hi * 100.0,
                    p.kind.name(),
                    self.cells[0].0
                ))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests;
