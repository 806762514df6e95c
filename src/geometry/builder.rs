//! Collecting triangles: floors, boxes, panels and OBJ meshes, then the BVH build.

use std::path::Path;
use std::time::Duration;

use glam::Vec3;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::cwbvh::CwBvh;
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;

use super::{parse, Axis, Geometry, SurfaceId, EDGE_MARGIN_REL, EPSILON_MIN_M, EPSILON_REL};
use crate::bounds::Aabb;
use crate::{Error, Result};

/// Collects scene triangles with their surface ids; [`GeometryBuilder::build`]
/// turns them into a [`Geometry`].
///
/// The shape methods that cannot fail by their nature (boxes, panels, flat
/// and sloping floors) take their numbers as given: a non-finite or zero-size
/// shape yields degenerate triangles, which `build` drops and counts in
/// [`Geometry::skipped_triangles`] rather than panicking. Range checks that
/// give meaning to numbers (is a depth positive?) belong to the scene loader.
#[derive(Clone, Debug)]
pub struct GeometryBuilder {
    domain_size_m: [f32; 2],
    /// In insertion order (visible to the tests' oracles).
    pub(super) tris: Vec<[Vec3; 3]>,
    pub(super) surfaces: Vec<SurfaceId>,
    is_floor: Vec<bool>,
}

impl GeometryBuilder {
    /// The horizontal domain's [size_x, size_y] (m).
    pub fn domain_size_m(&self) -> [f32; 2] {
        self.domain_size_m
    }

    /// A builder for a horizontal domain of `domain_size_m` = [size_x, size_y] (m).
    pub fn new(domain_size_m: [f32; 2]) -> Self {
        GeometryBuilder {
            domain_size_m,
            tris: Vec::new(),
            surfaces: Vec::new(),
            is_floor: Vec::new(),
        }
    }

    /// Triangles added so far (including any `build` will drop as degenerate).
    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    /// Bounds of the triangles added from index `first` on (a shape just
    /// added: `first` is [`GeometryBuilder::triangle_count`] before it), and
    /// how many of them are proper (finite with non-zero area, the ones
    /// `build` keeps). [`Aabb::EMPTY`] when there are none.
    pub fn extent_since(&self, first: usize) -> (Aabb, usize) {
        let mut bounds = Aabb::EMPTY;
        let mut proper = 0;
        for tri in self.tris.iter().skip(first) {
            tri.iter().for_each(|&v| bounds.grow(v));
            proper += usize::from(is_proper(tri));
        }
        (bounds, proper)
    }

    /// Add one triangle (m). Its index in [`super::Hit::triangle`] is the
    /// number of triangles added before it.
    pub fn add_triangle(&mut self, v0: Vec3, v1: Vec3, v2: Vec3, surface: SurfaceId) {
        self.push([v0, v1, v2], surface, false);
    }

    /// A flat floor at `depth_m` below the mean surface: two triangles
    /// covering the domain, facing up.
    pub fn flat_floor(&mut self, depth_m: f32, surface: SurfaceId) {
        self.slope_floor(depth_m, depth_m, Axis::X, surface);
    }

    /// A plane floor whose depth runs linearly from `from_depth_m` at the
    /// domain's low edge (coordinate 0 along `axis`) to `to_depth_m` at its
    /// high edge: two triangles, facing up. Past the edges (within the margin)
    /// the plane continues with the same slope.
    pub fn slope_floor(
        &mut self,
        from_depth_m: f32,
        to_depth_m: f32,
        axis: Axis,
        surface: SurfaceId,
    ) {
        let [sx, sy] = self.domain_size_m;
        let m = self.edge_margin();
        let length = match axis {
            Axis::X => sx,
            Axis::Y => sy,
        };
        let z_at = |x: f32, y: f32| {
            let s = match axis {
                Axis::X => x,
                Axis::Y => y,
            };
            -(from_depth_m + (to_depth_m - from_depth_m) * (s / length))
        };
        let corner = |x: f32, y: f32| Vec3::new(x, y, z_at(x, y));
        let (x0, x1, y0, y1) = (-m, sx + m, -m, sy + m);
        self.add_quad(
            [
                corner(x0, y0),
                corner(x1, y0),
                corner(x1, y1),
                corner(x0, y1),
            ],
            Vec3::Z,
            surface,
            true,
        );
    }

    /// A gridded floor: `depths_m` (m, positive down; negative where the
    /// floor rises above the water line as land) at `nx` x `ny` points
    /// spanning the domain, row-major with rows along y (index `iy * nx +
    /// ix`, point at x = ix * size_x / (nx - 1), y = iy * size_y / (ny - 1)).
    /// Each grid cell becomes two triangles; a skirt of the edge depths
    /// extends the grid by the edge margin so the domain edge stays covered.
    pub fn heightfield_floor(
        &mut self,
        depths_m: &[f32],
        nx: usize,
        ny: usize,
        surface: SurfaceId,
    ) -> Result<()> {
        const FIELD: &str = "floor.heightfield";
        if nx < 2 || ny < 2 {
            return Err(Error::invalid(
                FIELD,
                format!("a {nx} x {ny} grid is too small (at least 2 x 2 points)"),
            ));
        }
        let expected = nx
            .checked_mul(ny)
            .ok_or_else(|| Error::invalid(FIELD, format!("a {nx} x {ny} grid is too large")))?;
        if depths_m.len() != expected {
            return Err(Error::invalid(
                FIELD,
                format!(
                    "{} depths for a {nx} x {ny} grid (needs {expected})",
                    depths_m.len()
                ),
            ));
        }
        if let Some(i) = depths_m.iter().position(|d| !d.is_finite()) {
            return Err(Error::invalid(
                format!("{FIELD}[row {}][column {}]", i / nx, i % nx),
                format!("depth {} m is not a finite number", depths_m[i]),
            ));
        }
        let [sx, sy] = self.domain_size_m;
        if !(sx.is_finite() && sx > 0.0 && sy.is_finite() && sy > 0.0) {
            return Err(Error::invalid(
                "domain size",
                format!("{sx} x {sy} m is not a positive finite size"),
            ));
        }
        // (nx + 1) x (ny + 1) cells including the skirt, two triangles each;
        // triangle indices are u32.
        let cells = (nx + 1).saturating_mul(ny + 1);
        if cells > (u32::MAX as usize - self.tris.len()) / 2 {
            return Err(Error::invalid(
                FIELD,
                format!("a {nx} x {ny} grid has too many triangles"),
            ));
        }

        let m = self.edge_margin();
        // Grid coordinates with one skirt point beyond each edge. k / (n - 1)
        // is exactly 1 at the last point, so the edge lands exactly on size.
        let coords = |n: usize, size: f32| -> Vec<f32> {
            let mut c = Vec::with_capacity(n + 2);
            c.push(-m);
            c.extend((0..n).map(|k| size * (k as f32 / (n - 1) as f32)));
            c.push(size + m);
            c
        };
        let xs = coords(nx, sx);
        let ys = coords(ny, sy);
        let point = |i: usize, j: usize| {
            // Skirt points repeat the depth of the nearest edge point.
            let ix = i.saturating_sub(1).min(nx - 1);
            let iy = j.saturating_sub(1).min(ny - 1);
            Vec3::new(xs[i], ys[j], -depths_m[iy * nx + ix])
        };
        self.reserve(2 * cells);
        for j in 0..=ny {
            for i in 0..=nx {
                let quad = [
                    point(i, j),
                    point(i + 1, j),
                    point(i + 1, j + 1),
                    point(i, j + 1),
                ];
                // Counter-clockwise seen from above: faces up.
                self.push([quad[0], quad[1], quad[2]], surface, true);
                self.push([quad[0], quad[2], quad[3]], surface, true);
            }
        }
        Ok(())
    }

    /// Read a heightfield CSV: depths (m), one grid row per line (the first
    /// data line is y = 0), values separated by commas or, on lines without
    /// commas, by whitespace; `#` starts a comment. Returns (depths, nx, ny)
    /// ready for [`GeometryBuilder::heightfield_floor`]. Errors name the file
    /// and line.
    pub fn heightfield_from_csv(path: &Path) -> Result<(Vec<f32>, usize, usize)> {
        parse::read_heightfield_csv(path)
    }

    /// An axis-aligned box of `size` (m, full edge lengths) around `center`:
    /// 12 triangles wound with outward normals.
    pub fn add_box(&mut self, center: Vec3, size: Vec3, surface: SurfaceId) {
        let half = size * 0.5;
        for axis in 0..3 {
            let (a, u, v) = (
                Vec3::AXES[axis],
                Vec3::AXES[(axis + 1) % 3],
                Vec3::AXES[(axis + 2) % 3],
            );
            let (hu, hv) = (u * half[(axis + 1) % 3], v * half[(axis + 2) % 3]);
            for side in [-1.0f32, 1.0] {
                let c = center + a * (side * half[axis]);
                let outward = a * side;
                self.add_quad(
                    [c - hu - hv, c + hu - hv, c + hu + hv, c - hu + hv],
                    outward,
                    surface,
                    false,
                );
            }
        }
    }

    /// A horizontal rectangular panel of `size` = [x, y] (m) centred on
    /// `center`: two triangles wound facing up. Like all geometry it is
    /// two-sided — rays hit it from above and from below, with the hit normal
    /// facing the ray; whether the underside reflects is the material's call.
    pub fn add_panel(&mut self, center: Vec3, size: [f32; 2], surface: SurfaceId) {
        let hx = Vec3::X * (size[0] * 0.5);
        let hy = Vec3::Y * (size[1] * 0.5);
        self.add_quad(
            [
                center - hx - hy,
                center + hx - hy,
                center + hx + hy,
                center - hx + hy,
            ],
            Vec3::Z,
            surface,
            false,
        );
    }

    /// Add the triangles of a Wavefront OBJ mesh, each vertex mapped to
    /// `offset + scale * v` (m). Coordinates are taken as z-up (no axis swap).
    /// Only `v` and `f` lines are read (see the parser's notes); on error
    /// nothing is added and the error names the file and line.
    pub fn add_obj(
        &mut self,
        path: &Path,
        offset: Vec3,
        scale: f32,
        surface: SurfaceId,
    ) -> Result<()> {
        if !offset.is_finite() {
            return Err(Error::invalid(
                format!("{}: offset", path.display()),
                format!("{offset} is not finite"),
            ));
        }
        if !(scale.is_finite() && scale > 0.0) {
            return Err(Error::invalid(
                format!("{}: scale", path.display()),
                format!("{scale} is not a positive finite number"),
            ));
        }
        let mesh = parse::read_obj(path)?;
        self.reserve(mesh.len());
        for tri in mesh {
            self.push(tri.map(|v| offset + scale * v), surface, false);
        }
        Ok(())
    }

    /// Build the BVH. Triangles with non-finite vertices or zero area are
    /// dropped (they cannot be hit, and non-finite bounds would corrupt the
    /// BVH) and counted in [`Geometry::skipped_triangles`].
    pub fn build(self) -> Geometry {
        let keep: Vec<usize> = (0..self.tris.len())
            .filter(|&i| is_proper(&self.tris[i]))
            .collect();
        let skipped = self.tris.len() - keep.len();

        let bvh = if keep.is_empty() {
            // Infinitely deep, empty water: the empty BVH's traversal visits nothing.
            CwBvh::default()
        } else {
            let prims: Vec<Triangle> = keep
                .iter()
                .map(|&i| {
                    let [v0, v1, v2] = self.tris[i];
                    Triangle {
                        v0: v0.into(),
                        v1: v1.into(),
                        v2: v2.into(),
                    }
                })
                .collect();
            // Medium preset without spatial pre-splits, so primitive_indices is a
            // permutation of the input and triangles can be reordered into it.
            build_cwbvh_from_tris(
                &prims,
                BvhBuildParams::medium_build(),
                &mut Duration::default(),
            )
        };
        debug_assert!(!bvh.uses_spatial_splits);
        debug_assert_eq!(bvh.primitive_indices.len(), keep.len());

        // Store triangles in BVH order: a leaf's triangles are then adjacent
        // in memory and hit ids need no indirection.
        let n = bvh.primitive_indices.len();
        let mut tris = Vec::with_capacity(n);
        let mut surfaces = Vec::with_capacity(n);
        let mut source_index = Vec::with_capacity(n);
        let mut is_floor = Vec::with_capacity(n);
        let mut bounds = Aabb::EMPTY;
        for &p in &bvh.primitive_indices {
            let src = keep[p as usize];
            let tri = self.tris[src];
            tri.iter().for_each(|&v| bounds.grow(v));
            tris.push(tri);
            surfaces.push(self.surfaces[src]);
            source_index.push(u32::try_from(src).unwrap_or(u32::MAX));
            is_floor.push(self.is_floor[src]);
        }

        let mut scale = 0.0f32;
        if !tris.is_empty() {
            scale = bounds.min.abs().max(bounds.max.abs()).max_element();
        }
        for s in self.domain_size_m {
            if s.is_finite() {
                scale = scale.max(s.abs());
            }
        }
        let has_floor = is_floor.iter().any(|&f| f);
        let epsilon_m = (EPSILON_REL * scale).max(EPSILON_MIN_M);
        // Four epsilons above the highest vertex: far beyond the rounding of
        // the watertight test and of the hit points.
        let ceiling = super::ceiling::Ceiling::new(&tris, &bounds, 4.0 * epsilon_m);
        Geometry {
            bvh,
            tris,
            surfaces,
            source_index,
            is_floor,
            has_floor,
            bounds,
            domain_size_m: self.domain_size_m,
            epsilon_m,
            skipped,
            ceiling,
        }
    }

    /// Floors reach this far (m) past each domain edge.
    fn edge_margin(&self) -> f32 {
        let [sx, sy] = self.domain_size_m;
        EDGE_MARGIN_REL * sx.max(sy)
    }

    fn reserve(&mut self, n: usize) {
        self.tris.reserve(n);
        self.surfaces.reserve(n);
        self.is_floor.reserve(n);
    }

    fn push(&mut self, tri: [Vec3; 3], surface: SurfaceId, floor: bool) {
        self.tris.push(tri);
        self.surfaces.push(surface);
        self.is_floor.push(floor);
    }

    /// Two triangles for a planar quad given in order around its edge,
    /// wound so that their normal points along `facing`.
    fn add_quad(&mut self, mut q: [Vec3; 4], facing: Vec3, surface: SurfaceId, floor: bool) {
        if (q[1] - q[0]).cross(q[2] - q[0]).dot(facing) < 0.0 {
            q.reverse();
        }
        self.push([q[0], q[1], q[2]], surface, floor);
        self.push([q[0], q[2], q[3]], surface, floor);
    }
}

/// Finite vertices and non-zero area.
fn is_proper(tri: &[Vec3; 3]) -> bool {
    let [a, b, c] = *tri;
    if !(a.is_finite() && b.is_finite() && c.is_finite()) {
        return false;
    }
    // f64 so that small but real triangles do not underflow to zero area.
    let n = (b - a).as_dvec3().cross((c - a).as_dvec3());
    n.length_squared() > 0.0
}
