//! The sky a rough sea reflects toward a ray from above, averaged over its
//! facets: along the orthographic sensor's view once per scene
//! ([`Scene::reflected_sky`]), along any other ray per ray
//! ([`Scene::facets_reflected_sky`]); control variates for the sky one
//! facet reflects (`render::air_sea`).

use super::{Scene, SensorKind};
use glam::Vec3;

/// The sky a rough sea's facets reflect toward a sensor looking along
/// `direction` (travel, down), averaged over the facets as one camera
/// ray draws them (`SeaSurface::split_from_above`, Smith's masking of the
/// reflected ray; each band's Fresnel reflectance): a control variate for
/// the sky each sample's one facet reflects (`render::air_sea`).
#[derive(Clone, Debug, PartialEq)]
pub struct ReflectedSky {
    pub direction: Vec3,
    /// Per band (W m^-2 sr^-1 nm^-1).
    pub mean: Vec<f64>,
}

/// Facets drawn for [`ReflectedSky`]: its own noise, the same in every
/// pixel and unbiased, is a fraction of a per cent of the reflected sky.
pub const REFLECTED_SKY_FACETS: u64 = 1 << 18;

/// Mixed into the scene's seed for [`ReflectedSky`]'s facets.
const REFLECTED_SKY_KEY: u64 = 0x7265_666c_5f73_6b79;

impl Scene {
    /// The facets' mean reflected sky along the orthographic sensor's
    /// view, over a rough sea; none for a flat sea or a pinhole camera.
    /// Computed once, deterministic from the scene's seed.
    pub fn reflected_sky(&self) -> Option<&ReflectedSky> {
        // Sequential: it may be first asked for from inside a parallel
        // loop, whose other items would ask again on this thread.
        self.reflected_sky
            .get_or_init(|| {
                if self.surface.slope_variance <= 0.0
                    || !matches!(self.sensor.kind, SensorKind::Orthographic { .. })
                {
                    return None;
                }
                let d = -self.sensor.toward;
                let sky_l: Vec<f64> = self
                    .sky
                    .irradiance
                    .iter()
                    .map(|e| e / std::f64::consts::PI)
                    .collect();
                let mut rng =
                    crate::rng::Pcg32::new(crate::rng::mix64(self.seed ^ REFLECTED_SKY_KEY), 0);
                let mean = self.facets_reflected_sky(d, &sky_l, REFLECTED_SKY_FACETS, &mut rng);
                Some(ReflectedSky { direction: d, mean })
            })
            .as_ref()
    }

    /// The sky a rough sea reflects toward a ray travelling along `d`
    /// (down) from above, per band, averaged over `n` facets drawn as one
    /// camera ray draws them (`SeaSurface::split_from_above`; Smith's
    /// masking of the reflected ray as a weight; each band's Fresnel
    /// reflectance); `sky_l` is the isotropic sky's radiance per band.
    pub fn facets_reflected_sky(
        &self,
        d: Vec3,
        sky_l: &[f64],
        n: u64,
        rng: &mut crate::rng::Pcg32,
    ) -> Vec<f64> {
        let dispersive = self.dispersive();
        let mut sum = vec![0.0; sky_l.len()];
        for _ in 0..n {
            let split = self.surface.split_from_above(d, rng);
            let dir = split.reflected;
            if dir.z <= 0.0 {
                continue;
            }
            let unmasked = self.surface.masking(dir.as_dvec3());
            let g = self.sky.model.at(dir);
            for (b, s) in sum.iter_mut().enumerate() {
                let r = if dispersive {
                    crate::optics::surface::fresnel_reflectance(
                        split.cos_i,
                        1.0,
                        self.water_index[b],
                    )
                } else {
                    split.reflectance
                };
                *s += unmasked * r * sky_l[b] * g.band(b);
            }
        }
        sum.iter().map(|s| s / n as f64).collect()
    }
}
