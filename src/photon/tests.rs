use super::*;
use crate::rng::Pcg32;

fn random_unit(rng: &mut Pcg32) -> Vec3 {
    let z = 1.0 - 2.0 * rng.uniform_f32();
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * rng.uniform_f32();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

#[test]
fn octahedral_error_is_bounded() {
    let mut rng = Pcg32::new(11, 0);
    let mut worst = 0.0f32;
    let mut dirs: Vec<Vec3> = (0..200_000).map(|_| random_unit(&mut rng)).collect();
    // The poles, the equator and the octant seams are where encodings fold.
    dirs.extend([Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z]);
    dirs.push(Vec3::new(1.0, 1.0, 0.0).normalize());
    dirs.push(Vec3::new(-1.0, 1.0, -1e-7).normalize());
    for d in dirs {
        let e = oct_decode(oct_encode(d));
        assert!((e.length() - 1.0).abs() < 1e-6);
        let angle = d.dot(e).clamp(-1.0, 1.0).acos();
        // acos loses precision near 1; use the cross product for small angles.
        let angle = angle.min(d.cross(e).length().asin());
        worst = worst.max(angle);
    }
    assert!(worst <= OCT_MAX_ANGLE_ERROR_RAD, "worst {worst}");
    assert!(worst > 1e-6, "the bound should be tight-ish, worst {worst}");
}

#[test]
fn quantisation_error_is_half_a_step() {
    let q = AxisQuantizer::new(-12.5, 37.25);
    let half = q.step() * 0.5;
    let mut rng = Pcg32::new(5, 1);
    for _ in 0..100_000 {
        let p = -12.5 + 49.75 * rng.uniform_f32();
        let d = q.decode(q.encode(p));
        assert!((d - p).abs() <= half * 1.0001 + 4.0 * f32::EPSILON * 37.25);
    }
    assert_eq!(q.encode(-12.5), 0);
    assert_eq!(q.encode(37.25), 65535);
    let flat = AxisQuantizer::new(-10.0, -10.0);
    assert_eq!(flat.decode(flat.encode(-10.0)), -10.0);
}

/// The four-lane errors are those of decoding each candidate with
/// `oct_decode`, bit for bit, and the code chosen is the same, over a
/// million random directions and the folds (poles, equator, octant seams).
#[test]
fn octahedral_lanes_match_the_scalar_decode() {
    let mut rng = crate::rng::Pcg32::new(11, 3);
    let mut dirs: Vec<Vec3> = (0..1_000_000)
        .map(|_| {
            let z = 2.0 * rng.uniform_f64() - 1.0;
            let phi = std::f64::consts::TAU * rng.uniform_f64();
            let r = (1.0 - z * z).max(0.0).sqrt();
            glam::DVec3::new(r * phi.cos(), r * phi.sin(), z).as_vec3()
        })
        .collect();
    for x in [-1.0f32, -0.5, 0.0, 0.5, 1.0] {
        for y in [-1.0f32, -0.5, 0.0, 0.5, 1.0] {
            for z in [-1.0f32, -1e-7, 0.0, 1e-7, 1.0] {
                let d = Vec3::new(x, y, z);
                if d.length() > 0.0 {
                    dirs.push(d.normalize());
                }
            }
        }
    }
    for d in dirs {
        let codes = oct_candidates(d);
        let lanes = oct_errors(codes, d);
        let scalar = codes.map(|c| (oct_decode(c) - d).length_squared());
        assert_eq!(lanes.map(f32::to_bits), scalar.map(f32::to_bits), "{d:?}");
        // And the code chosen is the scalar decode's first smallest.
        let mut best = (codes[0], f32::INFINITY);
        for (c, e) in codes.into_iter().zip(scalar) {
            if e < best.1 {
                best = (c, e);
            }
        }
        assert_eq!(oct_encode(d), best.0, "{d:?}");
    }
}
