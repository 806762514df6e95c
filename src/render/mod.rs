//! Rendering: the radiance cube an imaging spectrometer sees, and in-water
//! radiometers, by either integrator ([`Integrator`]): the photon map's ray
//! marcher ([`march::RayMarcher`]) or the reference path tracer
//! ([`path::PathTracer`]).
//!
//! The image is split into 16 x 16 pixel tiles rendered in parallel in
//! Morton order (neighbouring tiles query neighbouring photons, which keeps
//! the tile cache warm) and handed to a [`TileSink`] as they finish (the
//! job's cube set, or a part's tile files), so the whole cube is never in
//! memory. Every pixel sample draws from the random
//! stream (seed, pixel, sample), so the cube is bit-identical for any
//! thread count.
//!
//! **Standard-error cube** (`NAME.stderr.hdr`, also the EXR's second
//! layer). For the path integrator, with two or more samples per pixel:
//! the standard error of the mean over a pixel's independent paths. For
//! the photon map, always: its photon noise from independent photon
//! groups carried along every ray (`estimate::groups`), plus, with two or
//! more samples per pixel, the sampling error given the map (the samples'
//! spread over their count); at one sample per pixel the renderer's own
//! sampling noise (march jitter, rough-surface facets) is not in it. With
//! the sensor above the surface at one sample per pixel it also holds the
//! noise of the paths through the air: the variance of their part
//! (`air::AirView::drawn_part`) over the pixel's tile. With surroundings
//! it holds, at any number of samples, the error of the mean lookup of
//! the adjoint paths shared by every sample (`air::shared`).
//!
//! Not for: emission (see `emit`), writing files (the sinks live in
//! `job::outputs` and `job::distributed::tile_file`) or file formats (see
//! `cube`).

pub mod air;
pub mod air_sea;
pub mod camera;
pub mod ground;
pub mod land;
pub mod march;
mod moments;
pub mod path;
mod radiometer;
pub mod sea_air;
pub mod sun;
pub mod targets;

use crate::cube::quicklook::Quicklook;
use crate::error::Result;
use crate::estimate::estimator::{with_scratch, Estimator};
use crate::estimate::groups::{CHANNELS, GROUPS};
use crate::morton::morton3;
use crate::progress::Progress;
use crate::rng::Pcg32;
use crate::scene::settings::PATH_RADIOMETER_PATHS_PER_SPP;
use crate::scene::Scene;
use crate::store::PhotonQuery;
use air_sea::from_air_parts;
use glam::Vec3;
use march::RayMarcher;
use moments::Moments;
use path::{PathScratch, PathTracer};
pub use radiometer::{
    radiometers, radiometers_path, read_radiometers, RadiometerReading, VOV_LIMIT,
};
use std::cell::RefCell;

/// Side of an image tile in pixels.
pub const TILE_PX: usize = 16;
// A spectral EXR tile is 2 x 2 image tiles, aligned, so tiles finishing in
// their Morton order finish the EXR's tiles in theirs.
const _: () = assert!(TILE_PX == crate::cube::exr::TILE);
/// Samples (jittered positions within 0.5 m) per radiometer reading.
pub const RADIOMETER_SAMPLES: u64 = 256;

const PIXEL_STREAM: u64 = 0x7069_7865_6c73;

/// A light-transport integrator: radiance along sensor rays and at
/// radiometers. Implementations are shared by all rendering threads.
pub trait Integrator: Sync {
    /// Bands of every radiance vector.
    fn bands(&self) -> usize;
    /// Runs of bands in the vectors `camera` and `in_water` write: 1 (the
    /// radiance), or [`CHANNELS`] (the radiance, then the photon groups'
    /// parts of it).
    fn channels(&self) -> usize;
    /// Radiance per band reaching a sensor along `ray` (in air), and the
    /// part of it that left the water into `water` (one value per band).
    fn camera(
        &self,
        ray: camera::CameraRay,
        rng: &mut Pcg32,
        out: &mut [f64],
        water: &mut [f64],
    ) -> Result<()>;
    /// [`camera`](Self::camera) for a call whose result is a small
    /// correction averaged with many (the air's control variates): the
    /// same expectation, taken cheaper where the integrator can — the
    /// photon map marches with steps `step_factor` times longer. The
    /// path integrator takes it as `camera`.
    fn camera_coarse(
        &self,
        ray: camera::CameraRay,
        step_factor: f32,
        rng: &mut Pcg32,
        out: &mut [f64],
        water: &mut [f64],
    ) -> Result<()> {
        let _ = step_factor;
        self.camera(ray, rng, out, water)
    }
    /// Radiance per band arriving at `p` (in water) along `-dir`.
    fn in_water(&self, p: Vec3, dir: Vec3, rng: &mut Pcg32, out: &mut [f64]) -> Result<()>;
    /// Samples (jittered positions, each one path or march) per radiometer
    /// reading.
    fn radiometer_samples(&self) -> u64;
    /// True when a pixel's samples are independent, so that their spread
    /// is the pixel's error and a standard-error cube can be written.
    fn independent_samples(&self) -> bool;
}

impl Integrator for RayMarcher<'_> {
    fn bands(&self) -> usize {
        self.scene.bands.len()
    }
    fn channels(&self) -> usize {
        CHANNELS
    }
    fn camera(
        &self,
        ray: camera::CameraRay,
        rng: &mut Pcg32,
        out: &mut [f64],
        water: &mut [f64],
    ) -> Result<()> {
        self.camera_coarse(ray, 1.0, rng, out, water)
    }
    fn camera_coarse(
        &self,
        ray: camera::CameraRay,
        step_factor: f32,
        rng: &mut Pcg32,
        out: &mut [f64],
        water: &mut [f64],
    ) -> Result<()> {
        with_scratch(self.bands(), |s| {
            from_air_parts(
                self.scene,
                &self.sky_l,
                ray,
                rng,
                out,
                water,
                &mut |p, d, rng, out| self.march_coarse(p, d, step_factor, rng, s, out),
            )
        })
    }
    fn in_water(&self, p: Vec3, dir: Vec3, rng: &mut Pcg32, out: &mut [f64]) -> Result<()> {
        with_scratch(self.bands(), |s| self.march(p, dir, rng, s, out))
    }
    fn radiometer_samples(&self) -> u64 {
        RADIOMETER_SAMPLES
    }
    fn independent_samples(&self) -> bool {
        false
    }
}

thread_local! {
    static PATH_SCRATCH: RefCell<Option<PathScratch>> = const { RefCell::new(None) };
}

/// Run `f` with this thread's path buffers for `bands` bands.
fn with_path_scratch<R>(bands: usize, f: impl FnOnce(&mut PathScratch) -> R) -> R {
    crate::parallel::with_band_scratch(&PATH_SCRATCH, bands, f)
}

impl Integrator for PathTracer<'_> {
    fn bands(&self) -> usize {
        self.scene.bands.len()
    }
    fn channels(&self) -> usize {
        1
    }
    fn camera(
        &self,
        ray: camera::CameraRay,
        rng: &mut Pcg32,
        out: &mut [f64],
        water: &mut [f64],
    ) -> Result<()> {
        with_path_scratch(out.len(), |s| {
            from_air_parts(
                self.scene,
                &self.sky_l,
                ray,
                rng,
                out,
                water,
                &mut |p, d, rng, out| {
                    self.in_water(p, d, rng, s, out);
                    Ok(())
                },
            )
        })
    }
    fn in_water(&self, p: Vec3, dir: Vec3, rng: &mut Pcg32, out: &mut [f64]) -> Result<()> {
        with_path_scratch(out.len(), |s| {
            PathTracer::in_water(self, p, dir, rng, s, out)
        });
        Ok(())
    }
    fn radiometer_samples(&self) -> u64 {
        PATH_RADIOMETER_PATHS_PER_SPP * self.scene.sensor.samples_per_pixel as u64
    }
    fn independent_samples(&self) -> bool {
        true
    }
}

/// Units of the radiance cubes.
pub const RADIANCE_UNITS: &str = "W m-2 sr-1 nm-1";

/// A product cube written beside the total radiance.
#[derive(Clone, Copy, Debug)]
pub struct Product {
    /// File name suffix: `NAME.SUFFIX.hdr`.
    pub suffix: &'static str,
    /// Its layer in the EXR.
    pub layer: &'static str,
    pub description: &'static str,
    pub units: &'static str,
}

/// The products (Mobley 1999): L_w, the radiance that left the water
/// through the surface; the surface-reflected radiance L_t - L_w (sky in
/// the facets and sun glint); R_rs = L_w / E_d(0+), with E_d(0+) the sun's
/// horizontal irradiance plus the sky's.
pub const PRODUCTS: [Product; 3] = [
    Product {
        suffix: "lw",
        layer: "lw",
        description: "water-leaving radiance (L_w)",
        units: RADIANCE_UNITS,
    },
    Product {
        suffix: "surface",
        layer: "surface",
        description: "surface-reflected radiance at the surface, sky and sun glint (L_t - L_w from just above it)",
        units: RADIANCE_UNITS,
    },
    Product {
        suffix: "rrs",
        layer: "rrs",
        description: "remote-sensing reflectance (R_rs = L_w / E_d(0+))",
        units: "sr-1",
    },
];

/// The products of a sensor above the surface, after [`PRODUCTS`]: the
/// reflectance at the sensor rho_t = pi L_t / (E_0 mu_0), with E_0 the
/// sun's beam-normal irradiance at the top of the atmosphere on the day
/// (the Earth–Sun distance in it) and mu_0 the cosine of the sun's zenith;
/// the path radiance L_path (light scattered into the view that never
/// reached the surface); the total transmittances t_down, from the top of
/// the atmosphere to the surface (E_d(0+) / (E_0 mu_0)), and t_up, from a
/// Lambertian ground to the sensor along its view. The last three are the
/// air's, horizontally uniform, and so the same in every pixel of an
/// orthographic view; they are cubes so that a pixel's L_t can be taken
/// apart (L_t = L_path + t_up L_surface-leaving, over a uniform ground)
/// with the same tools as the other products.
pub const AIR_PRODUCTS: [Product; 4] = [
    Product {
        suffix: "rhot",
        layer: "rhot",
        description: "reflectance at the sensor (rho_t = pi L_t / (E_0 cos theta_s), E_0 at the top of the atmosphere on the day)",
        units: "1",
    },
    Product {
        suffix: "lpath",
        layer: "lpath",
        description: "atmospheric path radiance at the sensor (L_path: scattered into the view, never reached the surface)",
        units: RADIANCE_UNITS,
    },
    Product {
        suffix: "tdown",
        layer: "tdown",
        description: "total transmittance of the air from its top to the surface, direct and diffuse (t_down = E_d(0+) / (E_0 cos theta_s))",
        units: "1",
    },
    Product {
        suffix: "tup",
        layer: "tup",
        description: "total transmittance of the air from a Lambertian ground to the sensor along its view, direct and scattered (t_up)",
        units: "1",
    },
];

/// pi / (E_0 mu_0): radiance to reflectance for the sun's beam-normal
/// irradiance `e0` at the top of the atmosphere and the cosine `mu0` of its
/// zenith (0 where no sunlight arrives).
pub fn reflectance_factor(e0: f64, mu0: f64) -> f64 {
    let top = e0 * mu0;
    if top > 0.0 {
        std::f64::consts::PI / top
    } else {
        0.0
    }
}

/// The product cubes a render of `scene` writes: [`PRODUCTS`], then
/// [`AIR_PRODUCTS`] with the sensor above the surface.
pub fn products(scene: &Scene) -> Vec<Product> {
    let air = scene.atmosphere.as_ref().and_then(|a| a.view.as_ref());
    PRODUCTS
        .iter()
        .chain(air.map(|_| AIR_PRODUCTS.iter()).into_iter().flatten())
        .copied()
        .collect()
}

/// What a render measured besides its tiles (which went to its sink).
#[derive(Clone, Debug, Default)]
pub struct Rendered {
    pub radiometers: Vec<RadiometerReading>,
    /// Tile-cache counters after the render (zero without a photon map).
    pub cache: crate::store::cache::CacheStats,
    /// What the render found wrong with its inputs (see
    /// [`targets::face_warnings`]).
    pub warnings: Vec<String>,
}

/// Where finished image tiles go, from any worker thread, in any order.
pub trait TileSink: Sync {
    fn write(&self, tile: &TileResult) -> Result<()>;
}

/// Render `scene` from `map` with the photon-map integrator into `sink`
/// with `threads` threads (0 = all cores), then read its radiometers.
pub fn render(
    scene: &Scene,
    map: &dyn PhotonQuery,
    sink: &dyn TileSink,
    threads: usize,
    progress: &dyn Progress,
) -> Result<Rendered> {
    let light = RayMarcher::new(scene, Estimator::new(scene, map)?);
    Ok(Rendered {
        radiometers: render_with(scene, &light, sink, threads, progress)?,
        cache: map.cache_stats(),
        warnings: targets::face_warnings(scene, map)?,
    })
}

/// Render `scene` with the path integrator (no photon map) into `sink`,
/// then read its radiometers; a Lambertian ground with its exact radiance
/// ([`ground::Ground`]).
pub fn render_path(
    scene: &Scene,
    sink: &dyn TileSink,
    threads: usize,
    progress: &dyn Progress,
) -> Result<Rendered> {
    let radiometers = match ground::Ground::new(scene) {
        Some(g) => render_with(scene, &g, sink, threads, progress)?,
        None => render_with(scene, &PathTracer::new(scene), sink, threads, progress)?,
    };
    Ok(Rendered {
        radiometers,
        ..Default::default()
    })
}

/// The rendered values of one image tile (16 x 16 pixels, fewer at the
/// right and bottom edges), pixel-major with the bands innermost.
#[derive(Clone, Debug, PartialEq)]
pub struct TileResult {
    /// Tile column and row.
    pub i: usize,
    pub j: usize,
    /// Width and height in pixels.
    pub w: usize,
    pub h: usize,
    /// L_t per pixel and band.
    pub values: Vec<f32>,
    /// Its standard error (empty without a standard-error cube).
    pub errors: Vec<f32>,
    /// The products in the order of [`PRODUCTS`].
    pub products: Vec<Vec<f32>>,
    /// Quicklook colour per pixel (linear RGB).
    pub rgb: Vec<f32>,
}

/// The image tiles of `scene` as (column, row), in the Morton order they
/// are rendered in (neighbouring tiles query neighbouring photons).
pub fn image_tiles(scene: &Scene) -> Vec<(usize, usize)> {
    let [w, h] = scene.sensor.pixels;
    let (tx, ty) = (w.div_ceil(TILE_PX), h.div_ceil(TILE_PX));
    let mut tiles: Vec<(u64, usize, usize)> = (0..ty)
        .flat_map(|j| (0..tx).map(move |i| (morton3([i as u16, j as u16, 0]), i, j)))
        .collect();
    tiles.sort_unstable();
    tiles.into_iter().map(|(_, i, j)| (i, j)).collect()
}

/// What the standard-error cube holds for `scene`'s integrator, or None
/// when it writes none (the path integrator at one sample per pixel).
pub fn stderr_description(scene: &Scene) -> Option<String> {
    let spp = scene.sensor.samples_per_pixel;
    match scene.render.integrator {
        crate::scene::IntegratorMode::PhotonMap if spp == 1 && scene.sensor.altitude_m.is_some() => {
            Some(format!(
                "photon noise from {GROUPS} photon groups, 1 sample per pixel, and the noise of the paths through the air: the variance of their part pooled over each {TILE_PX} x {TILE_PX} tile, and the error of the air paths' lookups shared by every sample"
            ))
        }
        crate::scene::IntegratorMode::PhotonMap => Some(format!(
            "photon noise from {GROUPS} photon groups, {spp} samples per pixel"
        )),
        crate::scene::IntegratorMode::Path if spp >= 2 => {
            Some(format!("{spp} independent paths per pixel"))
        }
        crate::scene::IntegratorMode::Path => None,
    }
}

/// Render tile (`i`, `j`) of `scene` with `light`.
pub fn render_tile(
    scene: &Scene,
    light: &dyn Integrator,
    air: Option<&air::AirView>,
    (i, j): (usize, usize),
    quicklook: &Quicklook,
) -> Result<TileResult> {
    let nb = scene.bands.len();
    let [w, h] = scene.sensor.pixels;
    let spp = scene.sensor.samples_per_pixel as u64;
    let channels = light.channels();
    let with_errors = stderr_description(scene).is_some();
    // E_d(0+): the sun's horizontal irradiance plus the sky's.
    let ed: Vec<f64> = (0..nb).map(|b| scene.incident_irradiance(b)).collect();
    let (x0, y0) = (i * TILE_PX, j * TILE_PX);
    let (tw, th) = (TILE_PX.min(w - x0), TILE_PX.min(h - y0));
    let mut values = vec![0f32; tw * th * nb];
    let mut errors = vec![0f32; if with_errors { tw * th * nb } else { 0 }];
    let mut rgb = vec![0f32; tw * th * 3];
    let mut products = vec![vec![0f32; tw * th * nb]; products(scene).len()];
    // With the sensor above the surface: pi / (E_0 mu_0) per band, for
    // rho_t, and the air's own products, the same in every pixel (L_path,
    // t_down, t_up).
    let toa = scene.atmosphere.as_ref().and_then(|a| {
        let view = a.view.as_ref()?;
        let mu0 = scene.sun.zenith_rad.cos();
        let to_rho: Vec<f64> = a
            .bands
            .iter()
            .map(|band| reflectance_factor(band.toa_irradiance, mu0))
            .collect();
        let t_down: Vec<f64> = a.bands.iter().map(|band| band.t_down(mu0)).collect();
        Some((
            to_rho,
            [
                view.path_radiance.clone(),
                t_down,
                view.transmittance_up.clone(),
            ],
        ))
    });
    // Above the surface at one sample per pixel the samples' spread is not
    // known: each pixel's draw of the air paths' part (`AirView::
    // drawn_part`) is kept, and its variance over the tile is added to
    // every pixel's (each draws its paths from nearly the same
    // distribution; the adjacency changes over hundreds of metres).
    let air_noise = air.filter(|_| spp == 1 && with_errors);
    let mut drawn = vec![0f64; if air_noise.is_some() { tw * th * nb } else { 0 }];
    let mut acc = Moments::new(nb, channels);
    let mut sample = vec![0f64; nb * channels];
    let (mut water, mut water_sum) = (vec![0f64; nb], vec![0f64; nb]);
    // With the sensor above the surface: the radiance leaving the surface
    // at each ground point, before the air.

    let (mut parts, mut surface_sum) = (air::AirSample::new(nb), vec![0f64; nb]);
    // The variance of the part every sample at its ground point adds alike
    // (the shared air paths' mean lookup), summed over the samples.
    let mut known_var = vec![0f64; nb];
    let mut se = vec![0f64; nb];
    for py in 0..th {
        for px in 0..tw {
            let (gx, gy) = (x0 + px, y0 + py);
            let pixel = (gy * w + gx) as u64;
            acc.clear();
            water_sum.iter_mut().for_each(|v| *v = 0.0);
            surface_sum.iter_mut().for_each(|v| *v = 0.0);
            known_var.iter_mut().for_each(|v| *v = 0.0);
            for s in 0..spp {
                let mut rng = Pcg32::new(scene.seed ^ PIXEL_STREAM, pixel * spp + s);
                let (u, v) = if spp == 1 {
                    (0.5, 0.5)
                } else {
                    (rng.uniform_f32(), rng.uniform_f32())
                };
                let ray = camera::ray(&scene.sensor, gx, gy, u, v);
                match air {
                    Some(a) => {
                        a.camera(light, ray, &mut rng, &mut sample, &mut water, &mut parts)?
                    }
                    None => {
                        light.camera(ray, &mut rng, &mut sample, &mut water)?;
                        parts.at_surface.copy_from_slice(&sample[..nb]);
                    }
                }
                acc.add(&sample);
                if let Some(a) = air_noise {
                    let at = (py * tw + px) * nb;
                    a.drawn_part(&sample[..nb], &parts, &mut drawn[at..at + nb]);
                }
                water_sum.iter_mut().zip(&water).for_each(|(a, v)| *a += v);
                surface_sum
                    .iter_mut()
                    .zip(&parts.at_surface)
                    .for_each(|(a, v)| *a += v);
                known_var
                    .iter_mut()
                    .zip(&parts.known_var)
                    .for_each(|(a, v)| *a += v);
            }
            let base = (py * tw + px) * nb;
            for (b, m) in acc.mean().enumerate() {
                let lw = water_sum[b] / spp as f64;
                let leaving = surface_sum[b] / spp as f64;
                values[base + b] = m as f32;
                products[0][base + b] = lw as f32;
                products[1][base + b] = (leaving - lw) as f32;
                products[2][base + b] = if ed[b] > 0.0 {
                    (lw / ed[b]) as f32
                } else {
                    0.0
                };
                if let Some((to_rho, air)) = &toa {
                    products[3][base + b] = (m * to_rho[b]) as f32;
                    for (product, values) in products[4..].iter_mut().zip(air) {
                        product[base + b] = values[b] as f32;
                    }
                }
            }
            if !errors.is_empty() {
                acc.standard_error(&mut se);
                // The shared paths' error is common to a pixel's samples.
                for ((e, s), v) in errors[base..base + nb].iter_mut().zip(&se).zip(&known_var) {
                    *e = (s * s + v / spp as f64).sqrt() as f32;
                }
            }
            let c = quicklook.rgb(&values[base..base + nb]);
            rgb[(py * tw + px) * 3..(py * tw + px) * 3 + 3].copy_from_slice(&c);
        }
    }
    let pixels = tw * th;
    if air_noise.is_some() && pixels > 1 {
        for b in 0..nb {
            let mean = (0..pixels).map(|p| drawn[p * nb + b]).sum::<f64>() / pixels as f64;
            let var = (0..pixels)
                .map(|p| (drawn[p * nb + b] - mean).powi(2))
                .sum::<f64>()
                / (pixels - 1) as f64;
            for p in 0..pixels {
                let e = &mut errors[p * nb + b];
                *e = (f64::from(*e).powi(2) + var).sqrt() as f32;
            }
        }
    }
    Ok(TileResult {
        i,
        j,
        w: tw,
        h: th,
        values,
        errors,
        products,
        rgb,
    })
}

/// Render `scene`'s image tiles with `light` into `sink`, then read its
/// radiometers.
pub fn render_with(
    scene: &Scene,
    light: &dyn Integrator,
    sink: &dyn TileSink,
    threads: usize,
    progress: &dyn Progress,
) -> Result<Vec<RadiometerReading>> {
    render_tiles(scene, light, &image_tiles(scene), sink, threads, progress)?;
    read_radiometers(scene, light, threads)
}

/// How many tiles past the oldest unfinished one may be handed out with
/// `workers` rendering: a sink that writes in a fixed order (the spectral
/// EXR) holds at most this many finished tiles while one is slow. Two
/// more than the workers keeps them busy past a tile twice as slow as the
/// others.
pub fn dispatch_window(workers: usize) -> usize {
    workers.max(1) + 2
}

/// Tile indices handed out in order to the rendering threads, never more
/// than `window` past the oldest unfinished one (a thread asking for more
/// waits for it).
struct Dispatch {
    state: std::sync::Mutex<DispatchState>,
    ready: std::sync::Condvar,
    window: usize,
}

struct DispatchState {
    next: usize,
    oldest: usize,
    done: Vec<bool>,
    stopped: bool,
}

impl Dispatch {
    fn new(tiles: usize, window: usize) -> Dispatch {
        Dispatch {
            state: std::sync::Mutex::new(DispatchState {
                next: 0,
                oldest: 0,
                done: vec![false; tiles],
                stopped: false,
            }),
            ready: std::sync::Condvar::new(),
            window: window.max(1),
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, DispatchState> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The next tile, or `None` once all are handed out or a thread failed.
    fn take(&self) -> Option<usize> {
        let mut s = self.lock();
        loop {
            if s.stopped || s.next >= s.done.len() {
                return None;
            }
            if s.next < s.oldest + self.window {
                s.next += 1;
                return Some(s.next - 1);
            }
            s = self.ready.wait(s).unwrap_or_else(|e| e.into_inner());
        }
    }

    fn finish(&self, k: usize) {
        let mut s = self.lock();
        s.done[k] = true;
        while s.oldest < s.done.len() && s.done[s.oldest] {
            s.oldest += 1;
        }
        self.ready.notify_all();
    }

    fn stop(&self) {
        self.lock().stopped = true;
        self.ready.notify_all();
    }
}

/// Render the image tiles `tiles` of `scene` with `light` into `sink`, in
/// parallel on `threads`.
pub fn render_tiles(
    scene: &Scene,
    light: &dyn Integrator,
    tiles: &[(usize, usize)],
    sink: &dyn TileSink,
    threads: usize,
    progress: &dyn Progress,
) -> Result<()> {
    let pool = crate::parallel::pool(threads)?;
    let quicklook = Quicklook::new(&scene.bands);
    // With the sensor above the surface, the air's tables first.
    let air = pool.install(|| air::AirView::new(scene, light))?;
    progress.stage("render tiles", tiles.len() as u64);
    let dispatch = Dispatch::new(tiles.len(), dispatch_window(pool.current_num_threads()));
    // One loop per pool thread, each taking the next tile in order.
    let results = pool.broadcast(|_| -> Result<()> {
        while let Some(k) = dispatch.take() {
            let step = crate::progress::check(progress)
                .and_then(|()| render_tile(scene, light, air.as_ref(), tiles[k], &quicklook))
                .and_then(|t| sink.write(&t));
            if let Err(e) = step {
                dispatch.stop();
                return Err(e);
            }
            progress.advance(1);
            dispatch.finish(k);
        }
        Ok(())
    });
    results.into_iter().collect::<Result<()>>()?;
    progress.finish();
    Ok(())
}

/// Per-band sums of samples, for tests: each band's mean, its standard
/// error and one sample's spread.
#[cfg(test)]
pub(crate) struct BandSums {
    n: u64,
    sum: Vec<f64>,
    sum_sq: Vec<f64>,
}

#[cfg(test)]
impl BandSums {
    pub(crate) fn new(bands: usize) -> Self {
        BandSums {
            n: 0,
            sum: vec![0.0; bands],
            sum_sq: vec![0.0; bands],
        }
    }

    /// One sample: a value per band.
    pub(crate) fn add(&mut self, values: impl IntoIterator<Item = f64>) {
        self.n += 1;
        for ((s, s2), v) in self.sum.iter_mut().zip(&mut self.sum_sq).zip(values) {
            *s += v;
            *s2 += v * v;
        }
    }

    /// Per band: (mean, standard error of the mean, one sample's spread).
    pub(crate) fn stats(&self) -> Vec<(f64, f64, f64)> {
        let n = self.n as f64;
        self.sum
            .iter()
            .zip(&self.sum_sq)
            .map(|(s, s2)| {
                let m = s / n;
                let sd = (s2 / n - m * m).max(0.0).sqrt();
                (m, sd / n.sqrt(), sd)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests;
