//! What looks at the scene: the orthographic image, the pinhole camera's
//! view and the radiometers lie in the water of the domain, or the scene
//! is refused naming the key.

use crate::common::*;
use crate::scenes::{accepted, floored, refused_at};

/// An orthographic image must lie inside the domain, with open and with
/// periodic edges (camera rays are not wrapped).
#[test]
fn the_image_lies_inside_the_domain() {
    let s = |sensor: &str| format!("{MINIMAL_SCENE}[sensor]\n{sensor}\n");
    refused_at(
        &s("pixels = [32, 32]\ngsd_m = 1.0"),
        "gsd_m",
        "sensor.gsd_m",
        &["32 x 32 pixels of 1 m", "outside the domain"],
    );
    refused_at(
        &s("pixels = [4, 4]\ngsd_m = 1.0\ncenter_m = [1.0, 5.0]"),
        "center_m",
        "sensor.center_m",
        &["x -1 to 3"],
    );
    let open = s("pixels = [4, 4]\ngsd_m = 1.0\ncenter_m = [9.0, 5.0]").replace(
        "size_m = [10.0, 10.0]",
        "size_m = [10.0, 10.0]\nedges = \"open\"",
    );
    refused_at(
        &open,
        "center_m",
        "sensor.center_m",
        &["outside the domain"],
    );
    // Filling the domain exactly; the default GSD fits whatever the pixels.
    accepted(&s("pixels = [40, 20]\ngsd_m = 0.25"));
    accepted(&s("pixels = [4, 4]\ngsd_m = 1.0\ncenter_m = [2.0, 8.0]"));
    accepted(&s("pixels = [640, 3]"));
}

/// A pinhole camera's image must meet the water inside the domain: its
/// centre (else `look_at_m` is at fault) and its corners (else `fov_deg`).
#[test]
fn the_pinhole_view_lies_inside_the_domain() {
    let s = |sensor: &str| {
        format!("{MINIMAL_SCENE}[sensor]\nkind = \"pinhole\"\npixels = [8, 8]\n{sensor}\n")
    };
    let above = "position_m = [5.0, 5.0, 10.0]";
    accepted(&s(&format!(
        "{above}\nlook_at_m = [5.0, 5.0, 0.0]\nfov_deg = 30.0"
    )));
    refused_at(
        &s(&format!("{above}\nlook_at_m = [900.0, 5.0, 0.0]")),
        "look_at_m",
        "sensor.look_at_m",
        &["centre meets the water at x", "outside the domain"],
    );
    // 10 m up, a 60-degree view spans 11.5 m: wider than the 10 m domain.
    refused_at(
        &s(&format!(
            "{above}\nlook_at_m = [5.0, 5.0, 0.0]\nfov_deg = 60.0"
        )),
        "fov_deg",
        "sensor.fov_deg",
        &["corner", "outside the domain"],
    );
    refused_at(
        &s("position_m = [5.0, 1.0, 1.0]\nlook_at_m = [5.0, 9.0, 0.0]\nfov_deg = 120.0"),
        "fov_deg",
        "sensor.fov_deg",
        &["above the horizon"],
    );
}

/// A radiometer outside the domain or below the floor at its position is
/// refused.
#[test]
fn radiometers_lie_in_the_water_of_the_domain() {
    let r = |depth: f64, pos: &str| {
        floored(&format!(
            "[[radiometer]]\ndepth_m = {depth:?}\nposition_m = {pos}\n"
        ))
    };
    for pos in ["[5200.0, 5.0]", "[-100.0, 5.0]", "[5.0, 10.5]"] {
        refused_at(
            &r(1.0, pos),
            "position_m",
            "radiometer[0].position_m",
            &["outside the domain"],
        );
    }
    refused_at(
        &r(3.5, "[5.0, 5.0]"),
        "depth_m = 3.5",
        "radiometer[0].depth_m",
        &["below the floor", "3.000 m deep"],
    );
    // Under a slope the floor at the radiometer counts.
    let slope = format!("{MINIMAL_SCENE}[bottom]\nslope = {{ from_depth_m = 1.0, to_depth_m = 9.0 }}\n[[radiometer]]\ndepth_m = 4.0\nposition_m = [1.0, 5.0]\n");
    refused_at(
        &slope,
        "depth_m = 4.0",
        "radiometer[0].depth_m",
        &["below the floor"],
    );
    accepted(&slope.replace("[1.0, 5.0]", "[8.0, 5.0]"));
    accepted(&r(2.9, "[0.0, 10.0]"));
    accepted(&r(-2.0, "[5.0, 5.0]"));
    // A field of view is a half-angle from 0 up to (not including) 90.
    let fov = |h: &str| format!("{}half_angle_deg = {h}\n", r(1.0, "[5.0, 5.0]"));
    for h in ["-1.0", "90.0", "nan"] {
        refused_at(
            &fov(h),
            "half_angle_deg",
            "radiometer[0].half_angle_deg",
            &["below 90 degrees"],
        );
    }
    accepted(&fov("10.0"));
}
