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
//! its side. Shapes are interpolated trilinearly between voxel centres.
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

use crate::error::Result;
use crate::photon::VOLUME_LAYERS;
use crate::store::PhotonQuery;
use glam::Vec3;

/// Vertical histogram bins for the equal-count layers.
const Z_BINS: usize = 4096;
/// Most depth layers of a grid.
const MAX_LAYERS: usize = 64;

/// Band shapes of the in-scatter toward the two viewing directions, per voxel.
pub struct BandShapeGrid {
    bands: usize,
    /// Viewing directions: [`VIEW_UP`], [`VIEW_DOWN`] and, in a scene
    /// whose rays looking down at a target truncate the phase functions'
    /// forward peak otherwise, [`VIEW_UP_TARGET`].
    views: usize,
    /// Cells along x and y, layers along z.
    n: [usize; 3],
    size_m: [f32; 2],
    /// Layer edges from the top (highest z) down, `n[2] + 1` values.
    z_edges: Vec<f32>,
    /// Layer centres, top down.
    z_centres: Vec<f32>,
    /// Depths where the IOPs jump (z, negative), never interpolated across.
    jumps: Vec<f32>,
    /// Per voxel (x fastest, then y, then z) and viewing direction: the
    /// band shares (sum 1), or all zero where no photon fell.
    shapes: Vec<f32>,
    /// Per voxel, viewing direction, group and band: the group's part of
    /// the shares.
    deviations: Vec<f32>,
}

use crate::photon::GROUPS;

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

    /// Bytes of a grid of `voxels` voxels over `bands` bands and `views`
    /// viewing directions, at its peak while building (f64 sums per group,
    /// then the f32 shares and group parts).
    pub fn bytes(voxels: usize, bands: usize, views: usize) -> u64 {
        let per = GROUPS * std::mem::size_of::<f64>() + (1 + GROUPS) * std::mem::size_of::<f32>();
        (voxels * views * bands * per) as u64
    }

    /// Build the grid from the volume photons of `map` over a domain of
    /// `size_m`, with about `voxels` voxels; `weight(photon, view)` is a
    /// photon's phase weight toward a viewer in each of `views` viewing
    /// directions ([`VIEW_UP`], [`VIEW_DOWN`], [`VIEW_UP_TARGET`]). With `layers_only` (a scene whose light field cannot vary
    /// across the domain) the voxels are depth layers spanning the domain:
    /// the grid resolves only what varies, and each layer gathers as many
    /// photons as the grid's cells of that depth would together.
    pub fn build(
        map: &dyn PhotonQuery,
        size_m: [f64; 2],
        voxels: usize,
        layers_only: bool,
        boundaries_m: &[f64],
        views: usize,
        weight: &(dyn Fn(&crate::photon::Photon, usize) -> f64 + Sync),
    ) -> Result<BandShapeGrid> {
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
        let (nz, nxy) = if layers_only {
            (voxels.clamp(1, MAX_LAYERS), 1)
        } else {
            let nz = ((voxels as f64).cbrt().round() as usize).clamp(1, MAX_LAYERS);
            (
                nz,
                ((voxels as f64 / nz as f64).sqrt().round() as usize).max(1),
            )
        };
        // Equal-count layers.
        let mut z_edges = vec![0.0f32];
        let mut acc = 0u64;
        let mut next = 1;
        for (i, h) in hist.iter().enumerate() {
            acc += h;
            while next < nz && acc * nz as u64 >= total * next as u64 {
                z_edges.push(-depth * (i + 1) as f32 / Z_BINS as f32);
                next += 1;
            }
        }
        while z_edges.len() < nz {
            z_edges.push(-depth);
        }
        z_edges.push(-depth);
        // Layers also end where the IOPs jump, and shapes are not blended
        // across such a depth (see `shape_and_groups_at`).
        let jumps: Vec<f32> = boundaries_m
            .iter()
            .map(|&d| -d as f32)
            .filter(|&z| z < 0.0 && z > -depth)
            .collect();
        z_edges.extend(&jumps);
        z_edges.sort_by(|a, b| b.total_cmp(a));
        z_edges.dedup();
        let nz = z_edges.len() - 1;
        let z_centres = z_edges.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
        let size = [size_m[0] as f32, size_m[1] as f32];
        let mut grid = BandShapeGrid {
            bands,
            views,
            n: [nxy, nxy, nz],
            size_m: size,
            z_edges,
            z_centres,
            jumps,
            shapes: Vec::new(),
            deviations: Vec::new(),
        };
        // Pass 2: weighted power per voxel, viewing direction, group and band.
        let cells = nxy * nxy * nz;
        let per_voxel = GROUPS * bands;
        let mut sums = vec![0f64; cells * views * per_voxel];
        for layer in VOLUME_LAYERS {
            map.for_each_photon(layer, &mut |p| {
                let v = grid.voxel_of(p.position);
                let g = p.group as usize % GROUPS;
                for h in 0..views {
                    let w = weight(p, h) * p.power as f64;
                    if w.is_finite() {
                        sums[(v * views + h) * per_voxel + g * bands + p.band as usize] += w;
                    }
                }
            })?;
        }
        grid.shapes = vec![0.0; cells * views * bands];
        grid.deviations = vec![0.0; cells * views * per_voxel];
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
        self.n
    }

    /// Bytes held.
    pub fn heap_bytes(&self) -> u64 {
        ((self.shapes.len() + self.deviations.len()) * std::mem::size_of::<f32>()) as u64
    }

    fn layer_of(&self, z: f32) -> usize {
        // Edges run from the top down.
        self.z_edges[1..]
            .iter()
            .position(|&e| z >= e)
            .unwrap_or(self.n[2] - 1)
    }

    fn voxel_of(&self, p: Vec3) -> usize {
        let [nx, ny, _] = self.n;
        let cx = ((p.x / self.size_m[0] * nx as f32) as usize).min(nx - 1);
        let cy = ((p.y / self.size_m[1] * ny as f32) as usize).min(ny - 1);
        (self.layer_of(p.z) * ny + cy) * nx + cx
    }

    /// The band shares at `x` of the in-scatter travelling up (`up`) or
    /// down, interpolated trilinearly between voxel centres (clamped at the
    /// edges), into `out`; false where the voxels around x hold no weight.
    pub fn shape_at(&self, x: Vec3, up: bool, out: &mut [f64]) -> bool {
        let view = if up { VIEW_UP } else { VIEW_DOWN };
        self.shape_and_groups_at(x, view, out, None)
    }

    /// Viewing directions held.
    pub fn views(&self) -> usize {
        self.views
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
        let [nx, ny, nz] = self.n;
        let (h, views) = (view, self.views);
        debug_assert!(h < views);
        // Fractional cell coordinates of x relative to the centres.
        let axis = |v: f32, size: f32, n: usize| -> (usize, usize, f32) {
            let c = (v / size * n as f32 - 0.5).clamp(0.0, (n - 1) as f32);
            let i0 = c.floor() as usize;
            let i1 = (i0 + 1).min(n - 1);
            (i0, i1, c - i0 as f32)
        };
        let (x0, x1, fx) = axis(x.x, self.size_m[0], nx);
        let (y0, y1, fy) = axis(x.y, self.size_m[1], ny);
        // Layers: centres are uneven.
        let zc = &self.z_centres;
        let (z0, z1, fz) = if x.z >= zc[0] {
            (0, 0, 0.0)
        } else if x.z <= zc[nz - 1] {
            (nz - 1, nz - 1, 0.0)
        } else {
            let k = zc.iter().position(|&c| c < x.z).unwrap_or(nz - 1);
            let (za, zb) = (zc[k - 1], zc[k]);
            // A jump in the IOPs between x and a centre: only the layer on
            // x's side of it describes x.
            let between = |hi: f32, lo: f32| self.jumps.iter().any(|&j| j < hi && j >= lo);
            if between(za, x.z) {
                (k, k, 0.0)
            } else if between(x.z, zb) {
                (k - 1, k - 1, 0.0)
            } else {
                (k - 1, k, (za - x.z) / (za - zb))
            }
        };
        out.iter_mut().for_each(|o| *o = 0.0);
        if let Some(g) = groups.as_deref_mut() {
            g.iter_mut().for_each(|o| *o = 0.0);
        }
        let per_voxel = GROUPS * self.bands;
        let mut weight = 0.0f64;
        for (zi, wz) in [(z0, 1.0 - fz), (z1, fz)] {
            for (yi, wy) in [(y0, 1.0 - fy), (y1, fy)] {
                for (xi, wx) in [(x0, 1.0 - fx), (x1, fx)] {
                    let w = (wx * wy * wz) as f64;
                    if w <= 0.0 {
                        continue;
                    }
                    let v = (zi * ny + yi) * nx + xi;
                    let s = &self.shapes[(v * views + h) * self.bands..][..self.bands];
                    if s.iter().all(|&x| x == 0.0) {
                        continue;
                    }
                    weight += w;
                    for (o, &si) in out.iter_mut().zip(s) {
                        *o += w * si as f64;
                    }
                    if let Some(g) = groups.as_deref_mut() {
                        let d = &self.deviations[(v * views + h) * per_voxel..][..per_voxel];
                        for (o, &di) in g.iter_mut().zip(d) {
                            *o += w * di as f64;
                        }
                    }
                }
            }
        }
        if weight <= 0.0 {
            return false;
        }
        out.iter_mut().for_each(|o| *o /= weight);
        if let Some(g) = groups {
            g.iter_mut().for_each(|o| *o /= weight);
        }
        true
    }
}

#[cfg(test)]
mod tests;
