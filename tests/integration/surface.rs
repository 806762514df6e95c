//! The sea surface seen from the air, against results nobody here wrote:
//! the t / n^2 radiance transfer of a flat surface (Fresnel by the
//! textbook sine and tangent forms) and the Cox–Munk glint with Smith
//! shadowing. Tolerances come from rounding where the check is
//! deterministic and from the Monte Carlo standard errors otherwise.

use crate::common::minimal_with;
use crate::physics::{scene, simple};
use littoral::scene::Scene;
/// Unpolarised Fresnel reflectance from the air at incidence `theta_i`
/// (rad) into index `n`, by the textbook sine and tangent forms — a route
/// independent of `optics::surface::fresnel_reflectance`.
fn fresnel_by_angles(theta_i: f64, n: f64) -> f64 {
    if theta_i < 1e-6 {
        return ((n - 1.0) / (n + 1.0)).powi(2);
    }
    let theta_t = (theta_i.sin() / n).asin();
    let rs = (theta_i - theta_t).sin() / (theta_i + theta_t).sin();
    let rp = (theta_i - theta_t).tan() / (theta_i + theta_t).tan();
    0.5 * (rs * rs + rp * rp)
}

/// A camera ray from the air meets a flat sea surface: the refracted
/// branch asks the water for radiance along Snell's direction at the
/// point hit, and the sensor receives R L_sky + (1 - R) L_w / n^2
/// (OPTICS.md: L_air = T L_water / n^2), with R the Fresnel reflectance
/// of the view angle. Deterministic: a flat surface draws no random
/// numbers. Group runs (entries after the first `bands`) carry only the
/// transferred water radiance, no sky. Tolerance 1e-5 relative: the ray
/// directions are f32 (1e-7), and dR/dtheta stays below 10 per radian.
#[test]
fn flat_surface_transfers_water_radiance_as_t_over_n_squared() {
    use glam::Vec3;
    use littoral::render::air_sea::from_air;
    use littoral::render::camera::CameraRay;
    use littoral::rng::Pcg32;
    assert!((fresnel_by_angles(0.0, 1.34) - 0.0211).abs() < 5e-5);
    assert!((fresnel_by_angles(60f64.to_radians(), 1.34) - 0.0610).abs() < 5e-4);
    let (sky, lw) = (0.3, [2.0, 0.25]);
    for n in [1.34, 1.2] {
        let s = simple(0.1, 0.1, 30.0, r#"{ kind = "isotropic" }"#, n, 1, &[0.0]);
        assert_eq!(s.bands.len(), 1);
        for theta_deg in [0.0f64, 20.0, 45.0, 70.0, 85.0] {
            let (theta, phi) = (theta_deg.to_radians(), 0.7f64);
            let d = Vec3::new(
                (theta.sin() * phi.cos()) as f32,
                (theta.sin() * phi.sin()) as f32,
                -theta.cos() as f32,
            );
            let origin = Vec3::new(3.0, 4.0, 10.0);
            let mut calls = Vec::new();
            let mut water = |p: Vec3, dir: Vec3, _: &mut Pcg32, out: &mut [f64]| {
                calls.push((p, dir));
                out.copy_from_slice(&lw);
                Ok(())
            };
            let mut out = [0.0; 2];
            from_air(
                &s,
                &[sky],
                CameraRay {
                    origin,
                    direction: d,
                },
                &mut Pcg32::new(1, 0),
                &mut out,
                &mut water,
            )
            .unwrap();
            assert_eq!(calls.len(), 1, "one refracted branch");
            let (p, dir) = calls[0];
            let theta_w = (theta.sin() / n).asin();
            let want_dir = glam::DVec3::new(
                theta_w.sin() * phi.cos(),
                theta_w.sin() * phi.sin(),
                -theta_w.cos(),
            );
            assert!(
                (dir.as_dvec3() - want_dir).length() < 1e-6,
                "n {n} theta {theta_deg}: {dir} vs Snell {want_dir}"
            );
            let hit = glam::DVec3::new(
                3.0 + 10.0 * theta.tan() * phi.cos(),
                4.0 + 10.0 * theta.tan() * phi.sin(),
                0.0,
            );
            assert!(
                (p.as_dvec3() - hit).length() < 1e-3 && p.z < 0.0,
                "n {n} theta {theta_deg}: water asked at {p}, surface hit at {hit}"
            );
            let r = fresnel_by_angles(theta, n);
            let want = [
                r * sky + (1.0 - r) * lw[0] / (n * n),
                (1.0 - r) * lw[1] / (n * n),
            ];
            for k in 0..2 {
                assert!(
                    (out[k] / want[k] - 1.0).abs() < 1e-5,
                    "n {n} theta {theta_deg} run {k}: {} vs {}",
                    out[k],
                    want[k]
                );
            }
        }
        // Looking up: the sky alone, the water never asked.
        let mut out = [9.0; 2];
        let mut water = |_: Vec3, _: Vec3, _: &mut Pcg32, _: &mut [f64]| -> littoral::Result<()> {
            panic!("a ray looking up does not see the water")
        };
        from_air(
            &s,
            &[sky],
            CameraRay {
                origin: Vec3::new(1.0, 1.0, 10.0),
                direction: Vec3::new(0.0, 0.6, 0.8),
            },
            &mut Pcg32::new(1, 0),
            &mut out,
            &mut water,
        )
        .unwrap();
        assert_eq!(out, [sky, 0.0]);
    }
}

/// A Cox–Munk scene with two bands of direct normal sun irradiance 1.7.
fn glint_scene(zenith: f64, azimuth: f64, wind: f64) -> Scene {
    scene(&minimal_with(&format!(
        r#"
spectral = {{ start_nm = 500.0, end_nm = 600.0, bands = 2 }}
sun = {{ zenith_deg = {zenith}, azimuth_deg = {azimuth}, irradiance = 1.7 }}
surface = {{ kind = "cox-munk", wind_speed = {wind}, refractive_index = 1.34 }}
water = {{ iop = {{ a = 0.1, b = 0.1 }} }}
photons = {{ count = 1 }}
"#
    )))
}

/// Zenith and azimuth (rad) of a direction.
fn angles(v: glam::DVec3) -> (f64, f64) {
    let v = v.normalize();
    (v.z.clamp(-1.0, 1.0).acos(), v.y.atan2(v.x))
}

/// Smith's (1967) unshadowed fraction 1 / (1 + Lambda) of a direction at
/// zenith angle `theta` over Gaussian slopes of total variance `sigma2`,
/// from cot(theta): nu = cot(theta) / sigma, Lambda = (exp(-nu^2) /
/// (sqrt(pi) nu) - erfc(nu)) / 2.
fn smith_g1(theta: f64, sigma2: f64) -> f64 {
    let nu = 1.0 / (theta.tan() * sigma2.sqrt());
    let lambda = ((-nu * nu).exp() / (std::f64::consts::PI.sqrt() * nu) - libm::erfc(nu)) / 2.0;
    1.0 / (1.0 + lambda)
}

/// The Cox–Munk glint with Smith's shadowing of the sun and the view,
/// L = E_sun rho(omega) p(zx, zy) G1(theta_s) G1(theta_v) / (4 cos(theta_v)
/// cos^4(beta)), from angles by spherical trigonometry (Cox & Munk 1954):
/// cos 2 omega = cos theta_v cos theta_s + sin theta_v sin theta_s
/// cos(phi_v - phi_s), cos beta = (cos theta_s + cos theta_v) / (2 cos
/// omega), p = exp(-tan^2 beta / sigma^2) / (pi sigma^2). Returns L and
/// tan beta.
fn glint_by_angles(
    e_sun: f64,
    sigma2: f64,
    n: f64,
    sun: (f64, f64),
    view: (f64, f64),
) -> (f64, f64) {
    let ((ts, ps), (tv, pv)) = (sun, view);
    let cos_2w = tv.cos() * ts.cos() + tv.sin() * ts.sin() * (pv - ps).cos();
    let omega = 0.5 * cos_2w.clamp(-1.0, 1.0).acos();
    let cos_b = (ts.cos() + tv.cos()) / (2.0 * omega.cos());
    let tan2_b = 1.0 / (cos_b * cos_b) - 1.0;
    let p = (-tan2_b / sigma2).exp() / (std::f64::consts::PI * sigma2);
    let g = smith_g1(ts, sigma2) * smith_g1(tv, sigma2);
    let l = e_sun * fresnel_by_angles(omega, n) * p * g / (4.0 * tv.cos() * cos_b.powi(4));
    (l, tan2_b.max(0.0).sqrt())
}

/// `add_glint` adds the Cox–Munk glint formula with Smith's shadowing,
/// computed here independently from angles, for views at and around the specular
/// direction, across the principal plane and off it, three suns and
/// winds; and nothing on a flat surface or for a view below the horizon.
/// Same f32 directions on both sides, but a normalised f32 vector is unit
/// only to about 1e-7, which `add_glint` keeps (cos theta_v = v.z, the
/// half vector of v + s) and the angles here do not: a tilt of dbeta ~
/// 1e-7 moves ln L by (2 tan beta / (sigma^2 cos^2 beta) + 4 tan beta)
/// dbeta. The tolerance is ten times that bound plus 1e-6 relative.
#[test]
fn add_glint_is_the_cox_munk_formula() {
    use littoral::render::air_sea::add_glint;
    let (mut checked, mut worst) = (0, 0.0f64);
    for (zenith, azimuth, wind) in [
        (30.0f64, 0.0f64, 5.0f64),
        (60.0, 45.0, 12.0),
        (10.0, 200.0, 2.0),
    ] {
        let s = glint_scene(zenith, azimuth, wind);
        let sigma2 = 0.003 + 0.00512 * wind;
        assert!((s.surface.slope_variance - sigma2).abs() < 1e-15);
        let sun = angles(-s.sun.direction.as_dvec3());
        assert!((sun.0 - zenith.to_radians()).abs() < 1e-6);
        let specular = sun.1 + std::f64::consts::PI;
        for (tv_deg, dphi_deg) in [
            (zenith, 0.0f64),
            (0.0, 0.0),
            (zenith + 8.0, 0.0),
            (zenith - 5.0, 10.0f64),
            (40.0, 120.0),
            (75.0, -30.0),
        ] {
            let (tv, pv) = (
                tv_deg.clamp(0.0, 89.0).to_radians(),
                specular + dphi_deg.to_radians(),
            );
            let v = glam::Vec3::new(
                (tv.sin() * pv.cos()) as f32,
                (tv.sin() * pv.sin()) as f32,
                tv.cos() as f32,
            )
            .normalize();
            let mut out = [0.0, 0.0];
            add_glint(&s, v, &mut out);
            let (want, tan_b) = glint_by_angles(1.7, sigma2, 1.34, sun, angles(v.as_dvec3()));
            let sensitivity = 2.0 * tan_b * (1.0 + tan_b * tan_b) / sigma2 + 4.0 * tan_b;
            let tol = 1e-6 * (1.0 + sensitivity);
            let rel = out[0] / want - 1.0;
            assert!(
                rel.abs() <= tol && out[1] == out[0],
                "sun {zenith}/{azimuth} U {wind} view {tv_deg}/{dphi_deg}: {out:?} vs {want} (tol {tol:.1e})"
            );
            worst = worst.max(rel.abs() / tol);
            // It adds to what is there.
            let first = out[0];
            add_glint(&s, v, &mut out);
            assert_eq!(out[0], 2.0 * first);
            checked += (want > 1e-3) as usize;
        }
        let mut out = [0.0; 2];
        add_glint(&s, glam::Vec3::new(0.6, 0.0, -0.8), &mut out);
        assert_eq!(out, [0.0; 2], "a view from below the horizon");
    }
    eprintln!("add_glint vs Cox-Munk by angles: worst difference {worst:.2} of the tolerance");
    assert!(checked >= 8, "most geometries see glint: {checked}");
    let flat = simple(0.1, 0.1, 30.0, r#"{ kind = "isotropic" }"#, 1.34, 1, &[0.0]);
    let mut out = [0.0];
    add_glint(&flat, glam::Vec3::new(-0.5, 0.0, 0.866), &mut out);
    assert_eq!(out, [0.0], "no glint from a flat surface");
}

/// The glint formula conserves the light facets reflect: its radiance
/// integrated over the view hemisphere, int L cos(theta_v) d omega, equals
/// the irradiance the facets mirror, E_sun int rho(omega) cos(omega) p / cos
/// beta G1(sun) G1(up) dzx dzy over the slopes facing the sun whose
/// reflection `up` goes up and escapes unshadowed —
/// a check of the 1 / (4 cos theta_v cos^4 beta) Jacobian that the formula
/// comparison above cannot see. Midpoint rules on both sides; refining
/// them changes the ratio by under 1e-5, so 1e-4 is allowed.
#[test]
fn glint_integrates_to_the_reflected_irradiance() {
    use glam::DVec3;
    use littoral::render::air_sea::add_glint;
    use std::f64::consts::PI;
    for (zenith, wind) in [(30.0f64, 3.0f64), (50.0, 8.0)] {
        let s = glint_scene(zenith, 0.0, wind);
        let sigma2 = s.surface.slope_variance;
        let to_sun = (-s.sun.direction.as_dvec3()).normalize();
        // Views: midpoint rule in (cos theta_v, phi) over the hemisphere.
        let (nu, nphi) = (1500usize, 1500usize);
        let mut views = 0.0;
        for i in 0..nu {
            let mu = (i as f64 + 0.5) / nu as f64;
            let st = (1.0 - mu * mu).sqrt();
            for j in 0..nphi {
                let phi = 2.0 * PI * (j as f64 + 0.5) / nphi as f64;
                let v =
                    glam::Vec3::new((st * phi.cos()) as f32, (st * phi.sin()) as f32, mu as f32);
                let mut out = [0.0, 0.0];
                add_glint(&s, v, &mut out);
                views += out[0] * v.z as f64;
            }
        }
        views *= (1.0 / nu as f64) * (2.0 * PI / nphi as f64);
        // Slopes: midpoint rule over +-8 standard deviations per axis.
        let half = 8.0 * (0.5 * sigma2).sqrt();
        let cells = 1200usize;
        let h = 2.0 * half / cells as f64;
        let mut facets = 0.0;
        for i in 0..cells {
            let zx = -half + (i as f64 + 0.5) * h;
            for j in 0..cells {
                let zy = -half + (j as f64 + 0.5) * h;
                let m = DVec3::new(-zx, -zy, 1.0).normalize();
                let cos_w = m.dot(to_sun);
                let up = 2.0 * cos_w * m.z - to_sun.z;
                if cos_w <= 0.0 || up <= 0.0 {
                    continue;
                }
                let p = (-(zx * zx + zy * zy) / sigma2).exp() / (PI * sigma2);
                let g = smith_g1(to_sun.z.acos(), sigma2) * smith_g1(up.min(1.0).acos(), sigma2);
                facets += fresnel_by_angles(cos_w.acos(), 1.34) * cos_w * p * g / m.z;
            }
        }
        facets *= 1.7 * h * h;
        let ratio = views / facets;
        eprintln!("glint sun {zenith} U {wind}: hemisphere {views:.6e}, facets {facets:.6e}, ratio {ratio:.7}");
        assert!(
            (ratio - 1.0).abs() < 1e-4,
            "sun {zenith} U {wind}: ratio {ratio}"
        );
    }
}
