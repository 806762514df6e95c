//! The mean radiance leaving the surface per direction cell, from
//! integrator calls: the air view's control variate and the sea's upward
//! light that the air returns (`render::sea_air`).

use super::super::camera::CameraRay;
use super::super::Integrator;
use super::classes::BINS;
use super::{
    AirView, Class, CALL_STEPS, ENV_KEY, ENV_SAMPLES, ENV_SHARE, LAND_KEY, POOLED_KEY, POOLED_PATHS,
};
use crate::error::Result;
use crate::optics::atmosphere::transport::{point_in_cell, AZIMUTH_BINS, CELLS};
use crate::rng::Pcg32;
use crate::scene::Scene;
use glam::DVec3;
use rayon::prelude::*;

impl AirView<'_> {
    /// The mean radiance leaving the surface per direction cell and band,
    /// glint taken out, at points of the class `class`: up to
    /// `ENV_SAMPLES` integrator calls per cell (the water's classes share
    /// twice that), at random points of the class and directions
    /// cosine-weighted within the cell, on either side of the sun's
    /// vertical plane.
    ///
    /// Returns the table and, for a water class, its depth bins' factors
    /// (`classes::BINS` x bands; empty for the land).
    pub(super) fn environment(
        &self,
        light: &dyn Integrator,
        class: Class,
    ) -> Result<(Vec<f64>, Vec<f64>)> {
        let [w, h] = self.scene.sensor.pixels;
        let samples = (w * h) as f64 * f64::from(self.scene.sensor.samples_per_pixel);
        let per_cell = ((samples * ENV_SHARE / CELLS as f64) as u64).clamp(1, ENV_SAMPLES);
        let (per_cell, key) = match class {
            Class::Land => (per_cell, LAND_KEY),
            Class::Water(k) => {
                let waters = self.classes.waters() as u64;
                let per_class = (2 * per_cell).div_ceil(waters).clamp(1, per_cell);
                (per_class, ENV_KEY.wrapping_add(k as u64))
            }
        };
        let leaving = self.table(light, Some(class), per_cell, key)?;
        Ok((leaving.table, leaving.factors))
    }

    /// The table of [`AirView::environment`] from `per_cell` calls of
    /// `light` per cell at points of `class` (`None`: of the water), drawn
    /// from the stream `key`; for a water class, with its depth bins'
    /// factors.
    pub(super) fn table(
        &self,
        light: &dyn Integrator,
        class: Option<Class>,
        per_cell: u64,
        key: u64,
    ) -> Result<Leaving> {
        let [sx, sy] = self.scene.domain.size_m;
        let bin = |at: DVec3| self.classes.at(at).1;
        leaving_table(
            self.scene,
            light,
            CALL_STEPS,
            per_cell,
            key,
            self.ray_height_m,
            &|rng| self.point_of_class(rng, sx, sy, class),
            &|at, up, glint| self.glint_at(at, up, glint),
            matches!(class, Some(Class::Water(_)))
                .then_some(&bin as &(dyn Fn(DVec3) -> usize + Sync)),
        )
    }

    /// Per band, the scattered part of the table plus the glint, from
    /// `POOLED_PATHS` adjoint paths (in chunks of their own streams, summed
    /// in order), and its standard error from the chunks' spread.
    pub(super) fn pooled(&self) -> (Vec<f64>, Vec<f64>) {
        let nb = self.columns.len();
        let chunks = 64u64;
        let per = POOLED_PATHS / chunks;
        let seed = crate::rng::mix64(self.scene.seed ^ POOLED_KEY);
        let sums: Vec<Vec<f64>> = (0..chunks)
            .into_par_iter()
            .map(|k| {
                let mut sum = vec![0.0; nb];
                let mut glint = vec![0.0; nb];
                for i in 0..per {
                    let mut rng = Pcg32::new(seed, k * per + i);
                    self.adjoint(DVec3::ZERO, &mut rng, |_, _, dir, w| {
                        let up = -dir;
                        self.glint(up, &mut glint);
                        let c = self.cell(up);
                        for b in 0..nb {
                            sum[b] += w[b] * (self.env[c * nb + b] + glint[b]);
                        }
                        Ok(())
                    })
                    .expect("the pooled paths call no integrator");
                }
                sum
            })
            .collect();
        let k = chunks as f64;
        (0..nb)
            .map(|b| {
                let means = sums.iter().map(|s| s[b] / per as f64);
                let m = means.clone().sum::<f64>() / k;
                let var = means.map(|x| (x - m) * (x - m)).sum::<f64>() / (k - 1.0);
                (m, (var / k).sqrt())
            })
            .unzip()
    }
}

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
/// `per_cell` calls of `light` per cell (marching with steps
/// `step_factor` times the scene's), from the stream `key`, at points
/// `point` draws and directions cosine-weighted within the cell, on
/// either side of the sun's vertical plane, each ray handed down from
/// `ray_height_m` above its point; `glint_at(point, up, out)` writes the
/// glint the call's radiance holds there. Each cell's calls draw from
/// their own streams: the same table for any number of threads.
///
/// With `bin` (a point's bin of [`BINS`]) the table and each bin's factor
/// per band are fitted together ([`fit_bins`]), so that the table times a
/// point's bin's factor follows what changes from point to point.
#[allow(clippy::too_many_arguments)]
pub(crate) fn leaving_table(
    scene: &Scene,
    light: &dyn Integrator,
    step_factor: f32,
    per_cell: u64,
    key: u64,
    ray_height_m: f64,
    point: &(dyn Fn(&mut Pcg32) -> DVec3 + Sync),
    glint_at: &(dyn Fn(DVec3, DVec3, &mut [f64]) + Sync),
    bin: Option<&(dyn Fn(DVec3) -> usize + Sync)>,
) -> Result<Leaving> {
    let nb = scene.bands.len();
    let channels = light.channels();
    let seed = crate::rng::mix64(scene.seed ^ key);
    let cells: Vec<Result<CellCalls>> = (0..CELLS)
        .into_par_iter()
        .map(|c| {
            let (mut sum, mut sum_sq, mut out, mut water, mut glint) = (
                vec![0.0; nb],
                vec![0.0; nb],
                vec![0.0; nb * channels],
                vec![0.0; nb],
                vec![0.0; nb],
            );
            let bins = if bin.is_some() { BINS } else { 0 };
            let (mut bin_sum, mut bin_calls) = (vec![0.0; bins * nb], vec![0u64; bins]);
            for k in 0..per_cell {
                let mut rng = Pcg32::new(seed, c as u64 * per_cell.max(ENV_SAMPLES) + k);
                let u = [rng.uniform_f64(), rng.uniform_f64()];
                let (mu, phi) = point_in_cell(c / AZIMUTH_BINS, c % AZIMUTH_BINS, u);
                let phi = if rng.uniform_f64() < 0.5 { phi } else { -phi } + scene.sun.azimuth_rad;
                let sz = (1.0 - mu * mu).max(0.0).sqrt();
                let up = DVec3::new(sz * phi.cos(), sz * phi.sin(), mu.max(1e-3)).normalize();
                let at = point(&mut rng);
                let ray = ray_from_above(at, up, ray_height_m);
                light.camera_coarse(ray, step_factor, &mut rng, &mut out, &mut water)?;
                glint_at(at, up, &mut glint);
                let j = bin.map(|f| f(at));
                if let Some(j) = j {
                    bin_calls[j] += 1;
                }
                for b in 0..nb {
                    let x = out[b] - glint[b];
                    sum[b] += x / per_cell as f64;
                    sum_sq[b] += x * x;
                    if let Some(j) = j {
                        bin_sum[j * nb + b] += x;
                    }
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
            Ok(CellCalls {
                mean: sum,
                var,
                bin_sum,
                bin_calls,
            })
        })
        .collect();
    let cells = cells.into_iter().collect::<Result<Vec<CellCalls>>>()?;
    let mut env: Vec<f64> = cells.iter().flat_map(|c| c.mean.iter().copied()).collect();
    let var = cells.iter().flat_map(|c| c.var.iter().copied()).collect();
    let factors = match bin {
        Some(_) => fit_bins(&cells, nb, &mut env),
        None => Vec::new(),
    };
    Ok(Leaving {
        table: env,
        var,
        factors,
    })
}

/// Rounds of [`fit_bins`].
const FIT_ROUNDS: usize = 4;

/// The table and the bins' factors of x = table(cell) factor(bin), per
/// band, fitted to the calls' sums by alternating means: each cell's
/// value the mean of its calls' x / factor, each bin's factor the sum of
/// its calls' x over the sum of their cells' values (1 where either is
/// not positive), normalised to a mean of 1 over the calls. A cell then
/// no longer carries the depths its few calls happened to meet: with one
/// factor per class the built-in scene's shallowest class (floors 0-0.5
/// m, ten times apart in the red) left a cell's table off by 40 %.
/// Writes the table into `table` (cell-major) and returns the factors
/// (bin-major).
fn fit_bins(cells: &[CellCalls], nb: usize, table: &mut [f64]) -> Vec<f64> {
    let mut factors = vec![1.0; BINS * nb];
    let calls: Vec<u64> = (0..BINS)
        .map(|j| cells.iter().map(|c| c.bin_calls[j]).sum())
        .collect();
    let total: u64 = calls.iter().sum();
    if total == 0 {
        return factors;
    }
    let (mut num, mut den) = (vec![0.0; BINS * nb], vec![0.0; BINS * nb]);
    for _ in 0..FIT_ROUNDS {
        cell_values(cells, nb, &factors, table);
        num.iter_mut().for_each(|v| *v = 0.0);
        den.iter_mut().for_each(|v| *v = 0.0);
        for (c, cell) in cells.iter().enumerate() {
            for j in 0..BINS {
                let n = cell.bin_calls[j] as f64;
                for b in 0..nb {
                    num[j * nb + b] += cell.bin_sum[j * nb + b];
                    den[j * nb + b] += n * table[c * nb + b];
                }
            }
        }
        for b in 0..nb {
            let mut mean = 0.0;
            for j in 0..BINS {
                let (n, d) = (num[j * nb + b], den[j * nb + b]);
                let f = if n > 0.0 && d > 0.0 { n / d } else { 1.0 };
                factors[j * nb + b] = f;
                mean += f * calls[j] as f64 / total as f64;
            }
            if mean > 0.0 {
                for j in 0..BINS {
                    factors[j * nb + b] /= mean;
                }
            }
        }
    }
    // The cells' values under the last factors.
    cell_values(cells, nb, &factors, table);
    factors
}

/// Each cell's value per band: the mean of its calls' x / factor (cells
/// without calls keep theirs).
fn cell_values(cells: &[CellCalls], nb: usize, factors: &[f64], table: &mut [f64]) {
    for (c, cell) in cells.iter().enumerate() {
        let n: u64 = cell.bin_calls.iter().sum();
        if n == 0 {
            continue;
        }
        for b in 0..nb {
            let sum: f64 = (0..BINS)
                .filter(|&j| cell.bin_calls[j] > 0)
                .map(|j| cell.bin_sum[j * nb + b] / factors[j * nb + b])
                .sum();
            table[c * nb + b] = sum / n as f64;
        }
    }
}

/// One direction cell's calls of [`leaving_table`]: the mean and its
/// variance per band, and per bin the sum per band and the calls.
struct CellCalls {
    mean: Vec<f64>,
    var: Vec<f64>,
    bin_sum: Vec<f64>,
    bin_calls: Vec<u64>,
}

/// What [`leaving_table`] found.
pub(crate) struct Leaving {
    /// The mean radiance leaving the surface per cell and band
    /// (cell-major), glint taken out; with bins, the fitted values.
    pub table: Vec<f64>,
    /// The variance of each cell's plain mean (from the calls' spread; 0
    /// for a single call).
    pub var: Vec<f64>,
    /// Per bin and band (bin-major), the bins' factors; empty without
    /// bins.
    pub factors: Vec<f64>,
}
