//! Validation of the floor and the submerged targets: `[bottom]`,
//! `[[bottom.patch]]` and `[[target]]`, added to the geometry.

use super::*;

/// The floor's shape (into `geo`) and reflectance; `None` without a floor.
pub(super) fn bottom(
    ctx: &Ctx,
    b: Option<&BottomFile>,
    geo: &mut GeometryBuilder,
) -> Result<Option<Bottom>> {
    let bottom = match b {
        None => None,
        Some(b) => {
            let bk = |k| [K("bottom"), K(k)];
            match (b.depth_m, &b.slope, &b.heightfield) {
                (Some(d), None, None) => {
                    if !finite_in(d, 1e-3, 1e5) {
                        return Err(ctx.err(&bk("depth_m"), "must be a positive depth (m)"));
                    }
                    geo.flat_floor(d as f32, FLOOR);
                }
                (None, Some(s), None) => {
                    let sk = |k| [K("bottom"), K("slope"), K(k)];
                    for (k, v) in [
                        ("from_depth_m", s.from_depth_m),
                        ("to_depth_m", s.to_depth_m),
                    ] {
                        if !finite_in(v, 1e-3, 1e5) {
                            return Err(ctx.err(&sk(k), "must be a positive depth (m)"));
                        }
                    }
                    let axis = s.axis.unwrap_or(Axis::X);
                    geo.slope_floor(s.from_depth_m as f32, s.to_depth_m as f32, axis, FLOOR);
                }
                (None, None, Some(h)) => {
                    let (depths, nx, ny) = GeometryBuilder::heightfield_from_csv(&ctx.path(h))?;
                    geo.heightfield_floor(&depths, nx, ny, FLOOR)
                        .map_err(|e| ctx.err(&bk("heightfield"), e.to_string()))?;
                }
                _ => {
                    return Err(ctx.err(
                        &[K("bottom")],
                        "give exactly one of depth_m, slope or heightfield",
                    ))
                }
            }
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
            Some(Bottom {
                reflectance,
                patches,
            })
        }
    };
    Ok(bottom)
}

/// The targets (into `geo`, surface ids 1, 2, ...) and their reflectances.
pub(super) fn targets(
    ctx: &Ctx,
    targets: &[TargetFile],
    geo: &mut GeometryBuilder,
) -> Result<Vec<Vec<f64>>> {
    let mut target_reflectance = Vec::new();
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
                return Err(ctx.err(&tk("size_m"), "a box needs size_m = [x, y, z] > 0"))
            }
            TargetKind::Panel => {
                return Err(ctx.err(&tk("size_m"), "a panel needs size_m = [x, y] > 0"))
            }
            TargetKind::Mesh => {
                let file = t
                    .file
                    .as_ref()
                    .ok_or_else(|| ctx.err(&tk("file"), "a mesh needs file = \"mesh.obj\""))?;
                let scale = t.scale.unwrap_or(1.0);
                if !finite_in(scale, 1e-6, 1e6) {
                    return Err(ctx.err(&tk("scale"), "must be positive"));
                }
                geo.add_obj(&ctx.path(file), c, scale as f32, id)?;
            }
        }
        target_reflectance.push(ctx.reflectance(&t.reflectance, &tk("reflectance"))?);
    }
    Ok(target_reflectance)
}
