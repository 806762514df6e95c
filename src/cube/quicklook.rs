//! True-colour quicklooks: spectra to CIE XYZ to sRGB, and 8-bit PNGs.
//!
//! Design note: [`Quicklook`] integrates a spectrum against the CIE 1931 2°
//! colour-matching functions as a weighted sum over bands,
//! `X = sum_i L_i xbar_i dl_i` (likewise Y, Z), where `xbar_i` is the CMF
//! averaged over band i's Gaussian response and `dl_i` the band's share of
//! the wavelength axis: half the distance between its neighbours' centres
//! (the full spacing at the ends; its FWHM when there is one band). For the
//! usual even grid, whose FWHM equals the spacing, that is the band width;
//! unlike the FWHM it also integrates sparse band sets (e.g. ocean-colour
//! bands with gaps between them) without leaving the gaps black.
//! X, Y, Z are in the spectrum's units times nm: for radiance in
//! W m-2 sr-1 nm-1, Y is luminance / (683 lm/W).
//!
//! Bands whose centre lies outside the CMF tables (360–830 nm) contribute
//! nothing: the eye does not see there, and the tables refuse to
//! extrapolate. A cube with no band in that range gives a black image
//! ([`Quicklook::has_visible_bands`] tells).
//!
//! XYZ goes to linear sRGB with the standard (D65 white) matrix, and
//! [`write_png`] applies an exposure (by default, the 99th percentile of
//! luminance maps to 1), clips, applies the sRGB transfer curve and writes an
//! 8-bit PNG atomically. Equal-energy light is therefore not neutral here:
//! it is illuminant E, slightly pink in sRGB.
//!
//! Not for: colour-accurate rendering (no chromatic adaptation, no gamut
//! mapping beyond clipping), or cubes in other units than spectral radiance
//! per nm. An RGB image is held whole (three floats per pixel); the cube is
//! not ([`Quicklook::cube_rgb`] reads one band at a time).

use std::path::Path;

use crate::cube::envi::EnviCube;
use crate::error::{Error, Result};
use crate::optics::tables::cie_1931;
use crate::spectral::BandGrid;

/// XYZ to linear sRGB (IEC 61966-2-1, D65 white), rows R, G, B.
const XYZ_TO_SRGB: [[f32; 3]; 3] = [
    [3.240_454_2, -1.537_138_5, -0.498_531_4],
    [-0.969_266, 1.876_010_8, 0.041_556],
    [0.055_643_4, -0.204_025_9, 1.057_225_2],
];

/// Rec. 709 / sRGB luminance weights of linear R, G, B (the Y row of the
/// inverse matrix).
const LUMA: [f32; 3] = [0.212_672_9, 0.715_152_2, 0.072_175];

/// Which luminance percentile auto exposure maps to 1: high enough to use
/// the range, low enough that sun glints and stray bright pixels saturate
/// instead of darkening the whole image.
const AUTO_EXPOSURE_PERCENTILE: f64 = 0.99;

/// Per-band weights turning a spectrum into CIE XYZ; see the module doc.
#[derive(Clone, Debug, PartialEq)]
pub struct Quicklook {
    /// (X, Y, Z) weight of each band, in nm.
    weights: Vec<[f32; 3]>,
}

impl Quicklook {
    /// Weights for the bands of `bands`.
    pub fn new(bands: &BandGrid) -> Quicklook {
        let centers: Vec<f64> = bands.centers_nm().iter().map(|&c| f64::from(c)).collect();
        let fwhm: Vec<f64> = bands.fwhm_nm().iter().map(|&w| f64::from(w)).collect();
        Self::from_bands(&centers, Some(&fwhm))
    }

    /// Weights for the bands of a cube read back; without FWHMs in its
    /// header, each band's response is taken as wide as its share of the axis.
    pub fn for_cube(cube: &EnviCube) -> Quicklook {
        Self::from_bands(cube.wavelengths_nm(), cube.fwhm_nm())
    }

    fn from_bands(centers_nm: &[f64], fwhm_nm: Option<&[f64]>) -> Quicklook {
        let widths = axis_shares(centers_nm, fwhm_nm);
        let (xbar, ybar, zbar) = cie_1931();
        let weights = centers_nm
            .iter()
            .zip(&widths)
            .enumerate()
            .map(|(i, (&c, &dl))| {
                let fwhm = fwhm_nm.and_then(|f| f.get(i)).copied().unwrap_or(dl);
                // Out of the tables' range (or a degenerate width): invisible.
                let w = |t: &crate::optics::tables::Table| {
                    t.band_average(c, fwhm).map_or(0.0, |v| (v * dl) as f32)
                };
                [w(xbar), w(ybar), w(zbar)]
            })
            .collect();
        Quicklook { weights }
    }

    /// Number of bands the weights are for.
    pub fn bands(&self) -> usize {
        self.weights.len()
    }

    /// Whether any band lies where the eye sees (360–830 nm).
    pub fn has_visible_bands(&self) -> bool {
        self.weights.iter().any(|w| w.iter().any(|&v| v != 0.0))
    }

    /// The (X, Y, Z) weights of band `b`, in nm; zero for a band out of range.
    pub fn band_weights(&self, b: usize) -> [f32; 3] {
        self.weights.get(b).copied().unwrap_or([0.0; 3])
    }

    /// CIE XYZ of `spectrum` (one value per band; extra values are ignored
    /// and missing ones count as zero).
    pub fn xyz(&self, spectrum: &[f32]) -> [f32; 3] {
        debug_assert_eq!(spectrum.len(), self.weights.len());
        let mut xyz = [0f32; 3];
        for (w, &l) in self.weights.iter().zip(spectrum) {
            for (acc, wk) in xyz.iter_mut().zip(w) {
                *acc += wk * l;
            }
        }
        xyz
    }

    /// Linear sRGB of `spectrum` (unclipped: out-of-gamut colours have
    /// negative components).
    pub fn rgb(&self, spectrum: &[f32]) -> [f32; 3] {
        xyz_to_linear_srgb(self.xyz(spectrum))
    }

    /// The linear sRGB image of a whole cube, `[y][x][rgb]`, accumulated one
    /// band at a time so that only one band and the image are in memory.
    pub fn cube_rgb(&self, cube: &EnviCube) -> Result<Vec<f32>> {
        if cube.bands() != self.bands() {
            return Err(Error::invalid(
                "quicklook",
                format!(
                    "weights are for {} bands but {} has {}",
                    self.bands(),
                    cube.header_path().display(),
                    cube.bands()
                ),
            ));
        }
        let pixels = cube.samples() * cube.lines();
        let mut xyz = vec![[0f32; 3]; pixels];
        for (b, w) in self.weights.iter().enumerate() {
            if *w == [0.0; 3] {
                continue;
            }
            for (acc, &l) in xyz.iter_mut().zip(&cube.band(b)?) {
                for (a, wk) in acc.iter_mut().zip(w) {
                    *a += wk * l;
                }
            }
        }
        Ok(xyz.into_iter().flat_map(xyz_to_linear_srgb).collect())
    }
}

/// Each band's share of the wavelength axis (nm): half the distance between
/// its neighbours in wavelength order, the full gap to the one neighbour at
/// the ends, the FWHM (or 1 nm) for a lone band.
fn axis_shares(centers_nm: &[f64], fwhm_nm: Option<&[f64]>) -> Vec<f64> {
    let n = centers_nm.len();
    if n == 1 {
        return vec![fwhm_nm.and_then(|f| f.first()).copied().unwrap_or(1.0)];
    }
    // Headers read back need not list bands in order.
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| centers_nm[a].total_cmp(&centers_nm[b]));
    let mut shares = vec![0.0; n];
    for (k, &i) in order.iter().enumerate() {
        let lo = centers_nm[order[k.saturating_sub(1)]];
        let hi = centers_nm[order[(k + 1).min(n - 1)]];
        let span = hi - lo;
        shares[i] = if k == 0 || k == n - 1 {
            span
        } else {
            0.5 * span
        };
    }
    shares
}

/// CIE XYZ to linear sRGB (D65 white).
pub fn xyz_to_linear_srgb(xyz: [f32; 3]) -> [f32; 3] {
    XYZ_TO_SRGB.map(|row| row[0] * xyz[0] + row[1] * xyz[1] + row[2] * xyz[2])
}

/// The sRGB transfer curve (linear 0..1 to encoded 0..1).
fn srgb_encode(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// Check an image's size against its buffer; returns the size as PNG wants it.
fn png_size(width: usize, height: usize, channels: usize, len: usize) -> Result<(u32, u32)> {
    let (Ok(w), Ok(h)) = (u32::try_from(width), u32::try_from(height)) else {
        return Err(Error::invalid(
            "image size",
            format!("{width} x {height} is too large for PNG"),
        ));
    };
    if w == 0 || h == 0 {
        return Err(Error::invalid(
            "image size",
            format!("{width} x {height} is empty"),
        ));
    }
    let want = width
        .checked_mul(height)
        .and_then(|n| n.checked_mul(channels));
    if want != Some(len) {
        return Err(Error::invalid(
            "image size",
            format!("{width} x {height} x {channels} values do not match the {len} given"),
        ));
    }
    Ok((w, h))
}

/// The exposure that maps the 99th-percentile luminance of `rgb_linear` to 1
/// (NaNs and negative luminance ignored; 1 for an all-dark image).
pub fn auto_exposure(rgb_linear: &[f32]) -> f32 {
    let mut luma: Vec<f32> = rgb_linear
        .chunks_exact(3)
        .map(|p| LUMA[0] * p[0] + LUMA[1] * p[1] + LUMA[2] * p[2])
        .filter(|y| y.is_finite())
        .map(|y| y.max(0.0))
        .collect();
    if luma.is_empty() {
        return 1.0;
    }
    let k = ((luma.len() - 1) as f64 * AUTO_EXPOSURE_PERCENTILE).round() as usize;
    let (_, &mut p, above) = luma.select_nth_unstable_by(k, f32::total_cmp);
    let max = above.iter().copied().fold(p, f32::max);
    // A mostly black image still shows its few lit pixels.
    let reference = if p > 0.0 { p } else { max };
    if reference > 0.0 && (1.0 / reference).is_finite() {
        1.0 / reference
    } else {
        1.0
    }
}

/// Write a linear sRGB image (`[y][x][rgb]`, `width * height * 3` values)
/// as an 8-bit sRGB PNG at `path`, atomically. `exposure` multiplies the
/// values first; `None` chooses [`auto_exposure`]. Values are clipped to
/// 0..1 after exposure; NaNs become black.
pub fn write_png(
    path: &Path,
    width: usize,
    height: usize,
    rgb_linear: &[f32],
    exposure: Option<f32>,
) -> Result<()> {
    let (w, h) = png_size(width, height, 3, rgb_linear.len())?;
    let scale = match exposure {
        Some(e) if e.is_finite() && e > 0.0 => e,
        Some(e) => {
            return Err(Error::invalid(
                "exposure",
                format!("must be a positive number, got {e}"),
            ))
        }
        None => auto_exposure(rgb_linear),
    };
    let bytes: Vec<u8> = rgb_linear
        .iter()
        .map(|&c| {
            // clamp passes NaN through: make it black explicitly.
            let c = if c.is_nan() {
                0.0
            } else {
                (c * scale).clamp(0.0, 1.0)
            };
            (srgb_encode(c) * 255.0).round() as u8
        })
        .collect();
    encode_png(path, w, h, png::ColorType::Rgb, &bytes, true)
}

/// Write `values` (`[y][x]`) as an 8-bit grey PNG, scaled linearly from
/// their minimum (black) to their maximum (white), atomically. Returns that
/// (min, max), or `None` if no value is finite; NaNs and infinities are
/// black, and a constant image is all black.
pub fn write_grey_png(
    path: &Path,
    width: usize,
    height: usize,
    values: &[f32],
) -> Result<Option<(f32, f32)>> {
    let (w, h) = png_size(width, height, 1, values.len())?;
    let range = values
        .iter()
        .filter(|v| v.is_finite())
        .fold(None, |r: Option<(f32, f32)>, &v| {
            Some(r.map_or((v, v), |(lo, hi)| (lo.min(v), hi.max(v))))
        });
    let (lo, hi) = range.unwrap_or((0.0, 0.0));
    // In f64: hi - lo can overflow f32 for extreme values.
    let span = f64::from(hi) - f64::from(lo);
    let bytes: Vec<u8> = values
        .iter()
        .map(|&v| {
            if v.is_finite() && span > 0.0 {
                ((f64::from(v) - f64::from(lo)) / span * 255.0).round() as u8
            } else {
                0
            }
        })
        .collect();
    encode_png(path, w, h, png::ColorType::Grayscale, &bytes, false)?;
    Ok(range)
}

fn encode_png(
    path: &Path,
    w: u32,
    h: u32,
    color: png::ColorType,
    bytes: &[u8],
    srgb: bool,
) -> Result<()> {
    let failed = |e: png::EncodingError| Error::io(path, "encode PNG", std::io::Error::other(e));
    let mut out = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut out, w, h);
        encoder.set_color(color);
        encoder.set_depth(png::BitDepth::Eight);
        if srgb {
            encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        }
        let mut writer = encoder.write_header().map_err(failed)?;
        writer.write_image_data(bytes).map_err(failed)?;
        writer.finish().map_err(failed)?;
    }
    crate::output::write_atomic(path, &out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 5 nm bands across the whole CMF range.
    fn visible() -> BandGrid {
        BandGrid::even(360.0, 830.0, 95).unwrap()
    }

    fn single_band(grid: &BandGrid, nm: f32) -> Vec<f32> {
        grid.centers_nm()
            .iter()
            .map(|&c| if (c - nm).abs() < 1e-3 { 1.0 } else { 0.0 })
            .collect()
    }

    /// A flat spectrum of 1 integrates to Y = the integral of ybar over
    /// wavelength (106.86 nm for the CIE 1931 observer): the weights are a
    /// quadrature of the colour-matching integral, not just a colour ratio.
    #[test]
    fn flat_unit_spectrum_integrates_to_the_cmf_integrals() {
        let grid = visible();
        let q = Quicklook::new(&grid);
        let xyz = q.xyz(&vec![1.0; grid.len()]);
        let (xbar, ybar, zbar) = cie_1931();
        for (got, table) in xyz.iter().zip([xbar, ybar, zbar]) {
            let want = table.integral();
            assert!(
                (f64::from(*got) / want - 1.0).abs() < 5e-3,
                "{} {got} vs {want}",
                table.name()
            );
        }
        assert!((xyz[1] - 106.86).abs() < 0.6, "{xyz:?}");
    }

    /// Equal-energy light is CIE illuminant E, XYZ = (1, 1, 1) once
    /// normalised; its linear sRGB (D65 white) is the matrix's row sums,
    /// (1.2048, 0.9483, 0.9088) — a known pinkish white, not neutral grey.
    #[test]
    fn equal_energy_spectrum_is_illuminant_e() {
        let grid = visible();
        let q = Quicklook::new(&grid);
        let spectrum = vec![0.02; grid.len()];
        let xyz = q.xyz(&spectrum);
        let rgb = q.rgb(&spectrum);
        for (k, want) in [1.204_784_3f32, 0.948_300_8, 0.908_842_7]
            .iter()
            .enumerate()
        {
            let got = rgb[k] / xyz[1];
            assert!(
                (got / want - 1.0).abs() < 0.02,
                "channel {k}: {got} vs {want}"
            );
        }
        // The same with a coarse 10 nm grid over 400-700 nm only.
        let coarse = BandGrid::even(400.0, 700.0, 31).unwrap();
        let q = Quicklook::new(&coarse);
        let rgb = q.rgb(&vec![1.0; coarse.len()]);
        let y = q.xyz(&vec![1.0; coarse.len()])[1];
        assert!((rgb[0] / y / 1.2048 - 1.0).abs() < 0.05, "{rgb:?}");
        assert!((rgb[2] / y / 0.9088 - 1.0).abs() < 0.05, "{rgb:?}");
    }

    /// Monochromatic light: 450 nm lies in the blue corner of the gamut,
    /// 610 nm in the red, 530 nm in the green.
    #[test]
    fn narrow_bands_take_their_colour() {
        let grid = visible();
        let q = Quicklook::new(&grid);
        let blue = q.rgb(&single_band(&grid, 450.0));
        assert!(blue[2] > 4.0 * blue[0].max(blue[1]), "{blue:?}");
        let red = q.rgb(&single_band(&grid, 610.0));
        assert!(red[0] > 4.0 * red[1].max(red[2]), "{red:?}");
        let green = q.rgb(&single_band(&grid, 530.0));
        assert!(green[1] > 2.0 * green[0].max(green[2]), "{green:?}");
    }

    #[test]
    fn invisible_bands_contribute_nothing() {
        let grid = BandGrid::explicit(vec![300.0, 550.0, 900.0, 1200.0], vec![10.0; 4]).unwrap();
        let q = Quicklook::new(&grid);
        assert!(q.has_visible_bands());
        assert_eq!(q.band_weights(0), [0.0; 3]);
        assert_ne!(q.band_weights(1), [0.0; 3]);
        assert_eq!(q.band_weights(2), [0.0; 3]);
        assert_eq!(q.band_weights(99), [0.0; 3]);
        let nir = BandGrid::even(900.0, 1000.0, 5).unwrap();
        let q = Quicklook::new(&nir);
        assert!(!q.has_visible_bands());
        assert_eq!(q.rgb(&[7.0; 5]), [0.0; 3]);
    }

    #[test]
    fn axis_shares_split_the_gaps() {
        assert_eq!(
            axis_shares(&[400.0, 410.0, 430.0], None),
            [10.0, 15.0, 20.0]
        );
        assert_eq!(
            axis_shares(&[430.0, 400.0, 410.0], None),
            [20.0, 10.0, 15.0]
        );
        assert_eq!(axis_shares(&[500.0], Some(&[8.0])), [8.0]);
        assert_eq!(axis_shares(&[500.0], None), [1.0]);
    }

    fn decode(path: &Path) -> (png::OutputInfo, Vec<u8>) {
        let bytes = std::fs::read(path).unwrap();
        let mut reader = png::Decoder::new(std::io::Cursor::new(bytes))
            .read_info()
            .unwrap();
        let (w, h) = (reader.info().width as usize, reader.info().height as usize);
        let channels = reader.info().color_type.samples();
        let mut buf = vec![0; w * h * channels];
        let info = reader.next_frame(&mut buf).unwrap();
        (info, buf)
    }

    #[test]
    fn rgb_png_decodes_with_its_size_and_exposure() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("q.png");
        let (w, h) = (7, 5);
        // Grey ramp 0..34 (luminance = value for neutral pixels), one NaN.
        let mut rgb: Vec<f32> = (0..w * h).flat_map(|i| [i as f32; 3]).collect();
        rgb[3] = f32::NAN;
        write_png(&path, w, h, &rgb, None).unwrap();
        let (info, px) = decode(&path);
        assert_eq!((info.width, info.height), (7, 5));
        assert_eq!(info.color_type, png::ColorType::Rgb);
        assert_eq!(info.bit_depth, png::BitDepth::Eight);
        assert_eq!(&px[0..3], [0, 0, 0]);
        assert_eq!(px[3], 0, "NaN is black");
        // 99th percentile of 35 values is the brightest: it maps to white.
        assert_eq!(&px[px.len() - 3..], [255, 255, 255]);
        let mid = 17 * 3;
        assert!(px[mid] == px[mid + 1] && px[mid + 1] == px[mid + 2]);

        write_png(&path, 1, 1, &[0.5, 0.5, 0.5], Some(1.0)).unwrap();
        assert_eq!(decode(&path).1, [188, 188, 188], "sRGB curve of 0.5");
        write_png(&path, 1, 1, &[-1.0, 2.0, 0.0], Some(1.0)).unwrap();
        assert_eq!(decode(&path).1, [0, 255, 0], "clipped");
    }

    #[test]
    fn grey_png_spans_min_to_max() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("g.png");
        let values = [2.0, 4.0, 3.0, f32::NAN, 6.0, 2.0];
        let range = write_grey_png(&path, 3, 2, &values).unwrap();
        assert_eq!(range, Some((2.0, 6.0)));
        let (info, px) = decode(&path);
        assert_eq!(
            (info.width, info.height, info.color_type),
            (3, 2, png::ColorType::Grayscale)
        );
        assert_eq!(px, [0, 128, 64, 0, 255, 0]);
        assert_eq!(write_grey_png(&path, 1, 1, &[f32::NAN]).unwrap(), None);
    }

    #[test]
    fn bad_images_are_refused_and_write_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.png");
        assert!(write_png(&path, 2, 2, &[0.0; 11], None).is_err());
        assert!(write_png(&path, 0, 2, &[], None).is_err());
        assert!(write_png(&path, 1, 1, &[0.0; 3], Some(0.0)).is_err());
        assert!(write_png(&path, 1, 1, &[0.0; 3], Some(f32::NAN)).is_err());
        assert!(write_grey_png(&path, usize::MAX, 2, &[0.0]).is_err());
        assert!(write_grey_png(&path, 3, 1, &[0.0; 2]).is_err());
        assert!(std::fs::read_dir(dir.path()).unwrap().next().is_none());
        let e = write_png(&dir.path().join("no/such.png"), 1, 1, &[0.0; 3], None).unwrap_err();
        assert!(e.to_string().contains("no/such.png"), "{e}");
    }

    /// The band-at-a-time image of a cube equals the per-pixel colours.
    #[test]
    fn cube_rgb_matches_per_pixel_spectra() {
        use crate::cube::envi::{CubeSpec, EnviWriter};
        let dir = tempfile::tempdir().unwrap();
        let grid = BandGrid::even(420.0, 680.0, 14).unwrap();
        let (w, h, n) = (5, 3, grid.len());
        let values: Vec<f32> = (0..w * h * n)
            .map(|i| ((i * 37) % 11) as f32 * 0.01)
            .collect();
        let spec = CubeSpec {
            samples: w,
            lines: h,
            bands: grid.clone(),
            description: String::new(),
            data_units: "W m-2 sr-1 nm-1".into(),
        };
        let writer = EnviWriter::create(dir.path(), "c", spec).unwrap();
        writer.write_tile(0, 0, w, h, &values).unwrap();
        let (_, hdr) = writer.finish().unwrap();
        let cube = EnviCube::open(&hdr).unwrap();
        let q = Quicklook::for_cube(&cube);
        assert_eq!(q, Quicklook::new(&grid));
        let image = q.cube_rgb(&cube).unwrap();
        assert_eq!(image.len(), w * h * 3);
        for (p, spectrum) in values.chunks_exact(n).enumerate() {
            let want = q.rgb(spectrum);
            for (got, want) in image[3 * p..3 * p + 3].iter().zip(want) {
                assert!(
                    (got - want).abs() <= 1e-5 * want.abs().max(1.0),
                    "{got} vs {want}"
                );
            }
        }
        let other = Quicklook::new(&BandGrid::even(420.0, 680.0, 3).unwrap());
        assert!(other.cube_rgb(&cube).is_err());
    }

    #[test]
    fn auto_exposure_ignores_the_brightest_percent() {
        let mut rgb: Vec<f32> = (0..1000).flat_map(|_| [0.5; 3]).collect();
        for p in rgb.chunks_exact_mut(3).take(5) {
            p.fill(1000.0); // glints
        }
        assert!((auto_exposure(&rgb) - 2.0).abs() < 1e-4);
        assert_eq!(auto_exposure(&[0.0; 6]), 1.0);
        let sparse: Vec<f32> = (0..1000)
            .flat_map(|i| [if i == 0 { 4.0 } else { 0.0 }; 3])
            .collect();
        assert!((auto_exposure(&sparse) - 0.25).abs() < 1e-4);
    }
}
