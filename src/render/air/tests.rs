use super::*;
use crate::optics::atmosphere::transport::band_light;
use crate::scene::Overrides;
use glam::Vec3;

/// A surface whose radiance leaving it along a camera ray, per band, is
/// `radiance(ray, band)` (field 0); field 1 is the number of bands.
struct Surface<F>(F, usize);

impl<F: Fn(&CameraRay, usize) -> f64 + Sync> Integrator for Surface<F> {
    fn bands(&self) -> usize {
        self.1
    }
    fn channels(&self) -> usize {
        1
    }
    fn camera(
        &self,
        ray: CameraRay,
        _: &mut Pcg32,
        out: &mut [f64],
        water: &mut [f64],
    ) -> Result<()> {
        assert!(ray.direction.z < 0.0 && ray.origin.z > 0.0);
        for (b, o) in out.iter_mut().enumerate() {
            *o = (self.0)(&ray, b);
        }
        water.iter_mut().for_each(|w| *w = 0.0);
        Ok(())
    }
    fn in_water(&self, _: Vec3, _: Vec3, _: &mut Pcg32, _: &mut [f64]) -> Result<()> {
        unreachable!("the air asks only for the radiance leaving the surface")
    }
    fn radiometer_samples(&self) -> u64 {
        1
    }
    fn independent_samples(&self) -> bool {
        true
    }
}

/// Over a ground that sends the same radiance L0 up everywhere, a sensor
/// above the atmosphere sees L_path + L0 (T + t), with t the diffuse
/// transmittance along its view. By reciprocity t is the sky's irradiance
/// at the ground under a sun at the view's zenith angle over mu_v times
/// the top's irradiance: the forward photons of the sky
/// (`transport::band_light`) against the adjoint air paths of
/// `AirView::adjoint`, two estimators sharing only the columns. Within 4
/// combined standard errors, per band, at 30 and 60 degrees off nadir.
#[test]
fn the_diffuse_transmittance_up_is_the_sky_s_down_by_reciprocity() {
    for view_deg in [30.0f64, 60.0] {
        let text = format!(
            "[spectral]\ncenters_nm = [412.0, 550.0, 670.0]\nfwhm_nm = [10.0, 10.0, 10.0]\n\
             [sun]\nzenith_deg = 40.0\nspectrum = \"extraterrestrial\"\n\
             [domain]\nsize_m = [10.0, 10.0]\n[water]\niop = {{ a = 0.1, b = 0.2 }}\n\
             [photons]\ncount = 1000\n\
             [sensor]\npixels = [2, 2]\ngsd_m = 1.0\naltitude_m = 800000.0\n\
             view_zenith_deg = {view_deg:?}\nview_azimuth_deg = 30.0\n\
             [atmosphere]\nsky_photons = 1000\n[atmosphere.aerosol]\nmodel = \"custom\"\n\
             tau_550 = 0.3\nssa = 0.9\nscale_height_km = 1.5\n"
        );
        let scene =
            Scene::parse(&text, std::path::Path::new("t.toml"), &Overrides::default()).unwrap();
        // The adjoint paths alone: no table, no pooled part.
        let air = AirView::air(&scene).unwrap();
        let nb = scene.bands.len();
        let l0 = 1.0;
        // A Lambertian ground lit from above: L0 in every direction.
        let flat = Surface(|_: &CameraRay, _| l0, nb);
        let n = 400_000u64;
        let mut sums = crate::render::BandSums::new(nb);
        let (mut out, mut water, mut parts) = (vec![0.0; nb], vec![0.0; nb], AirSample::new(nb));
        let ray = crate::render::camera::ray(&scene.sensor, 0, 0, 0.5, 0.5);
        for i in 0..n {
            let mut rng = Pcg32::new(5, i);
            air.camera(&flat, ray, &mut rng, &mut out, &mut water, &mut parts)
                .unwrap();
            sums.add(
                (0..nb)
                    .map(|b| out[b] - air.view.path_radiance[b] - air.view.transmittance[b] * l0),
            );
        }
        let mu_v = view_deg.to_radians().cos();
        for (b, (mean, se, _)) in sums.stats().into_iter().enumerate() {
            let sky = band_light(
                &air.columns[b],
                view_deg.to_radians(),
                400_000,
                9,
                b as u64,
                false,
            );
            let want = sky.diffuse_flux / mu_v * l0;
            let se_want = sky.diffuse_flux_se / mu_v * l0;
            let z = (mean - want) / (se * se + se_want * se_want).sqrt();
            assert!(
                z.abs() < 4.0,
                "view {view_deg}, band {b}: {mean} +- {se} against {want} +- {se_want}"
            );
            assert!(se < 0.01 * want, "{se} {want}");
        }
    }
}

/// The control variate changes the noise, not the mean: over a surface
/// whose radiance varies with place and direction, under a rough sea's
/// glint, the pixel's scattered part with the table and the pooled paths
/// agrees with the adjoint paths alone within 4 combined standard errors,
/// at a fraction of their spread.
#[test]
fn the_control_variate_keeps_the_mean() {
    let scene = rough_sea_under_air(10.0, 800000.0, 0.3, 1.0, "");
    let nb = scene.bands.len();
    // A surface whose radiance changes with place, direction and band.
    let light = Surface(
        |ray: &CameraRay, b| {
            let p = foot(ray);
            let l = 1.0
                + 0.5 * (std::f64::consts::TAU * p.x / 10.0).sin()
                + 0.8 * f64::from(-ray.direction.z);
            l * (1.0 + 0.1 * b as f64)
        },
        nb,
    );
    let plain = AirView::air(&scene).unwrap();
    let with = AirView::new(&scene, &light).unwrap().unwrap();
    let ray = crate::render::camera::ray(&scene.sensor, 1, 0, 0.3, 0.7);
    let run = |air: &AirView, seed: u64| {
        let mut sums = crate::render::BandSums::new(nb);
        let (mut out, mut water, mut parts) = (vec![0.0; nb], vec![0.0; nb], AirSample::new(nb));
        for i in 0..200_000u64 {
            let mut rng = Pcg32::new(seed, i);
            air.camera(&light, ray, &mut rng, &mut out, &mut water, &mut parts)
                .unwrap();
            sums.add((0..nb).map(|b| {
                out[b] - air.view.path_radiance[b] - air.view.transmittance[b] * parts.at_surface[b]
            }));
        }
        sums.stats()
    };
    let (a, b) = (run(&plain, 1), run(&with, 2));
    let (_, pooled_se) = with.pooled_part();
    for k in 0..nb {
        let se = (a[k].1 * a[k].1 + b[k].1 * b[k].1 + pooled_se[k] * pooled_se[k]).sqrt();
        assert!(
            (a[k].0 - b[k].0).abs() < 4.0 * se,
            "band {k}: {:?} against {:?} (pooled se {})",
            a[k],
            b[k],
            pooled_se[k]
        );
        assert!(
            b[k].2 < 0.5 * a[k].2,
            "spread {} against {}",
            b[k].2,
            a[k].2
        );
    }
}

/// With the domain in its own mean (`[surroundings] kind = "mean"`), the
/// pixel's scattered part (the pooled part plus one drawn path's
/// difference, counting for every path that lands within the domain)
/// has the mean of the plain adjoint paths that see the surface's own
/// radiance within the domain and the table plus the glint beyond it:
/// from 300 m over a 100 m domain under an aerosol 100 m high, where a
/// good share of the paths land within, over a surface bright around the
/// pixel (so the paths within see far more than the table's mean). Within 4 combined standard errors.
#[test]
fn the_mean_surroundings_keep_the_mean() {
    let scene = rough_sea_under_air(100.0, 300.0, 0.5, 0.1, "[surroundings]\nkind = \"mean\"\n");
    let nb = scene.bands.len();
    let ray = crate::render::camera::ray(&scene.sensor, 1, 0, 0.3, 0.7);
    let ground = foot(&ray);
    // Bright within 15 m of the pixel's ground point, where the paths that
    // land within the domain gather: far from the domain's mean there.
    let light = Surface(
        move |ray: &CameraRay, b| {
            let p = foot(ray);
            let near = (p - ground).truncate().length() < 15.0;
            let l = 1.0 + if near { 4.0 } else { 0.0 } + 0.8 * f64::from(-ray.direction.z);
            l * (1.0 + 0.1 * b as f64)
        },
        nb,
    );
    let air = AirView::new(&scene, &light).unwrap().unwrap();
    let n = 200_000u64;
    let mut within = 0u64;
    // The plain paths: the surface within the domain, the table beyond.
    let mut plain = crate::render::BandSums::new(nb);
    let mut glint = vec![0.0; nb];
    for i in 0..n {
        let mut rng = Pcg32::new(3, i);
        let mut one = vec![0.0; nb];
        air.adjoint(ground, &mut rng, |rng, meet, dir, w| {
            let up = -dir;
            let inside = (0.0..100.0).contains(&meet.x) && (0.0..100.0).contains(&meet.y);
            let (mut l, mut water) = (vec![0.0; nb], vec![0.0; nb]);
            if inside {
                within += 1;
                let r = CameraRay {
                    origin: (meet + up * (air.ray_height_m / up.z)).as_vec3(),
                    direction: dir.as_vec3(),
                };
                light.camera(r, rng, &mut l, &mut water)?;
            } else {
                air.glint(up, &mut glint);
                let c = air.cell(up);
                for b in 0..nb {
                    l[b] = air.env[c * nb + b] + glint[b];
                }
            }
            for b in 0..nb {
                one[b] = w[b] * l[b];
            }
            Ok(())
        })
        .unwrap();
        plain.add(one);
    }
    assert!(
        within > n / 20,
        "{within} of {n} paths land within the domain"
    );
    let (a, b) = (plain.stats(), scattered_part(&air, &light, ray, n / 4, 4));
    assert_same_mean(&air, &a, &b);
}

/// With land in a periodic domain (`[land]`), the pixel's scattered part
/// (the water's pooled part, the land's excess over the paths that meet
/// it, and one drawn path's difference from its own class's table) has
/// the mean of the plain adjoint paths that see the surface's own
/// radiance, within 4 combined standard errors, and a fraction of their
/// spread: from 300 m under an aerosol 100 m high, over a 100 m domain
/// whose beach (a sixth of it) sends ten times the water's radiance and
/// whose shallows are three times as bright as the rest of the water.
#[test]
fn land_in_the_domain_keeps_the_mean() {
    let scene = beach(false);
    let nb = scene.bands.len();
    let ray = crate::render::camera::ray(&scene.sensor, 1, 0, 0.3, 0.7);
    let ground = foot(&ray);
    let light = beach_light(&scene);
    let air = AirView::new(&scene, &light).unwrap().unwrap();
    assert!(
        (air.land_share - 1.0 / 6.0).abs() < 0.01,
        "{}",
        air.land_share
    );
    let n = 200_000u64;
    let mut water = vec![0.0; nb];
    let a = plain_paths(&air, ground, n, |rng, meet, up, l| {
        light.camera(air.ray_to(meet, up), rng, l, &mut water)
    });
    let b = scattered_part(&air, &light, ray, n / 4, 4);
    assert_same_mean(&air, &a, &b);
    for k in 0..nb {
        assert!(
            b[k].2 < 0.5 * a[k].2,
            "spread {} against {}",
            b[k].2,
            a[k].2
        );
    }
}

/// The pixel's scattered part along `ray` (L_t less L_path and the direct
/// transmittance times the radiance leaving the ground) over `n` camera
/// samples of `air` from the stream `seed`: per band mean, standard error
/// (the shared paths' error, common to the samples, included) and spread.
fn scattered_part(
    air: &AirView,
    light: &dyn Integrator,
    ray: CameraRay,
    n: u64,
    seed: u64,
) -> Vec<(f64, f64, f64)> {
    let nb = air.columns.len();
    let mut sums = crate::render::BandSums::new(nb);
    let (mut out, mut water, mut parts) = (vec![0.0; nb], vec![0.0; nb], AirSample::new(nb));
    for i in 0..n {
        let mut rng = Pcg32::new(seed, i);
        air.camera(light, ray, &mut rng, &mut out, &mut water, &mut parts)
            .unwrap();
        sums.add((0..nb).map(|b| {
            out[b] - air.view.path_radiance[b] - air.view.transmittance[b] * parts.at_surface[b]
        }));
    }
    sums.stats()
        .into_iter()
        .zip(&parts.known_var)
        .map(|((m, se, sd), v)| (m, (se * se + v).sqrt(), sd))
        .collect()
}

/// The plain adjoint paths' means `a` and the pixel's `b` agree within 4
/// combined standard errors per band, the pooled part's included.
fn assert_same_mean(air: &AirView, a: &[(f64, f64, f64)], b: &[(f64, f64, f64)]) {
    let (_, pooled_se) = air.pooled_part();
    for k in 0..a.len() {
        let se = (a[k].1 * a[k].1 + b[k].1 * b[k].1 + pooled_se[k] * pooled_se[k]).sqrt();
        assert!(
            (a[k].0 - b[k].0).abs() < 4.0 * se,
            "band {k}: plain {:?} against {:?} (pooled se {})",
            a[k],
            b[k],
            pooled_se[k]
        );
    }
}

/// Two bands under a rough sea (Cox–Munk 5 m/s, sun 30 degrees) in a
/// square domain `domain_m` across, seen from `altitude_m` 20 degrees off
/// nadir through a custom aerosol of `tau_550` and scale height
/// `height_km`, with the TOML `extra` added.
fn rough_sea_under_air(
    domain_m: f64,
    altitude_m: f64,
    tau_550: f64,
    height_km: f64,
    extra: &str,
) -> Scene {
    let text = format!(
        "[spectral]\ncenters_nm = [450.0, 650.0]\nfwhm_nm = [10.0, 10.0]\n\
         [sun]\nzenith_deg = 30.0\nspectrum = \"extraterrestrial\"\n\
         [surface]\nkind = \"cox-munk\"\nwind_speed = 5.0\n\
         [domain]\nsize_m = [{domain_m:?}, {domain_m:?}]\n[water]\niop = {{ a = 0.1, b = 0.2 }}\n\
         [photons]\ncount = 1000\n\
         [sensor]\npixels = [2, 2]\ngsd_m = 1.0\naltitude_m = {altitude_m:?}\n\
         view_zenith_deg = 20.0\nview_azimuth_deg = 200.0\n\
         [atmosphere]\nsky_photons = 1000\n[atmosphere.aerosol]\nmodel = \"custom\"\n\
         tau_550 = {tau_550:?}\nscale_height_km = {height_km:?}\n{extra}"
    );
    Scene::parse(&text, std::path::Path::new("t.toml"), &Overrides::default()).unwrap()
}

/// Where `ray` meets the mean surface, z = 0.
fn foot(ray: &CameraRay) -> DVec3 {
    let (o, d) = (ray.origin.as_dvec3(), ray.direction.as_dvec3());
    o + d * (o.z / -d.z)
}

/// A 100 m domain with a beach (a sixth of it; ten times the water's
/// radiance in [`beach_light`]) and shallows (three times as bright as the
/// rest of the water), repeating or in its own mean (`mean`): from 300 m
/// under an aerosol 100 m high.
fn beach(mean: bool) -> Scene {
    let around = if mean {
        "[surroundings]\nkind = \"mean\"\n"
    } else {
        ""
    };
    rough_sea_under_air(
        100.0,
        300.0,
        0.5,
        0.1,
        &format!(
            "[bottom]\nslope = {{ from_depth_m = -2.0, to_depth_m = 10.0, axis = \"x\" }}\n\
             reflectance = 0.2\n[land]\nreflectance = 0.3\n{around}"
        ),
    )
}

/// The radiance leaving the ground of [`beach`].
fn beach_light(scene: &Scene) -> Surface<impl Fn(&CameraRay, usize) -> f64 + Sync + '_> {
    Surface(
        |ray: &CameraRay, b| {
            let p = foot(ray);
            let l = if scene.is_land(p.x as f32, p.y as f32) {
                10.0
            } else {
                let shallows = if p.x < 40.0 { 2.0 } else { 0.0 };
                1.0 + shallows + 0.8 * f64::from(-ray.direction.z)
            };
            l * (1.0 + 0.1 * b as f64)
        },
        scene.bands.len(),
    )
}

/// With land and shallows in a domain in its own mean, the pixel's
/// scattered part (the pooled part, the shared paths' mean lookup at its
/// ground point and one drawn path's difference from its class's table)
/// has the mean of the plain adjoint paths that see the surface's own
/// radiance within the domain and the domain's mean (the water's table,
/// the glint and the land's share of its excess) beyond: within 4
/// combined standard errors, the shared paths' own included.
#[test]
fn land_and_shallows_in_their_mean_keep_the_mean() {
    let scene = beach(true);
    let nb = scene.bands.len();
    let ray = crate::render::camera::ray(&scene.sensor, 1, 0, 0.3, 0.7);
    let ground = foot(&ray);
    let light = beach_light(&scene);
    let air = AirView::new(&scene, &light).unwrap().unwrap();
    assert!(air.classes.waters() >= 3, "{}", air.classes.waters());
    let n = 200_000u64;
    let (mut glint, mut excess, mut water) = (vec![0.0; nb], vec![0.0; nb], vec![0.0; nb]);
    let a = plain_paths(&air, ground, n, |rng, meet, up, l| {
        if (0.0..100.0).contains(&meet.x) && (0.0..100.0).contains(&meet.y) {
            return light.camera(air.ray_to(meet, up), rng, l, &mut water);
        }
        air.excess(meet, up, false, &mut glint, &mut excess);
        air.glint(up, &mut glint);
        let c = air.cell(up);
        for b in 0..nb {
            l[b] = air.env[c * nb + b] + glint[b] + excess[b];
        }
        Ok(())
    });
    let b = scattered_part(&air, &light, ray, n / 4, 4);
    assert_same_mean(&air, &a, &b);
}

/// Per band mean, standard error and spread of `n` plain adjoint paths
/// from the sensor to the ground point `ground` (streams of seed 3), each
/// adding its band weights times what `seen(rng, where, up, out)` writes
/// for where it met the ground.
fn plain_paths(
    air: &AirView,
    ground: DVec3,
    n: u64,
    mut seen: impl FnMut(&mut Pcg32, DVec3, DVec3, &mut [f64]) -> Result<()>,
) -> Vec<(f64, f64, f64)> {
    let nb = air.columns.len();
    let mut plain = crate::render::BandSums::new(nb);
    let mut l = vec![0.0; nb];
    for i in 0..n {
        let mut rng = Pcg32::new(3, i);
        let mut one = vec![0.0; nb];
        air.adjoint(ground, &mut rng, |rng, meet, dir, w| {
            seen(rng, meet, -dir, &mut l)?;
            for b in 0..nb {
                one[b] = w[b] * l[b];
            }
            Ok(())
        })
        .unwrap();
        plain.add(one);
    }
    plain.stats()
}

/// The variance the shared paths give for their mean lookup is that
/// mean's spread between independent sets of them: over 48 sets, at a
/// ground point by the beach of [`beach`], per band, the
/// spread over the predicted standard error within 0.7-1.3 (about 3.4
/// standard errors of a spread from 48 draws).
#[test]
fn the_shared_paths_know_their_error() {
    let scene = beach(true);
    let nb = scene.bands.len();
    let light = beach_light(&scene);
    let air = AirView::new(&scene, &light).unwrap().unwrap();
    let surround = Surround::Mean;
    let ground = DVec3::new(30.0, 50.0, 0.0);
    let sets = 48;
    let mut means = vec![Vec::new(); nb];
    let mut var = vec![0.0; nb];
    for seed in 0..sets {
        let shared = air.shared(&surround, 1000 + seed);
        let (mut m, mut v) = (vec![0.0; nb], vec![0.0; nb]);
        air.lookup(
            &shared,
            ground,
            Lookup {
                mean: &mut m,
                var: &mut v,
            },
        );
        for b in 0..nb {
            means[b].push(m[b]);
            var[b] += v[b] / sets as f64;
        }
    }
    for b in 0..nb {
        let mean = means[b].iter().sum::<f64>() / sets as f64;
        let spread =
            (means[b].iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (sets - 1) as f64).sqrt();
        let ratio = spread / var[b].sqrt();
        assert!(
            (0.7..1.3).contains(&ratio),
            "band {b}: spread {spread} against {} (mean {mean})",
            var[b].sqrt()
        );
    }
}

/// Over water whose radiance falls with the depth of its floor, the
/// control a path's call is measured against (its class's table times its
/// depth bin's factor, plus the glint) follows the radiance: over random
/// points of the water of [`beach`] and directions, the control's RMS
/// relative error is below 5 % for a radiance (1 + 0.8 mu) exp(-0.3 depth)
/// of the floor, plus the glint.
/// Bins are eighths of a class by area; the widest spans 0.5 m of floor
/// (the class of 4–8 m), where exp(-0.3 depth) changes by 14 %, a spread of
/// ±7 % about its middle (RMS 4 %); the cells' 5-degree rows add little
/// (3.5 % measured). With one table per class (every factor 1) it is 30 %.
#[test]
fn the_control_follows_the_depth_of_the_floor() {
    // As many calls per cell as a 256 x 256 image gets.
    let mut scene = beach(true);
    scene.sensor.pixels = [256, 256];
    let nb = scene.bands.len();
    let depth = |p: DVec3| -2.0 + 0.12 * p.x;
    // With the glint, as an integrator's radiance has it.
    let light = Surface(
        |ray: &CameraRay, b| {
            let p = foot(ray);
            let mut glint = vec![0.0; nb];
            crate::render::air_sea::add_glint(&scene, -ray.direction, &mut glint);
            (1.0 + 0.8 * f64::from(-ray.direction.z)) * (-0.3 * depth(p)).exp() + glint[b]
        },
        nb,
    );
    let air = AirView::new(&scene, &light).unwrap().unwrap();
    let mut rng = Pcg32::new(11, 0);
    let (mut glint, mut control, mut l, mut water) =
        (vec![0.0; nb], vec![0.0; nb], vec![0.0; nb], vec![0.0; nb]);
    let (mut sq, mut n) = (0.0, 0);
    while n < 20_000 {
        let meet = DVec3::new(rng.uniform_f64() * 100.0, rng.uniform_f64() * 100.0, 0.0);
        if depth(meet) <= 0.05 {
            continue;
        }
        let up = crate::optics::phase::cosine_hemisphere(Vec3::Z, &mut rng).as_dvec3();
        if up.z < 0.05 {
            continue;
        }
        air.control(meet, up, &mut glint, &mut control);
        light
            .camera(air.ray_to(meet, up), &mut rng, &mut l, &mut water)
            .unwrap();
        for b in 0..nb {
            let e = control[b] / l[b] - 1.0;
            sq += e * e;
            n += 1;
        }
    }
    let rms = (sq / n as f64).sqrt();
    assert!(rms < 0.05, "RMS {rms}");
}
