//! Validation of `[atmosphere]` and the light it brings to the surface:
//! the sun's beam through the air and the sky, per band.

use super::*;
use crate::optics::atmosphere::transport::{band_light, ground_response, CELLS};
use crate::optics::atmosphere::{
    profile, Aerosol, AerosolHeight, AtmosphereSpec, Column, RayleighSetting,
};
use crate::optics::sky::{SkyModel, SkyTable};
use rayon::prelude::*;
use std::sync::Arc;

/// Photons per band for the sky at the surface, by default.
pub const DEFAULT_SKY_PHOTONS: u64 = 50_000;

/// Mixed into the scene's seed for the sky's photons.
const SKY_KEY: u64 = 0x736b_795f_7472_6163;

/// The atmosphere of `a`, its columns built on the scene's bands.
pub(super) fn spec(ctx: &Ctx, a: &AtmosphereFile) -> Result<AtmosphereSpec> {
    let key = |k| [K("atmosphere"), K(k)];
    let name = a.profile.as_deref().unwrap_or("us-standard-1976");
    let Some(profile) = profile::profile(name) else {
        return Err(ctx.err(
            &key("profile"),
            format!(
                "'{name}' is not a profile: use one of {}",
                profile::PROFILES.join(", ")
            ),
        ));
    };
    let surface_pressure_hpa = a.surface_pressure_hpa.unwrap_or(profile.p_hpa[0]);
    ctx.within(
        &key("surface_pressure_hpa"),
        surface_pressure_hpa,
        500.0,
        1100.0,
        "must be at least 500 hPa",
        "hPa",
    )?;
    let ozone_du = a.ozone_du.unwrap_or_else(|| profile.ozone_du());
    ctx.within(
        &key("ozone_du"),
        ozone_du,
        0.0,
        1000.0,
        "must be >= 0",
        "DU",
    )?;
    let rayleigh = match &a.rayleigh {
        None | Some(RayleighFile::On(true)) => RayleighSetting::Standard,
        Some(RayleighFile::On(false)) => RayleighSetting::Off,
        Some(RayleighFile::Tau(t)) => {
            ctx.within(&key("rayleigh"), t.tau, 0.0, 10.0, "tau must be >= 0", "")?;
            RayleighSetting::Tau(t.tau)
        }
    };
    let gas_tau = match &a.gas_tau_file {
        None => None,
        Some(name) => {
            let steps = key("gas_tau_file");
            let t = Table::from_csv_file(&ctx.file(name, &steps)?, "atmosphere.gas_tau_file")?;
            let v = ctx.per_band(&t, &steps)?;
            if let Some((b, x)) = v.iter().enumerate().find(|(_, x)| x.is_nan() || **x < 0.0) {
                let nm = ctx.bands.centers_nm()[b];
                return Err(ctx.err(&steps, format!("optical depth {x} at {nm} nm is negative")));
            }
            Some(v)
        }
    };
    let aerosol = a.aerosol.as_ref().map(|x| aerosol(ctx, x)).transpose()?;
    let ozone_table = tables::ozone_absorption();
    let (lo, hi) = ozone_table.range_nm();
    let ozone_per_atm_cm = ctx
        .bands
        .centers_nm()
        .iter()
        .zip(ctx.bands.fwhm_nm())
        .map(|(&c, &w)| {
            let c = f64::from(c);
            if (lo..=hi).contains(&c) {
                ozone_table.band_average(c, f64::from(w)).unwrap_or(0.0)
            } else if c > hi {
                0.0
            } else {
                ozone_table.at(lo).unwrap_or(0.0)
            }
        })
        .collect();
    Ok(AtmosphereSpec {
        profile,
        surface_pressure_hpa,
        ozone_du,
        rayleigh,
        aerosol,
        gas_tau,
        ozone_per_atm_cm,
    })
}

fn aerosol(ctx: &Ctx, a: &AerosolFile) -> Result<Aerosol> {
    let key = |k| [K("atmosphere"), K("aerosol"), K(k)];
    ctx.within(&key("tau_550"), a.tau_550, 0.0, 10.0, "must be >= 0", "")?;
    let name = match a.model {
        AerosolModel::Custom => None,
        AerosolModel::Continental => Some("continental"),
        AerosolModel::Maritime => Some("maritime"),
        AerosolModel::Urban => Some("urban"),
    };
    if let Some(name) = name {
        return named_aerosol(ctx, a, name);
    }
    let angstrom = a.angstrom.unwrap_or(1.0);
    ctx.within(
        &key("angstrom"),
        angstrom,
        -1.0,
        4.0,
        "must be at least -1",
        "",
    )?;
    let ssa = a.ssa.unwrap_or(1.0);
    ctx.within(&key("ssa"), ssa, 0.0, 1.0, "must be >= 0", "")?;
    let g = match &a.phase {
        None => 0.7,
        Some(p) => {
            let AerosolPhaseKind::HenyeyGreenstein = p.kind;
            if !(p.g.is_finite() && p.g.abs() < 0.99) {
                return Err(ctx.err(&key("phase"), "g must lie between -0.99 and 0.99"));
            }
            p.g
        }
    };
    Ok(Aerosol {
        tau_550: a.tau_550,
        angstrom,
        ssa,
        g,
        height: aerosol_height(ctx, a)?,
        named: None,
    })
}

/// A named 6S model: its spectrum, albedo and phase function come from its
/// tables, so the user's are refused; every band must lie within them
/// unless `[spectral] out_of_range = "clamp"`.
fn named_aerosol(ctx: &Ctx, a: &AerosolFile, name: &str) -> Result<Aerosol> {
    let key = |k| [K("atmosphere"), K("aerosol"), K(k)];
    let m = crate::optics::atmosphere::aerosol::named(name).expect("a shipped model");
    for (k, given) in [
        ("angstrom", a.angstrom.is_some()),
        ("ssa", a.ssa.is_some()),
        ("phase", a.phase.is_some()),
    ] {
        if given {
            return Err(ctx.err(
                &key(k),
                format!("the {name} model sets it (its Mie tables); give model = \"custom\" to set your own"),
            ));
        }
    }
    let (lo, hi) = m.range_nm();
    if ctx.policy != OutOfRange::Clamp {
        if let Some(c) = ctx
            .bands
            .centers_nm()
            .iter()
            .map(|&c| f64::from(c))
            .find(|c| !(lo..=hi).contains(c))
        {
            return Err(ctx.err(
                &key("model"),
                format!(
                    "the {name} model is tabulated from {lo} to {hi} nm, not at {c} nm (set spectral.out_of_range = \"clamp\" to use its nearest wavelength)"
                ),
            ));
        }
    }
    let at = |nm: f64| m.at(nm).expect("within the tables");
    let i550 = m.nm.iter().position(|&v| v == 550.0).unwrap_or(0);
    Ok(Aerosol {
        tau_550: a.tau_550,
        angstrom: -(at(860.0_f64.min(hi)).ext_rel / at(443.0_f64.max(lo)).ext_rel).ln()
            / (860.0_f64.min(hi) / 443.0_f64.max(lo)).ln(),
        ssa: m.ssa[i550],
        g: m.g[i550],
        height: aerosol_height(ctx, a)?,
        named: Some(m),
    })
}

/// `scale_height_km` or `top_km` (2 km scale height when neither).
fn aerosol_height(ctx: &Ctx, a: &AerosolFile) -> Result<AerosolHeight> {
    let key = |k| [K("atmosphere"), K("aerosol"), K(k)];
    Ok(match (a.scale_height_km, a.top_km) {
        (Some(h), None) => {
            ctx.within(
                &key("scale_height_km"),
                h,
                0.1,
                100.0,
                "must be at least 0.1 km",
                "km",
            )?;
            AerosolHeight::ScaleHeight(h)
        }
        (None, Some(t)) => {
            ctx.within(
                &key("top_km"),
                t,
                0.01,
                100.0,
                "must be at least 0.01 km",
                "km",
            )?;
            AerosolHeight::Top(t)
        }
        (None, None) => AerosolHeight::ScaleHeight(2.0),
        (Some(_), Some(_)) => {
            return Err(ctx.err(&key("top_km"), "give scale_height_km or top_km, not both"))
        }
    })
}

/// The sun's beam and the sky at the surface under `spec`, for the sun
/// `sun` whose irradiance is the beam-normal irradiance at the top of the
/// atmosphere: the sun of the surface (its beam through the air), the sky
/// and what the atmosphere did, per band. Over a Lambertian ground of
/// reflectance `ground` per band the sky also holds the light the ground
/// reflects and the air returns, to every order
/// (`transport::ground_response`).
pub(super) fn light(
    ctx: &Ctx,
    a: &AtmosphereFile,
    spec: AtmosphereSpec,
    sun: &Sun,
    day_of_year: Option<f64>,
    seed: u64,
    ground: Option<&[f64]>,
) -> Result<(Sun, Sky, AtmosphereLight)> {
    let photons = a.sky_photons.unwrap_or(DEFAULT_SKY_PHOTONS);
    if !(100..=100_000_000).contains(&photons) {
        return Err(ctx.err(
            &[K("atmosphere"), K("sky_photons")],
            "must be between 100 and 100000000",
        ));
    }
    let centers = ctx.bands.centers_nm();
    let ground_seed = crate::rng::mix64(seed ^ GROUND_KEY);
    let seed = crate::rng::mix64(seed ^ SKY_KEY);
    let columns: Vec<Column> = (0..centers.len())
        .map(|b| Column::new(&spec, b, f64::from(centers[b])))
        .collect();
    let lights: Vec<_> = columns
        .par_iter()
        .enumerate()
        .map(|(b, column)| {
            let l = band_light(column, sun.zenith_rad, photons, seed, b as u64, false);
            let g = ground.map(|_| ground_response(column, photons, ground_seed, b as u64));
            (column.totals(), l, g)
        })
        .collect();
    let toa = &sun.irradiance;
    let mu0 = sun.zenith_rad.cos();
    let mut bands = Vec::with_capacity(lights.len());
    let mut radiance = Vec::with_capacity(lights.len());
    for (b, (totals, l, g)) in lights.into_iter().enumerate() {
        let f0 = toa[b];
        let direct = f0 * mu0 * l.direct_transmittance;
        let mut sky: Vec<f64> = l.sky.iter().map(|v| v * f0).collect();
        let mut band = BandAtmosphere {
            nm: f64::from(centers[b]),
            tau: totals,
            direct_transmittance: l.direct_transmittance,
            toa_irradiance: f0,
            direct,
            diffuse: f0 * l.diffuse,
            diffuse_flux: f0 * l.diffuse_flux,
            diffuse_flux_se: f0 * l.diffuse_flux_se,
            up_at_top: f0 * l.up_at_top,
            absorbed: f0 * l.absorbed,
            spherical_albedo: 0.0,
            spherical_albedo_se: 0.0,
            surface_albedo: 0.0,
            surface_up: 0.0,
            surface_up_se: 0.0,
        };
        if let (Some(g), Some(r)) = (g, ground) {
            // E = E_black / (1 - R s): the ground's radiance R E / pi
            // comes back as the sky `g.sky` per unit radiance, and leaves
            // at the top or is absorbed in its shares.
            let r = r[b];
            let black = direct + band.diffuse;
            let total = black / (1.0 - r * g.spherical_albedo);
            let leaving = r * total / std::f64::consts::PI;
            for (v, k) in sky.iter_mut().zip(&g.sky) {
                *v += leaving * k;
            }
            let up = r * total;
            band.diffuse += up * g.spherical_albedo;
            band.diffuse_flux += up * g.spherical_albedo_flux;
            band.diffuse_flux_se = band.diffuse_flux_se.hypot(up * g.spherical_albedo_se);
            band.up_at_top += up * g.to_top;
            band.absorbed += up * g.absorbed;
            band.spherical_albedo = g.spherical_albedo_flux;
            band.spherical_albedo_se = g.spherical_albedo_se;
        }
        radiance.push(sky);
        bands.push(band);
    }
    debug_assert!(radiance.iter().all(|r| r.len() == CELLS));
    let surface_sun = Sun {
        irradiance: bands
            .iter()
            .map(|b| b.toa_irradiance * b.direct_transmittance)
            .collect(),
        ..sun.clone()
    };
    let sky = Sky {
        irradiance: bands.iter().map(|b| b.diffuse).collect(),
        model: SkyModel::Table(Arc::new(SkyTable::new(sun.azimuth_rad, &radiance))),
    };
    let light = AtmosphereLight {
        spec,
        day_of_year,
        sky_photons: photons,
        sky_seed: seed,
        sea_coupling: a.sea_coupling.unwrap_or(true),
        bands,
        sky_radiance: radiance,
        columns,
        view: None,
    };
    Ok((surface_sun, sky, light))
}

/// Photons per band for the path radiance, per photon of the sky: a
/// collision adds to one direction here, to 324 cells there.
const PATH_PHOTONS_PER_SKY_PHOTON: u64 = 4;

/// Mixed into the scene's seed for the path radiance's photons.
const PATH_KEY: u64 = 0x7061_7468_5f72_6164;

/// Mixed into the scene's seed for the photons a Lambertian ground sends
/// up into the air.
const GROUND_KEY: u64 = 0x6772_6f75_6e64_5f75;

/// Mixed into the scene's seed for the upward transmittance's photons.
const UP_KEY: u64 = 0x7570_5f74_7261_6e73;

/// The air between the ground and `sensor` (at `altitude_m`) along its
/// view, for the sun `sun` (at the surface; its zenith and azimuth are the
/// top's).
pub(super) fn view(light: &AtmosphereLight, sun: &Sun, sensor: &Sensor, seed: u64) -> ViewLight {
    let altitude_m = sensor.altitude_m.unwrap_or(0.0);
    let z_km = altitude_m * 1e-3;
    let toward = sensor.toward.as_dvec3().normalize();
    // The view's azimuth from the sun's, in the transport's frame.
    let phi = toward.y.atan2(toward.x) - sun.azimuth_rad;
    let s = (1.0 - toward.z * toward.z).max(0.0).sqrt();
    let view = glam::DVec3::new(s * phi.cos(), s * phi.sin(), toward.z);
    let photons = light.sky_photons * PATH_PHOTONS_PER_SKY_PHOTON;
    let up_seed = crate::rng::mix64(seed ^ UP_KEY);
    let seed = crate::rng::mix64(seed ^ PATH_KEY);
    let per_band: Vec<[f64; 5]> = light
        .columns
        .par_iter()
        .enumerate()
        .map(|(b, column)| {
            let depth = column.depth_at(z_km);
            let t = (-(column.total() - depth) / toward.z).exp();
            let (l, se) = crate::optics::atmosphere::transport::path_radiance(
                column,
                sun.zenith_rad,
                view,
                depth,
                photons,
                seed,
                b as u64,
            );
            let f0 = light.bands[b].toa_irradiance;
            let (t_up, t_up_se) = crate::optics::atmosphere::transport::transmittance_up(
                column,
                toward.z.clamp(-1.0, 1.0).acos(),
                depth,
                light.sky_photons,
                up_seed,
                b as u64,
            );
            [t, l * f0, se * f0, t_up, t_up_se]
        })
        .collect();
    ViewLight {
        altitude_m,
        transmittance: per_band.iter().map(|v| v[0]).collect(),
        path_radiance: per_band.iter().map(|v| v[1]).collect(),
        path_radiance_se: per_band.iter().map(|v| v[2]).collect(),
        transmittance_up: per_band.iter().map(|v| v[3]).collect(),
        transmittance_up_se: per_band.iter().map(|v| v[4]).collect(),
    }
}
