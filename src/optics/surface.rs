//! The sea surface: Fresnel reflection and refraction on a flat or
//! Cox–Munk wind-roughened interface.
//!
//! Units and conventions: directions are unit vectors of travel, z up, the
//! mean surface is z = 0 with air above (n = 1) and water below
//! (n = `n_water`, about 1.34).
//!
//! Rough surface (Cox & Munk 1954, isotropic): facet slopes (zx, zy) are
//! independent normals of variance sigma^2 / 2 each, sigma^2 = 0.003 +
//! 0.00512 U (U in m/s), so the total slope variance is sigma^2. A ray meets
//! facets in proportion to their projected area along the ray, so a slope
//! drawn from the distribution is accepted with probability proportional to
//! max(0, -d . n) / n_z (rejection sampling; slopes are truncated at 6
//! standard deviations, a probability below 1e-8).
//!
//! Shadowing (Smith 1967, "Geometrical shadowing of a random rough
//! surface", IEEE Trans. Antennas Propag. 15: 668): a ray leaving a facet
//! escapes the surface with probability G1 = 1 / (1 + Lambda(mu)), Lambda =
//! [exp(-nu^2) / (sqrt(pi) nu) - erfc(nu)] / 2 with nu = mu / (sigma
//! sqrt(1 - mu^2)) and mu its cosine to the vertical ([`smith_lambda`]);
//! otherwise it meets another facet, drawn as the first was (by projected
//! area along its new direction, from the side it is on): multiple
//! scattering at the surface, up to 16 facets, after which the mean flat
//! surface is used. A ray leaving into the wrong half-space (a reflection
//! pointing back into the surface, a refraction pointing back out) always
//! meets another facet. Smith's function is exactly the one for which the
//! projected-area normalisation of the facet sampler is cos(theta) (1 +
//! Lambda) (tested), so a beam's single-facet reflection is the Cox–Munk
//! glint times G1(sun) G1(view), what `render::air_sea::add_glint` adds.
//!
//! Refractive index per band: a `SeaSurface` has one index. Emission
//! gives each photon its band's surface (`Scene::surface_in`); the
//! renderers draw one set of facets and directions at the scene's reference
//! index and reweight each band's Fresnel choices to its own index
//! ([`SurfaceEvent::weight_for`]), neglecting only the dispersion of the
//! refracted direction (under 0.3 degrees across 400-700 nm).
//!
//! Not for: radiance transfer factors (the renderer applies n^2 itself).

use crate::rng::Pcg32;
use glam::{DVec3, Vec3};

/// Unpolarised Fresnel reflectance for light going from index `n1` into
/// `n2` at incidence cosine `cos_i` (> 0). Returns 1 for total internal
/// reflection.
pub fn fresnel_reflectance(cos_i: f64, n1: f64, n2: f64) -> f64 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let eta = n1 / n2;
    let sin_t2 = eta * eta * (1.0 - cos_i * cos_i);
    if sin_t2 >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t2).sqrt();
    let rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    let rp = (n1 * cos_t - n2 * cos_i) / (n1 * cos_t + n2 * cos_i);
    0.5 * (rs * rs + rp * rp)
}

/// Mirror `d` about the plane with unit normal `n`.
pub fn reflect(d: DVec3, n: DVec3) -> DVec3 {
    d - 2.0 * d.dot(n) * n
}

/// Refract `d` through a facet with unit normal `n` (facing against `d`),
/// from index `n1` to `n2`; `None` on total internal reflection.
pub fn refract(d: DVec3, n: DVec3, n1: f64, n2: f64) -> Option<DVec3> {
    let eta = n1 / n2;
    let cos_i = -d.dot(n);
    let sin_t2 = eta * eta * (1.0 - cos_i * cos_i);
    if sin_t2 > 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin_t2).sqrt();
    Some((eta * d + (eta * cos_i - cos_t) * n).normalize())
}

/// The sea surface model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeaSurface {
    /// Refractive index of the water.
    pub n_water: f64,
    /// Total slope variance sigma^2 (0 for a flat surface).
    pub slope_variance: f64,
}

/// What happened to a ray at the surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceEvent {
    /// New direction of travel.
    pub direction: Vec3,
    /// True if the ray crossed into the other medium.
    pub transmitted: bool,
    /// Facets met (1 unless the ray left a facet back into the surface).
    pub facets: u32,
    /// The Fresnel choices made on the way, for reweighting to another
    /// refractive index ([`SurfaceEvent::weight_for`]).
    pub trail: FresnelTrail,
}

/// The Fresnel choices of one [`SeaSurface::interact`]: per facet, the
/// incidence cosine, the side the ray came from and whether it reflected.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FresnelTrail {
    len: u8,
    cos_i: [f32; MAX_SURFACE_BOUNCES],
    /// Bit 0: came from the air; bit 1: reflected.
    flags: [u8; MAX_SURFACE_BOUNCES],
}

impl FresnelTrail {
    const EMPTY: FresnelTrail = FresnelTrail {
        len: 0,
        cos_i: [0.0; MAX_SURFACE_BOUNCES],
        flags: [0; MAX_SURFACE_BOUNCES],
    };

    fn push(&mut self, cos_i: f64, from_above: bool, reflected: bool) {
        let k = self.len as usize;
        if k < MAX_SURFACE_BOUNCES {
            self.cos_i[k] = cos_i as f32;
            self.flags[k] = from_above as u8 | (reflected as u8) << 1;
            self.len += 1;
        }
    }
}

impl SurfaceEvent {
    /// The probability of this event's Fresnel choices with water of index
    /// `n_band` over their probability with the index `n_ref` they were
    /// drawn with: the weight that makes the event, drawn once, an
    /// unbiased sample for a band of another index (the facets and
    /// directions stay those drawn at `n_ref`). 1 when the two are equal.
    pub fn weight_for(&self, n_band: f64, n_ref: f64) -> f64 {
        if n_band == n_ref {
            return 1.0;
        }
        let mut w = 1.0;
        for k in 0..self.trail.len as usize {
            let cos_i = self.trail.cos_i[k] as f64;
            let from_above = self.trail.flags[k] & 1 != 0;
            let reflected = self.trail.flags[k] & 2 != 0;
            let r = |n: f64| {
                if from_above {
                    fresnel_reflectance(cos_i, 1.0, n)
                } else {
                    fresnel_reflectance(cos_i, n, 1.0)
                }
            };
            let (rb, rr) = (r(n_band), r(n_ref));
            w *= if reflected {
                rb / rr
            } else {
                (1.0 - rb) / (1.0 - rr)
            };
        }
        w
    }
}

const MAX_SURFACE_BOUNCES: usize = 16;

impl SeaSurface {
    /// A flat surface.
    pub fn flat(n_water: f64) -> Self {
        SeaSurface {
            n_water,
            slope_variance: 0.0,
        }
    }

    /// A Cox–Munk surface for wind speed `u` (m/s).
    pub fn cox_munk(n_water: f64, u: f64) -> Self {
        SeaSurface {
            n_water,
            slope_variance: 0.003 + 0.00512 * u,
        }
    }

    /// A ray travelling along `d` meets the surface from above (`d.z < 0`)
    /// or below (`d.z > 0`): reflect or refract it, choosing by Fresnel.
    pub fn interact(&self, d: Vec3, rng: &mut Pcg32) -> SurfaceEvent {
        self.interact_from(d, d.z < 0.0, rng)
    }

    /// [`Self::interact`] for a ray on a given side: in the air
    /// (`from_above`) or in the water, whichever way it travels (a ray that
    /// left a facet and was shadowed by another may travel away from the
    /// mean surface). `transmitted` says whether it ends on the other side.
    pub fn interact_from(&self, d: Vec3, from_above: bool, rng: &mut Pcg32) -> SurfaceEvent {
        let mut d = d.as_dvec3();
        // Which side the ray is on now; it flips when it is transmitted.
        let mut from_above = from_above;
        let start_above = from_above;
        let mut trail = FresnelTrail::EMPTY;
        for bounce in 0..MAX_SURFACE_BOUNCES {
            let Some(n_up) = self.sample_facet_from(d, from_above, rng) else {
                // No facet faces a shadowed ray this steep: it leaves as it is.
                return SurfaceEvent {
                    direction: d.as_vec3(),
                    transmitted: from_above != start_above,
                    facets: bounce as u32,
                    trail,
                };
            };
            let (n1, n2) = if from_above {
                (1.0, self.n_water)
            } else {
                (self.n_water, 1.0)
            };
            // Facet normal facing the incoming ray.
            let n = if from_above { n_up } else { -n_up };
            let cos_i = -d.dot(n);
            let r = fresnel_reflectance(cos_i, n1, n2);
            let (next, crossed) = if rng.uniform_f64() < r {
                (reflect(d, n), false)
            } else {
                match refract(d, n, n1, n2) {
                    Some(t) => (t, true),
                    None => (reflect(d, n), false),
                }
            };
            trail.push(cos_i, from_above, !crossed);
            if crossed {
                from_above = !from_above;
            }
            d = next;
            // Leaving into the right half-space, unshadowed, ends the
            // interaction.
            let leaving = if from_above { d.z > 0.0 } else { d.z < 0.0 };
            if leaving && (self.slope_variance <= 0.0 || rng.uniform_f64() < self.masking(d)) {
                return SurfaceEvent {
                    direction: d.as_vec3(),
                    transmitted: from_above != start_above,
                    facets: bounce as u32 + 1,
                    trail,
                };
            }
        }
        // Give up on the rough surface: the mean plane reflects a ray
        // heading into it, and lets one heading away go.
        let n = if from_above { DVec3::Z } else { -DVec3::Z };
        let d = if d.dot(n) < 0.0 { reflect(d, n) } else { d };
        SurfaceEvent {
            direction: d.normalize().as_vec3(),
            transmitted: from_above != start_above,
            facets: MAX_SURFACE_BOUNCES as u32 + 1,
            trail,
        }
    }

    /// A ray from the air along `d` (`d.z < 0`) meets one facet, sampled
    /// like `interact` does, and is split instead of choosing a branch: the
    /// Fresnel reflectance with the reflected direction, and the refracted
    /// direction. Either may head back into the surface (steep facets);
    /// `interact` continues such rays.
    pub fn split_from_above(&self, d: Vec3, rng: &mut Pcg32) -> SurfaceSplit {
        let d = d.as_dvec3();
        let n = self.sample_facet(d, rng);
        let cos_i = -d.dot(n);
        SurfaceSplit {
            cos_i,
            reflectance: fresnel_reflectance(cos_i, 1.0, self.n_water),
            reflected: reflect(d, n).normalize().as_vec3(),
            refracted: refract(d, n, 1.0, self.n_water)
                .unwrap_or_else(|| reflect(d, n))
                .normalize()
                .as_vec3(),
        }
    }

    /// Slope density of the facets, p(zx, zy) = exp(-(zx^2 + zy^2) /
    /// sigma^2) / (pi sigma^2), truncated (0) beyond 6 standard deviations
    /// on either axis as the sampler truncates it (rough surfaces only).
    pub fn slope_density(&self, zx: f64, zy: f64) -> f64 {
        let s2 = self.slope_variance;
        let s_max = 6.0 * (0.5 * s2).sqrt();
        if zx.abs() > s_max || zy.abs() > s_max {
            return 0.0;
        }
        (-(zx * zx + zy * zy) / s2).exp() / (std::f64::consts::PI * s2)
    }

    /// The normalisation of the facet sampler for a ray from the air along
    /// `d` (`d.z < 0`): the mean over truncated slopes of max(0, -d . m~),
    /// m~ = (-zx, -zy, 1), by the midpoint rule (400 x 400 cells; exactly
    /// -d.z when no facet within the truncation faces away from the ray).
    pub fn facing_normalisation(&self, d: DVec3) -> f64 {
        let s2 = self.slope_variance;
        let s_max = 6.0 * (0.5 * s2).sqrt();
        if d.z.abs() >= (d.x.abs() + d.y.abs()) * s_max {
            return -d.z;
        }
        const CELLS: usize = 400;
        let h = 2.0 * s_max / CELLS as f64;
        // The quadrature's weights are the density times pi s2.
        facet_quadrature(s2, d, CELLS, |_, _| {}) * h * h / (std::f64::consts::PI * s2)
    }

    /// The single-facet transmission of a collimated beam from the air
    /// along `i` (`i.z < 0`) into the water direction `o` (`o.z < 0`):
    /// `(density, t)` with `density` the pdf per sr of `o` when a facet is
    /// drawn as `interact` draws its first one and the beam is refracted
    /// there (Fresnel ignored), and `t` that facet's Fresnel transmittance.
    /// The facet is m = (i - n o) / |i - n o| (Walter et al. 2007); the
    /// density is p(zx, zy) (-i . m) n^2 |o . m| / (Z cos^4 theta_m
    /// |i - n o|^2), Z = [`Self::facing_normalisation`]. None when no facet
    /// refracts `i` into `o`.
    pub fn beam_transmission_density(&self, i: DVec3, o: DVec3, z_norm: f64) -> Option<(f64, f64)> {
        self.beam_transmission(i, o, z_norm).map(|b| (b.0, b.1))
    }

    /// [`Self::beam_transmission_density`] and the facet's incidence
    /// cosine (-i . m), for its transmittance at another index.
    pub fn beam_transmission(&self, i: DVec3, o: DVec3, z_norm: f64) -> Option<(f64, f64, f64)> {
        let n = self.n_water;
        let h = i - n * o;
        let len = h.length();
        if len <= 0.0 {
            return None;
        }
        let m = h / len;
        let cos_im = -i.dot(m);
        let cos_om = o.dot(m);
        if m.z <= 0.0 || cos_im <= 0.0 || cos_om >= 0.0 {
            return None;
        }
        let (zx, zy) = (-m.x / m.z, -m.y / m.z);
        let p = self.slope_density(zx, zy);
        if p <= 0.0 {
            return None;
        }
        let density = p * cos_im * n * n * (-cos_om) / (z_norm * m.z.powi(4) * len * len);
        Some((density, 1.0 - fresnel_reflectance(cos_im, 1.0, n), cos_im))
    }

    /// A facet normal (up) drawn for a ray from the air along `d` exactly
    /// as the first facet of `interact` is drawn (flat: +z).
    pub fn sample_facet_from_above(&self, d: DVec3, rng: &mut Pcg32) -> DVec3 {
        self.sample_facet(d, rng)
    }

    /// The probability that a ray leaving the surface along `d` is not
    /// shadowed by another facet: Smith's G1 = 1 / (1 + Lambda) (1 on a
    /// flat surface; 0 for a ray along the mean surface).
    pub fn masking(&self, d: DVec3) -> f64 {
        if self.slope_variance <= 0.0 {
            return 1.0;
        }
        // Most rays leave steeply, past nu = SMITH_NU_NEGLIGIBLE where G1
        // is exactly 1: nu > N <=> mu > N sigma sin <=> z^2 (1 + N^2
        // sigma^2) > N^2 sigma^2 |d|^2, with no square root or division.
        // At the boundary both sides give 1.0 (see `smith_lambda`).
        let n2s2 = SMITH_NU_NEGLIGIBLE * SMITH_NU_NEGLIGIBLE * self.slope_variance;
        if d.z * d.z * (1.0 + n2s2) > n2s2 * d.length_squared() {
            return 1.0;
        }
        1.0 / (1.0 + smith_lambda(d.z.abs() / d.length(), self.slope_variance))
    }

    /// Upward facet normal met by a ray along `d` from the side `d.z` says
    /// (flat: +z).
    fn sample_facet(&self, d: DVec3, rng: &mut Pcg32) -> DVec3 {
        self.sample_facet_from(d, d.z < 0.0, rng)
            .unwrap_or(DVec3::Z)
    }

    /// Upward facet normal met by a ray along `d` from the air
    /// (`from_above`) or the water, by projected area along the ray (flat:
    /// +z). None when no facet within the truncation faces the ray, or
    /// after 2^20 rejected draws (a shadowed ray so steep that almost none
    /// does).
    fn sample_facet_from(&self, d: DVec3, from_above: bool, rng: &mut Pcg32) -> Option<DVec3> {
        if self.slope_variance <= 0.0 {
            return Some(DVec3::Z);
        }
        let s = (0.5 * self.slope_variance).sqrt();
        let s_max = 6.0 * s;
        // Bound of +-d . (-zx, -zy, 1) over slopes within 6 sigma (per axis).
        let tilt = (d.x.abs() + d.y.abs()) * s_max;
        let bound = d.z.abs() + tilt;
        let toward = if from_above { -d.z } else { d.z };
        if toward <= 0.0 && tilt <= -toward {
            return None;
        }
        for _ in 0..1 << 20 {
            let (zx, zy) = (rng.normal() * s, rng.normal() * s);
            if zx.abs() > s_max || zy.abs() > s_max {
                continue;
            }
            let m = DVec3::new(-zx, -zy, 1.0);
            // Projected area along the ray relative to the facet's horizontal area.
            let facing = if from_above { -d.dot(m) } else { d.dot(m) };
            if facing > 0.0 && rng.uniform_f64() * bound < facing {
                return Some(m.normalize());
            }
        }
        None
    }
}

/// One facet's split of a ray from the air (see `SeaSurface::split_from_above`).
#[derive(Clone, Copy, Debug)]
pub struct SurfaceSplit {
    /// Incidence cosine on the facet (for the reflectance at another index).
    pub cos_i: f64,
    /// Fresnel reflectance of the facet.
    pub reflectance: f64,
    /// Reflected direction (in the air unless it heads down).
    pub reflected: Vec3,
    /// Refracted direction (in the water unless it heads up).
    pub refracted: Vec3,
}

/// Smith's (1967) shadowing function Lambda for a direction of cosine
/// `mu` (to the vertical, 0..=1) over isotropic Gaussian slopes of total
/// variance `slope_variance`: [exp(-nu^2) / (sqrt(pi) nu) - erfc(nu)] / 2,
/// nu = mu / (sigma sqrt(1 - mu^2)). 0 looking straight up or down,
/// growing without bound toward the horizon.
///
/// Above nu = [`SMITH_NU_NEGLIGIBLE`] it is 0: there Lambda is below the
/// first term, exp(-nu^2) / (2 sqrt(pi) nu) < 2e-18, less than half an ulp
/// of 1, so G1 = 1 / (1 + Lambda) is exactly 1 either way and the
/// exponential and erfc (most rays leaving the surface steeply) are saved.
pub fn smith_lambda(mu: f64, slope_variance: f64) -> f64 {
    let mu = mu.clamp(0.0, 1.0);
    let sin = (1.0 - mu * mu).sqrt();
    if sin <= 0.0 {
        return 0.0;
    }
    let nu = mu / (slope_variance.sqrt() * sin);
    if nu <= 0.0 {
        return f64::INFINITY;
    }
    if nu > SMITH_NU_NEGLIGIBLE {
        return 0.0;
    }
    smith_lambda_nu(nu)
}

/// Above this nu, Smith's Lambda is negligible against 1 (see [`smith_lambda`]).
pub const SMITH_NU_NEGLIGIBLE: f64 = 6.0;

/// Smith's Lambda at nu > 0, as printed.
fn smith_lambda_nu(nu: f64) -> f64 {
    if nu > 26.0 {
        return 0.0; // exp(-nu^2) underflows
    }
    0.5 * ((-nu * nu).exp() / (std::f64::consts::PI.sqrt() * nu) - libm::erfc(nu)).max(0.0)
}

/// A quadrature over the Cox–Munk facets a ray along `d` meets (from the
/// air when `d.z < 0`): the slopes (zx, zy) on a `cells` x `cells`
/// midpoint grid over six standard deviations, each facet weighted by the
/// slope density times its projected area along the ray, |d . (-zx, -zy,
/// 1)|, over the facets that face the ray. Calls `f` with the facet's unit
/// normal on the ray's side and its weight; returns the sum of the
/// weights, which normalises them. Written from the physics, not from the
/// sampler (`SeaSurface::interact`), so it is an independent reference
/// for it.
pub fn facet_quadrature(
    slope_variance: f64,
    d: DVec3,
    cells: usize,
    mut f: impl FnMut(DVec3, f64),
) -> f64 {
    let from_above = d.z < 0.0;
    let s_max = 6.0 * (0.5 * slope_variance).sqrt();
    let h = 2.0 * s_max / cells as f64;
    let mut norm = 0.0;
    for i in 0..cells {
        let zx = -s_max + (i as f64 + 0.5) * h;
        for j in 0..cells {
            let zy = -s_max + (j as f64 + 0.5) * h;
            let m_up = DVec3::new(-zx, -zy, 1.0);
            let facing = if from_above {
                -d.dot(m_up)
            } else {
                d.dot(m_up)
            };
            if facing <= 0.0 {
                continue;
            }
            let w = (-(zx * zx + zy * zy) / slope_variance).exp() * facing;
            norm += w;
            f(if from_above { m_up } else { -m_up }.normalize(), w);
        }
    }
    norm
}

#[cfg(test)]
mod tests;
