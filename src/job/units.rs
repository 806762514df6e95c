//! The units of every number a report holds, written into the report
//! itself (`units`), keyed by the field's path: `.` between names, `[]`
//! for an element of a list of records (`tally[].Ed`). A list of numbers
//! (one per band) has its numbers' unit. The emission report's energy
//! block also carries its own `units`, as before.
//!
//! Tested against real reports: every numeric field of a photon-map render,
//! a path-integrator render and an emission has an entry here.

use std::collections::BTreeMap;

const SPECTRAL_IRRADIANCE: &str = "W m^-2 nm^-1";
const SPECTRAL_RADIANCE: &str = "W m^-2 sr^-1 nm^-1";

/// Field path and unit, for every numeric field of `RunReport` and
/// `EmitReport`.
const UNITS: &[(&str, &str)] = &[
    ("bands_nm", "nm"),
    ("fwhm_nm", "nm"),
    ("Ed_above_surface", SPECTRAL_IRRADIANCE),
    ("above_surface.Ed", SPECTRAL_IRRADIANCE),
    ("above_surface.Ed_stderr", SPECTRAL_IRRADIANCE),
    ("above_surface.Eu", SPECTRAL_IRRADIANCE),
    ("above_surface.Eu_stderr", SPECTRAL_IRRADIANCE),
    ("tally[].depth_m", "m"),
    (
        "tally[].water_fraction",
        "1 (share of the domain that is water at the depth)",
    ),
    ("tally[].Ed", SPECTRAL_IRRADIANCE),
    ("tally[].Ed_stderr", SPECTRAL_IRRADIANCE),
    ("tally[].Eu", SPECTRAL_IRRADIANCE),
    ("tally[].Eu_stderr", SPECTRAL_IRRADIANCE),
    ("tally[].Eod", "W m^-2 nm^-1 (scalar irradiance)"),
    ("tally[].Eod_stderr", "W m^-2 nm^-1 (scalar irradiance)"),
    ("tally[].Eou", "W m^-2 nm^-1 (scalar irradiance)"),
    ("tally[].Eou_stderr", "W m^-2 nm^-1 (scalar irradiance)"),
    ("tally[].Lu", SPECTRAL_RADIANCE),
    ("tally[].Lu_stderr", SPECTRAL_RADIANCE),
    ("tally[].Ld", SPECTRAL_RADIANCE),
    ("tally[].Ld_stderr", SPECTRAL_RADIANCE),
    ("tally[].R", "1 (Eu / Ed)"),
    ("kd[].from_m", "m"),
    ("kd[].to_m", "m"),
    ("kd[].Kd", "m^-1"),
    ("energy.emitted", "W nm^-1"),
    ("energy.escaped", "W nm^-1"),
    ("energy.absorbed_water", "W nm^-1"),
    ("energy.absorbed_surfaces", "W nm^-1"),
    ("energy.lost_edges", "W nm^-1"),
    ("energy.inelastic_out", "W nm^-1"),
    ("energy.inelastic_lost", "W nm^-1"),
    ("energy.inelastic_in", "W nm^-1"),
    ("energy.water_leaving", "W nm^-1"),
    ("energy.water_leaving_inelastic", "W nm^-1"),
    ("energy.residual", "W nm^-1"),
    ("energy.closure_sigma", "standard errors"),
    ("energy.closure_sigma_per_band", "standard errors"),
    ("photons.traced", "photons"),
    ("photons.stored_volume", "photons"),
    ("photons.stored_surface", "photons"),
    ("photons.truncated", "photons"),
    ("photon_power", "W nm^-1 per photon"),
    ("map.photons", "photons"),
    ("map.tiles", "tiles"),
    ("map.file_bytes", "bytes"),
    ("map.bytes_per_photon", "bytes per photon"),
    ("map.spilled_bytes", "bytes"),
    ("map.spilled_frames", "frames"),
    ("map.split_cells", "cells"),
    ("radiometers[].depth_m", "m"),
    ("radiometers[].position_m", "m"),
    ("radiometers[].L", SPECTRAL_RADIANCE),
    ("radiometers[].stderr", SPECTRAL_RADIANCE),
    ("radiometers[].band_mean_stderr", SPECTRAL_RADIANCE),
    ("radiometers[].vov", "1"),
    ("radiometers[].largest_share", "1"),
    ("estimate.k", "photons"),
    ("estimate.k_expanded", "photons"),
    ("estimate.radius_m", "m"),
    ("estimate.max_radius_m", "m"),
    ("estimate.step_m", "m"),
    ("estimate.gather_rays", "rays"),
    ("estimate.boundary_grid_m", "m"),
    ("estimate.forward_peak_deg", "deg"),
    ("estimate.forward_peak_down_deg", "deg"),
    ("estimate.forward_peak_target_deg", "deg"),
    (
        "estimate.shape_photons_per_band",
        "photons per band and voxel",
    ),
    ("sensor.pixels", "pixels"),
    ("sensor.samples_per_pixel", "samples"),
    ("sensor.bands", "bands"),
    ("sensor.georef.origin_m", "m"),
    ("sensor.georef.epsg", "EPSG code"),
    (
        "sensor.geotransform",
        "m (GDAL order: x0, dx, 0, y0, 0, dy)",
    ),
    ("sensor.sun_zenith_deg", "deg"),
    ("sensor.sun_azimuth_deg", "deg"),
    ("cache.hits", "lookups"),
    ("cache.misses", "lookups"),
    ("cache.evictions", "tiles"),
    ("cache.decodes", "tiles"),
    ("cache.decoded_bytes", "bytes"),
    ("cache.resident_bytes", "bytes"),
    ("cache.peak_resident_bytes", "bytes"),
    ("memory.budget_bytes", "bytes"),
    ("memory.reserve_bytes", "bytes"),
    ("memory.boundary_grid_bytes", "bytes"),
    ("memory.band_shape_grid_bytes", "bytes"),
    ("memory.tile_cache_bytes", "bytes"),
    ("mem_budget_bytes", "bytes"),
    ("peak_memory.anon_bytes", "bytes"),
    ("peak_memory.file_bytes", "bytes"),
    ("peak_memory.rss_bytes", "bytes"),
    ("peak_rss_bytes", "bytes"),
    ("timings_s.scene", "s"),
    ("timings_s.emit", "s"),
    ("timings_s.render", "s"),
    ("timings_s.emit_and_store", "s"),
    ("timings_s.total", "s"),
];

/// The units table a report carries.
pub fn report_units() -> BTreeMap<String, String> {
    UNITS
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}
