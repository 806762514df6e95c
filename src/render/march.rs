//! Light transport along sensor rays: the sea surface, ray marching in the
//! water with next-event single scattering of the refracted sun and the
//! photon-map in-scatter estimate, and the floor and targets.
//!
//! Photon estimates use phase functions whose forward peak is a delta, so
//! the march attenuates with c - f b (`estimate::peak`); next-event single
//! scattering of the sun uses the exact phase function and the full
//! extinction toward the sun.
//!
//! Choices: the sun is refracted through the mean (flat) surface for next
//! event estimation, also under a rough surface; the transmittance toward
//! the sun is exact in uniform and layered water (cut at every layer
//! boundary: four midpoint samples read a 2 m layer seen from 6 m below
//! as 3 m) and in a gradient of constituents (`WaterModel::
//! gradient_optical_depth`), and by the midpoint rule at most 0.5 m apart
//! in gridded water; steps lengthen as the light along the ray fades
//! (`steps::stretch`: 1 / sqrt(T) times the scene's step, at most 4
//! times), run on across turns (`steps::Step`), and their estimates'
//! searches shrink with it (`steps::search_share`); the surface seen from
//! the air is `air_sea::from_air`, shared with the path integrator; camera rays are not wrapped at periodic edges; a
//! ray looking up at the surface sees the sky through it and, marching on
//! down, the light from below that it reflects (a rough surface's event
//! drawn as the path integrator draws it); a target's face
//! is read by final gathering (`RayMarcher::gather`), the floor by its
//! surface photon estimate.

use super::air_sea::sky_radiance;
use super::sun::SunBeam;
use crate::error::Result;
use crate::estimate::estimator::{Estimator, Scratch};
use crate::estimate::groups::CHANNELS;
use crate::optics::iop::Iop;
use crate::optics::phase::Mixture;
use crate::optics::surface::{fresnel_reflectance, refract};
use crate::rng::Pcg32;
use crate::scene::settings::TARGET_PEAK_MARGIN_M;
use crate::scene::{Scene, FLOOR};
use glam::{DVec3, Vec3};
use steps::{
    search_share, stretch, PeakTurns, Step, SEARCH_SHARE_MIN, STEP_REST_EPS_M, STEP_STRETCH_MAX,
};

mod boundaries;
mod steps;
#[cfg(test)]
mod tests;

/// Longest march through water without a hit (m).
const MAX_MARCH_M: f32 = 500.0;
/// Longest step of the midpoint rule for the sun's transmittance through
/// gridded water (m).
const SUN_STEP_M: f32 = 0.5;
/// Share of turns into the forward peak drawn around the refracted sun
/// where the sun is near the peak's cone (see `RayMarcher::turn`).
const TURN_SUN_GUIDE: f64 = 0.3;
/// How far outside the peak's cone the sun may lie for turns to be drawn
/// around it too (3 degrees).
const TURN_SUN_MARGIN_RAD: f64 = 0.052;
/// Share of final-gather directions drawn around the refracted sun.
const GATHER_GUIDE: f64 = 0.3;
/// Stop marching when every band's transmittance is below this.
const MIN_TRANSMITTANCE: f64 = 1e-4;

/// Per-march buffers, one entry per band (`est` one per channel).
struct MarchBuffers {
    est: Vec<f64>,
    sun_t: Vec<f64>,
    /// The direct sun's inelastic source per band at the step's sample.
    inelastic_sun: Vec<f64>,
    beam: Vec<f64>,
    iops: Vec<Iop>,
    tmp: Vec<Iop>,
    /// Turns into the particles' forward peak drawn for every band at once
    /// (rays looking down at a target): see [`PeakTurns`].
    turns: Option<PeakTurns>,
    /// How the march goes: its step, stretch and turns.
    course: Course,
    /// The step under way, which runs on across turns ([`Step`]).
    step: Step,
}

/// How a march goes: its step (m) where every band's light is whole,
/// the most that step stretches as the light fades ([`stretch`]), the
/// least share of the scene's searches its estimates take as the light
/// fades ([`search_share`]; 1: whole searches), whether its steps run on
/// across turns ([`Step`]; always but under a hero band's turns), and
/// whether it gathers at a target it meets (see [`RayMarcher::gather`];
/// gather rays do not gather again).
#[derive(Clone, Copy, Debug)]
struct Course {
    step_m: f32,
    stretch_max: f32,
    share_min: f64,
    spans_turns: bool,
    gather: bool,
}

impl Course {
    /// Steps of `step_m` where the light is whole, stretched up to
    /// [`STEP_STRETCH_MAX`] times and run on across turns, with searches
    /// down to [`SEARCH_SHARE_MIN`] of the scene's.
    fn paced(step_m: f32, gather: bool) -> Self {
        Course {
            step_m,
            stretch_max: STEP_STRETCH_MAX,
            share_min: SEARCH_SHARE_MIN,
            spans_turns: true,
            gather,
        }
    }
}

/// How a straight run of a march ended.
enum Segment {
    /// Scattered into the forward peak at `at`, on along `to`, every band
    /// weighted by `weight`.
    Turned { at: Vec3, to: Vec3, weight: f64 },
    /// At the floor, a target, the surface or the end of the march.
    Ended,
}

/// The photon-map integrator along one ray: precomputed light sources, the
/// estimator, and the march through surface, water, floor and targets.
pub struct RayMarcher<'a> {
    pub scene: &'a Scene,
    pub est: Estimator<'a>,
    /// Refracted sun direction in the water (travel, pointing down).
    pub sun_w: Vec3,
    /// Beam-normal irradiance of the refracted sun just below the surface, per band.
    pub e_w: Vec<f64>,
    /// Sky radiance per band (isotropic).
    pub sky_l: Vec<f64>,
    /// The sun's beam below a rough surface, sampled for the direct sun
    /// on floors and targets (a flat surface refracts it exactly, `sun_w`).
    sun: SunBeam<'a>,
    /// Horizontal irradiance of the sun above the surface per band.
    sun_h: Vec<f64>,
    /// Whether the sun shines in any band.
    has_sun: bool,
}

impl<'a> RayMarcher<'a> {
    pub fn new(scene: &'a Scene, est: Estimator<'a>) -> Self {
        let n = scene.surface.n_water;
        let d = scene.sun.direction.as_dvec3();
        let cos_s = -d.z;
        let sun_w = refract(d, DVec3::Z, 1.0, n).unwrap_or(DVec3::NEG_Z);
        let cos_w = -sun_w.z;
        // Horizontal irradiance is kept (times each band's Fresnel
        // transmittance); the beam narrows by cos_w / cos_s.
        let e_w = scene
            .sun
            .irradiance
            .iter()
            .zip(&scene.water_index)
            .map(|(e, &n_b)| e * (1.0 - fresnel_reflectance(cos_s, 1.0, n_b)) * cos_s / cos_w)
            .collect();
        let sky_l = sky_radiance(scene);
        RayMarcher {
            scene,
            est,
            sun_w: sun_w.as_vec3(),
            e_w,
            sky_l,
            sun: SunBeam::new(scene),
            sun_h: (0..scene.bands.len())
                .map(|b| scene.sun.horizontal_irradiance(b))
                .collect(),
            has_sun: scene.sun.irradiance.iter().any(|&e| e > 0.0),
        }
    }

    fn bands(&self) -> usize {
        self.scene.bands.len()
    }

    /// Transmittance per band from `x` toward the sun up to the surface
    /// (0 where a target or the floor shades x); `here` holds the IOPs at x,
    /// `tmp` is space for other points in heterogeneous water.
    fn sun_transmittance(&self, x: Vec3, here: &[Iop], tmp: &mut [Iop], out: &mut [f64]) {
        self.transmittance_up(x, -self.sun_w, here, tmp, out);
    }

    /// The direct sun's irradiance per band on a face at `x` (normal `n`,
    /// IOPs `here`) under a rough surface, into `out`: the beams
    /// [`SunBeam::sample`] draws through the facets (one by the facet
    /// density, one for light meeting more than one facet), each
    /// attenuated along its own way up to the surface (`t` is scratch), as
    /// the path integrator draws them, in place of the mean flat surface's
    /// single refracted direction. Single scattering along the march
    /// still sees the sun through the mean flat surface.
    #[allow(clippy::too_many_arguments)]
    fn rough_direct(
        &self,
        x: Vec3,
        n: Vec3,
        here: &[Iop],
        tmp: &mut [Iop],
        t: &mut [f64],
        rng: &mut Pcg32,
        out: &mut [f64],
    ) {
        out.iter_mut().for_each(|o| *o = 0.0);
        let scene = self.scene;
        for beam in self.sun.sample(rng).into_iter().flatten() {
            let cos = n.dot(-beam.dir) as f64;
            if cos <= 0.0 {
                continue;
            }
            self.transmittance_up(x, -beam.dir, here, tmp, t);
            for (b, o) in out.iter_mut().enumerate() {
                let f = beam
                    .crossing
                    .band_factor(scene.water_index[b], scene.surface.n_water);
                *o += self.sun_h[b] * beam.g * f * cos * t[b];
            }
        }
    }

    /// Transmittance per band from `x` along `up` (pointing up) to the
    /// surface, 0 where a target or the floor is in the way.
    fn transmittance_up(&self, x: Vec3, up: Vec3, here: &[Iop], tmp: &mut [Iop], out: &mut [f64]) {
        let len = (-x.z / up.z).max(0.0);
        if self.scene.geometry.occluded(x, up, len) {
            out.iter_mut().for_each(|o| *o = 0.0);
            return;
        }
        let water = &self.scene.water;
        if water.is_uniform() {
            for (o, iop) in out.iter_mut().zip(here) {
                *o = (-iop.c() * len as f64).exp();
            }
            return;
        }
        if !(water.layered_optical_depth(x, up, len, tmp, out)
            || water.gradient_optical_depth(x, up, len, out))
        {
            // Other smooth fields (grids): midpoint samples at most
            // `SUN_STEP_M` apart.
            let samples = ((len / SUN_STEP_M).ceil() as usize).max(4);
            out.iter_mut().for_each(|o| *o = 0.0);
            for s in 0..samples {
                let p = x + up * (len * (s as f32 + 0.5) / samples as f32);
                water.iops(p, tmp);
                for (o, iop) in out.iter_mut().zip(tmp.iter()) {
                    *o += iop.c() * len as f64 / samples as f64;
                }
            }
        }
        out.iter_mut().for_each(|o| *o = (-*o).exp());
    }

    /// Radiance per band arriving at `p0` (in water) travelling along `-dir`,
    /// i.e. what an instrument at p0 looking along `dir` sees. `out` holds
    /// one value per band, or [`CHANNELS`] runs of bands: the radiance and
    /// each photon group's part of it (`estimate::groups`), which the march
    /// carries as it carries the photon estimates.
    pub fn march(
        &self,
        p0: Vec3,
        dir: Vec3,
        rng: &mut Pcg32,
        scratch: &mut Scratch,
        out: &mut [f64],
    ) -> Result<()> {
        self.march_coarse(p0, dir, 1.0, rng, scratch, out)
    }

    /// [`march`](Self::march) with steps `factor` times the scene's: the
    /// same expectation (one jittered sample per step is unbiased for the
    /// step's integral at any length; the turns into the peak are drawn
    /// at their own rate), fewer estimates, more noise. For calls whose
    /// result is a small correction averaged over many (the air's control
    /// variates, `render::air`).
    pub fn march_coarse(
        &self,
        p0: Vec3,
        dir: Vec3,
        factor: f32,
        rng: &mut Pcg32,
        scratch: &mut Scratch,
        out: &mut [f64],
    ) -> Result<()> {
        let step_m = self.scene.estimate.step_m as f32 * factor;
        self.march_with(p0, dir, rng, scratch, out, Course::paced(step_m, true))
    }

    /// [`march`](Self::march) on its `course`.
    ///
    /// **The particles' forward peak is scattered into explicitly.** The
    /// photon estimates weigh photons by the truncated phase functions
    /// (`estimate::peak`), whose forward delta scatters light of the ray's
    /// own direction back into it. Where the radiance varies within the
    /// peak's cone (20 degrees looking down) that is wrong: above a small
    /// bright target the delta carried the target's radiance up at reduced
    /// extinction where the cone sees the floor around it (a 0.5 m box 6 m
    /// down read 15 % bright from the air). So the ray itself scatters into
    /// the particle delta: at rate sigma = f_p min_b b_p (the same for every
    /// band, so no band is reweighted) it turns by an angle drawn from the
    /// delta's own shape (`TruncatedPhase::sample_peak`) and the march goes
    /// on from there, each band still attenuated by c - f_w b_w - f_p b_p.
    /// What a band's f_p b_p exceeds sigma by, and the pure-water delta
    /// (about 1e-3 of b_w), stay a delta — except on rays looking down at
    /// a target, which turn at a hero band's rate with every band weighted
    /// to its own ([`PeakTurns`]): there the excess kept as a delta carried
    /// the bright face's light up through the cone where it sees the sand
    /// (boxes 6 m down read 2–7 % bright at 100 traced photons per m^2,
    /// more the denser the map; with the hero's turns within 1 %).
    /// This turns bias into variance: a
    /// pixel over a small target sees the floor around it through the
    /// turns, as light does. Looking up, the delta took the light inside
    /// the cone to be the ray's own where it brightens toward the sun
    /// (zenith radiance 2-4 % low, the aureole 20 % low 5 degrees from
    /// the refracted sun); turns near the sun are drawn by MIS
    /// ([`turn`](Self::turn)).
    fn march_with(
        &self,
        p0: Vec3,
        dir: Vec3,
        rng: &mut Pcg32,
        scratch: &mut Scratch,
        out: &mut [f64],
        course: Course,
    ) -> Result<()> {
        let nb = self.bands();
        let channels = out.len() / nb;
        debug_assert!(channels == 1 || channels == CHANNELS);
        out.iter_mut().for_each(|o| *o = 0.0);
        let mut tr = vec![1.0f64; nb];
        let mut buf = MarchBuffers {
            est: vec![0.0f64; out.len()],
            sun_t: vec![0.0f64; nb],
            inelastic_sun: vec![0.0f64; nb],
            beam: vec![0.0f64; nb],
            iops: vec![Iop::default(); nb],
            tmp: vec![Iop::default(); nb],
            turns: None,
            course,
            step: Step::default(),
        };
        let (mut p, mut dir) = (p0, dir);
        let mut travelled = 0.0f32;
        let at_target = self.looks_at_target(p0, dir);
        if at_target {
            buf.turns = Some(PeakTurns::new(nb, rng));
        }
        loop {
            match self.segment(
                p,
                dir,
                travelled,
                at_target,
                rng,
                scratch,
                out,
                &mut tr,
                &mut buf,
                course.gather,
            )? {
                Segment::Turned { at, to, weight } => {
                    travelled += (at - p).length();
                    tr.iter_mut().for_each(|t| *t *= weight);
                    p = at;
                    dir = to;
                }
                Segment::Ended => return Ok(()),
            }
        }
    }

    /// One straight run of [`march_with`](Self::march_with) from `p0` along
    /// `dir`: the steps' sources into `out` with each band's transmittance
    /// `tr` (carried in and out), up to a scattering into the forward peak
    /// (`Turned`) or the end of the ray, where the floor, a target or the
    /// sky through the surface is added (`Ended`).
    ///
    /// It stays one function: each step is one pass over the bands in
    /// which the step's sample, its turn into the forward peak, the IOPs
    /// and the sun's transmittance there are shared by every band's
    /// source, closed-form single scattering and transmittance; split, the
    /// renderer's innermost loop would hand a dozen borrowed buffers
    /// between pieces at every step.
    #[allow(clippy::too_many_arguments)]
    fn segment(
        &self,
        p0: Vec3,
        dir: Vec3,
        travelled: f32,
        at_target: bool,
        rng: &mut Pcg32,
        scratch: &mut Scratch,
        out: &mut [f64],
        tr: &mut [f64],
        buf: &mut MarchBuffers,
        gather: bool,
    ) -> Result<Segment> {
        let nb = self.bands();
        let scene = self.scene;
        let MarchBuffers {
            est,
            sun_t,
            inelastic_sun,
            iops,
            tmp,
            turns: hero,
            ..
        } = buf;
        let t_surface = if dir.z > 0.0 {
            -p0.z / dir.z
        } else {
            f32::INFINITY
        };
        let limit = t_surface.min(MAX_MARCH_M - travelled);
        // An instrument may sit closer to the floor than the self-intersection epsilon.
        let hit = scene.geometry.intersect_from_point(p0, dir, limit);
        let t_end = hit.map_or(limit.max(0.0), |h| h.t);
        let step = buf.course.step_m;
        let (pw, pp) = (&scene.water_phase, &scene.particle_phase);
        let (fw, fp) = self.est.forward_fractions(dir, at_target);
        // 1 - cos of the single-scattering angle from |sun_w + dir|^2 / 2: a
        // ray looking into the sun (a final-gather ray) meets the forward
        // peak, where a cosine has too few digits.
        let m_ss = 0.5 * (self.sun_w + dir).length_squared() as f64;
        let (pw_ss, pp_ss) = (pw.eval_one_minus_cos(m_ss), pp.eval_one_minus_cos(m_ss));
        let inelastic = self.est.inelastic.is_some();
        // Stratified: one jittered sample in each step, weighted by the
        // transmittance to the sample itself (unbiased for the step's
        // integral of T times the source). Single scattering of the sun is
        // integrated over the step in closed form instead, where the water
        // varies smoothly or not at all: along the step it falls as
        // exp(-k s), k = c up_len_per_s, with k from the IOPs at the sample,
        // so that the step's jitter no longer moves the dominant source of
        // strongly absorbed bands (at 650 nm in the built-in scene, c dt ~
        // 0.35: the transmittance across a step varies by 30 %).
        let closed_form = !scene.water.is_layered();
        let up_len_per_s = (-dir.z / -self.sun_w.z).max(0.0) as f64;
        // Steps run on across turns, except under a hero band's turns.
        let spans = buf.course.spans_turns && hero.is_none();
        let mut t0 = 0.0f32;
        while t0 < t_end {
            if buf.step.rest <= STEP_REST_EPS_M || !spans {
                let len = (step * stretch(tr, buf.course.stretch_max)).min(t_end - t0);
                buf.step = Step {
                    len,
                    rest: len,
                    at: Some(len * rng.uniform_f32()),
                };
            }
            let dt = buf.step.rest.min(t_end - t0);
            // The piece's sample: the step's own where it lies within reach.
            let mut s = match buf.step.at {
                Some(a) if a < dt => a,
                _ => dt * rng.uniform_f32(),
            };
            let mut x = p0 + dir * (t0 + s);
            scene.water.iops(x, iops);
            // A scattering into the particles' forward peak within the piece
            // (at the rate of the IOPs at the sample, as the piece takes
            // them) ends the piece there, and a sample beyond it is drawn
            // again before it (the step's own goes on past the turn).
            let sigma = match hero {
                Some(h) => {
                    for (s, i) in h.sigma.iter_mut().zip(iops.iter()) {
                        *s = fp * i.b_p;
                    }
                    h.sigma[h.hero]
                }
                None => fp * iops.iter().fold(f64::INFINITY, |m, i| m.min(i.b_p)),
            };
            let turn = if sigma > 0.0 && sigma.is_finite() {
                let d = rng.exponential(sigma);
                (d < dt as f64).then_some(d as f32)
            } else {
                None
            };
            let len = turn.unwrap_or(dt);
            if s >= len {
                s = len * rng.uniform_f32();
                x = p0 + dir * (t0 + s);
                scene.water.iops(x, iops);
            }
            // Whether the step's estimate is taken here, and its length.
            let (estimate, est_len) = if spans {
                (matches!(buf.step.at, Some(a) if a < len), buf.step.len)
            } else {
                (true, len)
            };
            buf.step.rest = if spans { buf.step.rest - len } else { 0.0 };
            buf.step.at = match buf.step.at {
                Some(a) if spans && a >= len => Some(a - len),
                _ => None,
            };
            // With turns at a hero band's rate, each band's MIS weight at
            // the sample (the run has not turned before it).
            if let Some(h) = hero.as_mut() {
                let mut at = std::mem::take(&mut h.at_sample);
                h.advance(s as f64, false, false, &mut at);
                h.at_sample = at;
            }
            if estimate {
                let share = search_share(tr, buf.course.share_min);
                self.est
                    .volume_with_iops(x, -dir, at_target, share, iops, scratch, est)?;
            }
            self.sun_transmittance(x, iops, tmp, sun_t);
            // The direct sun's inelastic source toward the viewer, at the
            // piece's sample (see `Estimator::add_inelastic`).
            if inelastic {
                if !estimate {
                    self.est.absorbers_at(x, scratch);
                }
                self.est
                    .inelastic_sun(m_ss, &self.e_w, sun_t, scratch, inelastic_sun);
            }
            let mut alive = false;
            for b in 0..nb {
                let iop = iops[b];
                // The forward delta of the truncated phase functions puts
                // its share of scattering back into the ray (see `peak`).
                let c = iop.c() - fw * iop.b_w - fp * iop.b_p;
                let single = (iop.b_w * pw_ss + iop.b_p * pp_ss) * self.e_w[b] * sun_t[b];
                let mis = hero.as_ref().map_or(1.0, |h| h.at_sample[b]);
                // The transmittance to the sample; times the piece's length
                // for its own sources, the step's for the estimate.
                let to_sample = tr[b] * mis * (-c * s as f64).exp();
                let f = to_sample * len as f64;
                // The closed form holds for the transmittance alone, not
                // under a hero band's weights, which vary along the step.
                let single_step = if closed_form && hero.is_none() {
                    // single at s is single(0) exp(-k s); T(s) = exp(-c s).
                    let k = iop.c() * up_len_per_s;
                    let rate = c + k;
                    let integral = if rate * (len as f64) > 1e-9 {
                        (1.0 - (-rate * len as f64).exp()) / rate
                    } else {
                        len as f64
                    };
                    tr[b] * single * (k * s as f64).exp() * integral
                } else {
                    f * single
                };
                out[b] += f * inelastic_sun[b] + single_step;
                if estimate {
                    let g = to_sample * est_len as f64;
                    out[b] += g * est[b];
                    for k in (nb + b..out.len()).step_by(nb) {
                        out[k] += g * est[k];
                    }
                }
                tr[b] *= (-c * len as f64).exp();
            }
            // Each band's MIS weight at the step's end, or at the turn.
            if let Some(h) = hero.as_mut() {
                let mut at = std::mem::take(&mut h.at_sample);
                h.advance(len as f64, turn.is_some(), true, &mut at);
                tr.iter_mut().zip(&at).for_each(|(t, a)| *t *= a);
                h.at_sample = at;
            }
            for &t in tr.iter() {
                alive |= t > MIN_TRANSMITTANCE;
            }
            if !alive {
                return Ok(Segment::Ended);
            }
            if let Some(d) = turn {
                if let Some((to, weight)) = self.turn(dir, at_target, rng) {
                    return Ok(Segment::Turned {
                        at: p0 + dir * (t0 + d),
                        to,
                        weight,
                    });
                }
            }
            t0 += len;
        }
        if let Some(h) = hit {
            self.at_floor(&h, rng, scratch, buf, out, tr, gather)?;
        } else if t_surface <= limit {
            let at = p0 + dir * t_surface;
            return Ok(self.under_surface(Vec3::new(at.x, at.y, 0.0), dir, rng, out, tr));
        }
        Ok(Segment::Ended)
    }

    /// Whether a march from `p0` along `dir` looks down at a target: at
    /// the depth of some target's top (below `p0`) its line passes within
    /// [`TARGET_PEAK_MARGIN_M`] of the target's horizontal extent. Such a
    /// ray takes the phase functions' forward peak as
    /// `forward_peak_target_deg` wide instead of `forward_peak_down_deg`
    /// for its whole march, turns included (each ray's transfer equation
    /// holds for any split of the peak): the light rising off a target
    /// smaller than the expanded search that counts photons travelling
    /// toward the viewer (about a metre at 2500 photons per m^2 in Chl 10)
    /// is smeared by it over the darker water around, and the wider peak
    /// leaves more of that light's in-scatter to the exact turns. A 1 m
    /// box 1.5 m down in Chl 10 read 5 % low with 20 degrees and 1.6 % low
    /// with 30 (40 read a 2 m box at 5.5 m 6 % low in the red); applied to
    /// every ray looking down, 40 degrees raised the built-in scene's
    /// deep-water pixel noise from 2.2 % to 3.8 %.
    fn looks_at_target(&self, p0: Vec3, dir: Vec3) -> bool {
        if dir.z >= 0.0 {
            return false;
        }
        self.scene.target_extents.iter().any(|b| {
            let top = b.max.z;
            if p0.z < top {
                return false;
            }
            let at = p0 + dir * ((top - p0.z) / dir.z);
            let dx = (b.min.x - at.x).max(at.x - b.max.x).max(0.0);
            let dy = (b.min.y - at.y).max(at.y - b.max.y).max(0.0);
            dx.hypot(dy) <= TARGET_PEAK_MARGIN_M
        })
    }

    /// A turn into the particles' forward peak from `dir`: the new
    /// direction and its weight. Where the sun lies within
    /// [`TURN_SUN_MARGIN_RAD`] of the peak's cone, by one-sample MIS with
    /// directions drawn from the particle phase function around the sun
    /// ([`TURN_SUN_GUIDE`] of them), balance heuristic: a turn toward the
    /// sun meets the forward peak of its single scattering, which turns
    /// drawn from the peak alone reach rarely and with a weight of
    /// thousands. A draw outside the cone weighs 0.
    fn turn(&self, dir: Vec3, at_target: bool, rng: &mut Pcg32) -> Option<(Vec3, f64)> {
        let peak = self.est.particle_peak(dir, at_target);
        let to_sun = -self.sun_w;
        let apart = (dir.dot(to_sun) as f64).clamp(-1.0, 1.0).acos();
        if !self.has_sun || apart > peak.peak_half_angle() + TURN_SUN_MARGIN_RAD {
            return peak.sample_peak(dir, rng);
        }
        let pp = &self.scene.particle_phase;
        let (to, w) = if rng.uniform_f64() < TURN_SUN_GUIDE {
            let u = [rng.uniform_f64(), rng.uniform_f64()];
            (pp.sample_direction(to_sun, u), 1.0)
        } else {
            peak.sample_peak(dir, rng)?
        };
        let pa = peak.peak_density(dir, to);
        if pa <= 0.0 {
            return Some((to, 0.0));
        }
        let pb = pp.eval_one_minus_cos(0.5 * (to - to_sun).length_squared() as f64);
        Some((
            to,
            w * pa / ((1.0 - TURN_SUN_GUIDE) * pa + TURN_SUN_GUIDE * pb),
        ))
    }

    /// Radiance per band leaving a target's Lambertian face at `x` (normal
    /// `n`, facing the water) in the light of everything but the direct
    /// sun, by final gathering: the irradiance from `rays` marches out of
    /// the face, each seeing what a sensor ray sees there (single
    /// scattering of the sun, the volume photons' in-scatter with its band
    /// shapes, the sky through the surface, the floor's surface estimate),
    /// times R / pi. `out` is laid out as [`march`](Self::march)'s.
    ///
    /// Why: a target's face is small next to the surface search it needs
    /// (a 1 m face holds a few hundred surface photons at the built-in
    /// scene's density, a handful per band), so its band shapes and level
    /// from the surface map were off by tens of per cent; the volume
    /// photons around it are many more, and the march's band shapes come
    /// from the band-shape grid.
    ///
    /// Directions: the cosine lobe, and [`GATHER_GUIDE`] of them drawn
    /// around the refracted sun's direction from the water's scattering
    /// mixture at `x` (one-sample MIS), since a gather ray near the sun
    /// sees its single-scattered aureole through the forward peak.
    #[allow(clippy::too_many_arguments)]
    fn gather(
        &self,
        x: Vec3,
        n: Vec3,
        surface: crate::geometry::SurfaceId,
        rays: u32,
        rng: &mut Pcg32,
        scratch: &mut Scratch,
        out: &mut [f64],
    ) -> Result<()> {
        let scene = self.scene;
        let nb = self.bands();
        let mut l = vec![0.0f64; out.len()];
        out.iter_mut().for_each(|o| *o = 0.0);
        let axis = -self.sun_w;
        let sun = scene.sun.irradiance.iter().any(|&e| e > 0.0);
        let mut iops = vec![Iop::default(); nb];
        scene.water.iops(x, &mut iops);
        let (bw, b) = iops
            .iter()
            .fold((0.0, 0.0), |(w, t), i| (w + i.b_w, t + i.b()));
        let mixture = Mixture {
            first: &scene.water_phase,
            second: &scene.particle_phase,
            q: if b > 0.0 { bw / b } else { 0.0 },
        };
        let guide = if sun && b > 0.0 { GATHER_GUIDE } else { 0.0 };
        let start = x + n * 1e-3;
        for _ in 0..rays {
            let w = if rng.uniform_f64() < guide {
                mixture.sample_around(axis, rng)
            } else {
                crate::optics::phase::cosine_hemisphere(n, rng)
            };
            let cos_n = w.dot(n) as f64;
            if cos_n <= 0.0 {
                continue;
            }
            let m = 0.5 * (w - axis).length_squared() as f64;
            let lambert = cos_n / std::f64::consts::PI;
            let phase = mixture.eval_one_minus_cos(m);
            let pdf = (1.0 - guide) * lambert + guide * phase;
            if !pdf.is_finite() {
                continue; // exactly on the peak of a phase function without a finite one
            }
            // L cos / pdf over the rays is the irradiance; times R / pi.
            let k = lambert / pdf / rays as f64;
            let step_m = self.scene.estimate.step_m as f32;
            let course = Course::paced(step_m, false);
            self.march_with(start, w, rng, scratch, &mut l, course)?;
            for (o, v) in out.iter_mut().zip(&l) {
                *o += k * v;
            }
        }
        for b in 0..nb {
            let r = scene.reflectance(surface, x, b);
            for k in (b..out.len()).step_by(nb) {
                out[k] *= r;
            }
        }
        Ok(())
    }
}
