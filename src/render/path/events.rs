//! What a path meets in the water, one method each: the floor or a
//! target (the sun directly, then a bounce), the sea surface from below
//! (the sky through it, the reflection back down), and a tentative
//! collision (null, or a scattering with the sun by light sampling, the
//! roulette and the next direction).

use super::*;

impl PathTracer<'_> {
    /// A path meeting the floor or a target (`h`): the sun directly, then
    /// a Lambertian bounce. Returns the next direction, or none when the
    /// path ends.
    pub(super) fn at_floor(
        &self,
        h: &crate::geometry::Hit,
        rng: &mut Pcg32,
        scratch: &mut PathScratch,
        out: &mut [f64],
    ) -> Option<Vec3> {
        let scene = self.scene;
        let n_w = scene.surface.n_water;
        let PathScratch {
            w,
            iops,
            tmp,
            tr,
            guided,
            ..
        } = scratch;
        let (pos, n) = (h.position, h.normal);
        for sun in self.sun.sample(rng).into_iter().flatten() {
            let (s_w, g) = (sun.dir, sun.g);
            let cos_n = (-s_w).dot(n) as f64;
            if cos_n > 0.0 {
                self.transmittance(pos + n * 1e-3, -s_w, rng, tmp, tr);
                for b in 0..out.len() {
                    let r = scene.reflectance(h.surface, pos, b);
                    let t = sun.crossing.band_factor(scene.water_index[b], n_w);
                    out[b] += w[b] * r / PI * cos_n * g * t * self.sun_h[b] * tr[b];
                }
            }
        }
        for (b, x) in w.iter_mut().enumerate() {
            *x *= scene.reflectance(h.surface, pos, b);
        }
        self.bounce(pos, n, w, guided, iops, rng)
    }

    /// A path meeting the sea surface from below, travelling along `dir`:
    /// the sky through it, and the light it reflects back down (per band
    /// when the water's index varies with band, `dispersive`). Returns the
    /// reflected direction, or none when the path left the water.
    pub(super) fn at_surface(
        &self,
        dir: Vec3,
        dispersive: bool,
        rng: &mut Pcg32,
        w: &mut [f64],
        out: &mut [f64],
    ) -> Option<Vec3> {
        let scene = self.scene;
        let n_w = scene.surface.n_water;
        if scene.surface.slope_variance <= 0.0 {
            let g = refract(dir.as_dvec3(), DVec3::NEG_Z, n_w, 1.0)
                .map_or(0.0, |s| scene.sky.model.relative(s.as_vec3()));
            for b in 0..out.len() {
                let n = scene.water_index[b];
                let r = fresnel_reflectance(dir.z as f64, n, 1.0);
                out[b] += w[b] * (1.0 - r) * (n * n) * g * self.sky_l[b];
                w[b] *= r;
            }
            return Some(Vec3::new(dir.x, dir.y, -dir.z));
        }
        let ev = scene.surface.interact(dir, rng);
        if dispersive {
            for (b, x) in w.iter_mut().enumerate() {
                *x *= ev.weight_for(scene.water_index[b], n_w);
            }
        }
        if ev.transmitted {
            let g = scene.sky.model.relative(ev.direction);
            for b in 0..out.len() {
                let n = scene.water_index[b];
                out[b] += w[b] * (n * n) * g * self.sky_l[b];
            }
            return None;
        }
        Some(ev.direction)
    }

    /// A tentative collision at `pos` of a path travelling along `dir`:
    /// null (the path flies on), or a scattering with the sun's in-scatter
    /// by light sampling, roulette, and the next direction drawn by the
    /// phase function (or guided toward the sun) with the disc it finds
    /// weighed by MIS; `events` counts the scattering.
    ///
    /// It stays one function: its stages share the direction density
    /// (`dir_pdf`, the mixture of the phase function and guiding) and the
    /// path's band weights, and their order is what makes it unbiased: the
    /// sun's light sampling is weighed against the direction drawn after
    /// it, and roulette falls between the vertex's own estimate and the
    /// continuation.
    pub(super) fn at_collision(
        &self,
        pos: Vec3,
        dir: Vec3,
        events: &mut u32,
        rng: &mut Pcg32,
        scratch: &mut PathScratch,
        out: &mut [f64],
    ) -> Collided {
        let scene = self.scene;
        let n_w = scene.surface.n_water;
        let mu_bar = self.mu_bar;
        let PathScratch {
            w,
            iops,
            tmp,
            tr,
            guided,
            flown,
            ..
        } = scratch;
        scene.water.iops(pos, iops);
        // Each band's null coefficient: the tracking rate less the
        // extinction collisions carry (all but the absorption `kappa`).
        let null = |iop: &Iop, kappa: f64| (mu_bar - iop.c() + kappa).max(0.0);
        let (mut s_sum, mut n_sum) = (0.0, 0.0);
        for ((x, iop), &k) in w.iter().zip(iops.iter()).zip(&self.kappa) {
            s_sum += x * iop.b();
            n_sum += x * null(iop, k);
        }
        if s_sum + n_sum <= 0.0 {
            return Collided::End;
        }
        let p_s = s_sum / (s_sum + n_sum);
        if rng.uniform_f64() >= p_s {
            let k = 1.0 / (mu_bar * (1.0 - p_s));
            for ((x, iop), &kappa) in w.iter_mut().zip(iops.iter()).zip(&self.kappa) {
                *x *= null(iop, kappa) * k;
            }
            return Collided::Null;
        }
        absorb(w, &self.kappa, flown);
        let k = 1.0 / (mu_bar * p_s);
        for (x, iop) in w.iter_mut().zip(iops.iter()) {
            *x *= iop.b() * k;
        }
        let (pw, pp) = (&scene.water_phase, &scene.particle_phase);
        let q = water_share(w, iops);
        let mix = |m: f64| self.mixture(q, m);
        // Density (per sr) of drawing `next` as the next direction: the
        // mixture around the path's direction and, guiding, around the
        // direction toward the sun.
        let dir_pdf = |next: Vec3| -> f64 {
            let around = mix(one_minus(next, dir));
            match self.guide {
                Some(axis) => {
                    (1.0 - GUIDE_FRACTION) * around + GUIDE_FRACTION * mix(one_minus(next, axis))
                }
                None => around,
            }
        };
        // The sun scattered toward the viewer: light sampling, weighed
        // (balance heuristic) against finding the disc by the direction
        // drawn below.
        for sun in self.sun.sample(rng).into_iter().flatten() {
            let s_w = sun.dir;
            self.transmittance(pos, -s_w, rng, tmp, tr);
            let mis = if sun.pdf.is_finite() {
                sun.pdf / (sun.pdf + dir_pdf(-s_w))
            } else {
                1.0
            };
            let m = one_minus(-s_w, dir);
            let (fw, fp) = (pw.eval_one_minus_cos(m), pp.eval_one_minus_cos(m));
            for b in 0..out.len() {
                let iop = iops[b];
                let bb = iop.b();
                if bb > 0.0 && tr[b] > 0.0 {
                    let t = sun.crossing.band_factor(scene.water_index[b], n_w);
                    out[b] += w[b] * (iop.b_w * fw + iop.b_p * fp) / bb
                        * sun.g
                        * t
                        * mis
                        * self.sun_h[b]
                        * tr[b];
                }
            }
        }
        // Roulette after the vertex's own estimate and before the
        // continuation: a path drawn toward the sun with a small weight
        // keeps that weight for the estimate it was drawn for.
        *events += 1;
        // A path travelling close to the sun's direction gathers its
        // forward peak at the next vertices: killing it, or restoring the
        // small weight that guiding gave it, would make those estimates a
        // rare jackpot (the heavy tail of in-water Lu under
        // Fournier–Forand).
        let importance = self
            .guide
            .map_or(1.0, |axis| 4.0 * PI * mix(one_minus(dir, axis)));
        if !Self::survive(w, *events, importance, rng) {
            return Collided::End;
        }
        let next = match self.guide {
            Some(axis) if rng.uniform_f64() < GUIDE_FRACTION => self.sample_around(axis, q, rng),
            _ => self.sample_around(dir, q, rng),
        };
        let m = one_minus(next, dir);
        let (fw, fp) = (pw.eval_one_minus_cos(m), pp.eval_one_minus_cos(m));
        let pdf = dir_pdf(next);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return Collided::End;
        }
        *guided *= mix(m) / pdf;
        for (x, iop) in w.iter_mut().zip(iops.iter()) {
            let bb = iop.b();
            *x = if bb > 0.0 {
                *x * (iop.b_w * fw + iop.b_p * fp) / (bb * pdf)
            } else {
                0.0
            };
        }
        // The sun's disc found by the drawn direction (flat surface),
        // weighed against light sampling.
        if let Some((l_over_e, light_pdf, crossing)) = self.sun_seen(next) {
            self.transmittance(pos, next, rng, tmp, tr);
            let mis = pdf / (pdf + light_pdf);
            for b in 0..out.len() {
                let t = crossing.band_factor(scene.water_index[b], n_w);
                out[b] += w[b] * l_over_e * t * mis * self.sun_h[b] * tr[b];
            }
        }
        Collided::Scattered(next)
    }
}

/// What a tentative collision in the water came to.
pub(super) enum Collided {
    /// A null collision: the path flies on.
    Null,
    /// A scattering into this direction.
    Scattered(Vec3),
    /// The path ended (roulette, or nothing left to carry).
    End,
}
