//! The sun's beam below the surface, sampled: through a flat surface the
//! disc refracted, through a Cox–Munk surface the beam refracted by the
//! facets (the first one by its density, the rest as `interact` meets
//! them). Shared by the path integrator (next-event estimation with MIS)
//! and the photon-map march (the direct sun on floors and targets under a
//! rough surface). Not for the sun's light in the photon map: emission
//! traces it through the same facets itself.

use crate::optics::phase::scatter;
use crate::optics::surface::{fresnel_reflectance, refract};
use crate::rng::Pcg32;
use crate::scene::Scene;
use glam::{DVec3, Vec3};

/// Angular radius of the sun's disc seen from the Earth (0.2665 degrees).
pub const SUN_HALF_ANGLE_RAD: f64 = 4.6513e-3;

/// A sample of the direct sun in the water.
pub struct SunSample {
    /// Direction of travel of the sampled sunlight in the water.
    pub dir: Vec3,
    /// The sampled radiance over its pdf, divided by the sun's horizontal
    /// irradiance above the surface: E_h g is the beam-normal irradiance
    /// the sample stands for.
    pub g: f64,
    /// Light-sampling pdf of `-dir` per sr in the water (infinite under a
    /// rough surface, where it is not computed and no MIS is done).
    pub pdf: f64,
    /// How the beam crossed the surface, for each band's own Fresnel
    /// transmittance ([`Crossing::band_factor`]).
    pub crossing: Crossing,
}

/// How sunlight crossed the surface into the water, drawn at the reference
/// refractive index.
#[derive(Clone, Copy)]
pub enum Crossing {
    /// Through one facet (or the flat surface) at this incidence cosine.
    Facet(f64),
    /// Through the facets `interact` met.
    Event(crate::optics::surface::SurfaceEvent),
}

impl Crossing {
    /// A band's transmittance over the one the sample carries: 1 unless
    /// the water's index varies between bands.
    pub fn band_factor(&self, n_band: f64, n_ref: f64) -> f64 {
        if n_band == n_ref {
            return 1.0;
        }
        match self {
            Crossing::Facet(cos_i) => {
                (1.0 - fresnel_reflectance(*cos_i, 1.0, n_band))
                    / (1.0 - fresnel_reflectance(*cos_i, 1.0, n_ref))
            }
            Crossing::Event(ev) => ev.weight_for(n_band, n_ref),
        }
    }
}

/// The sun's beam of one scene.
pub struct SunBeam<'a> {
    scene: &'a Scene,
    /// Under a rough surface, the facet sampler's normalisation for the
    /// sun's direction (`SeaSurface::facing_normalisation`); None when flat.
    pub rough_norm: Option<f64>,
}

impl<'a> SunBeam<'a> {
    pub fn new(scene: &'a Scene) -> Self {
        SunBeam {
            scene,
            rough_norm: (scene.surface.slope_variance > 0.0).then(|| {
                scene
                    .surface
                    .facing_normalisation(scene.sun.direction.as_dvec3())
            }),
        }
    }

    /// A direction of the sun's disc, uniform in solid angle (travel, in air).
    fn disc_direction(&self, rng: &mut Pcg32) -> Vec3 {
        let cos_max = SUN_HALF_ANGLE_RAD.cos();
        let cos_t = 1.0 - rng.uniform_f64() * (1.0 - cos_max);
        let phi = std::f64::consts::TAU * rng.uniform_f64();
        scatter(self.scene.sun.direction, cos_t as f32, phi as f32)
    }

    /// Solid angle of the sun's disc in air (sr).
    pub fn disc_solid_angle() -> f64 {
        std::f64::consts::TAU * (1.0 - SUN_HALF_ANGLE_RAD.cos())
    }

    /// Samples of the direct sun in the water: `[0]` weighed by MIS (the
    /// sun's disc refracted by a flat surface, or the beam refracted by
    /// the first facet of a rough one), `[1]` the part of a rough
    /// surface's transmission that meets more than one facet (drawn by
    /// `interact`, no MIS). None where the sampled ray does not enter the
    /// water (see [`SunSample`]).
    pub fn sample(&self, rng: &mut Pcg32) -> [Option<SunSample>; 2] {
        let n = self.scene.surface.n_water;
        let Some(z_norm) = self.rough_norm else {
            let d_a = self.disc_direction(rng);
            let cos_s = -self.scene.sun.direction.z as f64;
            let cos_a = -d_a.z as f64;
            let single = refract(d_a.as_dvec3(), DVec3::Z, 1.0, n)
                .filter(|_| cos_a > 0.0)
                .map(|d_w| {
                    let cos_w = -d_w.z;
                    let t = 1.0 - fresnel_reflectance(cos_a, 1.0, n);
                    SunSample {
                        dir: d_w.as_vec3(),
                        g: t * cos_a / (cos_s * cos_w),
                        pdf: n * n * cos_w / (cos_a * Self::disc_solid_angle()),
                        crossing: Crossing::Facet(cos_a),
                    }
                });
            return [single, None];
        };
        let surface = &self.scene.surface;
        let i = self.scene.sun.direction.as_dvec3();
        let m = surface.sample_facet_from_above(i, rng);
        let single = refract(i, m, 1.0, n).filter(|o| o.z < 0.0).and_then(|o| {
            let (pdf, t, cos_im) = surface.beam_transmission(i, o, z_norm)?;
            // The refracted beam escapes the facets unshadowed (Smith).
            Some(SunSample {
                dir: o.as_vec3(),
                g: t * surface.masking(o) / -o.z,
                pdf,
                crossing: Crossing::Facet(cos_im),
            })
        });
        let ev = surface.interact(self.scene.sun.direction, rng);
        let multiple =
            (ev.transmitted && ev.facets > 1 && ev.direction.z < 0.0).then(|| SunSample {
                dir: ev.direction,
                g: 1.0 / -(ev.direction.z as f64),
                pdf: f64::INFINITY,
                crossing: Crossing::Event(ev),
            });
        [single, multiple]
    }
}
