//! How the sky's radiance is spread over the hemisphere.
//!
//! The sky's spectrum fixes its horizontal irradiance E_sky per band
//! (`[sky] spectrum` or `radiance`, E = pi L); its distribution gives the
//! radiance toward each sky direction s (a unit vector pointing up to the
//! sky element) as
//!
//! ```text
//! L(s) = E_sky / pi * g(s),   integral over the hemisphere of g(s) cos(Z) = pi
//! ```
//!
//! so that any distribution keeps the horizontal irradiance. g is the same
//! in every band (a shape, not a colour), except for a sky computed
//! through an `[atmosphere]` (`table`), whose shape changes with the band.
//!
//! - `isotropic`: g = 1.
//! - `cie-clear`: the CIE standard clear sky (CIE S 011/E:2003, ISO
//!   15469:2004, sky type 12, "CIE standard clear sky, low illuminance
//!   turbidity"): relative radiance f(chi) phi(Z) with the gradation
//!   phi(Z) = 1 + a exp(b / cos Z) (phi = 1 at the horizon) and the
//!   indicatrix f(chi) = 1 + c (exp(d chi) - exp(d pi / 2)) + e cos^2 chi,
//!   a = -1, b = -0.32, c = 10, d = -3, e = 0.45, Z the element's zenith
//!   angle and chi its angle from the sun. Normalised numerically (a
//!   midpoint rule on a 180 x 720 grid in zenith and azimuth, relative
//!   error below 1e-5 against finer grids).
//!
//! Emission draws sky photons in proportion to g(s) cos Z by rejection
//! from the cosine-weighted hemisphere, against the bound f(0) phi(90°) /
//! norm, which no direction exceeds (a table: by its cells' shares).
//!
//! - `table`: the mean radiance of each cell of the atmosphere's sky grid
//!   ([`crate::optics::atmosphere::transport`]), per band.
//!
//! Not for: the sun's disc (the sun is its own source), or polarisation.

use crate::optics::atmosphere::transport::{
    cell_of, point_in_cell, projected_solid_angle, zenith_cosines, AZIMUTH_BINS, CELLS,
};
use crate::optics::phase::cosine_hemisphere;
use crate::rng::Pcg32;
use glam::{DVec3, Vec3};
use std::f64::consts::PI;
use std::sync::Arc;

/// The CIE type 12 coefficients (gradation a, b; indicatrix c, d, e).
const CIE_CLEAR: [f64; 5] = [-1.0, -0.32, 10.0, -3.0, 0.45];

/// The sky's radiance distribution.
#[derive(Clone, Debug, PartialEq)]
pub enum SkyModel {
    /// The same radiance from every direction.
    Isotropic,
    /// The CIE standard clear sky for the sun toward `sun` (unit, up).
    CieClear {
        sun: DVec3,
        /// 1 / (the hemisphere integral of f phi cos Z / pi).
        scale: f64,
        /// The hemisphere integral of g s (see [`SkyModel::moment`]).
        moment: DVec3,
    },
    /// A sky computed through an atmosphere: per band, constant over each
    /// cell of [`crate::optics::atmosphere::transport`]'s grid.
    Table(Arc<SkyTable>),
}

/// A per-band sky, constant over the cells of the atmosphere's sky grid
/// (`transport::ZENITH_BINS` x `transport::AZIMUTH_BINS`, azimuth from the
/// sun's, folded about its vertical plane).
#[derive(Clone, Debug, PartialEq)]
pub struct SkyTable {
    /// The sun's azimuth (radians, the scene's frame, toward the sun).
    sun_azimuth: f64,
    /// g per band and cell (band-major), each band's hemisphere integral of
    /// g cos Z being pi.
    g: Vec<f64>,
    /// Per band, the cumulative share of the irradiance over the cells.
    cdf: Vec<f64>,
    /// Per band, the hemisphere integral of g s ([`SkyModel::moment`]):
    /// its part along the sun's azimuth and its vertical part (pi).
    moment: Vec<[f64; 2]>,
}

impl SkyTable {
    /// The table of mean cell radiances `radiance[band][cell]` (any unit)
    /// for the sun at azimuth `sun_azimuth` (radians). A band with no sky
    /// light is isotropic (it carries no power either way).
    pub fn new(sun_azimuth: f64, radiance: &[Vec<f64>]) -> SkyTable {
        let mut g = Vec::with_capacity(radiance.len() * CELLS);
        let mut cdf = Vec::with_capacity(radiance.len() * CELLS);
        let mut moment = Vec::with_capacity(radiance.len());
        let cells = cell_moments();
        for l in radiance {
            let e: f64 = (0..CELLS)
                .map(|c| l[c].max(0.0) * projected_solid_angle(c / AZIMUTH_BINS))
                .sum();
            let mut acc = 0.0;
            for (c, &v) in l.iter().enumerate().take(CELLS) {
                let v = if e > 0.0 { v.max(0.0) * PI / e } else { 1.0 };
                g.push(v);
                acc += v * projected_solid_angle(c / AZIMUTH_BINS) / PI;
                cdf.push(acc);
            }
            let band = &g[g.len() - CELLS..];
            moment.push(
                cells
                    .iter()
                    .zip(band)
                    .fold([0.0; 2], |[h, z], (m, &v)| [h + v * m[0], z + v * m[1]]),
            );
        }
        SkyTable {
            sun_azimuth,
            g,
            cdf,
            moment,
        }
    }

    fn cell(&self, s: Vec3) -> usize {
        let phi = f64::from(s.y).atan2(f64::from(s.x)) - self.sun_azimuth;
        cell_of(f64::from(s.z), phi)
    }
}

impl SkyModel {
    /// The CIE clear sky for the sun toward `sun_toward` (unit, up: minus
    /// the direction sunlight travels).
    pub fn cie_clear(sun_toward: Vec3) -> SkyModel {
        let sun = sun_toward.as_dvec3().normalize();
        let (nz, na) = (180, 720);
        let (dz, da) = (
            std::f64::consts::FRAC_PI_2 / nz as f64,
            std::f64::consts::TAU / na as f64,
        );
        let (mut sum, mut first) = (0.0, DVec3::ZERO);
        for i in 0..nz {
            let z = (i as f64 + 0.5) * dz;
            let (sz, cz) = z.sin_cos();
            for j in 0..na {
                let a = (j as f64 + 0.5) * da;
                let s = DVec3::new(sz * a.cos(), sz * a.sin(), cz);
                let f = cie_relative(s, sun) * sz * dz * da;
                sum += f * cz;
                first += f * s;
            }
        }
        let scale = std::f64::consts::PI / sum;
        SkyModel::CieClear {
            sun,
            scale,
            moment: first * scale,
        }
    }

    /// g(s) in `band` for the sky element toward `s` (unit, pointing up; 0
    /// below the horizon).
    pub fn relative(&self, band: usize, s: Vec3) -> f64 {
        match self {
            SkyModel::Isotropic => 1.0,
            SkyModel::CieClear { sun, scale, .. } => {
                if s.z <= 0.0 {
                    return 0.0;
                }
                scale * cie_relative(s.as_dvec3().normalize(), *sun)
            }
            SkyModel::Table(t) => {
                if s.z <= 0.0 {
                    return 0.0;
                }
                t.g[band * CELLS + t.cell(s)]
            }
        }
    }

    /// g(s) for the sky element toward `s` in every band at once: one
    /// lookup, read per band.
    pub fn at(&self, s: Vec3) -> SkyAt<'_> {
        match self {
            SkyModel::Table(t) if s.z > 0.0 => SkyAt::Cell(t, t.cell(s)),
            _ => SkyAt::Same(self.relative(0, s)),
        }
    }

    /// The integral of g(s) s over the sky above the horizon in `band`
    /// (d omega; its vertical part is pi): for a face of normal n,
    /// n . moment is the signed integral of g(s) n.s over the sky, so
    /// E_sky / pi times it is the sky's irradiance on a tilted face, less
    /// what the sky behind the face's plane would take away.
    pub fn moment(&self, band: usize) -> DVec3 {
        match self {
            SkyModel::Isotropic => DVec3::new(0.0, 0.0, PI),
            SkyModel::CieClear { moment, .. } => *moment,
            SkyModel::Table(t) => {
                let [h, z] = t.moment[band];
                let (sin, cos) = t.sun_azimuth.sin_cos();
                DVec3::new(h * cos, h * sin, z)
            }
        }
    }

    /// An upper bound of g over the hemisphere (the CIE sky's and the
    /// isotropic one's; a table is sampled directly).
    pub fn max_relative(&self) -> f64 {
        match self {
            SkyModel::Isotropic => 1.0,
            SkyModel::CieClear { scale, .. } => {
                let [_, _, c, d, e] = CIE_CLEAR;
                // f is largest at chi = 0, phi at the horizon (phi = 1).
                scale * (1.0 + c * (1.0 - (d * std::f64::consts::FRAC_PI_2).exp()) + e)
            }
            SkyModel::Table(t) => t.g.iter().copied().fold(0.0, f64::max),
        }
    }

    /// The direction of travel (down) of a sky photon of `band`, drawn in
    /// proportion to g(s) cos Z: by rejection from the cosine-weighted
    /// hemisphere, or for a table a cell by its share of the irradiance,
    /// then a direction cosine-weighted within it, on either side of the
    /// sun's vertical plane.
    pub fn sample_travel(&self, band: usize, rng: &mut Pcg32) -> Vec3 {
        if let SkyModel::Table(t) = self {
            let cdf = &t.cdf[band * CELLS..(band + 1) * CELLS];
            let u = rng.uniform_f64() * cdf[CELLS - 1];
            let c = cdf.partition_point(|&v| v <= u).min(CELLS - 1);
            let (mu, phi) = point_in_cell(
                c / AZIMUTH_BINS,
                c % AZIMUTH_BINS,
                [rng.uniform_f64(), rng.uniform_f64()],
            );
            let phi = if rng.uniform_f64() < 0.5 { phi } else { -phi } + t.sun_azimuth;
            let sz = (1.0 - mu * mu).max(0.0).sqrt();
            return -Vec3::new((sz * phi.cos()) as f32, (sz * phi.sin()) as f32, mu as f32);
        }
        let max = self.max_relative();
        loop {
            let travel = cosine_hemisphere(-Vec3::Z, rng);
            if matches!(self, SkyModel::Isotropic)
                || rng.uniform_f64() * max < self.relative(0, -travel)
            {
                return travel;
            }
        }
    }
}

/// g toward one sky element, in every band ([`SkyModel::at`]).
#[derive(Clone, Copy, Debug)]
pub enum SkyAt<'a> {
    /// The same in every band.
    Same(f64),
    /// A table's cell.
    Cell(&'a SkyTable, usize),
}

impl SkyAt<'_> {
    /// g in `band`.
    pub fn band(&self, band: usize) -> f64 {
        match *self {
            SkyAt::Same(g) => g,
            SkyAt::Cell(t, c) => t.g[band * CELLS + c],
        }
    }
}

/// Each cell's integral of s d(omega) over both its mirror halves, in
/// the sun's frame: [along the sun's azimuth, vertical] (the part across
/// it cancels between the halves). Over zenith Z0-Z1 and azimuth a0-a1:
/// (integral of sin^2 Z dZ) 2 (sin a1 - sin a0) and the cell's projected
/// solid angle.
fn cell_moments() -> Vec<[f64; 2]> {
    let step = PI / AZIMUTH_BINS as f64;
    let sin_sq = |z: f64| z / 2.0 - (2.0 * z).sin() / 4.0;
    (0..CELLS)
        .map(|c| {
            let (iz, ia) = (c / AZIMUTH_BINS, c % AZIMUTH_BINS);
            let [top, bottom] = zenith_cosines(iz).map(f64::acos);
            let (a0, a1) = (ia as f64 * step, (ia + 1) as f64 * step);
            [
                (sin_sq(bottom) - sin_sq(top)) * 2.0 * (a1.sin() - a0.sin()),
                projected_solid_angle(iz),
            ]
        })
        .collect()
}

/// The CIE relative radiance f(chi) phi(Z) of the sky element toward `s`
/// (unit, z > 0) for the sun toward `sun`.
fn cie_relative(s: DVec3, sun: DVec3) -> f64 {
    let [a, b, c, d, e] = CIE_CLEAR;
    let cos_z = s.z;
    let phi = if cos_z > 1e-9 {
        1.0 + a * (b / cos_z).exp()
    } else {
        1.0
    };
    let cos_chi = s.dot(sun).clamp(-1.0, 1.0);
    let chi = cos_chi.acos();
    let f = 1.0
        + c * ((d * chi).exp() - (d * std::f64::consts::FRAC_PI_2).exp())
        + e * cos_chi * cos_chi;
    f * phi
}

#[cfg(test)]
mod tests;
