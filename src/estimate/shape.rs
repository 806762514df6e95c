//! A coarse 3-D grid of band shapes, accumulated from every volume photon
//! of the map in one streaming pass: the spectral half of the `grid`
//! spectral mode.
//!
//! **Why.** A radiance estimate's band shape from a k-nearest search rests
//! on k / N photons per band, fewer still once the phase function's forward
//! lobe has weighted them (a handful carry most of the in-scatter). Here the
//! level comes from the local search (all bands) and the band shape from
//! the same phase-weighted in-scatter summed over every photon of the
//! voxels around x, tens of thousands of them:
//!
//! ```text
//! L_i(x, v) = L(x, v) s_i(x, v),   s_i = S_i / sum_j S_j,
//! S_i = sum over band-i photons of the voxel of p(w_p . v) Phi_p
//! ```
//!
//! with the estimator's own (truncated) phase weights toward two viewing
//! directions: light travelling up (seen by a sensor looking down) and
//! light travelling down (seen looking up); an estimate takes the one on
//! its side. Shapes are interpolated bilinearly between the centres of
//! the horizontal cells; in depth each band follows its own exponential
//! profile across the layer holding x (see [`Profile`]), so that a
//! voxel's shares, means over a layer, become the shares at x.
//!
//! **Voxels.** Horizontal cells are even over the domain; vertical layers
//! hold equal numbers of photons (the light crowds toward the surface).
//! The number of voxels follows the photon count so that a voxel holds
//! about `photons_per_band` photons per band (the estimator grows that
//! count as the square root of the photons traced): the grid refines and
//! its noise falls as photons are added, which keeps the estimate
//! consistent. Bounded by `max_voxels` (a fixed share of memory).
//!
//! **Noise.** Each voxel also keeps the linearised part of each photon
//! group in its shares, (S_{g,i} - s_i S_g) / S (see `estimate::groups`),
//! so that the shape's own photon noise enters the standard error of an
//! estimate, correlated as it is over the voxel.
//!
//! Not for: the level of an estimate (the k-nearest search), surface
//! estimates (the floor's band shape is the reflectance times the
//! incident light, which the expanded search gives well).

use crate::bounds::Aabb;
use crate::error::Result;
use crate::photon::VOLUME_LAYERS;
use crate::store::PhotonQuery;
use glam::Vec3;

/// Vertical histogram bins for the equal-count layers.
const Z_BINS: usize = 4096;
/// Narrowest column of cells over a target (m): the light a ray looking
/// down at a target weighs comes from 30 degrees and more off its axis,
/// from around a small target as much as from it, and a narrower column
/// holds too few photons for steady shapes.
const MIN_COLUMN_M: f32 = 2.0;
/// Most depth layers of a grid.
const MAX_LAYERS: usize = 64;

/// Band shapes of the in-scatter toward the two viewing directions, per voxel.
pub struct BandShapeGrid {
    bands: usize,
    /// Viewing directions: [`VIEW_UP`], [`VIEW_DOWN`] and, in a scene
    /// whose rays looking down at a target truncate the phase functions'
    /// forward peak otherwise, [`VIEW_UP_TARGET`].
    views: usize,
    /// Cells along x and y (from 0), layers along the depth (from the
    /// surface down, so that every axis ascends).
    axes: [Axis; 3],
    /// Columns over the targets' footprints, each a stack of the grid's
    /// layers after the even cells' voxels, holding the photons inside it.
    columns: Vec<Column>,
    /// Per voxel (x fastest, then y, then z) and viewing direction: the
    /// band shares (sum 1), or all zero where no photon fell.
    shapes: Vec<f32>,
    /// Per voxel, viewing direction, group and band: the group's part of
    /// the shares.
    deviations: Vec<f32>,
    /// Per voxel, viewing direction and band: the rate x at which the
    /// band's weight falls across the layer, as exp(-x tau) at the
    /// fraction tau of the layer's thickness, and the log of the profile's
    /// scale (see [`Profile`]).
    rates: Vec<Profile>,
}

use crate::photon::GROUPS;

/// Direction bins of the shapes for oblique rays (see
/// [`direction_bin`]).
pub const DIRECTION_BINS: usize = 9;

/// Cosines of the angles from the refracted sun's direction (8, 16, 28 and
/// 45 degrees) that bound the bins of light travelling down around it.
const SUN_BIN_COS: [f32; 4] = [
    0.990_27,
    0.961_26,
    0.882_95,
    std::f32::consts::FRAC_1_SQRT_2,
];

/// The bin of a photon travelling along `dir` (unit), for the band shapes
/// of oblique rays: light travelling down in four cones around the
/// refracted sun's direction of travel `sun_w` (the aureole, whose band
/// shape at depth differs most from the diffuse light's), then steep and
/// shallow; light travelling up in three bands of elevation.
///
/// Why: the viewing directions above weigh the photons for a ray looking
/// straight up or down. A ray looking up elsewhere (a final-gather ray off
/// a target's face) weighs other photons most, and with the vertical
/// shapes a target 3 m deep read its face's red bands 3–6 % high, the
/// green 2 % low (the vertical view looking up weighs the
/// aureole's red-rich light, which a gather ray near the sun leaves to its
/// forward peak). For such a ray the estimate weighs each bin's shape by
/// its own photons' weights toward the ray
/// ([`BandShapeGrid::mixed_shape_and_groups_at`]).
pub fn direction_bin(dir: Vec3, sun_w: Vec3) -> usize {
    if dir.z < 0.0 {
        let c = dir.dot(sun_w);
        match SUN_BIN_COS.iter().position(|&b| c >= b) {
            Some(i) => i,
            None if dir.z < -0.5 => 4,
            None => 5,
        }
    } else if dir.z < 0.5 {
        6
    } else if dir.z < 0.87 {
        7
    } else {
        8
    }
}

/// The shape of light travelling up, seen by a ray looking down.
pub const VIEW_UP: usize = 0;
/// The shape of light travelling down, seen by a ray looking up.
pub const VIEW_DOWN: usize = 1;
/// The shape of light travelling up as a ray looking down at a target
/// weighs it (`forward_peak_target_deg`): a wider truncated peak weighs
/// the light travelling nearly straight up less, and its band shape
/// differs (with the other truncation's shapes, a 2 m box 5.5 m deep in
/// Chl 10 water read its blue and red bands 4–5 % low, the green 1–3 %
/// high).
pub const VIEW_UP_TARGET: usize = 2;

impl BandShapeGrid {
    /// Voxels (both hemispheres) a grid over `volume_photons` photons of
    /// `bands` bands would have.
    pub fn planned_voxels(
        volume_photons: u64,
        bands: usize,
        photons_per_band: usize,
        max_voxels: usize,
    ) -> usize {
        let per_voxel = (photons_per_band * bands) as u64;
        ((volume_photons / per_voxel.max(1)) as usize).clamp(1, max_voxels.max(1))
    }

    /// Bytes of the grid `plan` describes over `bands` bands, at its peak
    /// while building (f64 sums per group and the bands' places, then the
    /// f32 shares, group parts and rates).
    pub fn bytes(plan: &GridPlan, bands: usize) -> u64 {
        let per =
            (GROUPS + 1) * std::mem::size_of::<f64>() + (2 + GROUPS) * std::mem::size_of::<f32>();
        (plan.most_cells() * plan.views * bands * per) as u64
    }

    /// Cells along x and y and layers along z for about `voxels` voxels,
    /// before target columns and IOP jumps add their edges.
    fn base_dims(voxels: usize, layers_only: bool) -> [usize; 3] {
        if layers_only {
            return [1, 1, voxels.clamp(1, MAX_LAYERS)];
        }
        let nz = ((voxels as f64).cbrt().round() as usize).clamp(1, MAX_LAYERS);
        let nxy = ((voxels as f64 / nz as f64).sqrt().round() as usize).max(1);
        [nxy, nxy, nz]
    }

    /// Build the grid `plan` describes from the volume photons of `map`;
    /// `weight(photon, view)` is a photon's phase weight toward a viewer
    /// in each of the plan's viewing directions ([`VIEW_UP`],
    /// [`VIEW_DOWN`], [`VIEW_UP_TARGET`]).
    pub fn build(
        map: &dyn PhotonQuery,
        plan: &GridPlan,
        weight: &(dyn Fn(&crate::photon::Photon, usize) -> f64 + Sync),
    ) -> Result<BandShapeGrid> {
        let GridPlan {
            size_m,
            voxels,
            layers_only,
            boundaries_m,
            columns,
            views,
        } = *plan;
        let bands = map.bands().len();
        // Pass 1: the depth distribution of the photons, below the surface
        // down to the deepest (from the map's index).
        let z_min = VOLUME_LAYERS
            .iter()
            .map(|&l| map.layer_bounds(l).min.z)
            .fold(f32::INFINITY, f32::min);
        let depth = if z_min.is_finite() { -z_min } else { 0.0 }.max(1e-3);
        let mut hist = vec![0u64; Z_BINS];
        let bin = |z: f32| (((-z / depth) * Z_BINS as f32) as usize).min(Z_BINS - 1);
        for layer in VOLUME_LAYERS {
            map.for_each_photon(layer, &mut |p| hist[bin(p.position.z)] += 1)?;
        }
        let total: u64 = hist.iter().sum();
        let [nxy, _, nz] = Self::base_dims(voxels, layers_only);
        // Equal-count layers, as depths from the surface down.
        let mut z_edges = vec![0.0f32];
        let mut acc = 0u64;
        let mut next = 1;
        for (i, h) in hist.iter().enumerate() {
            acc += h;
            while next < nz && acc * nz as u64 >= total * next as u64 {
                z_edges.push(depth * (i + 1) as f32 / Z_BINS as f32);
                next += 1;
            }
        }
        z_edges.push(depth);
        // Layers also end where the IOPs jump: an estimate reads only the
        // layer holding it, so shapes are not blended across such a depth.
        let jumps: Vec<f32> = boundaries_m
            .iter()
            .map(|&d| d as f32)
            .filter(|&d| d > 0.0 && d < depth)
            .collect();
        let columns = if layers_only { &[][..] } else { columns };
        let mut grid = BandShapeGrid {
            bands,
            views,
            axes: [
                Axis::across(size_m[0], nxy),
                Axis::across(size_m[1], nxy),
                Axis::new([z_edges, jumps].concat()),
            ],
            columns: columns.iter().map(|b| Column::over(b, size_m)).collect(),
            shapes: Vec::new(),
            deviations: Vec::new(),
            rates: Vec::new(),
        };
        // Pass 2: weighted power per voxel, viewing direction, group and band.
        let cells = grid.base_cells() + grid.columns.len() * grid.axes[2].cells();
        let per_voxel = GROUPS * bands;
        let mut sums = vec![0f64; cells * views * per_voxel];
        // And each band's weight times its place in the layer (0 at the
        // top, 1 at the bottom).
        let mut places = vec![0f64; cells * views * bands];
        for layer in VOLUME_LAYERS {
            map.for_each_photon(layer, &mut |p| {
                let v = grid.voxel_of(p.position);
                let tau = f64::from(grid.axes[2].place(-p.position.z));
                let g = p.group as usize % GROUPS;
                for h in 0..views {
                    let w = weight(p, h) * p.power as f64;
                    if w.is_finite() {
                        sums[(v * views + h) * per_voxel + g * bands + p.band as usize] += w;
                        places[(v * views + h) * bands + p.band as usize] += w * tau;
                    }
                }
            })?;
        }
        grid.shapes = vec![0.0; cells * views * bands];
        grid.deviations = vec![0.0; cells * views * per_voxel];
        grid.rates = vec![Profile::FLAT; cells * views * bands];
        let pools = rate_pools(map.bands().centers_nm());
        let mut band_sums = vec![0f64; bands];
        for (vh, by_group) in sums.chunks(per_voxel).enumerate() {
            band_sums.iter_mut().for_each(|s| *s = 0.0);
            for run in by_group.chunks(bands) {
                band_sums.iter_mut().zip(run).for_each(|(s, r)| *s += r);
            }
            let t: f64 = band_sums.iter().sum();
            if t <= 0.0 {
                continue;
            }
            let shape = &mut grid.shapes[vh * bands..][..bands];
            for (o, s) in shape.iter_mut().zip(&band_sums) {
                *o = (s / t) as f32;
            }
            let place = &places[vh * bands..][..bands];
            for (b, rate) in grid.rates[vh * bands..][..bands].iter_mut().enumerate() {
                let (lo, hi) = pools[b];
                let w: f64 = band_sums[lo..hi].iter().sum();
                if w > 0.0 {
                    *rate = Profile::new(rate_of_mean(place[lo..hi].iter().sum::<f64>() / w));
                }
            }
            let dev = &mut grid.deviations[vh * per_voxel..][..per_voxel];
            for (run, out) in by_group.chunks(bands).zip(dev.chunks_mut(bands)) {
                let t_g: f64 = run.iter().sum();
                for ((o, r), s) in out.iter_mut().zip(run).zip(&band_sums) {
                    *o = ((r - s / t * t_g) / t) as f32;
                }
            }
        }
        Ok(grid)
    }

    /// Cells along x and y and layers along z.
    pub fn dims(&self) -> [usize; 3] {
        self.axes.each_ref().map(Axis::cells)
    }

    /// Bytes held.
    pub fn heap_bytes(&self) -> u64 {
        ((self.shapes.len() + self.deviations.len() + 2 * self.rates.len())
            * std::mem::size_of::<f32>()) as u64
    }

    /// Target columns held.
    pub fn columns(&self) -> usize {
        self.columns.len()
    }

    fn base_cells(&self) -> usize {
        self.axes.iter().map(Axis::cells).product()
    }

    /// The column holding (x, y), if any (the first, where two overlap).
    fn column_of(&self, x: f32, y: f32) -> Option<usize> {
        self.columns.iter().position(|c| c.holds(x, y))
    }

    fn voxel_of(&self, p: Vec3) -> usize {
        let [ax, ay, az] = &self.axes;
        let layer = az.cell_of(-p.z);
        match self.column_of(p.x, p.y) {
            Some(c) => self.base_cells() + c * az.cells() + layer,
            None => (layer * ay.cells() + ay.cell_of(p.y)) * ax.cells() + ax.cell_of(p.x),
        }
    }

    /// The band shares at `x` of the in-scatter travelling up (`up`) or
    /// down, bilinear between the cells' centres (clamped at the edges)
    /// and along each band's profile within the layer holding x, into
    /// `out`; false where the voxels around x hold no weight.
    pub fn shape_at(&self, x: Vec3, up: bool, out: &mut [f64]) -> bool {
        let view = if up { VIEW_UP } else { VIEW_DOWN };
        self.shape_and_groups_at(x, view, out, None)
    }

    /// Viewing directions held.
    pub fn views(&self) -> usize {
        self.views
    }

    /// The band shares at `x` of light weighed by `weights`, pairs of a
    /// viewing direction (a [`direction_bin`]'s view) and its weight,
    /// into `out`, and with `groups` each photon group's part, both mixed
    /// alike; `scratch` holds a view's shares and group parts while
    /// mixing (`(1 + GROUPS) * bands` values). False where no view with
    /// weight holds shares around x.
    pub fn mixed_shape_and_groups_at(
        &self,
        x: Vec3,
        weights: &[(usize, f64)],
        out: &mut [f64],
        mut groups: Option<&mut [f64]>,
        scratch: &mut Vec<f64>,
    ) -> bool {
        let nb = self.bands;
        scratch.resize((1 + GROUPS) * nb, 0.0);
        let (one, one_groups) = scratch.split_at_mut(nb);
        out.iter_mut().for_each(|o| *o = 0.0);
        if let Some(g) = groups.as_deref_mut() {
            g.iter_mut().for_each(|o| *o = 0.0);
        }
        let mut total = 0.0;
        for &(view, w) in weights {
            if w <= 0.0 || !w.is_finite() {
                continue;
            }
            let with_groups = groups.is_some();
            if !self.shape_and_groups_at(x, view, one, with_groups.then_some(&mut *one_groups)) {
                continue;
            }
            total += w;
            out.iter_mut()
                .zip(one.iter())
                .for_each(|(o, s)| *o += w * s);
            if let Some(g) = groups.as_deref_mut() {
                g.iter_mut()
                    .zip(one_groups.iter())
                    .for_each(|(o, s)| *o += w * s);
            }
        }
        normalised(total, out, groups)
    }

    /// [`BandShapeGrid::shape_at`], and with `groups` (`GROUPS` runs of
    /// bands) each photon group's part of the shares, interpolated alike.
    pub fn shape_and_groups_at(
        &self,
        x: Vec3,
        view: usize,
        out: &mut [f64],
        mut groups: Option<&mut [f64]>,
    ) -> bool {
        let (h, views, nb) = (view, self.views, self.bands);
        debug_assert!(h < views);
        let [ax, ay, az] = &self.axes;
        let (nx, ny, nz) = (ax.cells(), ay.cells(), az.cells());
        // The layer holding x, where in it x lies, and its voxels around
        // x with their weights: in a target's column its own, elsewhere
        // the four even cells around it.
        let layer = az.cell_of(-x.z);
        let tau = f64::from(az.place(-x.z));
        let mut corners = [(0usize, 0.0f32); 4];
        match self.column_of(x.x, x.y) {
            Some(c) => corners[0] = (self.base_cells() + c * nz + layer, 1.0),
            None => {
                let (x0, x1, fx) = ax.bracket(x.x);
                let (y0, y1, fy) = ay.bracket(x.y);
                let mut i = 0;
                for (yi, wy) in [(y0, 1.0 - fy), (y1, fy)] {
                    for (xi, wx) in [(x0, 1.0 - fx), (x1, fx)] {
                        corners[i] = ((layer * ny + yi) * nx + xi, wx * wy);
                        i += 1;
                    }
                }
            }
        }
        out.iter_mut().for_each(|o| *o = 0.0);
        if let Some(g) = groups.as_deref_mut() {
            g.iter_mut().for_each(|o| *o = 0.0);
        }
        let per_voxel = GROUPS * nb;
        let mut weight = 0.0f64;
        POINT.with_borrow_mut(|point| {
            point.resize(nb, 0.0);
            for (v, w) in corners {
                let w = w as f64;
                if w <= 0.0 {
                    continue;
                }
                let at = (v * views + h) * nb;
                let s = &self.shapes[at..][..nb];
                if s.iter().all(|&x| x == 0.0) {
                    continue;
                }
                // The voxel's shares at x: each band's mean over the layer
                // times its profile there, scaled to sum 1; `point` holds
                // each band's factor from the one to the other.
                let mut sum = 0.0;
                for ((p, &si), rate) in point.iter_mut().zip(s).zip(&self.rates[at..][..nb]) {
                    *p = rate.at(tau);
                    sum += si as f64 * *p;
                }
                if sum <= 0.0 {
                    continue;
                }
                weight += w;
                let scale = w / sum;
                for ((o, p), &si) in out.iter_mut().zip(point.iter_mut()).zip(s) {
                    *p *= scale;
                    *o += si as f64 * *p;
                }
                if let Some(g) = groups.as_deref_mut() {
                    // Each group's part scales with its band's share.
                    let d = &self.deviations[(v * views + h) * per_voxel..][..per_voxel];
                    for (run, d_run) in g.chunks_mut(nb).zip(d.chunks(nb)) {
                        for ((o, &di), p) in run.iter_mut().zip(d_run).zip(point.iter()) {
                            *o += di as f64 * p;
                        }
                    }
                }
            }
        });
        normalised(weight, out, groups)
    }
}

thread_local! {
    /// One voxel's shares at an estimate's point
    /// ([`BandShapeGrid::shape_and_groups_at`]).
    static POINT: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Half-width (nm) of the run of bands whose places in a layer are pooled
/// for each band's rate ([`rate_pools`]).
const RATE_POOL_NM: f32 = 6.0;

/// For each band, the bands [lo, hi) within [`RATE_POOL_NM`] of it: a
/// band's rate of fall across a layer changes slowly with wavelength,
/// and one band's photons alone leave it noisy.
fn rate_pools(centers: &[f32]) -> Vec<(usize, usize)> {
    centers
        .iter()
        .map(|&c| {
            let lo = centers.partition_point(|&x| x < c - RATE_POOL_NM);
            let hi = centers.partition_point(|&x| x <= c + RATE_POOL_NM);
            (lo, hi.max(lo + 1))
        })
        .collect()
}

/// Largest rate of fall across a layer (the weight's ratio from top to
/// bottom, e^40).
const MAX_RATE: f64 = 40.0;

/// The mean place tau (0 to 1) of a weight that goes as exp(-x tau) over
/// a layer: 1/x - 1/(e^x - 1), 1/2 at x = 0, falling with x.
fn mean_place(x: f64) -> f64 {
    if x.abs() < 1e-4 {
        0.5 - x / 12.0
    } else {
        1.0 / x - 1.0 / x.exp_m1()
    }
}

/// The rate x whose [`mean_place`] is `mean`, within +-[`MAX_RATE`].
fn rate_of_mean(mean: f64) -> f64 {
    let mean = mean.clamp(mean_place(MAX_RATE), mean_place(-MAX_RATE));
    let (mut lo, mut hi) = (-MAX_RATE, MAX_RATE);
    for _ in 0..64 {
        let mid = 0.5 * (lo + hi);
        if mean_place(mid) > mean {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// A band's profile across a layer: its weight going as exp(-x tau) at
/// the fraction tau of the layer's thickness, over its mean over the
/// layer, x e^(-x tau) / (1 - e^(-x)), held as x and the log of
/// x / (1 - e^(-x)).
///
/// Why: a voxel's shares are means over a layer, and the light of a
/// strongly absorbed band falls across it much faster than the light as
/// a whole. Its share of the mean is then not its share at any one depth:
/// with the layer's light falling as exp(-K z) and the band's as exp(-K_i
/// z), the mean share over a layer h thick exceeds the share at its
/// middle by sinh(K_i h/2)/(K_i h/2) over sinh(K h/2)/(K h/2). With the
/// built-in grid's layers (about 1 m thick near the surface; 750 nm
/// falls about 2.5 per m) the nadir radiance 2 m down in deep uniform
/// water read +132 % at 750-800 nm and the water-leaving radiance 3-4 %
/// off at 650-800 nm (`benches/scripts/deep_water.sh`).
/// Each band's profile across the layer is taken as exponential, its rate
/// from the mean place of its weight there (pooled over the bands within
/// [`RATE_POOL_NM`]), and the voxel's shares at a depth are its mean
/// shares times the profiles there, scaled to sum 1: exact for light
/// falling exponentially in each band.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Profile {
    rate: f32,
    log_scale: f32,
}

impl Profile {
    /// Flat across the layer.
    const FLAT: Profile = Profile {
        rate: 0.0,
        log_scale: 0.0,
    };

    fn new(x: f64) -> Profile {
        let scale = if x.abs() < 1e-6 {
            1.0 + 0.5 * x
        } else {
            x / -(-x).exp_m1()
        };
        Profile {
            rate: x as f32,
            log_scale: scale.ln() as f32,
        }
    }

    /// The profile at `tau`, over its mean over the layer.
    fn at(self, tau: f64) -> f64 {
        (f64::from(self.log_scale) - f64::from(self.rate) * tau).exp()
    }
}

/// Divide the shares `out` and the group parts `groups` by the weight
/// summed into them; false (and nothing to read) without weight.
fn normalised(weight: f64, out: &mut [f64], groups: Option<&mut [f64]>) -> bool {
    if weight <= 0.0 {
        return false;
    }
    out.iter_mut().for_each(|o| *o /= weight);
    if let Some(g) = groups {
        g.iter_mut().for_each(|o| *o /= weight);
    }
    true
}

/// What a band-shape grid resolves: the domain of `size_m` in about
/// `voxels` voxels, as depth layers alone with `layers_only` (a scene whose
/// light field cannot vary across the domain: the grid resolves only what
/// varies, and each layer gathers as many photons as the grid's cells of
/// that depth would together); layers end at the depths `boundaries_m`
/// where the IOPs jump; a column of voxels stands over each of the
/// footprints of `columns` (the targets), holding the photons inside it, so
/// that the light over a target is not blended with the light beside it
/// (before, the 13 m cells of the box scenes gave the light over a 4 m box
/// the band shape of the sand's: its red bands read 2-4 % high); `views`
/// viewing directions.
#[derive(Clone, Copy)]
pub struct GridPlan<'a> {
    pub size_m: [f64; 2],
    pub voxels: usize,
    pub layers_only: bool,
    pub boundaries_m: &'a [f64],
    pub columns: &'a [Aabb],
    pub views: usize,
}

impl GridPlan<'_> {
    /// Most voxels the grid can have: its even cells times its layers
    /// with every jump's edge, and a stack of those layers per column.
    fn most_cells(&self) -> usize {
        let [nxy, _, nz] = BandShapeGrid::base_dims(self.voxels, self.layers_only);
        let columns = if self.layers_only {
            0
        } else {
            self.columns.len()
        };
        let layers = nz + self.boundaries_m.len();
        (nxy * nxy + columns) * layers
    }
}

/// A target's column of voxels: its footprint widened to at least
/// [`MIN_COLUMN_M`] on each axis, as rectangles [x0, x1, y0, y1] of the
/// periodic domain (up to four where it crosses an edge).
struct Column {
    rects: Vec<[f32; 4]>,
}

impl Column {
    fn over(b: &Aabb, size_m: [f64; 2]) -> Column {
        let spans = |lo: f32, hi: f32, size: f64| -> Vec<[f32; 2]> {
            let size = size as f32;
            let widen = 0.5 * (MIN_COLUMN_M - (hi - lo)).max(0.0);
            let (lo, hi) = (lo - widen, hi + widen);
            if hi - lo >= size {
                vec![[0.0, size]]
            } else if lo < 0.0 {
                vec![[lo + size, size], [0.0, hi]]
            } else if hi > size {
                vec![[lo, size], [0.0, hi - size]]
            } else {
                vec![[lo, hi]]
            }
        };
        let (xs, ys) = (
            spans(b.min.x, b.max.x, size_m[0]),
            spans(b.min.y, b.max.y, size_m[1]),
        );
        let rects = xs
            .iter()
            .flat_map(|x| ys.iter().map(move |y| [x[0], x[1], y[0], y[1]]))
            .collect();
        Column { rects }
    }

    fn holds(&self, x: f32, y: f32) -> bool {
        self.rects
            .iter()
            .any(|r| (r[0]..r[1]).contains(&x) && (r[2]..r[3]).contains(&y))
    }
}

/// One axis of the grid: ascending cell edges and their centres.
struct Axis {
    edges: Vec<f32>,
    centres: Vec<f32>,
}

impl Axis {
    /// Cells between the `edges` (sorted and deduplicated here).
    fn new(mut edges: Vec<f32>) -> Axis {
        edges.sort_by(f32::total_cmp);
        edges.dedup();
        if edges.len() < 2 {
            edges.push(edges.first().copied().unwrap_or(0.0) + 1.0);
        }
        let centres = edges.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
        Axis { edges, centres }
    }

    /// `n` even cells over `[0, size]`.
    fn across(size: f64, n: usize) -> Axis {
        let step = size as f32 / n as f32;
        Axis::new((0..=n).map(|i| i as f32 * step).collect())
    }

    fn cells(&self) -> usize {
        self.centres.len()
    }

    /// The cell holding `v` (clamped to the axis).
    fn cell_of(&self, v: f32) -> usize {
        self.edges[1..self.edges.len() - 1]
            .partition_point(|&e| e <= v)
            .min(self.cells() - 1)
    }

    /// Where `v` lies in its cell, from 0 at the cell's low edge to 1 at
    /// its high edge (clamped to the axis).
    fn place(&self, v: f32) -> f32 {
        let i = self.cell_of(v);
        let (lo, hi) = (self.edges[i], self.edges[i + 1]);
        ((v - lo) / (hi - lo)).clamp(0.0, 1.0)
    }

    /// The two cells whose centres bracket `v` and the weight of the
    /// second, clamped at the ends.
    fn bracket(&self, v: f32) -> (usize, usize, f32) {
        let c = &self.centres;
        let n = c.len();
        if v <= c[0] {
            return (0, 0, 0.0);
        }
        if v >= c[n - 1] {
            return (n - 1, n - 1, 0.0);
        }
        let k = c.partition_point(|&x| x <= v).clamp(1, n - 1);
        let (lo, hi) = (c[k - 1], c[k]);
        (k - 1, k, (v - lo) / (hi - lo))
    }
}

#[cfg(test)]
mod tests;
