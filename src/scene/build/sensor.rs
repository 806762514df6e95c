//! Validation of what looks at the scene: the camera (`[sensor]`) and the
//! radiometers (`[[radiometer]]`).

use super::*;

/// The camera and the radiometers, checked against the domain and the
/// floor.
pub(super) fn sensor_and_radiometers(
    ctx: &Ctx,
    f: &SceneFile,
    domain: &Domain,
    geometry: &crate::geometry::Geometry,
    ov: &Overrides,
) -> Result<(Sensor, Vec<Radiometer>)> {
    let sk = |k| [K("sensor"), K(k)];
    let default = SensorFile {
        kind: None,
        pixels: None,
        gsd_m: None,
        samples_per_pixel: None,
        center_m: None,
        position_m: None,
        look_at_m: None,
        fov_deg: None,
        response: None,
        altitude_m: None,
        view_zenith_deg: None,
        view_azimuth_deg: None,
    };
    let s = f.sensor.as_ref().unwrap_or(&default);
    let pixels = s.pixels.unwrap_or([256, 256]);
    if pixels.iter().any(|&p| p == 0 || p > 65_536) {
        return Err(ctx.err(
            &sk("pixels"),
            "must be between 1 and 65536 in each direction",
        ));
    }
    let spp = ov.samples_per_pixel.or(s.samples_per_pixel).unwrap_or(1);
    if spp == 0 || spp > 65_536 {
        return Err(ctx.err(&sk("samples_per_pixel"), "must be between 1 and 65536"));
    }
    let vec3 = |v: [f64; 3]| Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32);
    let kind =
        match s.kind.unwrap_or_default() {
            SensorKindName::Orthographic => {
                let gsd = s.gsd_m.unwrap_or(
                    domain.size_m[0].min(domain.size_m[1]) / pixels[0].max(pixels[1]) as f64,
                );
                let low = "must be a positive ground sample distance";
                ctx.within(&sk("gsd_m"), gsd, 1e-6, 1e6, low, "m")?;
                let center_m = s
                    .center_m
                    .unwrap_or([domain.size_m[0] / 2.0, domain.size_m[1] / 2.0]);
                if !center_m.iter().all(|v| v.is_finite()) {
                    return Err(ctx.err(&sk("center_m"), "must be finite"));
                }
                footprint(ctx, s, domain, pixels, gsd, center_m)?;
                SensorKind::Orthographic {
                    gsd_m: gsd,
                    center_m,
                }
            }
            SensorKindName::Pinhole => {
                let position = vec3(s.position_m.ok_or_else(|| {
                    ctx.err(&sk("position_m"), "a pinhole camera needs position_m")
                })?);
                let look_at = vec3(s.look_at_m.ok_or_else(|| {
                    ctx.err(&sk("look_at_m"), "a pinhole camera needs look_at_m")
                })?);
                if !(position.is_finite() && position.z > 0.0) {
                    return Err(ctx.err(&sk("position_m"), "must be above the water (z > 0)"));
                }
                if !look_at.is_finite() || (look_at - position).length() < 1e-6 {
                    return Err(ctx.err(&sk("look_at_m"), "must differ from position_m"));
                }
                let fov_deg = s.fov_deg.unwrap_or(30.0);
                if !finite_in(fov_deg, 0.01, 170.0) {
                    return Err(ctx.err(&sk("fov_deg"), "must be between 0.01 and 170 degrees"));
                }
                let kind = SensorKind::Pinhole {
                    position,
                    look_at,
                    fov_deg,
                };
                pinhole_footprint(ctx, &kind, domain, pixels)?;
                kind
            }
        };
    // A csv: response is read relative to the scene, like every file it
    // names (but not an emission input: it changes no photon).
    let response = match &s.response {
        None => None,
        Some(name) => {
            let name = match name.strip_prefix("csv:") {
                Some(file) if std::path::Path::new(file).is_relative() => {
                    format!("csv:{}", ctx.dir.join(file).display())
                }
                _ => name.clone(),
            };
            let response = crate::spectral::response::SpectralResponse::named(&name)
                .map_err(|e| ctx.err(&sk("response"), e.to_string()))?;
            // Refused now, not after the render that would resample into it.
            if response.weights(&ctx.bands).is_empty() {
                let c = ctx.bands.centers_nm();
                return Err(ctx.err(
                    &sk("response"),
                    format!(
                        "the scene's bands ({:.1}-{:.1} nm) cover no band of {} (each needs {} % of its response inside)",
                        c[0],
                        c[c.len() - 1],
                        response.name,
                        crate::spectral::response::MIN_COVERAGE * 100.0
                    ),
                ));
            }
            Some(response)
        }
    };
    let orthographic = matches!(kind, SensorKind::Orthographic { .. });
    let toward = match (s.view_zenith_deg, s.view_azimuth_deg) {
        (None, None) => Vec3::Z,
        _ if !orthographic => {
            let k = if s.view_zenith_deg.is_some() {
                "view_zenith_deg"
            } else {
                "view_azimuth_deg"
            };
            return Err(ctx.err(
                &sk(k),
                "only for an orthographic sensor (a pinhole camera looks along look_at_m)",
            ));
        }
        (z, a) => {
            let z = z.unwrap_or(0.0);
            ctx.within(
                &sk("view_zenith_deg"),
                z,
                0.0,
                70.0,
                "must be >= 0",
                "degrees",
            )?;
            let a = a.unwrap_or(0.0);
            if !a.is_finite() {
                return Err(ctx.err(&sk("view_azimuth_deg"), "must be a finite angle"));
            }
            let (z, a) = (z.to_radians(), a.to_radians());
            Vec3::new(
                (z.sin() * a.cos()) as f32,
                (z.sin() * a.sin()) as f32,
                z.cos() as f32,
            )
            .normalize()
        }
    };
    let altitude_m =
        match s.altitude_m {
            None => None,
            Some(_) if f.atmosphere.is_none() => return Err(ctx.err(
                &sk("altitude_m"),
                "only with [atmosphere]: without one the sensor sees the water from just above it",
            )),
            Some(_) if !orthographic => {
                return Err(ctx.err(
                    &sk("altitude_m"),
                    "only for an orthographic sensor (a pinhole camera sits at position_m)",
                ))
            }
            Some(h) => {
                ctx.within(&sk("altitude_m"), h, 1.0, 1e6, "must be at least 1 m", "m")?;
                Some(h)
            }
        };
    let sensor = Sensor {
        kind,
        pixels,
        samples_per_pixel: spp,
        response,
        toward,
        altitude_m,
    };

    Ok((sensor, radiometers(ctx, f, domain, geometry)?))
}

/// `[[radiometer]]`: each inside the domain and not below the floor.
fn radiometers(
    ctx: &Ctx,
    f: &SceneFile,
    domain: &Domain,
    geometry: &crate::geometry::Geometry,
) -> Result<Vec<Radiometer>> {
    let vec3 = |v: [f64; 3]| Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32);
    let mut radiometers = Vec::new();
    for (i, r) in f.radiometer.iter().enumerate() {
        let rk = |k| [K("radiometer"), I(i), K(k)];
        if !finite_in(r.depth_m, -1e5, 1e5) || r.depth_m == 0.0 {
            return Err(ctx.err(
                &rk("depth_m"),
                "must be a finite depth, not 0 (positive below the surface, negative above)",
            ));
        }
        let (name, view) = match &r.view {
            None => ("nadir".to_string(), -Vec3::Z),
            Some(View::Named(n)) if n == "nadir" => (n.clone(), -Vec3::Z),
            Some(View::Named(n)) if n == "zenith" => (n.clone(), Vec3::Z),
            Some(View::Vector(v))
                if v.iter().all(|x| x.is_finite()) && vec3(*v).length() > 1e-6 =>
            {
                (format!("{},{},{}", v[0], v[1], v[2]), vec3(*v).normalize())
            }
            Some(_) => {
                return Err(ctx.err(
                    &rk("view"),
                    "use \"nadir\", \"zenith\" or a non-zero [x, y, z]",
                ))
            }
        };
        let position_m = r
            .position_m
            .unwrap_or([domain.size_m[0] / 2.0, domain.size_m[1] / 2.0]);
        if !position_m.iter().all(|v| v.is_finite()) {
            return Err(ctx.err(&rk("position_m"), "must be finite"));
        }
        // Outside the domain there is no water to measure (with either kind
        // of edge: a position past a periodic edge is not wrapped).
        let [sx, sy] = domain.size_m;
        let [x, y] = position_m;
        if !((0.0..=sx).contains(&x) && (0.0..=sy).contains(&y)) {
            return Err(ctx.err(
                &rk("position_m"),
                format!("[{x}, {y}] is outside the domain, x 0 to {sx} and y 0 to {sy} m"),
            ));
        }
        // Below the floor no light arrives: it would read exactly 0.
        if let Some(floor) = geometry.floor_depth_at(x as f32, y as f32) {
            let floor = floor as f64;
            if r.depth_m > floor + 1e-6 * floor.max(1.0) {
                return Err(ctx.err(
                    &rk("depth_m"),
                    format!(
                        "{} m is below the floor, {floor:.3} m deep at [{x}, {y}]",
                        r.depth_m
                    ),
                ));
            }
        }
        let half_angle_deg = r.half_angle_deg.unwrap_or(0.0);
        if !(0.0..90.0).contains(&half_angle_deg) {
            return Err(ctx.err(
                &rk("half_angle_deg"),
                format!("{half_angle_deg} must be at least 0 and below 90 degrees"),
            ));
        }
        radiometers.push(Radiometer {
            depth_m: r.depth_m,
            view_name: name,
            view,
            position_m,
            half_angle_deg,
        });
    }

    Ok(radiometers)
}

/// The orthographic image must lie inside the domain, with either kind of
/// edge: camera rays are not wrapped at periodic edges, so pixels past one
/// would see water without photons. Names `gsd_m` (or `pixels`) when the
/// image is larger than the domain, `center_m` when it only sits off it.
fn footprint(
    ctx: &Ctx,
    s: &SensorFile,
    domain: &Domain,
    pixels: [usize; 2],
    gsd: f64,
    center_m: [f64; 2],
) -> Result<()> {
    let sk = |k| [K("sensor"), K(k)];
    let [sx, sy] = domain.size_m;
    let (wx, wy) = (pixels[0] as f64 * gsd, pixels[1] as f64 * gsd);
    let (x0, x1) = (center_m[0] - wx / 2.0, center_m[0] + wx / 2.0);
    let (y0, y1) = (center_m[1] - wy / 2.0, center_m[1] + wy / 2.0);
    // Pixel edges are sums of f64 steps: allow their rounding.
    let tol = 1e-9 * sx.max(sy);
    if x0 >= -tol && y0 >= -tol && x1 <= sx + tol && y1 <= sy + tol {
        return Ok(());
    }
    let what = format!(
        "the image ({} x {} pixels of {gsd} m) spans x {x0} to {x1}, y {y0} to {y1} m, outside the domain (x 0 to {sx}, y 0 to {sy} m; camera rays are not wrapped at periodic edges)",
        pixels[0], pixels[1]
    );
    let key = if wx > sx + tol || wy > sy + tol {
        if s.gsd_m.is_some() {
            "gsd_m"
        } else {
            "pixels"
        }
    } else {
        "center_m"
    };
    Err(ctx.err(&sk(key), what))
}

/// A pinhole camera's view: the centre and the four corners of its image
/// must meet the water inside the domain (camera rays are not wrapped at
/// periodic edges, and a ray above the horizon sees no water). The centre
/// outside blames `look_at_m`; a corner outside, `fov_deg`.
fn pinhole_footprint(
    ctx: &Ctx,
    kind: &SensorKind,
    domain: &Domain,
    pixels: [usize; 2],
) -> Result<()> {
    let sensor = Sensor {
        kind: kind.clone(),
        pixels,
        samples_per_pixel: 1,
        response: None,
        toward: Vec3::Z,
        altitude_m: None,
    };
    let [sx, sy] = domain.size_m;
    let [w, h] = pixels;
    // (pixel, offset) of the image's centre and its corners.
    let centre = (
        w / 2,
        h / 2,
        if w % 2 == 0 { 0.0 } else { 0.5 },
        if h % 2 == 0 { 0.0 } else { 0.5 },
    );
    let points = [
        ("centre", centre),
        ("top-left corner", (0, 0, 0.0, 0.0)),
        ("top-right corner", (w - 1, 0, 1.0, 0.0)),
        ("bottom-left corner", (0, h - 1, 0.0, 1.0)),
        ("bottom-right corner", (w - 1, h - 1, 1.0, 1.0)),
    ];
    for (name, (px, py, u, v)) in points {
        let r = crate::render::camera::ray(&sensor, px, py, u, v);
        let key = if name == "centre" {
            "look_at_m"
        } else {
            "fov_deg"
        };
        let at = if r.direction.z < 0.0 {
            let t = -r.origin.z / r.direction.z;
            Some(r.origin + r.direction * t)
        } else {
            None
        };
        let what = match at {
            None => format!("the image's {name} looks above the horizon and sees no water"),
            Some(p) if p.x < 0.0 || p.y < 0.0 || p.x as f64 > sx || p.y as f64 > sy => format!(
                "the image's {name} meets the water at x {:.1}, y {:.1} m, outside the domain (x 0 to {sx}, y 0 to {sy} m; camera rays are not wrapped at periodic edges)",
                p.x, p.y
            ),
            Some(_) => continue,
        };
        return Err(ctx.err(&[K("sensor"), K(key)], what));
    }
    Ok(())
}
