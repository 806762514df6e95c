//! Boundary-bias compensation: how much of a search region lies in the water.
//!
//! Design note. A density estimate divides the flux of the photons found
//! around a search site by the volume searched. Near the sea surface, the
//! floor, a target or an open domain edge part of the search sphere lies
//! where no photon can be, and dividing by the whole sphere underestimates
//! radiance (by about 1/2 at a flat boundary, 1/4 at an edge, 1/8 at a
//! corner). Following the poster *Simulated Spectral Light Transport in
//! Coastal Waters Using Adaptive Photon Mapping* (Goodenough, RIT DIRSIG
//! group), the boundaries are described by six axial distances and the
//! search volume is corrected in one of two ways ([`BoundaryMode`]); `none`
//! is Jensen's plain estimate (Jensen 2001, *Realistic Image Synthesis Using
//! Photon Mapping*: flux over the sphere's volume) for comparison.
//!
//! Notation (as in DESIGN.md section 5): O the search site, P a photon, R the
//! search radius, B the axial distances from O to the nearest boundary along
//! +x, -x, +y, -y, +z, -z, each capped at R ([`AxialDistances`]; B = R means
//! "no boundary within R").
//! - *ellipsoid*: photons with the adaptive distance
//!   D' = sqrt(sum_a ((P_a - O_a) R / B_a)^2) <= R are used, B_a taken on
//!   the side of the photon's offset; the volume is the eight octant
//!   ellipsoid pieces, sum (pi/6) Bx By Bz ([`ellipsoid_distance`],
//!   [`ellipsoid_volume`]). The ellipsoid lies inside the sphere, so a
//!   Euclidean radius-R search followed by the D' test finds exactly its
//!   photons.
//! - *clipped-sphere*: a Euclidean search, with the volume of the sphere
//!   intersected with the box [-B_-x, B_+x] x [-B_-y, B_+y] x [-B_-z, B_+z]
//!   ([`clipped_sphere_volume`]): the sphere minus the caps cut by the axial
//!   planes, their overlaps added back. It is computed as eight octant pieces,
//!   each the integral over one axis of the exact area of a disc cut by a
//!   quadrant, with Gauss-Legendre quadrature split at every kink of that area
//!   (relative error below 1e-12). [`clipped_disc_area`] is the 2-D analogue for
//!   estimates on surfaces.
//!
//! B comes either from six axis rays traced through the scene
//! ([`axial_distances_traced`]) or from a precomputed grid, trilinearly
//! interpolated ([`BoundaryGrid`]), the cheap alternative. Periodic domain
//! edges are not boundaries, so there the photon search must wrap around
//! them too (`query` does not wrap yet).
//!
//! Not for: boundaries that are not axis-aligned planes. Both modes model
//! the water near O as the box of the six axial distances, so a sloping floor
//! or a target's edge inside the sphere is only approximated; and a site must
//! lie in the water (a site on a surface should first be moved off it, e.g.
//! with [`crate::geometry::Geometry::spawn_origin`]). This module does not
//! search photons or form radiance.

use crate::error::{Error, Result};
use crate::scene::{Scene, FLOOR};
use glam::Vec3;
use rayon::prelude::*;
use std::f64::consts::PI;
use std::str::FromStr;
use std::sync::OnceLock;

/// Axial boundary distances (m), each in [0, R]: [+x, -x, +y, -y, +z, -z].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxialDistances(pub [f32; 6]);

impl AxialDistances {
    /// No boundary within `r` on any side: the plain sphere.
    pub fn unbounded(r: f32) -> Self {
        AxialDistances([r; 6])
    }

    /// The distances in f64, for the volume functions.
    pub fn to_f64(&self) -> [f64; 6] {
        self.0.map(f64::from)
    }
}

/// The six axis directions, in the order of [`AxialDistances`].
const DIRECTIONS: [Vec3; 6] = [
    Vec3::X,
    Vec3::NEG_X,
    Vec3::Y,
    Vec3::NEG_Y,
    Vec3::Z,
    Vec3::NEG_Z,
];

/// How the density estimate treats boundaries inside the search sphere.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoundaryMode {
    /// Jensen's plain estimate: the full sphere.
    None,
    /// The adaptive (ellipsoid) distance and the octant-ellipsoid volume.
    Ellipsoid,
    /// Euclidean search, the sphere's volume clipped by the axial planes.
    ClippedSphere,
}

impl BoundaryMode {
    /// Every mode, for ablation loops.
    pub const ALL: [BoundaryMode; 3] = [
        BoundaryMode::None,
        BoundaryMode::Ellipsoid,
        BoundaryMode::ClippedSphere,
    ];

    /// The name used in scene files and on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            BoundaryMode::None => "none",
            BoundaryMode::Ellipsoid => "ellipsoid",
            BoundaryMode::ClippedSphere => "clipped-sphere",
        }
    }

    /// The volume (m^3) to divide by for a search of radius `r` at a site
    /// with axial distances `b`.
    pub fn volume(self, r: f32, b: &AxialDistances) -> f64 {
        match self {
            BoundaryMode::None => sphere_volume(f64::from(r).max(0.0)),
            BoundaryMode::Ellipsoid => ellipsoid_volume(&b.to_f64()),
            BoundaryMode::ClippedSphere => clipped_sphere_volume(f64::from(r), &b.to_f64()),
        }
    }

    /// Whether a photon at `offset` = P - O, already found by a Euclidean
    /// search of radius `r`, belongs to this mode's search region.
    pub fn accepts(self, offset: Vec3, r: f32, b: &AxialDistances) -> bool {
        match self {
            BoundaryMode::None | BoundaryMode::ClippedSphere => offset.length_squared() <= r * r,
            BoundaryMode::Ellipsoid => ellipsoid_distance(offset, r, b) <= r,
        }
    }
}

impl std::fmt::Display for BoundaryMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl FromStr for BoundaryMode {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        BoundaryMode::ALL
            .into_iter()
            .find(|m| m.as_str() == s)
            .ok_or_else(|| {
                Error::invalid(
                    "boundary mode",
                    format!("'{s}': use \"none\", \"ellipsoid\" or \"clipped-sphere\""),
                )
            })
    }
}

fn sphere_volume(r: f64) -> f64 {
    4.0 / 3.0 * PI * r * r * r
}

// ---------------------------------------------------------------------------
// Volumes and areas.

/// Volume of the sphere of radius `r` centred at O intersected with the
/// axis-aligned box [-B_-x, B_+x] x [-B_-y, B_+y] x [-B_-z, B_+z], `b` =
/// [+x, -x, +y, -y, +z, -z] (each clamped to [0, r]): the sphere minus the
/// caps cut by the six axial planes, overlaps added back. Relative error
/// below 1e-12. A non-positive or NaN `r` gives 0.
pub fn clipped_sphere_volume(r: f64, b: &[f64; 6]) -> f64 {
    if r.is_nan() || r <= 0.0 {
        return 0.0;
    }
    if r.is_infinite() {
        // Only the box is left.
        let side = |i: usize| b[i].max(0.0) + b[i + 1].max(0.0);
        return side(0) * side(2) * side(4);
    }
    // f64::max maps NaN to 0, so a NaN distance counts as a boundary at O.
    let b = b.map(|v| v.max(0.0).min(r));
    let mut v = 0.0;
    for x in [b[0], b[1]] {
        for y in [b[2], b[3]] {
            for z in [b[4], b[5]] {
                v += octant_volume(r, x, y, z, 1);
            }
        }
    }
    v
}

/// The octant-ellipsoid volume of the ellipsoid mode: the sum over the 8
/// octants of (pi/6) Bx By Bz with the B on each octant's sides. The sum
/// factors into (pi/6)(B_+x + B_-x)(B_+y + B_-y)(B_+z + B_-z); with every
/// B = R it is the sphere's 4/3 pi R^3. Negative or NaN distances count as 0.
pub fn ellipsoid_volume(b: &[f64; 6]) -> f64 {
    let side = |i: usize| b[i].max(0.0) + b[i + 1].max(0.0);
    PI / 6.0 * side(0) * side(2) * side(4)
}

/// The adaptive distance D' = sqrt(sum_a ((P_a - O_a) R / B_a)^2) of a photon
/// at `offset` = P - O, with B_a taken on the side of the offset. An offset
/// component toward a side with B_a = 0 gives infinity (the photon is beyond
/// a boundary through O); a zero component contributes nothing.
pub fn ellipsoid_distance(offset: Vec3, r: f32, b: &AxialDistances) -> f32 {
    let mut sum = 0.0f32;
    for a in 0..3 {
        let d = offset[a];
        if d == 0.0 {
            continue;
        }
        let side = if d > 0.0 { b.0[2 * a] } else { b.0[2 * a + 1] };
        if side.is_nan() || side <= 0.0 {
            return f32::INFINITY;
        }
        let s = d * r / side;
        sum += s * s;
    }
    sum.sqrt()
}

/// Area of the disc of radius `r` in a plane clipped by up to four in-plane
/// axial lines at distances `b` = [+u, -u, +v, -v] from its centre (each
/// clamped to [0, r]), i.e. the disc intersected with the rectangle
/// [-b_-u, b_+u] x [-b_-v, b_+v]. Exact (closed form). A non-positive or NaN
/// `r` gives 0.
pub fn clipped_disc_area(r: f64, b: &[f64; 4]) -> f64 {
    if r.is_nan() || r <= 0.0 {
        return 0.0;
    }
    let b = b.map(|v| v.max(0.0));
    let mut area = 0.0;
    for u in [b[0], b[1]] {
        for v in [b[2], b[3]] {
            area += quadrant_area(r, u, v);
        }
    }
    area
}

/// Area of the disc of radius `rho` centred at the origin within the
/// rectangle [0, a] x [0, b] (a, b >= 0).
///
/// With the corner inside the disc it is a b. Otherwise (a, b clamped to
/// rho) it is the rectangle's part [0, s_b] x [0, b] plus the area under the
/// arc from u = s_b to u = a, where s_a = sqrt(rho^2 - a^2):
/// 1/2 (s_b b + a s_a + rho^2 (asin(a/rho) - asin(s_b/rho))). The angle is
/// taken by atan2 of its sine and cosine, with the sine's numerator
/// a b - s_a s_b rewritten as rho^2 (a^2 + b^2 - rho^2) / (a b + s_a s_b)
/// so that no term cancels: every piece is non-negative, which keeps the
/// relative error at rounding level even for slivers.
fn quadrant_area(rho: f64, a: f64, b: f64) -> f64 {
    if !(rho > 0.0 && a > 0.0 && b > 0.0) {
        return 0.0;
    }
    let a = a.min(rho);
    let b = b.min(rho);
    let rho_sq = rho * rho;
    // s^2 = (rho - a)(rho + a) is exact to rounding even when a is near rho;
    // a^2 + b^2 - rho^2 is formed as small square minus small square so a
    // sliver (one side tiny, the other near rho) keeps its relative precision.
    let s_a_sq = (rho - a) * (rho + a);
    let s_b_sq = (rho - b) * (rho + b);
    let excess = if a >= b {
        b * b - s_a_sq
    } else {
        a * a - s_b_sq
    };
    if excess <= 0.0 {
        return a * b;
    }
    let (s_a, s_b) = (s_a_sq.sqrt(), s_b_sq.sqrt());
    let angle = (rho_sq * excess / (a * b + s_a * s_b)).atan2(s_a * b + a * s_b);
    0.5 * (s_b * b + a * s_a + rho_sq * angle)
}

/// Volume of the ball of radius `r` centred at the origin within
/// [0, x] x [0, y] x [0, z], each in [0, r]. `pieces` > 1 splits every
/// quadrature interval further (used by tests to check convergence).
fn octant_volume(r: f64, x: f64, y: f64, z: f64, pieces: usize) -> f64 {
    let mut s = [x, y, z];
    s.sort_by(f64::total_cmp);
    // Integrating along the shortest side keeps the interval short and the
    // slices' kinks (near x = r for short sides) out of it.
    let [x, y, z] = s;
    if x <= 0.0 {
        return 0.0;
    }
    if x >= r {
        return PI / 6.0 * r * r * r;
    }
    if x * x + y * y + z * z <= r * r {
        return x * y * z;
    }
    if y >= r {
        // One plane: a quarter of the slab 0 < x' < x of the ball.
        return PI / 4.0 * x * (r * r - x * x / 3.0);
    }
    // V = int_0^x A(x') dx' with A the quadrant area of the slice of radius
    // rho = sqrt(r^2 - x'^2). Substituting x' = r sin(theta) (rho = r
    // cos(theta), dx' = rho dtheta) removes the square-root branch at x' = r.
    // A has kinks where rho equals y, z or the corner distance; the
    // quadrature intervals end there.
    let theta_of = |k: f64| ((r - k) * (r + k)).sqrt().atan2(k);
    let theta_end = x.atan2(((r - x) * (r + x)).sqrt());
    let mut cuts = [0.0, theta_end, theta_end, theta_end, theta_end];
    for (slot, k) in [y, z, y.hypot(z)].into_iter().enumerate() {
        if k < r {
            cuts[slot + 2] = theta_of(k).clamp(0.0, theta_end);
        }
    }
    cuts.sort_by(f64::total_cmp);
    let slice = |theta: f64| {
        let rho = r * theta.cos();
        quadrant_area(rho, y, z) * rho
    };
    cuts.windows(2)
        .filter(|w| w[1] > w[0])
        .map(|w| integrate(&slice, w[0], w[1], pieces))
        .sum()
}

/// Gauss-Legendre points per quadrature interval.
const GL_POINTS: usize = 20;

/// Nodes and weights of `n`-point Gauss-Legendre quadrature on [0, 1]
/// (Newton iteration on the Legendre recurrence, as in Numerical Recipes'
/// `gauleg`).
fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut rule = vec![(0.0, 0.0); n];
    for i in 0..n.div_ceil(2) {
        let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let dx = p1 / dp;
            x -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        // Map [-1, 1] to [0, 1].
        rule[i] = (0.5 * (1.0 - x), 0.5 * w);
        rule[n - 1 - i] = (0.5 * (1.0 + x), 0.5 * w);
    }
    rule
}

fn gl_rule() -> &'static [(f64, f64)] {
    static RULE: OnceLock<Vec<(f64, f64)>> = OnceLock::new();
    RULE.get_or_init(|| gauss_legendre(GL_POINTS))
}

/// Integral of `f` over [p, q] in `pieces` equal parts. Each part is mapped
/// through theta = p + h (3t^2 - 2t^3), whose derivative vanishes at both
/// ends: the (theta - kink)^(3/2) behaviour of the slice areas at the
/// interval ends becomes smooth in t, and Gauss-Legendre converges
/// geometrically again.
fn integrate(f: &impl Fn(f64) -> f64, p: f64, q: f64, pieces: usize) -> f64 {
    let pieces = pieces.max(1);
    let h = (q - p) / pieces as f64;
    let mut sum = 0.0;
    for j in 0..pieces {
        let a = p + j as f64 * h;
        for &(t, w) in gl_rule() {
            let u = t * t * (3.0 - 2.0 * t);
            let du = 6.0 * t * (1.0 - t);
            sum += w * du * f(a + h * u);
        }
    }
    sum * h
}

// ---------------------------------------------------------------------------
// Axial distances.

/// Distance (m) from `o` along axis direction `k` to the first geometry hit
/// within `t_max`, with the surface hit; `None` when nothing is hit. In a
/// periodic domain horizontal rays leaving an edge continue from the
/// opposite edge, as photons do; one that comes out under the floor there
/// stops at the edge.
fn trace_axis(scene: &Scene, o: Vec3, k: usize, t_max: f32) -> Option<(f32, u32)> {
    // Bounds the loop when a tiny periodic domain meets a long ray.
    const MAX_STEPS: usize = 256;
    let geo = &scene.geometry;
    let dir = DIRECTIONS[k];
    let axis = k / 2;
    let forward = k.is_multiple_of(2);
    let size = geo.domain_size_m();
    let wraps = scene.domain.periodic && axis < 2;
    let mut origin = o;
    let mut travelled = 0.0f32;
    for _ in 0..MAX_STEPS {
        let remaining = t_max - travelled;
        if remaining.is_nan() || remaining <= 0.0 {
            return None;
        }
        let wall = wraps.then(|| {
            let w = if forward {
                size[axis] - origin[axis]
            } else {
                origin[axis]
            };
            w.max(0.0)
        });
        let segment = wall.map_or(remaining, |w| w.min(remaining));
        if segment > 0.0 {
            if let Some(hit) = geo.intersect(origin, dir, segment) {
                return Some((travelled + hit.t, hit.surface));
            }
        }
        match wall {
            Some(w) if w < remaining => {
                travelled += w;
                // Where the floor does not match across a periodic edge the
                // water has a step there: a ray wrapping from the water into
                // the ground has met it at the edge.
                let under_floor = |p: Vec3| geo.floor_depth_at(p.x, p.y).is_some_and(|d| p.z < -d);
                let mut edge = origin;
                edge[axis] = if forward { size[axis] } else { 0.0 };
                origin[axis] = if forward { 0.0 } else { size[axis] };
                if under_floor(origin) && !under_floor(edge) {
                    return Some((travelled, FLOOR));
                }
            }
            _ => return None,
        }
    }
    None
}

/// Distance (m) from `o` along axis direction `k` to the boundaries known in
/// closed form: the mean sea surface z = 0 (+z) and, with open edges, the
/// domain walls. Negative when `o` is outside the water; infinite when there
/// is no such boundary.
fn analytic_distance(scene: &Scene, o: Vec3, k: usize) -> f32 {
    let size = scene.geometry.domain_size_m();
    let open = !scene.domain.periodic;
    match k {
        0 if open => size[0] - o.x,
        1 if open => o.x,
        2 if open => size[1] - o.y,
        3 if open => o.y,
        4 => -o.z,
        _ => f32::INFINITY,
    }
}

/// `r` made usable as a cap: NaN and negative radii become 0.
fn cap_radius(r: f32) -> f32 {
    r.max(0.0)
}

/// Axial distances from `o` by tracing six axis rays through the scene: the
/// sea surface z = 0 (+z: distance -o.z), the floor and targets
/// ([`crate::geometry::Geometry::intersect`]), and, when the domain edges are
/// open, the walls x = 0, x = size_x, y = 0, y = size_y; each capped at `r`.
/// In a periodic domain horizontal rays wrap around the edges, and one that
/// wraps from the water into the ground (a floor that does not match
/// across the edge) stops at the edge. A site
/// outside the water gets 0 toward the boundary it is beyond; a non-finite
/// site gets all zeros.
pub fn axial_distances_traced(scene: &Scene, o: Vec3, r: f32) -> AxialDistances {
    let r = cap_radius(r);
    if !o.is_finite() {
        return AxialDistances([0.0; 6]);
    }
    AxialDistances(std::array::from_fn(|k| {
        let hit = trace_axis(scene, o, k, r).map_or(f32::INFINITY, |(t, _)| t);
        hit.min(analytic_distance(scene, o, k)).clamp(0.0, r)
    }))
}

/// A precomputed grid of axial distances over the water volume, trilinearly
/// interpolated: the cheap alternative to [`axial_distances_traced`].
///
/// The grid holds only what needs tracing — distances to the floor and
/// targets, wrapped in periodic domains, capped at `max_distance_m` — and the
/// sea surface and open walls are applied in closed form at query time, so
/// they are exact. Nodes below the floor hold the linear extension of the
/// water's values (negative toward the floor), so cells cut by a planar floor
/// interpolate the floor distance exactly instead of mixing in meaningless
/// values from inside the ground. Errors remain where a ray's first hit jumps
/// (rays grazing a target's edge) and in cells that reach into a target.
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
    /// R = 2 m, capping at 4 m gives errors up to R; 30 m gives none). The
    /// grid spans the domain horizontally and from the
    /// surface to one spacing below the deepest geometry (or
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
    let forward = |q: Vec3, k: usize| {
        trace_axis(scene, q, k, max_distance_m).map_or(max_distance_m, |(t, _)| t)
    };
    // A node on or below the floor cannot trace its own values (rays from a
    // surface ignore it). Its values continue the water's linearly: moving
    // the site by m along a direction shortens that direction's distance by
    // m, from a point just above the floor; and for horizontal directions
    // whose backward ray meets the floor, the negative distance back to it
    // (exact for a planar sloping floor).
    let lift = 4.0 * geo.epsilon_m();
    match geo.floor_depth_at(p.x, p.y).map(|d| -d) {
        Some(floor_z) if p.z < floor_z + lift => {
            let q = Vec3::new(p.x, p.y, floor_z + lift);
            std::array::from_fn(|k| {
                if k < 4 {
                    let back = k ^ 1;
                    if let Some((t, FLOOR)) = trace_axis(scene, p, back, max_distance_m) {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;
    use crate::scene::Overrides;
    use std::path::Path;

    fn cap_volume(r: f64, d: f64) -> f64 {
        let h = r - d;
        PI * h * h * (3.0 * r - h) / 3.0
    }

    /// Circular segment beyond a chord at distance d from the centre.
    fn segment_area(r: f64, d: f64) -> f64 {
        if d >= r {
            return 0.0;
        }
        r * r * (d / r).acos() - d * (r * r - d * d).sqrt()
    }

    /// Adaptive Simpson to an absolute tolerance (an independent quadrature).
    fn simpson(f: &dyn Fn(f64) -> f64, a: f64, b: f64, tol: f64) -> f64 {
        /// One panel [a, b] with f at a, the midpoint and b, and its Simpson estimate.
        fn step(
            f: &dyn Fn(f64) -> f64,
            [a, b]: [f64; 2],
            [fa, fm, fb]: [f64; 3],
            whole: f64,
            tol: f64,
            depth: u32,
        ) -> f64 {
            let m = 0.5 * (a + b);
            let (flm, frm) = (f(0.5 * (a + m)), f(0.5 * (m + b)));
            let left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
            let right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
            let diff = left + right - whole;
            if depth == 0 || diff.abs() <= 15.0 * tol {
                return left + right + diff / 15.0;
            }
            step(f, [a, m], [fa, flm, fm], left, 0.5 * tol, depth - 1)
                + step(f, [m, b], [fm, frm, fb], right, 0.5 * tol, depth - 1)
        }
        let (fa, fm, fb) = (f(a), f(0.5 * (a + b)), f(b));
        let whole = (b - a) / 6.0 * (fa + 4.0 * fm + fb);
        step(f, [a, b], [fa, fm, fb], whole, tol, 40)
    }

    /// Volume of {x > a, y > b} within the ball of radius r, as the integral
    /// over x of the circular segment {y > b} of the slice — an independent
    /// route (acos segment formula, adaptive Simpson) to the overlap of two
    /// perpendicular caps.
    fn two_cap_overlap(r: f64, a: f64, b: f64) -> f64 {
        let end = (r * r - b * b).sqrt();
        if a >= end {
            return 0.0;
        }
        let f = |x: f64| segment_area((r * r - x * x).max(0.0).sqrt(), b);
        simpson(&f, a, end, 1e-15)
    }

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs().max(f64::MIN_POSITIVE)
    }

    /// Gauss-Legendre nodes integrate polynomials up to degree 2n - 1 exactly.
    #[test]
    fn gauss_legendre_is_exact_for_polynomials() {
        let rule = gauss_legendre(GL_POINTS);
        for k in 0..2 * GL_POINTS {
            let q: f64 = rule.iter().map(|&(t, w)| w * t.powi(k as i32)).sum();
            assert!(rel(q, 1.0 / (k as f64 + 1.0)) < 1e-13, "degree {k}: {q}");
        }
    }

    /// The quadrant area matches the direct integral int_0^a min(b, sqrt(rho^2 - u^2)) du.
    #[test]
    fn quadrant_area_matches_direct_integral() {
        let mut rng = Pcg32::new(11, 0);
        for _ in 0..200 {
            let rho = 0.5 + rng.uniform_f64();
            let a = 1.2 * rho * rng.uniform_f64();
            let b = 1.2 * rho * rng.uniform_f64();
            let f = |u: f64| b.min((rho * rho - u * u).max(0.0).sqrt());
            let direct = simpson(&f, 0.0, a.min(rho), 1e-14);
            let got = quadrant_area(rho, a, b);
            assert!(
                (got - direct).abs() < 1e-11,
                "rho {rho} a {a} b {b}: {got} vs {direct}"
            );
        }
    }

    /// Splitting every quadrature interval into 7 changes the octant volumes
    /// by less than 1e-12 relative: the 20-point rule has converged.
    #[test]
    fn octant_quadrature_has_converged() {
        let mut rng = Pcg32::new(12, 0);
        let r = 1.7;
        let mut worst = 0.0f64;
        for _ in 0..2000 {
            let s = [0, 1, 2].map(|_| r * rng.uniform_f64());
            let coarse = octant_volume(r, s[0], s[1], s[2], 1);
            let fine = octant_volume(r, s[0], s[1], s[2], 7);
            worst = worst.max(rel(coarse, fine));
        }
        eprintln!("octant quadrature: worst relative change on refinement {worst:.2e}");
        assert!(worst < 1e-12, "{worst}");
    }

    /// Test 2: against closed forms to 1e-6 relative (observed ~1e-14).
    /// One plane at distance d: V = 4/3 pi r^3 - pi h^2 (3r - h)/3, h = r - d,
    /// on each of the six sides. Two perpendicular planes a, b:
    /// V = sphere - cap(a) - cap(b) + overlap(a, b), the overlap integrated
    /// independently ([`two_cap_overlap`]). Two opposite planes: the caps
    /// never overlap. Degenerate boxes: V = 0, half, quarter, eighth.
    #[test]
    fn clipped_sphere_matches_closed_forms() {
        let r = 1.3;
        let sphere = sphere_volume(r);
        let mut worst = 0.0f64;
        let mut check = |got: f64, want: f64, what: &str| {
            let e = if want == 0.0 {
                got.abs()
            } else {
                rel(got, want)
            };
            assert!(e < 1e-6, "{what}: {got} vs {want}");
            worst = worst.max(e);
        };
        for d in [0.0, 1e-9, 0.01, 0.3, 0.65, 1.0, 1.29, 1.3] {
            for side in 0..6 {
                let mut b = [r; 6];
                b[side] = d;
                let want = sphere - cap_volume(r, d);
                check(
                    clipped_sphere_volume(r, &b),
                    want,
                    &format!("cap d {d} side {side}"),
                );
            }
        }
        let pairs = [
            (0.0, 0.0),
            (0.1, 0.2),
            (0.5, 0.5),
            (0.9, 0.3),
            (1.0, 1.0),
            (1.2, 0.05),
        ];
        for &(a, bb) in &pairs {
            // Perpendicular pairs on several axis combinations.
            for (i, j) in [(0, 2), (1, 4), (3, 5), (5, 0)] {
                let mut b = [r; 6];
                b[i] = a;
                b[j] = bb;
                let want =
                    sphere - cap_volume(r, a) - cap_volume(r, bb) + two_cap_overlap(r, a, bb);
                check(
                    clipped_sphere_volume(r, &b),
                    want,
                    &format!("perpendicular {a} {bb}"),
                );
            }
            // Opposite planes.
            let mut b = [r; 6];
            b[2] = a;
            b[3] = bb;
            let want = sphere - cap_volume(r, a) - cap_volume(r, bb);
            check(
                clipped_sphere_volume(r, &b),
                want,
                &format!("opposite {a} {bb}"),
            );
        }
        // Thin slabs between opposite planes: pi (r^2 w - (a^3 + b^3)/3),
        // w = a + b, where sphere - cap - cap would cancel.
        for (a, bb) in [(1e-6, 2e-6), (1e-3, 0.0), (0.02, 0.03)] {
            let want = PI * (r * r * (a + bb) - (a * a * a + bb * bb * bb) / 3.0);
            let got = clipped_sphere_volume(r, &[r, r, r, r, a, bb]);
            check(got, want, &format!("slab {a} {bb}"));
        }
        let mut b = [r; 6];
        b[0] = 0.0;
        b[1] = 0.0;
        check(clipped_sphere_volume(r, &b), 0.0, "both x sides at O");
        check(
            clipped_sphere_volume(r, &[0.0, r, r, r, r, r]),
            sphere / 2.0,
            "half",
        );
        check(
            clipped_sphere_volume(r, &[0.0, r, 0.0, r, r, r]),
            sphere / 4.0,
            "quarter",
        );
        check(
            clipped_sphere_volume(r, &[r, 0.0, r, 0.0, 0.0, r]),
            sphere / 8.0,
            "eighth",
        );
        check(clipped_sphere_volume(r, &[r; 6]), sphere, "no planes");
        // A box inside the sphere is just the box.
        check(clipped_sphere_volume(r, &[0.5; 6]), 1.0, "inner box");
        eprintln!("clipped sphere vs closed forms: worst relative error {worst:.2e}");
    }

    /// Fraction of `n` uniform points of the cube [-r, r]^3 inside the sphere
    /// and the box `b`, counted in parallel chunks with per-chunk streams.
    fn mc_clipped_sphere(r: f64, b: &[f64; 6], n: u64, seed: u64) -> f64 {
        const CHUNK: u64 = 100_000;
        let hits: u64 = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut rng = Pcg32::new(seed, c);
                let count = CHUNK.min(n - c * CHUNK);
                let mut hits = 0u64;
                for _ in 0..count {
                    let x = (2.0 * rng.uniform_f64() - 1.0) * r;
                    let y = (2.0 * rng.uniform_f64() - 1.0) * r;
                    let z = (2.0 * rng.uniform_f64() - 1.0) * r;
                    let inside = x * x + y * y + z * z <= r * r
                        && x <= b[0]
                        && -x <= b[1]
                        && y <= b[2]
                        && -y <= b[3]
                        && z <= b[4]
                        && -z <= b[5];
                    hits += inside as u64;
                }
                hits
            })
            .sum();
        hits as f64 / n as f64
    }

    /// Test 1: the clipped-sphere volume against Monte Carlo, 10^7 points per
    /// configuration, 24 random configurations with 1 to 6 active planes
    /// (B < R), plus a plane through O and two close opposite planes. The
    /// estimate 8 r^3 p_hat has standard error 8 r^3 sqrt(p (1 - p) / n);
    /// the tolerance is 4 standard errors.
    #[test]
    fn clipped_sphere_matches_monte_carlo() {
        let r = 1.3;
        let n = 10_000_000u64;
        let mut rng = Pcg32::new(2026, 0);
        let mut configs = Vec::new();
        for i in 0..24 {
            let active = 1 + i % 6;
            let mut sides = [0usize, 1, 2, 3, 4, 5];
            for s in 0..6 {
                let j = s + rng.below((6 - s) as u32) as usize;
                sides.swap(s, j);
            }
            let mut b = [r; 6];
            for &s in &sides[..active] {
                b[s] = r * rng.uniform_f64();
            }
            configs.push(b);
        }
        configs[3][5] = 0.0; // a plane through O (-z), with others
        configs[7][0] = 0.0;
        configs[10][2] = 0.08 * r; // two opposite planes, both close
        configs[10][3] = 0.05 * r;
        configs.push([0.1 * r, 0.12 * r, r, r, r, r]);
        let cube = 8.0 * r * r * r;
        let mut worst_z = 0.0f64;
        for (i, b) in configs.iter().enumerate() {
            let exact = clipped_sphere_volume(r, b);
            let p_hat = mc_clipped_sphere(r, b, n, 100 + i as u64);
            let p = exact / cube;
            let se = cube * (p * (1.0 - p) / n as f64).sqrt();
            let z = (cube * p_hat - exact) / se;
            worst_z = worst_z.max(z.abs());
            assert!(
                z.abs() < 4.0,
                "config {i} {b:?}: exact {exact}, MC {} ({z:.2} SE)",
                cube * p_hat
            );
        }
        eprintln!(
            "clipped sphere vs Monte Carlo: {} configurations, worst |z| = {worst_z:.2} SE",
            configs.len()
        );
    }

    /// Test 3: the ellipsoid volume. All B = R gives the sphere; one side
    /// B_+z = d gives the upper half-ellipsoid (2/3 pi R^2 d) plus the lower
    /// half-sphere; and the volume of {D' <= R} measured by Monte Carlo (2e6
    /// uniform points of the cube [-R, R]^3 per configuration, tolerance 4
    /// standard errors) matches.
    #[test]
    fn ellipsoid_volume_matches_its_region() {
        let r = 1.3f64;
        assert!(rel(ellipsoid_volume(&[r; 6]), sphere_volume(r)) < 1e-15);
        for d in [0.0, 0.2, 0.9] {
            let mut b = [r; 6];
            b[4] = d;
            let want = 2.0 / 3.0 * PI * r * r * d + sphere_volume(r) / 2.0;
            let got = ellipsoid_volume(&b);
            assert!((got - want).abs() <= 1e-14 * want, "d {d}: {got} vs {want}");
        }
        let rf = r as f32;
        let configs = [
            AxialDistances([rf; 6]),
            AxialDistances([rf, rf, rf, rf, 0.3, rf]),
            AxialDistances([0.2, 1.0, rf, 0.0, 0.7, 0.4]),
            AxialDistances([0.1, 0.15, 0.9, 0.5, 1.2, 0.05]),
        ];
        let n = 2_000_000u64;
        let cube = 8.0 * r * r * r;
        for (i, b) in configs.iter().enumerate() {
            let mut rng = Pcg32::new(31, i as u64);
            let mut hits = 0u64;
            for _ in 0..n {
                let p = Vec3::new(
                    (2.0 * rng.uniform_f32() - 1.0) * rf,
                    (2.0 * rng.uniform_f32() - 1.0) * rf,
                    (2.0 * rng.uniform_f32() - 1.0) * rf,
                );
                hits += (ellipsoid_distance(p, rf, b) <= rf) as u64;
            }
            let exact = ellipsoid_volume(&b.to_f64());
            let p = exact / cube;
            let se = cube * (p * (1.0 - p) / n as f64).sqrt();
            let mc = cube * hits as f64 / n as f64;
            let z = (mc - exact) / se;
            eprintln!("ellipsoid config {i}: exact {exact:.6}, MC {mc:.6} ({z:+.2} SE)");
            assert!(z.abs() < 4.0, "config {i}: exact {exact}, MC {mc}");
        }
        // Offsets toward a side with B = 0 are outside; along it, inside.
        let b = AxialDistances([1.0, 0.0, 1.0, 1.0, 1.0, 1.0]);
        assert_eq!(
            ellipsoid_distance(Vec3::new(-1e-6, 0.0, 0.0), 1.0, &b),
            f32::INFINITY
        );
        assert_eq!(ellipsoid_distance(Vec3::new(0.0, 0.5, 0.0), 1.0, &b), 0.5);
    }

    /// Test 4: the clipped disc. Closed forms: one line at d, pi r^2 minus the
    /// segment r^2 acos(d/r) - d sqrt(r^2 - d^2); two opposite lines, or two
    /// perpendicular lines whose corner lies outside the disc, minus both
    /// segments (they cannot overlap). Monte Carlo: 4e6 points of the square
    /// per configuration, within 4 standard errors.
    #[test]
    fn clipped_disc_matches_closed_forms_and_monte_carlo() {
        let r = 0.8f64;
        let disc = PI * r * r;
        for d in [0.0, 1e-7, 0.2, 0.5, 0.79, 0.8] {
            for side in 0..4 {
                let mut b = [r; 4];
                b[side] = d;
                let want = disc - segment_area(r, d);
                let got = clipped_disc_area(r, &b);
                assert!(rel(got, want) < 1e-12, "d {d} side {side}: {got} vs {want}");
            }
        }
        for (a, c) in [(0.1, 0.3), (0.6, 0.7), (0.0, 0.5)] {
            let want = disc - segment_area(r, a) - segment_area(r, c);
            let opposite = clipped_disc_area(r, &[a, c, r, r]);
            assert!(rel(opposite, want) < 1e-12, "opposite {a} {c}: {opposite}");
            if a * a + c * c >= r * r {
                let perpendicular = clipped_disc_area(r, &[a, r, c, r]);
                assert!(
                    rel(perpendicular, want) < 1e-12,
                    "perp {a} {c}: {perpendicular}"
                );
            }
        }
        assert_eq!(clipped_disc_area(r, &[0.0, 0.0, r, r]), 0.0);
        let configs = [
            [0.3, r, 0.2, r],
            [0.1, 0.75, 0.6, 0.05],
            [0.0, r, 0.4, 0.7],
            [0.6; 4],
        ];
        let n = 4_000_000u64;
        let square = 4.0 * r * r;
        for (i, b) in configs.iter().enumerate() {
            let mut rng = Pcg32::new(41, i as u64);
            let mut hits = 0u64;
            for _ in 0..n {
                let u = (2.0 * rng.uniform_f64() - 1.0) * r;
                let v = (2.0 * rng.uniform_f64() - 1.0) * r;
                let inside =
                    u * u + v * v <= r * r && u <= b[0] && -u <= b[1] && v <= b[2] && -v <= b[3];
                hits += inside as u64;
            }
            let exact = clipped_disc_area(r, b);
            let p = exact / square;
            let se = square * (p * (1.0 - p) / n as f64).sqrt();
            let mc = square * hits as f64 / n as f64;
            let z = (mc - exact) / se;
            eprintln!("disc config {i}: exact {exact:.6}, MC {mc:.6} ({z:+.2} SE)");
            assert!(z.abs() < 4.0, "config {i}: exact {exact}, MC {mc}");
        }
    }

    #[test]
    fn modes_parse_and_print() {
        for m in BoundaryMode::ALL {
            assert_eq!(m.as_str().parse::<BoundaryMode>().unwrap(), m);
            assert_eq!(m.to_string(), m.as_str());
        }
        let e = "sphere".parse::<BoundaryMode>().unwrap_err().to_string();
        assert!(
            e.contains("'sphere'") && e.contains("clipped-sphere"),
            "{e}"
        );
        let b = AxialDistances::unbounded(2.0);
        for m in BoundaryMode::ALL {
            assert!(rel(m.volume(2.0, &b), sphere_volume(2.0)) < 1e-12, "{m}");
        }
    }

    /// A 20 m x 10 m domain, floor at 5 m, a 2 x 2 x 1 m box spanning
    /// x 9..11, y 4..6, z -4.5..-3.5.
    fn box_scene(edges: &str) -> Scene {
        let toml = format!(
            r#"
[spectral]
start_nm = 500.0
end_nm = 500.0
bands = 1
[sun]
zenith_deg = 30.0
irradiance = 1.0
[domain]
size_m = [20.0, 10.0]
edges = "{edges}"
[water]
iop = {{ a = 0.1, b = 0.1 }}
[bottom]
depth_m = 5.0
reflectance = 0.1
[[target]]
kind = "box"
center_m = [10.0, 5.0, -4.0]
size_m = [2.0, 2.0, 1.0]
reflectance = 0.2
[photons]
count = 1000
"#
        );
        Scene::parse(&toml, Path::new("t.toml"), &Overrides::default())
            .unwrap_or_else(|e| panic!("{e}"))
    }

    fn assert_close(got: AxialDistances, want: [f32; 6], what: &str) {
        for k in 0..6 {
            assert!(
                (got.0[k] - want[k]).abs() < 1e-4,
                "{what}: side {k}: {:?} vs {want:?}",
                got.0
            );
        }
    }

    /// Test 5: traced distances to the surface, floor, box and walls, the
    /// cap at R, and periodic edges (wrapping rays, R when nothing is hit).
    #[test]
    fn traced_distances_in_a_box_scene() {
        let s = box_scene("open");
        let t = |o: Vec3, r| axial_distances_traced(&s, o, r);
        // Surface 2 m up, floor 3 m down, wall 3 m to -x; the rest beyond R.
        assert_close(
            t(Vec3::new(3.0, 5.0, -2.0), 4.0),
            [4.0, 3.0, 4.0, 4.0, 2.0, 3.0],
            "o1",
        );
        assert_close(t(Vec3::new(3.0, 5.0, -2.0), 1.0), [1.0; 6], "o1 capped");
        // Beside the box: its -x face 2 m ahead, floor 0.8 m down.
        assert_close(
            t(Vec3::new(7.0, 4.5, -4.2), 4.0),
            [2.0, 4.0, 4.0, 4.0, 4.0, 0.8],
            "o2",
        );
        // Above the box: its top 1.5 m down.
        assert_close(
            t(Vec3::new(10.0, 5.0, -2.0), 4.0),
            [4.0, 4.0, 4.0, 4.0, 2.0, 1.5],
            "o3",
        );
        // Near the -x, +y walls and the floor.
        assert_close(
            t(Vec3::new(0.5, 9.7, -4.9), 4.0),
            [4.0, 0.5, 0.3, 4.0, 4.0, 0.1],
            "o4",
        );
        // Outside the water: zero toward the boundary crossed.
        assert_eq!(t(Vec3::new(3.0, 5.0, 0.5), 4.0).0[4], 0.0);
        assert_eq!(t(Vec3::new(-1.0, 5.0, -1.0), 4.0).0[1], 0.0);
        assert_eq!(t(Vec3::NAN, 4.0).0, [0.0; 6]);

        let p = box_scene("periodic");
        let t = |o: Vec3, r| axial_distances_traced(&p, o, r);
        assert_close(
            t(Vec3::new(3.0, 5.0, -2.0), 4.0),
            [4.0, 4.0, 4.0, 4.0, 2.0, 3.0],
            "p1",
        );
        // +x wraps at 0.5 m and meets the box's -x face at x = 9.
        assert_close(
            t(Vec3::new(19.5, 5.0, -4.0), 10.0),
            [9.5, 8.5, 10.0, 10.0, 4.0, 1.0],
            "p2",
        );
        assert_close(
            t(Vec3::new(19.5, 5.0, -4.0), 4.0),
            [4.0, 4.0, 4.0, 4.0, 4.0, 1.0],
            "p2 capped",
        );
    }

    /// Test 6: the grid against tracing at 20 000 random water sites, R = 3 m,
    /// spacing 0.25 m. A direction's field is discontinuous where its ray
    /// starts or stops meeting the box: across the box's faces parallel to
    /// the ray, and in cells reaching into the box. Away from those (2
    /// spacings) the field is linear or constant per cell, so interpolation
    /// is exact up to rounding; the bound asserted is the loose 2 x spacing.
    /// Next to the floor the below-floor extension must keep the -z distance
    /// exact (1 mm). A periodic grid must carry wrapped distances.
    #[test]
    fn grid_matches_tracing() {
        let s = box_scene("open");
        let h = 0.25f32;
        let r = 3.0f32;
        let grid = BoundaryGrid::build(&s, h, 4.0).unwrap();
        assert_eq!(
            grid.bytes(),
            BoundaryGrid::planned_bytes(&s, h, 4.0).unwrap()
        );
        let (lo, hi) = (Vec3::new(9.0, 4.0, -4.5), Vec3::new(11.0, 6.0, -3.5));
        let m = 2.0 * h;
        let smooth = |o: Vec3, k: usize| {
            let near_box = (0..3).all(|a| o[a] > lo[a] - m && o[a] < hi[a] + m);
            let near_parallel_face = (0..3)
                .filter(|&a| a != k / 2)
                .any(|a| (o[a] - lo[a]).abs() < m || (o[a] - hi[a]).abs() < m);
            !near_box && !near_parallel_face
        };
        let mut rng = Pcg32::new(61, 0);
        let (mut all_sum, mut all_max, mut all_n) = (0f64, 0f32, 0usize);
        let (mut smooth_sum, mut smooth_max, mut smooth_n) = (0f64, 0f32, 0usize);
        let (mut floor_max, mut floor_n) = (0f32, 0usize);
        let mut sites = 0;
        while sites < 20_000 {
            let o = Vec3::new(
                20.0 * rng.uniform_f32(),
                10.0 * rng.uniform_f32(),
                -5.0 * rng.uniform_f32(),
            );
            let in_box = (0..3).all(|a| o[a] > lo[a] && o[a] < hi[a]);
            if in_box || o.z > -1e-3 || o.z < -4.999 {
                continue;
            }
            sites += 1;
            let traced = axial_distances_traced(&s, o, r);
            let interp = grid.distances(o, r);
            for k in 0..6 {
                let e = (traced.0[k] - interp.0[k]).abs();
                all_n += 1;
                all_sum += e as f64;
                all_max = all_max.max(e);
                if smooth(o, k) {
                    smooth_n += 1;
                    smooth_sum += e as f64;
                    smooth_max = smooth_max.max(e);
                    if k == 5 && o.z < -5.0 + m {
                        floor_n += 1;
                        floor_max = floor_max.max(e);
                    }
                }
            }
        }
        eprintln!(
            "grid vs traced (spacing {h} m, R {r} m, {} bytes, {sites} sites): \
             all {all_n} distances mean {:.2e} m max {all_max:.3} m; \
             away from box discontinuities {smooth_n} mean {:.2e} m max {smooth_max:.2e} m; \
             -z within {m} m of the floor {floor_n} max {floor_max:.2e} m",
            grid.bytes(),
            all_sum / all_n as f64,
            smooth_sum / smooth_n as f64,
        );
        assert!(floor_n > 100 && smooth_n > all_n / 2);
        assert!(smooth_max < 2.0 * h, "{smooth_max}");
        assert!(floor_max < 1e-3, "{floor_max}");

        let p = box_scene("periodic");
        let grid = BoundaryGrid::build(&p, h, 10.0).unwrap();
        for o in [Vec3::new(19.5, 5.0, -4.0), Vec3::new(19.9, 5.1, -3.9)] {
            let want = axial_distances_traced(&p, o, 10.0);
            let got = grid.distances(o, 10.0);
            assert!(
                (want.0[0] - got.0[0]).abs() < 1e-3,
                "{o}: {want:?} vs {got:?}"
            );
            assert!((want.0[0] - (29.0 - o.x)).abs() < 1e-4, "{o}: {want:?}");
        }
    }

    /// The grid on the built-in coastal scene (floor sloping 14.5 m over
    /// 200 m, periodic edges), 1 m spacing, R = 2 m, at 20 000 water sites
    /// more than 5 m from the targets. On a gentle slope the horizontal
    /// distance toward the shore grows ~14 m per metre of height, so a grid
    /// that stores distances capped at 2R has a kink inside the cells next to
    /// the floor and interpolates it badly; storing up to 30 m keeps the
    /// field linear there (the below-floor extension is exact for a planar
    /// slope). The periodic edge joins the 0.5 m shore to 15 m water: a -x
    /// ray near the shore either meets the slope or passes over the step
    /// into deep water, a discontinuity like a target's edge, so sites
    /// within 15 m of the edge are reported apart. Asserts the 30 m grid is
    /// within 1 cm away from the step.
    #[test]
    fn grid_on_a_sloping_floor() {
        let s = Scene::coastal(&Overrides::default()).unwrap();
        let r = 2.0f32;
        let targets = [
            Vec3::new(52.0, 140.0, -3.95),
            Vec3::new(105.0, 150.0, -7.65),
        ];
        let mut rng = Pcg32::new(71, 0);
        let mut sites = Vec::new();
        while sites.len() < 20_000 {
            let (x, y) = (200.0 * rng.uniform_f32(), 200.0 * rng.uniform_f32());
            let far = targets
                .iter()
                .all(|t| (t.x - x).abs() > 6.5 || (t.y - y).abs() > 6.5);
            let depth = s.geometry.floor_depth_at(x, y).unwrap();
            if far {
                sites.push(Vec3::new(
                    x,
                    y,
                    -depth * (0.001 + 0.998 * rng.uniform_f32()),
                ));
            }
        }
        let traced: Vec<_> = sites
            .iter()
            .map(|&o| axial_distances_traced(&s, o, r))
            .collect();
        let mut worst_interior = 0.0;
        for max_distance in [2.0 * r, 30.0] {
            let grid = BoundaryGrid::build(&s, 1.0, max_distance).unwrap();
            // [interior, near the periodic step] x per side.
            let (mut sum, mut max, mut n) = ([[0f64; 6]; 2], [[0f32; 6]; 2], [0usize; 2]);
            for (o, t) in sites.iter().zip(&traced) {
                let g = grid.distances(*o, r);
                let part = usize::from(o.x < 15.0 || o.x > 185.0);
                n[part] += 1;
                for k in 0..6 {
                    let e = (t.0[k] - g.0[k]).abs();
                    sum[part][k] += e as f64;
                    max[part][k] = max[part][k].max(e);
                }
            }
            for (part, name) in ["interior", "near the periodic step"].iter().enumerate() {
                let mean = sum[part].map(|v| format!("{:.1e}", v / n[part] as f64));
                eprintln!(
                    "coastal grid 1 m, stored up to {max_distance} m ({} bytes), {name} ({} sites): \
                     mean error per side {mean:?} m, max {:.3?} m",
                    grid.bytes(),
                    n[part],
                    max[part],
                );
            }
            worst_interior = max[0].iter().copied().fold(0.0, f32::max);
        }
        assert!(worst_interior < 0.01, "{worst_interior}");
    }

    #[test]
    fn grid_rejects_bad_spacing() {
        let s = box_scene("periodic");
        for bad in [0.0, -1.0, f32::NAN, f32::INFINITY, 1e-9] {
            assert!(BoundaryGrid::build(&s, bad, 4.0).is_err(), "{bad}");
        }
        assert!(BoundaryGrid::build(&s, 1.0, 0.0).is_err());
    }
}
