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
mod tests;
