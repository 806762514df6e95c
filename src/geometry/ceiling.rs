//! The highest point of the scene's triangles over each column of a coarse
//! grid in (x, y): a ray segment that stays above it over every column it
//! crosses hits nothing, so the BVH need not be walked.
//!
//! Most of an emission's segments run between scattering events in the
//! upper water, metres above the floor, and each would otherwise walk the
//! BVH from its root (the floor's root box spans the whole water column of
//! a sloping floor). The test is conservative: it answers "clear" only with
//! a margin of many times f32 rounding above every triangle vertex in the
//! columns, where the watertight triangle test cannot report a hit either.
//! So it changes no result, only how fast the miss is found.
//!
//! The grid has up to 128 × 128 columns over the triangles' (x, y) box
//! (1.6 m across the built-in 200 m scene).
//!
//! Not for: segments that cross more than [`MAX_COLUMNS`] columns (the
//! BVH answers those).

use crate::bounds::Aabb;
use glam::Vec3;

/// Columns per axis at most.
const GRID: usize = 128;

/// Segments crossing more columns than this go to the BVH.
pub const MAX_COLUMNS: usize = 64;

/// Per column, the highest triangle vertex over it.
#[derive(Clone, Debug)]
pub struct Ceiling {
    min: [f32; 2],
    max: [f32; 2],
    inv_cell: [f32; 2],
    dims: [usize; 2],
    /// The last column's index on each axis, as f32.
    last: [f32; 2],
    /// How far (m) a segment's (x, y) box is widened against rounding.
    pad: f32,
    /// An upper bound (m) on the height of every triangle over the column,
    /// plus the margin; `-inf` for columns no triangle meets.
    top: Vec<f32>,
    /// Per column, the greatest `top` of the 2 x 2 columns from it up in
    /// x and y (those beyond the grid count as `-inf`): one load answers
    /// a segment that crosses at most two columns per axis, most of them.
    top2: Vec<f32>,
    /// The per-axis constants of [`Ceiling::columns`], in the order of its
    /// lanes: x and y of the segment's low end, then of its high end.
    lanes: Lanes,
}

/// Four-lane constants, lanes `[x, y, x, y]`.
#[derive(Clone, Debug)]
struct Lanes {
    /// The margin, subtracted from the low end and added to the high end.
    pad: [f32; 4],
    /// The box's high side for the low end, its low side for the high end.
    far: [f32; 4],
    min: [f32; 4],
    inv_cell: [f32; 4],
    last: [f32; 4],
}

impl Ceiling {
    /// The ceiling of `tris` within `bounds` (their box), with `margin` (m)
    /// added to every column.
    pub fn new(tris: &[[Vec3; 3]], bounds: &Aabb, margin: f32) -> Option<Ceiling> {
        if tris.is_empty() || !bounds.is_valid() {
            return None;
        }
        let size = [bounds.max.x - bounds.min.x, bounds.max.y - bounds.min.y];
        let dims = size.map(|s| if s > 0.0 { GRID } else { 1 });
        let inv_cell = [0, 1].map(|a| {
            if size[a] > 0.0 {
                dims[a] as f32 / size[a]
            } else {
                0.0
            }
        });
        let mut c = Ceiling {
            min: [bounds.min.x, bounds.min.y],
            max: [bounds.max.x, bounds.max.y],
            inv_cell,
            dims,
            last: dims.map(|d| (d - 1) as f32),
            pad: margin,
            top: vec![f32::NEG_INFINITY; dims[0] * dims[1]],
            top2: Vec::new(),
            lanes: Lanes {
                pad: [-margin, -margin, margin, margin],
                far: [bounds.max.x, bounds.max.y, bounds.min.x, bounds.min.y],
                min: [bounds.min.x, bounds.min.y, bounds.min.x, bounds.min.y],
                inv_cell: [inv_cell[0], inv_cell[1], inv_cell[0], inv_cell[1]],
                last: [0, 1, 0, 1].map(|a| (dims[a] - 1) as f32),
            },
        };
        let cell_size = [0, 1].map(|a| size[a] as f64 / dims[a] as f64);
        for t in tris {
            let lo = t[0].min(t[1]).min(t[2]);
            let hi = t[0].max(t[1]).max(t[2]);
            let (i0, i1) = (c.column(0, lo.x - margin), c.column(0, hi.x + margin));
            let (j0, j1) = (c.column(1, lo.y - margin), c.column(1, hi.y + margin));
            // Over a column, a triangle is no higher than its highest vertex
            // nor, unless it is steep, than its plane at the column's corners
            // (a linear function's greatest value on a rectangle is at a
            // corner): a floor of two triangles across the whole scene then
            // gives each column its own depth.
            let [p0, p1, p2] = t.map(|v| v.as_dvec3());
            let n = (p1 - p0).cross(p2 - p0);
            let plane = n.z.abs() >= 0.1 * n.length();
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let mut top = hi.z as f64;
                    if plane {
                        let x = [i, i + 1].map(|k| c.min[0] as f64 + k as f64 * cell_size[0]);
                        let y = [j, j + 1].map(|k| c.min[1] as f64 + k as f64 * cell_size[1]);
                        let m = margin as f64;
                        let mut corner = f64::NEG_INFINITY;
                        for cx in [x[0] - m, x[1] + m] {
                            for cy in [y[0] - m, y[1] + m] {
                                let z = p0.z - (n.x * (cx - p0.x) + n.y * (cy - p0.y)) / n.z;
                                corner = corner.max(z);
                            }
                        }
                        top = top.min(corner);
                    }
                    let cell = &mut c.top[j * dims[0] + i];
                    *cell = cell.max((top + margin as f64) as f32);
                }
            }
        }
        c.top2 = (0..dims[1])
            .flat_map(|j| (0..dims[0]).map(move |i| (i, j)))
            .map(|(i, j)| {
                let (i1, j1) = ((i + 1).min(dims[0] - 1), (j + 1).min(dims[1] - 1));
                [(i, j), (i1, j), (i, j1), (i1, j1)]
                    .iter()
                    .map(|&(i, j)| c.top[j * dims[0] + i])
                    .fold(f32::NEG_INFINITY, f32::max)
            })
            .collect();
        Some(c)
    }

    /// The column on `axis` of `v`, clamped to the grid (no geometry lies
    /// beyond it). Monotonic in `v`, so two intervals that share a point
    /// share a column.
    #[inline]
    fn column(&self, axis: usize, v: f32) -> usize {
        // Clamped first, so truncation is the floor (and NaN gives 0).
        ((v - self.min[axis]) * self.inv_cell[axis])
            .max(0.0)
            .min(self.last[axis]) as i32 as usize
    }

    /// True when the segment from `a` to `b` lies above the ceiling of
    /// every column it crosses (so no triangle can be hit on it); false
    /// when it might not, or crosses too many columns to check.
    #[inline]
    pub fn clear(&self, a: Vec3, b: Vec3) -> bool {
        let low = a.z.min(b.z);
        if !low.is_finite() || !b.x.is_finite() || !b.y.is_finite() {
            return false;
        }
        let Some([i0, j0, i1, j1]) = self.columns(a, b) else {
            // Wholly beside the triangles' box.
            return true;
        };
        let w = self.dims[0];
        if i1 <= i0 + 1 && j1 <= j0 + 1 && low > self.top2[j0 * w + i0] {
            return true;
        }
        if (i1 - i0 + 1) * (j1 - j0 + 1) > MAX_COLUMNS {
            return false;
        }
        (j0..=j1).all(|j| {
            self.top[j * w + i0..=j * w + i1]
                .iter()
                .all(|&top| low > top)
        })
    }

    /// The first and last columns `[i0, j0, i1, j1]` under the (x, y) box
    /// of the segment from `a` to `b`, widened by the margin (its ends are
    /// rounded); None when that box lies wholly beside the triangles' box.
    /// `b`'s x and y are finite (`a`'s need not be).
    #[cfg(not(target_arch = "x86_64"))]
    #[inline]
    fn columns(&self, a: Vec3, b: Vec3) -> Option<[usize; 4]> {
        self.columns_scalar(a, b)
    }

    /// [`Self::columns`] one axis at a time.
    #[cfg_attr(target_arch = "x86_64", allow(dead_code))]
    fn columns_scalar(&self, a: Vec3, b: Vec3) -> Option<[usize; 4]> {
        let p = self.pad;
        let lo = [a.x.min(b.x) - p, a.y.min(b.y) - p];
        let hi = [a.x.max(b.x) + p, a.y.max(b.y) + p];
        if (hi[0] < self.min[0])
            | (lo[0] > self.max[0])
            | (hi[1] < self.min[1])
            | (lo[1] > self.max[1])
        {
            return None;
        }
        Some([
            self.column(0, lo[0]),
            self.column(1, lo[1]),
            self.column(0, hi[0]),
            self.column(1, hi[1]),
        ])
    }

    /// [`Self::columns`] with both ends of both axes in the lanes of one
    /// SSE register: the same operations lane by lane, so the same columns
    /// (tested against [`Self::columns_scalar`]). SSE's min and max return
    /// their second operand when either is NaN, here `b`'s finite one, as
    /// `f32::min` and `max` return the number; both truncate the clamped
    /// value.
    #[cfg(target_arch = "x86_64")]
    #[inline]
    fn columns(&self, a: Vec3, b: Vec3) -> Option<[usize; 4]> {
        use std::arch::x86_64::*;
        // SAFETY: SSE2 is part of the x86-64 baseline; loads are unaligned.
        unsafe {
            let va = _mm_setr_ps(a.x, a.y, a.x, a.y);
            let vb = _mm_setr_ps(b.x, b.y, b.x, b.y);
            // [lo x, lo y, hi x, hi y], widened by the margin.
            let v = _mm_movelh_ps(_mm_min_ps(va, vb), _mm_max_ps(va, vb));
            let v = _mm_add_ps(v, _mm_loadu_ps(self.lanes.pad.as_ptr()));
            // A low end past the box's high side, or a high end short of
            // its low side.
            let far = _mm_loadu_ps(self.lanes.far.as_ptr());
            let beside = (_mm_movemask_ps(_mm_cmpgt_ps(v, far)) & 0b0011)
                | (_mm_movemask_ps(_mm_cmplt_ps(v, far)) & 0b1100);
            if beside != 0 {
                return None;
            }
            let u = _mm_mul_ps(
                _mm_sub_ps(v, _mm_loadu_ps(self.lanes.min.as_ptr())),
                _mm_loadu_ps(self.lanes.inv_cell.as_ptr()),
            );
            let u = _mm_min_ps(
                _mm_max_ps(u, _mm_setzero_ps()),
                _mm_loadu_ps(self.lanes.last.as_ptr()),
            );
            let mut out = [0i32; 4];
            _mm_storeu_si128(out.as_mut_ptr().cast(), _mm_cvttps_epi32(u));
            Some(out.map(|c| c as usize))
        }
    }
}

#[cfg(test)]
mod tests;
