//! The CIE clear sky (`[sky] distribution = "cie-clear"`) where light
//! meets the surface: emission draws sky photons from it (the upward
//! irradiance a flat surface reflects above black water is the Fresnel
//! integral over the distribution), and the renderer sees it in the
//! surface (a nadir view reflects the zenith's radiance).

use crate::common::{f32s, render_job, tempdir};
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
    let text = format!(
        r#"
name = "sky"
[spectral]
start_nm = 500.0
end_nm = 500.0
bands = 1
[sun]
zenith_deg = {SUN_ZENITH_DEG}
azimuth_deg = 30.0
irradiance = 1.0
[sky]
radiance = {SKY}
distribution = "{distribution}"
[surface]
refractive_index = {N_WATER}
[domain]
size_m = [10.0, 10.0]
[water]
iop = {{ a = 0.5, b = 0.0 }}
[bottom]
depth_m = 5.0
reflectance = 0.0
[photons]
count = {photons}
[sensor]
pixels = [3, 3]
[tally]
depths_m = [0.0]
"#
    );
    Scene::parse(&text, Path::new("sky.toml"), &Overrides::default()).unwrap()
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
            sum += sky.relative(s) * fresnel_reflectance(mu, 1.0, N_WATER) * mu;
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
    let g = scene("cie-clear", 20_000).sky.model.relative(glam::Vec3::Z);
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
