//! Where a marched ray ends on a boundary: the floor or a target (the
//! direct sun on the face and the face's photon estimate), or the sea
//! surface seen from below (the sky through it, the light it reflects
//! back down marched on).

use super::*;
use crate::optics::sky::SkyAt;

impl RayMarcher<'_> {
    /// A marched ray meeting the floor or a target (`h`) with transmittance
    /// `tr`: the direct sun on the face (through a rough surface's facets
    /// or the flat one) and the face's photon estimate (gathered from the
    /// volume map on targets, when `gather`), reflected toward the viewer.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn at_floor(
        &self,
        h: &crate::geometry::Hit,
        rng: &mut Pcg32,
        scratch: &mut Scratch,
        buf: &mut MarchBuffers,
        out: &mut [f64],
        tr: &[f64],
        gather: bool,
    ) -> Result<()> {
        let nb = self.bands();
        let scene = self.scene;
        let MarchBuffers {
            est,
            sun_t,
            beam,
            iops,
            tmp,
            ..
        } = buf;
        // Floor or target: direct sun plus the surface photon estimate.
        let n = h.normal;
        let x = h.position + n * 1e-3;
        scene.water.iops(x, iops);
        // The direct sun's irradiance on the face per band, into sun_t.
        if self.sun.rough_norm.is_some() {
            self.rough_direct(x, n, iops, tmp, beam, rng, sun_t);
        } else {
            let cos_n = (-self.sun_w).dot(n).max(0.0) as f64;
            self.sun_transmittance(x, iops, tmp, sun_t);
            for (e, w) in sun_t.iter_mut().zip(&self.e_w) {
                *e = *w * *e * cos_n;
            }
        }
        let rays = scene.estimate.gather_rays;
        if gather && rays > 0 && h.surface != FLOOR {
            self.gather(h.position, n, h.surface, rays, rng, scratch, est)?;
        } else {
            self.est.surface(h.position, n, h.surface, scratch, est)?;
        }
        for b in 0..nb {
            let r = scene.reflectance(h.surface, h.position, b);
            let direct = sun_t[b] * r / std::f64::consts::PI;
            out[b] += tr[b] * (direct + est[b]);
            for k in (nb + b..out.len()).step_by(nb) {
                out[k] += tr[b] * est[k];
            }
        }
        Ok(())
    }

    /// A ray looking up meets the surface at `at`: the sky it sees through
    /// the surface (n^2 brighter) into `out`, and the light from below
    /// that the surface reflects down along the ray (`Turned`: the march
    /// goes on down with `tr` times the reflectance). A flat surface
    /// splits the ray by Fresnel (the reflected part by Russian roulette,
    /// so that a ray looking up is seldom marched twice); a rough one draws the facets' event as
    /// the path integrator does (`SeaSurface::interact`: transmitted to
    /// the sky or reflected down, each band reweighted to its own index),
    /// so both read the same light through the facets, and past the
    /// critical angle a radiometer sees the water below.
    pub(super) fn under_surface(
        &self,
        at: Vec3,
        dir: Vec3,
        rng: &mut Pcg32,
        out: &mut [f64],
        tr: &mut [f64],
    ) -> Segment {
        let scene = self.scene;
        let n_ref = scene.surface.n_water;
        let to = if scene.surface.slope_variance <= 0.0 {
            let g = refract(dir.as_dvec3(), glam::DVec3::NEG_Z, n_ref, 1.0)
                .map_or(SkyAt::Same(0.0), |s| scene.sky.model.at(s.as_vec3()));
            // The reflected part goes on with probability q, its largest
            // reflectance (every ray past the critical angle, 2 % of those
            // looking straight up), each band weighted by r / q.
            let mut q = 0.0f64;
            for (b, t) in tr.iter_mut().enumerate() {
                let n = scene.water_index[b];
                let r = fresnel_reflectance(dir.z as f64, n, 1.0);
                out[b] += *t * (1.0 - r) * n * n * g.band(b) * self.sky_l[b];
                *t *= r;
                q = q.max(r);
            }
            if q <= 0.0 || rng.uniform_f64() >= q {
                return Segment::Ended;
            }
            tr.iter_mut().for_each(|t| *t /= q);
            Vec3::new(dir.x, dir.y, -dir.z)
        } else {
            let ev = scene.surface.interact(dir, rng);
            let dispersive = scene.dispersive();
            let weight = |b: usize| {
                if dispersive {
                    ev.weight_for(scene.water_index[b], n_ref)
                } else {
                    1.0
                }
            };
            if ev.transmitted {
                let g = scene.sky.model.at(ev.direction);
                for (b, t) in tr.iter().enumerate() {
                    let n = scene.water_index[b];
                    out[b] += t * weight(b) * n * n * g.band(b) * self.sky_l[b];
                }
                return Segment::Ended;
            }
            for (b, t) in tr.iter_mut().enumerate() {
                *t *= weight(b);
            }
            ev.direction
        };
        if to.z >= 0.0 || tr.iter().all(|&t| t <= MIN_TRANSMITTANCE) {
            return Segment::Ended;
        }
        Segment::Turned {
            at,
            to,
            weight: 1.0,
        }
    }
}
