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
//! cosine-weighted around the normal n, E_diffuse = pi L_in(w), where
//! L_in is the sky (unoccluded and above the horizon), the land again
//! (met along w; Russian roulette on the reflectance after two bounces),
//! or the sea (what a ray from the air meets there: `air_sea`, the water
//! below it through the integrator's own `in_water`). On a level face the
//! sky's own part is taken out as a control variate: E_diffuse = E_sky +
//! pi (L_in(w) - L_sky(w)), exact where nothing hides the sky, since the
//! cosine-weighted hemisphere around the vertical is the sky's.
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
    let level = n.z > 1.0 - 1e-6;
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
    if level && !sky_seen {
        // The control variate's difference: minus the sky hidden along w.
        let mut hidden = vec![0.0; nb];
        sky(scene, sky_l, w, &mut hidden);
        for (i, h) in incoming.iter_mut().zip(&hidden) {
            *i -= h;
        }
    }

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
            // Level: E_sky + pi (L_in - L_sky); sloping: pi L_in.
            let diffuse = if level {
                scene.sky.irradiance[b] + if sky_seen { 0.0 } else { pi * incoming[k] }
            } else {
                pi * incoming[k]
            };
            r / pi * (direct + diffuse)
        } else {
            r * incoming[k]
        };
    }
    Ok(())
}
