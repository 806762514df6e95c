//! What a path meets in the water, one method each: the floor or a
//! target (the sun directly, then a bounce), the sea surface from below
//! (the sky through it, the reflection back down), and a tentative
//! collision (null, or a scattering with the sun by light sampling, the
//! roulette and the next direction).

use super::*;
use crate::optics::inelastic::{Absorbers, Kind};
use crate::optics::sky::SkyAt;

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
            target,
            ..
        } = scratch;
        let target = *target;
        let (pos, n) = (h.position, h.normal);
        for sun in self.sun.sample(rng).into_iter().flatten() {
            let (s_w, g) = (sun.dir, sun.g);
            let cos_n = (-s_w).dot(n) as f64;
            if cos_n > 0.0 {
                self.transmittance(pos + n * 1e-3, -s_w, rng, tmp, tr);
                for b in 0..out.len() {
                    let r = scene.reflectance(h.surface, pos, b);
                    let t = sun.crossing.band_factor(scene.water_index[b], n_w);
                    add(
                        out,
                        target,
                        b,
                        w[b] * r / PI * cos_n * g * t * self.sun_h[b] * tr[b],
                    );
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
        target: Option<usize>,
        out: &mut [f64],
    ) -> Option<Vec3> {
        let scene = self.scene;
        let n_w = scene.surface.n_water;
        if scene.surface.slope_variance <= 0.0 {
            let g = refract(dir.as_dvec3(), DVec3::NEG_Z, n_w, 1.0)
                .map_or(SkyAt::Same(0.0), |s| scene.sky.model.at(s.as_vec3()));
            for (b, x) in w.iter_mut().enumerate() {
                let n = scene.water_index[b];
                let r = fresnel_reflectance(dir.z as f64, n, 1.0);
                add(
                    out,
                    target,
                    b,
                    *x * (1.0 - r) * (n * n) * g.band(b) * self.sky_l[b],
                );
                *x *= r;
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
            let g = scene.sky.model.at(ev.direction);
            for (b, x) in w.iter().enumerate() {
                let n = scene.water_index[b];
                add(out, target, b, x * (n * n) * g.band(b) * self.sky_l[b]);
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
            target,
            ..
        } = scratch;
        let target_now = *target;
        scene.water.iops(pos, iops);
        // Each band's null coefficient: the tracking rate less the
        // extinction collisions carry (all but the absorption `kappa`).
        let null = |iop: &Iop, kappa: f64| (mu_bar - iop.c() + kappa).max(0.0);
        let (mut s_sum, mut n_sum) = (0.0, 0.0);
        for ((x, iop), &k) in w.iter().zip(iops.iter()).zip(&self.kappa) {
            s_sum += x * iop.b();
            n_sum += x * null(iop, k);
        }
        // Inelastic light: the inelastic source of the bands the path
        // carries is a third kind of event, drawn with a probability
        // `INELASTIC_BOOST` times its share of the collision rate (at most
        // `INELASTIC_MAX_SHARE`), its rate bounded by the largest anywhere
        // (the event weighs the source where it is); the other two keep
        // their odds among the rest.
        let p_r = if self.inelastic.is_some() {
            let r_sum: f64 = w
                .iter()
                .zip(&self.inelastic_bound)
                .map(|(x, g)| x * g)
                .sum();
            if r_sum > 0.0 {
                (INELASTIC_BOOST * r_sum / (s_sum + n_sum + r_sum)).min(INELASTIC_MAX_SHARE)
            } else {
                0.0
            }
        } else {
            0.0
        };
        if p_r > 0.0 && rng.uniform_f64() < p_r {
            let k = 1.0 / (mu_bar * p_r);
            return self.inelastic_event(pos, dir, k, events, rng, w, target, tmp, tr, flown, out);
        }
        if s_sum + n_sum <= 0.0 {
            return Collided::End;
        }
        let p_s = s_sum / (s_sum + n_sum);
        let keep = 1.0 - p_r;
        if rng.uniform_f64() >= p_s {
            let k = 1.0 / (mu_bar * (1.0 - p_s) * keep);
            for ((x, iop), &kappa) in w.iter_mut().zip(iops.iter()).zip(&self.kappa) {
                *x *= null(iop, kappa) * k;
            }
            return Collided::Null;
        }
        absorb(w, &self.kappa, flown);
        let k = 1.0 / (mu_bar * p_s * keep);
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
                    let l = w[b] * (iop.b_w * fw + iop.b_p * fp) / bb
                        * sun.g
                        * t
                        * mis
                        * self.sun_h[b]
                        * tr[b];
                    add(out, target_now, b, l);
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
                add(
                    out,
                    target_now,
                    b,
                    w[b] * l_over_e * t * mis * self.sun_h[b] * tr[b],
                );
            }
        }
        Collided::Scattered(next)
    }
}

impl PathTracer<'_> {
    /// An inelastic event at `pos` of a path travelling along `dir` whose
    /// band throughputs are `w`, `k` = 1 / (rate x the event's
    /// probability): one process is drawn in proportion to its source for
    /// this path here, the throughputs become those of the excitation
    /// bands that feed the bands the path carries, the sun is estimated
    /// through the process's phase function by light sampling alone (the
    /// continuation's own direction never counts the sun, so no MIS weight
    /// is needed), and the path goes on in a direction drawn from that
    /// phase function.
    ///
    /// A path that has met no inelastic event carries every sensor band;
    /// its first one draws the band it will feed from then on (`target`:
    /// half the draws in proportion to each band's throughput times its
    /// gain, half uniform over the bands fed) and divides by that choice's
    /// probability, since the excitation throughputs of different sensor
    /// bands cannot share one vector. Later events feed the same band.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn inelastic_event(
        &self,
        pos: Vec3,
        dir: Vec3,
        k: f64,
        events: &mut u32,
        rng: &mut Pcg32,
        w: &mut [f64],
        target: &mut Option<usize>,
        tmp: &mut [Iop],
        tr: &mut [f64],
        flown: &mut f64,
        out: &mut [f64],
    ) -> Collided {
        let Some(inelastic) = self.inelastic else {
            return Collided::End;
        };
        let scene = self.scene;
        let n_w = scene.surface.n_water;
        absorb(w, &self.kappa, flown);
        let nb = w.len();
        let mut parts = vec![Absorbers::default(); nb];
        if inelastic.fluoresces() {
            scene.water.absorbers(pos, &mut parts);
        }
        // Each process's gain here per band (Raman's is the same
        // everywhere), and its source for this path.
        let gains: Vec<Vec<f64>> = inelastic
            .processes
            .iter()
            .map(|p| match p.kind {
                Kind::Raman => p.gain_bound.clone(),
                _ => p
                    .rows
                    .iter()
                    .map(|row| row.iter().map(|&(e, c)| c * p.strength(&parts[e])).sum())
                    .collect(),
            })
            .collect();
        let rates: Vec<f64> = gains
            .iter()
            .map(|g| w.iter().zip(g).map(|(x, g)| x * g).sum())
            .collect();
        let all: f64 = rates.iter().sum();
        if !(all > 0.0 && all.is_finite()) {
            return Collided::End;
        }
        let chosen = if rates.len() == 1 {
            0
        } else {
            let mut u = rng.uniform_f64() * all;
            rates
                .iter()
                .position(|&r| {
                    u -= r;
                    u < 0.0
                })
                .unwrap_or_else(|| rates.iter().rposition(|&r| r > 0.0).unwrap_or(0))
        };
        let (process, gain) = (&inelastic.processes[chosen], &gains[chosen]);
        // (One process: drawn with certainty.)
        let k = if rates.len() == 1 {
            k
        } else {
            k * all / rates[chosen]
        };
        let coefficient = |e: usize| process.scale[e] * process.strength(&parts[e]);
        let mut excitation = vec![0.0; nb];
        match *target {
            None => {
                let total = rates[chosen];
                // The sensor band: half the draws in proportion to w_m
                // gain_m, half uniform over the bands fed (a defensive
                // mixture: a band whose share is small but whose own light
                // is faint, the near infrared, would otherwise rest on
                // rare draws of large weight).
                let fed = w.iter().zip(gain).filter(|&(x, g)| x * g > 0.0).count();
                if fed == 0 {
                    return Collided::End;
                }
                let uniform = rng.uniform_f64() < INELASTIC_UNIFORM_TARGET;
                let mut u = rng.uniform_f64() * if uniform { fed as f64 } else { total };
                let mut m = None;
                for (b, (x, g)) in w.iter().zip(gain).enumerate() {
                    let p = x * g;
                    if p > 0.0 {
                        m = Some(b);
                        let step = if uniform { 1.0 } else { p };
                        if u < step {
                            break;
                        }
                        u -= step;
                    }
                }
                let Some(m) = m else {
                    return Collided::End;
                };
                let q = (1.0 - INELASTIC_UNIFORM_TARGET) * w[m] * gain[m] / total
                    + INELASTIC_UNIFORM_TARGET / fed as f64;
                // w_m c(e) T(e, m) k / q_m.
                let scale = k * w[m] / q;
                for (e, x) in excitation.iter_mut().enumerate() {
                    *x = coefficient(e) * process.transfer(e, m) * scale;
                }
                *target = Some(m);
            }
            Some(_) => {
                for (e, x) in excitation.iter_mut().enumerate() {
                    let c = coefficient(e);
                    if c > 0.0 {
                        let fed: f64 = w
                            .iter()
                            .enumerate()
                            .map(|(b, wb)| wb * process.transfer(e, b))
                            .sum();
                        *x = c * fed * k;
                    }
                }
            }
        }
        w.copy_from_slice(&excitation);
        let target = *target;
        let phase = &process.phase;
        for sun in self.sun.sample(rng).into_iter().flatten() {
            let s_w = sun.dir;
            self.transmittance(pos, -s_w, rng, tmp, tr);
            let p = phase.eval_one_minus_cos(one_minus(-s_w, dir));
            for b in 0..nb {
                if w[b] > 0.0 && tr[b] > 0.0 {
                    let t = sun.crossing.band_factor(scene.water_index[b], n_w);
                    add(out, target, b, w[b] * p * sun.g * t * self.sun_h[b] * tr[b]);
                }
            }
        }
        *events += 1;
        if !Self::survive(w, *events, 1.0, rng) {
            return Collided::End;
        }
        let u = [rng.uniform_f64(), rng.uniform_f64()];
        Collided::Scattered(phase.sample_direction(dir, u))
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
