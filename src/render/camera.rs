//! Camera rays: an orthographic sensor (a ground sample distance, looking
//! down at nadir or along `[sensor] view_zenith_deg`) and a pinhole camera,
//! both above the water.

use crate::scene::{Sensor, SensorKind};
use glam::Vec3;

/// Height of orthographic rays' origins above the mean surface (m).
const ORTHO_HEIGHT_M: f32 = 10.0;

/// A ray in air toward the water.
#[derive(Clone, Copy, Debug)]
pub struct CameraRay {
    pub origin: Vec3,
    pub direction: Vec3,
}

/// Ray for pixel (`px`, `py`) at sub-pixel offset (`u`, `v`) in [0, 1).
/// Pixel (0, 0) is the top-left of the image: low x, high y.
pub fn ray(sensor: &Sensor, px: usize, py: usize, u: f32, v: f32) -> CameraRay {
    let [w, h] = sensor.pixels;
    let sx = (px as f32 + u) / w as f32 - 0.5;
    let sy = 0.5 - (py as f32 + v) / h as f32;
    match &sensor.kind {
        SensorKind::Orthographic { gsd_m, center_m } => {
            let gsd = *gsd_m as f32;
            // The ray meets the mean surface at the pixel's ground point,
            // coming from the sensor's direction.
            let ground = Vec3::new(
                center_m[0] as f32 + sx * w as f32 * gsd,
                center_m[1] as f32 + sy * h as f32 * gsd,
                0.0,
            );
            let toward = sensor.toward;
            CameraRay {
                origin: ground + toward * (ORTHO_HEIGHT_M / toward.z),
                direction: -toward,
            }
        }
        SensorKind::Pinhole {
            position,
            look_at,
            fov_deg,
        } => {
            let forward = (*look_at - *position).normalize();
            // Image "up" leans toward +y when looking straight down.
            let up_hint = if forward.cross(Vec3::Z).length() < 1e-6 {
                Vec3::Y
            } else {
                Vec3::Z
            };
            let right = forward.cross(up_hint).normalize();
            let up = right.cross(forward);
            let half = (fov_deg.to_radians() as f32 * 0.5).tan();
            let aspect = h as f32 / w as f32;
            let d = forward + right * (2.0 * sx * half) + up * (2.0 * sy * half * aspect);
            CameraRay {
                origin: *position,
                direction: d.normalize(),
            }
        }
    }
}

#[cfg(test)]
mod tests;
