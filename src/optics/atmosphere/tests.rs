use super::transport::{
    band_light, point_in_cell, projected_solid_angle, AZIMUTH_BINS, CELLS, ZENITH_BINS,
};
use super::*;

fn spec(rayleigh: RayleighSetting, aerosol: Option<Aerosol>, ozone_du: f64) -> AtmosphereSpec {
    AtmosphereSpec {
        profile: profile::profile("us-standard-1976").unwrap(),
        surface_pressure_hpa: 1013.25,
        ozone_du,
        rayleigh,
        aerosol,
        gas_tau: None,
        ozone_per_atm_cm: vec![0.085],
    }
}

/// Bodhaine et al.'s fit against Hansen & Travis (1974), tau = 0.008569
/// l^-4 (1 + 0.0113 l^-2 + 0.00013 l^-4): two published formulas from
/// different refractive-index and depolarisation data, within 0.5 %.
#[test]
fn rayleigh_optical_depth_agrees_with_hansen_travis() {
    for nm in (400..=900).step_by(25) {
        let l = nm as f64 * 1e-3;
        let ht = 0.008569 * l.powi(-4) * (1.0 + 0.0113 * l.powi(-2) + 0.00013 * l.powi(-4));
        let b = rayleigh::optical_depth(nm as f64);
        assert!((b / ht - 1.0).abs() < 5e-3, "{nm} nm: {b} against {ht}");
    }
    // Air's depolarisation ratio: near 0.03 in the visible, rising toward
    // the blue.
    let d = rayleigh::depolarisation(550.0);
    assert!((0.027..0.031).contains(&d), "{d}");
    assert!(rayleigh::depolarisation(400.0) > d);
}

/// The Sun's distance through the year: (r0/r)^2 at perihelion (about 3
/// January, r = 0.98329 AU) and aphelion (about 4 July, 1.01671 AU).
#[test]
fn earth_sun_factor_follows_the_orbit() {
    let peri = 1.0 / (0.98329f64 * 0.98329);
    let aph = 1.0 / (1.01671f64 * 1.01671);
    assert!((earth_sun_factor(3.0) / peri - 1.0).abs() < 2e-3);
    assert!((earth_sun_factor(185.0) / aph - 1.0).abs() < 2e-3);
    let mean: f64 = (1..=365).map(|d| earth_sun_factor(d as f64)).sum::<f64>() / 365.0;
    assert!((mean - 1.0).abs() < 1e-3, "{mean}");
}

/// The U.S. Standard profile's ozone column is the 345.6 DU AFGL's levels
/// give by the trapezoid rule (an independent sum over the CSV's rows).
#[test]
fn profiles_hold_their_ozone() {
    let p = profile::profile("us-standard-1976").unwrap();
    let text = include_str!("../../../data/afgl_profiles.csv");
    let rows: Vec<Vec<f64>> = text
        .lines()
        .filter(|l| l.starts_with("us-standard-1976,"))
        .map(|l| l.split(',').skip(1).map(|v| v.parse().unwrap()).collect())
        .collect();
    let mut du = 0.0;
    for w in rows.windows(2) {
        let n = |r: &Vec<f64>| r[3] * r[5] * 1e-6;
        du += 0.5 * (n(&w[0]) + n(&w[1])) * (w[1][0] - w[0][0]) * 1e5 / 2.686_780_1e16;
    }
    assert!((p.ozone_du() - du).abs() < 1e-9 * du);
    assert!((du - 345.6).abs() < 0.1, "{du}");
    for name in profile::PROFILES {
        let q = profile::profile(name).unwrap();
        assert_eq!(q.z_km.len(), 50, "{name}");
        assert!(q.ozone_du() > 250.0 && q.ozone_du() < 400.0, "{name}");
    }
}

/// A column holds exactly the optical depths it was given, spread as
/// asked: Rayleigh and gases by pressure, the aerosol by its scale height
/// or up to its top.
#[test]
fn columns_hold_their_optical_depths() {
    let aerosol = Aerosol {
        tau_550: 0.2,
        angstrom: 1.3,
        ssa: 0.9,
        g: 0.7,
        height: AerosolHeight::ScaleHeight(2.0),
        named: None,
    };
    let c = Column::new(
        &spec(RayleighSetting::Standard, Some(aerosol), 300.0),
        0,
        500.0,
    );
    let t = c.totals();
    let close = |a: f64, b: f64| (a - b).abs() < 1e-12 * b.max(1.0);
    assert!(close(t.rayleigh, rayleigh::optical_depth(500.0)));
    assert!(close(
        t.aerosol_scattering,
        0.9 * 0.2 * (500.0f64 / 550.0).powf(-1.3)
    ));
    assert!(close(
        t.aerosol_absorption,
        0.1 * 0.2 * (500.0f64 / 550.0).powf(-1.3)
    ));
    assert!(close(t.ozone, 0.085 * 0.3));
    assert!(close(c.total(), t.extinction()));
    assert!(c.depth.windows(2).all(|w| w[1] >= w[0]));
    // Below the scale height: 1 - 1/e of the aerosol.
    let below: f64 = c
        .layers
        .iter()
        .filter(|l| l.top_km <= 2.0)
        .map(|l| l.aerosol_scattering)
        .sum();
    assert!(close(below / t.aerosol_scattering, 1.0 - (-1.0f64).exp()));
    // Half the air lies below about 5.5 km.
    let half: f64 = c
        .layers
        .iter()
        .filter(|l| l.top_km <= 5.0)
        .map(|l| l.rayleigh)
        .sum();
    assert!(
        (0.40..0.50).contains(&(half / t.rayleigh)),
        "{}",
        half / t.rayleigh
    );
    let top = Aerosol {
        height: AerosolHeight::Top(1.5),
        named: None,
        ..aerosol
    };
    let c = Column::new(&spec(RayleighSetting::Off, Some(top), 0.0), 0, 550.0);
    let low: Vec<_> = c
        .layers
        .iter()
        .filter(|l| l.aerosol_scattering > 0.0)
        .collect();
    assert_eq!(low.len(), 2, "0-1 km and 1-1.5 km");
    for l in low {
        assert!(close(
            l.aerosol_scattering,
            0.18 * (l.top_km - l.bottom_km) / 1.5
        ));
    }
}

/// Everything leaving the top of the atmosphere goes somewhere: the direct
/// beam (exact), the sky at the surface, back out of the top and absorbed
/// in the air add up to mu0 per unit irradiance, within the photons'
/// noise; and the sky's cells add up to the irradiance the photons
/// reaching the surface carry (two independent estimators).
#[test]
fn energy_closes_and_the_cells_hold_the_sky_irradiance() {
    let aerosol = Aerosol {
        tau_550: 0.3,
        angstrom: 1.0,
        ssa: 0.85,
        g: 0.7,
        height: AerosolHeight::ScaleHeight(1.5),
        named: None,
    };
    let c = Column::new(
        &spec(RayleighSetting::Standard, Some(aerosol), 300.0),
        0,
        450.0,
    );
    let sun = 50f64.to_radians();
    let mu0 = sun.cos();
    let runs: Vec<_> = (0..8)
        .map(|s| band_light(&c, sun, 20_000, 7, s, false))
        .collect();
    let mean = |f: &dyn Fn(&transport::BandLight) -> f64| {
        let v: Vec<f64> = runs.iter().map(f).collect();
        let m = v.iter().sum::<f64>() / v.len() as f64;
        let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() - 1) as f64;
        (m, (var / v.len() as f64).sqrt())
    };
    let (sum, se) =
        mean(&|l| mu0 * l.direct_transmittance + l.diffuse_flux + l.up_at_top + l.absorbed);
    assert!(
        (sum - mu0).abs() < 4.0 * se + 1e-9,
        "{sum} against {mu0} +- {se}"
    );
    let (cells, se_c) = mean(&|l| l.diffuse);
    let (flux, se_f) = mean(&|l| l.diffuse_flux);
    let se = (se_c * se_c + se_f * se_f).sqrt();
    assert!(
        (cells - flux).abs() < 4.0 * se,
        "{cells} against {flux} +- {se}"
    );
    assert!(se < 0.01 * flux, "{se}");
}

/// Single scattering in an optically thin Rayleigh layer, cell by cell,
/// against the closed form: down at the surface L = F0 p(Theta) mu0
/// (exp(-tau/mu0) - exp(-tau/mu)) / (mu0 - mu), up at the top L = F0
/// p(Theta) mu0 (1 - exp(-tau/mu0 - tau/mu)) / (mu0 + mu), each averaged
/// cosine-weighted over the cell by quadrature. At tau = 0.002 multiple
/// scattering is 0.1 % of it. Sixteen independent runs give each cell's
/// standard error: the cells' squared z-scores average about 1 (15/13 for
/// an error estimated from 16 runs), none beyond 6, and the total, whose
/// noise is the collisions' Poisson count, lies within 4 of its standard
/// errors.
#[test]
fn a_thin_layer_scatters_once_as_the_closed_form_says() {
    let tau = 0.002;
    let c = Column::new(&spec(RayleighSetting::Tau(tau), None, 0.0), 0, 550.0);
    let sun = 30f64.to_radians();
    let mu0 = sun.cos();
    let (runs, photons) = (16, 250_000);
    let lights: Vec<_> = (0..runs)
        .map(|s| band_light(&c, sun, photons, 11, s, true))
        .collect();
    let q = rayleigh::phase_q(550.0);
    let p = |cos: f64| 3.0 / (4.0 * std::f64::consts::PI * (3.0 + q)) * (1.0 + q * cos * cos);
    let closed = |mu: f64, phi: f64, down: bool| {
        // Travel of the scattered light: down (-s) or up (s).
        let (sz, s0) = ((1.0 - mu * mu).sqrt(), sun.sin());
        let sign = if down { -1.0 } else { 1.0 };
        let cos = sign * (-s0 * sz * phi.cos() - mu0 * mu);
        let att = if down {
            mu0 * ((-tau / mu0).exp() - (-tau / mu).exp()) / (mu0 - mu)
        } else {
            mu0 * (1.0 - (-tau / mu0 - tau / mu).exp()) / (mu0 + mu)
        };
        p(cos) * att
    };
    let collisions = (runs * photons) as f64 * (1.0 - (-tau / mu0).exp());
    let level = 1.0 / collisions.sqrt();
    for down in [true, false] {
        let table = |l: &transport::BandLight| -> Vec<f64> {
            if down {
                l.sky.clone()
            } else {
                l.toa.clone().unwrap()
            }
        };
        let tables: Vec<Vec<f64>> = lights.iter().map(table).collect();
        let mut want = vec![0.0; CELLS];
        for iz in 0..ZENITH_BINS {
            for ia in 0..AZIMUTH_BINS {
                let n = 24;
                let mut sum = 0.0;
                for i in 0..n {
                    for j in 0..n {
                        let u = [(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64];
                        let (mu, phi) = point_in_cell(iz, ia, u);
                        sum += closed(mu, phi, down);
                    }
                }
                want[iz * AZIMUTH_BINS + ia] = sum / (n * n) as f64;
            }
        }
        let total = |v: &[f64]| -> f64 {
            (0..CELLS)
                .map(|c| v[c] * projected_solid_angle(c / AZIMUTH_BINS))
                .sum()
        };
        let got_total = tables.iter().map(|t| total(t)).sum::<f64>() / runs as f64;
        let ratio = got_total / total(&want);
        assert!(
            (ratio - 1.0).abs() < 4.0 * level,
            "level {ratio}, down {down}"
        );
        let mut chi2 = 0.0;
        for c in 0..CELLS {
            let v: Vec<f64> = tables.iter().map(|t| t[c]).collect();
            let m = v.iter().sum::<f64>() / runs as f64;
            let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (runs - 1) as f64;
            let z = (m - want[c]) / (var / runs as f64).sqrt();
            assert!(
                z.abs() < 6.0,
                "cell {c}: {m} against {}, z {z}, down {down}",
                want[c]
            );
            chi2 += z * z;
        }
        let per_cell = chi2 / CELLS as f64;
        assert!(per_cell < 1.5, "chi2 per cell {per_cell}, down {down}");
    }
}

/// The named models read back their tables: at a tabulated wavelength the
/// extinction, albedo and phase are the table's; halfway between two the
/// mean of theirs; each wavelength's phase function, read linearly in
/// angle as the renderers read it, has the Mie asymmetry the table gives
/// within 2e-3; outside 350-860 nm there is nothing.
#[test]
fn named_aerosols_read_back_their_tables() {
    for name in aerosol::MODELS {
        let m = aerosol::named(name).unwrap();
        assert_eq!(m.nm.len(), m.phase.len());
        let i550 = m.nm.iter().position(|&v| v == 550.0).unwrap();
        assert_eq!(m.ext_rel[i550], 1.0);
        for (k, &nm) in m.nm.iter().enumerate() {
            let at = m.at(nm).unwrap();
            assert_eq!((at.ext_rel, at.ssa), (m.ext_rel[k], m.ssa[k]));
            assert_eq!(at.phase, m.phase[k]);
            let a = Aerosol {
                tau_550: 0.2,
                angstrom: 0.0,
                ssa: 0.0,
                g: 0.0,
                height: AerosolHeight::ScaleHeight(1.0),
                named: Some(m),
            };
            let g = a.phase_at(nm).mean_cosine();
            assert!(
                (g - m.g[k]).abs() < 2e-3,
                "{name} {nm} nm: g {g} against {}",
                m.g[k]
            );
            assert!((a.tau(nm) - 0.2 * m.ext_rel[k]).abs() < 1e-12);
            assert_eq!(a.ssa_at(nm), m.ssa[k]);
        }
        let mid = 0.5 * (m.nm[3] + m.nm[4]);
        let at = m.at(mid).unwrap();
        assert!((at.ssa - 0.5 * (m.ssa[3] + m.ssa[4])).abs() < 1e-12);
        assert!(m.at(340.0).is_none() && m.at(870.0).is_none());
    }
    // What 6S gives these models at 550 nm (6SV1.0B's own component
    // tables mixed by its rule): albedo 0.8932 / 0.9890 / 0.6888.
    for (name, ssa) in [
        ("continental", 0.8932),
        ("maritime", 0.9890),
        ("urban", 0.6888),
    ] {
        let m = aerosol::named(name).unwrap();
        let at = m.at(550.0).unwrap();
        assert!((at.ssa - ssa).abs() < 2e-4, "{name}: {}", at.ssa);
    }
}

/// A column under a named model holds tau_550 times the model's relative
/// extinction at its wavelength, split by the model's albedo, and takes
/// the model's phase function.
#[test]
fn a_named_aerosol_sets_the_column() {
    let m = aerosol::named("urban").unwrap();
    let a = Aerosol {
        tau_550: 0.4,
        angstrom: 0.0,
        ssa: 0.0,
        g: 0.0,
        height: AerosolHeight::Top(2.0),
        named: Some(m),
    };
    let s = spec(RayleighSetting::Off, Some(a), 0.0);
    let at = m.at(443.0).unwrap();
    let c = Column::new(&s, 0, 443.0);
    let t = c.totals();
    assert!((t.aerosol_scattering + t.aerosol_absorption - 0.4 * at.ext_rel).abs() < 1e-12);
    assert!((t.aerosol_scattering / (0.4 * at.ext_rel) - at.ssa).abs() < 1e-12);
    assert!(matches!(c.aerosol_phase, PhaseFunction::Tabulated(_)));
}
