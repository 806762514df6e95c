//! The photon map against the path integrator, the unbiased reference, in
//! six small scenes: deep water, a floor, layered water, a submerged
//! target, a rough surface (with the water's index per band after Quan &
//! Fry, so the photons' per-band refraction meets the integrators'
//! reweighted Fresnel choices), and radiometers at and near a floor.
//!
//! Every radiometer band is held to 3 sigma plus 2 %, sigma combining the
//! photon map's standard error (photon groups and jittered samples) and
//! the path integrator's (independent paths). The same scenes at 4 M
//! photons and 262 k paths are `benches/scripts/against_path.sh`, with
//! their figures in benches/README.md.

use crate::common::{render_job, tempdir};
use littoral::scene::{IntegratorMode, Overrides, Scene};
use std::path::Path;

const PHOTONS: u64 = 4_000_000;
/// Paths per radiometer: 1024 per sample per pixel.
const SPP: u32 = 64;

fn base(name: &str, extra: &str, depths: &[f64]) -> String {
    let mut s = format!(
        r#"
name = "{name}"
[spectral]
start_nm = 450.0
end_nm = 650.0
bands = 8
[sun]
zenith_deg = 30.0
irradiance = 1.0
[sky]
radiance = 0.02
[domain]
size_m = [40.0, 40.0]
[photons]
count = 1000
[sensor]
pixels = [1, 1]
[estimate]
max_radius_m = 2.0
step_m = 0.25
{extra}
"#
    );
    for d in depths {
        s += &format!(
            "[[radiometer]]\ndepth_m = {d}\nview = \"nadir\"\nposition_m = [20.0, 20.0]\n"
        );
    }
    s
}

fn scenes() -> Vec<(&'static str, String)> {
    let water = "[water]\nchl = 1.0\ncdom_440 = 0.05\n";
    vec![
        ("deep", base("deep", water, &[1.0, 3.0, -1.0])),
        (
            "shallow",
            base(
                "shallow",
                &format!("{water}[bottom]\ndepth_m = 4.0\nreflectance = \"sand\"\n"),
                &[1.0, 3.9, -1.0],
            ),
        ),
        (
            "layered",
            base(
                "layered",
                "[water]\nchl = 0.5\ncdom_440 = 0.05\n[[water.layer]]\ntop_m = 2.0\nbottom_m = 4.0\n\
                 chl = 8.0\ncdom_440 = 0.2\nnap_440 = 0.1\n[bottom]\ndepth_m = 8.0\nreflectance = 0.2\n",
                &[1.0, 3.0, -1.0],
            ),
        ),
        (
            "target",
            base(
                "target",
                &format!(
                    "{water}[bottom]\ndepth_m = 6.0\nreflectance = 0.1\n[[target]]\nkind = \"panel\"\n\
                     center_m = [20.0, 20.0, -3.0]\nsize_m = [4.0, 4.0]\nreflectance = 0.5\n"
                ),
                &[1.0, 2.5, -1.0],
            ),
        ),
        (
            "rough",
            base(
                "rough",
                &format!(
                    "[surface]\nkind = \"cox-munk\"\nwind_speed = 8.0\nrefractive_index = \"quan-fry\"\n\
                     {water}[bottom]\ndepth_m = 5.0\nreflectance = \"sand\"\n"
                ),
                &[1.0, 4.0, -1.0],
            ),
        ),
        (
            "near_floor",
            base(
                "near_floor",
                &format!("{water}[bottom]\ndepth_m = 3.0\nreflectance = 0.3\n"),
                &[2.9999, 2.99, 1.5],
            ),
        ),
    ]
}

#[test]
fn photon_map_radiometers_match_the_path_integrator_in_six_scenes() {
    let dir = tempdir();
    let mut failures = Vec::new();
    for (name, text) in scenes() {
        let photon_map = Overrides {
            photons: Some(PHOTONS),
            ..Overrides::default()
        };
        let s = Scene::parse(&text, Path::new("scene.toml"), &photon_map).unwrap();
        let pm = render_job(&s, &dir.path().join(name), 0).radiometers;
        let path = Overrides {
            integrator: Some(IntegratorMode::Path),
            samples_per_pixel: Some(SPP),
            ..Overrides::default()
        };
        let s = Scene::parse(&text, Path::new("scene.toml"), &path).unwrap();
        let reference = littoral::render::radiometers_path(&s, 0).unwrap();
        for (a, b) in pm.iter().zip(&reference) {
            let mut worst = 0.0f64;
            for i in 0..a.L.len() {
                let sigma = a.stderr[i].hypot(b.stderr[i]);
                let allowed = 3.0 * sigma + 0.02 * b.L[i];
                let off = (a.L[i] - b.L[i]).abs();
                worst = worst.max(off / allowed);
                if off > allowed {
                    failures.push(format!(
                        "{name} at {} m, band {i}: photon map {:.5} +- {:.5}, path {:.5} +- {:.5}",
                        a.depth_m, a.L[i], a.stderr[i], b.L[i], b.stderr[i]
                    ));
                }
            }
            let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
            eprintln!(
                "{name} {} m: photon map / path {:.3}, worst band at {worst:.2} of its allowance",
                a.depth_m,
                mean(&a.L) / mean(&b.L)
            );
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
