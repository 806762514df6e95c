//! The emission report: irradiance profiles, apparent optical properties
//! and the energy budget, per band, in absolute units.

use super::tally::{lu_cone_projected_solid_angle, Totals, ED, EOD, EOU, EU, LD, LU};
use crate::scene::Scene;
use serde::{Deserialize, Serialize};

/// Irradiances at one tally depth (W m^-2 nm^-1 per band).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[allow(non_snake_case)]
pub struct DepthTally {
    pub depth_m: f64,
    /// The share of the domain that is water at this depth (the floor
    /// below it; targets not counted out). Every quantity of the tally is
    /// a mean over that water, not over the whole domain: where a sloping
    /// floor leaves 69 % of the domain wet at 5 m, E_d at 5 m is the mean
    /// E_d of that 69 %.
    #[serde(default = "one")]
    pub water_fraction: f64,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub Ed: Vec<f64>,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub Eu: Vec<f64>,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub Eod: Vec<f64>,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub Eou: Vec<f64>,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub Ed_stderr: Vec<f64>,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub Eu_stderr: Vec<f64>,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub Eod_stderr: Vec<f64>,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub Eou_stderr: Vec<f64>,
    /// Upwelling radiance travelling within `emit::tally::LU_CONE_DEG` of
    /// straight up (what a radiometer looking at nadir measures),
    /// W m^-2 sr^-1 nm^-1.
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub Lu: Vec<f64>,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub Lu_stderr: Vec<f64>,
    /// Downwelling radiance travelling within the same cone of straight
    /// down (what a radiometer looking at the zenith measures; direct sun
    /// within the cone included), W m^-2 sr^-1 nm^-1.
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub Ld: Vec<f64>,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub Ld_stderr: Vec<f64>,
    /// Irradiance reflectance Eu / Ed.
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub R: Vec<f64>,
}

/// Just above the surface (Eu includes light reflected by the surface).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[allow(non_snake_case)]
pub struct AboveSurface {
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub Ed: Vec<f64>,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub Eu: Vec<f64>,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub Ed_stderr: Vec<f64>,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub Eu_stderr: Vec<f64>,
}

/// Diffuse attenuation of Ed between two tally depths (1/m).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[allow(non_snake_case)]
pub struct KdLayer {
    pub from_m: f64,
    pub to_m: f64,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub Kd: Vec<f64>,
}

/// Where the emitted power went, per band (W nm^-1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Energy {
    pub units: String,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub emitted: Vec<f64>,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub escaped: Vec<f64>,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub absorbed_water: Vec<f64>,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub absorbed_surfaces: Vec<f64>,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub lost_edges: Vec<f64>,
    /// Fell on land from the sky (`[land]`): reflected or absorbed there,
    /// not traced on. Empty in reports written before land existed.
    #[serde(default, deserialize_with = "crate::nan_json::f64s")]
    pub on_land: Vec<f64>,
    /// Inelastic light (`[water] raman`, `[water.fluorescence]`): power
    /// taken out of each band by Raman scattering and fluorescence that
    /// was emitted into another band of the grid, emitted beyond the grid,
    /// and power emitted into it from shorter bands. Zero without
    /// inelastic light. Power emitted is less than power taken by λ'/λ
    /// (and the quantum yield): the rest goes into the water's vibration,
    /// or is absorbed. (Older reports, Raman alone, named them raman_*.)
    #[serde(
        default,
        alias = "raman_out",
        deserialize_with = "crate::nan_json::f64s"
    )]
    pub inelastic_out: Vec<f64>,
    #[serde(
        default,
        alias = "raman_lost",
        deserialize_with = "crate::nan_json::f64s"
    )]
    pub inelastic_lost: Vec<f64>,
    #[serde(
        default,
        alias = "raman_in",
        deserialize_with = "crate::nan_json::f64s"
    )]
    pub inelastic_in: Vec<f64>,
    /// Power that left the water up through the surface (the
    /// water-leaving light, without the surface's reflection), and the
    /// part of it inelastic light had moved into the band: their ratio is
    /// the inelastic share of the water-leaving light, over the domain
    /// and every direction. Absent from older reports.
    #[serde(default, deserialize_with = "crate::nan_json::f64s")]
    pub water_leaving: Vec<f64>,
    #[serde(default, deserialize_with = "crate::nan_json::f64s")]
    pub water_leaving_inelastic: Vec<f64>,
    /// emitted + inelastic in - (escaped + absorbed + lost + inelastic
    /// out and lost), per band.
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub residual: Vec<f64>,
    /// residual / its standard error, per band.
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub closure_sigma_per_band: Vec<f64>,
    /// The largest |residual / standard error| over the bands.
    #[serde(deserialize_with = "crate::nan_json::f64_or_nan")]
    pub closure_sigma: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PhotonCounts {
    pub traced: u64,
    pub stored_volume: u64,
    pub stored_surface: u64,
    /// Paths stopped at the event limit (counted as absorbed in water).
    pub truncated: u64,
}

/// What the emission report needs of the scene besides the run's totals.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReportInputs {
    pub scene: String,
    pub bands_nm: Vec<f32>,
    pub fwhm_nm: Vec<f32>,
    pub area_m2: f64,
    pub tally_depths_m: Vec<f64>,
    /// The share of the domain that is water at each tally depth
    /// ([`water_fraction`]); empty in reports written before it existed
    /// (read as 1).
    #[serde(default)]
    pub water_fraction: Vec<f64>,
    /// E_d(0+) per band (W m^-2 nm^-1).
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub incident_irradiance: Vec<f64>,
    /// Power per photon of each band (W nm^-1).
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub photon_power: Vec<f64>,
    /// The air's side of the budget, with an atmosphere whose sky returns
    /// the domain's own sea's light or none (see [`AirInputs::of`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub air: Option<AirInputs>,
}

/// What the air did with the sun's light, per band (W m^-2 nm^-1 on a
/// horizontal plane): the sun at the top, what leaves the top and what
/// the air absorbs (the sea's light it was sent included), and the
/// standard error of what these leave for the surface.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AirInputs {
    pub top: Vec<f64>,
    pub to_space: Vec<f64>,
    pub absorbed: Vec<f64>,
    pub stderr: Vec<f64>,
    /// The sky holds what the air returns of the sea's light
    /// (`sea_coupling`); otherwise that light is taken to leave.
    pub coupled: bool,
}

impl AirInputs {
    /// The air of `scene`: none without an atmosphere, and none where the
    /// air above the domain sees other ground than the domain's own sea
    /// (land or another sea all around, whose light its sky returns).
    pub fn of(scene: &Scene) -> Option<AirInputs> {
        let a = scene.atmosphere.as_deref()?;
        match &scene.surroundings {
            Some(crate::scene::Surroundings::Lambertian(_)) => return None,
            Some(crate::scene::Surroundings::Water(_)) if a.sea_coupling => return None,
            _ => {}
        }
        let mu0 = scene.sun.zenith_rad.cos();
        let n = a.sky_photons.max(1) as f64;
        Some(AirInputs {
            top: a.bands.iter().map(|b| b.toa_irradiance * mu0).collect(),
            to_space: a.bands.iter().map(|b| b.up_at_top).collect(),
            absorbed: a.bands.iter().map(|b| b.absorbed).collect(),
            stderr: a
                .bands
                .iter()
                .map(|b| {
                    // The photons' own direct share against the exact one
                    // (binomial), the sky's flux against its cells, and
                    // the sea's upward irradiance the air was sent.
                    let t = b.direct_transmittance;
                    let direct = b.toa_irradiance * mu0 * (t * (1.0 - t) / n).sqrt();
                    direct.hypot(b.diffuse_flux_se).hypot(b.surface_up_se)
                })
                .collect(),
            coupled: a.sea_coupling,
        })
    }
}

/// The budget of the air over the domain, per band (W nm^-1): the sun's
/// power at the top and the power the surface sends up (the photons'
/// E_u(0+)) go into it; what reaches the surface (the emitted power),
/// leaves the top and is absorbed come out. Without `sea_coupling` the
/// surface's light is taken to leave the top.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AirBudget {
    pub units: String,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub top: Vec<f64>,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub surface_up: Vec<f64>,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub to_surface: Vec<f64>,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub to_space: Vec<f64>,
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub absorbed_air: Vec<f64>,
    /// top + surface_up - (to_surface + to_space + absorbed_air).
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub residual: Vec<f64>,
    /// residual / its standard error (the photons' E_u(0+) and the air's
    /// own, [`AirInputs::stderr`]), per band, and the largest |.|.
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub closure_sigma_per_band: Vec<f64>,
    #[serde(deserialize_with = "crate::nan_json::f64_or_nan")]
    pub closure_sigma: f64,
}

impl AirBudget {
    fn new(air: &AirInputs, area: f64, emitted: &[f64], eu: &[f64], eu_se: &[f64]) -> AirBudget {
        let nb = emitted.len();
        let per = |v: &[f64]| -> Vec<f64> { v.iter().map(|x| x * area).collect() };
        let top = per(&air.top);
        let surface_up = per(eu);
        let to_space: Vec<f64> = (0..nb)
            .map(|b| air.to_space[b] * area + if air.coupled { 0.0 } else { surface_up[b] })
            .collect();
        let absorbed_air = per(&air.absorbed);
        let mut residual = Vec::with_capacity(nb);
        let mut sigma = Vec::with_capacity(nb);
        for b in 0..nb {
            let r = top[b] + surface_up[b] - emitted[b] - to_space[b] - absorbed_air[b];
            let up_se = if air.coupled { eu_se[b] * area } else { 0.0 };
            let sd = up_se.hypot(air.stderr[b] * area);
            residual.push(r);
            sigma.push(in_sigmas(r, sd));
        }
        AirBudget {
            units: "W nm^-1".into(),
            closure_sigma: largest(&sigma),
            top,
            surface_up,
            to_surface: emitted.to_vec(),
            to_space,
            absorbed_air,
            residual,
            closure_sigma_per_band: sigma,
        }
    }
}

impl ReportInputs {
    pub fn new(scene: &Scene, photon_power: &[f64]) -> Self {
        ReportInputs {
            scene: scene.name.clone(),
            bands_nm: scene.bands.centers_nm().to_vec(),
            fwhm_nm: scene.bands.fwhm_nm().to_vec(),
            area_m2: scene.domain.area_m2(),
            tally_depths_m: scene.tally_depths.clone(),
            water_fraction: scene
                .tally_depths
                .iter()
                .map(|&d| water_fraction(scene, d))
                .collect(),
            incident_irradiance: (0..scene.bands.len())
                .map(|b| scene.incident_irradiance(b))
                .collect(),
            photon_power: photon_power.to_vec(),
            air: AirInputs::of(scene),
        }
    }
}

/// The physics part of the emission report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EmissionReport {
    pub scene: String,
    pub bands_nm: Vec<f32>,
    pub fwhm_nm: Vec<f32>,
    pub tally: Vec<DepthTally>,
    pub above_surface: AboveSurface,
    pub kd: Vec<KdLayer>,
    pub energy: Energy,
    /// With an atmosphere: the air's budget (see [`AirBudget`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub air: Option<AirBudget>,
    pub photons: PhotonCounts,
    /// Power carried by one photon of each band (W nm^-1).
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub photon_power: Vec<f64>,
}

impl EmissionReport {
    /// The tallies as a CSV table, one row per depth and band, as
    /// HydroLight users read profiles: irradiances in W m^-2 nm^-1,
    /// radiances in W m^-2 sr^-1 nm^-1 (Lu, Ld: the 10-degree cones), each
    /// with its standard error.
    pub fn profiles_csv(&self) -> String {
        let mut t = String::from(
            "depth_m,wavelength_nm,Ed_W_m2_nm,Ed_stderr,Eu_W_m2_nm,Eu_stderr,Eod_W_m2_nm,Eod_stderr,\
             Eou_W_m2_nm,Eou_stderr,Lu_W_m2_sr_nm,Lu_stderr,Ld_W_m2_sr_nm,Ld_stderr,water_fraction\n",
        );
        for d in &self.tally {
            for (b, nm) in self.bands_nm.iter().enumerate() {
                let v = [
                    d.Ed[b],
                    d.Ed_stderr[b],
                    d.Eu[b],
                    d.Eu_stderr[b],
                    d.Eod[b],
                    d.Eod_stderr[b],
                    d.Eou[b],
                    d.Eou_stderr[b],
                    d.Lu[b],
                    d.Lu_stderr[b],
                    d.Ld[b],
                    d.Ld_stderr[b],
                ];
                t.push_str(&format!("{},{nm}", d.depth_m));
                for x in v {
                    t.push_str(&format!(",{x}"));
                }
                t.push_str(&format!(",{}\n", d.water_fraction));
            }
        }
        t
    }

    /// The diffuse attenuation of downwelling irradiance between tally
    /// depths as a CSV table (1/m), one row per layer and band.
    pub fn kd_csv(&self) -> String {
        let mut t = String::from("from_m,to_m,wavelength_nm,Kd_per_m\n");
        for l in &self.kd {
            for (nm, k) in self.bands_nm.iter().zip(&l.Kd) {
                t.push_str(&format!("{},{},{nm},{k}\n", l.from_m, l.to_m));
            }
        }
        t
    }

    /// Turn run totals into absolute quantities.
    pub fn new(scene: &Scene, totals: &Totals, photon_power: &[f64]) -> Self {
        Self::from_inputs(&ReportInputs::new(scene, photon_power), totals)
    }

    /// [`EmissionReport::new`] from what it needs of the scene (shards
    /// carry these, so a merge needs no scene).
    pub fn from_inputs(inputs: &ReportInputs, totals: &Totals) -> Self {
        let photon_power = &inputs.photon_power[..];
        let nb = inputs.bands_nm.len();
        let n = totals.traced as f64;
        let area = inputs.area_m2;
        // A tally mean per traced photon m becomes irradiance m N P_b / A.
        let scale: Vec<f64> = (0..nb).map(|b| n * photon_power[b] / area).collect();
        let series = |slot: usize| -> (Vec<f64>, Vec<f64>) {
            (0..nb)
                .map(|b| {
                    let (m, se) = totals.mean_and_stderr(slot, b);
                    (m * scale[b], se * scale[b])
                })
                .unzip()
        };
        let mut tally = Vec::new();
        for (d, &depth) in inputs.tally_depths_m.iter().enumerate() {
            // Means over the water present at this depth.
            let wet = inputs.water_fraction.get(d).copied().unwrap_or(1.0);
            let per_wet = if wet > 0.0 { 1.0 / wet } else { 1.0 };
            let series = |slot: usize| -> (Vec<f64>, Vec<f64>) {
                let (m, s) = series(slot);
                (
                    m.iter().map(|v| v * per_wet).collect(),
                    s.iter().map(|v| v * per_wet).collect(),
                )
            };
            let (ed, ed_se) = series(totals.slot(d, ED));
            let (eu, eu_se) = series(totals.slot(d, EU));
            let (eod, eod_se) = series(totals.slot(d, EOD));
            let (eou, eou_se) = series(totals.slot(d, EOU));
            let omega = lu_cone_projected_solid_angle();
            let radiance = |q: usize| -> (Vec<f64>, Vec<f64>) {
                let (l, s) = series(totals.slot(d, q));
                (
                    l.iter().map(|v| v / omega).collect(),
                    s.iter().map(|v| v / omega).collect(),
                )
            };
            let (lu, lu_se) = radiance(LU);
            let (ld, ld_se) = radiance(LD);
            let r = ed
                .iter()
                .zip(&eu)
                .map(|(d, u)| if *d > 0.0 { u / d } else { 0.0 })
                .collect();
            tally.push(DepthTally {
                depth_m: depth,
                water_fraction: wet,
                Ed: ed,
                Eu: eu,
                Eod: eod,
                Eou: eou,
                Ed_stderr: ed_se,
                Eu_stderr: eu_se,
                Eod_stderr: eod_se,
                Eou_stderr: eou_se,
                Lu: lu,
                Lu_stderr: lu_se,
                Ld: ld,
                Ld_stderr: ld_se,
                R: r,
            });
        }
        let kd = kd_layers(&tally);
        let (up, uu) = totals.above_slots();
        let (ed, ed_se) = series(up);
        let (eu, eu_se) = series(uu);

        let energy = energy(inputs, totals);
        let air = inputs
            .air
            .as_ref()
            .map(|a| AirBudget::new(a, area, &energy.emitted, &eu, &eu_se));
        EmissionReport {
            scene: inputs.scene.clone(),
            bands_nm: inputs.bands_nm.clone(),
            fwhm_nm: inputs.fwhm_nm.clone(),
            tally,
            above_surface: AboveSurface {
                Ed: ed,
                Eu: eu,
                Ed_stderr: ed_se,
                Eu_stderr: eu_se,
            },
            kd,
            energy,
            air,
            photons: PhotonCounts {
                traced: totals.traced,
                stored_volume: totals.stored_volume,
                stored_surface: totals.stored_surface,
                truncated: totals.truncated,
            },
            photon_power: photon_power.to_vec(),
        }
    }
}

/// Kd between consecutive tally depths, from their E_d (NaN where a band
/// has none at either depth).
fn kd_layers(tally: &[DepthTally]) -> Vec<KdLayer> {
    tally
        .windows(2)
        .map(|w| KdLayer {
            from_m: w[0].depth_m,
            to_m: w[1].depth_m,
            Kd: w[0]
                .Ed
                .iter()
                .zip(&w[1].Ed)
                .map(|(a, b)| {
                    if *a > 0.0 && *b > 0.0 {
                        (a / b).ln() / (w[1].depth_m - w[0].depth_m)
                    } else {
                        f64::NAN
                    }
                })
                .collect(),
        })
        .collect()
}

/// The energy budget: emitted, the power in each fate, and the closure
/// residual in binomial standard deviations per band.
fn energy(inputs: &ReportInputs, totals: &Totals) -> Energy {
    let photon_power = &inputs.photon_power[..];
    let nb = inputs.bands_nm.len();
    let n = totals.traced as f64;
    let area = inputs.area_m2;
    let power = |counts: &[u64]| -> Vec<f64> {
        counts
            .iter()
            .zip(photon_power)
            .map(|(&c, p)| c as f64 / super::trace::FATE_UNIT as f64 * p)
            .collect()
    };
    let emitted: Vec<f64> = (0..nb)
        .map(|b| inputs.incident_irradiance[b] * area)
        .collect();
    let escaped = power(&totals.escaped);
    let absorbed_water = power(&totals.absorbed_water);
    let absorbed_surfaces = power(&totals.absorbed_surfaces);
    let lost_edges = power(&totals.lost_edges);
    let on_land = if totals.on_land.is_empty() {
        vec![0.0; nb]
    } else {
        power(&totals.on_land)
    };
    let (inelastic_out, inelastic_lost, inelastic_in) = (
        power(&totals.inelastic_out),
        power(&totals.inelastic_lost),
        power(&totals.inelastic_in),
    );
    let (water_leaving, water_leaving_inelastic) = (
        power(&totals.left_water),
        power(&totals.left_water_inelastic),
    );
    let mut residual = Vec::with_capacity(nb);
    let mut sigma = Vec::with_capacity(nb);
    for b in 0..nb {
        let sinks = escaped[b]
            + absorbed_water[b]
            + absorbed_surfaces[b]
            + lost_edges[b]
            + on_land[b]
            + inelastic_out[b]
            + inelastic_lost[b];
        let res = emitted[b] + inelastic_in[b] - sinks;
        // The band's photon count is binomial: sd = P_b sqrt(N p (1 - p)).
        let p = emitted[b] / (photon_power[b] * n).max(f64::MIN_POSITIVE);
        let sd = photon_power[b] * (n * p * (1.0 - p)).max(0.0).sqrt();
        residual.push(res);
        sigma.push(in_sigmas(res, sd));
    }
    let closure_sigma = largest(&sigma);
    Energy {
        units: "W nm^-1".into(),
        emitted,
        escaped,
        absorbed_water,
        absorbed_surfaces,
        lost_edges,
        on_land,
        inelastic_out,
        inelastic_lost,
        inelastic_in,
        water_leaving,
        water_leaving_inelastic,
        residual,
        closure_sigma_per_band: sigma,
        closure_sigma,
    }
}

/// A budget's residual `res` in standard errors `sd` (infinite when the
/// budget should close exactly and does not).
fn in_sigmas(res: f64, sd: f64) -> f64 {
    if sd > 0.0 {
        res / sd
    } else if res == 0.0 {
        0.0
    } else {
        f64::INFINITY
    }
}

/// The largest |x| of `xs` (0 for none).
fn largest(xs: &[f64]) -> f64 {
    xs.iter().fold(0.0f64, |m, s| m.max(s.abs()))
}

fn one() -> f64 {
    1.0
}

/// Cells per side of the grid [`water_fraction`] samples the floor on.
const WATER_GRID: usize = 256;

/// The share of `scene`'s domain where the floor lies below `depth_m`
/// (1 without a floor), from the floor's depth at the centres of a
/// 256 x 256 grid of cells (an error of at most one cell row, 0.4 %, along
/// each contour). Targets are not counted out.
pub fn water_fraction(scene: &Scene, depth_m: f64) -> f64 {
    let [sx, sy] = scene.domain.size_m;
    let n = WATER_GRID;
    let mut wet = 0usize;
    for j in 0..n {
        let y = (j as f64 + 0.5) / n as f64 * sy;
        for i in 0..n {
            let x = (i as f64 + 0.5) / n as f64 * sx;
            match scene.geometry.floor_depth_at(x as f32, y as f32) {
                Some(floor) if f64::from(floor) <= depth_m => {}
                _ => wet += 1,
            }
        }
    }
    wet as f64 / (n * n) as f64
}
