//! Scene geometry: the sea floor and submerged targets as triangles in one BVH.
//!
//! Design note. Every reflecting surface — a flat, sloping or gridded floor,
//! boxes, panels, meshes read from Wavefront OBJ — is flattened into one list
//! of triangles, each tagged with a [`SurfaceId`] chosen by the caller (for
//! example 0 = floor, 1.. = targets). The list goes into a single obvhs
//! compressed wide BVH ([`obvhs::cwbvh::CwBvh`], medium build preset), and the
//! triangles are stored in the BVH's primitive order so a leaf's triangles are
//! contiguous in memory. Two queries: [`Geometry::intersect`] (closest hit) for
//! photon and camera paths, [`Geometry::occluded`] (any hit) for shadow rays
//! of next-event estimation.
//!
//! Conventions. Lengths in metres; z is up; the mean sea surface is z = 0 and
//! water lies below it. Depths are positive numbers meaning z = -depth. The
//! horizontal domain is [0, size_x] x [0, size_y]; floors reach slightly past
//! its edges (by [`EDGE_MARGIN_REL`] of the larger side) so that a photon
//! travelling exactly along an edge, or wrapped there by periodic boundaries,
//! cannot slip between the floor and the domain edge. Triangles are two-sided:
//! [`Hit::normal`] is the geometric normal turned to face the incoming ray, and
//! winding only documents intent (floors and panels face up, boxes outward).
//!
//! Robustness. Triangle tests use the watertight algorithm of Woop, Benthin and
//! Wald (2013) as in pbrt-v4, with the edge functions evaluated in f64 (the
//! products of two f32 are exact there, so their signs are right): a ray that
//! crosses a shared edge of two triangles hits at least one of them, and no
//! photon falls through a cracked floor. Self-intersection is avoided by an
//! epsilon relative to the scene's scale ([`Geometry::epsilon_m`]): hits with
//! t <= epsilon are ignored, and [`Geometry::spawn_origin`] moves a new ray's
//! origin off its surface by the same amount for grazing directions.
//!
//! Not for: water-column optics (the water is not geometry), the wavy sea
//! surface (handled analytically by the sea-surface model, `optics::surface`), instancing or
//! moving geometry, or shading (surface reflectance belongs to the material
//! list indexed by [`SurfaceId`]).

mod builder;
mod ceiling;
mod parse;
#[cfg(test)]
mod tests;

pub use builder::GeometryBuilder;

use glam::Vec3;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray, RayHit};

use crate::bounds::Aabb;

/// Which reflecting surface a triangle belongs to (index into the scene's
/// surface list; the caller assigns meaning, e.g. 0 = floor, 1.. = targets).
pub type SurfaceId = u32;

/// How far floors extend past the domain edges, relative to the larger
/// horizontal side of the domain.
pub const EDGE_MARGIN_REL: f32 = 1e-3;

/// Self-intersection epsilon relative to the scene's scale (largest absolute
/// coordinate). f32 hit points carry errors of a few ulp of that scale
/// (~1e-7 relative); 1e-5 leaves a margin of ~100 ulp, enough for rays leaving
/// a surface at up to ~88° from its normal. Grazing rays should use
/// [`Geometry::spawn_origin`].
pub const EPSILON_REL: f32 = 1e-5;

/// Smallest self-intersection epsilon (m), and the smallest ray parameter a
/// hit may have: obvhs culls BVH nodes that end before t = 1e-4 (a constant in
/// its node test, independent of `Ray::tmin`), so no query may accept hits
/// closer than that or it would disagree with a brute-force search.
pub const EPSILON_MIN_M: f32 = 1e-4;

/// Which horizontal axis a slope runs along.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Axis {
    X,
    Y,
}

/// A ray-triangle hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit (m when the direction is unit length).
    pub t: f32,
    /// Hit point (m), interpolated from the triangle's vertices so that it
    /// lies on the triangle's plane to within f32 rounding.
    pub position: Vec3,
    /// Unit geometric normal, turned to face the incoming ray
    /// (`normal.dot(dir) < 0`).
    pub normal: Vec3,
    /// The surface the triangle belongs to.
    pub surface: SurfaceId,
    /// The triangle's index in the order triangles were added to the
    /// [`GeometryBuilder`] (stable across BVH builds).
    pub triangle: u32,
}

/// All scene triangles in one BVH, ready for ray queries. Immutable and
/// `Sync`: share one instance between all tracing threads.
pub struct Geometry {
    bvh: CwBvh,
    /// Triangle vertices in BVH primitive order (m).
    tris: Vec<[Vec3; 3]>,
    /// Per triangle, in BVH order.
    surfaces: Vec<SurfaceId>,
    /// Per triangle, in BVH order: its index in builder order.
    source_index: Vec<u32>,
    /// Per triangle, in BVH order: added by one of the floor methods.
    is_floor: Vec<bool>,
    has_floor: bool,
    bounds: Aabb,
    domain_size_m: [f32; 2],
    epsilon_m: f32,
    skipped: usize,
    /// The highest triangle over each (x, y) column, for segments that
    /// cannot hit anything.
    ceiling: Option<ceiling::Ceiling>,
}

impl std::fmt::Debug for Geometry {
    // The BVH nodes are not worth printing; the summary is.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Geometry")
            .field("triangles", &self.tris.len())
            .field("bvh_nodes", &self.bvh.nodes.len())
            .field("has_floor", &self.has_floor)
            .field("bounds", &self.bounds)
            .field("domain_size_m", &self.domain_size_m)
            .field("epsilon_m", &self.epsilon_m)
            .field("skipped", &self.skipped)
            .finish()
    }
}

/// A ray prepared for the watertight triangle test: the permutation that
/// makes the largest direction component z and the shear that maps the
/// direction onto +z, computed once per ray instead of once per triangle.
struct PreparedRay {
    origin: Vec3,
    kx: usize,
    ky: usize,
    kz: usize,
    sx: f32,
    sy: f32,
    sz: f32,
    /// Hits need t > t_min (ray parameter units).
    t_min: f32,
}

impl PreparedRay {
    fn new(origin: Vec3, dir: Vec3, t_min: f32) -> Self {
        let a = dir.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let kx = (kz + 1) % 3;
        let ky = (kx + 1) % 3;
        let d = dir.to_array();
        PreparedRay {
            origin,
            kx,
            ky,
            kz,
            sx: -d[kx] / d[kz],
            sy: -d[ky] / d[kz],
            sz: 1.0 / d[kz],
            t_min,
        }
    }

    /// Watertight ray-triangle test (Woop et al. 2013; pbrt-v4
    /// `IntersectTriangle`). Returns the ray parameter and barycentric
    /// weights of a hit with `t_min < t < t_end`.
    #[inline]
    fn intersect(&self, tri: &[Vec3; 3], t_end: f32) -> Option<(f32, [f64; 3])> {
        let mut x = [0f64; 3];
        let mut y = [0f64; 3];
        let mut z = [0f64; 3];
        for i in 0..3 {
            let p = (tri[i] - self.origin).to_array();
            // The shear is done in f32 exactly as for every other triangle
            // sharing this vertex, which is what makes shared edges watertight.
            let pz = p[self.kz];
            x[i] = (p[self.kx] + self.sx * pz) as f64;
            y[i] = (p[self.ky] + self.sy * pz) as f64;
            z[i] = (pz * self.sz) as f64;
        }
        // Products of f32 values are exact in f64, so each edge function has
        // the right sign and a shared edge gives exactly opposite values.
        let e0 = x[1] * y[2] - y[1] * x[2];
        let e1 = x[2] * y[0] - y[2] * x[0];
        let e2 = x[0] * y[1] - y[0] * x[1];
        if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
            return None;
        }
        let det = e0 + e1 + e2;
        if det == 0.0 {
            return None;
        }
        let t = ((e0 * z[0] + e1 * z[1] + e2 * z[2]) / det) as f32;
        if !(t > self.t_min && t < t_end) {
            return None;
        }
        Some((t, [e0 / det, e1 / det, e2 / det]))
    }
}

impl Geometry {
    /// Closest hit with t in (epsilon, t_max], or `None`. `dir` need not be
    /// unit length; t is in units of `dir` (metres when it is unit). Rays with
    /// a non-finite origin or a zero or non-finite direction return `None`.
    pub fn intersect(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<Hit> {
        self.closest(origin, dir, t_max, false)
    }

    /// Closest hit with t in [0, t_max] for a ray from a point that is not on
    /// a surface (an instrument, a scattering event in the water): unlike
    /// [`Geometry::intersect`], a surface closer than the self-intersection
    /// epsilon is found. The ray starts twice the epsilon behind `origin`
    /// (`dir` unit length), and a hit behind `origin` sends the search on
    /// from the plain origin.
    pub fn intersect_from_point(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<Hit> {
        let back = 2.0 * self.epsilon_m.max(EPSILON_MIN_M);
        match self.closest(origin - dir * back, dir, t_max + back, false) {
            Some(mut h) if h.t >= back => {
                h.t = (h.t - back).max(0.0);
                Some(h)
            }
            Some(_) => self.intersect(origin, dir, t_max),
            None => None,
        }
    }

    /// True when something lies on the ray with t in (epsilon, t_max) — the
    /// shadow-ray test, exclusive at t_max so a light or surface point at
    /// exactly t_max does not shadow itself. Invalid rays are not occluded.
    pub fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        let Some(t_min) = self.t_min(origin, dir, t_max) else {
            return false;
        };
        if self.clear(origin, dir, t_max) {
            return false;
        }
        let dir = positive_zeros(dir);
        let prep = PreparedRay::new(origin, dir, t_min);
        let ray = Ray::new(origin.into(), dir.into(), t_min, t_max);
        let tris = &self.tris;
        // ray_traverse_miss stops at the first primitive that reports t < tmax.
        !self
            .bvh
            .ray_traverse_miss(ray, |_, id| match prep.intersect(&tris[id], t_max) {
                Some((t, _)) => t,
                None => f32::INFINITY,
            })
    }

    /// Number of triangles in the BVH.
    /// Feed everything that determines ray hits (triangles with their
    /// surfaces and floor flags, domain, epsilon) to `sink`, for the
    /// provenance of photon maps traced through this geometry.
    pub fn digest_into(&self, sink: &mut dyn FnMut(&[u8])) {
        for (i, t) in self.tris.iter().enumerate() {
            for v in t {
                for c in v.to_array() {
                    sink(&c.to_le_bytes());
                }
            }
            sink(&self.surfaces[i].to_le_bytes());
            sink(&[self.is_floor[i] as u8]);
        }
        for c in self.domain_size_m {
            sink(&c.to_le_bytes());
        }
        sink(&self.epsilon_m.to_le_bytes());
    }

    /// Heap bytes held by the geometry (BVH and triangle tables), for the
    /// memory budget of the stages that hold it.
    pub fn heap_bytes(&self) -> u64 {
        fn bytes<T>(v: &Vec<T>) -> u64 {
            (v.capacity() * std::mem::size_of::<T>()) as u64
        }
        bytes(&self.bvh.nodes)
            + bytes(&self.bvh.primitive_indices)
            + bytes(&self.tris)
            + bytes(&self.surfaces)
            + bytes(&self.source_index)
            + bytes(&self.is_floor)
    }

    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    /// Bounds of all triangles (m); [`Aabb::EMPTY`] when there are none.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The horizontal domain size (m) given to the builder.
    pub fn domain_size_m(&self) -> [f32; 2] {
        self.domain_size_m
    }

    /// Self-intersection epsilon (m): `max(EPSILON_MIN_M, EPSILON_REL * scale)`
    /// with scale the largest absolute coordinate of the scene and domain.
    pub fn epsilon_m(&self) -> f32 {
        self.epsilon_m
    }

    /// How many triangles the builder dropped as degenerate (zero area) or
    /// non-finite — a scene loader may want to report or reject these.
    pub fn skipped_triangles(&self) -> usize {
        self.skipped
    }

    /// Origin for a ray leaving a surface at `position` (with normal
    /// `normal`, either orientation) in direction `dir`: moved off the surface
    /// by twice the epsilon to the side `dir` points into, so that even
    /// grazing rays cannot re-hit the surface they start on.
    pub fn spawn_origin(&self, position: Vec3, normal: Vec3, dir: Vec3) -> Vec3 {
        let offset = normal * (2.0 * self.epsilon_m);
        if normal.dot(dir) >= 0.0 {
            position + offset
        } else {
            position - offset
        }
    }

    /// Depth (m, positive below the mean surface) of the top floor triangle
    /// below or above (x, y), ignoring targets; `None` without a floor there.
    pub fn floor_depth_at(&self, x: f32, y: f32) -> Option<f32> {
        if !self.has_floor || !x.is_finite() || !y.is_finite() {
            return None;
        }
        // A vertical ray from above everything, downward, keeping floor
        // triangles only: the first floor hit is the floor at (x, y).
        let top = self.bounds.max.z.max(0.0) + 1.0;
        let hit = self.closest(Vec3::new(x, y, top), Vec3::NEG_Z, f32::INFINITY, true)?;
        Some(-hit.position.z)
    }

    /// Smallest accepted ray parameter, or `None` for a ray that can hit
    /// nothing (invalid origin or direction, empty t range).
    #[inline]
    fn t_min(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<f32> {
        if self.tris.is_empty() || !origin.is_finite() || !dir.is_finite() {
            return None;
        }
        let len = dir.length();
        if len == 0.0 || !len.is_finite() {
            return None;
        }
        // In ray-parameter units, never below obvhs' node-culling constant.
        let t_min = (self.epsilon_m / len).max(EPSILON_MIN_M);
        if t_max.is_nan() || t_max <= t_min {
            return None;
        }
        Some(t_min)
    }

    /// True when the segment from `origin` to t_max (in units of `dir`)
    /// passes above every triangle near it (see `ceiling`).
    #[inline]
    fn clear(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        match &self.ceiling {
            Some(c) => c.clear(origin, origin + dir * t_max),
            None => false,
        }
    }

    fn closest(&self, origin: Vec3, dir: Vec3, t_max: f32, floor_only: bool) -> Option<Hit> {
        let t_min = self.t_min(origin, dir, t_max)?;
        if self.clear(origin, dir, t_max) {
            return None;
        }
        let dir = positive_zeros(dir);
        let prep = PreparedRay::new(origin, dir, t_min);
        // obvhs accepts a primitive only if t < tmax; one ulp past t_max makes
        // the range inclusive as documented (next_up(inf) is inf).
        let t_end = t_max.next_up();
        let ray = Ray::new(origin.into(), dir.into(), t_min, t_end);
        let mut ray_hit = RayHit::none();
        let mut bary = [0f64; 3];
        let (tris, is_floor) = (&self.tris, &self.is_floor);
        // `id` is a position in the BVH's primitive order, which is also the
        // order of our arrays (the triangles were reordered at build).
        let found = self.bvh.ray_traverse(ray, &mut ray_hit, |r, id| {
            if floor_only && !is_floor[id] {
                return f32::INFINITY;
            }
            match prep.intersect(&tris[id], r.tmax) {
                Some((t, b)) => {
                    // The traversal accepts exactly the t < r.tmax we return.
                    bary = b;
                    t
                }
                None => f32::INFINITY,
            }
        });
        if !found {
            return None;
        }
        let id = ray_hit.primitive_id as usize;
        let [p0, p1, p2] = self.tris[id];
        let position =
            (p0.as_dvec3() * bary[0] + p1.as_dvec3() * bary[1] + p2.as_dvec3() * bary[2]).as_vec3();
        // f64 so that tiny triangles (kept by the builder's f64 area test)
        // still get a unit normal.
        let mut normal = (p1 - p0)
            .as_dvec3()
            .cross((p2 - p0).as_dvec3())
            .normalize_or_zero()
            .as_vec3();
        if normal.dot(dir) > 0.0 {
            normal = -normal;
        }
        Some(Hit {
            t: ray_hit.t,
            position,
            normal,
            surface: self.surfaces[id],
            triangle: self.source_index[id],
        })
    }
}

/// `dir` with any -0.0 component replaced by +0.0. obvhs inverts a zero
/// component to `signum / EPSILON` (so -0.0 gives a huge negative inverse) but
/// picks the near and far slab planes by `direction < 0.0` (false for -0.0):
/// with a -0.0 component the two disagree and the node test culls boxes the
/// ray passes through. Vectors such as `-Vec3::X` carry -0.0 components.
#[inline]
fn positive_zeros(dir: Vec3) -> Vec3 {
    // IEEE: -0.0 + 0.0 = +0.0, and x + 0.0 = x for every other x.
    dir + Vec3::ZERO
}
