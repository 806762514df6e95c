//! A Lambertian ground (`[surface] kind = "lambertian"`): no water, the
//! ground at z = 0 of reflectance R per band. Every point of it sends
//! R E / pi in every direction, with E the sun's horizontal irradiance
//! plus the sky's (`Scene::incident_irradiance`; under an atmosphere the
//! sky holds every order of reflection between the ground and the air,
//! `optics::atmosphere::transport::ground_response`). That is exact, so
//! the render is deterministic per pixel: the air above a sensor at
//! altitude (`render::air`) is what is sampled.
//!
//! Its products: the radiance leaving the ground is the `surface` cube,
//! L_w and R_rs are 0 (no water).

use super::camera::CameraRay;
use super::Integrator;
use crate::error::Result;
use crate::rng::Pcg32;
use crate::scene::Scene;
use glam::Vec3;

/// The radiance of a Lambertian ground.
pub struct Ground {
    /// R E / pi per band.
    radiance: Vec<f64>,
}

impl Ground {
    /// The ground of `scene`, none for a sea.
    pub fn new(scene: &Scene) -> Option<Ground> {
        let r = scene.ground.as_ref()?;
        Some(Ground {
            radiance: lambertian_radiance(scene, r),
        })
    }
}

/// The radiance per band of a Lambertian surface of reflectance `r` per
/// band under `scene`'s sun and sky: R E / pi.
pub fn lambertian_radiance(scene: &Scene, r: &[f64]) -> Vec<f64> {
    r.iter()
        .enumerate()
        .map(|(b, r)| r * scene.incident_irradiance(b) / std::f64::consts::PI)
        .collect()
}

impl Integrator for Ground {
    fn bands(&self) -> usize {
        self.radiance.len()
    }
    fn channels(&self) -> usize {
        1
    }
    /// The ground's radiance for a ray that meets it (going down), else 0
    /// (the sky above a ground is not rendered: sensors look down).
    fn camera(
        &self,
        ray: CameraRay,
        _rng: &mut Pcg32,
        out: &mut [f64],
        water: &mut [f64],
    ) -> Result<()> {
        water.iter_mut().for_each(|w| *w = 0.0);
        let down = ray.direction.z < 0.0;
        for (o, l) in out.iter_mut().zip(&self.radiance) {
            *o = if down { *l } else { 0.0 };
        }
        Ok(())
    }
    /// No water: nothing arrives under the ground (scenes with a ground
    /// have no radiometers).
    fn in_water(&self, _p: Vec3, _dir: Vec3, _rng: &mut Pcg32, out: &mut [f64]) -> Result<()> {
        out.iter_mut().for_each(|o| *o = 0.0);
        Ok(())
    }
    fn radiometer_samples(&self) -> u64 {
        1
    }
    fn independent_samples(&self) -> bool {
        true
    }
}
