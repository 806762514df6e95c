//! Land in the domain: the floor where it rises above the water line
//! (`[land]`), what the scene answers about it.

use super::Scene;
use glam::Vec3;

/// Land: the floor where it rises above the water line, a Lambertian
/// surface (`render::land`).
#[derive(Clone, Debug)]
pub struct Land {
    /// Reflectance per band.
    pub reflectance: Vec<f64>,
    /// The largest of `reflectance`.
    pub max_reflectance: f64,
    /// The land's highest point above the mean surface (m).
    pub top_m: f32,
    /// Its steepest slope (degrees).
    pub steepest_deg: f64,
}

impl Scene {
    /// True when `p` lies below the floor (which a path wrapped across a
    /// periodic edge reaches where the floor's depths differ at the seam).
    pub fn under_floor(&self, p: Vec3) -> bool {
        self.bottom.is_some()
            && self
                .geometry
                .floor_depth_at(p.x, p.y)
                .is_some_and(|d| p.z < -d)
    }

    /// What the land leaves out here: a warning when it rises more
    /// steeply than the sun stands, so that it may shade the water, which
    /// `render::land` does not simulate.
    pub fn land_warnings(&self) -> Vec<String> {
        let Some(land) = &self.land else {
            return Vec::new();
        };
        let elevation = 90.0 - self.sun.zenith_rad.to_degrees();
        if land.steepest_deg <= elevation {
            return Vec::new();
        }
        vec![format!(
            "the land rises at up to {:.0} degrees, steeper than the sun's elevation ({elevation:.0} degrees): its shadow on the water and the sky it hides from the water are not simulated",
            land.steepest_deg
        )]
    }

    /// True where the floor rises above the water line at (`x`, `y`).
    pub fn is_land(&self, x: f32, y: f32) -> bool {
        self.land.is_some() && self.geometry.floor_depth_at(x, y).is_some_and(|d| d < 0.0)
    }
}
