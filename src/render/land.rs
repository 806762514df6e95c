//! Land in the domain: where the floor rises above the water line
//! (`[bottom]` depths below zero), a Lambertian surface of `[land]
//! reflectance` that sensor rays from the air meet before the sea.
//!
//! The radiance leaving a land point x toward the viewer, per band,
//!
//! ```text
//! L(x) = R / pi (E_sun max(0, n.s) V(x, s) + E_diffuse(x))
//! ```
//!
//! is estimated by both integrators alike: the sun's part exactly (a
//! shadow ray against the land), the diffuse part by one direction w drawn
//! cosine-weighted around the normal n, where L_in(w) is the sky
//! (unoccluded and above the horizon), the land again (met along w;
//! Russian roulette on the reflectance after two bounces), or the sea
//! (what a ray from the air meets there: `air_sea`, the water below it
//! through the integrator's own `in_water`).
//!
//! The sky's own part is taken out as a control variate, on a tilted face
//! as on a level one. With S(w) the sky's radiance above the horizon (0
//! below) and R the mirror image across the face's plane,
//!
//! ```text
//! E_diffuse = E_sky/pi (n . M) + pi (L_in(w) - S(w) + S(R w))
//! ```
//!
//! where M is the sky's first moment, the integral of g(s) s over it
//! (`SkyModel::moment`): n . M counts the sky behind the face's plane
//! negatively, and S(R w) adds it back (R maps the directions in front
//! of the plane onto those behind it and keeps n . w's size). Unbiased;
//! exact wherever w sees the sky and R w is below the horizon, which on
//! a level face is always. One direction of the sky alone (pi L_in(w))
//! was the land's noise under an atmosphere's sky: on the built-in
//! scene's beach (a slope of 1 in 12.5) its pixels spread by 9 % (1.4826
//! x median absolute deviation) with one in a thousand 200 % bright where
//! w met the aureole, and the paths from the air that land on the beach
//! carried that into deep water's pixels.
//!
//! Not in it: land casting shadows on the water or hiding the sky from
//! it, and light reflected off the land into the water (the water sees the
//! sky in every direction above the horizon: right for shores lower than
//! the sun's elevation, and the report warns of steeper land:
//! `Scene::land_warnings`). The water-leaving radiance (L_w) of a pixel
//! that meets land first is zero.

use super::air_sea::{from_air_to, set_sky as sky, InWater};
use super::camera::CameraRay;
use crate::error::Result;
use crate::geometry::Hit;
use crate::optics::phase::cosine_hemisphere;
use crate::rng::Pcg32;
use crate::scene::{Scene, FLOOR};
use glam::Vec3;

#[cfg(test)]
mod tests;

/// How far above the land's highest point (m) rays from the air start
/// looking for it.
const ABOVE_TOP_M: f32 = 1.0;

/// Bounces on land before Russian roulette on the reflectance.
const ROULETTE_AFTER: u32 = 2;

/// Where a ray from the air travelling along `d` (down) toward the point
/// `ground` on the mean surface meets the land first, if it does.
pub fn meet(scene: &Scene, ground: Vec3, d: Vec3) -> Option<Hit> {
    let land = scene.land.as_ref()?;
    if d.z >= 0.0 {
        return None;
    }
    let t = (land.top_m + ABOVE_TOP_M) / -d.z;
    scene
        .geometry
        .intersect(ground - d * t, d, t)
        .filter(|h| h.surface == FLOOR && h.position.z > 0.0)
}

/// The radiance per band leaving the land point `hit` against the
/// direction of travel `d` into `out` (the first run; runs after it, the
/// photon groups' parts of any light from the water, reflected alike);
/// `bounce` counts the land points before this one on the path.
#[allow(clippy::too_many_arguments)]
pub fn radiance(
    scene: &Scene,
    sky_l: &[f64],
    hit: &Hit,
    d: Vec3,
    bounce: u32,
    rng: &mut Pcg32,
    out: &mut [f64],
    in_water: &mut InWater,
) -> Result<()> {
    let land = scene
        .land
        .as_ref()
        .expect("a land hit comes from a scene with land");
    let nb = sky_l.len();
    let (p, n) = (hit.position, hit.normal);
    debug_assert!(n.dot(d) <= 0.0);
    let reach = |from: Vec3, w: Vec3| {
        if w.z > 0.0 {
            (land.top_m + ABOVE_TOP_M - from.z) / w.z
        } else {
            from.z / -w.z
        }
    };
    // Russian roulette after a few bounces: survive with the largest
    // band's reflectance, the weight divided by it.
    let mut weight = 1.0;
    if bounce >= ROULETTE_AFTER {
        let q = land.max_reflectance;
        if q <= 0.0 || rng.uniform_f64() >= q {
            out.iter_mut().for_each(|o| *o = 0.0);
            return Ok(());
        }
        weight = 1.0 / q;
    }

    // The diffuse light: one cosine-weighted direction around the normal.
    let w = cosine_hemisphere(n, rng);
    let from = scene.geometry.spawn_origin(p, n, w);
    let mut incoming = vec![0.0; out.len()];
    let mut sky_seen = false;
    match scene.geometry.intersect(from, w, reach(from, w)) {
        Some(h) if h.surface == FLOOR && h.position.z > 0.0 => {
            radiance(
                scene,
                sky_l,
                &h,
                w,
                bounce + 1,
                rng,
                &mut incoming,
                in_water,
            )?;
        }
        _ if w.z > 0.0 => {
            sky(scene, sky_l, w, &mut incoming);
            sky_seen = true;
        }
        _ => {
            // The sea: what a ray from the air meets there, the way to it
            // clear of land.
            let mut water = vec![0.0; nb];
            from_air_to(
                scene,
                sky_l,
                CameraRay {
                    origin: from,
                    direction: w,
                },
                false,
                rng,
                &mut incoming,
                &mut water,
                in_water,
            )?;
        }
    }
    // The control variate's difference (first run): pi (S(R w) - S(w)),
    // S(w) being what w saw when it saw the sky.
    let mut control = vec![0.0; nb];
    if !sky_seen {
        add_sky(scene, sky_l, w, -1.0, &mut control);
    }
    add_sky(scene, sky_l, w - n * (2.0 * n.dot(w)), 1.0, &mut control);

    // The sun: exact, with a shadow ray against the land.
    let s = -scene.sun.direction;
    let cos_sun = n.dot(s);
    let sunlit = cos_sun > 0.0 && s.z > 0.0 && {
        let from = scene.geometry.spawn_origin(p, n, s);
        !scene.geometry.occluded(from, s, reach(from, s))
    };
    let pi = std::f64::consts::PI;
    for (k, o) in out.iter_mut().enumerate() {
        let b = k % nb;
        let r = land.reflectance[b] * weight;
        *o = if k < nb {
            let direct = if sunlit {
                scene.sun.irradiance[b] * f64::from(cos_sun)
            } else {
                0.0
            };
            let sky_part = sky_l[b] * n.as_dvec3().dot(scene.sky.model.moment(b));
            let diffuse = if sky_seen {
                sky_part + pi * control[b]
            } else {
                sky_part + pi * (incoming[k] + control[b])
            };
            r / pi * (direct + diffuse)
        } else {
            r * incoming[k]
        };
    }
    Ok(())
}

/// Add `sign` times the sky's radiance per band toward `s` (up) to `out`,
/// none below the horizon.
fn add_sky(scene: &Scene, sky_l: &[f64], s: Vec3, sign: f64, out: &mut [f64]) {
    if s.z <= 0.0 {
        return;
    }
    let g = scene.sky.model.at(s.normalize());
    for (b, (o, l)) in out.iter_mut().zip(sky_l).enumerate() {
        *o += sign * l * g.band(b);
    }
}
