//! Whole-cube operations that stream through cubes larger than memory: a
//! window cut into a new cube (one 64 x 64 tile of all bands at a time),
//! a band range cut into a new cube (tiles of those bands), per-band
//! statistics (one band at a time), the per-band difference of two
//! cubes (two bands at a time), and the cube in a real sensor's bands (one
//! tile of all bands at a time).

use super::envi::{CubeFiles, CubeSpec, EnviCube, EnviWriter, Interleave};
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

/// The spec of a cube derived from `cube`: `samples` x `lines` over
/// `bands`, its description followed by `note` (if any), its data units.
fn derived_spec(cube: &EnviCube, size: [usize; 2], bands: BandGrid, note: &str) -> CubeSpec {
    spec_from(cube.description(), cube.data_units(), size, bands, note)
}

/// The spec of a derived cube from its source's description and units.
fn spec_from(
    description: &str,
    units: Option<&str>,
    [samples, lines]: [usize; 2],
    bands: BandGrid,
    note: &str,
) -> CubeSpec {
    let description = description.replace(['{', '}'], "");
    CubeSpec {
        samples,
        lines,
        bands,
        description: if note.is_empty() {
            description
        } else {
            format!("{description} ({note})")
        },
        data_units: units.unwrap_or("unknown").replace(['{', '}'], ""),
        band_names: Vec::new(),
    }
}

/// Header keys a derived cube keeps from its source: where it lies on the
/// map and the sun it was rendered under.
const CARRIED_KEYS: [&str; 5] = [
    "map info",
    "coordinate system string",
    "pixel size",
    "sun elevation",
    "sun azimuth",
];

/// The one-line `key = value` lines of `cube`'s header with a key of
/// [`CARRIED_KEYS`], for a cube derived from it; for a window whose top
/// left pixel is `(x0, y0)` of the source, `map info`'s reference pixel
/// moves by (-x0, -y0) so that every pixel keeps its map position.
fn carried_lines(cube: &EnviCube, (x0, y0): (usize, usize)) -> Result<Vec<String>> {
    let text = std::fs::read_to_string(cube.header_path())
        .map_err(|e| Error::io(cube.header_path(), "read", e))?;
    let mut lines = Vec::new();
    for line in text.lines() {
        let Some((key, value)) = line.split_once('=') else {
            continue;
        };
        let key = key.trim().to_ascii_lowercase();
        let value = value.trim();
        let one_line = value.matches('{').count() == value.matches('}').count();
        if !CARRIED_KEYS.contains(&key.as_str()) || !one_line {
            continue;
        }
        if key == "map info" && (x0, y0) != (0, 0) {
            // {projection, ref x, ref y, easting, northing, dx, dy, ...}
            let inner = value.trim_start_matches('{').trim_end_matches('}');
            let mut fields: Vec<String> = inner.split(',').map(|f| f.trim().to_string()).collect();
            let shift =
                |f: &str, by: usize| f.parse::<f64>().ok().map(|v| (v - by as f64).to_string());
            match (
                fields.get(1).and_then(|f| shift(f, x0)),
                fields.get(2).and_then(|f| shift(f, y0)),
            ) {
                (Some(rx), Some(ry)) => {
                    fields[1] = rx;
                    fields[2] = ry;
                    lines.push(format!("map info = {{{}}}", fields.join(", ")));
                }
                _ => continue,
            }
        } else {
            lines.push(format!("{key} = {value}"));
        }
    }
    Ok(lines)
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
    let note = format!("window {w} x {h} at {x0}, {y0}");
    let spec = derived_spec(cube, [w, h], band_grid(cube)?, &note);
    let extra = carried_lines(cube, (x0, y0))?;
    copy_tiles(
        cube,
        (x0, y0),
        EnviWriter::create_with(dir, name, spec, &extra)?,
    )
}

/// Copy the window of `cube` at `(x0, y0)` the size of `writer`'s cube into
/// it, one 64 x 64 tile of all bands at a time, and finish it.
fn copy_tiles(cube: &EnviCube, (x0, y0): (usize, usize), writer: EnviWriter) -> Result<CubeFiles> {
    let (w, h, nb) = (writer.spec().samples, writer.spec().lines, cube.bands());
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

/// `cube` as float32 little-endian in `interleave` order, a new cube
/// `dir/NAME.{hdr,bsq|bil|bip}` with the same bands and description.
pub fn convert(
    cube: &EnviCube,
    interleave: Interleave,
    dir: &Path,
    name: &str,
) -> Result<CubeFiles> {
    let spec = derived_spec(cube, [cube.samples(), cube.lines()], band_grid(cube)?, "");
    copy_tiles(
        cube,
        (0, 0),
        EnviWriter::create_interleaved(dir, name, spec, &carried_lines(cube, (0, 0))?, interleave)?,
    )
}

/// The window `x0..x0+w` x `y0..y0+h` of `cube` as CSV: a header
/// `x,y,<nm>,...` and one row per pixel (row order); the window's values
/// are held, not the cube's.
pub fn window_csv(cube: &EnviCube, (x0, y0, w, h): (usize, usize, usize, usize)) -> Result<String> {
    let mut values = vec![Vec::new(); cube.bands()];
    for (b, v) in values.iter_mut().enumerate() {
        *v = cube.window(b, x0, y0, w, h)?;
    }
    let mut text = String::from("x,y");
    for nm in cube.wavelengths_nm() {
        text.push_str(&format!(",{nm}"));
    }
    text.push('\n');
    for i in 0..w * h {
        text.push_str(&format!("{},{}", x0 + i % w, y0 + i / w));
        for band in &values {
            text.push_str(&format!(",{}", band[i]));
        }
        text.push('\n');
    }
    Ok(text)
}

/// The bands `from..=to` (0-based, inclusive) of `cube` as a new cube
/// `dir/NAME.{hdr,bsq}`, one 64 x 64 tile of those bands at a time.
pub fn subset(
    cube: &EnviCube,
    (from, to): (usize, usize),
    dir: &Path,
    name: &str,
) -> Result<CubeFiles> {
    if from > to || to >= cube.bands() {
        return Err(Error::data(
            cube.header_path(),
            None,
            "bands",
            format!(
                "{from}..={to} is not a band range of the {}-band cube (bands are numbered from 0)",
                cube.bands()
            ),
        ));
    }
    let all = band_grid(cube)?;
    let bands = BandGrid::explicit(
        all.centers_nm()[from..=to].to_vec(),
        all.fwhm_nm()[from..=to].to_vec(),
    )?;
    let note = format!("bands {from} to {to}");
    let spec = derived_spec(cube, [cube.samples(), cube.lines()], bands, &note);
    let (w, h, nb) = (cube.samples(), cube.lines(), to - from + 1);
    let writer = EnviWriter::create_with(dir, name, spec, &carried_lines(cube, (0, 0))?)?;
    for ty in (0..h).step_by(TILE) {
        for tx in (0..w).step_by(TILE) {
            let (tw, th) = (TILE.min(w - tx), TILE.min(h - ty));
            let mut tile = vec![0f32; tw * th * nb];
            for b in from..=to {
                for (i, v) in cube.window(b, tx, ty, tw, th)?.iter().enumerate() {
                    tile[i * nb + b - from] = *v;
                }
            }
            writer.write_tile(tx, ty, tw, th, &tile)?;
        }
    }
    writer.finish()
}

/// Bands of a cube integrated over the bands of a sensor
/// (`spectral::response`): the sensor bands the cube covers, by wavelength,
/// each with its cube bands' weights.
pub struct Resampler {
    /// The sensor bands made, by wavelength.
    pub made: Vec<crate::spectral::response::BandWeights>,
    /// Their grid (the sensor's centres and widths).
    pub bands: BandGrid,
    /// Their names in the sensor's table (`B1`, ...).
    pub names: Vec<String>,
}

impl Resampler {
    /// The sensor bands of `sensor` that `grid` covers. Bands whose
    /// response the grid's spectral range does not cover are left out;
    /// none covered is an error, reported against `source`.
    pub fn new(
        grid: &BandGrid,
        sensor: &crate::spectral::response::SpectralResponse,
        source: &Path,
    ) -> Result<Resampler> {
        let mut made = sensor.weights(grid);
        // The cube's bands rise in wavelength (a panchromatic band is listed last).
        made.sort_by(|a, b| {
            let c = |m: &crate::spectral::response::BandWeights| sensor.bands[m.band].centre_nm;
            c(a).total_cmp(&c(b))
        });
        if made.is_empty() {
            return Err(Error::data(
                source,
                None,
                "wavelength",
                format!(
                    "the cube's {:.1}-{:.1} nm cover no band of {} (each needs {} % of its response inside)",
                    grid.centers_nm()[0],
                    grid.centers_nm()[grid.len() - 1],
                    sensor.name,
                    crate::spectral::response::MIN_COVERAGE * 100.0
                ),
            ));
        }
        let bands = BandGrid::explicit(
            made.iter()
                .map(|m| sensor.bands[m.band].centre_nm as f32)
                .collect(),
            made.iter()
                .map(|m| sensor.bands[m.band].fwhm_nm as f32)
                .collect(),
        )?;
        let names = made
            .iter()
            .map(|m| sensor.bands[m.band].name.clone())
            .collect();
        Ok(Resampler { made, bands, names })
    }

    /// `pixels` pixels in the sensor's bands (bands innermost), from
    /// `value(pixel, cube band)`; sums in f64.
    pub fn apply(&self, pixels: usize, value: impl Fn(usize, usize) -> f32) -> Vec<f32> {
        let out_nb = self.made.len();
        let mut sums = vec![0f64; pixels * out_nb];
        for (o, m) in self.made.iter().enumerate() {
            for &(b, weight) in &m.weights {
                for i in 0..pixels {
                    sums[i * out_nb + o] += weight * value(i, b) as f64;
                }
            }
        }
        sums.iter().map(|&v| v as f32).collect()
    }

    /// The spec of a cube in these bands, from the source cube's
    /// description and units.
    pub fn spec(
        &self,
        sensor_name: &str,
        [samples, lines]: [usize; 2],
        description: &str,
        units: Option<&str>,
    ) -> CubeSpec {
        let note = format!("in the bands of {sensor_name}");
        let mut spec = spec_from(
            description,
            units,
            [samples, lines],
            self.bands.clone(),
            &note,
        );
        spec.band_names = self.names.clone();
        spec
    }
}

/// `cube` integrated over the bands of `sensor` (`spectral::response`) as a new
/// cube `dir/NAME.{hdr,bsq}`, one 64 x 64 tile at a time; returns its
/// files and the sensor bands made, by wavelength ([`Resampler`]).
pub fn resample(
    cube: &EnviCube,
    sensor: &crate::spectral::response::SpectralResponse,
    dir: &Path,
    name: &str,
) -> Result<(CubeFiles, Vec<crate::spectral::response::BandWeights>)> {
    let resampler = Resampler::new(&band_grid(cube)?, sensor, cube.header_path())?;
    let (w, h, nb) = (cube.samples(), cube.lines(), cube.bands());
    let spec = resampler.spec(&sensor.name, [w, h], cube.description(), cube.data_units());
    let writer = EnviWriter::create_with(dir, name, spec, &carried_lines(cube, (0, 0))?)?;
    for ty in (0..h).step_by(TILE) {
        for tx in (0..w).step_by(TILE) {
            let (tw, th) = (TILE.min(w - tx), TILE.min(h - ty));
            let mut bands = vec![Vec::new(); nb];
            for m in &resampler.made {
                for &(b, _) in &m.weights {
                    if bands[b].is_empty() {
                        bands[b] = cube.window(b, tx, ty, tw, th)?;
                    }
                }
            }
            let tile = resampler.apply(tw * th, |i, b| bands[b][i]);
            writer.write_tile(tx, ty, tw, th, &tile)?;
        }
    }
    Ok((writer.finish()?, resampler.made))
}

/// One band's statistics over its finite values.
#[derive(Clone, Debug, Serialize)]
pub struct BandStats {
    pub band: usize,
    pub wavelength_nm: f64,
    pub min: Option<f32>,
    pub max: Option<f32>,
    pub mean: Option<f64>,
    /// Standard deviation over the pixels (population).
    pub sd: Option<f64>,
    pub finite: u64,
    pub non_finite: u64,
}

/// Per-band statistics of `cube`, one band in memory at a time.
pub fn stats(cube: &EnviCube) -> Result<Vec<BandStats>> {
    (0..cube.bands())
        .map(|b| {
            let v = cube.band(b)?;
            let (mut min, mut max, mut sum, mut sum_sq, mut n) =
                (f32::INFINITY, f32::NEG_INFINITY, 0f64, 0f64, 0u64);
            for &x in v.iter().filter(|x| x.is_finite()) {
                min = min.min(x);
                max = max.max(x);
                sum += f64::from(x);
                sum_sq += f64::from(x) * f64::from(x);
                n += 1;
            }
            let mean = (n > 0).then(|| sum / n as f64);
            Ok(BandStats {
                band: b,
                wavelength_nm: cube.wavelengths_nm()[b],
                min: (n > 0).then_some(min),
                max: (n > 0).then_some(max),
                mean,
                sd: mean.map(|m| (sum_sq / n as f64 - m * m).max(0.0).sqrt()),
                finite: n,
                non_finite: v.len() as u64 - n,
            })
        })
        .collect()
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
