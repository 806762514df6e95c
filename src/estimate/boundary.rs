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
//!   estimates on surfaces. Where a vertical boundary (the sea surface, the
//!   floor) cuts the sphere, the estimate is levelled by
//!   [`vertical_linear_factor`]: the density at O from a fit linear in
//!   depth, since the cut region's photons lie on one side of O and the
//!   plain ratio reads the density at their centroid.
//!
//! B comes either from six axis rays traced through the scene
//! ([`axial_distances_traced`]) or from a precomputed grid, trilinearly
//! interpolated ([`BoundaryGrid`]), the cheap alternative. Periodic domain
//! edges are not boundaries, so there the photon search continues across
//! them (the estimator searches the periodic images; `store::query` itself
//! knows nothing of the domain).
//!
//! Not for: boundaries that are not axis-aligned planes. Both modes model
//! the water near O as the box of the six axial distances, so a sloping floor
//! or a target's edge inside the sphere is only approximated; and a site must
//! lie in the water (a site on a surface should first be moved off it, e.g.
//! with [`crate::geometry::Geometry::spawn_origin`]). This module does not
//! search photons or form radiance.

pub use crate::scene::settings::BoundaryMode;
use crate::scene::{Scene, FLOOR};
use glam::Vec3;
use std::f64::consts::PI;
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

    /// The distances for a smaller search of radius `r`: each capped at r.
    pub fn capped(&self, r: f32) -> Self {
        AxialDistances(self.0.map(|d| d.min(r)))
    }
}

/// In-plane boundary distances (m) of a surface search disc, each in
/// [0, R]: along [+u, -u, +v, -v], where u and v span the surface's tangent
/// plane (u = x and v = y for a horizontal surface).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiscDistances {
    pub u: Vec3,
    pub v: Vec3,
    pub d: [f32; 4],
}

impl DiscDistances {
    /// No boundary within `r`: the whole disc, in the plane with `normal`.
    pub fn unbounded(r: f32, normal: Vec3) -> Self {
        let (u, v) = tangent_basis(normal);
        DiscDistances { u, v, d: [r; 4] }
    }

    /// The distances for a smaller search of radius `r`: each capped at r.
    pub fn capped(&self, r: f32) -> Self {
        DiscDistances {
            d: self.d.map(|d| d.min(r)),
            ..*self
        }
    }

    /// The offset's in-plane coordinates (along u, v).
    fn coords(&self, offset: Vec3) -> [f32; 2] {
        [offset.dot(self.u), offset.dot(self.v)]
    }
}

/// An orthonormal tangent basis (u, v) of the plane with unit `normal`: u
/// is horizontal (x for a horizontal plane), v = normal x u.
pub fn tangent_basis(normal: Vec3) -> (Vec3, Vec3) {
    let h = Vec3::Z.cross(normal);
    let u = if h.length_squared() > 1e-8 {
        h.normalize()
    } else {
        Vec3::X
    };
    let v = normal.cross(u).normalize();
    (u, v)
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

impl BoundaryMode {
    /// The volume (m^3) to divide by for a search of radius `r` at a site
    /// with axial distances `b`.
    pub fn volume(self, r: f32, b: &AxialDistances) -> f64 {
        match self {
            BoundaryMode::None => sphere_volume(f64::from(r).max(0.0)),
            BoundaryMode::Ellipsoid => ellipsoid_volume(&b.to_f64()),
            BoundaryMode::ClippedSphere => clipped_sphere_volume(f64::from(r), &b.to_f64()),
        }
    }

    /// The area (m^2) to divide by for a surface search of radius `r`: the
    /// disc, the disc clipped by the in-plane boundary lines (exact), or the
    /// four quarter-ellipses of the adaptive distance.
    pub fn area(self, r: f32, b: &DiscDistances) -> f64 {
        let r = f64::from(r).max(0.0);
        let d = b.d.map(|v| f64::from(v).clamp(0.0, r));
        match self {
            BoundaryMode::None => PI * r * r,
            BoundaryMode::ClippedSphere => clipped_disc_area(r, &d),
            BoundaryMode::Ellipsoid => PI / 4.0 * (d[0] + d[1]) * (d[2] + d[3]),
        }
    }

    /// Whether a surface photon at `offset` = P - O, found by a Euclidean
    /// search of radius `r`, belongs to this mode's search disc (the
    /// offset is measured in the tangent plane). A surface may go on past
    /// the lines that clip the disc (the floor under a target), so the
    /// clipped disc keeps only photons inside its lines (as the clipped
    /// sphere keeps only those inside its planes).
    pub fn accepts_in_disc(self, offset: Vec3, r: f32, b: &DiscDistances) -> bool {
        let [x, y] = b.coords(offset);
        match self {
            BoundaryMode::None => x * x + y * y <= r * r,
            BoundaryMode::ClippedSphere => {
                x * x + y * y <= r * r && x <= b.d[0] && -x <= b.d[1] && y <= b.d[2] && -y <= b.d[3]
            }
            BoundaryMode::Ellipsoid => {
                let mut sum = 0.0f32;
                for (c, (pos, neg)) in [(x, (b.d[0], b.d[1])), (y, (b.d[2], b.d[3]))] {
                    if c == 0.0 {
                        continue;
                    }
                    let side = if c > 0.0 { pos } else { neg };
                    if side.is_nan() || side <= 0.0 {
                        return false;
                    }
                    let s = c * r / side;
                    sum += s * s;
                }
                sum.sqrt() <= r
            }
        }
    }

    /// Whether a photon at `offset` = P - O, already found by a Euclidean
    /// search of radius `r`, belongs to this mode's search region.
    pub fn accepts(self, offset: Vec3, r: f32, b: &AxialDistances) -> bool {
        match self {
            BoundaryMode::None => offset.length_squared() <= r * r,
            // Within the box whose volume is counted: a photon past an
            // axial plane is beyond a boundary that does not reach it (past
            // a target's edge, beside the box on the floor below), and its
            // space is not in the volume.
            BoundaryMode::ClippedSphere => {
                let d = &b.0;
                offset.length_squared() <= r * r
                    && offset.x <= d[0]
                    && -offset.x <= d[1]
                    && offset.y <= d[2]
                    && -offset.y <= d[3]
                    && offset.z <= d[4]
                    && -offset.z <= d[5]
            }
            BoundaryMode::Ellipsoid => ellipsoid_distance(offset, r, b) <= r,
        }
    }
}

/// The factor that turns a clipped sphere's density estimate (the found
/// photons' weight over the clipped volume) into a local-linear one: the
/// density at the site itself when it varies linearly with depth across
/// the search. `r` is the radius, `b` the axial distances (only the
/// vertical ones, +z and -z, count), `first` the found photons' weighted
/// mean vertical offset from the site (m).
///
/// Why: a sphere cut by the sea surface (or the floor) keeps the part below
/// (above) the site, whose photons lie deeper (higher) on average than the
/// site. Where the photon density changes with depth, as the diffuse light
/// just below the surface does (the direct sun, not stored, feeds it on its
/// way down), dividing their weight by the clipped volume gives the
/// density at the clipped region's centroid, not at the site: 1 m below
/// the surface looking up, radiance read 5–7 % high. With the density
/// rho0 + g z across the slab z in [-b_-z, b_+z] of the sphere, the weight
/// sums are S0 = rho0 V + g M1 and S1 = rho0 M1 + g M2 (V, M1, M2 the
/// slab's volume and first and second vertical moments), so rho0 = (S0 -
/// S1 M1 / M2) / (V - M1^2 / M2), which is S0 / V times the returned
/// factor. 1 when the sphere is not cut vertically (M1 = 0). The factor is
/// held to [1/2, 2]: a boundary exactly at the site leaves the gradient
/// resting on few photons.
pub fn vertical_linear_factor(r: f64, b: &AxialDistances, first: f64) -> f64 {
    let (hi, lo) = (
        f64::from(b.0[4]).clamp(0.0, r),
        f64::from(b.0[5]).clamp(0.0, r),
    );
    if r <= 0.0 || (hi >= r && lo >= r) || !first.is_finite() {
        return 1.0;
    }
    // Moments of the sphere's slices, area pi (r^2 - z^2), over [-lo, hi].
    let m = |k: i32, z: f64| -> f64 {
        let k = f64::from(k);
        PI * (r * r * z.powf(k + 1.0) / (k + 1.0) - z.powf(k + 3.0) / (k + 3.0))
    };
    let sign = |k: i32| if k % 2 == 0 { 1.0 } else { -1.0 };
    // Integral over [-lo, hi] of z^k pi (r^2 - z^2): F(hi) - F(-lo).
    let moment = |k: i32| m(k, hi) + sign(k) * m(k, lo);
    let (v, m1, m2) = (moment(0), moment(1), moment(2));
    if v <= 0.0 || m2 <= 0.0 {
        return 1.0;
    }
    let den = 1.0 - m1 * m1 / (m2 * v);
    if den <= 1e-9 {
        return 1.0;
    }
    ((1.0 - first * m1 / m2) / den).clamp(0.5, 2.0)
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
/// stops at the edge. With `from_point`, `o` is a point in the water, not
/// on a surface: a surface closer than the geometry's self-intersection
/// epsilon counts ([`crate::geometry::Geometry::intersect_from_point`]).
fn trace_axis(
    scene: &Scene,
    o: Vec3,
    k: usize,
    t_max: f32,
    from_point: bool,
) -> Option<(f32, u32)> {
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
            let hit = if from_point && travelled == 0.0 {
                geo.intersect_from_point(origin, dir, segment)
            } else {
                geo.intersect(origin, dir, segment)
            };
            if let Some(hit) = hit {
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
        let hit = trace_axis(scene, o, k, r, false).map_or(f32::INFINITY, |(t, _)| t);
        hit.min(analytic_distance(scene, o, k)).clamp(0.0, r)
    }))
}

/// In-plane distances from `o` on the surface `id` with unit `normal`
/// (facing the water) to where the surface ends, by four rays along the
/// tangent basis started 1 mm above the surface: the waterline (z = 0), any
/// other surface (a target standing on the floor, the floor under a
/// target), and with open edges the domain walls; each capped at `r`. The
/// surface's own triangles are passed through (a gently curved floor goes
/// on). In a periodic domain rays are not wrapped: surfaces continue there.
pub fn disc_distances_traced(
    scene: &Scene,
    o: Vec3,
    normal: Vec3,
    id: crate::geometry::SurfaceId,
    r: f32,
) -> DiscDistances {
    let r = cap_radius(r);
    let (u, v) = tangent_basis(normal);
    let start = o + normal * 1e-3;
    let size = scene.geometry.domain_size_m();
    let open = !scene.domain.periodic;
    let d = [u, -u, v, -v].map(|dir| {
        let mut t = r;
        if dir.z > 1e-6 {
            t = t.min(-o.z / dir.z);
        }
        if open {
            for axis in 0..2 {
                if dir[axis] > 1e-6 {
                    t = t.min((size[axis] - o[axis]) / dir[axis]);
                } else if dir[axis] < -1e-6 {
                    t = t.min(o[axis] / -dir[axis]);
                }
            }
        }
        let mut from = start;
        let mut travelled = 0.0f32;
        // Pass through the surface's own triangles (a few at most).
        for _ in 0..4 {
            match scene.geometry.intersect(from, dir, t - travelled) {
                Some(h) if h.surface == id => {
                    travelled += h.t + 1e-4;
                    from = start + dir * travelled;
                }
                Some(h) => {
                    t = t.min(travelled + h.t);
                    break;
                }
                None => break,
            }
        }
        t.clamp(0.0, r)
    });
    DiscDistances { u, v, d }
}

mod grid;
pub use grid::BoundaryGrid;

#[cfg(test)]
mod tests;
