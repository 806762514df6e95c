//! The CIE clear sky (`[sky] distribution = "cie-clear"`) where light
//! meets the surface: emission draws sky photons from it (the upward
//! irradiance a flat surface reflects above black water is the Fresnel
//! integral over the distribution), and the renderer sees it in the
//! surface (a nadir view reflects the zenith's radiance), through a rough
//! one both ways as a quadrature over the facets says.

use crate::common::{f32s, minimal_with, render_job, tempdir};
use littoral::emit::Emitter;
use littoral::optics::sky::SkyModel;
use littoral::optics::surface::fresnel_reflectance;
use littoral::scene::{IntegratorMode, Overrides, Scene};
use std::f64::consts::PI;
use std::path::Path;

const N_WATER: f64 = 1.34;
const SKY: f64 = 0.05;
const SUN_ZENITH_DEG: f64 = 50.0;

/// Clear water (no scattering) over a black floor, flat surface, a sun
/// at 50 degrees and a CIE clear sky.
fn scene(distribution: &str, photons: u64) -> Scene {
    let text = scene_text(distribution, photons);
    Scene::parse(&text, Path::new("sky.toml"), &Overrides::default()).unwrap()
}

/// The TOML of [`scene`].
fn scene_text(distribution: &str, photons: u64) -> String {
    minimal_with(&format!(
        r#"
name = "sky"
spectral = {{ start_nm = 500.0, end_nm = 500.0, bands = 1 }}
sun = {{ zenith_deg = {SUN_ZENITH_DEG}, azimuth_deg = 30.0 }}
sky = {{ radiance = {SKY}, distribution = "{distribution}" }}
surface = {{ refractive_index = {N_WATER} }}
water = {{ iop = {{ a = 0.5, b = 0.0 }} }}
bottom = {{ depth_m = 5.0, reflectance = 0.0 }}
photons = {{ count = {photons} }}
sensor = {{ pixels = [3, 3] }}
tally = {{ depths_m = [0.0] }}
"#
    ))
}

/// The Fresnel reflectance integrated over a sky model: (1/pi) integral of
/// g(s) rho(theta) cos(theta) over the hemisphere (midpoint rule).
fn reflected_share(sky: &SkyModel) -> f64 {
    let (nm, na) = (400, 720);
    let mut sum = 0.0;
    for i in 0..nm {
        let mu = (i as f64 + 0.5) / nm as f64;
        let sz = (1.0 - mu * mu).sqrt();
        for j in 0..na {
            let a = (j as f64 + 0.5) * std::f64::consts::TAU / na as f64;
            let s = glam::Vec3::new((sz * a.cos()) as f32, (sz * a.sin()) as f32, mu as f32);
            sum += sky.relative(0, s) * fresnel_reflectance(mu, 1.0, N_WATER) * mu;
        }
    }
    sum / PI / nm as f64 * std::f64::consts::TAU / na as f64
}

/// Above black, non-scattering water only the surface sends light up: the
/// emission's upward irradiance above the surface is E_sun cos(theta_s)
/// rho(theta_s) plus the sky's irradiance times its Fresnel share, within
/// four standard errors of the tally, and the CIE sky's share differs from
/// the isotropic sky's by more than that (the test can tell them apart).
#[test]
fn emission_draws_sky_photons_from_the_distribution() {
    let mut shares = Vec::new();
    for distribution in ["cie-clear", "isotropic"] {
        let s = scene(distribution, 400_000);
        let e = Emitter::new(&s).unwrap();
        let t = e.trace_all(0).unwrap();
        let (_, eu_slot) = t.above_slots();
        let (mean, se) = t.mean_and_stderr(eu_slot, 0);
        let area = 100.0;
        let power = e.photon_power(0) * s.photons as f64 / area;
        let sun = SUN_ZENITH_DEG.to_radians().cos();
        let share = reflected_share(&s.sky.model);
        let want = sun * fresnel_reflectance(sun, 1.0, N_WATER) + PI * SKY * share;
        let (got, se) = (mean * power, se * power);
        assert!(
            (got - want).abs() < 4.0 * se,
            "{distribution}: Eu(0+) {got} against {want} +- {se}"
        );
        shares.push((share, se / (PI * SKY)));
    }
    let (cie, iso) = (shares[0], shares[1]);
    assert!((cie.0 - iso.0).abs() > 8.0 * cie.1.max(iso.1), "{shares:?}");
}

/// A nadir view of a flat surface over black water sees the zenith sky
/// reflected: rho(0) L_sky g(zenith), in both integrators.
#[test]
fn the_surface_reflects_the_zenith_sky() {
    let dir = tempdir();
    let g = scene("cie-clear", 20_000)
        .sky
        .model
        .relative(0, glam::Vec3::Z);
    assert!(
        (g - 1.0).abs() > 0.1,
        "the zenith differs from the mean: {g}"
    );
    let want = fresnel_reflectance(1.0, 1.0, N_WATER) * SKY * g;
    for integrator in [IntegratorMode::PhotonMap, IntegratorMode::Path] {
        let mut scene = scene("cie-clear", 20_000);
        scene.render.integrator = integrator;
        let r = render_job(&scene, &dir.path().join(format!("{integrator:?}")), 0);
        for v in f32s(&r.outputs.products[1].bsq) {
            let v = v as f64;
            assert!(
                (v - want).abs() <= 1e-4 * want,
                "{integrator:?}: {v} against {want}"
            );
        }
    }
}

/// Sky light through a Cox–Munk surface, by quadrature over the slopes:
/// for a ray along `d` meeting the surface (from the air when `d.z < 0`),
/// the first facet drawn by projected area along the ray, split by
/// Fresnel, and the branch that reaches the sky (reflected from the air,
/// refracted from the water) leaving unshadowed (Smith's G1) with the sky's
/// relative radiance `g` there. Returns that single-facet part and the
/// probability that the ray goes on to meet another facet (a branch
/// heading back into the surface, or shadowed), whose sky light lies
/// between 0 and that probability times the sky's brightest `g`.
fn sky_through_facets(
    slope_variance: f64,
    d: glam::DVec3,
    g: &dyn Fn(glam::DVec3) -> f64,
) -> (f64, f64) {
    use glam::DVec3;
    use littoral::optics::surface::{facet_quadrature, reflect, refract, smith_lambda};
    let from_above = d.z < 0.0;
    let (n1, n2) = if from_above {
        (1.0, N_WATER)
    } else {
        (N_WATER, 1.0)
    };
    let g1 = |v: DVec3| 1.0 / (1.0 + smith_lambda(v.z.abs(), slope_variance));
    let (mut single, mut more) = (0.0, 0.0);
    let norm = facet_quadrature(slope_variance, d, 500, |m, w| {
        let f = fresnel_reflectance(-d.dot(m), n1, n2);
        let branches = [(Some(reflect(d, m)), f), (refract(d, m, n1, n2), 1.0 - f)];
        for (k, (out, p)) in branches.into_iter().enumerate() {
            let Some(out) = out else { continue };
            let to_sky = (k == 0) == from_above;
            let away = if (k == 0) == from_above {
                out.z > 0.0
            } else {
                out.z < 0.0
            };
            let leave = if away { g1(out) } else { 0.0 };
            if to_sky {
                single += w * p * leave * g(out);
            }
            more += w * p * (1.0 - leave);
        }
    });
    (single / norm, more / norm)
}

/// Sky light through a rough surface, as both integrators see it: over
/// black, non-scattering water under a CIE clear sky (no sun), Cox–Munk
/// at 8 m/s, a sensor in the air looking down 30 and 50 degrees off nadir
/// sees the sky reflected in the facets (`Integrator::camera`), and an
/// instrument 1 mm under the surface looking up (the zenith and 40
/// degrees off it, where steep facets reflect totally) sees it refracted,
/// n^2 times brighter (`Integrator::in_water`). Over 100 000 samples each
/// the mean lies within four standard errors of the quadrature
/// (`sky_through_facets`), widened by the bound on the light of rays that
/// meet a second facet (0.2 % of it at 30 degrees, 9 % at 50). The same
/// quadrature with an isotropic sky's radiance in place of the CIE sky's
/// misses every case by more than that: the test sees the sky's shape
/// through the facets.
#[test]
fn sky_through_a_rough_surface_matches_a_quadrature() {
    use glam::{DVec3, Vec3};
    use littoral::render::camera::CameraRay;
    use littoral::render::march::RayMarcher;
    use littoral::render::path::PathTracer;
    use littoral::render::Integrator;
    let u = 8.0;
    // The scene above without the sun, under a Cox–Munk surface, in
    // almost clear water.
    let text = scene_text("cie-clear", 20_000)
        .replace("irradiance = 1.0", "irradiance = 0.0")
        .replace(
            "[surface]\n",
            &format!("[surface]\nkind = \"cox-munk\"\nwind_speed = {u}\n"),
        )
        .replace("a = 0.5, b = 0.0", "a = 0.01, b = 0.0");
    let scene = Scene::parse(&text, Path::new("rough-sky.toml"), &Overrides::default()).unwrap();
    let emitter = littoral::emit::Emitter::new(&scene).unwrap();
    let map = littoral::store::InMemoryMap::from_source(&emitter).unwrap();
    let marcher = RayMarcher::new(
        &scene,
        littoral::estimate::Estimator::new(&scene, &map).unwrap(),
    );
    let tracer = PathTracer::new(&scene);
    let integrators: [(&str, &dyn Integrator); 2] = [("photon map", &marcher), ("path", &tracer)];
    let sky = &scene.sky.model;
    let g = |v: DVec3| sky.relative(0, v.as_vec3());
    let g_max = (0..=90)
        .flat_map(|i| (0..360).map(move |j| (i, j)))
        .map(|(i, j): (i32, i32)| {
            let (t, a) = ((i as f64).to_radians(), (j as f64).to_radians());
            g(DVec3::new(t.sin() * a.cos(), t.sin() * a.sin(), t.cos()))
        })
        .fold(0.0f64, f64::max);
    let depth = 0.001;
    for (k, theta) in [150.0f64, 130.0, 0.0, 40.0].into_iter().enumerate() {
        // Traced backwards, the ray meets the surface along the view.
        let t = theta.to_radians();
        let d = DVec3::new(t.sin(), 0.0, t.cos());
        let below = d.z > 0.0;
        // Light from under the surface travels 1 mm through a = 0.01 /m.
        let scale = if below {
            N_WATER * N_WATER * (-0.01 * depth / d.z).exp()
        } else {
            1.0
        } * SKY;
        let (single, more) = sky_through_facets(scene.surface.slope_variance, d, &g);
        let (lo, hi) = (scale * single, scale * (single + more * g_max));
        let (iso, _) = sky_through_facets(scene.surface.slope_variance, d, &|_| 1.0);
        let iso = scale * iso;
        for (name, light) in integrators {
            let mut rng = littoral::rng::Pcg32::new(41, k as u64);
            let n = 100_000;
            let (mut sum, mut sum_sq) = (0.0, 0.0);
            let mut out = vec![0.0; light.bands() * light.channels()];
            let mut water = vec![0.0; light.bands()];
            for _ in 0..n {
                if below {
                    let p = Vec3::new(5.0, 5.0, -depth as f32);
                    light.in_water(p, d.as_vec3(), &mut rng, &mut out).unwrap();
                } else {
                    let ray = CameraRay {
                        origin: Vec3::new(5.0, 5.0, 1.0),
                        direction: d.as_vec3(),
                    };
                    light.camera(ray, &mut rng, &mut out, &mut water).unwrap();
                }
                sum += out[0];
                sum_sq += out[0] * out[0];
            }
            let mean = sum / n as f64;
            let se = ((sum_sq / n as f64 - mean * mean) / n as f64).sqrt();
            assert!(
                mean > lo - 4.0 * se && mean < hi + 4.0 * se,
                "{name}, {theta} degrees: {mean} +- {se} against [{lo}, {hi}]"
            );
            assert!(
                (mean - iso).abs() > 4.0 * se + (hi - lo),
                "{name}, {theta} degrees: the isotropic sky's {iso} is not told apart from {mean}"
            );
        }
    }
}
