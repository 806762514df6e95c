//! Validation of the light sources and the interface: `[sun]`, `[sky]`
//! and `[surface]`.

use super::*;
use crate::optics::sky::SkyModel;

/// The sun: position and direct normal irradiance per band (with an
/// atmosphere, `atmosphere`, at its top: scaled by the Earth–Sun distance
/// of `day_of_year`).
pub(super) fn sun(ctx: &Ctx, s: &SunFile, atmosphere: bool) -> Result<Sun> {
    let nb = ctx.bands.len();
    if !finite_in(s.zenith_deg, 0.0, 89.0) {
        return Err(ctx.err(
            &[K("sun"), K("zenith_deg")],
            "must be between 0 and 89 degrees",
        ));
    }
    if !s.azimuth_deg.is_finite() {
        return Err(ctx.err(&[K("sun"), K("azimuth_deg")], "must be a finite angle"));
    }
    let key = |k| [K("sun"), K(k)];
    let sun_irr = match (&s.spectrum, s.irradiance) {
        (Some(name), None) => {
            let solar = |which| ctx.per_band(tables::solar(which), &key("spectrum"));
            match name.as_str() {
                "astm-g173-direct" if atmosphere => {
                    let what = "'astm-g173-direct' is the beam at the ground after an atmosphere: with [atmosphere] give the sun at its top, \"extraterrestrial\" (ASTM G173's) or a .csv file";
                    return Err(ctx.err(&key("spectrum"), what));
                }
                "astm-g173-direct" => solar(SolarSpectrum::DirectCircumsolar)?,
                "astm-g173-extraterrestrial" | "extraterrestrial" => {
                    solar(SolarSpectrum::Extraterrestrial)?
                }
                csv if csv.ends_with(".csv") => {
                    let t =
                        Table::from_csv_file(&ctx.file(csv, &key("spectrum"))?, "sun.spectrum")?;
                    ctx.per_band(&t, &key("spectrum"))?
                }
                other => {
                    let what = format!(
                        "'{other}': use \"astm-g173-direct\", \"extraterrestrial\" (\"astm-g173-extraterrestrial\") or a .csv file"
                    );
                    return Err(ctx.err(&key("spectrum"), what));
                }
            }
        }
        (None, Some(e)) => {
            ctx.within(
                &key("irradiance"),
                e,
                0.0,
                f64::MAX,
                "must be >= 0",
                "W m^-2 nm^-1",
            )?;
            vec![e; nb]
        }
        (None, None) => return Err(ctx.err(&[K("sun")], "give spectrum or irradiance")),
        (Some(_), Some(_)) => {
            let what = "give spectrum or irradiance, not both";
            return Err(ctx.err(&key("irradiance"), what));
        }
    };
    let sun_irr = match s.day_of_year {
        None => sun_irr,
        Some(_) if !atmosphere => {
            let what = "only with [atmosphere]: without one the sun's spectrum is the irradiance at the surface";
            return Err(ctx.err(&key("day_of_year"), what));
        }
        Some(d) => {
            ctx.within(&key("day_of_year"), d, 1.0, 366.0, "must be at least 1", "")?;
            let f = crate::optics::atmosphere::earth_sun_factor(d);
            sun_irr.iter().map(|e| e * f).collect()
        }
    };
    let (zen, az) = (s.zenith_deg.to_radians(), s.azimuth_deg.to_radians());
    let toward_sun = Vec3::new(
        (zen.sin() * az.cos()) as f32,
        (zen.sin() * az.sin()) as f32,
        zen.cos() as f32,
    );
    let sun = Sun {
        zenith_rad: zen,
        azimuth_rad: az,
        direction: -toward_sun.normalize(),
        irradiance: sun_irr,
    };
    Ok(sun)
}

/// The sky: horizontal diffuse irradiance per band, and how its radiance
/// spreads over the hemisphere.
pub(super) fn sky(ctx: &Ctx, s: &SkyFile, sun: &Sun, atmosphere: bool) -> Result<Sky> {
    let nb = ctx.bands.len();
    let key = |k| [K("sky"), K(k)];
    if atmosphere {
        let set = [
            ("spectrum", s.spectrum.is_some()),
            ("radiance", s.radiance.is_some()),
            ("distribution", s.distribution.is_some()),
        ];
        if let Some((k, _)) = set.iter().find(|(_, set)| *set) {
            let what = "with [atmosphere] the sky comes from the atmosphere: leave [sky] out";
            return Err(ctx.err(&key(k), what));
        }
    }
    let sky_irr = match (&s.spectrum, s.radiance) {
        (None, None) => vec![0.0; nb],
        (Some(n), None) if n == "none" => vec![0.0; nb],
        (Some(n), None) if n == "astm-g173-diffuse" => {
            ctx.per_band(tables::sky_diffuse_irradiance(), &key("spectrum"))?
        }
        (Some(n), None) if n.ends_with(".csv") => {
            let t = Table::from_csv_file(&ctx.file(n, &key("spectrum"))?, "sky.spectrum")?;
            ctx.per_band(&t, &key("spectrum"))?
        }
        (Some(n), None) => {
            let what = format!(
                "'{n}': use \"none\", \"astm-g173-diffuse\" or a .csv file of horizontal irradiance"
            );
            return Err(ctx.err(&key("spectrum"), what));
        }
        (None, Some(l)) => {
            let unit = "W m^-2 sr^-1 nm^-1";
            ctx.within(&key("radiance"), l, 0.0, f64::MAX, "must be >= 0", unit)?;
            vec![std::f64::consts::PI * l; nb]
        }
        (Some(_), Some(_)) => {
            let what = "give spectrum or radiance, not both";
            return Err(ctx.err(&key("radiance"), what));
        }
    };
    let model = match s.distribution.unwrap_or_default() {
        SkyDistribution::Isotropic => SkyModel::Isotropic,
        SkyDistribution::CieClear => SkyModel::cie_clear(-sun.direction),
    };
    let sky = Sky {
        irradiance: sky_irr,
        model,
    };
    Ok(sky)
}

/// Refuse a scene that emits no light: the sun's horizontal irradiance
/// and the sky's are zero in every band. Names the sun's key, and the
/// sky's when one is given.
pub(super) fn check_emits(ctx: &Ctx, f: &SceneFile, sun: &Sun, sky: &Sky) -> Result<()> {
    let fwhm = ctx.bands.fwhm_nm();
    let total: f64 = (0..ctx.bands.len())
        .map(|b| (sun.horizontal_irradiance(b) + sky.irradiance[b]) * fwhm[b] as f64)
        .sum();
    if total > 0.0 && total.is_finite() {
        return Ok(());
    }
    let sun_key = if f.sun.spectrum.is_some() {
        "spectrum"
    } else {
        "irradiance"
    };
    let sky_key = match (&f.sky.spectrum, f.sky.radiance) {
        (Some(_), _) => "sky.spectrum is zero too",
        (None, Some(_)) => "sky.radiance is zero too",
        (None, None) => "there is no sky (sky.spectrum or sky.radiance)",
    };
    let what = if total.is_finite() {
        format!("the scene emits no light: the sun is zero in every band and {sky_key}")
    } else {
        "the total emitted power overflows".to_string()
    };
    Err(ctx.err(&[K("sun"), K(sun_key)], what))
}

/// Quan & Fry's defaults: a temperate ocean.
const DEFAULT_TEMPERATURE_C: f64 = 20.0;
const DEFAULT_SALINITY_PSU: f64 = 35.0;

/// The water's refractive index per band: a constant (1.34 by default), or
/// Quan & Fry (1995) at each band's centre for the scene's temperature and
/// salinity.
fn water_index(ctx: &Ctx, s: &SurfaceFile) -> Result<Vec<f64>> {
    let key = |k| [K("surface"), K(k)];
    let named = match &s.refractive_index {
        None => None,
        Some(RefractiveIndex::Constant(n)) => Some(Err(*n)),
        Some(RefractiveIndex::Named(name)) if name == "quan-fry" => Some(Ok(())),
        Some(RefractiveIndex::Named(name)) => {
            return Err(ctx.err(
                &key("refractive_index"),
                format!("'{name}' is not a model: give a number (1-2) or \"quan-fry\""),
            ))
        }
    };
    if !matches!(named, Some(Ok(()))) {
        for k in ["temperature_c", "salinity_psu"] {
            let set = if k == "temperature_c" {
                s.temperature_c.is_some()
            } else {
                s.salinity_psu.is_some()
            };
            if set {
                return Err(ctx.err(&key(k), "only used with refractive_index = \"quan-fry\""));
            }
        }
    }
    let bands = ctx.bands.len();
    match named {
        None => Ok(vec![1.34; bands]),
        Some(Err(n)) => {
            if !finite_in(n, 1.0, 2.0) {
                return Err(ctx.err(&key("refractive_index"), "must be between 1 and 2"));
            }
            Ok(vec![n; bands])
        }
        Some(Ok(())) => {
            let t = s.temperature_c.unwrap_or(DEFAULT_TEMPERATURE_C);
            if !finite_in(t, -2.0, 40.0) {
                return Err(ctx.err(&key("temperature_c"), "must be between -2 and 40 degrees C"));
            }
            let sal = s.salinity_psu.unwrap_or(DEFAULT_SALINITY_PSU);
            if !finite_in(sal, 0.0, 45.0) {
                return Err(ctx.err(&key("salinity_psu"), "must be between 0 and 45 PSU"));
            }
            Ok(ctx
                .bands
                .centers_nm()
                .iter()
                .map(|&nm| crate::optics::water_index::quan_fry(nm as f64, t, sal))
                .collect())
        }
    }
}

/// The sea surface: refractive index and roughness. The surface carries
/// the reference index (the mean over the bands) the renderers trace
/// geometry with; the second value is the index per band.
pub(super) fn surface(ctx: &Ctx, s: &SurfaceFile) -> Result<(SeaSurface, Vec<f64>)> {
    let index = water_index(ctx, s)?;
    let n_water = index.iter().sum::<f64>() / index.len().max(1) as f64;
    // A constant index is its own mean, bit for bit.
    let n_water = if index.iter().all(|&n| n == index[0]) {
        index[0]
    } else {
        n_water
    };
    let wind = s.wind_speed.unwrap_or(0.0);
    if !finite_in(wind, 0.0, 30.0) {
        return Err(ctx.err(
            &[K("surface"), K("wind_speed")],
            "must be between 0 and 30 m/s",
        ));
    }
    let surface = match s.kind.unwrap_or_default() {
        // A Lambertian ground has no sea surface: the flat one is never
        // met (`Scene::ground`).
        SurfaceKind::Flat | SurfaceKind::Lambertian => SeaSurface::flat(n_water),
        SurfaceKind::CoxMunk => SeaSurface::cox_munk(n_water, wind),
    };
    Ok((surface, index))
}

/// `[surface] kind = "lambertian"`: the ground's reflectance per band,
/// none for a sea. A ground has no water, so the sea's keys, the floor,
/// targets, tallies, radiometers and a photon map are refused, each
/// naming its key.
pub(super) fn ground(ctx: &Ctx, f: &SceneFile, ov: &Overrides) -> Result<Option<Vec<f64>>> {
    let s = &f.surface;
    let key = |k| [K("surface"), K(k)];
    if !f.lambertian_ground() {
        if s.reflectance.is_some() {
            return Err(ctx.err(
                &key("reflectance"),
                "only for a Lambertian ground (kind = \"lambertian\"); a sea's floor takes [bottom] reflectance",
            ));
        }
        return Ok(None);
    }
    let sea = "is the sea's: a Lambertian ground ([surface] kind = \"lambertian\") has no water";
    let given: [(&[Step], bool); 9] = [
        (&[K("land")], f.land.is_some()),
        (&key("wind_speed"), s.wind_speed.is_some()),
        (&key("refractive_index"), s.refractive_index.is_some()),
        (&key("temperature_c"), s.temperature_c.is_some()),
        (&key("salinity_psu"), s.salinity_psu.is_some()),
        (&[K("bottom")], f.bottom.is_some()),
        (&[K("target")], !f.target.is_empty()),
        (&[K("tally"), K("depths_m")], !f.tally.depths_m.is_empty()),
        (&[K("radiometer")], !f.radiometer.is_empty()),
    ];
    if let Some((steps, _)) = given.iter().find(|(_, g)| *g) {
        return Err(ctx.err(steps, sea));
    }
    let photon_map = Some(IntegratorMode::PhotonMap);
    if ov.integrator == photon_map {
        return Err(Error::invalid(
            "--integrator",
            "photon-map: a Lambertian ground has no water for a photon map; its radiance is exact with the path integrator's renderer",
        ));
    }
    if f.render.integrator == photon_map {
        return Err(ctx.err(
            &[K("render"), K("integrator")],
            "a Lambertian ground has no water for a photon map; its radiance is exact with \"path\"",
        ));
    }
    let Some(r) = &s.reflectance else {
        return Err(ctx.err(
            &key("reflectance"),
            "a Lambertian ground needs its reflectance: a number, a bottom type or a CSV file",
        ));
    };
    Ok(Some(ctx.reflectance(r, &key("reflectance"))?))
}

/// `[surroundings]`: a Lambertian surface of a reflectance per band, the
/// domain's mean, or deep water of its own IOPs, all around the domain;
/// none for a periodic domain. Only with an atmosphere (without air no
/// light crosses from beyond the domain to the sensor). The scene `text`
/// at `path` with its overrides `ov` makes the water's scene.
pub(super) fn surroundings(
    ctx: &Ctx,
    f: &SceneFile,
    text: &str,
    path: &std::path::Path,
    ov: &crate::scene::Overrides,
) -> Result<Option<Surroundings>> {
    let Some(s) = &f.surroundings else {
        return Ok(None);
    };
    let key = |k| [K("surroundings"), K(k)];
    if f.atmosphere.is_none() {
        return Err(ctx.err(
            &key("kind"),
            "only with [atmosphere]: without air no light from beyond the domain reaches the sensor",
        ));
    }
    if s.water.is_some() != (s.kind == SurroundingsKind::Water) {
        return Err(ctx.err(
            &key("water"),
            "kind = \"water\" and its [water] table go together: water = { chl = ... } or { iop = ... }",
        ));
    }
    match (s.kind, &s.reflectance) {
        (SurroundingsKind::Water, None) => {
            let water = s.water.as_ref().expect("checked above");
            Ok(Some(Surroundings::Water(std::sync::Arc::new(sea_beyond(
                ctx, text, path, ov, water,
            )?))))
        }
        (SurroundingsKind::Water, Some(_)) => Err(ctx.err(
            &key("reflectance"),
            "only for kind = \"lambertian\" (water surroundings are given by their water)",
        )),
        (SurroundingsKind::Periodic, None) => Ok(None),
        (SurroundingsKind::Mean, None) => Ok(Some(Surroundings::Mean)),
        (SurroundingsKind::Periodic | SurroundingsKind::Mean, Some(_)) => Err(ctx.err(
            &key("reflectance"),
            "only for kind = \"lambertian\" (periodic and mean surroundings are the domain's own)",
        )),
        (SurroundingsKind::Lambertian, None) => Err(ctx.err(
            &key("reflectance"),
            "Lambertian surroundings need their reflectance: a number, a bottom type or a CSV file",
        )),
        (SurroundingsKind::Lambertian, Some(r)) => Ok(Some(Surroundings::Lambertian(
            ctx.reflectance(r, &key("reflectance"))?,
        ))),
    }
}

/// The sea beyond the domain for `[surroundings] kind = "water"`: the
/// scene `text` with `water` as its `[water]` and without its floor,
/// land, targets, radiometers, surroundings and sensor altitude (deep
/// water under the same sun, sky, atmosphere and sea surface). A fault in
/// the water names `surroundings.water`.
fn sea_beyond(
    ctx: &Ctx,
    text: &str,
    path: &std::path::Path,
    ov: &crate::scene::Overrides,
    water: &toml::Table,
) -> Result<crate::scene::Scene> {
    let steps = [K("surroundings"), K("water")];
    let mut wrapped = toml::Table::new();
    wrapped.insert("water".into(), toml::Value::Table(water.clone()));
    let fragment = toml::to_string(&wrapped).map_err(|e| ctx.err(&steps, e.to_string()))?;
    let mut derived = crate::scene::text::SceneText::parse(text)?;
    for key in [
        "water",
        "bottom",
        "land",
        "target",
        "radiometer",
        "surroundings",
        "sensor.altitude_m",
    ] {
        derived = derived.remove(key);
    }
    let derived = derived
        .merge(&fragment)
        .map_err(|e| ctx.err(&steps, e.to_string()))?;
    crate::scene::Scene::parse(&derived.text(), path, ov).map_err(|e| match e {
        crate::error::Error::Scene { key, what, .. } => ctx.err(
            &steps,
            format!("{}: {what}", key.strip_prefix("water.").unwrap_or(&key)),
        ),
        other => other,
    })
}
