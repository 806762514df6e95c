//! `littoral-cube`: look inside radiance cubes (ENVI: littoral's float32
//! BSQ, or BSQ, BIL and BIP cubes of 16-bit integers or 32/64-bit floats
//! that other software writes): a JSON summary, one pixel's spectrum, one
//! band as an image, a true-colour quicklook, a window or a band range cut
//! into a new cube, the cube in another interleave, a window as CSV, the
//! cube in a real sensor's bands, per-band statistics, the per-band
//! difference of two cubes, and a spectral OpenEXR copy.
//!
//! Thin, like `littoral`: arguments and exit codes here, the reading and
//! image writing in the library (`littoral::cube`). Every command reads the
//! cube with positioned reads and holds at most one band (plus, for the
//! quicklook, the RGB image; for `csv`, the window), so it works on cubes
//! larger than memory.
//! Not for: editing cubes, or formats other than ENVI.

use clap::{Parser, Subcommand};
use littoral::cli::{self, print, AnyResult};
use littoral::cube::quicklook::{write_grey_png, write_png};
use littoral::cube::{EnviCube, Quicklook};
use littoral::Error;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "littoral-cube",
    version,
    about = "Inspect radiance cubes (ENVI: BSQ, BIL or BIP; int16, uint16, float32 or float64)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Band centres in nm, comma-separated, for a cube whose header has
    /// neither `wavelength` nor wavelengths in its `band names` (or to
    /// replace them).
    #[arg(long, global = true, value_delimiter = ',', allow_hyphen_values = true)]
    wavelengths: Option<Vec<f64>>,
}

#[derive(Subcommand)]
enum Command {
    /// Print a JSON summary: size, wavelength range, value statistics.
    Info {
        /// The cube's header (NAME.hdr) or data file (NAME.bsq).
        cube: PathBuf,
    },
    /// Print one pixel's spectrum as CSV: wavelength_nm,value.
    Spectrum {
        /// The cube's header or data file.
        cube: PathBuf,
        /// Column, from 0 at the left.
        x: usize,
        /// Line, from 0 at the top.
        y: usize,
    },
    /// Write the band nearest a wavelength as a grey PNG, scaled linearly
    /// from the band's minimum (black) to its maximum (white).
    Band {
        /// The cube's header or data file.
        cube: PathBuf,
        /// Wavelength in nm.
        nm: f64,
        /// PNG file to write.
        #[arg(long)]
        out: PathBuf,
    },
    /// Write a true-colour PNG (CIE 1931 colour matching to sRGB).
    Quicklook {
        /// The cube's header or data file.
        cube: PathBuf,
        /// PNG file to write.
        #[arg(long)]
        out: PathBuf,
        /// Multiply linear values by this (default: the 99th percentile of
        /// luminance maps to white).
        #[arg(long)]
        exposure: Option<f32>,
    },
    /// Cut the window of W x H pixels at (X, Y) into a new cube.
    Window {
        /// The cube's header or data file.
        cube: PathBuf,
        /// Left column of the window.
        x: usize,
        /// Top line of the window.
        y: usize,
        /// Width in pixels.
        w: usize,
        /// Height in lines.
        h: usize,
        /// Header of the new cube (NAME.hdr; NAME.bsq is written beside it).
        #[arg(long)]
        out: PathBuf,
    },
    /// Write the cube with its values in another order (BSQ, BIL or BIP),
    /// as float32 little-endian.
    Convert {
        /// The cube's header or data file.
        cube: PathBuf,
        /// The new cube's interleave.
        #[arg(long, value_enum)]
        interleave: littoral::cube::envi::Interleave,
        /// Header of the new cube (NAME.hdr; the data beside it as
        /// NAME.bsq, NAME.bil or NAME.bip).
        #[arg(long)]
        out: PathBuf,
    },
    /// Print the window of W x H pixels at (X, Y) as CSV: x,y and one
    /// column per band (its wavelength in nm as the header).
    Csv {
        /// The cube's header or data file.
        cube: PathBuf,
        /// Left column of the window.
        x: usize,
        /// Top line of the window.
        y: usize,
        /// Width in pixels.
        w: usize,
        /// Height in lines.
        h: usize,
    },
    /// Cut the bands FROM..=TO (numbered from 0) into a new cube.
    Subset {
        /// The cube's header or data file.
        cube: PathBuf,
        /// First band kept (from 0).
        from: usize,
        /// Last band kept (inclusive).
        to: usize,
        /// Header of the new cube (NAME.hdr; NAME.bsq is written beside it).
        #[arg(long)]
        out: PathBuf,
    },
    /// Integrate the cube over a real sensor's bands into a new cube
    /// (bands whose response the cube's wavelengths do not cover are left
    /// out and listed).
    Resample {
        /// The cube's header or data file.
        cube: PathBuf,
        /// sentinel2a-msi, sentinel2b-msi, landsat8-oli, landsat9-oli,
        /// aviris-ng, enmap, prisma, or csv:FILE (wavelength_nm,BAND,... responses on an
        /// even grid, or band,center_nm,fwhm_nm Gaussians).
        #[arg(long)]
        sensor: String,
        /// Header of the new cube (NAME.hdr; NAME.bsq is written beside it).
        #[arg(long)]
        out: PathBuf,
    },
    /// Print per-band statistics as JSON: wavelength, min, max, mean,
    /// standard deviation, finite and non-finite counts.
    Stats {
        /// The cube's header or data file.
        cube: PathBuf,
    },
    /// Print how cube B differs from cube A as JSON: per band RMSE, largest
    /// difference and means, and the RMSE over the whole cube.
    Diff {
        /// The reference cube's header or data file.
        a: PathBuf,
        /// The other cube's header or data file.
        b: PathBuf,
        /// Fail (exit 1, after printing the JSON) if any |b - a| exceeds
        /// this (in the cube's units), or a NaN or infinity of one cube is
        /// not in the other.
        #[arg(long, allow_hyphen_values = true)]
        tol: Option<f64>,
    },
    /// Assemble the part directories of a render split with `littoral
    /// render --tiles I/N` into the files a whole render writes (cubes
    /// byte-identical to it); the scene is built again from what the parts
    /// recorded, so its files must be where they were.
    Assemble {
        /// Every part directory of the render, any order.
        #[arg(required = true)]
        parts: Vec<PathBuf>,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
        /// Worker threads (0 = one per core).
        #[arg(long, default_value_t = 0, value_parser = littoral::cli::threads_arg)]
        threads: usize,
    },
    /// Write the cube as a spectral OpenEXR file (one channel per band,
    /// named S0.<nm>nm), tile by tile.
    Exr {
        /// The cube's header or data file.
        cube: PathBuf,
        /// EXR file to write.
        #[arg(long)]
        out: PathBuf,
        /// Lossless compression of the EXR.
        #[arg(long, value_enum, default_value_t = littoral::cube::exr::ExrCompression::Zip)]
        compression: littoral::cube::exr::ExrCompression,
    },
}

/// Values read per chunk when scanning a whole cube (4 MiB of floats).
const SCAN_VALUES: usize = 1 << 20;

fn main() -> ExitCode {
    // Before any thread exists, so that every thread shares the one arena.
    littoral::mem::tune_allocator();
    cli::remove_temporaries_on_signals("littoral-cube");
    cli::exit("littoral-cube", run(Cli::parse()))
}

fn run(cli: Cli) -> AnyResult<()> {
    if let Some(bad) = cli
        .wavelengths
        .iter()
        .flatten()
        .find(|v| !(v.is_finite() && **v > 0.0))
    {
        return Err(
            Error::invalid("--wavelengths", format!("{bad} is not a wavelength in nm")).into(),
        );
    }
    let wavelengths = cli.wavelengths;
    let open = |path: &PathBuf| EnviCube::open_with(path, wavelengths.as_deref());
    match cli.command {
        Command::Info { cube } => info(&open(&cube)?),
        Command::Spectrum { cube, x, y } => {
            let cube = open(&cube)?;
            let spectrum = cube.spectrum(x, y)?;
            let mut text = String::from("wavelength_nm,value\n");
            for (nm, v) in cube.wavelengths_nm().iter().zip(&spectrum) {
                text.push_str(&format!("{nm},{v}\n"));
            }
            print(&text)
        }
        Command::Band { cube, nm, out } => band(&open, &cube, nm, &out),
        Command::Quicklook {
            cube,
            out,
            exposure,
        } => {
            png_only(&out)?;
            quicklook(&open(&cube)?, &out, exposure)
        }
        Command::Window {
            cube,
            x,
            y,
            w,
            h,
            out,
        } => {
            let cube = open(&cube)?;
            let (dir, name) = cube_out(&out)?;
            not_an_input(&cube, &cube_files(dir, &name, &["bsq"]))?;
            let files = littoral::cube::ops::window(&cube, (x, y, w, h), dir, &name)?;
            let summary =
                serde_json::json!({ "hdr": files.hdr, "bsq": files.bsq, "samples": w, "lines": h });
            print(&format!("{summary}\n"))
        }
        Command::Subset {
            cube,
            from,
            to,
            out,
        } => {
            let cube = open(&cube)?;
            let (dir, name) = cube_out(&out)?;
            not_an_input(&cube, &cube_files(dir, &name, &["bsq"]))?;
            let files = littoral::cube::ops::subset(&cube, (from, to), dir, &name)?;
            let summary =
                serde_json::json!({ "hdr": files.hdr, "bsq": files.bsq, "bands": to - from + 1 });
            print(&format!("{summary}\n"))
        }
        Command::Resample { cube, sensor, out } => resample(&open, &cube, &sensor, &out),
        Command::Convert {
            cube,
            interleave,
            out,
        } => {
            let cube = open(&cube)?;
            let (dir, name) = cube_out(&out)?;
            not_an_input(&cube, &cube_files(dir, &name, &["bsq", "bil", "bip"]))?;
            let files = littoral::cube::ops::convert(&cube, interleave, dir, &name)?;
            let summary = serde_json::json!({
                "hdr": files.hdr,
                "data": files.bsq,
                "interleave": interleave.extension(),
            });
            print(&format!("{summary}\n"))
        }
        Command::Csv { cube, x, y, w, h } => print(&littoral::cube::ops::window_csv(
            &open(&cube)?,
            (x, y, w, h),
        )?),
        Command::Assemble {
            parts,
            out,
            threads,
        } => {
            let r = littoral::job::distributed::parts::assemble(&parts, &out, threads)?;
            eprintln!("assembled {} parts: {}", parts.len(), r.summary());
            Ok(())
        }
        Command::Stats { cube } => {
            let stats = littoral::cube::ops::stats(&open(&cube)?)?;
            print(&format!("{}\n", serde_json::to_string_pretty(&stats)?))
        }
        Command::Diff { a, b, tol } => diff(&open, &a, &b, tol),
        Command::Exr {
            cube,
            out,
            compression,
        } => {
            let cube = open(&cube)?;
            not_an_input(&cube, std::slice::from_ref(&out))?;
            littoral::cube::exr::write_spectral_exr_layers_with(
                &[("radiance", &cube)],
                &out,
                compression,
            )?;
            Ok(())
        }
    }
}

/// `diff`: how cube `b` differs from cube `a`, as JSON; with `tol`, an
/// error when a value differs by more.
fn diff(
    open: &dyn Fn(&PathBuf) -> littoral::Result<EnviCube>,
    a: &PathBuf,
    b: &PathBuf,
    tol: Option<f64>,
) -> AnyResult<()> {
    if tol.is_some_and(|t| t.is_nan() || t < 0.0) {
        return Err(Error::invalid("--tol", "must be a number >= 0").into());
    }
    let d = littoral::cube::ops::diff(&open(a)?, &open(b)?)?;
    print(&format!("{}\n", serde_json::to_string_pretty(&d)?))?;
    match tol {
        Some(t) if !d.within(t) => Err(Error::invalid(
            "--tol",
            format!(
                "{} differs from {}: largest difference {:e}, {} non-finite values differ (tolerance {t:e})",
                b.display(),
                a.display(),
                d.max_abs,
                d.non_finite_differ
            ),
        )
        .into()),
        _ => Ok(()),
    }
}

/// `band`: the band nearest `nm` as a grey PNG at `out`.
fn band(
    open: &dyn Fn(&PathBuf) -> littoral::Result<EnviCube>,
    cube: &PathBuf,
    nm: f64,
    out: &std::path::Path,
) -> AnyResult<()> {
    if !nm.is_finite() {
        return Err(Error::invalid("NM", format!("'{nm}' is not a wavelength in nm")).into());
    }
    png_only(out)?;
    let cube = &open(cube)?;
    not_an_input(cube, &[out.to_path_buf()])?;
    let b = cube.band_index_nearest(nm);
    let centre = cube.wavelengths_nm()[b];
    let reach = cube.fwhm_nm().map_or(0.0, |f| f[b]).max(1e-9);
    if (nm - centre).abs() > reach {
        return Err(Error::invalid(
            "NM",
            format!(
                "{nm} nm is {:.1} nm from the nearest band ({centre} nm, FWHM {reach} nm): no band covers it",
                (nm - centre).abs()
            ),
        )
        .into());
    }
    let values = cube.band(b)?;
    let range = write_grey_png(out, cube.samples(), cube.lines(), &values)?;
    let summary = serde_json::json!({
        "band": b,
        "wavelength_nm": cube.wavelengths_nm()[b],
        "min": range.map(|r| r.0),
        "max": range.map(|r| r.1),
        "out": out,
    });
    print(&format!("{summary}\n"))
}

/// `quicklook`: the true-colour PNG at `out`.
fn quicklook(cube: &EnviCube, out: &std::path::Path, exposure: Option<f32>) -> AnyResult<()> {
    not_an_input(cube, &[out.to_path_buf()])?;
    let q = Quicklook::for_cube(cube);
    if !q.has_visible_bands() {
        return Err(Error::data(
            cube.header_path(),
            None,
            "wavelength",
            "no band lies within 360-830 nm: nothing to see",
        )
        .into());
    }
    let rgb = q.cube_rgb(cube)?;
    write_png(out, cube.samples(), cube.lines(), &rgb, exposure)?;
    Ok(())
}

/// `resample`: the cube in the bands of `sensor`, at `out` (NAME.hdr).
fn resample(
    open: &dyn Fn(&PathBuf) -> littoral::Result<EnviCube>,
    cube: &PathBuf,
    sensor: &str,
    out: &std::path::Path,
) -> AnyResult<()> {
    let sensor = littoral::spectral::response::SpectralResponse::named(sensor)?;
    let cube = &open(cube)?;
    let (dir, name) = cube_out(out)?;
    not_an_input(cube, &cube_files(dir, &name, &["bsq"]))?;
    let (files, made) = littoral::cube::ops::resample(cube, &sensor, dir, &name)?;
    let band = |i: usize| {
        let b = &sensor.bands[i];
        serde_json::json!({ "name": b.name, "centre_nm": b.centre_nm, "fwhm_nm": b.fwhm_nm })
    };
    let left_out: Vec<&str> = (0..sensor.bands.len())
        .filter(|i| !made.iter().any(|m| m.band == *i))
        .map(|i| sensor.bands[i].name.as_str())
        .collect();
    let summary = serde_json::json!({
        "hdr": files.hdr,
        "bsq": files.bsq,
        "sensor": sensor.name,
        "bands": made.iter().map(|m| band(m.band)).collect::<Vec<_>>(),
        "left_out": left_out,
    });
    print(&format!("{}\n", serde_json::to_string_pretty(&summary)?))
}

/// The directory and cube name of an `--out NAME.hdr` (a `.hdr` file
/// name); the directory is made if it does not exist, as `render --out`
/// makes its own.
fn cube_out(out: &std::path::Path) -> AnyResult<(&std::path::Path, String)> {
    match (out.extension().and_then(|e| e.to_str()), out.file_stem()) {
        (Some(e), Some(stem)) if e.eq_ignore_ascii_case("hdr") => {
            let dir = littoral::output::parent_dir(out);
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, "create", e))?;
            Ok((dir, stem.to_string_lossy().into_owned()))
        }
        _ => Err(Error::invalid(
            "--out",
            format!("{}: name the new cube's header, NAME.hdr", out.display()),
        )
        .into()),
    }
}

/// The files a new cube `dir/NAME` is written as: its header and its data
/// file under each of `data` (extensions).
fn cube_files(dir: &std::path::Path, name: &str, data: &[&str]) -> Vec<PathBuf> {
    std::iter::once(dir.join(format!("{name}.hdr")))
        .chain(data.iter().map(|e| dir.join(format!("{name}.{e}"))))
        .collect()
}

/// Refuse outputs that would overwrite the input cube's header or data.
fn not_an_input(cube: &EnviCube, outs: &[PathBuf]) -> AnyResult<()> {
    use littoral::output::set::refuse_input;
    for o in outs {
        refuse_input(o, "--out", cube.header_path(), "input cube's header")?;
        refuse_input(o, "--out", cube.data_path(), "input cube's data file")?;
    }
    Ok(())
}

/// Images are written as PNG only; another extension is refused rather
/// than given PNG bytes under a misleading name.
fn png_only(out: &std::path::Path) -> AnyResult<()> {
    match out.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("png") => Ok(()),
        _ => Err(Error::invalid(
            "--out",
            format!(
                "{}: only PNG images are written (name it .png)",
                out.display()
            ),
        )
        .into()),
    }
}

/// The JSON summary, scanning every value in chunks of rows.
fn info(cube: &EnviCube) -> AnyResult<()> {
    let (mut min, mut max, mut sum) = (f32::INFINITY, f32::NEG_INFINITY, 0f64);
    let (mut finite, mut non_finite) = (0u64, 0u64);
    let rows_per_chunk = (SCAN_VALUES / cube.samples()).max(1);
    for b in 0..cube.bands() {
        for y0 in (0..cube.lines()).step_by(rows_per_chunk) {
            let h = rows_per_chunk.min(cube.lines() - y0);
            for v in cube.band_rows(b, y0, h)? {
                if v.is_finite() {
                    min = min.min(v);
                    max = max.max(v);
                    sum += f64::from(v);
                    finite += 1;
                } else {
                    non_finite += 1;
                }
            }
        }
    }
    let w = cube.wavelengths_nm();
    let w_min = w.iter().copied().fold(f64::INFINITY, f64::min);
    let w_max = w.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let (min, max, mean) = if finite > 0 {
        (Some(min), Some(max), Some(sum / finite as f64))
    } else {
        (None, None, None)
    };
    let summary = serde_json::json!({
        "header": cube.header_path(),
        "data": cube.data_path(),
        "description": cube.description(),
        "data_units": cube.data_units(),
        "samples": cube.samples(),
        "lines": cube.lines(),
        "bands": cube.bands(),
        "wavelength_nm": { "min": w_min, "max": w_max },
        "value": { "min": min, "max": max, "mean": mean, "non_finite": non_finite },
    });
    print(&format!("{summary:#}\n"))
}
