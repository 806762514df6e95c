use super::*;
use crate::render::air_sea::sky_radiance;
use crate::scene::Overrides;

/// A land face tilted by 21.8 degrees (a slope of 0.4) under the CIE
/// clear sky, the sun 40 degrees from the zenith to one side of the
/// slope's fall line, a flat sea below whose water sends nothing up.
fn slope() -> Scene {
    let text = crate::testing::minimal_with(
        "[sun]\nzenith_deg = 40.0\nazimuth_deg = 30.0\n\
         [sky]\nradiance = 0.05\ndistribution = \"cie-clear\"\n\
         [domain]\nsize_m = [100.0, 100.0]\n\
         [bottom]\nslope = { from_depth_m = -20.0, to_depth_m = 20.0, axis = \"x\" }\n\
         reflectance = 0.3\n[land]\nreflectance = 0.3\n",
    );
    Scene::parse(&text, std::path::Path::new("t.toml"), &Overrides::default()).unwrap()
}

/// The radiance leaving a tilted land face has the mean of its exact
/// value: the sun's part, and R / pi times the integral of L_in (n . w)
/// over the hemisphere around the normal by the midpoint rule (1000 x
/// 2000 in n . w and azimuth), L_in the sky above the horizon and the
/// sea's reflection of it below; within 4 standard errors of 100 000
/// calls. Dropping the sky's mirror term S(R w) from the control takes
/// the sky behind the face's plane out of the mean (about 3 % here).
#[test]
fn a_tilted_face_has_its_exact_mean() {
    let scene = slope();
    let nb = scene.bands.len();
    let sky_l = sky_radiance(&scene);
    let d = Vec3::NEG_Z;
    let hit = meet(&scene, Vec3::new(20.0, 50.0, 0.0), d).expect("land at x = 20 m");
    let n = hit.normal;
    assert!((n.z - 0.928).abs() < 1e-3, "{n}");
    let mut dark = |_: Vec3, _: Vec3, _: &mut Pcg32, out: &mut [f64]| -> Result<()> {
        out.iter_mut().for_each(|o| *o = 0.0);
        Ok(())
    };
    let calls = 100_000u64;
    let (mut sum, mut sq) = (vec![0.0; nb], vec![0.0; nb]);
    let mut out = vec![0.0; nb];
    for i in 0..calls {
        let mut rng = Pcg32::new(9, i);
        radiance(&scene, &sky_l, &hit, d, 0, &mut rng, &mut out, &mut dark).unwrap();
        for b in 0..nb {
            sum[b] += out[b];
            sq[b] += out[b] * out[b];
        }
    }
    // The exact value.
    let (t1, t2) = n.any_orthonormal_pair();
    let (nm, na) = (1000, 2000);
    let (dmu, da) = (1.0 / nm as f64, std::f64::consts::TAU / na as f64);
    let mut q = vec![0.0; nb];
    let mut l = vec![0.0; nb];
    let mut water = vec![0.0; nb];
    let mut rng = Pcg32::new(10, 0);
    for i in 0..nm {
        let mu = (i as f64 + 0.5) * dmu;
        let sz = (1.0 - mu * mu).sqrt();
        for j in 0..na {
            let a = (j as f64 + 0.5) * da;
            let w = (t1 * (sz * a.cos()) as f32 + t2 * (sz * a.sin()) as f32 + n * mu as f32)
                .normalize();
            if w.z > 0.0 {
                let g = scene.sky.model.at(w);
                for b in 0..nb {
                    l[b] = sky_l[b] * g.band(b);
                }
            } else {
                let ray = CameraRay {
                    origin: scene.geometry.spawn_origin(hit.position, n, w),
                    direction: w,
                };
                from_air_to(
                    &scene, &sky_l, ray, false, &mut rng, &mut l, &mut water, &mut dark,
                )
                .unwrap();
            }
            for b in 0..nb {
                q[b] += l[b] * mu * dmu * da;
            }
        }
    }
    let s = -scene.sun.direction;
    let land = scene.land.as_ref().unwrap();
    for b in 0..nb {
        let exact = land.reflectance[b] / std::f64::consts::PI
            * (scene.sun.irradiance[b] * f64::from(n.dot(s)) + q[b]);
        let mean = sum[b] / calls as f64;
        let se = ((sq[b] / calls as f64 - mean * mean).max(0.0) / calls as f64).sqrt();
        assert!(
            (mean - exact).abs() < 4.0 * se + 1e-4 * exact,
            "band {b}: {mean} against {exact} (se {se})"
        );
    }
}
