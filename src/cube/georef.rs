//! Map geometry of a rendered cube for its ENVI header: `map info`, the
//! CRS as `coordinate system string`, and the sun's angles.
//!
//! Conventions: the scene's frame has x east and y north (m); image row 0
//! is its high-y (north) edge and column 0 its low-x (west) edge
//! (`render::camera::ray`), so a north-up map grid. ENVI's reference pixel
//! (1, 1) is the upper-left corner of the upper-left pixel. With `[georef]
//! epsg` a WGS 84 / UTM zone, the map info names the zone and hemisphere
//! and the coordinate system string is the zone's ESRI WKT, so GDAL reads
//! a geotransform and a CRS; without one the map info is `Arbitrary`
//! (a local metric frame: a geotransform, no CRS). Only an orthographic
//! sensor is on a map grid; a pinhole camera's cube gets the sun's angles
//! only.

use crate::scene::{Scene, SensorKind};

/// The cube's affine map transform in GDAL's order (x of the upper-left
/// corner, pixel width, 0, y of the upper-left corner, 0, -pixel height),
/// in the map's coordinates; None for a pinhole camera.
pub fn geotransform(scene: &Scene) -> Option<[f64; 6]> {
    let SensorKind::Orthographic { gsd_m, center_m } = &scene.sensor.kind else {
        return None;
    };
    let [w, h] = scene.sensor.pixels;
    let o = scene.georef.origin_m;
    let x_ul = o[0] + center_m[0] - w as f64 * gsd_m / 2.0;
    let y_ul = o[1] + center_m[1] + h as f64 * gsd_m / 2.0;
    Some([x_ul, *gsd_m, 0.0, y_ul, 0.0, -gsd_m])
}

/// Extra ENVI header lines for a cube of `scene`.
pub fn envi_header_lines(scene: &Scene) -> Vec<String> {
    let mut lines = Vec::new();
    if let Some([x_ul, gsd_m, _, y_ul, _, _]) = geotransform(scene) {
        let g = &scene.georef;
        match g.utm_zone() {
            Some((zone, north)) => {
                let hemi = if north { "North" } else { "South" };
                lines.push(format!(
                    "map info = {{UTM, 1, 1, {x_ul}, {y_ul}, {gsd_m}, {gsd_m}, {zone}, {hemi}, WGS-84, units=Meters}}"
                ));
                lines.push(format!(
                    "coordinate system string = {{{}}}",
                    utm_wkt(zone, north)
                ));
            }
            None => lines.push(format!(
                "map info = {{Arbitrary, 1, 1, {x_ul}, {y_ul}, {gsd_m}, {gsd_m}, units=Meters}}"
            )),
        }
        lines.push(format!("pixel size = {{{gsd_m}, {gsd_m}, units=Meters}}"));
    }
    lines.push(format!(
        "sun elevation = {}",
        90.0 - scene.sun.zenith_rad.to_degrees()
    ));
    // ENVI's sun azimuth is a compass bearing (clockwise from north).
    lines.push(format!("sun azimuth = {}", scene.sun.compass_azimuth_deg()));
    lines
}

/// The ESRI WKT of WGS 84 / UTM `zone` (north or south).
pub fn utm_wkt(zone: u32, north: bool) -> String {
    let meridian = -183.0 + 6.0 * zone as f64;
    let (hemi, false_northing) = if north {
        ("N", 0.0)
    } else {
        ("S", 10_000_000.0)
    };
    format!(
        "PROJCS[\"WGS_1984_UTM_Zone_{zone}{hemi}\",GEOGCS[\"GCS_WGS_1984\",DATUM[\"D_WGS_1984\",\
         SPHEROID[\"WGS_1984\",6378137.0,298.257223563]],PRIMEM[\"Greenwich\",0.0],\
         UNIT[\"Degree\",0.0174532925199433]],PROJECTION[\"Transverse_Mercator\"],\
         PARAMETER[\"False_Easting\",500000.0],PARAMETER[\"False_Northing\",{false_northing:.1}],\
         PARAMETER[\"Central_Meridian\",{meridian:.1}],PARAMETER[\"Scale_Factor\",0.9996],\
         PARAMETER[\"Latitude_Of_Origin\",0.0],UNIT[\"Meter\",1.0]]"
    )
}
