//! Rendering: the radiance cube an imaging spectrometer sees, and in-water
//! radiometers, from a scene and its photon map.
//!
//! The image is split into 16 x 16 pixel tiles rendered in parallel in
//! Morton order (neighbouring tiles query neighbouring photons, which keeps
//! the tile cache warm) and written to the ENVI cube as they finish, so the
//! whole cube is never in memory. Every pixel sample draws from the random
//! stream (seed, pixel, sample), so the cube is bit-identical for any
//! thread count.
//!
//! Not for: emission (see `emit`) or file formats (see `cube`).

pub mod camera;
pub mod march;

use crate::cube::envi::{CubeSpec, EnviWriter};
use crate::cube::quicklook::{write_png, Quicklook};
use crate::error::Result;
use crate::estimate::estimator::{with_scratch, Estimator};
use crate::morton::morton3;
use crate::progress::Progress;
use crate::rng::{mix64, Pcg32};
use crate::scene::{Radiometer, Scene};
use crate::store::PhotonQuery;
use glam::Vec3;
use march::RayMarcher;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// Side of an image tile in pixels.
pub const TILE_PX: usize = 16;
/// Samples (jittered positions within 0.5 m) per radiometer reading.
pub const RADIOMETER_SAMPLES: u64 = 32;

const PIXEL_STREAM: u64 = 0x7069_7865_6c73;
const RADIOMETER_STREAM: u64 = 0x7261_6469_6f6d;

/// A radiometer reading.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[allow(non_snake_case)]
pub struct RadiometerReading {
    pub depth_m: f64,
    pub view: String,
    pub position_m: [f64; 2],
    /// Radiance per band (W m^-2 sr^-1 nm^-1).
    #[serde(deserialize_with = "crate::json::f64s")]
    pub L: Vec<f64>,
    /// Standard error per band of the mean over the jittered samples: the
    /// march's sampling error. Photon-map noise is correlated over the
    /// search radius, so it is not in this figure (in deep water at 8 M
    /// photons and k = 800 it was 3-7 % between distant positions).
    #[serde(deserialize_with = "crate::json::f64s")]
    pub stderr: Vec<f64>,
}

/// What a render wrote.
#[derive(Clone, Debug)]
pub struct Rendered {
    pub hdr: PathBuf,
    pub bsq: PathBuf,
    pub exr: PathBuf,
    pub png: PathBuf,
    pub radiometers: Vec<RadiometerReading>,
    /// Tile-cache counters after the render.
    pub cache: crate::store::cache::CacheStats,
}

/// Render `scene` from `map` into `dir/NAME.{hdr,bsq,png}` with `threads`
/// threads (0 = all cores).
pub fn render(
    scene: &Scene,
    map: &dyn PhotonQuery,
    dir: &Path,
    threads: usize,
    progress: &dyn Progress,
) -> Result<Rendered> {
    let pool = crate::parallel::pool(threads)?;
    let light = RayMarcher::new(scene, Estimator::new(scene, map)?);
    let nb = scene.bands.len();
    let [w, h] = scene.sensor.pixels;
    let spec = CubeSpec {
        samples: w,
        lines: h,
        bands: scene.bands.clone(),
        description: format!("littoral radiance cube of scene '{}'", scene.name),
        data_units: "W m-2 sr-1 nm-1".into(),
    };
    let writer = EnviWriter::create(dir, &scene.name, spec)?;
    let quicklook = Quicklook::new(&scene.bands);
    let (tx, ty) = (w.div_ceil(TILE_PX), h.div_ceil(TILE_PX));
    let mut tiles: Vec<(u64, usize, usize)> = (0..ty)
        .flat_map(|j| (0..tx).map(move |i| (morton3([i as u16, j as u16, 0]), i, j)))
        .collect();
    tiles.sort_unstable();
    progress.stage("render tiles", tiles.len() as u64);
    let spp = scene.sensor.samples_per_pixel as u64;
    let rgb_tiles: Vec<(usize, usize, Vec<f32>)> = pool.install(|| {
        tiles
            .par_iter()
            .map(|&(_, i, j)| -> Result<(usize, usize, Vec<f32>)> {
                let (x0, y0) = (i * TILE_PX, j * TILE_PX);
                let (tw, th) = (TILE_PX.min(w - x0), TILE_PX.min(h - y0));
                let mut values = vec![0f32; tw * th * nb];
                let mut rgb = vec![0f32; tw * th * 3];
                let mut acc = vec![0f64; nb];
                let mut sample = vec![0f64; nb];
                with_scratch(nb, |scratch| -> Result<()> {
                    for py in 0..th {
                        for px in 0..tw {
                            let (gx, gy) = (x0 + px, y0 + py);
                            let pixel = (gy * w + gx) as u64;
                            acc.iter_mut().for_each(|a| *a = 0.0);
                            for s in 0..spp {
                                let mut rng =
                                    Pcg32::new(scene.seed ^ PIXEL_STREAM, pixel * spp + s);
                                let (u, v) = if spp == 1 {
                                    (0.5, 0.5)
                                } else {
                                    (rng.uniform_f32(), rng.uniform_f32())
                                };
                                let ray = camera::ray(&scene.sensor, gx, gy, u, v);
                                light.camera(ray, &mut rng, scratch, &mut sample)?;
                                acc.iter_mut().zip(&sample).for_each(|(a, s)| *a += s);
                            }
                            let base = (py * tw + px) * nb;
                            for b in 0..nb {
                                values[base + b] = (acc[b] / spp as f64) as f32;
                            }
                            let c = quicklook.rgb(&values[base..base + nb]);
                            rgb[(py * tw + px) * 3..(py * tw + px) * 3 + 3].copy_from_slice(&c);
                        }
                    }
                    Ok(())
                })?;
                writer.write_tile(x0, y0, tw, th, &values)?;
                progress.advance(1);
                Ok((i, j, rgb))
            })
            .collect::<Result<Vec<_>>>()
    })?;
    progress.finish();
    let mut image = vec![0f32; w * h * 3];
    for (i, j, rgb) in rgb_tiles {
        let (x0, y0) = (i * TILE_PX, j * TILE_PX);
        let tw = TILE_PX.min(w - x0);
        for (row, chunk) in rgb.chunks(tw * 3).enumerate() {
            let start = ((y0 + row) * w + x0) * 3;
            image[start..start + chunk.len()].copy_from_slice(chunk);
        }
    }
    let png = dir.join(format!("{}.png", scene.name));
    write_png(&png, w, h, &image, None)?;
    let crate::cube::envi::CubeFiles { hdr, bsq } = writer.finish()?;
    // The spectral OpenEXR copy, tile by tile from the finished cube.
    let exr = dir.join(format!("{}.exr", scene.name));
    crate::cube::exr::write_spectral_exr(&crate::cube::EnviCube::open(&hdr)?, &exr)?;
    let radiometers = pool.install(|| {
        scene
            .radiometers
            .par_iter()
            .enumerate()
            .map(|(i, r)| read_radiometer(&light, i as u64, r))
            .collect::<Result<Vec<_>>>()
    })?;
    Ok(Rendered {
        hdr,
        bsq,
        exr,
        png,
        radiometers,
        cache: map.cache_stats(),
    })
}

/// Radiometer readings only (no image).
pub fn radiometers(scene: &Scene, map: &dyn PhotonQuery) -> Result<Vec<RadiometerReading>> {
    let light = RayMarcher::new(scene, Estimator::new(scene, map)?);
    scene
        .radiometers
        .iter()
        .enumerate()
        .map(|(i, r)| read_radiometer(&light, i as u64, r))
        .collect()
}

fn read_radiometer(light: &RayMarcher, index: u64, r: &Radiometer) -> Result<RadiometerReading> {
    let nb = light.scene.bands.len();
    let mut sum = vec![0f64; nb];
    let mut sum_sq = vec![0f64; nb];
    let mut one = vec![0f64; nb];
    with_scratch(nb, |scratch| -> Result<()> {
        for s in 0..RADIOMETER_SAMPLES {
            let mut rng = Pcg32::new(light.scene.seed ^ RADIOMETER_STREAM, mix64(index) ^ s);
            // Jitter within a 0.5 m footprint: the spread gives the error.
            let jx = (rng.uniform_f64() - 0.5) * 0.5;
            let jy = (rng.uniform_f64() - 0.5) * 0.5;
            let p = Vec3::new(
                (r.position_m[0] + jx) as f32,
                (r.position_m[1] + jy) as f32,
                -r.depth_m as f32,
            );
            if r.depth_m > 0.0 {
                light.march(p, r.view, &mut rng, scratch, &mut one)?;
            } else {
                light.camera(
                    camera::CameraRay {
                        origin: p,
                        direction: r.view,
                    },
                    &mut rng,
                    scratch,
                    &mut one,
                )?;
            }
            for b in 0..nb {
                sum[b] += one[b];
                sum_sq[b] += one[b] * one[b];
            }
        }
        Ok(())
    })?;
    let n = RADIOMETER_SAMPLES as f64;
    let l: Vec<f64> = sum.iter().map(|s| s / n).collect();
    let se = sum_sq
        .iter()
        .zip(&l)
        .map(|(s2, m)| ((s2 / n - m * m).max(0.0) / (n - 1.0)).sqrt())
        .collect();
    Ok(RadiometerReading {
        depth_m: r.depth_m,
        view: r.view_name.clone(),
        position_m: r.position_m,
        L: l,
        stderr: se,
    })
}
