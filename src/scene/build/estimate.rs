//! Validation of how the scene is rendered: `[estimate]` (the photon-map
//! estimate's searches and forward peaks) and `[render]`.

use super::*;
use crate::scene::settings::{
    policy_k, DEFAULT_FORWARD_PEAK_DEG, DEFAULT_FORWARD_PEAK_DOWN_DEG,
    DEFAULT_FORWARD_PEAK_TARGET_DEG, DEFAULT_GATHER_RAYS, DEFAULT_K_EXPANDED_PER_K,
    DEFAULT_MAX_RADIUS_M, DEFAULT_SHAPE_PHOTONS_PER_BAND, DEFAULT_STEP_M,
};

/// `[estimate]` and `[render]`, with the command line's overrides.
pub(super) fn estimate_and_render(
    ctx: &Ctx,
    f: &SceneFile,
    ov: &Overrides,
) -> Result<(EstimateSettings, RenderSettings)> {
    let e = &f.estimate;
    let ek = |k| [K("estimate"), K(k)];
    let k = e.k.unwrap_or_else(|| policy_k(f.photons().count));
    if k == 0 || k > 100_000 {
        return Err(ctx.err(&ek("k"), "must be between 1 and 100000"));
    }
    let k_expanded = e.k_expanded.unwrap_or(DEFAULT_K_EXPANDED_PER_K * k);
    if k_expanded < k || k_expanded > 1_000_000 {
        return Err(ctx.err(&ek("k_expanded"), "must be at least k and at most 1000000"));
    }
    if let Some(r) = e.radius_m {
        ctx.within(
            &ek("radius_m"),
            r,
            1e-6,
            1e4,
            "must be a positive radius",
            "m",
        )?;
    }
    let max_radius_m = e.max_radius_m.unwrap_or(DEFAULT_MAX_RADIUS_M);
    let low = "must be a positive radius";
    ctx.within(&ek("max_radius_m"), max_radius_m, 1e-6, 1e4, low, "m")?;
    let step_m = e.step_m.unwrap_or(DEFAULT_STEP_M);
    ctx.within(
        &ek("step_m"),
        step_m,
        1e-3,
        1e3,
        "must be a positive step",
        "m",
    )?;
    let boundary = ov.boundary.or(e.boundary).unwrap_or_default();
    let spectral = ov.spectral.or(e.spectral).unwrap_or_default();
    let peak = |key: &'static str, value: Option<f64>, default: f64| -> Result<f64> {
        let v = value.unwrap_or(default);
        if finite_in(v, 0.0, 90.0) {
            Ok(v)
        } else {
            Err(ctx.err(
                &ek(key),
                "must be between 0 and 90 degrees (0 keeps the exact phase function)",
            ))
        }
    };
    let forward_peak_deg = peak(
        "forward_peak_deg",
        e.forward_peak_deg,
        DEFAULT_FORWARD_PEAK_DEG,
    )?;
    let forward_peak_down_deg = peak(
        "forward_peak_down_deg",
        e.forward_peak_down_deg,
        DEFAULT_FORWARD_PEAK_DOWN_DEG,
    )?;
    let forward_peak_target_deg = peak(
        "forward_peak_target_deg",
        e.forward_peak_target_deg,
        DEFAULT_FORWARD_PEAK_TARGET_DEG,
    )?;
    if let Some(h) = e.boundary_grid_m {
        if !finite_in(h, 0.01, 100.0) {
            return Err(ctx.err(
                &ek("boundary_grid_m"),
                "must be a grid spacing between 0.01 and 100 m",
            ));
        }
    }
    let shape_photons_per_band = e
        .shape_photons_per_band
        .unwrap_or(DEFAULT_SHAPE_PHOTONS_PER_BAND);
    if !(1..=1_000_000).contains(&shape_photons_per_band) {
        return Err(ctx.err(
            &ek("shape_photons_per_band"),
            "must be between 1 and 1000000",
        ));
    }
    let gather_rays = e.gather_rays.unwrap_or(DEFAULT_GATHER_RAYS);
    if gather_rays > 4096 {
        return Err(ctx.err(&ek("gather_rays"), "must be at most 4096"));
    }
    let estimate = EstimateSettings {
        k,
        radius_m: e.radius_m,
        max_radius_m,
        k_expanded,
        boundary,
        spectral,
        step_m,
        forward_peak_deg,
        forward_peak_down_deg,
        forward_peak_target_deg,
        boundary_grid_m: e.boundary_grid_m,
        shape_photons_per_band,
        gather_rays,
    };
    let render = RenderSettings {
        integrator: ov.integrator.or(f.render.integrator).unwrap_or_default(),
        exr_compression: f.render.exr_compression.unwrap_or_default(),
    };
    Ok((estimate, render))
}
