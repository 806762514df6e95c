//! The photon map's per-band noise falls as photons are added.

use crate::common::{f32s, render_job, tempdir};
use littoral::scene::{Overrides, Scene, SpectralMode};
use std::path::Path;

/// Deep water with the same IOPs and sun in all 16 bands: every band of
/// every pixel has the same radiance, so the spread of (pixel, band)
/// values around their mean is the estimate's error.
const IDENTICAL_BANDS: &str = r#"
name = "ident"
[spectral]
start_nm = 450.0
end_nm = 600.0
bands = 16
[sun]
zenith_deg = 30.0
irradiance = 1.0
[domain]
size_m = [40.0, 40.0]
[water]
iop = { a = 0.1, b = 0.4 }
phase = { kind = "fournier-forand", bb_ratio = 0.0183 }
[photons]
count = 200000
[sensor]
pixels = [24, 24]
gsd_m = 1.0
[estimate]
max_radius_m = 3.0
step_m = 0.75
"#;

/// Relative spread of every (pixel, band) value of a render of the
/// identical-band scene with `photons` photons in `mode`.
fn spread(dir: &Path, photons: u64, mode: SpectralMode) -> f64 {
    let o = Overrides {
        photons: Some(photons),
        spectral: Some(mode),
        ..Overrides::default()
    };
    let scene = Scene::parse(IDENTICAL_BANDS, Path::new("ident.toml"), &o).unwrap();
    let r = render_job(&scene, &dir.join(format!("{photons}-{mode}")), 0);
    let v: Vec<f64> = f32s(&r.outputs.bsq).into_iter().map(f64::from).collect();
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    var.sqrt() / mean
}

/// With the default `grid` mode and the search-size policy, eight times
/// the photons cut the per-pixel per-band spread: measured over three
/// seeds it was 12.0 % +- 0.8 % (seed-to-seed deviation) at 200 k photons
/// and 7.6 % +- 0.3 % at 1.6 M, a ratio of 0.63 +- 0.05; asserted below
/// 0.8, over three deviations from the measured ratio. The `compensated`
/// mode at 200 k photons is far noisier per band (over twice the spread).
#[test]
fn identical_band_spread_falls_with_photons() {
    let dir = tempdir();
    let small = spread(dir.path(), 200_000, SpectralMode::Grid);
    let big = spread(dir.path(), 1_600_000, SpectralMode::Grid);
    let compensated = spread(dir.path(), 200_000, SpectralMode::Compensated);
    eprintln!("grid 200 k {small}, 1.6 M {big}; compensated 200 k {compensated}");
    assert!(big < 0.8 * small, "spread {small} -> {big}");
    assert!(
        compensated > 2.0 * small,
        "compensated {compensated}, grid {small}"
    );
}
