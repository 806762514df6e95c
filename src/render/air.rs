//! The sensor above the surface (`[sensor] altitude_m` under an
//! `[atmosphere]`): the radiance at the sensor from the radiance leaving
//! the surface, by either integrator, and the air between.
//!
//! For a camera ray meeting the ground at P along the view (unit `toward`
//! the sensor, cosine mu_v), per band b:
//!
//! ```text
//! L_t = L_path + T_b L(P) + (light leaving the surface elsewhere and
//!       scattered into the view)
//! ```
//!
//! - **L_path**, the light scattered into the view that never reached the
//!   surface, is the same for every pixel of an orthographic sensor over a
//!   horizontally uniform atmosphere: computed once per band when the
//!   scene is read ([`crate::scene::ViewLight`],
//!   `optics::atmosphere::transport::path_radiance`).
//! - **T_b L(P)**: the direct transmittance exp(-tau_b / mu_v) times the
//!   integrator's radiance leaving P toward the sensor, exactly.
//! - **The scattered part**, by an adjoint path from the sensor: a
//!   collision along the view is drawn from the bands' mean extinction (the
//!   pilot), then directions from the pilot's phase mixture and free paths
//!   from its extinction, each band weighted by its own scattering,
//!   transmittance and phase over the pilot's (ratios bounded by the small
//!   optical depths of air), until the path leaves the top or meets the
//!   ground at P', where the integrator's radiance leaving P' along the
//!   path is added with the band's weight. Horizontal positions wrap into
//!   the domain. Light leaving the water near P reaches the sensor through
//!   the air this way: the adjacency effect comes out of the transport.
//!
//! Not in it: light the surface sends up that the air returns down to the
//! surface (the sky at the surface is over a black surface).

use super::camera::CameraRay;
use super::Integrator;
use crate::error::Result;
use crate::optics::atmosphere::Column;
use crate::rng::Pcg32;
use crate::scene::{Scene, ViewLight};
use glam::DVec3;

/// Height above the surface of the rays handed to the integrator (m).
const RAY_HEIGHT_M: f64 = 10.0;

/// A path's largest band weight below which it plays Russian roulette.
const ROULETTE: f64 = 0.1;

/// The air between the ground and a sensor above it.
pub struct AirView<'s> {
    scene: &'s Scene,
    view: &'s ViewLight,
    columns: &'s [Column],
    pilot: Column,
    /// Per layer and band: the band's scattering optical depth over the
    /// pilot's extinction, and its Rayleigh share (band-major within the
    /// layer).
    scatter_ratio: Vec<f64>,
    share: Vec<f64>,
    /// Per layer: the pilot's Rayleigh share of scattering.
    pilot_share: Vec<f64>,
    toward: DVec3,
    altitude_km: f64,
}

impl<'s> AirView<'s> {
    /// The air of `scene`, none unless its sensor has an altitude.
    pub fn new(scene: &'s Scene) -> Option<AirView<'s>> {
        let a = scene.atmosphere.as_deref()?;
        let view = a.view.as_ref()?;
        let columns = &a.columns[..];
        let pilot = Column::mean(columns);
        let nl = pilot.layers.len();
        let nb = columns.len();
        let mut scatter_ratio = vec![0.0; nl * nb];
        let mut share = vec![0.0; nl * nb];
        let mut pilot_share = vec![0.0; nl];
        for i in 0..nl {
            let t = pilot.layers[i].tau();
            for (b, c) in columns.iter().enumerate() {
                let l = &c.layers[i];
                let s = l.rayleigh + l.aerosol_scattering;
                scatter_ratio[i * nb + b] = if t > 0.0 { s / t } else { 0.0 };
                share[i * nb + b] = l.rayleigh_share();
            }
            pilot_share[i] = pilot.layers[i].rayleigh_share();
        }
        Some(AirView {
            scene,
            view,
            columns,
            pilot,
            scatter_ratio,
            share,
            pilot_share,
            toward: scene.sensor.toward.as_dvec3().normalize(),
            altitude_km: view.altitude_m * 1e-3,
        })
    }

    /// The radiance at the sensor along camera ray `ray` (which meets the
    /// ground at its pixel's ground point) into `out` (every channel run of
    /// `light`), the water-leaving radiance at that ground point into
    /// `water`, and the radiance leaving the surface there (before the air)
    /// into `at_surface`.
    pub fn camera(
        &self,
        light: &dyn Integrator,
        ray: CameraRay,
        rng: &mut Pcg32,
        out: &mut [f64],
        water: &mut [f64],
        at_surface: &mut [f64],
    ) -> Result<()> {
        let nb = self.columns.len();
        light.camera(ray, rng, out, water)?;
        at_surface.copy_from_slice(&out[..nb]);
        for (k, o) in out.iter_mut().enumerate() {
            *o *= self.view.transmittance[k % nb];
        }
        for (o, p) in out.iter_mut().zip(&self.view.path_radiance) {
            *o += p;
        }
        let ground = ray.origin.as_dvec3()
            + ray.direction.as_dvec3() * (f64::from(ray.origin.z) / -f64::from(ray.direction.z));
        self.scattered(light, ground, rng, out)
    }

    /// The light leaving the surface elsewhere that the air scatters into
    /// the view of the pixel whose ground point is `ground`, added to `out`.
    fn scattered(
        &self,
        light: &dyn Integrator,
        ground: DVec3,
        rng: &mut Pcg32,
        out: &mut [f64],
    ) -> Result<()> {
        let nb = self.columns.len();
        let pilot = &self.pilot;
        let total = pilot.total();
        let mu_v = self.toward.z;
        let z_s = self.altitude_km.min(pilot.layers[0].top_km);
        let d_s = pilot.depth_at(z_s);
        // The first collision along the view, down from the sensor.
        let d_c = d_s + rng.exp1() * mu_v;
        if d_c >= total {
            return Ok(());
        }
        let mut z = pilot.height_at(d_c);
        let mut w = vec![0.0; nb];
        let i = pilot.layer_index(z);
        for (b, wb) in w.iter_mut().enumerate() {
            let c = &self.columns[b];
            let excess = (c.depth_at(z) - c.depth_at(z_s)) - (d_c - d_s);
            *wb = self.scatter_ratio[i * nb + b] * (-excess / mu_v).exp();
        }
        let mut pos = ground + self.toward * (z * 1e3 / mu_v);
        let mut dir = -self.toward;
        let mut layer = i;
        let mut tmp = Vec::new();
        let mut tmp_water = Vec::new();
        loop {
            // Scatter: a direction from the pilot's phase mixture.
            let s = self.pilot_share[layer];
            let column = &self.columns[0];
            let phase = if rng.uniform_f64() < s {
                &column.rayleigh_phase
            } else {
                &column.aerosol_phase
            };
            let cos = phase.sample_cos(rng.uniform_f64());
            let phi = std::f64::consts::TAU * rng.uniform_f64();
            let next = crate::optics::phase::scatter(dir.as_vec3(), cos as f32, phi as f32)
                .as_dvec3()
                .normalize();
            let cos = dir.dot(next);
            let pr = column.rayleigh_phase.eval(cos);
            let pa = column.aerosol_phase.eval(cos);
            let p_pilot = s * pr + (1.0 - s) * pa;
            for (b, wb) in w.iter_mut().enumerate() {
                let sb = self.share[layer * nb + b];
                // Each band's own Rayleigh phase (its q) and share.
                let c = &self.columns[b];
                let pb = sb * c.rayleigh_phase.eval(cos) + (1.0 - sb) * pa;
                *wb *= pb / p_pilot;
            }
            dir = next;
            let largest = w.iter().copied().fold(0.0, f64::max);
            if largest < ROULETTE {
                let q = largest / ROULETTE;
                if rng.uniform_f64() >= q {
                    return Ok(());
                }
                w.iter_mut().for_each(|v| *v /= q);
            }
            if dir.z.abs() < 1e-9 {
                // Level: it never reaches the ground nor the top.
                return Ok(());
            }
            // Fly.
            let d_here = pilot.depth_at(z);
            let step = rng.exp1() * dir.z.abs();
            let d_next = if dir.z < 0.0 {
                d_here + step
            } else {
                d_here - step
            };
            if dir.z >= 0.0 && d_next <= 0.0 {
                return Ok(());
            }
            if dir.z < 0.0 && d_next >= total {
                // The ground, at the pilot's no-collision probability.
                let mu = -dir.z;
                for (b, wb) in w.iter_mut().enumerate() {
                    let c = &self.columns[b];
                    let excess = (c.total() - c.depth_at(z)) - (total - d_here);
                    *wb *= (-excess / mu).exp();
                }
                let meet = pos + dir * (z * 1e3 / mu);
                let meet = self.wrap(meet);
                let ray = CameraRay {
                    origin: (meet - dir * (RAY_HEIGHT_M / mu)).as_vec3(),
                    direction: dir.as_vec3(),
                };
                tmp.resize(out.len(), 0.0);
                tmp_water.resize(nb, 0.0);
                light.camera(ray, rng, &mut tmp, &mut tmp_water)?;
                for (k, (o, t)) in out.iter_mut().zip(&tmp).enumerate() {
                    *o += w[k % nb] * t;
                }
                return Ok(());
            }
            let z_next = pilot.height_at(d_next);
            let next_layer = pilot.layer_index(z_next);
            for (b, wb) in w.iter_mut().enumerate() {
                let c = &self.columns[b];
                let excess = (c.depth_at(z_next) - c.depth_at(z)).abs() - (d_next - d_here).abs();
                *wb *= self.scatter_ratio[next_layer * nb + b] * (-excess / dir.z.abs()).exp();
            }
            pos += dir * ((z_next - z).abs() * 1e3 / dir.z.abs());
            z = z_next;
            layer = next_layer;
        }
    }

    /// `p` moved into the domain horizontally (the air is the same
    /// everywhere; the domain repeats for light that travels through it).
    fn wrap(&self, p: DVec3) -> DVec3 {
        let [sx, sy] = self.scene.domain.size_m;
        DVec3::new(p.x.rem_euclid(sx), p.y.rem_euclid(sy), 0.0)
    }
}

#[cfg(test)]
mod tests;
