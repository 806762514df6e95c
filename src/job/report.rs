//! The typed run reports: what `littoral emit` and `littoral render` write
//! as JSON. Every field is a named, typed value; the JSON keys are the
//! field names (the emission report's keys at the top level).

use super::budget::RenderShares;
use crate::emit::report::EmissionReport;
use crate::mem::MemoryPeaks;
use crate::render::RadiometerReading;
use crate::scene::{EstimateSettings, IntegratorMode};
use crate::store::cache::CacheStats;
use crate::store::{MapFile, WriteSummary};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The photon map a run wrote or reused.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MapSummary {
    /// Where the map is kept (absent for a render's scratch map).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path: Option<String>,
    pub photons: u64,
    pub tiles: u32,
    pub file_bytes: u64,
    pub bytes_per_photon: f64,
    /// Compressed bytes the sort spilled to scratch space (0 for a reused map).
    pub spilled_bytes: u64,
    /// Frames those bytes were written as (photons per frame set how well
    /// they compress; 0 for a reused map).
    #[serde(default)]
    pub spilled_frames: u64,
    /// Cells split at the end because they held more photons than a tile
    /// may (each is read back twice before its tiles are encoded; 0 for a
    /// reused map).
    #[serde(default)]
    pub split_cells: u32,
    /// SHA-256 of the emission inputs (see `provenance`).
    pub provenance: String,
}

impl MapSummary {
    /// The summary of a map just written.
    pub fn written(summary: &WriteSummary, provenance: String, path: Option<&Path>) -> Self {
        MapSummary {
            path: path.map(|p| p.display().to_string()),
            photons: summary.photons,
            tiles: summary.tiles,
            file_bytes: summary.file_bytes,
            bytes_per_photon: summary.file_bytes as f64 / summary.photons.max(1) as f64,
            spilled_bytes: summary.spilled_bytes,
            spilled_frames: summary.spilled_frames,
            split_cells: summary.splits,
            provenance,
        }
    }

    /// The summary of an existing map.
    pub fn existing(map: &MapFile, path: Option<&Path>) -> Self {
        let h = map.header();
        MapSummary {
            path: path.map(|p| p.display().to_string()),
            photons: h.photons,
            tiles: h.tiles,
            file_bytes: map.file_bytes(),
            bytes_per_photon: map.file_bytes() as f64 / h.photons.max(1) as f64,
            spilled_bytes: 0,
            spilled_frames: 0,
            split_cells: 0,
            provenance: h.provenance.digest_hex(),
        }
    }
}

/// Seconds spent in each stage of `emit`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct EmitTimings {
    pub scene: f64,
    pub emit_and_store: f64,
    pub total: f64,
}

/// The report of `littoral emit`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EmitReport {
    #[serde(flatten)]
    pub emission: EmissionReport,
    pub map: MapSummary,
    /// The atmosphere's part, with `[atmosphere]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub atmosphere: Option<AtmosphereReport>,
    pub timings_s: EmitTimings,
    /// Peak anonymous memory (what `--mem-budget` bounds) and peak mapped
    /// file pages, apart.
    pub peak_memory: MemoryPeaks,
    /// The budget the run was given (bytes).
    pub mem_budget_bytes: u64,
    /// Peak resident memory of the process (VmHWM, bytes): anonymous memory
    /// plus resident file pages.
    pub peak_rss_bytes: u64,
    /// The unit of every number above, by field path (`job::units`).
    #[serde(default)]
    pub units: std::collections::BTreeMap<String, String>,
    /// What the run found to warn about (left out of the JSON when none).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

impl EmitReport {
    /// The report as the JSON `littoral emit` writes.
    pub fn json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a report serialises") + "\n"
    }
}

/// A warning for every radiometer whose samples are dominated by a few
/// (VOV above [`VOV_LIMIT`](crate::render::VOV_LIMIT) in some band): its
/// standard error understates the error.
pub fn radiometer_warnings(readings: &[RadiometerReading]) -> Vec<String> {
    readings
        .iter()
        .enumerate()
        .filter_map(|(i, r)| {
            let bad: Vec<usize> = (0..r.vov.len())
                .filter(|&b| r.vov[b] > crate::render::VOV_LIMIT)
                .collect();
            let worst = *bad
                .iter()
                .max_by(|&&a, &&b| r.vov[a].total_cmp(&r.vov[b]))?;
            Some(format!(
                "radiometer {i} ({} at {} m, [{}, {}] m): a few samples dominate its reading in \
                 {} of {} bands, so its standard error is itself uncertain by about {:.0} % \
                 (band {worst}: relative variance of the variance {:.2}, trusted below {}; \
                 the largest sample is {:.1} % of the sum); take more samples",
                r.view,
                r.depth_m,
                r.position_m[0],
                r.position_m[1],
                bad.len(),
                r.vov.len(),
                // The relative error of a standard error is half that of its variance.
                50.0 * r.vov[worst].sqrt(),
                r.vov[worst],
                crate::render::VOV_LIMIT,
                100.0 * r.largest_share.get(worst).copied().unwrap_or(0.0),
            ))
        })
        .collect()
}

/// The sensor a render imaged with.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SensorSummary {
    pub pixels: [usize; 2],
    pub samples_per_pixel: u32,
    /// Bands of the cube.
    pub bands: usize,
    /// `[georef]`: map coordinates of the scene's origin and the CRS.
    #[serde(default)]
    pub georef: crate::scene::Georef,
    /// The cube's map transform in GDAL's order (upper-left x, pixel width,
    /// 0, upper-left y, 0, -pixel height; row 0 is the north edge); None
    /// for a pinhole camera.
    #[serde(default)]
    pub geotransform: Option<[f64; 6]>,
    /// Sun zenith and azimuth (degrees; the azimuth is the compass bearing
    /// toward the sun, clockwise from north: `Sun::compass_azimuth_deg`,
    /// not the scene's `[sun] azimuth_deg`).
    #[serde(default)]
    pub sun_zenith_deg: f64,
    #[serde(default)]
    pub sun_azimuth_deg: f64,
}

/// The files a render wrote.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Outputs {
    pub hdr: String,
    pub bsq: String,
    pub png: String,
    pub exr: String,
    pub json: String,
    /// The page for people: plots, figures and settings (`job::html`).
    #[serde(default)]
    pub html: String,
    /// The standard-error cube (path integrator with two or more samples
    /// per pixel).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stderr_hdr: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stderr_bsq: Option<String>,
    /// Depth profiles of Ed, Eu, Eod, Eou, Lu, Ld per band with standard
    /// errors (`NAME.profiles.csv`) and Kd per layer and band
    /// (`NAME.kd.csv`), from the emission's tallies (photon map only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub profiles_csv: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kd_csv: Option<String>,
    /// The atmosphere per band (`NAME.atmosphere.csv`,
    /// [`AtmosphereReport::csv`]), with `[atmosphere]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub atmosphere_csv: Option<String>,
    /// The product cubes (`render::products`: water-leaving radiance,
    /// surface-reflected radiance, remote-sensing reflectance; with the
    /// sensor above the surface the reflectance at the sensor and the path
    /// radiance), by suffix.
    #[serde(default)]
    pub products: Vec<ProductFiles>,
    /// With `[sensor] response`: the radiance (`product` "radiance") and
    /// each product in that sensor's bands, `NAME[.product].SENSOR.hdr`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sensor_cubes: Vec<ProductFiles>,
}

/// One product cube's files.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ProductFiles {
    /// `lw`, `surface` or `rrs` (or `radiance` among `sensor_cubes`).
    pub product: String,
    pub units: String,
    pub hdr: String,
    pub bsq: String,
}

/// Seconds spent in each stage of `render`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RenderTimings {
    pub scene: f64,
    /// Emission, or opening a reused map.
    pub emit: f64,
    pub render: f64,
    pub total: f64,
}

/// The scene's name and band grid, as the emission report gives them.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunBands {
    pub scene: String,
    pub bands_nm: Vec<f32>,
    pub fwhm_nm: Vec<f32>,
}

/// The atmosphere and the light it brought to the surface, per band
/// (`[atmosphere]`; over a black surface: light the sea sends back up and
/// the air returns is not in it).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[allow(non_snake_case)]
pub struct AtmosphereReport {
    pub profile: String,
    pub surface_pressure_hpa: f64,
    pub ozone_du: f64,
    pub day_of_year: Option<f64>,
    pub sun_zenith_deg: f64,
    /// Photons per band traced for the sky.
    pub sky_photons: u64,
    pub tau_rayleigh: Vec<f64>,
    pub tau_aerosol: Vec<f64>,
    pub aerosol_ssa: Vec<f64>,
    pub tau_ozone: Vec<f64>,
    pub tau_gas: Vec<f64>,
    /// The sun's beam-normal irradiance at the top (with the Earth–Sun
    /// distance).
    pub toa_irradiance: Vec<f64>,
    /// E_d(0+): the sun's beam and the sky, on a horizontal plane.
    pub Ed_direct: Vec<f64>,
    pub Ed_diffuse: Vec<f64>,
    /// The sky's irradiance counted by the photons reaching the surface,
    /// an independent estimate of `Ed_diffuse`, and its standard error.
    pub Ed_diffuse_flux: Vec<f64>,
    pub Ed_diffuse_flux_stderr: Vec<f64>,
    /// Direct transmittance exp(-tau / mu0) and the total downward one,
    /// E_d(0+) / (E_0 mu0).
    pub t_direct: Vec<f64>,
    pub t_down: Vec<f64>,
    /// Irradiance leaving the top and absorbed in the air.
    pub up_at_top: Vec<f64>,
    pub absorbed: Vec<f64>,
    /// Over a Lambertian ground or surroundings, and over the sea with
    /// `sea_coupling`: the air's spherical albedo for the light the
    /// surface sends up and its standard error (the irradiances above then
    /// hold every order of reflection between the surface and the air).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub spherical_albedo: Vec<f64>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub spherical_albedo_stderr: Vec<f64>,
    /// Over the sea with `sea_coupling`: the sea's albedo, the share of
    /// E_d(0+) over a black surface that it sends up.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub surface_albedo: Vec<f64>,
    /// With the sensor above the surface: its height, the direct
    /// transmittance from the ground to it along its view, and the path
    /// radiance it sees (light scattered into the view that never reached
    /// the surface) with its standard error.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub altitude_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub t_view: Vec<f64>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub L_path: Vec<f64>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub L_path_stderr: Vec<f64>,
    /// The total transmittance from a Lambertian ground to the sensor
    /// along its view (direct and scattered) and its standard error.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub t_up: Vec<f64>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub t_up_stderr: Vec<f64>,
}

impl AtmosphereReport {
    /// The report as a table, one row per band at `bands_nm`: optical
    /// depths, the sun at the top, E_d(0+) and the transmittances, and with
    /// the sensor above the surface its direct and total transmittance,
    /// the path radiance and the path reflectance pi L_path / (E_0 mu_0),
    /// each with its standard error where it has one.
    pub fn csv(&self, bands_nm: &[f32]) -> String {
        let view = self.altitude_m.is_some();
        let mut t = String::from(
            "wavelength_nm,tau_rayleigh,tau_aerosol,aerosol_ssa,tau_ozone,tau_gas,E0,\
             Ed_direct,Ed_diffuse,Ed_diffuse_flux,Ed_diffuse_flux_stderr,t_direct,t_down,\
             up_at_top,absorbed",
        );
        let ground = !self.spherical_albedo.is_empty();
        if ground {
            t.push_str(",spherical_albedo,spherical_albedo_stderr");
        }
        let sea = !self.surface_albedo.is_empty();
        if sea {
            t.push_str(",surface_albedo");
        }
        if view {
            t.push_str(",t_view,t_up,t_up_stderr,L_path,L_path_stderr,rho_path,rho_path_stderr");
        }
        t.push('\n');
        let mu0 = self.sun_zenith_deg.to_radians().cos();
        for (b, nm) in bands_nm.iter().enumerate() {
            let mut row = vec![
                f64::from(*nm),
                self.tau_rayleigh[b],
                self.tau_aerosol[b],
                self.aerosol_ssa[b],
                self.tau_ozone[b],
                self.tau_gas[b],
                self.toa_irradiance[b],
                self.Ed_direct[b],
                self.Ed_diffuse[b],
                self.Ed_diffuse_flux[b],
                self.Ed_diffuse_flux_stderr[b],
                self.t_direct[b],
                self.t_down[b],
                self.up_at_top[b],
                self.absorbed[b],
            ];
            if ground {
                row.extend([self.spherical_albedo[b], self.spherical_albedo_stderr[b]]);
            }
            if sea {
                row.push(self.surface_albedo[b]);
            }
            if view {
                let to_rho = crate::render::reflectance_factor(self.toa_irradiance[b], mu0);
                row.extend([
                    self.t_view[b],
                    self.t_up[b],
                    self.t_up_stderr[b],
                    self.L_path[b],
                    self.L_path_stderr[b],
                    self.L_path[b] * to_rho,
                    self.L_path_stderr[b] * to_rho,
                ]);
            }
            let cells: Vec<String> = row.iter().map(|v| v.to_string()).collect();
            t.push_str(&cells.join(","));
            t.push('\n');
        }
        t
    }

    /// The report of `scene`'s atmosphere, none without one.
    pub fn of(scene: &crate::scene::Scene) -> Option<AtmosphereReport> {
        let a = scene.atmosphere.as_ref()?;
        let col = |f: &dyn Fn(&crate::scene::BandAtmosphere) -> f64| -> Vec<f64> {
            a.bands.iter().map(f).collect()
        };
        let mu0 = scene.sun.zenith_rad.cos();
        // The sky exchanges light with a Lambertian ground or surroundings,
        // or with the sea (`render::sea_air`).
        let land = scene.ground.is_some()
            || scene
                .surroundings
                .as_ref()
                .is_some_and(|s| s.reflectance().is_some());
        let sea = !land && a.sea_coupling;
        let coupled = land || sea;
        Some(AtmosphereReport {
            profile: a.spec.profile.name.to_string(),
            surface_pressure_hpa: a.spec.surface_pressure_hpa,
            ozone_du: a.spec.ozone_du,
            day_of_year: a.day_of_year,
            sun_zenith_deg: scene.sun.zenith_rad.to_degrees(),
            sky_photons: a.sky_photons,
            tau_rayleigh: col(&|b| b.tau.rayleigh),
            tau_aerosol: col(&|b| b.tau.aerosol_scattering + b.tau.aerosol_absorption),
            aerosol_ssa: col(&|b| {
                let t = b.tau.aerosol_scattering + b.tau.aerosol_absorption;
                if t > 0.0 {
                    b.tau.aerosol_scattering / t
                } else {
                    1.0
                }
            }),
            tau_ozone: col(&|b| b.tau.ozone),
            tau_gas: col(&|b| b.tau.gas),
            toa_irradiance: col(&|b| b.toa_irradiance),
            Ed_direct: col(&|b| b.direct),
            Ed_diffuse: col(&|b| b.diffuse),
            Ed_diffuse_flux: col(&|b| b.diffuse_flux),
            Ed_diffuse_flux_stderr: col(&|b| b.diffuse_flux_se),
            t_direct: col(&|b| b.direct_transmittance),
            t_down: col(&|b| b.t_down(mu0)),
            up_at_top: col(&|b| b.up_at_top),
            absorbed: col(&|b| b.absorbed),
            spherical_albedo: if coupled {
                col(&|b| b.spherical_albedo)
            } else {
                Vec::new()
            },
            spherical_albedo_stderr: if coupled {
                col(&|b| b.spherical_albedo_se)
            } else {
                Vec::new()
            },
            surface_albedo: if sea {
                col(&|b| b.surface_albedo)
            } else {
                Vec::new()
            },
            altitude_m: a.view.as_ref().map(|v| v.altitude_m),
            t_view: a
                .view
                .as_ref()
                .map_or(Vec::new(), |v| v.transmittance.clone()),
            L_path: a
                .view
                .as_ref()
                .map_or(Vec::new(), |v| v.path_radiance.clone()),
            L_path_stderr: a
                .view
                .as_ref()
                .map_or(Vec::new(), |v| v.path_radiance_se.clone()),
            t_up: a
                .view
                .as_ref()
                .map_or(Vec::new(), |v| v.transmittance_up.clone()),
            t_up_stderr: a
                .view
                .as_ref()
                .map_or(Vec::new(), |v| v.transmittance_up_se.clone()),
        })
    }
}

/// The report of `littoral render`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[allow(non_snake_case)]
pub struct RunReport {
    /// The integrator that rendered.
    pub integrator: IntegratorMode,
    /// The emission report of the photon map (none for the path integrator).
    #[serde(flatten)]
    pub emission: Option<EmissionReport>,
    /// The scene's name and bands for a report without an emission report
    /// (the path integrator's), written where the emission report writes
    /// them (`scene`, `bands_nm`, `fwhm_nm`) so that every report's JSON
    /// has them. Written only: a typed read leaves it `None` (the emission
    /// report, or the cube's header, carries the same).
    #[serde(flatten, skip_deserializing, skip_serializing_if = "Option::is_none")]
    pub bands: Option<RunBands>,
    /// The photon map (none for the path integrator).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub map: Option<MapSummary>,
    /// True when the map was reused (its provenance matched the scene's).
    pub reused_map: bool,
    pub radiometers: Vec<RadiometerReading>,
    /// Downwelling plane irradiance just above the surface per band (W
    /// m^-2 nm^-1), exactly: the sun's horizontal irradiance plus the
    /// sky's, which the R_rs cube divides by (R_rs = L_w / Ed_above_surface)
    /// and every ratio in the report and the HTML page uses. The emission's
    /// Monte Carlo tally of the same irradiance, with its standard error,
    /// is `above_surface.Ed` (photon map only).
    #[serde(deserialize_with = "crate::nan_json::f64s")]
    pub Ed_above_surface: Vec<f64>,
    /// The atmosphere's part, with `[atmosphere]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub atmosphere: Option<AtmosphereReport>,
    pub estimate: EstimateSettings,
    pub sensor: SensorSummary,
    pub cache: CacheStats,
    pub memory: RenderShares,
    pub outputs: Outputs,
    pub timings_s: RenderTimings,
    /// Peak anonymous memory (what `--mem-budget` bounds) and peak mapped
    /// file pages (the photon map's resident pages), apart.
    pub peak_memory: MemoryPeaks,
    /// Peak resident memory of the process (VmHWM, bytes): anonymous memory
    /// plus resident pages of the mapped photon map.
    pub peak_rss_bytes: u64,
    /// What the user should know about the results: readings whose error
    /// bar cannot be trusted. `render` also prints each on stderr.
    #[serde(default)]
    pub warnings: Vec<String>,
    /// The unit of every number above, by field path (`job::units`).
    #[serde(default)]
    pub units: std::collections::BTreeMap<String, String>,
}

fn mib(bytes: u64) -> f64 {
    bytes as f64 / (1u64 << 20) as f64
}

/// "peak memory A MiB anonymous of a B MiB budget, C MiB mapped file pages".
fn memory_line(peaks: &MemoryPeaks, budget: u64) -> String {
    format!(
        "peak memory {:.1} MiB anonymous of a {:.1} MiB budget, {:.1} MiB mapped file pages",
        mib(peaks.anon_bytes),
        mib(budget),
        mib(peaks.file_bytes)
    )
}

impl EmitReport {
    /// The one-line summary `littoral emit` prints.
    pub fn summary(&self) -> String {
        format!(
            "emitted {} photons: {} volume + {} surface photons stored in {} ({} tiles, {:.2} bytes/photon); energy closure {:.2} sigma; {:.1} s, {}",
            self.emission.photons.traced,
            self.emission.photons.stored_volume,
            self.emission.photons.stored_surface,
            self.map.path.as_deref().unwrap_or("a scratch map"),
            self.map.tiles,
            self.map.bytes_per_photon,
            self.emission.energy.closure_sigma,
            self.timings_s.total,
            memory_line(&self.peak_memory, self.mem_budget_bytes)
        )
    }
}

impl RunReport {
    /// The one-line summary `littoral render` prints.
    pub fn summary(&self) -> String {
        let dir = Path::new(&self.outputs.json)
            .parent()
            .map_or_else(String::new, |d| d.display().to_string());
        let name = Path::new(&self.outputs.json)
            .file_stem()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        let stages = match self.integrator {
            IntegratorMode::PhotonMap => format!(
                "{} {:.1} s, render {:.1} s",
                if self.reused_map {
                    "reused map"
                } else {
                    "emit"
                },
                self.timings_s.emit,
                self.timings_s.render
            ),
            IntegratorMode::Path => format!(
                "path integrator, {} paths per pixel",
                self.sensor.samples_per_pixel
            ),
        };
        format!(
            "rendered {} ({}x{} px, {} bands) into {} in {:.1} s ({}); {}",
            name,
            self.sensor.pixels[0],
            self.sensor.pixels[1],
            self.sensor.bands,
            dir,
            self.timings_s.total,
            stages,
            memory_line(&self.peak_memory, self.memory.budget_bytes)
        )
    }
}
