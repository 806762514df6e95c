//! Searches of few photons, and searches cut to a share of the scene's,
//! read a uniform density: the k-nearest edge photon left out, and the
//! region of a shrunken search taken at its own count.

use crate::render::{uniform_box_map, BOX_SCENE};
use glam::Vec3;
use littoral::estimate::groups::CHANNELS;
use littoral::estimate::{Estimator, Scratch};
use littoral::scene::{Overrides, Scene};
use std::path::Path;

/// k-nearest searches of few photons read the density without the
/// k/(k - 1) of counting the photon on the search's edge: over 2023
/// interior sites of the uniform box 0.1 m apart (the 16 nearest photons
/// lie within about 2.3 cm, so the sites' estimates are independent), with
/// k = k_expanded = 16, the mean of the estimates is within 4 standard
/// errors (the sites' spread over sqrt of their count, about 0.6 %) of the
/// truth, where counting all 16 reads 16/15 of it (11 standard errors).
#[test]
fn nearest_searches_read_uniform_density_without_the_edge_photon() {
    let (map, truth) = uniform_box_map();
    let scene = box_scene_with_k(16);
    let est = Estimator::new(&scene, &map).unwrap();
    let mut scratch = Scratch::new(1);
    let mut out = [0.0f64; CHANNELS];
    let (mean, se) = over_interior_sites(|x| {
        est.volume(x, Vec3::Z, &mut scratch, &mut out).unwrap();
        out[0] / truth
    });
    eprintln!("k = 16: {mean:.4} of the truth, se {se:.4}");
    assert!(
        (mean - 1.0).abs() < 4.0 * se,
        "{mean} of the truth, se {se}"
    );
}

/// The uniform box's scene with k nearest photons in both searches (at
/// most 1 m away) instead of its fixed radius.
fn box_scene_with_k(k: usize) -> Scene {
    let text = BOX_SCENE.replace(
        "radius_m = 0.25",
        &format!("k = {k}\nk_expanded = {k}\nmax_radius_m = 1.0"),
    );
    Scene::parse(&text, Path::new("box.toml"), &Overrides::default()).unwrap()
}

/// The mean of `ratio` over 2023 interior sites of the uniform box 0.1 m
/// apart, and its standard error from the sites' spread.
fn over_interior_sites(mut ratio: impl FnMut(Vec3) -> f64) -> (f64, f64) {
    let mut ratios = Vec::new();
    for i in 0..17 {
        for j in 0..17 {
            for l in 0..7 {
                let x = Vec3::new(
                    0.2 + 0.1 * i as f32,
                    0.2 + 0.1 * j as f32,
                    -0.2 - 0.1 * l as f32,
                );
                ratios.push(ratio(x));
            }
        }
    }
    let n = ratios.len() as f64;
    let mean = ratios.iter().sum::<f64>() / n;
    let var = ratios.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// A share of the scene's searches (`Estimator::volume_with_iops`, as a
/// march takes where its light has faded) reads the same density: with
/// k = k_expanded = 160 and a share of 0.1, 16 photons within 0.1^(1/3)
/// of the largest radius, the mean over the 2023 interior sites of
/// `nearest_searches_read_uniform_density_without_the_edge_photon` is
/// within 4 standard errors of the truth. A search region taken for the
/// scene's 160 photons instead of the share's 16 (the largest radius, as
/// for a search that found too few) read 0.00014 of it.
#[test]
fn a_share_of_the_searches_reads_uniform_density() {
    let (map, truth) = uniform_box_map();
    let scene = box_scene_with_k(160);
    let est = Estimator::new(&scene, &map).unwrap();
    let mut scratch = Scratch::new(1);
    let mut out = [0.0f64; CHANNELS];
    let mut iops = vec![littoral::optics::iop::Iop::default(); 1];
    let (mean, se) = over_interior_sites(|x| {
        scene.water.iops(x, &mut iops);
        est.volume_with_iops(x, Vec3::Z, false, 0.1, &iops, &mut scratch, &mut out)
            .unwrap();
        out[0] / truth
    });
    eprintln!("k = 160, share 0.1: {mean:.4} of the truth, se {se:.4}");
    assert!(
        (mean - 1.0).abs() < 4.0 * se,
        "{mean} of the truth, se {se}"
    );
}
