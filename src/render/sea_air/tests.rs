use super::*;
use crate::optics::atmosphere::Column;
use crate::optics::phase::scatter;
use crate::optics::surface::SeaSurface;
use crate::rng::Pcg32;
use crate::scene::Overrides;
use std::f64::consts::PI;
use std::path::Path;

/// Black water under a sun at 60 degrees, a Rayleigh atmosphere and a
/// thick aerosol that does not absorb (so the air returns much of what the
/// sea's surface reflects), four bands; `surface` is the `[surface]`
/// table's body, `extra` more TOML.
fn scene(surface: &str, seed: u64, extra: &str) -> Scene {
    let text = format!(
        "seed = {seed}\n\
         [spectral]\nstart_nm = 400.0\nend_nm = 700.0\nbands = 4\n\
         [sun]\nzenith_deg = 60.0\nspectrum = \"extraterrestrial\"\n\
         [domain]\nsize_m = [10.0, 10.0]\n\
         [water]\niop = {{ a = 100.0, b = 0.0 }}\n\
         [surface]\n{surface}\n\
         [photons]\ncount = 1000\n\
         [atmosphere]\nsky_photons = 50000\n{extra}\n\
         [atmosphere.aerosol]\nmodel = \"custom\"\ntau_550 = 0.8\nangstrom = 0.0\nssa = 1.0\n\
         phase = {{ kind = \"henyey-greenstein\", g = 0.7 }}\nscale_height_km = 1.0\n"
    );
    Scene::parse(&text, Path::new("coupled.toml"), &Overrides::default()).unwrap()
}

/// An independent oracle of the coupled system in one dimension: photons
/// of the sun's beam traced analog from the top of `column` (absorbed with
/// the layer's co-albedo), the sea a surface `surface` over black water
/// (a photon it reflects goes up again, one it transmits ends). Returns
/// the diffuse irradiance at the surface per unit beam-normal irradiance
/// at the top (everything arriving but the unscattered beam; reflected
/// light returned by the air included) and its standard error.
fn oracle(column: &Column, surface: &SeaSurface, sun_zenith: f64, photons: u64) -> (f64, f64) {
    let total = column.total();
    let mu0 = sun_zenith.cos();
    let mut rng = Pcg32::new(0x6f72_6163_6c65, 7);
    let mut arrivals = 0u64;
    let mut squares = 0u64;
    for _ in 0..photons {
        let mut dir = DVec3::new(-sun_zenith.sin(), 0.0, -mu0);
        let mut tau = 0.0;
        let mut diffuse = false;
        let mut count = 0u64;
        loop {
            let step = rng.exponential(1.0) * dir.z.abs();
            let next = if dir.z < 0.0 { tau + step } else { tau - step };
            if next <= 0.0 {
                break;
            }
            if next >= total {
                if diffuse {
                    count += 1;
                }
                let ev = surface.interact(dir.as_vec3(), &mut rng);
                if ev.transmitted || ev.direction.z <= 0.0 {
                    break;
                }
                dir = ev.direction.as_dvec3().normalize();
                tau = total;
                diffuse = true;
                continue;
            }
            tau = next;
            let layer = column.layer_at(tau);
            if rng.uniform_f64() >= layer.ssa() {
                break;
            }
            let phase = if rng.uniform_f64() < layer.rayleigh_share() {
                &column.rayleigh_phase
            } else {
                &column.aerosol_phase
            };
            let mu = phase.sample_cos(rng.uniform_f64());
            let phi = 2.0 * PI * rng.uniform_f64();
            dir = scatter(dir.as_vec3(), mu as f32, phi as f32)
                .as_dvec3()
                .normalize();
            diffuse = true;
        }
        arrivals += count;
        squares += count * count;
    }
    let n = photons as f64;
    let mean = arrivals as f64 / n;
    let var = (squares as f64 / n - mean * mean).max(0.0) / n;
    (mu0 * mean, mu0 * var.sqrt())
}

/// Over black water the sea sends up only what its surface reflects, and
/// the sky over it must hold what the air returns of that, to every
/// order: the diffuse irradiance at the surface (from the sky's cells and
/// from the photons' flux), mean of four seeds, against the oracle's
/// within 4 combined standard errors, for a flat sea and a rough one.
/// Without the coupling (`sea_coupling = false`) the sky is 2-3 % short
/// in the blue, many standard errors.
#[test]
fn the_sky_over_a_reflecting_sea_holds_what_the_air_returns() {
    let mut failures = Vec::new();
    for surface in ["kind = \"flat\"", "kind = \"cox-munk\"\nwind_speed = 7.0"] {
        let runs: Vec<Scene> = (1..=4).map(|seed| scene(surface, seed, "")).collect();
        let s0 = &runs[0];
        let air = s0.atmosphere.as_deref().unwrap();
        for b in 0..s0.bands.len() {
            let f0 = air.bands[b].toa_irradiance;
            let (want, want_se) = oracle(
                &air.columns[b],
                &s0.surface_in(b),
                s0.sun.zenith_rad,
                1_000_000,
            );
            let (want, want_se) = (want * f0, want_se * f0);
            for field in ["cells", "flux"] {
                let got: Vec<f64> = runs
                    .iter()
                    .map(|s| {
                        let band = &s.atmosphere.as_deref().unwrap().bands[b];
                        if field == "cells" {
                            band.diffuse
                        } else {
                            band.diffuse_flux
                        }
                    })
                    .collect();
                let n = got.len() as f64;
                let m = got.iter().sum::<f64>() / n;
                let var = got.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
                let se = (var / n).sqrt().hypot(want_se);
                let band = &air.bands[b];
                eprintln!(
                    "{surface:?} band {b} {field}: {m:.5} against {want:.5} +- {se:.5} ({:+.3} %), A {:.4} s {:.4}",
                    100.0 * (m / want - 1.0),
                    band.surface_albedo,
                    band.spherical_albedo
                );
                if (m - want).abs() > 4.0 * se {
                    failures.push(format!(
                        "{surface:?} band {b} {field}: {m} against {want} +- {se}"
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
