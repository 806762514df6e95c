//! The light the sea sends up that the air returns to it: the sky over
//! the sea instead of over a black surface (`[atmosphere] sea_coupling`,
//! on by default).
//!
//! The sky at the surface is first traced over a black surface
//! (`optics::atmosphere::transport::band_light`). The sea then sends part
//! of E_d(0+) back up (its albedo A: the sun glint, the sky its surface
//! reflects and the light leaving the water, about 0.06 in the blue), and
//! the air returns a share s of that (its spherical albedo for that light,
//! about 0.2 at 412 nm), so that E_d(0+) in the blue is about 1 % higher
//! than over a black surface. The water cannot be a closed form the way a
//! Lambertian ground is (`transport::ground_response`): its light is known
//! only by transport. So when a scene is read, for each band:
//!
//! 1. **The sea's upward light.** The mean radiance leaving the surface
//!    per direction cell of the sky grid (`render::air::leaving_table`:
//!    [`COUPLING_SAMPLES`] path-integrator calls per cell at random points
//!    of the domain, under the sky over a black surface, sun glint taken
//!    out), plus the glint itself: the sun's beam reflected by the surface
//!    (`SeaSurface::interact`, so a flat sea's specular beam and a rough
//!    one's facets alike).
//! 2. **The air's answer.** `sky_photons` photons drawn from that light
//!    (a cell by its share of the upward irradiance, a direction
//!    cosine-weighted within it; or the sun's beam, kept where the
//!    surface reflects it) are traced up into the column
//!    (`transport::up_response`): the sky their collisions send back down
//!    (the same local estimates as the sky's), the share that returns, and
//!    the shares leaving the top and absorbed.
//! 3. **Every order.** Each order is taken to return in the first one's
//!    angular shape, as over a Lambertian ground: the returned light is
//!    the first order's over 1 - A s. The sky's cells, its irradiance,
//!    E_d(0+) (both estimates), the light leaving the top and the air's
//!    absorption gain it; the report gives A and s per band.
//!
//! Emission, both integrators, E_d(0+), R_rs and the air above then see
//! the same sky over the sea. Assumptions, each stated where it is used:
//! the returned light is the domain's mean, the same at every point (the
//! air spreads it over kilometres, the domain is hundreds of metres); the
//! sea's upward light is found under the sky over a black surface, and
//! later orders keep the first one's shape (both change a term of about
//! A s, itself about 1 %, by a few per cent of it).
//!
//! **Surroundings.** Land all around (`[surroundings] kind =
//! "lambertian"`) already returns its own light in the sky, as over a
//! Lambertian ground, and the air's reach is the land's: the sea of the
//! domain adds nothing. Deep water all around (`kind = "water"`) lends
//! the domain its own sky, which that sea's scene found in the same way.
//! Periodic and mean surroundings are the domain's own sea.

use super::air::{leaving_table, RAY_HEIGHT_M};
use super::path::PathTracer;
use crate::error::Result;
use crate::optics::atmosphere::transport::{
    irradiance, point_in_cell, projected_solid_angle, up_response, GroundResponse, AZIMUTH_BINS,
    CELLS,
};
use crate::optics::sky::{SkyModel, SkyTable};
use crate::scene::{Scene, Surroundings};
use glam::DVec3;
use rayon::prelude::*;
use std::sync::Arc;

/// Path-integrator calls per direction cell for the sea's mean upward
/// radiance (324 cells: 5 184 calls).
pub const COUPLING_SAMPLES: u64 = 16;

/// Streams of the table's calls and of the photons sent up.
const TABLE_KEY: u64 = 0x7365_615f_7570_7461;
const UP_KEY: u64 = 0x7365_615f_7570_6169;

/// Put the light the sea sends up and the air returns into `scene`'s sky
/// (see the module's text); nothing without an atmosphere, with
/// `sea_coupling = false`, over a Lambertian ground or with land all
/// around.
pub fn couple(scene: &mut Scene) -> Result<()> {
    let Some(air) = scene.atmosphere.as_deref() else {
        return Ok(());
    };
    if !air.sea_coupling || scene.ground.is_some() {
        return Ok(());
    }
    match &scene.surroundings {
        Some(Surroundings::Lambertian(_)) => return Ok(()),
        Some(Surroundings::Water(sea)) => {
            let sea = Arc::clone(sea);
            let theirs = sea
                .atmosphere
                .as_deref()
                .expect("the sea beyond has the air");
            let ours = Arc::make_mut(scene.atmosphere.as_mut().expect("checked above"));
            ours.bands.clone_from(&theirs.bands);
            ours.sky_radiance.clone_from(&theirs.sky_radiance);
            scene.sky = sea.sky.clone();
            return Ok(());
        }
        Some(Surroundings::Mean) | None => {}
    }
    let (table, variance) = upward_table(scene)?;
    let responses = responses(scene, &table, &variance);
    let air = Arc::make_mut(scene.atmosphere.as_mut().expect("checked above"));
    for (b, r) in responses.into_iter().enumerate() {
        let band = &mut air.bands[b];
        let black = band.direct + band.diffuse;
        if r.up <= 0.0 || black <= 0.0 {
            continue;
        }
        let a = r.up / black;
        let s = r.returned.spherical_albedo / r.up * r.source;
        // Every order, each in the first one's shape.
        let orders = r.source / (1.0 - a * s);
        band.surface_up = r.up / (1.0 - a * s);
        band.surface_up_se = r.up_se / (1.0 - a * s);
        for (v, k) in air.sky_radiance[b].iter_mut().zip(&r.returned.sky) {
            *v += orders * k;
        }
        band.diffuse += orders * r.returned.spherical_albedo;
        band.diffuse_flux += orders * r.returned.spherical_albedo_flux;
        band.diffuse_flux_se = band
            .diffuse_flux_se
            .hypot(orders * r.returned.spherical_albedo_se);
        band.up_at_top += orders * r.returned.to_top;
        band.absorbed += orders * r.returned.absorbed;
        band.spherical_albedo = r.returned.spherical_albedo_flux * r.source / r.up;
        band.spherical_albedo_se = r.returned.spherical_albedo_se * r.source / r.up;
        band.surface_albedo = a;
    }
    debug_assert!(air
        .bands
        .iter()
        .zip(&air.sky_radiance)
        .all(|(b, l)| (irradiance(l) - b.diffuse).abs() <= 1e-9 * b.diffuse.max(1e-300)));
    scene.sky.irradiance = air.bands.iter().map(|b| b.diffuse).collect();
    scene.sky.model = SkyModel::Table(Arc::new(SkyTable::new(
        scene.sun.azimuth_rad,
        &air.sky_radiance,
    )));
    Ok(())
}

/// The sea's mean radiance leaving the surface per direction cell and band
/// (cell-major), glint taken out, under the sky over a black surface: at
/// points anywhere in the domain, land included.
fn upward_table(scene: &Scene) -> Result<(Vec<f64>, Vec<f64>)> {
    let tracer = PathTracer::new(scene);
    let [sx, sy] = scene.domain.size_m;
    let height = RAY_HEIGHT_M
        + scene
            .land
            .as_ref()
            .map_or(0.0, |l| f64::from(l.top_m.max(0.0)));
    leaving_table(
        scene,
        &tracer,
        1.0,
        COUPLING_SAMPLES,
        TABLE_KEY,
        height,
        &|rng| DVec3::new(rng.uniform_f64() * sx, rng.uniform_f64() * sy, 0.0),
        &|at, up, glint| {
            glint.iter_mut().for_each(|g| *g = 0.0);
            if up.z > 0.0 && !scene.is_land(at.x as f32, at.y as f32) {
                super::air_sea::add_glint(scene, up.as_vec3(), glint);
            }
        },
        None,
    )
    .map(|l| (l.table, l.var))
}

/// One band's first order: what the air did with the light the sea sends
/// up, per unit of `source`.
struct Returned {
    /// The power the photons stood for (W m^-2 nm^-1): the table's upward
    /// irradiance plus the sun's horizontal irradiance (of which the
    /// surface reflects its share as glint).
    source: f64,
    /// The upward irradiance, glint included (W m^-2 nm^-1), and its
    /// standard error (the table's calls and the glint's draws).
    up: f64,
    up_se: f64,
    returned: GroundResponse,
}

/// Per band, the air's answer to the sea's upward light: the table's
/// cells (whose means have the variances `variance`) and the glint, drawn
/// in proportion to their power.
fn responses(scene: &Scene, table: &[f64], variance: &[f64]) -> Vec<Returned> {
    let air = scene
        .atmosphere
        .as_deref()
        .expect("only with an atmosphere");
    let nb = scene.bands.len();
    let seed = crate::rng::mix64(scene.seed ^ UP_KEY);
    (0..nb)
        .into_par_iter()
        .map(|b| {
            // The table's cells by their upward irradiance (both mirror
            // halves of a cell: its projected solid angle).
            let mut cdf = Vec::with_capacity(CELLS);
            let (mut sum, mut var) = (0.0, 0.0);
            for c in 0..CELLS {
                let omega = projected_solid_angle(c / AZIMUTH_BINS);
                sum += table[c * nb + b].max(0.0) * omega;
                var += variance[c * nb + b] * omega * omega;
                cdf.push(sum);
            }
            let sun = scene.sun.horizontal_irradiance(b);
            let source = sum + sun;
            if source <= 0.0 {
                return Returned {
                    source: 0.0,
                    up: 0.0,
                    up_se: 0.0,
                    returned: up_response(&air.columns[b], 0, seed, b as u64, |_| None),
                };
            }
            let surface = scene.surface_in(b);
            let (mut glints, mut reflected) = (0u64, 0u64);
            let returned = up_response(&air.columns[b], air.sky_photons, seed, b as u64, |rng| {
                let u = rng.uniform_f64() * source;
                if u >= sum {
                    glints += 1;
                    let ev = surface.interact(scene.sun.direction, rng);
                    if ev.transmitted || ev.direction.z <= 0.0 {
                        return None;
                    }
                    reflected += 1;
                    let d = ev.direction.as_dvec3().normalize();
                    let phi = d.y.atan2(d.x) - scene.sun.azimuth_rad;
                    let s = (1.0 - d.z * d.z).max(0.0).sqrt();
                    return Some(DVec3::new(s * phi.cos(), s * phi.sin(), d.z));
                }
                let c = cdf.partition_point(|&x| x <= u).min(CELLS - 1);
                let v = [rng.uniform_f64(), rng.uniform_f64()];
                let (mu, phi) = point_in_cell(c / AZIMUTH_BINS, c % AZIMUTH_BINS, v);
                let phi = if rng.uniform_f64() < 0.5 { phi } else { -phi };
                let s = (1.0 - mu * mu).max(0.0).sqrt();
                Some(DVec3::new(s * phi.cos(), s * phi.sin(), mu))
            });
            let (glint_share, glint_var) = if glints > 0 {
                let p = reflected as f64 / glints as f64;
                (p, p * (1.0 - p) / glints as f64)
            } else {
                (0.0, 0.0)
            };
            Returned {
                source,
                up: sum + sun * glint_share,
                up_se: (var + sun * sun * glint_var).sqrt(),
                returned,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests;
