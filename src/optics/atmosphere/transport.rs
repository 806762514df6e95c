//! Light through the atmosphere to the surface: the direct beam exactly,
//! the sky by Monte Carlo with local estimates.
//!
//! For each band, photons of the sun's beam at the top of the atmosphere
//! are traced through the column ([`super::Column`]) over a black surface.
//! Free paths are drawn in optical depth and cross the homogeneous layers
//! exactly; absorption is carried by weight (the weight times the layer's
//! single-scattering albedo at each collision), with Russian roulette
//! below a weight of [`ROULETTE_WEIGHT`]; the scattering is Rayleigh's or
//! the aerosol's in proportion to their shares in the layer.
//!
//! **The sky at the surface** is the radiance arriving from each sky
//! element, averaged over a grid of [`ZENITH_BINS`] x [`AZIMUTH_BINS`]
//! cells (5° of zenith by 10° of azimuth from the sun's, folded about the
//! sun's vertical plane, where the sky is symmetric). Each collision adds
//! its local estimate to every cell: for light scattered into the
//! direction -s toward the surface, with weight w after the collision,
//!
//! ```text
//! L(s) += mu0 / N  w  p(cos Theta) exp(-tau' / mu_s) / mu_s
//! ```
//!
//! per unit beam-normal irradiance at the top, where p is the layer's
//! phase mixture, tau' the optical depth below the collision and mu_s the
//! cosine of the element's zenith angle: the collision density's
//! contribution to the horizontally averaged radiance. The direction in
//! each cell is drawn once per collision (the same offset in every cell),
//! cosine-weighted within it, so that each cell's estimate is unbiased for
//! its cosine-weighted mean radiance and the cells' sum is the diffuse
//! irradiance exactly in expectation. The photons that reach the surface
//! after scattering give an independent estimate of that irradiance
//! (`diffuse_flux`), and those that leave at the top the reflectance of
//! the atmosphere over a black surface. The same local estimate toward the
//! top of the atmosphere gives the path radiance a sensor above it sees
//! over a black surface (`toa`, on request).
//!
//! Deterministic: each band's photons draw from their own stream of a
//! fixed seed, whatever the number of threads.

use super::Column;
use crate::optics::phase::{rayleigh_density, scatter, PhaseFunction};
use crate::rng::Pcg32;
use glam::DVec3;
use std::f64::consts::PI;

/// Sky cells in zenith (5° each).
pub const ZENITH_BINS: usize = 18;
/// Sky cells in azimuth from the sun's (10° each, 0–180°).
pub const AZIMUTH_BINS: usize = 18;
/// Cells of the sky grid.
pub const CELLS: usize = ZENITH_BINS * AZIMUTH_BINS;
/// Weight below which a photon plays Russian roulette (survives with
/// probability weight / this, at this weight).
pub const ROULETTE_WEIGHT: f64 = 0.05;

const ZENITH_STEP: f64 = PI / 2.0 / ZENITH_BINS as f64;
const AZIMUTH_STEP: f64 = PI / AZIMUTH_BINS as f64;

/// The light one band's column brings to a black surface, per unit
/// beam-normal irradiance at the top of the atmosphere.
#[derive(Clone, Debug, PartialEq)]
pub struct BandLight {
    /// Direct transmittance along the sun's path, exp(-tau / mu0).
    pub direct_transmittance: f64,
    /// Mean radiance of each sky cell at the surface (sr^-1), zenith-major.
    pub sky: Vec<f64>,
    /// The diffuse irradiance at the surface from the cells: sum of L
    /// times each cell's projected solid angle.
    pub diffuse: f64,
    /// The diffuse irradiance from the photons reaching the surface, and
    /// its standard error.
    pub diffuse_flux: f64,
    pub diffuse_flux_se: f64,
    /// Irradiance leaving the top of the atmosphere (over a black surface).
    pub up_at_top: f64,
    /// Irradiance absorbed in the air.
    pub absorbed: f64,
    /// Mean radiance of each cell leaving the top, zenith-major (cells of
    /// the travel direction's zenith and azimuth from the sun's), if asked.
    pub toa: Option<Vec<f64>>,
}

/// The cell of a direction `s` (unit, up) with azimuth `phi` measured from
/// the sun's.
pub fn cell_of(cos_zenith: f64, phi: f64) -> usize {
    let z = cos_zenith.clamp(0.0, 1.0).acos();
    let iz = ((z / ZENITH_STEP) as usize).min(ZENITH_BINS - 1);
    let a = phi.rem_euclid(2.0 * PI);
    let a = if a > PI { 2.0 * PI - a } else { a };
    let ia = ((a / AZIMUTH_STEP) as usize).min(AZIMUTH_BINS - 1);
    iz * AZIMUTH_BINS + ia
}

/// The cosines of zenith bounding zenith row `iz` ([upper edge's, lower
/// edge's]: the first is the larger).
pub fn zenith_cosines(iz: usize) -> [f64; 2] {
    [
        (iz as f64 * ZENITH_STEP).cos(),
        ((iz + 1) as f64 * ZENITH_STEP).cos(),
    ]
}

/// The projected solid angle of a cell (both mirror halves): the integral
/// of cos Z over it.
pub fn projected_solid_angle(iz: usize) -> f64 {
    let [a, b] = zenith_cosines(iz);
    // Integral of mu dmu over the row, times 2 x the azimuth step.
    0.5 * (a * a - b * b) * 2.0 * AZIMUTH_STEP
}

/// A direction in cell (`iz`, `ia`), cosine-weighted within it, from `u`
/// in [0, 1)^2: (cos Z, azimuth from the sun's).
pub fn point_in_cell(iz: usize, ia: usize, u: [f64; 2]) -> (f64, f64) {
    let [a, b] = zenith_cosines(iz);
    let mu = (b * b + u[0] * (a * a - b * b)).sqrt();
    (mu, (ia as f64 + u[1]) * AZIMUTH_STEP)
}

/// What became of the photons traced by [`trace`], per unit beam-normal
/// irradiance at the top: sums over the photons.
#[derive(Clone, Copy, Debug, Default)]
struct Fates {
    /// Weight reaching the surface after scattering, and its square.
    arrived: f64,
    arrived_sq: f64,
    /// Weight leaving the top, and absorbed.
    up: f64,
    absorbed: f64,
}

/// The direction of travel of the sun's beam at zenith `sun_zenith`
/// (radians): the sun's azimuth is 0, so sunlight travels toward azimuth
/// pi.
fn beam(sun_zenith: f64) -> DVec3 {
    DVec3::new(-sun_zenith.sin(), 0.0, -sun_zenith.cos())
}

/// Trace `photons` photons entering `column` at optical depth `tau0` from
/// the top, travelling along `start` (unit, down), over a black surface,
/// drawing from `rng`; at each collision `collide(tau, dir, w, share)`
/// sees the optical depth from the top, the direction of travel before
/// it, the weight after it and the layer's Rayleigh share of scattering.
fn trace(
    column: &Column,
    start: DVec3,
    tau0: f64,
    photons: u64,
    rng: &mut Pcg32,
    collide: impl FnMut(&mut Pcg32, f64, DVec3, f64, f64),
) -> Fates {
    trace_from(column, |_| Some(start), tau0, photons, rng, collide)
}

/// [`trace`] with each photon's direction of travel drawn by `start`
/// (none: the photon carries no light, and counts only in the number).
fn trace_from(
    column: &Column,
    mut start: impl FnMut(&mut Pcg32) -> Option<DVec3>,
    tau0: f64,
    photons: u64,
    rng: &mut Pcg32,
    mut collide: impl FnMut(&mut Pcg32, f64, DVec3, f64, f64),
) -> Fates {
    let total = column.total();
    let mut f = Fates::default();
    for _ in 0..photons {
        let Some(mut dir) = start(rng) else {
            continue;
        };
        let mut tau = tau0;
        let mut w = 1.0f64;
        let mut scattered = false;
        let mut arrived = 0.0;
        loop {
            let step = rng.exponential(1.0) * dir.z.abs();
            let next = if dir.z < 0.0 { tau + step } else { tau - step };
            if next >= total {
                if scattered {
                    arrived = w;
                }
                break;
            }
            if next <= 0.0 {
                f.up += w;
                break;
            }
            tau = next;
            let layer = column.layer_at(tau);
            let kept = w * layer.ssa();
            f.absorbed += w - kept;
            w = kept;
            let share = layer.rayleigh_share();
            collide(rng, tau, dir, w, share);
            let phase = if rng.uniform_f64() < share {
                &column.rayleigh_phase
            } else {
                &column.aerosol_phase
            };
            let mu = phase.sample_cos(rng.uniform_f64());
            let phi = 2.0 * PI * rng.uniform_f64();
            dir = scatter(dir.as_vec3(), mu as f32, phi as f32)
                .as_dvec3()
                .normalize();
            scattered = true;
            if w < ROULETTE_WEIGHT {
                if rng.uniform_f64() * ROULETTE_WEIGHT >= w {
                    f.absorbed += w;
                    break;
                }
                f.absorbed -= ROULETTE_WEIGHT - w;
                w = ROULETTE_WEIGHT;
            }
        }
        f.arrived += arrived;
        f.arrived_sq += arrived * arrived;
    }
    f
}

/// Trace `photons` photons of the sun at zenith `sun_zenith` (radians)
/// through `column` over a black surface, from stream `stream` of `seed`;
/// with `toa`, also the radiance leaving the top.
pub fn band_light(
    column: &Column,
    sun_zenith: f64,
    photons: u64,
    seed: u64,
    stream: u64,
    toa: bool,
) -> BandLight {
    let mu0 = sun_zenith.cos();
    let total = column.total();
    let mut rng = Pcg32::new(seed, stream);
    let mut sky = vec![0.0; CELLS];
    let mut top = toa.then(|| vec![0.0; CELLS]);
    let mut cells = Cells::default();
    let f = trace(
        column,
        beam(sun_zenith),
        0.0,
        photons,
        &mut rng,
        |rng, tau, dir, w, share| {
            cells.draw(rng);
            cells.add_down(&mut sky, column, share, dir, w, total - tau);
            if let Some(t) = top.as_mut() {
                cells.add(t, column, share, dir, w, |mu| (-tau / mu).exp() / mu, false);
            }
        },
    );
    let n = photons.max(1) as f64;
    let scale = mu0 / n;
    sky.iter_mut().for_each(|v| *v *= scale);
    if let Some(t) = top.as_mut() {
        t.iter_mut().for_each(|v| *v *= scale);
    }
    let diffuse = irradiance(&sky);
    let mean = f.arrived / n;
    let var = (f.arrived_sq / n - mean * mean).max(0.0) / n;
    BandLight {
        direct_transmittance: (-total / mu0).exp(),
        sky,
        diffuse,
        diffuse_flux: mu0 * mean,
        diffuse_flux_se: mu0 * var.sqrt(),
        up_at_top: mu0 * f.up / n,
        absorbed: mu0 * f.absorbed / n,
        toa: top,
    }
}

/// The path radiance a sensor at `depth` (optical depth from the top; 0
/// above the atmosphere) sees looking down along the travel direction
/// `view` (unit, up, azimuth from the sun's): the light scattered below it
/// that never reached the (black) surface, per unit beam-normal irradiance
/// at the top, by the local estimate at every collision below the sensor,
/// with its standard error (from the photons' spread).
pub fn path_radiance(
    column: &Column,
    sun_zenith: f64,
    view: DVec3,
    depth: f64,
    photons: u64,
    seed: u64,
    stream: u64,
) -> (f64, f64) {
    let mu0 = sun_zenith.cos();
    let mut rng = Pcg32::new(seed, stream);
    let (mut sum, mut sum_sq) = (0.0, 0.0);
    for _ in 0..photons {
        let mut one = 0.0;
        trace(
            column,
            beam(sun_zenith),
            0.0,
            1,
            &mut rng,
            |_, tau, dir, w, share| {
                if tau > depth {
                    let p = mixture(column, share, dir.dot(view));
                    one += w * p * (-(tau - depth) / view.z).exp() / view.z;
                }
            },
        );
        sum += one;
        sum_sq += one * one;
    }
    let n = photons.max(1) as f64;
    let mean = sum / n;
    let var = (sum_sq / n - mean * mean).max(0.0) / n;
    (mu0 * mean, mu0 * var.sqrt())
}

/// The total transmittance from a Lambertian ground to a sensor at
/// `depth` (optical depth from the top) looking down at zenith angle
/// `view_zenith` (radians): the radiance it sees from a ground of unit
/// radiance that nothing lights back, direct and scattered, with the
/// scattered part's standard error.
///
/// By reciprocity this is the share of a beam entering at the sensor's
/// level and travelling down along the view that reaches the ground
/// (per unit of its horizontal irradiance): exp(-tau_below / mu_v)
/// exactly, plus the photons that arrive after scattering, which may
/// wander above the sensor's level on their way.
pub fn transmittance_up(
    column: &Column,
    view_zenith: f64,
    depth: f64,
    photons: u64,
    seed: u64,
    stream: u64,
) -> (f64, f64) {
    let mut rng = Pcg32::new(seed, stream);
    let f = trace(
        column,
        beam(view_zenith),
        depth,
        photons,
        &mut rng,
        |_, _, _, _, _| {},
    );
    let n = photons.max(1) as f64;
    let mean = f.arrived / n;
    let var = (f.arrived_sq / n - mean * mean).max(0.0) / n;
    let direct = (-(column.total() - depth) / view_zenith.cos()).exp();
    (direct + mean, var.sqrt())
}

/// What the air does with light the surface sends up: per unit of a
/// Lambertian ground's radiance (an upward irradiance of pi;
/// [`ground_response`]) or per unit upward irradiance ([`up_response`]).
#[derive(Clone, Debug, PartialEq)]
pub struct GroundResponse {
    /// The mean radiance of each sky cell at the surface that this light
    /// comes back as (sr^-1 per unit ground radiance, so the sky's
    /// radiance per W m^-2 sr^-1 nm^-1 leaving the ground; or per W m^-2
    /// nm^-1 of upward irradiance), zenith-major.
    pub sky: Vec<f64>,
    /// The share of the upward irradiance the air sends back down: the
    /// spherical albedo s, from the cells (sum of `sky` times each cell's
    /// projected solid angle, over pi) and from the photons that return,
    /// with that estimate's standard error.
    pub spherical_albedo: f64,
    pub spherical_albedo_flux: f64,
    pub spherical_albedo_se: f64,
    /// The shares leaving the top and absorbed in the air (with the
    /// returned share, 1 in expectation).
    pub to_top: f64,
    pub absorbed: f64,
}

/// Trace `photons` photons leaving a Lambertian ground up into `column`
/// (cosine-weighted directions), from stream `stream` of `seed`: the sky
/// their collisions send back to the ground, by the same local estimates
/// as [`band_light`]'s, and their fates. A ground of reflectance R lit by
/// E over a black surface then receives E / (1 - R s) in all (every order
/// of reflection between the ground and the air, each returned in the
/// same angular shape), and its sky gains R E / (1 - R s) / pi times
/// `sky`.
pub fn ground_response(column: &Column, photons: u64, seed: u64, stream: u64) -> GroundResponse {
    let mut r = up_response(column, photons, seed, stream, |rng| {
        let mu = rng.uniform_f64().sqrt();
        let phi = 2.0 * PI * rng.uniform_f64();
        let s = (1.0 - mu * mu).max(0.0).sqrt();
        Some(DVec3::new(s * phi.cos(), s * phi.sin(), mu))
    });
    // Per unit radiance of the ground: an upward irradiance of pi.
    r.sky.iter_mut().for_each(|v| *v *= PI);
    r
}

/// What the air does with light leaving the surface whose directions
/// `draw` gives (unit, up, azimuth from the sun's; none: a photon that
/// carries no light), per unit of that light's upward irradiance: the sky
/// it returns as (mean radiance per cell, sr^-1), the share it sends back
/// down (from the cells and from the photons that return, with that
/// estimate's standard error) and the shares leaving the top and absorbed.
/// `photons` photons from stream `stream` of `seed`, each carrying 1 /
/// `photons` of the irradiance.
pub fn up_response(
    column: &Column,
    photons: u64,
    seed: u64,
    stream: u64,
    draw: impl FnMut(&mut Pcg32) -> Option<DVec3>,
) -> GroundResponse {
    let total = column.total();
    let mut rng = Pcg32::new(seed, stream);
    let mut sky = vec![0.0; CELLS];
    let mut cells = Cells::default();
    let f = trace_from(
        column,
        draw,
        total,
        photons,
        &mut rng,
        |rng, tau, dir, w, share| {
            cells.draw(rng);
            cells.add_down(&mut sky, column, share, dir, w, total - tau);
        },
    );
    let n = photons.max(1) as f64;
    sky.iter_mut().for_each(|v| *v /= n);
    let returned = irradiance(&sky);
    let mean = f.arrived / n;
    let var = (f.arrived_sq / n - mean * mean).max(0.0) / n;
    GroundResponse {
        sky,
        spherical_albedo: returned,
        spherical_albedo_flux: mean,
        spherical_albedo_se: var.sqrt(),
        to_top: f.up / n,
        absorbed: f.absorbed / n,
    }
}

/// The irradiance on a horizontal plane of the cells' mean radiances
/// `cells` (zenith-major): each times its projected solid angle.
pub fn irradiance(cells: &[f64]) -> f64 {
    (0..CELLS)
        .map(|c| cells[c] * projected_solid_angle(c / AZIMUTH_BINS))
        .sum()
}

/// The cells' directions for one collision: the same offset in every cell.
#[derive(Default)]
struct Cells {
    /// Per zenith row: cos Z and sin Z.
    rows: [(f64, f64); ZENITH_BINS],
    /// Per azimuth column: cos and sin of the azimuth.
    cols: [(f64, f64); AZIMUTH_BINS],
}

impl Cells {
    fn draw(&mut self, rng: &mut Pcg32) {
        let u = [rng.uniform_f64(), rng.uniform_f64()];
        for iz in 0..ZENITH_BINS {
            let (mu, _) = point_in_cell(iz, 0, u);
            self.rows[iz] = (mu, (1.0 - mu * mu).max(0.0).sqrt());
        }
        for ia in 0..AZIMUTH_BINS {
            let (_, phi) = point_in_cell(0, ia, u);
            self.cols[ia] = (phi.cos(), phi.sin());
        }
    }

    /// [`Cells::add`] toward the surface from a collision at optical depth
    /// `below` above it.
    fn add_down(
        &self,
        out: &mut [f64],
        column: &Column,
        share: f64,
        dir: DVec3,
        w: f64,
        below: f64,
    ) {
        self.add(
            out,
            column,
            share,
            dir,
            w,
            |mu| (-below / mu).exp() / mu,
            true,
        );
    }

    /// Add to `out` the local estimate of weight `w` for a photon travelling
    /// along `dir` toward each cell: light going down to the surface
    /// (`down`: travel -s for the sky element s) or up to the top (travel
    /// s), attenuated by `atten(mu)`.
    #[allow(clippy::too_many_arguments)]
    fn add(
        &self,
        out: &mut [f64],
        column: &Column,
        share: f64,
        dir: DVec3,
        w: f64,
        atten: impl Fn(f64) -> f64,
        down: bool,
    ) {
        let sign = if down { -1.0 } else { 1.0 };
        let (mut cos, mut aerosol) = ([0.0; AZIMUTH_BINS], [0.0; AZIMUTH_BINS]);
        for (iz, &(mu, sz)) in self.rows.iter().enumerate() {
            let a = w * atten(mu);
            if a == 0.0 {
                continue;
            }
            let row = &mut out[iz * AZIMUTH_BINS..(iz + 1) * AZIMUTH_BINS];
            for (cos, &(c, s)) in cos.iter_mut().zip(&self.cols) {
                // The travel direction: sign * (sz cos, sz sin, mu).
                *cos = sign * (dir.x * sz * c + dir.y * sz * s + dir.z * mu);
            }
            // Rayleigh and the aerosol's lookup, a row at a time: the
            // values of `mixture`.
            if let (PhaseFunction::Rayleigh { q }, Some(lookup)) =
                (&column.rayleigh_phase, &column.aerosol_lookup)
            {
                lookup.eval_each(&cos, &mut aerosol);
                for ((o, &c), &p) in row.iter_mut().zip(&cos).zip(&aerosol) {
                    let rayleigh = rayleigh_density(*q, c.clamp(-1.0, 1.0));
                    *o += a * (share * rayleigh + (1.0 - share) * p);
                }
            } else {
                for (o, &c) in row.iter_mut().zip(&cos) {
                    *o += a * mixture(column, share, c);
                }
            }
        }
    }
}

/// The layer's phase mixture at `cos`: called toward every sky cell at
/// every collision, so Rayleigh's closed form is written out here for the
/// loop to inline.
#[inline]
fn mixture(column: &Column, share: f64, cos: f64) -> f64 {
    let rayleigh = match column.rayleigh_phase {
        PhaseFunction::Rayleigh { q } => rayleigh_density(q, cos.clamp(-1.0, 1.0)),
        ref p => p.eval(cos),
    };
    share * rayleigh + (1.0 - share) * column.aerosol_density(cos)
}
