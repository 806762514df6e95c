//! Water Raman scattering in the path integrator against closed forms.

use crate::common::minimal_with;
use littoral::optics::inelastic::{RamanBands, RAMAN_DEPOLARISATION};
use littoral::optics::surface::fresnel_reflectance;
use littoral::scene::{IntegratorMode, Overrides, Scene};
use std::f64::consts::PI;
use std::path::Path;

const N_WATER: f64 = 1.34;
const SUN_ZENITH_DEG: f64 = 30.0;

fn path_scene(text: &str, spp: u32) -> Scene {
    let o = Overrides {
        samples_per_pixel: Some(spp),
        integrator: Some(IntegratorMode::Path),
        ..Overrides::default()
    };
    Scene::parse(text, Path::new("raman.toml"), &o).unwrap()
}

/// The Raman phase function as published: (3 / 16 pi) (1 + 3 rho) / (1 +
/// 2 rho) [1 + (1 - rho) / (1 + 3 rho) cos^2].
fn raman_phase(cos: f64) -> f64 {
    let rho = RAMAN_DEPOLARISATION;
    3.0 / (16.0 * PI) * (1.0 + 3.0 * rho) / (1.0 + 2.0 * rho)
        * (1.0 + (1.0 - rho) / (1.0 + 3.0 * rho) * cos * cos)
}

/// Water that absorbs (a = 0.1 m^-1 in every band) and does not scatter
/// elastically, over a black floor at 20 m, flat surface (n = 1.34), sun
/// at 30 degrees with unit normal irradiance in each of 31 bands from 400
/// to 700 nm, no sky. All the light a radiometer 1 mm deep looking
/// straight down sees is the sun's beam Raman-scattered once toward it:
/// L_m = sum_e b_R(e) T(e, m) p_R(-mu_w) F_w e^(a z_r) (e^(-k z_r) -
/// e^(-k H)) / k, with k = a (1 + 1 / mu_w) and F_w = mu0 t / mu_w the
/// refracted beam's normal irradiance. Light Raman-scattered twice adds a
/// share of order b_R H, 2e-3 at 400 nm. The bands below 465 nm, fed
/// from below the grid, read 0.
#[test]
fn single_raman_scattering_matches_the_closed_form() {
    let (a, depth, z_r) = (0.1, 20.0, 1e-3);
    let text = minimal_with(&format!(
        r#"
spectral = {{ start_nm = 400.0, end_nm = 700.0, bands = 31 }}
domain = {{ size_m = [40.0, 40.0] }}
sensor = {{ pixels = [1, 1] }}
sun = {{ zenith_deg = {SUN_ZENITH_DEG} }}
surface = {{ refractive_index = {N_WATER} }}
water = {{ iop = {{ a = {a}, b = 0.0 }}, raman = true }}
bottom = {{ depth_m = {depth}, reflectance = 0.0 }}
radiometer = [{{ depth_m = {z_r}, view = "nadir", position_m = [20.0, 20.0] }}]
"#
    ));
    let scene = path_scene(&text, 1024);
    let r = &littoral::render::radiometers_path(&scene, 0).unwrap()[0];
    let raman = RamanBands::new(&scene.bands);
    let mu0 = SUN_ZENITH_DEG.to_radians().cos();
    let sin_w = (1.0 - mu0 * mu0).sqrt() / N_WATER;
    let mu_w = (1.0 - sin_w * sin_w).sqrt();
    let f_w = mu0 * (1.0 - fresnel_reflectance(mu0, 1.0, N_WATER)) / mu_w;
    let k = a * (1.0 + 1.0 / mu_w);
    let column = (a * z_r).exp() * ((-k * z_r).exp() - (-k * depth).exp()) / k;
    let p = raman_phase(-mu_w);
    let nb = scene.bands.len();
    let expected: Vec<f64> = (0..nb)
        .map(|m| {
            let fed: f64 = (0..nb)
                .map(|e| raman.coefficient[e] * raman.transfer(e, m))
                .sum();
            fed * p * f_w * column
        })
        .collect();
    // Bands next to those fed only from below the grid receive 1e-7 of
    // the largest: nothing a run of this size sees.
    let floor = 1e-6 * expected.iter().copied().fold(0.0, f64::max);
    let mut failures = Vec::new();
    let (mut sum, mut sum_expected, mut var) = (0.0, 0.0, 0.0);
    for (m, &expected) in expected.iter().enumerate() {
        let (l, se) = (r.L[m], r.stderr[m]);
        eprintln!(
            "{:.0} nm: {l:.4e} +- {se:.2e} against {expected:.4e}",
            scene.bands.centers_nm()[m]
        );
        if (l - expected).abs() > 3.0 * se + 5e-3 * expected + floor {
            failures.push(format!(
                "band {m}: {l:.4e} +- {se:.2e} against {expected:.4e}"
            ));
        }
        sum += l;
        sum_expected += expected;
        var += se * se;
    }
    // Bands fed only from below the grid read nothing at all.
    assert!(r.L[..5].iter().all(|&l| l < 1e-12), "{:?}", &r.L[..5]);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // The band sum, whose error is smaller than any band's.
    let se = var.sqrt();
    assert!(
        (sum - sum_expected).abs() <= 3.0 * se + 2e-3 * sum_expected,
        "band sum {sum:.5e} +- {se:.2e} against {sum_expected:.5e}"
    );
}

/// Raman scattering is part of the water's absorption: water absorbing
/// less than b_R in some band is refused, naming the key and the band.
/// Photon emission does not move light between bands yet, so a Raman
/// scene refuses to emit photons, naming the key, and says what renders it.
#[test]
fn raman_scenes_are_checked_and_the_photon_map_says_what_it_lacks() {
    let text = |a: f64| {
        minimal_with(&format!(
            "water = {{ iop = {{ a = {a}, b = 0.1 }}, raman = true }}"
        ))
    };
    let e = Scene::parse(&text(1e-4), Path::new("raman.toml"), &Overrides::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("raman.toml:") && e.contains("water.raman") && e.contains("at 400 nm"),
        "{e}"
    );
    let scene = Scene::parse(&text(0.1), Path::new("raman.toml"), &Overrides::default()).unwrap();
    let e = littoral::emit::Emitter::new(&scene)
        .err()
        .expect("photon emission refuses Raman scattering")
        .to_string();
    assert!(
        e.contains("water.raman") && e.contains("--integrator path"),
        "{e}"
    );
}
