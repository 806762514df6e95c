//! The band-shape grid (`estimate::shape`) against the photons it
//! summarises: an estimate takes the band shape of its own view.

use crate::render::BOX_SCENE;
use glam::Vec3;
use littoral::bounds::Aabb;
use littoral::estimate::groups::CHANNELS;
use littoral::estimate::{Estimator, Scratch};
use littoral::photon::{volume_layer, Photon};
use littoral::rng::Pcg32;
use littoral::scene::{Overrides, Scene};
use littoral::store::InMemoryMap;
use littoral::store::{PhotonSource, StagedPhoton};
use std::ops::Range;
use std::path::Path;

/// Photons uniform in the 2 x 2 x 1 m box of `BOX_SCENE`, isotropic, two
/// bands: band 0 travelling within 28 degrees of the refracted sun's
/// direction (a sun 30 degrees from the zenith), band 1 otherwise.
struct SunBands {
    n: u64,
    sun_w: Vec3,
}

impl PhotonSource for SunBands {
    fn indices(&self) -> u64 {
        self.n
    }
    fn generate(&self, range: Range<u64>, out: &mut Vec<StagedPhoton>) {
        for i in range {
            let mut r = Pcg32::new(79, i);
            let p = Vec3::new(
                2.0 * r.uniform_f32(),
                2.0 * r.uniform_f32(),
                -r.uniform_f32(),
            );
            let z = 1.0 - 2.0 * r.uniform_f32();
            let s = (1.0 - z * z).max(0.0).sqrt();
            let phi = std::f32::consts::TAU * r.uniform_f32();
            let direction = Vec3::new(s * phi.cos(), s * phi.sin(), z);
            let photon = Photon {
                position: p,
                direction,
                band: u16::from(direction.dot(self.sun_w) < 28f32.to_radians().cos()),
                power: 1.0,
                group: littoral::photon::group_of_path(i),
            };
            out.push(StagedPhoton::new(&photon, volume_layer(photon.direction)));
        }
    }
    fn bands(&self) -> littoral::BandGrid {
        littoral::BandGrid::even(500.0, 510.0, 2).unwrap()
    }
    fn bounds(&self) -> Aabb {
        Aabb {
            min: Vec3::new(0.0, 0.0, -1.0),
            max: Vec3::new(2.0, 2.0, 0.0),
        }
    }
}

/// An oblique ray takes the band shape of its own view. In forward-peaked
/// water whose light travelling near the refracted sun is one band and all
/// other light another, a ray looking up along the sun (its in-scatter
/// truncates that light's peak) reads band 0's share of its in-scatter from
/// the `grid` mode as from the `compensated` mode, which weighs the found
/// photons themselves: over 147 sites 0.15 m apart (independent searches)
/// the mean difference is within 4 standard errors of the paired spread.
/// With the shapes of the view looking straight up, the grid reads the
/// share of a different view and fails.
#[test]
fn oblique_rays_take_the_band_shape_of_their_own_view() {
    let text = |spectral: &str| {
        BOX_SCENE
            .replace("zenith_deg = 0.0", "zenith_deg = 30.0")
            .replace("end_nm = 500.0\nbands = 1", "end_nm = 510.0\nbands = 2")
            .replace(
                "phase = { kind = \"isotropic\" }",
                "phase = { kind = \"fournier-forand\", bb_ratio = 0.0183 }",
            )
            .replace(
                "radius_m = 0.25\nspectral = \"naive\"",
                &format!("spectral = \"{spectral}\""),
            )
    };
    let parse = |t: String| Scene::parse(&t, Path::new("box.toml"), &Overrides::default()).unwrap();
    let (grid_scene, comp_scene) = (parse(text("grid")), parse(text("compensated")));
    let sun_w = littoral::optics::surface::refract(
        grid_scene.sun.direction.as_dvec3(),
        glam::DVec3::Z,
        1.0,
        grid_scene.surface.n_water,
    )
    .unwrap()
    .as_vec3();
    let map = InMemoryMap::from_source(&SunBands {
        n: 1_300_000,
        sun_w,
    })
    .unwrap();
    let grid = Estimator::new(&grid_scene, &map).unwrap();
    let comp = Estimator::new(&comp_scene, &map).unwrap();
    let mut scratch = Scratch::new(2);
    let mut out = [0.0f64; 2 * CHANNELS];
    let mut share = |est: &Estimator, x: Vec3| {
        // The viewer looks up along the sun: the light it sees travels
        // toward it along sun_w.
        est.volume(x, sun_w, &mut scratch, &mut out).unwrap();
        out[0] / (out[0] + out[1])
    };
    let mut diffs = Vec::new();
    let mut comp_mean = 0.0;
    for i in 0..7 {
        for j in 0..7 {
            for l in 0..3 {
                let x = Vec3::new(
                    0.55 + 0.15 * i as f32,
                    0.55 + 0.15 * j as f32,
                    -0.35 - 0.15 * l as f32,
                );
                let c = share(&comp, x);
                comp_mean += c;
                diffs.push(share(&grid, x) - c);
            }
        }
    }
    let n = diffs.len() as f64;
    comp_mean /= n;
    let mean = diffs.iter().sum::<f64>() / n;
    let se = (diffs.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
    eprintln!(
        "band 0 share: compensated {comp_mean:.4}, grid - compensated {mean:+.4} (se {se:.4})"
    );
    assert!(
        mean.abs() < 4.0 * se,
        "grid - compensated {mean} (se {se}) of {comp_mean}"
    );
}

/// The band-shape grid keeps to its byte cap with its target columns: the
/// built-in scene's grid, with a column over each of its two targets, and
/// a scene of 400 small boxes over 128 bands, whose columns alone would
/// pass the cap, both stay within `MAX_SHAPE_BYTES`; the second keeps as
/// many columns as fit.
#[test]
fn the_band_shape_grid_keeps_to_its_byte_cap_with_target_columns() {
    let photons = [20_000_000, 20_000_000];
    let coastal = Scene::coastal(&Overrides::default()).unwrap();
    let bytes = Estimator::shape_grid_bytes(&coastal, photons);
    assert!(bytes > 0 && bytes <= littoral::estimate::estimator::MAX_SHAPE_BYTES);
    assert_eq!(
        Estimator::shape_grid_columns(&coastal, photons),
        coastal.target_extents.len()
    );
    let mut text = String::from(
        "[spectral]\nstart_nm = 400.0\nend_nm = 800.0\nbands = 128\n[sun]\nzenith_deg = 30.0\nirradiance = 1.0\n\
         [domain]\nsize_m = [200.0, 200.0]\n[water]\niop = { a = 0.1, b = 0.2 }\n[photons]\ncount = 4000000\n\
         [bottom]\ndepth_m = 10.0\n",
    );
    for i in 0..400 {
        let (x, y) = (5.0 + 10.0 * (i % 20) as f64, 5.0 + 10.0 * (i / 20) as f64);
        text.push_str(&format!(
            "[[target]]\nkind = \"box\"\ncenter_m = [{x:?}, {y:?}, -5.0]\nsize_m = [1.0, 1.0, 1.0]\nreflectance = 0.5\n"
        ));
    }
    let many = Scene::parse(&text, Path::new("many.toml"), &Overrides::default()).unwrap();
    let bytes = Estimator::shape_grid_bytes(&many, photons);
    assert!(
        bytes <= littoral::estimate::estimator::MAX_SHAPE_BYTES,
        "{bytes} bytes"
    );
    let columns = Estimator::shape_grid_columns(&many, photons);
    assert!(columns > 0 && columns < 400, "{columns} columns");
}
