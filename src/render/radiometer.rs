//! Radiometer readings: radiance at points in the water or the air, by
//! either integrator, with their standard errors and the trust in them.

use super::march::RayMarcher;
use super::moments::Moments;
use super::path::PathTracer;
use super::{camera, Integrator};
use crate::error::Result;
use crate::estimate::estimator::Estimator;
use crate::rng::{mix64, Pcg32};
use crate::scene::{Radiometer, Scene};
use crate::store::PhotonQuery;
use glam::Vec3;
use rayon::prelude::*;

const RADIOMETER_STREAM: u64 = 0x7261_6469_6f6d;

/// A radiometer reading.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[allow(non_snake_case)]
pub struct RadiometerReading {
    pub depth_m: f64,
    pub view: String,
    pub position_m: [f64; 2],
    /// Radiance per band (W m^-2 sr^-1 nm^-1).
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub L: Vec<f64>,
    /// Standard error per band: for the path integrator the spread of its
    /// independent paths; for the photon map the photon noise from
    /// independent photon groups (`estimate::groups`) together with the
    /// spread of the jittered samples given the map.
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub stderr: Vec<f64>,
    /// Relative variance of the variance per band over the reading's
    /// samples (MCNP's VOV: sum (x - m)^4 / (sum (x - m)^2)^2 - 1/N). Below
    /// 0.1 the standard error can be trusted; above it a few samples
    /// dominate and `stderr` understates the error (a heavy tail).
    #[serde(default, deserialize_with = "crate::nan_json::f64s")]
    pub vov: Vec<f64>,
    /// Per band, the largest single sample's share of the samples' sum.
    #[serde(default, deserialize_with = "crate::nan_json::f64s")]
    pub largest_share: Vec<f64>,
    /// Standard error of the mean of `L` over all bands, from the samples'
    /// own band means (and the photon groups' band means): the bands of
    /// one sample are correlated, so it is neither the mean of `stderr`
    /// nor that over the square root of the band count.
    #[serde(default)]
    pub band_mean_stderr: f64,
}

/// The VOV above which a reading's standard error is not trusted (the
/// MCNP manual's criterion for a reliable confidence interval).
pub const VOV_LIMIT: f64 = 0.1;

/// Every radiometer's reading with `light`, in parallel on `threads`.
pub fn read_radiometers(
    scene: &Scene,
    light: &dyn Integrator,
    threads: usize,
) -> Result<Vec<RadiometerReading>> {
    let pool = crate::parallel::pool(threads)?;
    pool.install(|| {
        scene
            .radiometers
            .par_iter()
            .enumerate()
            .map(|(i, r)| read_radiometer(scene, light, i as u64, r))
            .collect::<Result<Vec<_>>>()
    })
}

/// Radiometer readings only (no image), with the photon-map integrator.
pub fn radiometers(scene: &Scene, map: &dyn PhotonQuery) -> Result<Vec<RadiometerReading>> {
    let light = RayMarcher::new(scene, Estimator::new(scene, map)?);
    scene
        .radiometers
        .iter()
        .enumerate()
        .map(|(i, r)| read_radiometer(scene, &light, i as u64, r))
        .collect()
}

/// Radiometer readings only (no image), with the path integrator.
pub fn radiometers_path(scene: &Scene, threads: usize) -> Result<Vec<RadiometerReading>> {
    let pool = crate::parallel::pool(threads)?;
    let light = PathTracer::new(scene);
    pool.install(|| {
        scene
            .radiometers
            .par_iter()
            .enumerate()
            .map(|(i, r)| read_radiometer(scene, &light, i as u64, r))
            .collect()
    })
}

fn read_radiometer(
    scene: &Scene,
    light: &dyn Integrator,
    index: u64,
    r: &Radiometer,
) -> Result<RadiometerReading> {
    let nb = scene.bands.len();
    let samples = light.radiometer_samples();
    let mut acc = Moments::new(nb, light.channels());
    let mut one = vec![0f64; nb * light.channels()];
    let mut water = vec![0f64; nb];
    for s in 0..samples {
        let mut rng = Pcg32::new(scene.seed ^ RADIOMETER_STREAM, mix64(index) ^ s);
        // Jitter within a 0.5 m footprint: the spread gives the error.
        let jx = (rng.uniform_f64() - 0.5) * 0.5;
        let jy = (rng.uniform_f64() - 0.5) * 0.5;
        let p = Vec3::new(
            (r.position_m[0] + jx) as f32,
            (r.position_m[1] + jy) as f32,
            -r.depth_m as f32,
        );
        let view = if r.half_angle_deg > 0.0 {
            within_field_of_view(r.view, r.half_angle_deg, &mut rng)
        } else {
            r.view
        };
        if r.depth_m > 0.0 {
            light.in_water(p, view, &mut rng, &mut one)?;
        } else {
            light.camera(
                camera::CameraRay {
                    origin: p,
                    direction: view,
                },
                &mut rng,
                &mut one,
                &mut water,
            )?;
        }
        acc.add(&one);
    }
    let l: Vec<f64> = acc.mean().collect();
    let mut se = vec![0f64; nb];
    acc.standard_error(&mut se);
    let (vov, largest_share) = acc.tail();
    Ok(RadiometerReading {
        band_mean_stderr: acc.band_mean_standard_error(),
        depth_m: r.depth_m,
        view: r.view_name.clone(),
        position_m: r.position_m,
        L: l,
        stderr: se,
        vov,
        largest_share,
    })
}

/// A direction within `half_angle_deg` of `axis`, drawn with density
/// proportional to the cosine of its angle from the axis (uniform on the
/// disc of radius sin(half angle) in the plane across it): what a flat
/// detector behind a circular aperture averages.
pub(super) fn within_field_of_view(axis: Vec3, half_angle_deg: f64, rng: &mut Pcg32) -> Vec3 {
    let r = half_angle_deg.to_radians().sin() * rng.uniform_f64().sqrt();
    let phi = 2.0 * std::f64::consts::PI * rng.uniform_f64();
    let (t, b) = axis.as_dvec3().any_orthonormal_pair();
    let d = axis.as_dvec3() * (1.0 - r * r).sqrt() + t * (r * phi.cos()) + b * (r * phi.sin());
    d.normalize().as_vec3()
}
