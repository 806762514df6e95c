//! The sensor above the surface (`[sensor] altitude_m` under an
//! `[atmosphere]`): the radiance at the sensor from the radiance leaving
//! the surface, by either integrator, and the air between.
//!
//! For a camera ray meeting the ground at P along the view (unit `toward`
//! the sensor, cosine mu_v), per band b:
//!
//! ```text
//! L_t = L_path + T_b L(P) + (light leaving the surface elsewhere and
//!       scattered into the view)
//! ```
//!
//! - **L_path**, the light scattered into the view that never reached the
//!   surface, is the same for every pixel of an orthographic sensor over a
//!   horizontally uniform atmosphere: computed once per band when the
//!   scene is read ([`crate::scene::ViewLight`],
//!   `optics::atmosphere::transport::path_radiance`).
//! - **T_b L(P)**: the direct transmittance exp(-tau_b / mu_v) times the
//!   integrator's radiance leaving P toward the sensor, exactly.
//! - **The scattered part**, by an adjoint path from the sensor: a
//!   collision along the view is drawn from the bands' mean extinction (the
//!   pilot), then directions from the pilot's phase mixture and free paths
//!   from its extinction, each band weighted by its own scattering,
//!   transmittance and phase over the pilot's (ratios bounded by the small
//!   optical depths of air), until the path leaves the top or meets the
//!   ground at P', where the integrator's radiance leaving P' along the
//!   path is added with the band's weight. Horizontal positions wrap into
//!   the domain. Light leaving the water near P reaches the sensor through
//!   the air this way: the adjacency effect comes out of the transport.
//!
//! **Control variate for the scattered part.** One adjoint path per sample
//! meets the ground in a fifth of the samples and sees there whatever the
//! surface sends its way, sun glint included: at one sample per pixel that
//! part alone was 30 % noise at the top of the atmosphere. So before the
//! tiles, the render estimates the mean radiance leaving the surface per
//! direction cell of the sky grid, sun glint taken out (up to
//! `ENV_SAMPLES` integrator calls per cell at random points of the domain,
//! at most an eighth of the image's samples), and the
//! scattered part of a table of that plus the exact glint from many
//! adjoint paths (`POOLED_PATHS`, no integrator call). Each pixel's path
//! then adds that mean plus its own difference W (L(P') - table - glint):
//! unbiased whatever the table holds, with the glint's and the sky's
//! sampling noise and the water's mean taken out of the pixel's variance.
//!
//! **Land in the domain** (`[land]`) is far brighter than the water, so
//! a table of the domain's mean leaves the paths that meet the beach with
//! large differences. With land the table is kept per class, one over the
//! water (where the glint is taken out) and one over the land, each from
//! points of its own class; the pooled part keeps the water's. Each
//! sample then sends [`SURROUND_PATHS`] adjoint paths: those that meet the
//! land add their class's table less the water's (a lookup), and one path,
//! drawn uniformly and counting for all, adds its difference from its own
//! class's table by an integrator call. Unbiased whatever the tables hold;
//! the land's share of the view is averaged over the paths instead of
//! carried by one.
//!
//! **Water by the depth of its floor.** Over a sloping floor the water
//! itself is far from one class: in the red, water over sand half a
//! metre down leaves ten times the radiance of water 4 m deep. So the
//! water is split into classes by the depth of its floor (`air::classes`),
//! each with its own table; the water's table is their mean weighted by
//! area, and the land is one more class. Within a class the radiance still
//! changes tenfold over the shallowest (floors 0–0.5 m at 750 nm), so each
//! class is cut into [`classes::BINS`] bins of depth, and the control at
//! a point is its class's table times its bin's factor per band, both
//! fitted to the table's calls (`table::fit_bins`). Any control is
//! unbiased as long as the lookups and the call use the same one; this
//! one cut the built-in scene's deep-water L_t noise from 3 km from 0.51
//! to 0.23 % at 750 nm and from 0.56 to 0.36 % at 649 nm: a path from
//! deep water that met the shallows added up to a third of the pixel's
//! L_t at 750 nm through its difference from a table of the whole
//! class.
//!
//! **Surroundings.** Beyond the domain a path sees Lambertian land
//! (`kind = "lambertian"`), deep water of its own IOPs (`kind =
//! "water"`: that sea's own table, from path-integrator calls on the
//! scene with its water replaced, plus the glint) or the domain's mean.
//!
//! The light the surface sends up that the air returns down to it is in
//! the sky at the surface: over the sea by `render::sea_air`, over a
//! Lambertian ground by `optics::atmosphere::transport::ground_response`.

use super::camera::CameraRay;
use super::Integrator;
use crate::error::Result;
use crate::optics::atmosphere::transport::{cell_of, CELLS};
use crate::optics::atmosphere::Column;
use crate::rng::Pcg32;
use crate::scene::{Scene, ViewLight};
use glam::DVec3;

/// Height above the surface (or above the land's top) of the rays handed
/// to the integrator (m).
pub(crate) const RAY_HEIGHT_M: f64 = 10.0;

/// Draws of a point of one class (land or water) before the table takes
/// whatever point it has: the table's values do not bias the pixel.
const CLASS_TRIES: u32 = 1 << 20;

/// A path's largest band weight below which it plays Russian roulette.
const ROULETTE: f64 = 0.1;

/// Integrator calls per direction cell for the mean radiance leaving the
/// surface, at most; fewer for a small image (`ENV_SHARE`).
pub const ENV_SAMPLES: u64 = 16;

/// The table's integrator calls are at most this share of the image's
/// samples (at least one per cell): the built-in 256 x 256 image gets 16
/// per cell (8 % more calls), a 4 x 4 one 1 per cell.
const ENV_SHARE: f64 = 1.0 / 8.0;

/// Adjoint paths for the scattered part of the mean radiance leaving the
/// surface.
pub const POOLED_PATHS: u64 = 400_000;

/// Adjoint paths per camera sample with surroundings: those that meet the
/// ground beyond the domain cost a lookup, and at most one of those within
/// it an integrator call.
pub const SURROUND_PATHS: usize = 16;

/// The integrator calls of the air view (its tables, and a sample's call
/// for a path landing within the domain) march with steps this many
/// times the scene's (`Integrator::camera_coarse`): their results are
/// corrections weighted by the light the air scatters, averaged over
/// many; the camera's own rays keep the scene's step. The built-in scene
/// from 3 km, whole run: 68.3 s against 78.2 s with the scene's step
/// (two pairs), band means within 5e-5 of each other, deep-water pixel
/// noise within 0.02 points; 8 times the step saved 1.4 s more for more
/// noise in the blue.
pub const CALL_STEPS: f32 = 4.0;

/// Streams of the table's and the pooled paths' randoms.
const ENV_KEY: u64 = 0x656e_765f_7461_626c;
const POOLED_KEY: u64 = 0x706f_6f6c_6564_5f70;
const LAND_KEY: u64 = 0x6c61_6e64_5f74_6162;
const SEA_KEY: u64 = 0x7365_615f_6265_796f;

/// Path-integrator calls per direction cell for the radiance leaving
/// water surroundings: the table is what the air sees beyond the domain
/// (not a control variate), the same for every pixel, so it is given more
/// calls than the domain's own.
const SEA_SAMPLES: u64 = 64;

/// The air between the ground and a sensor above it.
pub struct AirView<'s> {
    scene: &'s Scene,
    view: &'s ViewLight,
    columns: &'s [Column],
    pilot: Column,
    /// Per layer and band: the band's scattering optical depth over the
    /// pilot's extinction, and its Rayleigh share (band-major within the
    /// layer).
    scatter_ratio: Vec<f64>,
    share: Vec<f64>,
    /// Per layer: the pilot's Rayleigh share of scattering.
    pilot_share: Vec<f64>,
    /// The aerosol's phase function differs between bands (a named
    /// model's Mie tables), so each band evaluates its own.
    aerosol_varies: bool,
    toward: DVec3,
    altitude_km: f64,
    /// Per direction cell and band (cell-major): the mean radiance leaving
    /// the surface, sun glint taken out (with land in the domain: the
    /// water's); the water classes' tables weighted by their area.
    env: Vec<f64>,
    /// The ground's classes within the domain.
    classes: Classes,
    /// Per water class: its table as `env`.
    water_env: Vec<Vec<f64>>,
    /// Per water class: its depth bins' factors per band (bin-major,
    /// `classes::BINS` bins), by which a point's table is scaled.
    water_bins: Vec<Vec<f64>>,
    /// The same for the land in the domain; empty without land.
    land_env: Vec<f64>,
    /// The land's share of the domain (0 without land).
    land_share: f64,
    /// Height above z = 0 of the rays handed to the integrator (m).
    ray_height_m: f64,
    /// Per band: the scattered part the table and the glint give, and its
    /// standard error (from the chunks' spread).
    pooled: Vec<f64>,
    pooled_se: Vec<f64>,
    /// The ground beyond the domain; none for a periodic domain.
    surround: Option<Surround>,
    /// With surroundings: the adjoint paths shared by every sample.
    shared: Option<Shared>,
}

/// A sample's parts of the radiance at the sensor, per band.
pub struct AirSample {
    /// The radiance leaving the surface at the ground point, before the
    /// air.
    pub at_surface: Vec<f64>,
    /// What every sample at its ground point adds alike: the path
    /// radiance, the pooled part and the shared paths' mean lookup.
    pub known: Vec<f64>,
    /// The variance of the known part's estimate.
    pub known_var: Vec<f64>,
}

impl AirSample {
    /// Parts for `nb` bands.
    pub fn new(nb: usize) -> AirSample {
        AirSample {
            at_surface: vec![0.0; nb],
            known: vec![0.0; nb],
            known_var: vec![0.0; nb],
        }
    }
}

/// An adjoint path that met the ground within the domain: where, its
/// direction of travel and its band weights.
type Landing = (DVec3, DVec3, Vec<f64>);

/// What an adjoint path that meets the ground beyond the domain sees.
enum Surround {
    /// Land: its radiance per band (R E / pi).
    Land(Vec<f64>),
    /// The table's mean radiance per direction plus the glint.
    Mean,
    /// Deep water: its own table of the mean radiance leaving it per
    /// direction cell and band (cell-major, glint taken out), plus the
    /// glint.
    Water(Vec<f64>),
}

impl<'s> AirView<'s> {
    /// The air of `scene` for the integrator `light`, none unless its
    /// sensor has an altitude: the mean radiance leaving the surface and
    /// its scattered part are estimated here (in parallel on the current
    /// pool, the same for any number of threads).
    pub fn new(scene: &'s Scene, light: &dyn Integrator) -> Result<Option<AirView<'s>>> {
        let Some(mut air) = Self::air(scene) else {
            return Ok(None);
        };
        let shares = air.classes.water_share.clone();
        let water: f64 = shares.iter().sum();
        let nb = air.columns.len();
        let mut env = vec![0.0; CELLS * nb];
        for (k, share) in shares.iter().enumerate() {
            let (table, factors) = air.environment(light, Class::Water(k))?;
            let weight = if water > 0.0 {
                share / water
            } else {
                1.0 / shares.len() as f64
            };
            env.iter_mut()
                .zip(&table)
                .for_each(|(e, t)| *e += weight * t);
            air.water_env[k] = table;
            air.water_bins[k] = factors;
        }
        air.env = env;
        if air.land_share > 0.0 {
            air.land_env = air.environment(light, Class::Land)?.0;
        }
        if let Some(crate::scene::Surroundings::Water(sea)) = &scene.surroundings {
            let beyond = super::path::PathTracer::new(sea);
            let table = air.table(&beyond, None, SEA_SAMPLES, SEA_KEY)?.table;
            air.surround = Some(Surround::Water(table));
        }
        if !matches!(air.surround, Some(Surround::Land(_) | Surround::Water(_))) {
            (air.pooled, air.pooled_se) = air.pooled();
        }
        air.shared = air.surround.as_ref().map(|s| air.shared(s, scene.seed));
        Ok(Some(air))
    }

    /// The bytes the air view of `scene` holds (0 without one): its
    /// tables, the grid of classes and the shared paths it keeps.
    pub fn reserve_bytes(scene: &'s Scene) -> u64 {
        let Some(air) = Self::air(scene) else {
            return 0;
        };
        let nb = air.columns.len() as u64;
        let table = CELLS as u64 * nb * 8;
        // The water's classes and the land's; the water's mean, the sea's
        // and what the shared paths see beyond.
        let tables = air.classes.waters() as u64 + 1 + 3;
        // Each water class's depth factors.
        let factors = air.classes.waters() as u64 * BINS as u64 * nb * 8;
        let shared = if air.surround.is_some() {
            air.shared_kept() * (8 * nb + 20)
        } else {
            0
        };
        tables * table + factors + air.classes.bytes() + shared
    }

    /// The air alone, before its tables.
    fn air(scene: &'s Scene) -> Option<AirView<'s>> {
        let a = scene.atmosphere.as_deref()?;
        let view = a.view.as_ref()?;
        let columns = &a.columns[..];
        let pilot = Column::mean(columns);
        let classes = Classes::new(scene);
        let nl = pilot.layers.len();
        let nb = columns.len();
        let mut scatter_ratio = vec![0.0; nl * nb];
        let mut share = vec![0.0; nl * nb];
        let mut pilot_share = vec![0.0; nl];
        for i in 0..nl {
            let t = pilot.layers[i].tau();
            for (b, c) in columns.iter().enumerate() {
                let l = &c.layers[i];
                let s = l.rayleigh + l.aerosol_scattering;
                scatter_ratio[i * nb + b] = if t > 0.0 { s / t } else { 0.0 };
                share[i * nb + b] = l.rayleigh_share();
            }
            pilot_share[i] = pilot.layers[i].rayleigh_share();
        }
        Some(AirView {
            scene,
            view,
            columns,
            pilot,
            scatter_ratio,
            share,
            pilot_share,
            aerosol_varies: a.spec.aerosol.is_some_and(|x| x.named.is_some()),
            toward: scene.sensor.toward.as_dvec3().normalize(),
            altitude_km: view.altitude_m * 1e-3,
            env: vec![0.0; CELLS * nb],
            water_env: vec![vec![0.0; CELLS * nb]; classes.waters()],
            water_bins: vec![vec![1.0; BINS * nb]; classes.waters()],
            land_env: Vec::new(),
            land_share: classes.land_share,
            classes,
            ray_height_m: RAY_HEIGHT_M
                + scene
                    .land
                    .as_ref()
                    .map_or(0.0, |l| f64::from(l.top_m.max(0.0))),
            pooled: vec![0.0; nb],
            pooled_se: vec![0.0; nb],
            // Water surroundings get their table in `new`.
            surround: scene.surroundings.as_ref().map(|s| match s.reflectance() {
                Some(r) => Surround::Land(super::ground::lambertian_radiance(scene, r)),
                None => Surround::Mean,
            }),
            shared: None,
        })
    }

    /// The sun glint per band leaving the surface toward `up` (unit).
    fn glint(&self, up: DVec3, out: &mut [f64]) {
        out.iter_mut().for_each(|o| *o = 0.0);
        // A Lambertian ground has none.
        if up.z > 0.0 && self.scene.ground.is_none() {
            super::air_sea::add_glint(self.scene, up.as_vec3(), out);
        }
    }

    /// The direction cell of `up` (unit, leaving the surface).
    fn cell(&self, up: DVec3) -> usize {
        let phi = up.y.atan2(up.x) - self.scene.sun.azimuth_rad;
        cell_of(up.z, phi)
    }

    /// A point of the domain at random of class `class` (`None`: of the
    /// water), by rejection.
    fn point_of_class(&self, rng: &mut Pcg32, sx: f64, sy: f64, class: Option<Class>) -> DVec3 {
        let mut tries = 0;
        loop {
            let at = DVec3::new(rng.uniform_f64() * sx, rng.uniform_f64() * sy, 0.0);
            tries += 1;
            let of = match class {
                Some(class) => self.class_of(at) == class,
                None => !self.on_land(at),
            };
            if of || tries >= CLASS_TRIES {
                return at;
            }
        }
    }

    /// The class of the ground at `meet` within the domain: the land, or
    /// the water's class by the depth of its floor.
    fn class_of(&self, meet: DVec3) -> Class {
        self.classes.of(meet)
    }

    /// True where a path meeting the ground at `meet` takes the land's
    /// table.
    fn on_land(&self, meet: DVec3) -> bool {
        self.land_share > 0.0 && self.class_of(meet) == Class::Land
    }

    /// The ray handed to the integrator for the radiance leaving the
    /// ground at `at` toward `up`: from above the land's top.
    fn ray_to(&self, at: DVec3, up: DVec3) -> CameraRay {
        ray_from_above(at, up, self.ray_height_m)
    }

    /// The sun glint per band leaving the ground at `at` toward `up`: none
    /// on land.
    fn glint_at(&self, at: DVec3, up: DVec3, out: &mut [f64]) {
        if self.on_land(at) {
            out.iter_mut().for_each(|o| *o = 0.0);
        } else {
            self.glint(up, out);
        }
    }

    /// The control for a path meeting the ground at `meet` within the
    /// domain toward `up`, per band: its class's table (over the water,
    /// times its depth bin's factor) plus, over the water, the glint there
    /// (`glint` is scratch).
    fn control(&self, meet: DVec3, up: DVec3, glint: &mut [f64], out: &mut [f64]) {
        let nb = self.columns.len();
        let c = self.cell(up);
        match self.classes.at(meet) {
            (Class::Land, _) => out.copy_from_slice(&self.land_env[c * nb..(c + 1) * nb]),
            (Class::Water(k), j) => {
                self.glint(up, glint);
                let (t, h) = (&self.water_env[k], &self.water_bins[k]);
                for b in 0..nb {
                    out[b] = t[c * nb + b] * h[j * nb + b] + glint[b];
                }
            }
        }
    }

    /// The control's excess over the pooled part's (the water's table
    /// plus the glint) for a path meeting the ground at `meet` toward
    /// `up`, per band: within the domain, its class's table (over the
    /// water, times its depth bin's factor) less the water's (with the
    /// glint over the land); beyond it, for mean
    /// surroundings, the land's share of that.
    fn excess(&self, meet: DVec3, up: DVec3, inside: bool, glint: &mut [f64], out: &mut [f64]) {
        out.iter_mut().for_each(|o| *o = 0.0);
        let nb = self.columns.len();
        let c = self.cell(up);
        let (share, table) = match (inside, inside.then(|| self.classes.at(meet))) {
            (false, _) => (self.land_share, &self.land_env),
            (true, Some((Class::Water(k), j))) => {
                let (t, h, e) = (&self.water_env[k], &self.water_bins[k], &self.env);
                for b in 0..nb {
                    out[b] = t[c * nb + b] * h[j * nb + b] - e[c * nb + b];
                }
                return;
            }
            (true, _) => (1.0, &self.land_env),
        };
        if share == 0.0 {
            return;
        }
        self.glint(up, glint);
        for b in 0..nb {
            out[b] = share * (table[c * nb + b] - self.env[c * nb + b] - glint[b]);
        }
    }

    /// Per band: the scattered part of the mean radiance leaving the
    /// surface (the same for every pixel) and its standard error.
    pub fn pooled_part(&self) -> (&[f64], &[f64]) {
        (&self.pooled, &self.pooled_se)
    }

    /// The part of a sample's radiance at the sensor `l_t` that its paths
    /// through the air drew, per band: `l_t` less the radiance leaving
    /// the ground point times the direct transmittance and the part known
    /// alike for every sample there (`sample`, from [`AirView::camera`]).
    /// Its spread is the air paths' noise.
    pub fn drawn_part(&self, l_t: &[f64], sample: &AirSample, out: &mut [f64]) {
        for (b, o) in out.iter_mut().enumerate() {
            *o = l_t[b] - self.view.transmittance[b] * sample.at_surface[b] - sample.known[b];
        }
    }

    /// The radiance at the sensor along camera ray `ray` (which meets the
    /// ground at its pixel's ground point) into `out` (every channel run of
    /// `light`), the water-leaving radiance at that ground point into
    /// `water`, and its parts into `sample`.
    pub fn camera(
        &self,
        light: &dyn Integrator,
        ray: CameraRay,
        rng: &mut Pcg32,
        out: &mut [f64],
        water: &mut [f64],
        sample: &mut AirSample,
    ) -> Result<()> {
        let nb = self.columns.len();
        light.camera(ray, rng, out, water)?;
        sample.at_surface.copy_from_slice(&out[..nb]);
        for (k, o) in out.iter_mut().enumerate() {
            *o *= self.view.transmittance[k % nb];
        }
        sample.known_var.iter_mut().for_each(|v| *v = 0.0);
        for (b, k) in sample.known.iter_mut().enumerate() {
            *k = self.view.path_radiance[b] + self.pooled[b];
        }
        let ground = ray.origin.as_dvec3()
            + ray.direction.as_dvec3() * (f64::from(ray.origin.z) / -f64::from(ray.direction.z));
        if let Some(shared) = &self.shared {
            // The shared paths' mean lookup, and one of the sample's own
            // paths within the domain for the integrator call.
            let mut mean = vec![0.0; nb];
            self.lookup(
                shared,
                ground,
                Lookup {
                    mean: &mut mean,
                    var: &mut sample.known_var,
                },
            );
            sample
                .known
                .iter_mut()
                .zip(&mean)
                .for_each(|(k, m)| *k += m);
            for (o, k) in out.iter_mut().zip(&sample.known) {
                *o += k;
            }
            let within = self.landings(ground, rng, |_, _, _, _| {})?;
            return self.add_one_within(light, &within, rng, out);
        }
        for (o, k) in out.iter_mut().zip(&sample.known) {
            *o += k;
        }
        if self.land_share > 0.0 {
            return self.by_class(light, ground, rng, out);
        }
        let (mut glint, mut excess) = (vec![0.0; nb], vec![0.0; nb]);
        self.adjoint(ground, rng, |rng, meet, dir, w| {
            self.excess(meet, -dir, true, &mut glint, &mut excess);
            for b in 0..nb {
                out[b] += w[b] * excess[b];
            }
            self.add_difference(light, meet, dir, w, 1.0, rng, out)
        })
    }

    /// Add to `out`, times `scale`, the band weights `w` times the
    /// difference between the integrator's radiance leaving the ground at
    /// `meet` along the direction of travel `dir` reversed and the control
    /// there, its class's table plus the glint (channel 0; the photon
    /// groups' parts as they are).
    #[allow(clippy::too_many_arguments)]
    fn add_difference(
        &self,
        light: &dyn Integrator,
        meet: DVec3,
        dir: DVec3,
        w: &[f64],
        scale: f64,
        rng: &mut Pcg32,
        out: &mut [f64],
    ) -> Result<()> {
        let nb = self.columns.len();
        let up = -dir;
        let ray = self.ray_to(meet, up);
        let (mut tmp, mut water, mut glint) = (vec![0.0; out.len()], vec![0.0; nb], vec![0.0; nb]);
        light.camera_coarse(ray, CALL_STEPS, rng, &mut tmp, &mut water)?;
        let mut control = vec![0.0; nb];
        self.control(meet, up, &mut glint, &mut control);
        for (k, (o, t)) in out.iter_mut().zip(&tmp).enumerate() {
            let b = k % nb;
            let mean = if k < nb { control[b] } else { 0.0 };
            *o += scale * w[b] * (t - mean);
        }
        Ok(())
    }

    /// [`SURROUND_PATHS`] adjoint paths from the sensor to the ground point
    /// `ground`: each that meets the ground goes to `at(where, direction
    /// of travel, band weights, within the domain)`, in order, and those
    /// within the domain are returned.
    fn landings(
        &self,
        ground: DVec3,
        rng: &mut Pcg32,
        mut at: impl FnMut(DVec3, DVec3, &[f64], bool),
    ) -> Result<Vec<Landing>> {
        let [sx, sy] = self.scene.domain.size_m;
        let mut within = Vec::new();
        for _ in 0..SURROUND_PATHS {
            self.adjoint(ground, rng, |_, meet, dir, w| {
                let inside = (0.0..sx).contains(&meet.x) && (0.0..sy).contains(&meet.y);
                at(meet, dir, w, inside);
                if inside {
                    within.push((meet, dir, w.to_vec()));
                }
                Ok(())
            })?;
        }
        Ok(within)
    }

    /// One of the paths `within` the domain, drawn uniformly and counting
    /// for all of them (each path counting 1 / [`SURROUND_PATHS`]), adds
    /// its difference from the table by an integrator call.
    fn add_one_within(
        &self,
        light: &dyn Integrator,
        within: &[Landing],
        rng: &mut Pcg32,
        out: &mut [f64],
    ) -> Result<()> {
        if within.is_empty() {
            return Ok(());
        }
        let (meet, dir, w) = &within[rng.below(within.len() as u32) as usize];
        let scale = within.len() as f64 / SURROUND_PATHS as f64;
        self.add_difference(light, *meet, *dir, w, scale, rng, out)
    }

    /// The scattered part over a periodic domain with land in it (`out`
    /// already holds the pooled part, the water's table and the glint over
    /// every path):
    /// [`SURROUND_PATHS`] adjoint paths, each counting 1 / N, of which
    /// those that meet the land add its table's excess over the water's
    /// (beyond the domain, the land's share of it), and one of those
    /// within, drawn uniformly and counting for all of them, adds its
    /// difference from its own class's table by an integrator call.
    /// Unbiased, at most one call per sample, and only the paths that land
    /// within the domain carry its spatial variance within each class.
    fn by_class(
        &self,
        light: &dyn Integrator,
        ground: DVec3,
        rng: &mut Pcg32,
        out: &mut [f64],
    ) -> Result<()> {
        let nb = self.columns.len();
        let share = 1.0 / SURROUND_PATHS as f64;
        let (mut glint, mut excess) = (vec![0.0; nb], vec![0.0; nb]);
        let within = self.landings(ground, rng, |meet, dir, w, inside| {
            self.excess(meet, -dir, inside, &mut glint, &mut excess);
            for b in 0..nb {
                out[b] += share * w[b] * excess[b];
            }
        })?;
        self.add_one_within(light, &within, rng, out)
    }

    /// One adjoint path from the sensor down its view to the pixel whose
    /// ground point is `ground`: where it meets the ground after scattering
    /// in the air, `at_ground(rng, point, direction of travel, band
    /// weights)`.
    fn adjoint(
        &self,
        ground: DVec3,
        rng: &mut Pcg32,
        mut at_ground: impl FnMut(&mut Pcg32, DVec3, DVec3, &[f64]) -> Result<()>,
    ) -> Result<()> {
        let nb = self.columns.len();
        let pilot = &self.pilot;
        let total = pilot.total();
        let mu_v = self.toward.z;
        let z_s = self.altitude_km.min(pilot.layers[0].top_km);
        let d_s = pilot.depth_at(z_s);
        // The first collision along the view, down from the sensor.
        let d_c = d_s + rng.exp1() * mu_v;
        if d_c >= total {
            return Ok(());
        }
        let mut z = pilot.height_at(d_c);
        let mut w = vec![0.0; nb];
        let i = pilot.layer_index(z);
        for (b, wb) in w.iter_mut().enumerate() {
            let c = &self.columns[b];
            let excess = (c.depth_at(z) - c.depth_at(z_s)) - (d_c - d_s);
            *wb = self.scatter_ratio[i * nb + b] * (-excess / mu_v).exp();
        }
        let mut pos = ground + self.toward * (z * 1e3 / mu_v);
        let mut dir = -self.toward;
        let mut layer = i;
        loop {
            // Scatter: a direction from the pilot's phase mixture.
            let s = self.pilot_share[layer];
            let column = &self.columns[0];
            let phase = if rng.uniform_f64() < s {
                &column.rayleigh_phase
            } else {
                &column.aerosol_phase
            };
            let cos = phase.sample_cos(rng.uniform_f64());
            let phi = std::f64::consts::TAU * rng.uniform_f64();
            let next = crate::optics::phase::scatter(dir.as_vec3(), cos as f32, phi as f32)
                .as_dvec3()
                .normalize();
            let cos = dir.dot(next);
            let pr = column.rayleigh_phase.eval(cos);
            let pa = column.aerosol_phase.eval(cos);
            let p_pilot = s * pr + (1.0 - s) * pa;
            for (b, wb) in w.iter_mut().enumerate() {
                let sb = self.share[layer * nb + b];
                // Each band's own Rayleigh phase (its q) and share.
                let c = &self.columns[b];
                let pa = if self.aerosol_varies {
                    c.aerosol_density(cos)
                } else {
                    pa
                };
                let pb = sb * c.rayleigh_phase.eval(cos) + (1.0 - sb) * pa;
                *wb *= pb / p_pilot;
            }
            dir = next;
            let largest = w.iter().copied().fold(0.0, f64::max);
            if largest < ROULETTE {
                let q = largest / ROULETTE;
                if rng.uniform_f64() >= q {
                    return Ok(());
                }
                w.iter_mut().for_each(|v| *v /= q);
            }
            if dir.z.abs() < 1e-9 {
                // Level: it never reaches the ground nor the top.
                return Ok(());
            }
            // Fly.
            let d_here = pilot.depth_at(z);
            let step = rng.exp1() * dir.z.abs();
            let d_next = if dir.z < 0.0 {
                d_here + step
            } else {
                d_here - step
            };
            if dir.z >= 0.0 && d_next <= 0.0 {
                return Ok(());
            }
            if dir.z < 0.0 && d_next >= total {
                // The ground, at the pilot's no-collision probability.
                let mu = -dir.z;
                for (b, wb) in w.iter_mut().enumerate() {
                    let c = &self.columns[b];
                    let excess = (c.total() - c.depth_at(z)) - (total - d_here);
                    *wb *= (-excess / mu).exp();
                }
                let meet = pos + dir * (z * 1e3 / mu);
                let meet = if self.surround.is_some() {
                    DVec3::new(meet.x, meet.y, 0.0)
                } else {
                    self.wrap(meet)
                };
                return at_ground(rng, meet, dir, &w);
            }
            let z_next = pilot.height_at(d_next);
            let next_layer = pilot.layer_index(z_next);
            for (b, wb) in w.iter_mut().enumerate() {
                let c = &self.columns[b];
                let excess = (c.depth_at(z_next) - c.depth_at(z)).abs() - (d_next - d_here).abs();
                *wb *= self.scatter_ratio[next_layer * nb + b] * (-excess / dir.z.abs()).exp();
            }
            pos += dir * ((z_next - z).abs() * 1e3 / dir.z.abs());
            z = z_next;
            layer = next_layer;
        }
    }

    /// `p` moved into the domain horizontally (the air is the same
    /// everywhere; the domain repeats for light that travels through it).
    fn wrap(&self, p: DVec3) -> DVec3 {
        let [sx, sy] = self.scene.domain.size_m;
        DVec3::new(p.x.rem_euclid(sx), p.y.rem_euclid(sy), 0.0)
    }
}

/// The ground's class within the domain.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Class {
    Land,
    /// The water's class by the depth of its floor, shallowest first.
    Water(usize),
}

mod classes;
mod shared;
mod table;
use classes::{Classes, BINS};
use shared::{Lookup, Shared};
pub(crate) use table::leaving_table;
use table::ray_from_above;

#[cfg(test)]
mod tests;
