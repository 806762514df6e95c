//! Radiance estimates from the photon map, with the paper's boundary- and
//! spectral-bias compensations.
//!
//! Volume (in-scattered) radiance toward the viewer at x:
//!   L_i(x, w) = sum over photons p of band i of p(w_p, w) Phi_p / V,
//! where photons were stored at real scattering events, so the density
//! already carries the scattering coefficient (Jensen 2001); p is the local
//! mixture phase function (b_w p_w + b_p p_p) / b, with its forward peak
//! taken out as a delta (`estimate::peak`). Surface radiance leaving a
//! Lambertian floor or target: L_i = sum f_r Phi_p / A with f_r = R_i / pi,
//! over photons near the tangent plane that arrived from the water side.
//! The search is k nearest within a maximum radius (or a fixed radius);
//! V and A follow the boundary mode (`estimate::boundary`), and the band
//! estimates are combined with a larger search by the spectral mode
//! (`estimate::spectral`). In volume estimates the photons travelling
//! toward the viewer are counted at the larger scale
//! (`estimate::spectral::combine_with_coarse`): through the forward lobe a
//! few of them carry much of the in-scatter, too few in a search of k. In
//! the `grid` mode they are searched apart, in their own map layer (volume
//! photons are layered by the sign of their vertical travel,
//! `photon::volume_layer`): the `k` nearest of the other layer at the local
//! scale, the `k_expanded` nearest of theirs at the expanded scale. The
//! `naive` and `compensated` modes keep the poster's single search over
//! both layers, whose k nearest are the local search and whose photons
//! travelling into the viewer's hemisphere are counted at the larger
//! scale.
//!
//! Not for: direct light (the renderer adds single scattering of the sun
//! and direct sun on the floor by next-event estimation).

use super::peak::{MixedPhase, TruncatedPhase};
use crate::error::Result;
use crate::estimate::boundary::{self, AxialDistances, BoundaryGrid, BoundaryMode, DiscDistances};
use crate::estimate::groups::{GroupSums, Groups, CHANNELS, GROUPS};
use crate::estimate::shape::{
    direction_bin, BandShapeGrid, GridPlan, DIRECTION_BINS, VIEW_DOWN, VIEW_UP, VIEW_UP_TARGET,
};
use crate::estimate::spectral::{
    combine, combine_with_coarse, combine_with_shape, BandSums, SpectralMode,
};
use crate::geometry::SurfaceId;
use crate::optics::inelastic::{Absorbers, Inelastic, Kind};
use crate::optics::iop::Iop;
use crate::optics::phase::PhaseFunction;
use crate::photon::{LAYER_SURFACE, LAYER_VOLUME, LAYER_VOLUME_UP, VOLUME_LAYERS};
use crate::scene::Scene;
use crate::store::query::{Neighbour, PhotonQuery, Search};
use glam::Vec3;
use std::cell::RefCell;

mod search;

/// Surface photons count within this fraction of the search radius (plus
/// 5 mm) of the tangent plane: off-plane photons are on another surface
/// (a target's side, the far side of a thin panel). Photons of such a
/// surface within the tolerance of a junction count on both.
pub const PLANE_TOLERANCE: f32 = 0.02;

/// Reusable per-thread buffers of an estimate.
pub struct Scratch {
    bands: usize,
    mix: Vec<f32>,
    iops: Vec<Iop>,
    found: Vec<Neighbour>,
    part: Vec<Neighbour>,
    extra: Vec<Neighbour>,
    local: BandSums,
    expanded: BandSums,
    coarse: BandSums,
    shape: Vec<f64>,
    group_local: GroupSums,
    group_coarse: GroupSums,
    group_expanded: GroupSums,
    shape_groups: Vec<f64>,
    /// An oblique estimate's found photons' weights per direction bin, at
    /// the local and the expanded scale, then the bins' weights as views
    /// of the grid; one bin's shares and group parts while mixing.
    bin_sums: [[f64; DIRECTION_BINS]; 2],
    bin_views: Vec<(usize, f64)>,
    bin_shape: Vec<f64>,
    /// Inelastic light: the found photons' weights through the Raman
    /// phase function, the isotropic one (fluorescence) and the elastic
    /// one, per band, at the local scale and at the expanded one
    /// (`INELASTIC_*` order); then each band's density of the first two
    /// (`phase_density`) and of the elastic one.
    inelastic: [BandSums; 6],
    phase_density: [Vec<f64>; 2],
    elastic_density: Vec<f64>,
    inelastic_out: Vec<f64>,
    /// The water's absorbers at the estimate's point (fluorescence).
    parts: Vec<Absorbers>,
    /// Prefix sums over the bands of the Raman, isotropic and elastic
    /// densities, and each band's elastic radiance times a process's
    /// strength (`add_inelastic`).
    prefix: [Vec<f64>; 3],
    source_in: Vec<f64>,
}

/// A found photon's weight toward the viewer (power times the phase
/// function), whether it travels toward the viewer's hemisphere, and its
/// weights through the Raman and the isotropic phase functions (inelastic
/// light; zero without it). A type parameter of the estimate, not a
/// `dyn`, so that it is inlined into the loop over the photons (the
/// default render 3 % faster).
pub(super) trait PhotonWeight: Fn(&Neighbour) -> (f64, bool, [f64; 2]) {}

impl<F: Fn(&Neighbour) -> (f64, bool, [f64; 2])> PhotonWeight for F {}

/// Slots of `Scratch::inelastic` at one scale: Raman phase, isotropic,
/// elastic; the expanded scale's follow at `+ INELASTIC_SLOTS`.
pub(super) const INELASTIC_SLOTS: usize = 3;

impl Scratch {
    pub fn new(bands: usize) -> Self {
        Scratch {
            bands,
            mix: Vec::new(),
            iops: Vec::new(),
            found: Vec::new(),
            part: Vec::new(),
            extra: Vec::new(),
            local: BandSums::new(bands),
            expanded: BandSums::new(bands),
            coarse: BandSums::new(bands),
            shape: vec![0.0; bands],
            group_local: GroupSums::new(bands),
            group_coarse: GroupSums::new(bands),
            group_expanded: GroupSums::new(bands),
            shape_groups: vec![0.0; GROUPS * bands],
            bin_sums: [[0.0; DIRECTION_BINS]; 2],
            bin_views: Vec::with_capacity(DIRECTION_BINS),
            bin_shape: Vec::new(),
            inelastic: std::array::from_fn(|_| BandSums::new(bands)),
            phase_density: [vec![0.0; bands], vec![0.0; bands]],
            elastic_density: vec![0.0; bands],
            inelastic_out: vec![0.0; bands],
            parts: vec![Absorbers::default(); bands],
            prefix: std::array::from_fn(|_| Vec::with_capacity(bands + 1)),
            source_in: Vec::with_capacity(bands),
        }
    }
}

/// Radiance estimates over one photon map for one scene.
pub struct Estimator<'a> {
    pub scene: &'a Scene,
    pub map: &'a dyn PhotonQuery,
    pub boundary: BoundaryMode,
    pub spectral: SpectralMode,
    /// Phase functions with the forward peak truncated, for photon weights
    /// (see `peak`).
    /// [water, particle] for rays looking up or sideways, for rays
    /// looking down, and for rays looking down at a target.
    phases: [MixedPhase; 3],
    /// Precomputed axial distances, when the scene asks for them.
    grid: Option<BoundaryGrid>,
    /// Band shapes of the `grid` spectral mode.
    shapes: Option<BandShapeGrid>,
    /// The IOPs jump at depth boundaries (layers): volume photons are
    /// weighted by the ratio of scattering at the site to theirs.
    layered: bool,
    /// Inelastic light, when the scene has it (see [`Estimator::add_inelastic`]).
    pub inelastic: Option<&'a Inelastic>,
    /// The Raman phase function (photon weights for the Raman source).
    raman_phase: PhaseFunction,
    /// The sun's direction of travel under a flat surface, for the
    /// direction bins of the band shapes ([`direction_bin`]).
    sun_w: Vec3,
}

/// Which band shape of the grid an estimate takes: one viewing direction's,
/// or for an oblique ray the direction bins' weighed by the found photons'
/// weights toward it.
#[derive(Clone, Copy)]
pub(super) enum ShapeView {
    Fixed(usize),
    Binned,
}

/// Rays looking up within 3 degrees of the vertical take the shapes for a
/// ray looking straight up: the refracted sun is 20-40 degrees off the
/// vertical, where the truncated peak's edge weighs its aureole most, so a
/// ray looking up a little toward it weighs the light already otherwise.
const FIXED_UP_COS: f32 = 0.9986;

/// Most voxels of a band-shape grid, and most bytes, its target columns
/// and the layers of IOP jumps included (the budget charges
/// [`Estimator::shape_grid_bytes`]; the built-in scene's grid, with its
/// two targets' columns, holds 39 MiB).
const MAX_SHAPE_VOXELS: usize = 32_768;
pub const MAX_SHAPE_BYTES: u64 = 48 << 20;

/// Distances the boundary grid stores (m): far enough that the field stays
/// linear next to a gently sloping floor (see `BoundaryGrid::build`).
const GRID_MAX_DISTANCE_M: f64 = 30.0;

impl<'a> Estimator<'a> {
    pub fn new(scene: &'a Scene, map: &'a dyn PhotonQuery) -> Result<Self> {
        let (boundary, spectral) = (scene.estimate.boundary, scene.estimate.spectral);
        let grid = match (boundary, scene.estimate.boundary_grid_m) {
            (BoundaryMode::None, _) | (_, None) => None,
            (_, Some(h)) => Some(BoundaryGrid::build(
                scene,
                h as f32,
                Self::grid_max_distance(scene),
            )?),
        };
        let mut est = Estimator {
            scene,
            map,
            boundary,
            spectral,
            grid,
            shapes: None,
            layered: scene.water.is_layered(),
            inelastic: scene.inelastic.as_ref(),
            raman_phase: crate::optics::inelastic::raman_phase(),
            sun_w: {
                let d = scene.sun.direction.as_dvec3();
                crate::optics::surface::refract(d, glam::DVec3::Z, 1.0, scene.surface.n_water)
                    .unwrap_or(glam::DVec3::NEG_Z)
                    .as_vec3()
            },
            phases: [
                scene.estimate.forward_peak_deg,
                scene.estimate.forward_peak_down_deg,
                scene.estimate.forward_peak_target_deg,
            ]
            .map(|deg| {
                MixedPhase::new(
                    TruncatedPhase::new(&scene.water_phase, deg),
                    TruncatedPhase::new(&scene.particle_phase, deg),
                )
            }),
        };
        if spectral == SpectralMode::Grid {
            let boundaries = scene.water.depth_boundaries();
            let plan = Self::shape_plan(
                scene,
                VOLUME_LAYERS.map(|l| map.layer_photons(l)),
                &boundaries,
            );
            let shapes = BandShapeGrid::build(map, &plan, &|p: &crate::photon::Photon, view| {
                est.shape_weight(p, view)
            })?;
            est.shapes = Some(shapes);
        }
        Ok(est)
    }

    /// The phase weight of photon `p` toward a viewer straight above
    /// ([`VIEW_UP`], and [`VIEW_UP_TARGET`] looking down at a target) or
    /// below ([`VIEW_DOWN`]), as a volume estimate there weighs it: the
    /// local mixture of the truncated phase functions.
    fn shape_weight(&self, p: &crate::photon::Photon, view: usize) -> f64 {
        let base = Self::fixed_views(self.scene);
        if view >= base {
            return f64::from(u8::from(
                direction_bin(p.direction, self.sun_w) == view - base,
            ));
        }
        let toward_viewer = if view == VIEW_DOWN { -Vec3::Z } else { Vec3::Z };
        let iop = self.scene.water.iop(p.position, p.band as usize);
        let b = iop.b();
        let fw = if b > 0.0 { iop.b_w / b } else { 0.0 };
        let cos = p.direction.dot(toward_viewer) as f64;
        self.mixed_for(toward_viewer, view == VIEW_UP_TARGET)
            .mix(fw, cos)
    }

    /// Fixed viewing directions of the band-shape grid: light travelling
    /// up and down, and a third, light travelling up as rays looking down at a
    /// target weigh it, in a scene with targets whose peak for those rays
    /// (`forward_peak_target_deg`) differs from the one looking down.
    fn fixed_views(scene: &Scene) -> usize {
        let e = &scene.estimate;
        if scene.target_extents.is_empty() || e.forward_peak_target_deg == e.forward_peak_down_deg {
            2
        } else {
            3
        }
    }

    /// Viewing directions of the band-shape grid: [`Self::fixed_views`],
    /// then one per direction bin for oblique rays.
    fn shape_views(scene: &Scene) -> usize {
        Self::fixed_views(scene) + DIRECTION_BINS
    }

    /// The band shape for an estimate toward `toward_viewer`: the fixed
    /// view's for rays looking down and for rays looking up near the
    /// vertical, the direction bins' for other rays looking up (the
    /// final-gather rays off a target's top face).
    ///
    /// Rays looking down keep the fixed view at every angle: with the
    /// bins, a cosine-weighted radiometer 1 m deep looking down over the
    /// lower hemisphere (Chl 1 water, 4 M photons) read its green and red
    /// bands 3-16 % above the path integrator, with the fixed view within
    /// its 3 sigma + 2 %. The upwelling light's shape varies within the
    /// bins' wide elevation bands more than with the viewing angle.
    fn shape_for(&self, toward_viewer: Vec3, at_target: bool) -> ShapeView {
        let z = toward_viewer.z;
        if z >= 0.0 || z <= -FIXED_UP_COS {
            ShapeView::Fixed(self.shape_view(toward_viewer, at_target))
        } else {
            ShapeView::Binned
        }
    }

    /// The band-shape grid's view for an estimate toward `toward_viewer`
    /// (`at_target`: a ray looking down at a target).
    fn shape_view(&self, toward_viewer: Vec3, at_target: bool) -> usize {
        match (toward_viewer.z > 0.0, at_target) {
            (false, _) => VIEW_DOWN,
            (true, true) if Self::fixed_views(self.scene) > VIEW_UP_TARGET => VIEW_UP_TARGET,
            (true, _) => VIEW_UP,
        }
    }

    /// Voxels of the band-shape grid over a map of `volume_photons` volume
    /// photons ([down, up] layers): about `shape_photons_per_band` photons
    /// per band and voxel at `POLICY_PHOTONS` traced photons, that count
    /// growing as the square root of the photons traced, so that both the
    /// voxels' size and their noise shrink as photons are added. Photons of
    /// the up layer count as 1 / `upward_split` photon each: the copies of a
    /// split path refine the grid's upwelling light, not its resolution;
    /// so do those of paths split over targets (`Scene::target_split_gain`).
    fn shape_voxels(scene: &Scene, [down, up]: [u64; 2]) -> usize {
        let nb = scene.bands.len();
        let one = GridPlan {
            size_m: scene.domain.size_m,
            voxels: 1,
            layers_only: true,
            boundaries_m: &[],
            columns: &[],
            views: Self::shape_views(scene),
        };
        let by_bytes = (MAX_SHAPE_BYTES / BandShapeGrid::bytes(&one, nb)) as usize;
        let growth = (scene.photons as f64 / crate::scene::settings::POLICY_PHOTONS)
            .sqrt()
            .max(1.0);
        let per_band = (scene.estimate.shape_photons_per_band as f64 * growth).round() as usize;
        let photons = ((down + up / scene.upward_split.max(1) as u64) as f64
            / scene.target_split_gain())
        .round() as u64;
        BandShapeGrid::planned_voxels(photons, nb, per_band, MAX_SHAPE_VOXELS.min(by_bytes))
    }

    /// The band-shape grid of `scene` over a map of `volume_photons`
    /// volume photons ([down, up] layers), its layers ending at the depths
    /// `boundaries` where the IOPs jump and its cells at the targets'
    /// footprints.
    fn shape_plan<'s>(
        scene: &'s Scene,
        volume_photons: [u64; 2],
        boundaries: &'s [f64],
    ) -> GridPlan<'s> {
        let mut plan = GridPlan {
            size_m: scene.domain.size_m,
            voxels: Self::shape_voxels(scene, volume_photons),
            layers_only: scene.horizontally_uniform(),
            boundaries_m: boundaries,
            columns: &scene.target_extents,
            views: Self::shape_views(scene),
        };
        // The cap holds with the columns and the jumps' layers: fewer even
        // voxels first, then (a scene of very many targets) the columns of
        // the last targets go, whose light then shares the even cells.
        let nb = scene.bands.len();
        while plan.voxels > 1 && BandShapeGrid::bytes(&plan, nb) > MAX_SHAPE_BYTES {
            plan.voxels = (plan.voxels * 7 / 8).max(1);
        }
        while !plan.columns.is_empty() && BandShapeGrid::bytes(&plan, nb) > MAX_SHAPE_BYTES {
            plan.columns = &plan.columns[..plan.columns.len() - 1];
        }
        plan
    }

    /// Target columns the band-shape grid of `scene` holds over a map of
    /// `volume_photons` volume photons (fewer than its targets when the
    /// byte cap leaves no room for all).
    pub fn shape_grid_columns(scene: &Scene, volume_photons: [u64; 2]) -> usize {
        let boundaries = scene.water.depth_boundaries();
        Self::shape_plan(scene, volume_photons, &boundaries)
            .columns
            .len()
    }

    /// Bytes of the band-shape grid `Estimator::new` builds for `scene` over
    /// a map of `volume_photons` volume photons ([down, up] layers; 0
    /// unless `spectral = "grid"`), for the memory budget.
    pub fn shape_grid_bytes(scene: &Scene, volume_photons: [u64; 2]) -> u64 {
        match scene.estimate.spectral {
            SpectralMode::Grid => {
                let boundaries = scene.water.depth_boundaries();
                let plan = Self::shape_plan(scene, volume_photons, &boundaries);
                BandShapeGrid::bytes(&plan, scene.bands.len())
            }
            _ => 0,
        }
    }

    /// The band-shape grid's cells along x, y and layers along z, when the
    /// `grid` mode built one.
    pub fn shape_grid_dims(&self) -> Option<[usize; 3]> {
        self.shapes.as_ref().map(|g| g.dims())
    }

    fn grid_max_distance(scene: &Scene) -> f32 {
        GRID_MAX_DISTANCE_M.max(scene.estimate.largest_radius_m()) as f32
    }

    /// Bytes of the boundary grid `Estimator::new` would build for `scene`
    /// (0 without one), for the memory budget.
    pub fn grid_bytes(scene: &Scene) -> Result<u64> {
        match scene.estimate.boundary_grid_m {
            Some(h) if scene.estimate.boundary != BoundaryMode::None => Ok(
                BoundaryGrid::planned_bytes(scene, h as f32, Self::grid_max_distance(scene))?
                    as u64,
            ),
            _ => Ok(0),
        }
    }

    /// The truncated [water, particle] phase functions for light leaving
    /// toward the viewer along `toward_viewer` (a ray looking down sees
    /// light travelling up); `at_target`: a ray looking down at a target
    /// (`forward_peak_target_deg`).
    fn phases_for(&self, toward_viewer: Vec3, at_target: bool) -> &[TruncatedPhase; 2] {
        self.mixed_for(toward_viewer, at_target).parts()
    }

    /// The two of [`Self::phases_for`] as one mixture.
    fn mixed_for(&self, toward_viewer: Vec3, at_target: bool) -> &MixedPhase {
        let i = match (toward_viewer.z > 0.0, at_target) {
            (false, _) => 0,
            (true, false) => 1,
            (true, true) => 2,
        };
        &self.phases[i]
    }

    /// The fractions of pure-water and particle scattering that the
    /// truncated phase functions leave in the forward delta along a ray
    /// looking along `view` (`at_target`: see [`Self::volume_with_iops`]):
    /// it is marched with extinction c - f_w b_w - f_p b_p.
    pub fn forward_fractions(&self, view: Vec3, at_target: bool) -> (f64, f64) {
        let [w, p] = self.phases_for(-view, at_target);
        (w.forward_fraction(), p.forward_fraction())
    }

    /// The truncated particle phase function along a ray looking along
    /// `view`, whose forward delta `render::march` scatters into explicitly.
    pub fn particle_peak(&self, view: Vec3, at_target: bool) -> &TruncatedPhase {
        &self.phases_for(-view, at_target)[1]
    }

    /// In-scattered radiance per band at `x` toward the viewer, for light
    /// leaving x along `toward_viewer` (W m^-3 sr^-1 nm^-1; integrate along
    /// the ray). `out` has one entry per band, or [`CHANNELS`] runs of
    /// bands: the radiance, then each photon group's part of it
    /// (`estimate::groups`).
    pub fn volume(
        &self,
        x: Vec3,
        toward_viewer: Vec3,
        scratch: &mut Scratch,
        out: &mut [f64],
    ) -> Result<()> {
        let mut iops = std::mem::take(&mut scratch.iops);
        iops.resize(self.scene.bands.len(), Iop::default());
        self.scene.water.iops(x, &mut iops);
        let r = self.volume_with_iops(x, toward_viewer, false, 1.0, &iops, scratch, out);
        scratch.iops = iops;
        r
    }

    /// [`Estimator::volume`] with the IOPs at `x` (one per band) given;
    /// `at_target`: the viewer looks down at a target, and the phase
    /// functions' forward peak is `forward_peak_target_deg` wide (and the
    /// band shapes of the `grid` mode weigh the photons alike). The
    /// searches take `share` (in (0, 1]) of the scene's photons, k and
    /// k_expanded, within the cube root of that share of its radii: a
    /// march whose light has faded asks less of an estimate that weighs
    /// little in its pixel (`render::march::steps::search_share`).
    #[allow(clippy::too_many_arguments)]
    pub fn volume_with_iops(
        &self,
        x: Vec3,
        toward_viewer: Vec3,
        at_target: bool,
        share: f64,
        iops: &[Iop],
        scratch: &mut Scratch,
        out: &mut [f64],
    ) -> Result<()> {
        // The mixture weights of the two phase functions at x, per band.
        scratch.mix.clear();
        scratch.mix.extend(iops.iter().map(|iop| {
            let total = iop.b();
            if total > 0.0 {
                (iop.b_w / total) as f32
            } else {
                0.0
            }
        }));
        let mix = std::mem::take(&mut scratch.mix);
        let phases = self.mixed_for(toward_viewer, at_target);
        // Where the IOPs jump (depth layers), a photon stored at a
        // scattering event counts at x as the light field there, not as
        // its own water's scattering: weighted by b(x) / b(x_p), the
        // density of scattering events becomes a density of light, which
        // is continuous across the jump, and the search no longer carries
        // one layer's scattering into the other.
        let jumps = self.layered;
        let water = &self.scene.water;
        let inelastic = self.inelastic.is_some();
        // The Raman phase function only where Raman scattering is on.
        let raman_phase = self
            .inelastic
            .and_then(|i| i.process(Kind::Raman))
            .map(|_| &self.raman_phase);
        let weight = |n: &Neighbour| -> (f64, bool, [f64; 2]) {
            let band = n.photon.band as usize;
            let fw = mix[band] as f64;
            let cos = n.photon.direction.dot(toward_viewer) as f64;
            let power = n.photon.power as f64;
            let mut w = phases.mix(fw, cos) * power;
            // Through the Raman phase function and the isotropic one.
            let mut phases = if inelastic {
                [
                    raman_phase.map_or(0.0, |p| p.eval(cos) * power),
                    power / (4.0 * std::f64::consts::PI),
                ]
            } else {
                [0.0; 2]
            };
            if jumps {
                let there = water.scattering(n.photon.position, band);
                let k = if there > 0.0 {
                    iops[band].b() / there
                } else {
                    0.0
                };
                w *= k;
                phases.iter_mut().for_each(|p| *p *= k);
            }
            (w, cos > 0.0, phases)
        };
        let view = Some(self.shape_for(toward_viewer, at_target));
        let classes = if self.shapes.is_some() {
            // Light travelling toward the viewer looking down travels up.
            let (light, heavy) = if toward_viewer.z > 0.0 {
                (LAYER_VOLUME, LAYER_VOLUME_UP)
            } else {
                (LAYER_VOLUME_UP, LAYER_VOLUME)
            };
            Classes::Split { light, heavy }
        } else {
            Classes::Union(&VOLUME_LAYERS)
        };
        let r = self.estimate(x, classes, &weight, None, view, share, scratch, out);
        scratch.mix = mix;
        r?;
        self.add_inelastic(x, iops, scratch, out);
        Ok(())
    }

    /// Add the diffuse inelastic source at `x` to the elastic in-scatter
    /// `out`, from the densities `estimate` left in `scratch`.
    ///
    /// Emission moves photons between bands, so the map holds the light
    /// that Raman scattering and fluorescence moved wherever it went on;
    /// what the estimates add is the inelastic source itself, J_m = sum_k
    /// sum_e c_k(x, e) T_k(e, m) ∫ p_k L_e (the excitation bands' light
    /// scattered or re-emitted toward the viewer; `optics::inelastic`).
    /// The direct sun's part is added in closed form by the march
    /// ([`Self::inelastic_sun`]); the diffuse part comes from the elastic
    /// in-scatter estimate of each excitation band e, b_e ∫ p L_e, divided
    /// by b_e and carried from the elastic phase function to the process's
    /// (Raman, or isotropic for fluorescence) by the ratio of the found
    /// photons' weights through both, pooled over the run of bands that
    /// feed m (from the first to the last):
    /// a ratio of two sums over the same photons, so the band shapes of
    /// the `grid` mode serve the inelastic source too, and one band's few
    /// photons do not make it noisy.
    fn add_inelastic(&self, x: Vec3, iops: &[Iop], scratch: &mut Scratch, out: &mut [f64]) {
        let Some(inelastic) = self.inelastic else {
            return;
        };
        let Scratch {
            phase_density,
            elastic_density,
            inelastic_out,
            parts,
            prefix,
            source_in,
            ..
        } = scratch;
        if inelastic.fluoresces() {
            self.scene.water.absorbers(x, parts);
        }
        // Prefix sums of the densities over the bands (each row's bands
        // are one run of them), so that a row's pooled ratio costs two
        // lookups.
        let nb = self.scene.bands.len();
        for (k, v) in [&phase_density[0], &phase_density[1], &*elastic_density]
            .into_iter()
            .enumerate()
        {
            let p = &mut prefix[k];
            p.resize(nb + 1, 0.0);
            p[0] = 0.0;
            for e in 0..nb {
                p[e + 1] = p[e] + v[e];
            }
        }
        inelastic_out.iter_mut().for_each(|o| *o = 0.0);
        for p in &inelastic.processes {
            // ∫ p L_e from the elastic estimate, times the strength.
            source_in.clear();
            source_in.extend((0..nb).map(|e| {
                let b = iops[e].b();
                if b > 0.0 {
                    p.strength(&parts[e]) * out[e] / b
                } else {
                    0.0
                }
            }));
            let density = &prefix[phase_slot(p.kind)];
            let elastic = &prefix[2];
            for (m, row) in p.rows.iter().enumerate() {
                let (Some(&(first, _)), Some(&(last, _))) = (row.first(), row.last()) else {
                    continue;
                };
                let den = elastic[last + 1] - elastic[first];
                if den > 0.0 {
                    let num = density[last + 1] - density[first];
                    let sum: f64 = row.iter().map(|&(e, c)| c * source_in[e]).sum();
                    inelastic_out[m] += sum * num / den;
                }
            }
        }
        for (o, r) in out.iter_mut().zip(inelastic_out.iter()) {
            *o += r;
        }
    }

    /// Make `x` the point [`Self::inelastic_sun`] reads the water's
    /// absorbers at, as a volume estimate there would (a march piece
    /// without an estimate of its own).
    pub fn absorbers_at(&self, x: Vec3, scratch: &mut Scratch) {
        if self.inelastic.is_some_and(|i| i.fluoresces()) {
            self.scene.water.absorbers(x, &mut scratch.parts);
        }
    }

    /// The direct sun's inelastic source toward a viewer (per band, into
    /// `out`) at the point of the last volume estimate made with
    /// `scratch`, or of the last [`Self::absorbers_at`]: `m_ss` is 1 - cos
    /// of the angle between the sun's beam and the direction toward the
    /// viewer, `e_w[e] t[e]` the beam's irradiance there in band e (in
    /// the water, times its transmittance).
    pub fn inelastic_sun(
        &self,
        m_ss: f64,
        e_w: &[f64],
        t: &[f64],
        scratch: &mut Scratch,
        out: &mut [f64],
    ) {
        out.iter_mut().for_each(|o| *o = 0.0);
        let Some(inelastic) = self.inelastic else {
            return;
        };
        for p in &inelastic.processes {
            let phase = p.phase.eval_one_minus_cos(m_ss);
            let Scratch {
                parts, source_in, ..
            } = &mut *scratch;
            source_in.clear();
            source_in.extend((0..e_w.len()).map(|e| p.strength(&parts[e]) * e_w[e] * t[e]));
            let beam = &*source_in;
            for (o, row) in out.iter_mut().zip(&p.rows) {
                *o += phase * row.iter().map(|&(e, c)| c * beam[e]).sum::<f64>();
            }
        }
    }

    /// Radiance per band leaving a Lambertian surface at `x` with unit
    /// normal `normal` (facing the water) from the surface photon map.
    /// Photons count when they lie near the tangent plane (within
    /// [`PLANE_TOLERANCE`] of the search radius, plus 5 mm) and arrived from
    /// the water side; the search disc is clipped where the surface ends
    /// (the waterline, targets standing on it, open domain walls).
    pub fn surface(
        &self,
        x: Vec3,
        normal: Vec3,
        surface: SurfaceId,
        scratch: &mut Scratch,
        out: &mut [f64],
    ) -> Result<()> {
        let scene = self.scene;
        let weight = |n: &Neighbour| -> (f64, bool, [f64; 2]) {
            // Only light arriving on this side of the surface counts.
            if n.photon.direction.dot(normal) >= 0.0 {
                return (0.0, false, [0.0; 2]);
            }
            let r = scene.reflectance(surface, x, n.photon.band as usize);
            (
                r / std::f64::consts::PI * n.photon.power as f64,
                false,
                [0.0; 2],
            )
        };
        self.estimate(
            x,
            Classes::Union(&[LAYER_SURFACE]),
            &weight,
            Some((normal, surface)),
            None,
            1.0,
            scratch,
            out,
        )
    }
}

/// Which photons an estimate searches, and at which scale.
#[derive(Clone, Copy)]
enum Classes<'l> {
    /// One search over the union of these layers.
    Union(&'l [u16]),
    /// The `k` nearest of `light` at the local scale and the `k_expanded`
    /// nearest of `heavy` at the expanded scale: volume estimates of the
    /// grid mode, where the heavy layer holds the photons travelling toward
    /// the viewer.
    Split { light: u16, heavy: u16 },
}

/// The search region of an estimate: a sphere or a disc with its boundary
/// distances.
#[derive(Clone, Copy)]
enum Region {
    Volume(AxialDistances),
    Disc(DiscDistances),
}

impl Region {
    /// The region of a smaller search of radius `r`.
    fn capped(&self, r: f32) -> Region {
        match self {
            Region::Volume(b) => Region::Volume(b.capped(r)),
            Region::Disc(d) => Region::Disc(d.capped(r)),
        }
    }

    fn accepts(&self, mode: BoundaryMode, offset: Vec3, r: f32) -> bool {
        match self {
            Region::Volume(b) => mode.accepts(offset, r, b),
            Region::Disc(d) => mode.accepts_in_disc(offset, r, d),
        }
    }

    /// Volume (m^3) or area (m^2).
    fn size(&self, mode: BoundaryMode, r: f32) -> f64 {
        match self {
            Region::Volume(b) => mode.volume(r, b),
            Region::Disc(d) => mode.area(r, d),
        }
    }
}

thread_local! {
    static SCRATCH: RefCell<Option<Scratch>> = const { RefCell::new(None) };
}

impl crate::parallel::BandScratch for Scratch {
    fn for_bands(bands: usize) -> Self {
        Scratch::new(bands)
    }
    fn bands(&self) -> usize {
        self.bands
    }
}

/// Run `f` with this thread's scratch for `bands` bands.
pub fn with_scratch<R>(bands: usize, f: impl FnOnce(&mut Scratch) -> R) -> R {
    crate::parallel::with_band_scratch(&SCRATCH, bands, f)
}

/// The slot of `Scratch::phase_density` a process's phase function reads.
fn phase_slot(kind: Kind) -> usize {
    match kind {
        Kind::Raman => 0,
        Kind::Chlorophyll | Kind::Cdom => 1,
    }
}
