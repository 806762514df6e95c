//! The reference integrator: unbiased spectral backward path tracing
//! through the same scene the photons see, with next-event estimation of
//! the sun. It needs no photon map and is the truth the photon map is
//! measured against.
//!
//! **All bands on one path (spectral tracking).** A path carries a
//! throughput `w_b` for every band. Each band's smallest absorption
//! anywhere in the water, `kappa_b`, is carried by weight: every flight
//! multiplies `w_b` by exp(-kappa_b t). Free flights are sampled against
//! one rate `mu_bar`, twice the largest of any band's extinction beyond
//! its `kappa_b` (`MU_PAD`); at a tentative collision the path scatters with probability
//! `P_s = sum w_b b_b / (sum w_b b_b + sum w_b n_b)`, with null coefficient
//! `n_b = mu_bar - c_b + kappa_b`, and each band's throughput is
//! multiplied by `b_b / (mu_bar P_s)` for a real scattering or `n_b /
//! (mu_bar (1 - P_s))` for a null collision: the history-aware spectral
//! tracking of Kutz et al. 2017 (SIGGRAPH, "Spectral and decomposition
//! tracking") with the absorption control of their decomposition
//! tracking, unbiased in every band for any position-dependent IOPs.
//! Why the control: in the near infrared pure water's absorption is 2–3
//! m^-1 where the visible bands' extinction is well below 1, and against
//! the majorant it set, that band met a null collision (weight near 0)
//! almost wherever the other bands did; it lived only on paths that
//! scattered at every tentative collision, and a zenith radiance 3 m deep
//! in the built-in scene's water read with a per-path deviation of 29 at
//! 775 nm. Carried by weight, its absorption costs no collisions: 1.3
//! there, the worst band now the blue at 3.2 (2.8 before); uniform waters
//! read 10–20 % higher deviations (`benches/README.md`).
//!
//! **Scattering.** The new direction is drawn from the mixture `q p_w + (1 -
//! q) p_p` of the pure-water and particle phase functions, with `q` the
//! throughput-weighted share of pure-water scattering; each band is
//! weighted by its own `(b_w p_w + b_p p_p) / (b pdf)` (one-sample
//! balance over the two components). The floor and targets are Lambertian
//! (cosine-sampled, throughput times the reflectance).
//!
//! **The sun (next-event estimation with MIS).** At every scattering
//! vertex the direct sun is estimated twice and the two are weighed by the
//! balance heuristic: by light sampling, and by the continuation's own
//! drawn direction when it looks at the sun. Through a flat surface the
//! sun is its disc (0.2665 degrees radius, where the photon map has a
//! point; they differ within a degree of the sun only), refracted exactly
//! with its Fresnel transmittance, so the forward peak of the phase
//! function meets a finite radiance. Through a Cox–Munk surface the sun is
//! a point and its beam is refracted by the facets: the first facet drawn
//! as `SeaSurface::interact` draws it, with the analytic density of the
//! refracted direction (`SeaSurface::beam_transmission_density`) for MIS
//! and the Fresnel factor and Smith's unshadowed fraction as weights; the
//! rarer beams that meet more than one facet (shadowed, or sent back into
//! the surface) are drawn by `interact` itself and added without MIS,
//! so the sum is exactly the beam the photons see. Floor and target
//! vertices take the same samples without MIS (a Lambertian surface has no
//! peak). Transmittance toward the surface is exact in uniform water and
//! by ratio tracking against `c_bar` elsewhere; floors and targets shadow,
//! periodic edges wrap the shadow ray, open edges end it (no light enters
//! through the surface outside an open domain). Paths that leave the
//! water see the sky only.
//!
//! **The surface from below.** Flat: Fresnel split, the transmitted part
//! sees the sky (`n^2 t L_sky`), the reflected part goes on. Rough: the
//! facet sampling of `SeaSurface::interact` chooses. **Ends.** Russian
//! roulette on the largest band throughput from the fourth event on,
//! after each vertex's own sun estimate and before its continuation (a
//! path drawn toward the sun with a small weight keeps that weight for the
//! estimate it was drawn for), surviving with that throughput times
//! 4 pi p(w . w_sun), the path's phase function toward the sun against an
//! isotropic one (at least 1): a path travelling within a few degrees of
//! the sun gathers the forward peak at its next vertices, and restoring
//! the small weight guiding gave it made those gatherings rare jackpots.
//! In deep Fournier–Forand water at 1 m this cut the per-path standard
//! error of nadir Lu 3.4x (2.04 % -> 0.60 % over 1 M paths; the largest
//! path's share of the total 1.6 % -> 0.3 %), and the mean rose 3.9 %
//! toward the emission tally. Paths stop after `MAX_EVENTS` events, like
//! photons do. **Splitting.** A path whose weight the choice between
//! guided and unguided directions has raised above `SPLIT_ABOVE` goes on
//! as that many copies, each with its share (`PathScratch::split`): the
//! mixture's 1 / (1 - `GUIDE_FRACTION`) per forward scattering far from
//! the sun had made paths of weight 10–50 whose sun estimates, once drawn
//! into the forward peak, were the heaviest tail left.
//!
//! Above the water, sensor rays meet the surface as `air_sea::from_air`
//! has them, with the photon-map integrator.
//!
//! **Known limits.** The rough surface is run backwards by the same
//! facet sampling and shadowing that run it forwards; with Smith's
//! shadowing the single-facet part is reciprocal (G1 of both directions).
//!
//! Not for: speed at low noise (the photon map is for that); polarisation.

use super::air_sea::sky_radiance;
use super::sun::{Crossing, SunBeam, SUN_HALF_ANGLE_RAD};
use crate::emit::trace::MAX_EVENTS;
use crate::optics::inelastic::Inelastic;
use crate::optics::iop::Iop;
use crate::optics::phase::{cosine_hemisphere, Mixture};
use crate::optics::surface::{fresnel_reflectance, refract};
use crate::rng::Pcg32;
use crate::scene::Scene;
use glam::{DVec3, Vec3};
use std::f64::consts::PI;

mod events;
use events::Collided;

/// Events (scatterings, floor and surface hits) before Russian roulette.
const ROULETTE_AFTER: u32 = 4;
/// Share of scattering directions drawn around the direction toward the
/// sun rather than around the path's own direction.
const GUIDE_FRACTION: f64 = 0.3;
/// A path whose weight drawing directions has raised above this is split
/// (see [`PathScratch::split`]).
const SPLIT_ABOVE: f64 = 4.0;
/// The most copies one split makes.
const MAX_SPLIT: usize = 16;
/// The rate of tentative collisions over the largest extinction any band
/// must meet by collisions. With 1, the band that sets the rate meets
/// no null collision where its extinction peaks (its ideal probability of
/// scattering there is 1) while the bands below it make null collisions
/// common, so its weight grows by 1 / P_s at every scattering: the blue
/// of a strong chlorophyll and CDOM gradient read a per-path deviation
/// of 6.3 at 3 m, 4.3 with 1.5, 3.4 with 2 and 3 (2.9 against the plain
/// extinction majorant, where the near infrared paid instead).
const MU_PAD: f64 = 2.0;
/// How many times its share of the collision rate an inelastic event is
/// drawn with (the Raman source is a few 1e-4 of it: drawn as it is, the
/// Raman-scattered light rests on one path in hundreds).
const INELASTIC_BOOST: f64 = 50.0;
/// The largest probability of an inelastic event at one collision.
const INELASTIC_MAX_SHARE: f64 = 0.1;
/// Share of inelastic events whose sensor band is drawn uniformly over
/// the bands fed rather than in proportion to their source.
const INELASTIC_UNIFORM_TARGET: f64 = 0.5;
/// No split while this many copies wait (a bound on memory, not needed
/// for correctness: not splitting is always unbiased).
const MAX_PENDING: usize = 256;

/// The path integrator of one scene.
pub struct PathTracer<'a> {
    pub scene: &'a Scene,
    pub(super) sky_l: Vec<f64>,
    /// Horizontal irradiance of the sun above the surface per band.
    sun_h: Vec<f64>,
    /// Extinction majorant over every band and the whole water (1/m): the
    /// rate of residual ratio tracking toward the sun.
    c_bar: f64,
    /// The rate of tentative collisions (1/m): [`MU_PAD`] times the
    /// largest extinction of any band anywhere beyond the absorption
    /// `kappa` carries by weight.
    mu_bar: f64,
    /// Each band's smallest absorption anywhere in the water (1/m),
    /// carried by weight along every flight instead of by collisions.
    kappa: Vec<f64>,
    /// The largest of `kappa`.
    kappa_max: f64,
    /// Each band's smallest extinction anywhere in the water (1/m): the
    /// control of residual ratio tracking.
    c_min: Vec<f64>,
    /// Samples of the sun's beam in the water.
    sun: SunBeam<'a>,
    /// The IOPs of uniform water (None when they vary in space).
    uniform: Option<Vec<Iop>>,
    /// Direction toward the sun in the water (through the mean surface),
    /// around which scattering directions are also drawn; None without sun.
    guide: Option<Vec3>,
    /// Paths whose guided ratio exceeds this are split ([`SPLIT_ABOVE`];
    /// infinite: never).
    split_above: f64,
    /// Inelastic light (Raman scattering, fluorescence), when the scene
    /// has it.
    inelastic: Option<&'a Inelastic>,
    /// Per band: the largest gain of all inelastic processes together
    /// anywhere in the water (1/m), the bound inelastic events are drawn
    /// against.
    inelastic_bound: Vec<f64>,
}

/// Per-path buffers, one entry per band.
pub struct PathScratch {
    w: Vec<f64>,
    iops: Vec<Iop>,
    tmp: Vec<Iop>,
    tr: Vec<f64>,
    /// The product of the direction-sampling ratios (the scattering
    /// mixture's or the cosine lobe's density over the drawn direction's
    /// pdf) since the path began or was last split: how far the choice
    /// between guided and unguided directions has raised its weight.
    guided: f64,
    /// Distance flown (m) whose absorption `kappa` is not yet in `w`.
    flown: f64,
    /// The sensor band every contribution of this path goes to since it
    /// met an inelastic event (None before: each band's own). From then on
    /// `w` holds the throughputs of the excitation bands that feed it.
    target: Option<usize>,
    /// Copies made by splitting, waiting to be traced.
    pending: Vec<Pending>,
    /// Throughput buffers of traced copies, for reuse.
    spare: Vec<Vec<f64>>,
}

/// Where a path is between events.
#[derive(Clone, Copy)]
struct PathState {
    pos: Vec3,
    dir: Vec3,
    events: u32,
    /// On the floor or a target (the self-intersection epsilon applies).
    on_surface: bool,
}

/// A copy of a path made by splitting: its state, band throughputs and
/// guided ratio.
struct Pending {
    state: PathState,
    w: Vec<f64>,
    guided: f64,
    target: Option<usize>,
}

impl crate::parallel::BandScratch for PathScratch {
    fn for_bands(bands: usize) -> Self {
        PathScratch::new(bands)
    }
    fn bands(&self) -> usize {
        self.w.len()
    }
}

impl PathScratch {
    pub fn new(bands: usize) -> Self {
        PathScratch {
            w: vec![0.0; bands],
            iops: vec![Iop::default(); bands],
            tmp: vec![Iop::default(); bands],
            tr: vec![0.0; bands],
            guided: 1.0,
            flown: 0.0,
            target: None,
            pending: Vec::new(),
            spare: Vec::new(),
        }
    }

    /// Multiply the throughputs by the absorption `kappa` (per band, 1/m)
    /// over the distance flown since the last call.
    fn absorb(&mut self, kappa: &[f64]) {
        absorb(&mut self.w, kappa, &mut self.flown);
    }

    /// Split the path in `state` into `n` copies when drawing directions
    /// has raised its weight above `above` (`guided`; `n` that
    /// rounded up, at most [`MAX_SPLIT`]): each carries 1/n of the
    /// throughput, this one goes on and the others wait in `pending`.
    ///
    /// Why: a direction drawn around the path's own direction weighs its
    /// phase function over the mixture pdf, 1 / (1 - `GUIDE_FRACTION`)
    /// when the sun's share of the pdf is negligible, so a path that
    /// scatters forward many times far from the sun gathers a weight of
    /// 1.43^k (49 after a dozen events in the built-in scene's water under
    /// a flat surface), and when it is then drawn toward the sun its sun
    /// estimates inside the forward peak are a jackpot. The split copies
    /// share that weight and meet the sun independently. Unbiased for any
    /// `n`. Only this ratio counts, not the bands' spectral-tracking
    /// factors, which are not what makes the jackpots (see
    /// `benches/README.md` for the measured gain and cost).
    fn split(&mut self, state: PathState, above: f64) {
        // Splits follow events, which bring the flight's absorption in.
        debug_assert!(self.flown == 0.0);
        if self.guided <= above || self.guided.is_nan() || self.pending.len() >= MAX_PENDING {
            return;
        }
        let n = (self.guided.ceil() as usize).min(MAX_SPLIT);
        let k = 1.0 / n as f64;
        self.w.iter_mut().for_each(|x| *x *= k);
        self.guided *= k;
        for _ in 1..n {
            let mut w = self.spare.pop().unwrap_or_default();
            w.clear();
            w.extend_from_slice(&self.w);
            self.pending.push(Pending {
                state,
                w,
                guided: self.guided,
                target: self.target,
            });
        }
    }
}

impl<'a> PathTracer<'a> {
    pub fn new(scene: &'a Scene) -> Self {
        let nb = scene.bands.len();
        let n = scene.surface.n_water;
        let majorants: Vec<f64> = (0..nb).map(|b| scene.water.majorant(b)).collect();
        let c_bar = majorants.iter().copied().fold(0.0f64, f64::max);
        let kappa: Vec<f64> = (0..nb)
            .map(|b| scene.water.absorption_minorant(b))
            .collect();
        // What tentative collisions must cover is each band's extinction
        // beyond the absorption carried by weight; `MU_PAD` times the
        // largest, so that no band is left without null collisions where
        // its extinction peaks. At least a thousandth of the extinction,
        // so that a path in water that does not scatter still meets
        // collisions that end it.
        let mu_bar = MU_PAD
            * majorants
                .iter()
                .zip(&kappa)
                .map(|(c, k)| (c - k).max(1e-3 * c))
                .fold(0.0f64, f64::max);
        // Inelastic events are drawn at tentative collisions: with
        // absorption carried by weight, water that hardly scatters would
        // meet almost none where its light lives. At least the bands' mean
        // extinction.
        let mu_bar = if scene.inelastic.is_some() {
            mu_bar.max(majorants.iter().sum::<f64>() / nb as f64)
        } else {
            mu_bar
        };
        let uniform = scene.water.is_uniform().then(|| {
            let mut v = vec![Iop::default(); nb];
            scene.water.iops(Vec3::new(0.0, 0.0, -1.0), &mut v);
            v
        });
        let has_sun = scene.sun.irradiance.iter().any(|&e| e > 0.0);
        let guide = has_sun.then(|| {
            let d = scene.sun.direction.as_dvec3();
            -refract(d, DVec3::Z, 1.0, n)
                .unwrap_or(DVec3::NEG_Z)
                .as_vec3()
        });
        PathTracer {
            scene,
            guide,
            sky_l: sky_radiance(scene),
            sun_h: (0..nb)
                .map(|b| scene.sun.horizontal_irradiance(b))
                .collect(),
            c_bar,
            mu_bar,
            kappa_max: kappa.iter().copied().fold(0.0, f64::max),
            kappa,
            c_min: (0..nb).map(|b| scene.water.minorant(b)).collect(),
            sun: SunBeam::new(scene),
            uniform,
            split_above: SPLIT_ABOVE,
            inelastic: scene.inelastic.as_ref(),
            inelastic_bound: scene.inelastic.as_ref().map_or_else(Vec::new, |r| {
                (0..nb)
                    .map(|m| r.processes.iter().map(|p| p.gain_bound[m]).sum())
                    .collect()
            }),
        }
    }

    /// For a path direction `next` (in water, pointing up): the direct
    /// sun's radiance along it divided by the sun's horizontal irradiance,
    /// and the MIS light-sampling pdf of that direction per sr; None when
    /// `next` sees no direct sun (the disc through a flat surface, the
    /// first-facet transmission through a rough one), with how the light
    /// crossed the surface.
    fn sun_seen(&self, next: Vec3) -> Option<(f64, f64, Crossing)> {
        if next.z <= 0.0 {
            return None;
        }
        let n = self.scene.surface.n_water;
        if let Some(z_norm) = self.sun.rough_norm {
            let o = -next.as_dvec3();
            let i = self.scene.sun.direction.as_dvec3();
            let surface = &self.scene.surface;
            let (pdf, t, cos_im) = surface.beam_transmission(i, o, z_norm)?;
            let g1 = surface.masking(o);
            return Some((t * g1 * pdf / -o.z, pdf, Crossing::Facet(cos_im)));
        }
        let up_a = refract(next.as_dvec3(), DVec3::NEG_Z, n, 1.0)?;
        let to_sun = -self.scene.sun.direction.as_dvec3();
        if up_a.dot(to_sun) < SUN_HALF_ANGLE_RAD.cos() {
            return None;
        }
        let (cos_a, cos_w, cos_s) = (up_a.z, next.z as f64, to_sun.z);
        let omega = SunBeam::disc_solid_angle();
        let t = 1.0 - fresnel_reflectance(cos_a, 1.0, n);
        Some((
            n * n * t / (cos_s * omega),
            n * n * cos_w / (cos_a * omega),
            Crossing::Facet(cos_a),
        ))
    }

    /// Transmittance per band from `x` along `up` to the surface, into `tr`
    /// (0 where the floor, a target or an open edge is in the way).
    ///
    /// Exact in uniform and depth-layered water. Elsewhere by residual
    /// ratio tracking (Novák et al. 2014, "Residual ratio tracking for
    /// estimating attenuation in participating media"): each band's
    /// smallest extinction `c_min` is attenuated exactly and only the
    /// residual `c - c_min` by the product of null-collision
    /// probabilities at tentative collisions of rate `c_bar`. Plain ratio
    /// tracking's relative variance, exp(c^2 d / c_bar) - 1, is about
    /// 1 / T for the band whose extinction sets the majorant (water's own
    /// absorption in the near infrared: a 780 nm zenith radiance 3 m deep
    /// in the built-in scene read with a per-path deviation of 33); with
    /// the control it is exp((c - c_min)^2 d / c_bar) - 1, near 0 where a
    /// band's extinction hardly varies.
    fn transmittance(&self, x: Vec3, up: Vec3, rng: &mut Pcg32, tmp: &mut [Iop], tr: &mut [f64]) {
        let scene = self.scene;
        tr.iter_mut().for_each(|t| *t = 1.0);
        let total = if x.z < 0.0 && up.z > 0.0 {
            (-x.z / up.z) as f64
        } else {
            0.0
        };
        let layered = self.uniform.is_none() && scene.water.is_layered();
        let mut remaining = total;
        let mut pos = x;
        // Segments between periodic edges (bounded in case a ray runs along one).
        let mut segments = 0;
        while remaining > 0.0 && segments < 100_000 {
            segments += 1;
            let seg = remaining.min(scene.domain.edge_distance(pos, up));
            if scene.geometry.occluded(pos, up, seg as f32) {
                tr.iter_mut().for_each(|t| *t = 0.0);
                return;
            }
            if self.uniform.is_none() && !layered {
                self.segment_transmittance(pos, up, seg, rng, tmp, tr);
            }
            remaining -= seg;
            if remaining <= 1e-6 {
                break;
            }
            if !scene.domain.periodic {
                tr.iter_mut().for_each(|t| *t = 0.0);
                return;
            }
            pos = scene.domain.wrap(pos + up * seg as f32, up);
        }
        if let Some(u) = &self.uniform {
            for (o, iop) in tr.iter_mut().zip(u) {
                *o = (-iop.c() * total).exp();
            }
        } else if layered {
            // Layers are horizontally uniform: the wraps do not matter.
            scene
                .water
                .layered_optical_depth(x, up, total as f32, tmp, tr);
            tr.iter_mut().for_each(|t| *t = (-*t).exp());
        }
    }

    /// Multiply `tr` by each band's transmittance along the `seg` m from
    /// `pos` along `dir`, by residual ratio tracking (see `transmittance`).
    fn segment_transmittance(
        &self,
        pos: Vec3,
        dir: Vec3,
        seg: f64,
        rng: &mut Pcg32,
        tmp: &mut [Iop],
        tr: &mut [f64],
    ) {
        let water = &self.scene.water;
        for (t, c_min) in tr.iter_mut().zip(&self.c_min) {
            *t *= (-c_min * seg).exp();
        }
        let mut t = 0.0;
        loop {
            t += rng.exponential(self.c_bar);
            if t >= seg {
                break;
            }
            water.iops(pos + dir * t as f32, tmp);
            for ((o, iop), c_min) in tr.iter_mut().zip(tmp.iter()).zip(&self.c_min) {
                *o *= (1.0 - (iop.c() - c_min) / self.c_bar).clamp(0.0, 1.0);
            }
        }
    }

    /// The roulette importance of a path leaving along `dir` after a floor,
    /// target or surface event: 4 pi times the larger of the two phase
    /// functions toward the sun (the next vertex may scatter it in).
    fn importance(&self, dir: Vec3) -> f64 {
        self.guide.map_or(1.0, |axis| {
            let m = 0.5 * (dir - axis).length_squared() as f64;
            let (pw, pp) = (&self.scene.water_phase, &self.scene.particle_phase);
            4.0 * PI * pw.eval_one_minus_cos(m).max(pp.eval_one_minus_cos(m))
        })
    }

    /// Russian roulette after `ROULETTE_AFTER` events, surviving with the
    /// largest throughput times `importance` (at least 1: how much more
    /// than an isotropic scatterer the path's next sun estimates may
    /// bring); false ends the path.
    fn survive(w: &mut [f64], events: u32, importance: f64, rng: &mut Pcg32) -> bool {
        if events >= MAX_EVENTS {
            return false;
        }
        if events < ROULETTE_AFTER {
            return true;
        }
        let q = (w.iter().fold(0.0f64, |m, &x| m.max(x)) * importance.max(1.0)).min(1.0);
        if q <= 0.0 || rng.uniform_f64() >= q {
            return false;
        }
        w.iter_mut().for_each(|x| *x /= q);
        true
    }

    /// The scattering mixture, `q` pure water and `1 - q` particles.
    fn mixture_of(&self, q: f64) -> Mixture<'_> {
        Mixture {
            first: &self.scene.water_phase,
            second: &self.scene.particle_phase,
            q,
        }
    }

    /// The density per sr of the scattering mixture, `q` pure water and
    /// `1 - q` particles, at `m` = 1 - cos of the scattering angle.
    fn mixture(&self, q: f64, m: f64) -> f64 {
        self.mixture_of(q).eval_one_minus_cos(m)
    }

    /// A direction drawn from the scattering mixture (`q` pure water)
    /// around `axis`.
    fn sample_around(&self, axis: Vec3, q: f64, rng: &mut Pcg32) -> Vec3 {
        self.mixture_of(q).sample_around(axis, rng)
    }

    /// The direction leaving a Lambertian floor or target point `pos` with
    /// normal `n`, and each band's throughput `w` times its cosine lobe
    /// over the direction's pdf (the reflectance is already in `w`); None
    /// when the drawn direction points into the surface (the path ends).
    ///
    /// With a sun, `GUIDE_FRACTION` of the directions are drawn around the
    /// direction toward it from the water's scattering mixture at `pos`,
    /// as at scatterings (one-sample MIS with the cosine lobe). A bounce
    /// toward the sun is where the path's next vertex meets the forward
    /// peak of the phase function in its sun estimate: drawn by the cosine
    /// alone, its weight is the phase function within a degree of its
    /// peak, the heavy tail of radiance over a bright floor (Fournier–Forand
    /// water over a white floor at 3 m: per-path deviation 21 by cosine
    /// sampling; see `benches/README.md`).
    fn bounce(
        &self,
        pos: Vec3,
        n: Vec3,
        w: &mut [f64],
        guided: &mut f64,
        iops: &mut [Iop],
        rng: &mut Pcg32,
    ) -> Option<Vec3> {
        let Some(axis) = self.guide else {
            return Some(cosine_hemisphere(n, rng));
        };
        self.scene.water.iops(pos, iops);
        let q = water_share(w, iops);
        let next = if rng.uniform_f64() < GUIDE_FRACTION {
            self.sample_around(axis, q, rng)
        } else {
            cosine_hemisphere(n, rng)
        };
        let cos_n = next.dot(n) as f64;
        if cos_n <= 0.0 {
            return None;
        }
        let lambert = cos_n / PI;
        let pdf = (1.0 - GUIDE_FRACTION) * lambert
            + GUIDE_FRACTION * self.mixture(q, one_minus(next, axis));
        let k = lambert / pdf;
        w.iter_mut().for_each(|x| *x *= k);
        *guided *= k;
        Some(next)
    }

    /// Radiance per band arriving at `p0` (in water) travelling along
    /// `-dir`, i.e. what an instrument at p0 looking along `dir` sees: the
    /// path and every copy splitting made of it.
    pub fn in_water(
        &self,
        p0: Vec3,
        dir: Vec3,
        rng: &mut Pcg32,
        scratch: &mut PathScratch,
        out: &mut [f64],
    ) {
        out.iter_mut().for_each(|o| *o = 0.0);
        let Some(pos) = self.scene.domain.image(p0) else {
            return; // outside an open domain: no water there
        };
        let mut state = PathState {
            pos,
            dir,
            events: 0,
            on_surface: false,
        };
        scratch.w.iter_mut().for_each(|x| *x = 1.0);
        scratch.guided = 1.0;
        scratch.flown = 0.0;
        scratch.target = None;
        loop {
            self.trace(state, rng, scratch, out);
            let Some(next) = scratch.pending.pop() else {
                return;
            };
            scratch.w.copy_from_slice(&next.w);
            scratch.guided = next.guided;
            scratch.target = next.target;
            scratch.spare.push(next.w);
            state = next.state;
        }
    }

    /// One path (or copy) from `state` with throughputs `scratch.w` until
    /// it ends, adding its light to `out`; copies it splits into wait in
    /// `scratch.pending`.
    fn trace(&self, state: PathState, rng: &mut Pcg32, scratch: &mut PathScratch, out: &mut [f64]) {
        let scene = self.scene;
        let domain = &scene.domain;
        let dispersive = scene.dispersive();
        let PathState {
            mut pos,
            mut dir,
            mut events,
            mut on_surface,
        } = state;
        loop {
            let t_flight = rng.exponential(self.mu_bar);
            let t_surface = crate::scene::Domain::surface_distance(pos, dir);
            let t_edge = domain.edge_distance(pos, dir);
            let t_limit = t_flight.min(t_surface).min(t_edge);
            if !t_limit.is_finite() {
                return;
            }
            // From a point in the water (the start, a scattering or a null
            // collision) a surface nearer than the self-intersection epsilon
            // still counts; from a surface, the epsilon keeps the ray off it.
            let hit = if on_surface {
                scene.geometry.intersect(pos, dir, t_limit as f32)
            } else {
                scene
                    .geometry
                    .intersect_from_point(pos, dir, t_limit as f32)
            };
            on_surface = false;
            if let Some(h) = hit {
                scratch.flown += h.t as f64;
                scratch.absorb(&self.kappa);
                pos = h.position;
                let Some(next) = self.at_floor(&h, rng, scratch, out) else {
                    return;
                };
                dir = next;
                pos += h.normal * 1e-4;
                on_surface = true;
                events += 1;
                if !Self::survive(&mut scratch.w, events, self.importance(dir), rng) {
                    return;
                }
            } else if t_surface <= t_limit {
                scratch.flown += t_surface;
                scratch.absorb(&self.kappa);
                let next = pos + dir * t_surface as f32;
                pos = Vec3::new(next.x, next.y, 0.0);
                if let Some(p) = domain.image(pos) {
                    pos = p;
                }
                let Some(next) =
                    self.at_surface(dir, dispersive, rng, &mut scratch.w, scratch.target, out)
                else {
                    return;
                };
                dir = next;
                events += 1;
                if !Self::survive(&mut scratch.w, events, self.importance(dir), rng) {
                    return;
                }
            } else if t_edge <= t_limit {
                if !domain.periodic {
                    return;
                }
                scratch.flown += t_edge;
                pos = domain.wrap(pos + dir * t_edge as f32, dir);
                if scene.under_floor(pos) {
                    // A seam where the floor does not meet itself: its
                    // step is a wall the path ends at, as in emission.
                    return;
                }
                continue;
            } else {
                // A tentative collision.
                scratch.flown += t_flight;
                pos += dir * t_flight as f32;
                match self.at_collision(pos, dir, &mut events, rng, scratch, out) {
                    Collided::Null => {
                        // Water that does not scatter (b = 0) meets only
                        // null collisions, and without a floor below a
                        // path through it never ends: the absorption
                        // carried by weight is applied once it may have
                        // taken a factor e, and the path plays roulette.
                        if scratch.flown * self.kappa_max >= 1.0 {
                            scratch.absorb(&self.kappa);
                            let late = events.max(ROULETTE_AFTER);
                            if !Self::survive(&mut scratch.w, late, self.importance(dir), rng) {
                                return;
                            }
                        }
                        continue;
                    }
                    Collided::Scattered(next) => dir = next,
                    Collided::End => return,
                }
            }
            scratch.split(
                PathState {
                    pos,
                    dir,
                    events,
                    on_surface,
                },
                self.split_above,
            );
        }
    }
}

/// Add light `x` of band `b` to `out`: to its own band, or to the sensor
/// band `target` an inelastic event fixed (light of excitation band `b` feeds
/// it).
#[inline]
fn add(out: &mut [f64], target: Option<usize>, b: usize, x: f64) {
    out[target.unwrap_or(b)] += x;
}

/// Multiply the band throughputs `w` by their absorption `kappa` (1/m)
/// over the distance `flown`, and set it to 0.
fn absorb(w: &mut [f64], kappa: &[f64], flown: &mut f64) {
    if *flown > 0.0 {
        for (x, k) in w.iter_mut().zip(kappa) {
            *x *= (-k * *flown).exp();
        }
        *flown = 0.0;
    }
}

/// The throughput-weighted share of pure-water scattering among the bands'
/// scattering, `q` of the scattering mixture (`1 - q` is the particles').
fn water_share(w: &[f64], iops: &[Iop]) -> f64 {
    let (mut sw, mut sp) = (0.0, 0.0);
    for (x, iop) in w.iter().zip(iops) {
        let bb = iop.b();
        if bb > 0.0 {
            sw += x * iop.b_w / bb;
            sp += x * iop.b_p / bb;
        }
    }
    if sw + sp > 0.0 {
        sw / (sw + sp)
    } else {
        0.0
    }
}

/// 1 - cos of the angle between unit vectors, from |a - b|^2 / 2: near the
/// forward peak a cosine has too few digits.
fn one_minus(a: Vec3, b: Vec3) -> f64 {
    0.5 * (a - b).length_squared() as f64
}

#[cfg(test)]
mod tests;
