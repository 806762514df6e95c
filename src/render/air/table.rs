//! The mean radiance leaving the surface per direction cell, from
//! integrator calls: the air view's control variate and the sea's upward
//! light that the air returns (`render::sea_air`).

use super::super::camera::CameraRay;
use super::super::Integrator;
use super::ENV_SAMPLES;
use crate::error::Result;
use crate::optics::atmosphere::transport::{point_in_cell, AZIMUTH_BINS, CELLS};
use crate::rng::Pcg32;
use crate::scene::Scene;
use glam::DVec3;
use rayon::prelude::*;

/// The ray that sees the radiance leaving the ground at `at` toward `up`
/// (unit), coming down from `height_m` above it.
pub(super) fn ray_from_above(at: DVec3, up: DVec3, height_m: f64) -> CameraRay {
    CameraRay {
        origin: (at + up * (height_m / up.z)).as_vec3(),
        direction: (-up).as_vec3(),
    }
}

/// The mean radiance leaving the surface of `scene` per direction cell
/// of the sky grid and band (cell-major), sun glint taken out:
/// `per_cell` calls of `light` per cell, from the stream `key`, at points
/// `point` draws and directions cosine-weighted within the cell, on
/// either side of the sun's vertical plane, each ray handed down from
/// `ray_height_m` above its point; `glint_at(point, up, out)` writes the
/// glint the call's radiance holds there. Each cell's calls draw from
/// their own streams: the same table for any number of threads. Returns
/// the table and the variance of each of its means (from the calls'
/// spread; 0 for a single call).
pub(crate) fn leaving_table(
    scene: &Scene,
    light: &dyn Integrator,
    per_cell: u64,
    key: u64,
    ray_height_m: f64,
    point: &(dyn Fn(&mut Pcg32) -> DVec3 + Sync),
    glint_at: &(dyn Fn(DVec3, DVec3, &mut [f64]) + Sync),
) -> Result<(Vec<f64>, Vec<f64>)> {
    let nb = scene.bands.len();
    let channels = light.channels();
    let seed = crate::rng::mix64(scene.seed ^ key);
    let cells: Vec<Result<(Vec<f64>, Vec<f64>)>> = (0..CELLS)
        .into_par_iter()
        .map(|c| {
            let (mut sum, mut sum_sq, mut out, mut water, mut glint) = (
                vec![0.0; nb],
                vec![0.0; nb],
                vec![0.0; nb * channels],
                vec![0.0; nb],
                vec![0.0; nb],
            );
            for k in 0..per_cell {
                let mut rng = Pcg32::new(seed, c as u64 * per_cell.max(ENV_SAMPLES) + k);
                let u = [rng.uniform_f64(), rng.uniform_f64()];
                let (mu, phi) = point_in_cell(c / AZIMUTH_BINS, c % AZIMUTH_BINS, u);
                let phi = if rng.uniform_f64() < 0.5 { phi } else { -phi } + scene.sun.azimuth_rad;
                let sz = (1.0 - mu * mu).max(0.0).sqrt();
                let up = DVec3::new(sz * phi.cos(), sz * phi.sin(), mu.max(1e-3)).normalize();
                let at = point(&mut rng);
                let ray = ray_from_above(at, up, ray_height_m);
                light.camera(ray, &mut rng, &mut out, &mut water)?;
                glint_at(at, up, &mut glint);
                for b in 0..nb {
                    let x = out[b] - glint[b];
                    sum[b] += x / per_cell as f64;
                    sum_sq[b] += x * x;
                }
            }
            let n = per_cell as f64;
            let var: Vec<f64> = if per_cell > 1 {
                (0..nb)
                    .map(|b| ((sum_sq[b] / n - sum[b] * sum[b]) / (n - 1.0)).max(0.0))
                    .collect()
            } else {
                vec![0.0; nb]
            };
            Ok((sum, var))
        })
        .collect();
    let mut env = Vec::with_capacity(CELLS * nb);
    let mut var = Vec::with_capacity(CELLS * nb);
    for c in cells {
        let (m, v) = c?;
        env.extend(m);
        var.extend(v);
    }
    Ok((env, var))
}
