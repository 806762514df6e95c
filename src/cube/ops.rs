//! Whole-cube operations that stream through cubes larger than memory: a
//! window cut into a new cube (one 64 x 64 tile of all bands at a time),
//! and the per-band difference of two cubes (two bands at a time).

use super::envi::{CubeFiles, CubeSpec, EnviCube, EnviWriter};
use crate::error::{Error, Result};
use crate::spectral::BandGrid;
use serde::Serialize;
use std::path::Path;

/// Tile side (pixels) for copying windows.
const TILE: usize = 64;

/// The cube's bands as a grid. Without FWHMs in the header, each band's
/// width is the spacing to its nearest neighbour (1 nm for a single band).
fn band_grid(cube: &EnviCube) -> Result<BandGrid> {
    let centres: Vec<f32> = cube.wavelengths_nm().iter().map(|&v| v as f32).collect();
    let widths: Vec<f32> = match cube.fwhm_nm() {
        Some(f) => f.iter().map(|&v| v as f32).collect(),
        None => (0..centres.len())
            .map(|i| {
                let left = i.checked_sub(1).map(|j| centres[i] - centres[j]);
                let right = centres.get(i + 1).map(|c| c - centres[i]);
                match (left, right) {
                    (Some(l), Some(r)) => l.min(r),
                    (Some(d), None) | (None, Some(d)) => d,
                    (None, None) => 1.0,
                }
            })
            .collect(),
    };
    BandGrid::explicit(centres, widths)
}

/// Copy the window `x0..x0+w` x `y0..y0+h` of `cube` into a new cube
/// `dir/NAME.{hdr,bsq}` with the same bands; returns its files.
pub fn window(
    cube: &EnviCube,
    (x0, y0, w, h): (usize, usize, usize, usize),
    dir: &Path,
    name: &str,
) -> Result<CubeFiles> {
    let inside = |start: usize, len: usize, size: usize| {
        len > 0 && start.checked_add(len).is_some_and(|end| end <= size)
    };
    if !inside(x0, w, cube.samples()) || !inside(y0, h, cube.lines()) {
        return Err(Error::data(
            cube.header_path(),
            None,
            "window",
            format!(
                "{w} x {h} at ({x0}, {y0}) is not a window of the {} x {} cube",
                cube.samples(),
                cube.lines()
            ),
        ));
    }
    let spec = CubeSpec {
        samples: w,
        lines: h,
        bands: band_grid(cube)?,
        description: format!(
            "{} (window {w} x {h} at {x0}, {y0})",
            cube.description().replace(['{', '}'], "")
        ),
        data_units: cube
            .data_units()
            .unwrap_or("unknown")
            .replace(['{', '}'], ""),
    };
    let nb = cube.bands();
    let writer = EnviWriter::create(dir, name, spec)?;
    for ty in (0..h).step_by(TILE) {
        for tx in (0..w).step_by(TILE) {
            let (tw, th) = (TILE.min(w - tx), TILE.min(h - ty));
            let mut tile = vec![0f32; tw * th * nb];
            for b in 0..nb {
                let band = cube.window(b, x0 + tx, y0 + ty, tw, th)?;
                for (i, v) in band.iter().enumerate() {
                    tile[i * nb + b] = *v;
                }
            }
            writer.write_tile(tx, ty, tw, th, &tile)?;
        }
    }
    writer.finish()
}

/// How one band of two cubes differs. Statistics run over the pixels where
/// both values are finite; a pixel where a or b is NaN or infinite is
/// counted apart, as agreeing (the same bits in both) or not.
#[derive(Clone, Debug, Serialize)]
pub struct BandDiff {
    pub wavelength_nm: f64,
    /// Root-mean-square of b - a over the finite pixels.
    pub rmse: f64,
    /// Largest |b - a| over the finite pixels.
    pub max_abs: f64,
    pub mean_a: f64,
    pub mean_b: f64,
    /// Pixels where a or b is not finite and the two differ (NaN against a
    /// number, or different non-finite values).
    pub non_finite_differ: u64,
    /// Pixels where both hold the same non-finite value.
    pub non_finite_same: u64,
}

/// How two cubes of the same shape and bands differ.
#[derive(Clone, Debug, Serialize)]
pub struct CubeDiff {
    pub samples: usize,
    pub lines: usize,
    pub bands: Vec<BandDiff>,
    /// RMS of b - a over every value.
    pub rmse: f64,
    /// `rmse` over the RMS of a.
    pub relative_rmse: f64,
    /// The largest `max_abs` of any band.
    pub max_abs: f64,
    /// Pixels, over all bands, where a or b is not finite and they differ.
    pub non_finite_differ: u64,
}

impl CubeDiff {
    /// Whether b is within `tol` of a everywhere: every finite difference
    /// at most `tol` (absolute, in the cube's units) and no non-finite value
    /// in one cube that the other does not hold too.
    pub fn within(&self, tol: f64) -> bool {
        self.max_abs <= tol && self.non_finite_differ == 0
    }
}

/// Compare `b` against `a` band by band. The cubes must match in size and
/// band centres (to 1e-6 nm); an error names `b`'s header otherwise.
pub fn diff(a: &EnviCube, b: &EnviCube) -> Result<CubeDiff> {
    let shape = |c: &EnviCube| (c.samples(), c.lines(), c.bands());
    if shape(a) != shape(b) {
        return Err(Error::data(
            b.header_path(),
            None,
            "size",
            format!(
                "{:?} (samples, lines, bands) does not match {:?} of {}",
                shape(b),
                shape(a),
                a.header_path().display()
            ),
        ));
    }
    if let Some(i) =
        (0..a.bands()).find(|&i| (a.wavelengths_nm()[i] - b.wavelengths_nm()[i]).abs() > 1e-6)
    {
        return Err(Error::data(
            b.header_path(),
            None,
            "wavelength",
            format!(
                "band {i} is centred at {} nm, not {} nm as in {}",
                b.wavelengths_nm()[i],
                a.wavelengths_nm()[i],
                a.header_path().display()
            ),
        ));
    }
    let (mut sq_all, mut a_sq_all, mut n_all) = (0.0f64, 0.0f64, 0u64);
    let mut bands = Vec::with_capacity(a.bands());
    for i in 0..a.bands() {
        let (va, vb) = (a.band(i)?, b.band(i)?);
        let (mut sq, mut max_abs, mut sum_a, mut sum_b, mut a_sq) = (0.0, 0.0f64, 0.0, 0.0, 0.0);
        let (mut finite, mut differ, mut same) = (0u64, 0u64, 0u64);
        for (&x, &y) in va.iter().zip(&vb) {
            if !(x.is_finite() && y.is_finite()) {
                if x.to_bits() == y.to_bits() {
                    same += 1;
                } else {
                    differ += 1;
                }
                continue;
            }
            let d = y as f64 - x as f64;
            finite += 1;
            sq += d * d;
            max_abs = max_abs.max(d.abs());
            sum_a += x as f64;
            sum_b += y as f64;
            a_sq += x as f64 * x as f64;
        }
        sq_all += sq;
        a_sq_all += a_sq;
        n_all += finite;
        let n = finite.max(1) as f64;
        bands.push(BandDiff {
            wavelength_nm: a.wavelengths_nm()[i],
            rmse: (sq / n).sqrt(),
            max_abs,
            mean_a: sum_a / n,
            mean_b: sum_b / n,
            non_finite_differ: differ,
            non_finite_same: same,
        });
    }
    let n = n_all.max(1) as f64;
    let (rmse, rms_a) = ((sq_all / n).sqrt(), (a_sq_all / n).sqrt());
    Ok(CubeDiff {
        samples: a.samples(),
        lines: a.lines(),
        max_abs: bands.iter().map(|b| b.max_abs).fold(0.0, f64::max),
        non_finite_differ: bands.iter().map(|b| b.non_finite_differ).sum(),
        bands,
        rmse,
        relative_rmse: if rms_a > 0.0 { rmse / rms_a } else { 0.0 },
    })
}
