use super::*;

#[test]
fn orthographic_pixels_tile_the_footprint() {
    let s = Sensor {
        kind: SensorKind::Orthographic {
            gsd_m: 0.5,
            center_m: [50.0, 50.0],
        },
        pixels: [100, 80],
        samples_per_pixel: 1,
        response: None,
        toward: Vec3::Z,
        altitude_m: None,
    };
    let a = ray(&s, 0, 0, 0.0, 0.0);
    let b = ray(&s, 99, 79, 1.0, 1.0);
    assert!((a.origin.x - 25.0).abs() < 1e-4 && (a.origin.y - 70.0).abs() < 1e-4);
    assert!((b.origin.x - 75.0).abs() < 1e-4 && (b.origin.y - 30.0).abs() < 1e-4);
    assert_eq!(a.direction, -Vec3::Z);
    // Tilted: the ray still meets the surface at the pixel's ground point.
    let toward = Vec3::new(0.5f32.sin(), 0.0, 0.5f32.cos());
    let t = ray(&Sensor { toward, ..s }, 0, 0, 0.0, 0.0);
    let ground = t.origin + t.direction * (t.origin.z / -t.direction.z);
    assert!((ground.x - 25.0).abs() < 1e-4 && (ground.y - 70.0).abs() < 1e-4);
    assert_eq!(t.direction, -toward);
}

#[test]
fn pinhole_centre_ray_looks_at_the_target() {
    let s = Sensor {
        kind: SensorKind::Pinhole {
            position: Vec3::new(0.0, 0.0, 100.0),
            look_at: Vec3::new(50.0, 0.0, 0.0),
            fov_deg: 20.0,
        },
        pixels: [64, 64],
        samples_per_pixel: 1,
        response: None,
        toward: Vec3::Z,
        altitude_m: None,
    };
    let c = ray(&s, 32, 32, 0.0, 0.0);
    let want = (Vec3::new(50.0, 0.0, 0.0) - Vec3::new(0.0, 0.0, 100.0)).normalize();
    assert!(c.direction.dot(want) > 0.99999);
    let corner = ray(&s, 0, 0, 0.0, 0.0);
    let angle = corner.direction.dot(want).acos().to_degrees();
    assert!(angle > 10.0 && angle < 15.0, "{angle}");
}
