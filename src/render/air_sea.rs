//! Sensor rays meeting the sea surface from the air: what both integrators
//! share above the water.
//!
//! A camera ray meets one facet (`SeaSurface::split_from_above`). Both
//! branches are followed, weighted by Fresnel — choosing one would make the
//! bright reflected sky speckle: the reflected ray sees the sky, the
//! refracted one the water (whose radiance drops by n^2 leaving it). A ray
//! that leaves its facet back into the surface, or is shadowed by another
//! facet (Smith), meets it again (`SeaSurface::interact_from`). Sun glint on a rough surface is added
//! analytically from the Cox–Munk slope density, since a point sun cannot
//! be found by sampling directions.
//!
//! Not for: light inside the water (each integrator's own `in_water`).

use super::camera::CameraRay;
use crate::error::Result;
use crate::optics::surface::fresnel_reflectance;
use crate::rng::Pcg32;
use crate::scene::Scene;
use glam::Vec3;

/// Water shallower than this (m) at the water line is a film a ray cannot
/// enter where it meets it: a ray entering it 0.1 mm down may start under
/// the floor, whose position the geometry resolves to its
/// self-intersection epsilon (a millimetre or two at the scale of a 200 m
/// scene). It enters instead where the film is [`FILM_ENTRY_M`] deep, a
/// centimetre or so seaward ([`film_entry`]). The shallowest flat floor
/// is as deep as this (`[bottom] depth_m`).
pub const SHORE_FILM_M: f32 = 1e-3;

/// The depth (m) at which a ray meeting the film at the water line enters
/// the water.
const FILM_ENTRY_M: f32 = 1.5e-3;

/// How far (m) a ray meeting the film may be moved seaward to enter the
/// water; farther (a floor nearly level at the water line), the film
/// sends no light up.
const FILM_SHIFT_MAX_M: f32 = 0.05;

/// Facets per ray for the mean sky a rough sea reflects along a ray other
/// than the orthographic sensor's view: the sky's aureole, which one facet
/// reflects now and then, made a mean of this many.
const RAY_SKY_FACETS: u64 = 32;

/// Radiance per band arriving at a point in the water along `-dir` (what
/// an instrument there looking along `dir` sees), written into `out`.
pub type InWater<'f> = dyn FnMut(Vec3, Vec3, &mut Pcg32, &mut [f64]) -> Result<()> + 'f;

/// The radiance per band (W m^-2 sr^-1 nm^-1) of an isotropic sky of
/// `scene`'s horizontal irradiance; a direction's is this times
/// `scene.sky.model.relative(band, s)`.
pub fn sky_radiance(scene: &Scene) -> Vec<f64> {
    scene
        .sky
        .irradiance
        .iter()
        .map(|e| e / std::f64::consts::PI)
        .collect()
}

/// Radiance per band reaching a sensor along `ray` (in air), into `out`;
/// `sky_l` is the sky radiance, `in_water` the light below the surface.
/// `out` may be longer than the bands: runs after the first carry parts of
/// the in-water radiance (the photon groups of `estimate::groups`), which
/// the surface transfers as it transfers that radiance; the sky and the
/// glint add to the first run only.
pub fn from_air(
    scene: &Scene,
    sky_l: &[f64],
    ray: CameraRay,
    rng: &mut Pcg32,
    out: &mut [f64],
    in_water: &mut InWater,
) -> Result<()> {
    let mut water = vec![0.0; sky_l.len()];
    from_air_parts(scene, sky_l, ray, rng, out, &mut water, in_water)
}

/// [`from_air`], also writing into `water` (one value per band) the part
/// of the radiance that left the water: the water-leaving radiance L_w.
/// The rest of the first run of `out` is the surface-reflected radiance
/// (the sky seen in the facets and the sun's glint), so L_t = L_w +
/// surface by construction, term by term.
pub fn from_air_parts(
    scene: &Scene,
    sky_l: &[f64],
    ray: CameraRay,
    rng: &mut Pcg32,
    out: &mut [f64],
    water: &mut [f64],
    in_water: &mut InWater,
) -> Result<()> {
    from_air_to(scene, sky_l, ray, true, rng, out, water, in_water)
}

/// [`from_air_parts`], looking for land on the way down if `look_for_land`
/// (not for a ray leaving a land point, `render::land`, whose way down to
/// the sea is known to be clear of it).
#[allow(clippy::too_many_arguments)]
pub(super) fn from_air_to(
    scene: &Scene,
    sky_l: &[f64],
    ray: CameraRay,
    look_for_land: bool,
    rng: &mut Pcg32,
    out: &mut [f64],
    water: &mut [f64],
    in_water: &mut InWater,
) -> Result<()> {
    let d = ray.direction;
    water.iter_mut().for_each(|w| *w = 0.0);
    if d.z >= 0.0 {
        set_sky(scene, sky_l, d, out);
        return Ok(());
    }
    let p = ray.origin + d * (-ray.origin.z / d.z);
    let p = Vec3::new(p.x, p.y, 0.0);
    // Land in the way: its radiance, none of it from the water's surface.
    if let Some(hit) = look_for_land
        .then(|| super::land::meet(scene, p, d))
        .flatten()
    {
        return super::land::radiance(scene, sky_l, &hit, d, 0, rng, out, in_water);
    }
    let split = scene.surface.split_from_above(d, rng);
    // Each band's facet reflectance at its own refractive index.
    let nb = sky_l.len();
    let r: Vec<f64> = if scene.dispersive() {
        (0..nb)
            .map(|b| fresnel_reflectance(split.cos_i, 1.0, scene.water_index[b]))
            .collect()
    } else {
        vec![split.reflectance; nb]
    };
    let mut part = vec![0.0; out.len()];
    let (reflected_from_water, reflected_sky) =
        leave_surface(scene, sky_l, p, split.reflected, false, rng, out, in_water)?;
    // Over a rough sea the sky this one facet reflects gives way to the
    // facets' mean (a control variate: the estimate minus the sampled sky
    // plus its expectation): along an orthographic sensor's view the
    // scene's, along any other ray the mean of `RAY_SKY_FACETS` facets of
    // its own (an adjoint path of the air landing toward the sun's
    // aureole, a pinhole's ray).
    let mean_sky = scene
        .reflected_sky()
        .filter(|m| m.direction == d)
        .map(|m| std::borrow::Cow::Borrowed(&m.mean[..]))
        .or_else(|| {
            (scene.surface.slope_variance > 0.0).then(|| {
                std::borrow::Cow::Owned(scene.facets_reflected_sky(d, sky_l, RAY_SKY_FACETS, rng))
            })
        });
    if let (Some(_), true) = (&mean_sky, reflected_sky) {
        out[..nb].iter_mut().for_each(|o| *o = 0.0);
    }
    let (refracted_from_water, _) = leave_surface(
        scene,
        sky_l,
        p,
        split.refracted,
        true,
        rng,
        &mut part,
        in_water,
    )?;
    for (b, w) in water.iter_mut().enumerate() {
        if reflected_from_water {
            *w += r[b] * out[b];
        }
        if refracted_from_water {
            *w += (1.0 - r[b]) * part[b];
        }
    }
    for (k, (o, t)) in out.iter_mut().zip(&part).enumerate() {
        let r = r[k % nb];
        *o = r * *o + (1.0 - r) * t;
    }
    if let Some(m) = mean_sky {
        for (o, s) in out.iter_mut().zip(m.iter()) {
            *o += s;
        }
    }
    add_glint(scene, -d, out);
    Ok(())
}

/// Radiance reaching the surface point `p` along `-dir`, for a ray leaving
/// it along `dir` into the water (`in_water`) or the air; a ray heading back
/// into the surface, or shadowed by another facet, meets it again (its
/// Fresnel choices reweighted to each band's index). Radiance leaving the water drops by each band's n^2.
/// Whether the ray went into the water, and whether it went straight to
/// the sky (unshadowed, into the air).
#[allow(clippy::too_many_arguments)]
fn leave_surface(
    scene: &Scene,
    sky_l: &[f64],
    p: Vec3,
    dir: Vec3,
    into_water: bool,
    rng: &mut Pcg32,
    out: &mut [f64],
    in_water: &mut InWater,
) -> Result<(bool, bool)> {
    let surface = &scene.surface;
    let away = (into_water && dir.z < 0.0) || (!into_water && dir.z > 0.0);
    let unshadowed = away
        && (surface.slope_variance <= 0.0 || rng.uniform_f64() < surface.masking(dir.as_dvec3()));
    let (dir, into_water, event) = if unshadowed {
        (dir, into_water, None)
    } else {
        let ev = surface.interact_from(dir, !into_water, rng);
        (ev.direction, into_water != ev.transmitted, Some(ev))
    };
    if into_water {
        let depth = scene
            .land
            .as_ref()
            .and_then(|_| scene.geometry.floor_depth_at(p.x, p.y));
        match depth.filter(|&d| d < SHORE_FILM_M) {
            // At the water line, water thinner than the floor's own
            // resolution: the ray enters a little seaward, or (land, or
            // a floor too level to find the film's edge) sees nothing.
            Some(d) => match film_entry(scene, p, d) {
                Some(q) => in_water(q + dir * 1e-4, dir, rng, out)?,
                None => out.iter_mut().for_each(|o| *o = 0.0),
            },
            None => in_water(p + dir * 1e-4, dir, rng, out)?,
        }
    } else {
        set_sky(scene, sky_l, dir, out);
    }
    let nb = sky_l.len();
    let n_ref = scene.surface.n_water;
    // Per band: the Fresnel reweighting of a second meeting, then n^2.
    if let Some(ev) = event.filter(|_| scene.dispersive()) {
        let w: Vec<f64> = scene.water_index[..nb]
            .iter()
            .map(|&n| ev.weight_for(n, n_ref))
            .collect();
        for (k, o) in out.iter_mut().enumerate() {
            *o *= w[k % nb];
        }
    }
    if into_water {
        for (k, o) in out.iter_mut().enumerate() {
            let n = scene.water_index[k % nb];
            *o /= n * n;
        }
    }
    Ok((into_water, unshadowed && !into_water))
}

/// The sky radiance toward `s` (unit, up) into the first run of `out`,
/// zero in the others; `sky_l` is the isotropic sky's radiance.
pub(super) fn set_sky(scene: &Scene, sky_l: &[f64], s: Vec3, out: &mut [f64]) {
    let (l, rest) = out.split_at_mut(sky_l.len());
    let g = scene.sky.model.at(s);
    for (b, (o, v)) in l.iter_mut().zip(sky_l).enumerate() {
        *o = v * g.band(b);
    }
    rest.iter_mut().for_each(|o| *o = 0.0);
}

/// Where a ray meeting the water's surface at `p`, over a film of water
/// `depth` deep at the water line, enters the water: moved seaward (down
/// the floor's slope, from central differences 1 cm apart) to where the
/// film is [`FILM_ENTRY_M`] deep, at most [`FILM_SHIFT_MAX_M`]; none on
/// land or where the floor is too level. Moving the entry by a centimetre
/// keeps the film's light continuous with the water beside it: a film
/// that sent nothing up read 0 at floors 0.4-0.8 mm deep against 0.071 at
/// 1.6 mm (the built-in scene at 750 nm), which a path from the air
/// landing there carried into its pixel as a difference of -100 % from the
/// water's table (one pixel in 65 536 negative at 709 nm).
fn film_entry(scene: &Scene, p: Vec3, depth: f32) -> Option<Vec3> {
    if depth < 0.0 {
        return None;
    }
    let h = 0.01f32;
    let at = |x: f32, y: f32| scene.geometry.floor_depth_at(x, y);
    let gx = (at(p.x + h, p.y)? - at(p.x - h, p.y)?) / (2.0 * h);
    let gy = (at(p.x, p.y + h)? - at(p.x, p.y - h)?) / (2.0 * h);
    let slope = gx.hypot(gy);
    let shift = (FILM_ENTRY_M - depth) / slope;
    if !shift.is_finite() || shift > FILM_SHIFT_MAX_M {
        return None;
    }
    let q = Vec3::new(p.x + gx / slope * shift, p.y + gy / slope * shift, p.z);
    at(q.x, q.y).filter(|&d| d >= SHORE_FILM_M).map(|_| q)
}

/// Sun glint on a Cox–Munk surface seen from direction `v` (up), added to
/// `out`: L = E_sun rho p(zx, zy) G1(sun) G1(v) / (4 cos(theta_v)
/// cos^4(beta)), with Smith's unshadowed fractions G1 of both directions
/// (`optics::surface`).
pub fn add_glint(scene: &Scene, v: Vec3, out: &mut [f64]) {
    let s2 = scene.surface.slope_variance;
    if s2 <= 0.0 {
        return;
    }
    let v = v.as_dvec3();
    let s = -scene.sun.direction.as_dvec3();
    let h = (v + s).normalize();
    if h.z <= 0.0 || v.z <= 0.0 {
        return;
    }
    let (zx, zy) = (-h.x / h.z, -h.y / h.z);
    let p = (-(zx * zx + zy * zy) / s2).exp() / (std::f64::consts::PI * s2);
    let shadowing = scene.surface.masking(v) * scene.surface.masking(s);
    let g = p * shadowing / (4.0 * v.z * h.z.powi(4));
    let n_ref = scene.surface.n_water;
    let rho_ref = fresnel_reflectance(h.dot(v), 1.0, n_ref);
    for ((o, e), &n) in out
        .iter_mut()
        .zip(&scene.sun.irradiance)
        .zip(&scene.water_index)
    {
        let rho = if n == n_ref {
            rho_ref
        } else {
            fresnel_reflectance(h.dot(v), 1.0, n)
        };
        *o += e * rho * g;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Overrides;

    /// The facets' mean reflected sky replaces each sample's one facet
    /// without moving the mean: over black water under a rough sea and a
    /// CIE clear sky, camera rays along the sensor's view (with the
    /// scene's mean), along a view 1e-6 rad away (with a mean of its own
    /// `RAY_SKY_FACETS` facets) and the plain estimate of one facet (the
    /// reflected and refracted rays as `from_air_to` traces them, no
    /// mean) agree within 4 combined standard errors, the first two with
    /// a fraction of the plain one's spread.
    #[test]
    fn the_mean_reflected_sky_keeps_the_mean() {
        let text = "[spectral]\ncenters_nm = [450.0, 650.0]\nfwhm_nm = [10.0, 10.0]\n\
                    [sun]\nzenith_deg = 30.0\nirradiance = 1.0\n\
                    [sky]\nradiance = 0.1\ndistribution = \"cie-clear\"\n\
                    [surface]\nkind = \"cox-munk\"\nwind_speed = 6.0\n\
                    [domain]\nsize_m = [10.0, 10.0]\n[water]\niop = { a = 0.1, b = 0.2 }\n\
                    [photons]\ncount = 1000\n\
                    [sensor]\npixels = [2, 2]\ngsd_m = 1.0\nview_zenith_deg = 20.0\n";
        let scene =
            Scene::parse(text, std::path::Path::new("t.toml"), &Overrides::default()).unwrap();
        let view = scene.reflected_sky().unwrap().direction;
        let nb = scene.bands.len();
        let sky_l = sky_radiance(&scene);
        let run = |d: Vec3, seed: u64| {
            let mut sums = crate::render::BandSums::new(nb);
            let (mut out, mut water) = (vec![0.0; nb], vec![0.0; nb]);
            let ray = CameraRay {
                origin: Vec3::new(5.0, 5.0, 0.0) - d * (10.0 / d.z),
                direction: d,
            };
            for i in 0..200_000u64 {
                let mut rng = Pcg32::new(seed, i);
                from_air_parts(
                    &scene,
                    &sky_l,
                    ray,
                    &mut rng,
                    &mut out,
                    &mut water,
                    &mut |_, _, _, o| {
                        o.iter_mut().for_each(|v| *v = 0.0);
                        Ok(())
                    },
                )
                .unwrap();
                sums.add(out.iter().copied());
            }
            sums.stats()
        };
        // One facet, as `from_air_to` traces it, with no mean.
        let plain = |d: Vec3, seed: u64| {
            let mut sums = crate::render::BandSums::new(nb);
            let (mut out, mut part) = (vec![0.0; nb], vec![0.0; nb]);
            let p = Vec3::new(5.0, 5.0, 0.0);
            let black = &mut |_: Vec3, _: Vec3, _: &mut Pcg32, o: &mut [f64]| {
                o.iter_mut().for_each(|v| *v = 0.0);
                Ok(())
            };
            for i in 0..200_000u64 {
                let mut rng = Pcg32::new(seed, i);
                let split = scene.surface.split_from_above(d, &mut rng);
                leave_surface(
                    &scene,
                    &sky_l,
                    p,
                    split.reflected,
                    false,
                    &mut rng,
                    &mut out,
                    black,
                )
                .unwrap();
                leave_surface(
                    &scene,
                    &sky_l,
                    p,
                    split.refracted,
                    true,
                    &mut rng,
                    &mut part,
                    black,
                )
                .unwrap();
                for (o, t) in out.iter_mut().zip(&part) {
                    *o = split.reflectance * *o + (1.0 - split.reflectance) * t;
                }
                add_glint(&scene, -d, &mut out);
                sums.add(out.iter().copied());
            }
            sums.stats()
        };
        let nearby = (view + Vec3::new(1e-6, 0.0, 0.0)).normalize();
        assert_ne!(nearby, view);
        let without = plain(view, 3);
        for with in [run(view, 1), run(nearby, 2)] {
            for b in 0..nb {
                let se = (with[b].1.powi(2) + without[b].1.powi(2)).sqrt();
                assert!(
                    (with[b].0 - without[b].0).abs() < 4.0 * se,
                    "band {b}: {:?} against {:?}",
                    with[b],
                    without[b]
                );
                assert!(
                    with[b].2 < 0.5 * without[b].2,
                    "{:?} {:?}",
                    with[b],
                    without[b]
                );
            }
        }
    }

    /// A ray meeting the film of water at the water line enters where it
    /// is 1.5 mm deep, seaward and within 2 cm on a slope of 0.08 (the
    /// built-in scene's): from the air it sees the water there, not
    /// nothing. On land, and on water deeper than the film, nothing moves.
    #[test]
    fn the_film_at_the_water_line_sends_its_light_up() {
        let text = crate::testing::minimal_with(
            "[domain]\nsize_m = [100.0, 100.0]\n\
             [bottom]\nslope = { from_depth_m = -1.0, to_depth_m = 7.0, axis = \"x\" }\n\
             reflectance = 0.3\n[land]\nreflectance = 0.3\n",
        );
        let scene =
            Scene::parse(&text, std::path::Path::new("t.toml"), &Overrides::default()).unwrap();
        // The water line is at x = 12.5 m.
        for x in [12.5001f32, 12.505, 12.51] {
            let p = Vec3::new(x, 40.0, 0.0);
            let d = scene.geometry.floor_depth_at(p.x, p.y).unwrap();
            assert!((0.0..SHORE_FILM_M).contains(&d), "{x}: {d}");
            let q = film_entry(&scene, p, d).expect("a film on a slope has an edge");
            let dq = scene.geometry.floor_depth_at(q.x, q.y).unwrap();
            assert!(q.x > p.x && (q - p).length() < 0.02, "{p} -> {q}");
            assert!((dq - FILM_ENTRY_M).abs() < 1e-4, "{dq}");
            // From the air: the water below is asked for its light.
            let sky_l = vec![0.1; scene.bands.len()];
            let mut asked = 0;
            let mut in_water = |_: Vec3, _: Vec3, _: &mut Pcg32, out: &mut [f64]| -> Result<()> {
                asked += 1;
                out.iter_mut().for_each(|o| *o = 1.0);
                Ok(())
            };
            let (mut out, mut water) = (vec![0.0; scene.bands.len()], vec![0.0; scene.bands.len()]);
            let ray = CameraRay {
                origin: p + Vec3::Z * 10.0,
                direction: Vec3::NEG_Z,
            };
            let mut rng = Pcg32::new(1, 0);
            from_air_parts(
                &scene,
                &sky_l,
                ray,
                &mut rng,
                &mut out,
                &mut water,
                &mut in_water,
            )
            .unwrap();
            assert_eq!(asked, 1);
            assert!(water.iter().all(|&w| w > 0.5), "{water:?}");
        }
        assert!(film_entry(&scene, Vec3::new(12.4, 40.0, 0.0), -0.008).is_none());
    }
}
