//! The precomputed grid of boundary distances, the cheap alternative to
//! tracing six rays per estimate.

use super::{cap_radius, trace_axis, AxialDistances, DIRECTIONS};
use crate::error::{Error, Result};
use crate::scene::{Scene, FLOOR};
use glam::Vec3;
use rayon::prelude::*;

/// A precomputed grid of axial distances over the water volume, trilinearly
/// interpolated: the cheap alternative to [`axial_distances_traced`].
///
/// The grid holds only what needs tracing — distances to the floor and
/// targets, wrapped in periodic domains, capped at `max_distance_m` — and the
/// sea surface and open walls are applied in closed form at query time, so
/// they are exact. Nodes below the floor hold the linear extension of the
/// water's values (negative toward the floor), so cells cut by a planar floor
/// interpolate the floor distance exactly (to f32 rounding) instead of
/// mixing in meaningless values from inside the ground. Errors remain where
/// a ray's first hit jumps (rays grazing a target's edge) and in cells that
/// reach into a target.
pub struct BoundaryGrid {
    /// Position of node (0, 0, 0) (m).
    origin: Vec3,
    /// Node spacing per axis (m), at most the requested spacing.
    spacing: Vec3,
    /// Nodes per axis (each >= 2).
    dims: [usize; 3],
    /// Per node (x fastest, then y, then z): the traced distances along the
    /// six axis directions.
    values: Vec<[f32; 6]>,
    max_distance_m: f32,
    domain_size_m: [f32; 2],
    periodic: bool,
}

impl std::fmt::Debug for BoundaryGrid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BoundaryGrid")
            .field("origin", &self.origin)
            .field("spacing", &self.spacing)
            .field("dims", &self.dims)
            .field("max_distance_m", &self.max_distance_m)
            .field("bytes", &self.bytes())
            .finish()
    }
}

/// Node layout of a grid: origin, spacing, dimensions.
type Layout = (Vec3, Vec3, [usize; 3]);

impl BoundaryGrid {
    /// Trace the grid for `scene` with node spacing at most `spacing_m`,
    /// storing distances up to `max_distance_m`. That must be at least the
    /// largest search radius, and should be well beyond it over gentle
    /// slopes: the horizontal distance to a floor of slope s changes by
    /// spacing / s per cell, and a cap inside a cell spoils its
    /// interpolation (on the coastal scene's 1:14 slope, 1 m spacing and
    /// R = 2 m, capping at 4 m gives errors up to R; 30 m gives none beyond
    /// f32 rounding, 2e-5 m). The grid spans the domain horizontally and
    /// from the surface to one spacing below the deepest geometry (or
    /// `max_distance_m` deep without geometry). Uses the rayon pool.
    pub fn build(scene: &Scene, spacing_m: f32, max_distance_m: f32) -> Result<BoundaryGrid> {
        let (origin, spacing, dims) = Self::layout(scene, spacing_m, max_distance_m)?;
        let nodes = dims[0] * dims[1] * dims[2];
        let mut values = Vec::new();
        values.try_reserve_exact(nodes).map_err(|_| {
            Error::invalid(
                "boundary grid",
                format!(
                    "cannot allocate {} bytes for {nodes} nodes at spacing {spacing_m} m",
                    nodes * std::mem::size_of::<[f32; 6]>()
                ),
            )
        })?;
        values.par_extend((0..nodes).into_par_iter().map(|n| {
            let i = n % dims[0];
            let j = (n / dims[0]) % dims[1];
            let l = n / (dims[0] * dims[1]);
            let p = origin + spacing * Vec3::new(i as f32, j as f32, l as f32);
            node_values(scene, p, max_distance_m)
        }));
        Ok(BoundaryGrid {
            origin,
            spacing,
            dims,
            values,
            max_distance_m,
            domain_size_m: scene.geometry.domain_size_m(),
            periodic: scene.domain.periodic,
        })
    }

    /// Bytes the grid for `scene` at `spacing_m` would hold, without
    /// building it (for checking against a memory budget).
    pub fn planned_bytes(scene: &Scene, spacing_m: f32, max_distance_m: f32) -> Result<usize> {
        let (_, _, dims) = Self::layout(scene, spacing_m, max_distance_m)?;
        Ok(dims[0] * dims[1] * dims[2] * std::mem::size_of::<[f32; 6]>())
    }

    fn layout(scene: &Scene, spacing_m: f32, max_distance_m: f32) -> Result<Layout> {
        if !(spacing_m.is_finite() && spacing_m > 0.0) {
            return Err(Error::invalid(
                "boundary grid spacing",
                format!("{spacing_m} m: must be a positive length"),
            ));
        }
        if !(max_distance_m.is_finite() && max_distance_m > 0.0) {
            return Err(Error::invalid(
                "boundary grid max distance",
                format!("{max_distance_m} m: must be a positive length"),
            ));
        }
        let size = scene.geometry.domain_size_m();
        let bounds = scene.geometry.bounds();
        let bottom = if bounds.min.z.is_finite() {
            bounds.min.z.min(0.0)
        } else {
            -max_distance_m
        };
        // One layer below the deepest geometry so every cell cut by the
        // floor has nodes on both sides.
        let z_lo = bottom - spacing_m;
        let extent = Vec3::new(size[0], size[1], -z_lo);
        let mut dims = [0usize; 3];
        let mut spacing = Vec3::ZERO;
        for a in 0..3 {
            let cells = (extent[a] / spacing_m).ceil().max(1.0);
            if cells.is_nan() || cells >= 1e9 {
                return Err(Error::invalid(
                    "boundary grid spacing",
                    format!("{spacing_m} m is too fine for a {} m domain", extent[a]),
                ));
            }
            dims[a] = cells as usize + 1;
            spacing[a] = extent[a] / cells;
        }
        let bytes = dims[0]
            .checked_mul(dims[1])
            .and_then(|n| n.checked_mul(dims[2]))
            .and_then(|n| n.checked_mul(std::mem::size_of::<[f32; 6]>()));
        if bytes.is_none() {
            return Err(Error::invalid(
                "boundary grid spacing",
                format!("{spacing_m} m gives more nodes than memory can address"),
            ));
        }
        Ok((Vec3::new(0.0, 0.0, z_lo), spacing, dims))
    }

    /// Axial distances at `o`, interpolated and capped at `r`. Sites outside
    /// the grid use its nearest face; a non-finite site gets all zeros.
    pub fn distances(&self, o: Vec3, r: f32) -> AxialDistances {
        let r = cap_radius(r);
        if !o.is_finite() {
            return AxialDistances([0.0; 6]);
        }
        let g = (o - self.origin) / self.spacing;
        let mut base = [0usize; 3];
        let mut frac = [0f32; 3];
        for a in 0..3 {
            let top = (self.dims[a] - 1) as f32;
            let c = g[a].clamp(0.0, top);
            // The last cell is used for sites on the far face.
            let i = (c.floor() as usize).min(self.dims[a] - 2);
            base[a] = i;
            frac[a] = c - i as f32;
        }
        let (nx, nxy) = (self.dims[0], self.dims[0] * self.dims[1]);
        let first = base[0] + base[1] * nx + base[2] * nxy;
        let mut v = [0f32; 6];
        for corner in 0..8 {
            let (di, dj, dl) = (corner & 1, (corner >> 1) & 1, corner >> 2);
            let w = (if di == 1 { frac[0] } else { 1.0 - frac[0] })
                * (if dj == 1 { frac[1] } else { 1.0 - frac[1] })
                * (if dl == 1 { frac[2] } else { 1.0 - frac[2] });
            let node = &self.values[first + di + dj * nx + dl * nxy];
            for k in 0..6 {
                v[k] += w * node[k];
            }
        }
        let size = self.domain_size_m;
        AxialDistances(std::array::from_fn(|k| {
            // Where every corner saw nothing within max_distance_m there is
            // no boundary to report, whatever r is.
            let traced = if v[k] >= self.max_distance_m {
                f32::INFINITY
            } else {
                v[k]
            };
            let analytic = match k {
                0 if !self.periodic => size[0] - o.x,
                1 if !self.periodic => o.x,
                2 if !self.periodic => size[1] - o.y,
                3 if !self.periodic => o.y,
                4 => -o.z,
                _ => f32::INFINITY,
            };
            traced.min(analytic).clamp(0.0, r)
        }))
    }

    /// Heap bytes held by the grid.
    pub fn bytes(&self) -> usize {
        self.values.capacity() * std::mem::size_of::<[f32; 6]>()
    }

    /// Nodes per axis.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Node spacing per axis (m).
    pub fn spacing_m(&self) -> Vec3 {
        self.spacing
    }
}

/// The six stored values of the grid node at `p`.
fn node_values(scene: &Scene, p: Vec3, max_distance_m: f32) -> [f32; 6] {
    let geo = &scene.geometry;
    let trace = |q: Vec3, k: usize, from_point: bool| {
        trace_axis(scene, q, k, max_distance_m, from_point).map_or(max_distance_m, |(t, _)| t)
    };
    let forward = |q: Vec3, k: usize| trace(q, k, false);
    // A node on or below the floor cannot trace its own values (rays from a
    // surface ignore it). Its values continue the water's linearly: moving
    // the site by m along a direction shortens that direction's distance by
    // m, from a point just above the floor; and for horizontal directions
    // whose backward ray meets the floor, the negative distance back to it
    // (exact for a planar sloping floor).
    let lift = 4.0 * geo.epsilon_m();
    match geo.floor_depth_at(p.x, p.y).map(|d| -d) {
        // In the water but within the epsilon's reach of the floor (not on
        // it, where horizontal rays would run in its plane): traced as from
        // a point in the water, which finds the floor however near. (Lifted, a node a few millimetres above a gentle slope read
        // the lifted point's distance, lift / slope too long: 0.1 m at the
        // built-in scene's 1 in 12.5.)
        Some(floor_z) if p.z > floor_z && p.z < floor_z + lift => {
            std::array::from_fn(|k| trace(p, k, true))
        }
        Some(floor_z) if p.z < floor_z + lift => {
            let q = Vec3::new(p.x, p.y, floor_z + lift);
            std::array::from_fn(|k| {
                if k < 4 {
                    let back = k ^ 1;
                    if let Some((t, FLOOR)) = trace_axis(scene, p, back, max_distance_m, false) {
                        return -t;
                    }
                }
                let moved = (p - q).dot(DIRECTIONS[k]);
                (forward(q, k) - moved).min(max_distance_m)
            })
        }
        _ => std::array::from_fn(|k| forward(p, k)),
    }
}
