//! Validation of the floor and the submerged targets: `[bottom]`,
//! `[[bottom.patch]]` and `[[target]]`, added to the geometry.

use super::*;
use crate::bounds::Aabb;
use crate::geometry::Geometry;

/// Heights of land above the water line (m) a floor may reach.
pub const MAX_LAND_M: f64 = 1e4;

/// What [`bottom`] found of the floor's shape.
pub(super) struct FloorShape {
    /// Its deepest point (m, down).
    pub deepest_m: f64,
    /// Its highest point (m, up: above 0 where it rises above the water
    /// line as land).
    pub highest_m: f64,
    /// The steepest slope of the land (degrees; 0 without land).
    pub steepest_land_deg: f64,
}

/// The domain's size (m) as the geometry has it.
fn domain_size(geo: &GeometryBuilder) -> [f64; 2] {
    geo.domain_size_m().map(f64::from)
}

/// The steepest slope (degrees) of the heightfield's cells that reach
/// above the water line, from each cell's edge differences.
fn steepest_land_deg(depths: &[f32], nx: usize, ny: usize, sx: f64, sy: f64) -> f64 {
    let (dx, dy) = (sx / (nx - 1) as f64, sy / (ny - 1) as f64);
    let d = |i: usize, j: usize| f64::from(depths[j * nx + i]);
    let mut steepest = 0.0f64;
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            let corners = [d(i, j), d(i + 1, j), d(i, j + 1), d(i + 1, j + 1)];
            if corners.iter().all(|&c| c >= 0.0) {
                continue;
            }
            let gx = (d(i + 1, j) - d(i, j))
                .abs()
                .max((d(i + 1, j + 1) - d(i, j + 1)).abs())
                / dx;
            let gy = (d(i, j + 1) - d(i, j))
                .abs()
                .max((d(i + 1, j + 1) - d(i + 1, j)).abs())
                / dy;
            steepest = steepest.max(gx.hypot(gy).atan().to_degrees());
        }
    }
    steepest
}

/// The floor's shape (into `geo`) and reflectance, and what it is like;
/// `None` without a floor.
pub(super) fn bottom(
    ctx: &Ctx,
    b: Option<&BottomFile>,
    geo: &mut GeometryBuilder,
) -> Result<Option<(Bottom, FloorShape)>> {
    let bottom = match b {
        None => None,
        Some(b) => {
            let bk = |k| [K("bottom"), K(k)];
            let (deepest, highest, steepest) = match (b.depth_m, &b.slope, &b.heightfield) {
                (Some(d), None, None) => {
                    ctx.within(
                        &bk("depth_m"),
                        d,
                        1e-3,
                        1e5,
                        "must be a positive depth",
                        "m",
                    )?;
                    geo.flat_floor(d as f32, FLOOR);
                    (d, -d, 0.0)
                }
                (None, Some(s), None) => {
                    let sk = |k| [K("bottom"), K("slope"), K(k)];
                    for (k, v) in [
                        ("from_depth_m", s.from_depth_m),
                        ("to_depth_m", s.to_depth_m),
                    ] {
                        ctx.within(
                            &sk(k),
                            v,
                            -MAX_LAND_M,
                            1e5,
                            "must be a depth (negative: a height above the water line)",
                            "m",
                        )?;
                    }
                    if s.from_depth_m.max(s.to_depth_m) < 1e-3 {
                        return Err(ctx.err(
                            &sk("to_depth_m"),
                            "the floor is above the water line everywhere: one end must be under water (for land alone use [surface] kind = \"lambertian\")",
                        ));
                    }
                    let axis = s.axis.unwrap_or(Axis::X);
                    geo.slope_floor(s.from_depth_m as f32, s.to_depth_m as f32, axis, FLOOR);
                    let length = match axis {
                        Axis::X => domain_size(geo)[0],
                        Axis::Y => domain_size(geo)[1],
                    };
                    let steepest = ((s.to_depth_m - s.from_depth_m).abs() / length).atan();
                    (
                        s.from_depth_m.max(s.to_depth_m),
                        -s.from_depth_m.min(s.to_depth_m),
                        steepest.to_degrees(),
                    )
                }
                (None, None, Some(h)) => {
                    let path = ctx.file(h, &bk("heightfield"))?;
                    let (depths, nx, ny) = GeometryBuilder::heightfield_from_csv(&path)?;
                    geo.heightfield_floor(&depths, nx, ny, FLOOR)
                        .map_err(|e| ctx.err(&bk("heightfield"), e.to_string()))?;
                    let deepest = depths.iter().fold(f32::MIN, |a, &d| a.max(d)) as f64;
                    let highest = -(depths.iter().fold(f32::MAX, |a, &d| a.min(d)) as f64);
                    if deepest < 1e-3 {
                        return Err(ctx.err(
                            &bk("heightfield"),
                            format!("{}: the floor is above the water line everywhere: some depth must be positive (for land alone use [surface] kind = \"lambertian\")", path.display()),
                        ));
                    }
                    if highest > MAX_LAND_M {
                        return Err(ctx.err(
                            &bk("heightfield"),
                            format!("{}: the land rises {highest} m above the water line: at most {MAX_LAND_M} m", path.display()),
                        ));
                    }
                    let [sx, sy] = domain_size(geo);
                    let steepest = steepest_land_deg(&depths, nx, ny, sx, sy);
                    (deepest, highest, steepest)
                }
                _ => {
                    return Err(ctx.err(
                        &[K("bottom")],
                        "give exactly one of depth_m, slope or heightfield",
                    ))
                }
            };
            let refl = b.reflectance.clone().unwrap_or(Reflectance::Constant(0.2));
            let reflectance = ctx.reflectance(&refl, &bk("reflectance"))?;
            let mut patches = Vec::new();
            for (i, p) in b.patch.iter().enumerate() {
                let steps = [K("bottom"), K("patch"), I(i), K("reflectance")];
                if !(p.min_m[0] < p.max_m[0] && p.min_m[1] < p.max_m[1]) {
                    return Err(ctx.err(
                        &[K("bottom"), K("patch"), I(i), K("max_m")],
                        "max_m must exceed min_m",
                    ));
                }
                patches.push(Patch {
                    min_m: p.min_m,
                    max_m: p.max_m,
                    reflectance: ctx.reflectance(&p.reflectance, &steps)?,
                });
            }
            Some((
                Bottom {
                    reflectance,
                    patches,
                },
                FloorShape {
                    deepest_m: deepest,
                    highest_m: highest,
                    steepest_land_deg: steepest,
                },
            ))
        }
    };
    Ok(bottom)
}

/// The land, where the floor's highest point (m, up) is above
/// the water line: `[land]` is required then, and refused otherwise.
pub(super) fn land(ctx: &Ctx, f: &SceneFile, shape: Option<&FloorShape>) -> Result<Option<Land>> {
    let highest = shape.map_or(f64::NEG_INFINITY, |s| s.highest_m);
    let steepest_deg = shape.map_or(0.0, |s| s.steepest_land_deg);
    match (&f.land, highest > 0.0) {
        (None, false) => Ok(None),
        (Some(_), false) => Err(ctx.err(
            &[K("land")],
            "the floor never rises above the water line: give [bottom] depths below zero (a slope or a heightfield) for land, or leave [land] out",
        )),
        (None, true) => Err(ctx.err(
            &[K("bottom")],
            format!("the floor rises {highest} m above the water line: give the land's [land] reflectance"),
        )),
        (Some(l), true) => {
            let reflectance = ctx.reflectance(&l.reflectance, &[K("land"), K("reflectance")])?;
            let max_reflectance = reflectance.iter().fold(0.0f64, |a, &r| a.max(r));
            Ok(Some(Land {
                reflectance,
                max_reflectance,
                top_m: highest as f32,
                steepest_deg,
            }))
        }
    }
}

/// The targets (into `geo`, surface ids 1, 2, ...), their reflectances
/// and their extents (the bounds of each one's triangles).
pub(super) fn targets(
    ctx: &Ctx,
    targets: &[TargetFile],
    geo: &mut GeometryBuilder,
) -> Result<(Vec<Vec<f64>>, Vec<Aabb>)> {
    let mut target_reflectance = Vec::new();
    let mut extents = Vec::new();
    for (i, t) in targets.iter().enumerate() {
        let tk = |k| [K("target"), I(i), K(k)];
        let id = (i + 1) as SurfaceId;
        let c = Vec3::new(
            t.center_m[0] as f32,
            t.center_m[1] as f32,
            t.center_m[2] as f32,
        );
        if !c.is_finite() || c.z > 0.0 {
            return Err(ctx.err(&tk("center_m"), "must be finite and under water (z <= 0)"));
        }
        let size = t.size_m.clone().unwrap_or_default();
        let positive = size.iter().all(|&v| finite_in(v, 1e-4, 1e5));
        let first = geo.triangle_count();
        match t.kind {
            TargetKind::Box if size.len() == 3 && positive => geo.add_box(
                c,
                Vec3::new(size[0] as f32, size[1] as f32, size[2] as f32),
                id,
            ),
            TargetKind::Panel if size.len() == 2 && positive => {
                geo.add_panel(c, [size[0] as f32, size[1] as f32], id)
            }
            TargetKind::Box => {
                return Err(ctx.err(
                    &tk("size_m"),
                    format!(
                    "a box needs size_m = [x, y, z], 3 values each 1e-4 to 1e5 m (got {} values)",
                    size.len()
                ),
                ))
            }
            TargetKind::Panel => {
                return Err(ctx.err(
                    &tk("size_m"),
                    format!(
                    "a panel needs size_m = [x, y], 2 values each 1e-4 to 1e5 m (got {} values)",
                    size.len()
                ),
                ))
            }
            TargetKind::Mesh => {
                let file = t
                    .file
                    .as_ref()
                    .ok_or_else(|| ctx.err(&tk("file"), "a mesh needs file = \"mesh.obj\""))?;
                let scale = t.scale.unwrap_or(1.0);
                ctx.within(&tk("scale"), scale, 1e-6, 1e6, "must be positive", "")?;
                let path = ctx.file(file, &tk("file"))?;
                geo.add_obj(&path, c, scale as f32, id)?;
                let (_, proper) = geo.extent_since(first);
                let added = geo.triangle_count() - first;
                if added == 0 {
                    let what =
                        format!("{}: the mesh has no triangles (no f lines)", path.display());
                    return Err(ctx.err(&tk("file"), what));
                }
                if proper == 0 {
                    let what = format!(
                        "{}: all {added} triangles of the mesh have zero area (at scale {scale})",
                        path.display()
                    );
                    return Err(ctx.err(&tk("file"), what));
                }
            }
        }
        extents.push(geo.extent_since(first).0);
        target_reflectance.push(ctx.reflectance(&t.reflectance, &tk("reflectance"))?);
    }
    Ok((target_reflectance, extents))
}

/// Each target's whole extent must lie in the water of the domain: inside
/// [0, size_x] x [0, size_y] (with either kind of edge: geometry is not
/// repeated across a periodic edge, so the part of a target past one would
/// be cut off, not wrapped to the other side), at or below the surface
/// (z <= 0), and not entirely under the floor (its top below the floor at
/// every point of a grid over its footprint). A target partly sunk into the
/// floor is allowed.
pub(super) fn place_targets(
    ctx: &Ctx,
    targets: &[TargetFile],
    extents: &[Aabb],
    domain: &Domain,
    geometry: &Geometry,
) -> Result<()> {
    let [sx, sy] = domain.size_m;
    // The geometry is f32: allow its rounding at the domain's scale.
    let tol = 1e-5 * sx.max(sy).max(1.0);
    for (i, (t, e)) in targets.iter().zip(extents).enumerate() {
        let key = if t.kind == TargetKind::Mesh {
            [K("target"), I(i), K("file")]
        } else {
            [K("target"), I(i), K("size_m")]
        };
        let ck = [K("target"), I(i), K("center_m")];
        let (lo, hi) = (e.min.as_dvec3(), e.max.as_dvec3());
        let what = |which: &str| {
            format!(
                "the target spans x {:.3} to {:.3}, y {:.3} to {:.3}, z {:.3} to {:.3} m: {which}",
                lo.x, hi.x, lo.y, hi.y, lo.z, hi.z
            )
        };
        if lo.x < -tol || hi.x > sx + tol || lo.y < -tol || hi.y > sy + tol {
            // Too large to fit anywhere: its size; else its place.
            let steps = if hi.x - lo.x > sx || hi.y - lo.y > sy {
                &key
            } else {
                &ck
            };
            return Err(ctx.err(
                steps,
                what(&format!(
                    "it reaches outside the domain, x 0 to {sx} and y 0 to {sy} m (targets are not repeated across periodic edges)"
                )),
            ));
        }
        if hi.z > tol {
            let steps = if lo.z > tol { &ck } else { &key };
            return Err(ctx.err(steps, what("part of it is above the water (z > 0)")));
        }
        // The deepest floor over a 5 x 5 grid of the footprint (none
        // without a floor): a target whose top lies below it is buried
        // everywhere; one partly sunk into a slope is legitimate.
        const N: usize = 5;
        let mut deepest = f64::NEG_INFINITY;
        for a in 0..N {
            for b in 0..N {
                let x = lo.x + (hi.x - lo.x) * a as f64 / (N - 1) as f64;
                let y = lo.y + (hi.y - lo.y) * b as f64 / (N - 1) as f64;
                let (x, y) = (x.clamp(0.0, sx), y.clamp(0.0, sy));
                if let Some(d) = geometry.floor_depth_at(x as f32, y as f32) {
                    deepest = deepest.max(d as f64);
                }
            }
        }
        let top = -hi.z;
        if deepest.is_finite() && top > deepest + tol {
            return Err(ctx.err(
                &ck,
                what(&format!(
                    "it lies entirely below the floor (its top is {top:.3} m deep, the floor under it at most {deepest:.3} m)"
                )),
            ));
        }
    }
    Ok(())
}
