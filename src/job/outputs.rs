//! A render's files: the cube set written tile by tile as the render hands
//! over its tiles ([`CubeSet`], the render's [`TileSink`]: the ENVI cubes,
//! the spectral EXR and the sensor-band cubes), then the quicklook, the
//! depth profiles, the HTML page and the JSON report, all staged and
//! published as one set (`publish_run`).
//!
//! Every file is written once, streaming, in the staging directory
//! (`output::set::Staging`): no output is made by reading another back. The
//! HTML page reads the staged quicklook and cubes, never a final name, so
//! it always belongs to the same run as the files beside it.
//!
//! Not for: computing values (`render`), the tile files of a part
//! (`job::distributed::parts`).

use super::report::{self, Outputs, RenderTimings, RunReport, SensorSummary};
use super::{html, units, MapStage, RenderShares};
use crate::cube::envi::{CubeFiles, CubeSpec, EnviWriter};
use crate::cube::exr::{ExrLayer, ExrWriter};
use crate::cube::ops::Resampler;
use crate::cube::quicklook::write_png;
use crate::error::{Error, Result};
use crate::output::set::Staging;
use crate::render::{
    products as product_list, stderr_description, Rendered, TileResult, TileSink, RADIANCE_UNITS,
    TILE_PX,
};
use crate::scene::Scene;
use std::path::{Path, PathBuf};

/// The cubes of a render being written tile by tile into a staging
/// directory, and the quicklook's pixels gathered for the end.
pub struct CubeSet {
    dir: PathBuf,
    writer: EnviWriter,
    products: Vec<EnviWriter>,
    stderr: Option<EnviWriter>,
    exr: ExrWriter,
    exr_path: PathBuf,
    sensor: Option<SensorCubes>,
    image: std::sync::Mutex<Vec<f32>>,
}

/// With `[sensor] response`: the radiance and the product cubes integrated
/// over that sensor's bands, as `NAME[.product].SENSOR.{hdr,bsq}`, each
/// tile resampled as it arrives.
struct SensorCubes {
    resampler: Resampler,
    /// Per cube (the radiance, then the products): what it holds and its
    /// writer.
    cubes: Vec<(&'static str, EnviWriter)>,
}

/// A finished sensor-band cube: what it holds, its units and its files.
#[derive(Clone, Debug)]
pub struct SensorCubeFiles {
    pub product: &'static str,
    pub units: String,
    pub files: CubeFiles,
}

/// The files of a finished [`CubeSet`], where they were written.
#[derive(Clone, Debug)]
pub struct CubeSetFiles {
    pub radiance: CubeFiles,
    pub exr: PathBuf,
    pub png: PathBuf,
    /// The standard-error cube, when the integrator writes one.
    pub stderr: Option<CubeFiles>,
    /// The product cubes, in the order of `render::products`.
    pub products: Vec<CubeFiles>,
    /// The sensor-band cubes (radiance, then products), with `[sensor]
    /// response`.
    pub sensor: Vec<SensorCubeFiles>,
}

impl CubeSet {
    /// Create the cubes of `scene` in `dir` (under temporary names).
    pub fn create(scene: &Scene, dir: &Path) -> Result<CubeSet> {
        let [w, h] = scene.sensor.pixels;
        let spec_in = |description: String, units: &str| CubeSpec {
            samples: w,
            lines: h,
            bands: scene.bands.clone(),
            description,
            data_units: units.into(),
            band_names: Vec::new(),
        };
        let spec = |description: String| spec_in(description, RADIANCE_UNITS);
        let extra = crate::cube::georef::envi_header_lines(scene);
        let writer = EnviWriter::create_with(
            dir,
            &scene.name,
            spec(format!(
                "littoral total radiance at the sensor (L_t) of scene '{}'",
                scene.name
            )),
            &extra,
        )?;
        // The products: water-leaving radiance, surface-reflected radiance,
        // remote-sensing reflectance.
        let list = product_list(scene);
        let products = list
            .iter()
            .map(|p| {
                EnviWriter::create_with(
                    dir,
                    &format!("{}.{}", scene.name, p.suffix),
                    spec_in(
                        format!("littoral {} of scene '{}'", p.description, scene.name),
                        p.units,
                    ),
                    &extra,
                )
            })
            .collect::<Result<Vec<_>>>()?;
        let stderr = match stderr_description(scene) {
            Some(what) => Some(EnviWriter::create_with(
                dir,
                &format!("{}.stderr", scene.name),
                spec(format!(
                    "littoral standard error of the radiance cube of scene '{}' ({what})",
                    scene.name
                )),
                &extra,
            )?),
            None => None,
        };
        // The spectral OpenEXR: the radiance, its standard error, then the
        // products, each with the band centres its ENVI header records.
        let exr_path = dir.join(format!("{}.exr", scene.name));
        let named = in_layer_order(
            ("radiance", &writer),
            stderr.as_ref().map(|s| ("stderr", s)),
            list.iter().map(|p| p.layer).zip(&products),
        );
        let wavelengths: Vec<Vec<f64>> = named
            .iter()
            .map(|(_, w)| w.spec().header_wavelengths_nm())
            .collect();
        let layers: Vec<ExrLayer> = named
            .iter()
            .zip(&wavelengths)
            .map(|((name, w), nm)| ExrLayer {
                name,
                wavelengths_nm: nm,
                units: Some(&w.spec().data_units),
            })
            .collect();
        let exr = ExrWriter::create(&exr_path, &layers, (w, h), scene.render.exr_compression)?;
        let sensor = SensorCubes::create(scene, dir, &writer, &products, &extra)?;
        Ok(CubeSet {
            dir: dir.to_path_buf(),
            writer,
            products,
            stderr,
            exr,
            exr_path,
            sensor,
            image: std::sync::Mutex::new(vec![0f32; w * h * 3]),
        })
    }

    /// Finish the cubes and the EXR, and write the quicklook.
    pub fn finish(self, scene: &Scene) -> Result<CubeSetFiles> {
        let CubeSet {
            dir,
            writer,
            products,
            stderr,
            exr,
            exr_path,
            sensor,
            image,
        } = self;
        let [w, h] = scene.sensor.pixels;
        let image = image.into_inner().unwrap_or_else(|e| e.into_inner());
        let png = dir.join(format!("{}.png", scene.name));
        write_png(&png, w, h, &image, None)?;
        let radiance = writer.finish()?;
        let stderr = stderr.map(|s| s.finish()).transpose()?;
        let products = products
            .into_iter()
            .map(|p| p.finish())
            .collect::<Result<Vec<_>>>()?;
        exr.finish()?;
        let sensor = match sensor {
            Some(s) => s.finish()?,
            None => Vec::new(),
        };
        Ok(CubeSetFiles {
            radiance,
            exr: exr_path,
            png,
            stderr,
            products,
            sensor,
        })
    }
}

impl TileSink for CubeSet {
    /// Write one tile into every cube and the quicklook.
    fn write(&self, t: &TileResult) -> Result<()> {
        let (x0, y0) = (t.i * TILE_PX, t.j * TILE_PX);
        let cubes = in_layer_order(
            (&self.writer, &t.values[..]),
            self.stderr.as_ref().map(|s| (s, &t.errors[..])),
            self.products
                .iter()
                .zip(t.products.iter().map(Vec::as_slice)),
        );
        for (cube, values) in &cubes {
            cube.write_tile(x0, y0, t.w, t.h, values)?;
        }
        let layers: Vec<&[f32]> = cubes.iter().map(|(_, values)| *values).collect();
        self.exr.write_tile(x0, y0, t.w, t.h, &layers)?;
        if let Some(sensor) = &self.sensor {
            sensor.write(t)?;
        }
        let w = self.writer.spec().samples;
        let mut image = self.image.lock().unwrap_or_else(|e| e.into_inner());
        for (row, chunk) in t.rgb.chunks(t.w * 3).enumerate() {
            let start = ((y0 + row) * w + x0) * 3;
            image[start..start + chunk.len()].copy_from_slice(chunk);
        }
        Ok(())
    }
}

/// `radiance`, the standard error's (when there is one), then the
/// products': the order of the EXR's layers, in which `create` names them
/// and `write` fills them.
fn in_layer_order<T>(
    radiance: T,
    stderr: Option<T>,
    products: impl IntoIterator<Item = T>,
) -> Vec<T> {
    std::iter::once(radiance)
        .chain(stderr)
        .chain(products)
        .collect()
}

/// The names a render of `scene` publishes in its output directory (the
/// cubes with their GDAL side files, the EXR, PNG, CSVs, HTML and JSON),
/// for checking before any work that none of them is a link or a special
/// file, or one of the run's inputs.
pub fn run_file_names(scene: &Scene) -> Vec<String> {
    let n = &scene.name;
    let mut stems = vec![n.clone(), format!("{n}.stderr")];
    let list = product_list(scene);
    stems.extend(list.iter().map(|p| format!("{n}.{}", p.suffix)));
    if let Some(sensor) = &scene.sensor.response {
        let tag = sensor_tag(&sensor.name);
        stems.push(format!("{n}.{tag}"));
        stems.extend(list.iter().map(|p| format!("{n}.{}.{tag}", p.suffix)));
    }
    let mut names = Vec::new();
    for s in &stems {
        names.extend([
            format!("{s}.hdr"),
            format!("{s}.bsq"),
            format!("{s}.bsq.aux.xml"),
        ]);
    }
    for ext in [
        "exr",
        "png",
        "profiles.csv",
        "kd.csv",
        "atmosphere.csv",
        "html",
        "json",
    ] {
        names.push(format!("{n}.{ext}"));
    }
    names
}

impl SensorCubes {
    /// The sensor-band cubes of `scene` beside `radiance` and `products`
    /// in `dir`, with the header lines `extra`; `None` without `[sensor]
    /// response`.
    fn create(
        scene: &Scene,
        dir: &Path,
        radiance: &EnviWriter,
        products: &[EnviWriter],
        extra: &[String],
    ) -> Result<Option<SensorCubes>> {
        let Some(sensor) = &scene.sensor.response else {
            return Ok(None);
        };
        let spec = radiance.spec();
        let grid = crate::spectral::BandGrid::explicit(
            spec.bands.centers_nm().to_vec(),
            spec.bands.fwhm_nm().to_vec(),
        )?;
        let resampler = Resampler::new(&grid, sensor, &dir.join(format!("{}.hdr", scene.name)))?;
        let tag = sensor_tag(&sensor.name);
        let mut sources = vec![("radiance", scene.name.clone(), radiance)];
        sources.extend(
            product_list(scene)
                .into_iter()
                .zip(products)
                .map(|(p, w)| (p.suffix, format!("{}.{}", scene.name, p.suffix), w)),
        );
        let cubes = sources
            .into_iter()
            .map(|(product, stem, source)| {
                let s = source.spec();
                let spec = resampler.spec(
                    &sensor.name,
                    [s.samples, s.lines],
                    &s.description,
                    Some(&s.data_units),
                );
                let writer = EnviWriter::create_with(dir, &format!("{stem}.{tag}"), spec, extra)?;
                Ok((product, writer))
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Some(SensorCubes { resampler, cubes }))
    }

    /// Resample one tile of the radiance and the products.
    fn write(&self, t: &TileResult) -> Result<()> {
        let (x0, y0) = (t.i * TILE_PX, t.j * TILE_PX);
        let sources = std::iter::once(&t.values).chain(&t.products);
        for ((_, writer), values) in self.cubes.iter().zip(sources) {
            let nb = values.len() / (t.w * t.h);
            let tile = self.resampler.apply(t.w * t.h, |i, b| values[i * nb + b]);
            writer.write_tile(x0, y0, t.w, t.h, &tile)?;
        }
        Ok(())
    }

    fn finish(self) -> Result<Vec<SensorCubeFiles>> {
        self.cubes
            .into_iter()
            .map(|(product, writer)| {
                let units = writer.spec().data_units.clone();
                Ok(SensorCubeFiles {
                    product,
                    units,
                    files: writer.finish()?,
                })
            })
            .collect()
    }
}

/// How a sensor's cubes are tagged: its name, or a response file's stem.
fn sensor_tag(name: &str) -> String {
    Path::new(name)
        .file_stem()
        .map_or_else(|| name.to_string(), |s| s.to_string_lossy().into_owned())
}

/// The name a staged file will have once published, as the report shows it.
fn published(staging: &Staging, staged: &Path) -> String {
    let name = staged.file_name().unwrap_or_default().to_string_lossy();
    staging.final_path(&name).display().to_string()
}

/// The files and the report of a finished render: depth profiles and Kd as
/// CSV (photon map), the sensor-band cubes, the HTML page and the JSON
/// report, written beside the cube set in `staging`; then the whole set is
/// published with the JSON last.
#[allow(clippy::too_many_arguments)]
pub(super) fn publish_run(
    scene: &Scene,
    staging: Staging,
    files: CubeSetFiles,
    rendered: Rendered,
    stage: Option<MapStage>,
    shares: RenderShares,
    timings: RenderTimings,
    peaks: crate::mem::MemoryPeaks,
    warnings: Vec<String>,
) -> Result<RunReport> {
    let integrator = scene.render.integrator;
    let json_name = format!("{}.json", scene.name);
    let html_name = format!("{}.html", scene.name);
    // The exact E_d(0+) the R_rs cube divides by; the emission's noisy
    // tally of it stays in `above_surface.Ed`.
    let ed_above: Vec<f64> = (0..scene.bands.len())
        .map(|b| scene.incident_irradiance(b))
        .collect();
    let (emission, map, reused_map) = match stage {
        Some(s) => (Some(s.emission), Some(s.summary), s.reused),
        None => (None, None, false),
    };
    // Depth profiles and Kd, as CSV, from the emission's tallies.
    let mut profiles = None;
    if let Some(e) = &emission {
        let p = format!("{}.profiles.csv", scene.name);
        let k = format!("{}.kd.csv", scene.name);
        crate::output::write_atomic(&staging.dir().join(&p), e.profiles_csv().as_bytes())?;
        crate::output::write_atomic(&staging.dir().join(&k), e.kd_csv().as_bytes())?;
        profiles = Some((
            staging.final_path(&p).display().to_string(),
            staging.final_path(&k).display().to_string(),
        ));
    }
    // The atmosphere per band, as CSV.
    let atmosphere = report::AtmosphereReport::of(scene);
    let mut atmosphere_csv = None;
    if let Some(a) = &atmosphere {
        let name = format!("{}.atmosphere.csv", scene.name);
        let text = a.csv(scene.bands.centers_nm());
        crate::output::write_atomic(&staging.dir().join(&name), text.as_bytes())?;
        atmosphere_csv = Some(staging.final_path(&name).display().to_string());
    }
    let sensor_cubes = files
        .sensor
        .iter()
        .map(|c| report::ProductFiles {
            product: c.product.into(),
            units: c.units.clone(),
            hdr: published(&staging, &c.files.hdr),
            bsq: published(&staging, &c.files.bsq),
        })
        .collect();
    let bands = emission.is_none().then(|| report::RunBands {
        scene: scene.name.clone(),
        bands_nm: scene.bands.centers_nm().to_vec(),
        fwhm_nm: scene.bands.fwhm_nm().to_vec(),
    });
    let report = RunReport {
        integrator,
        Ed_above_surface: ed_above,
        atmosphere,
        emission,
        bands,
        map,
        reused_map,
        warnings: warnings
            .into_iter()
            .chain(report::radiometer_warnings(&rendered.radiometers))
            .chain(rendered.warnings.iter().cloned())
            .chain(scene.land_warnings())
            .collect(),
        radiometers: rendered.radiometers,
        estimate: scene.estimate.clone(),
        sensor: SensorSummary {
            pixels: scene.sensor.pixels,
            samples_per_pixel: scene.sensor.samples_per_pixel,
            bands: scene.bands.len(),
            georef: scene.georef,
            geotransform: crate::cube::georef::geotransform(scene),
            sun_zenith_deg: scene.sun.zenith_rad.to_degrees(),
            sun_azimuth_deg: scene.sun.compass_azimuth_deg(),
        },
        cache: rendered.cache,
        memory: shares,
        outputs: Outputs {
            hdr: published(&staging, &files.radiance.hdr),
            bsq: published(&staging, &files.radiance.bsq),
            png: published(&staging, &files.png),
            exr: published(&staging, &files.exr),
            json: staging.final_path(&json_name).display().to_string(),
            html: staging.final_path(&html_name).display().to_string(),
            stderr_hdr: files.stderr.as_ref().map(|c| published(&staging, &c.hdr)),
            stderr_bsq: files.stderr.as_ref().map(|c| published(&staging, &c.bsq)),
            profiles_csv: profiles.as_ref().map(|p| p.0.clone()),
            kd_csv: profiles.map(|p| p.1),
            atmosphere_csv,
            products: product_list(scene)
                .iter()
                .zip(&files.products)
                .map(|(p, f)| report::ProductFiles {
                    product: p.suffix.into(),
                    units: p.units.into(),
                    hdr: published(&staging, &f.hdr),
                    bsq: published(&staging, &f.bsq),
                })
                .collect(),
            sensor_cubes,
        },
        timings_s: timings,
        peak_memory: peaks,
        peak_rss_bytes: peaks.rss_bytes,
        units: units::report_units(),
    };
    let text = serde_json::to_string_pretty(&report)
        .map_err(|e| Error::invalid("report", e.to_string()))?
        + "\n";
    html::write(
        scene,
        &report,
        staging.dir(),
        &staging.dir().join(&html_name),
    )?;
    crate::output::write_atomic(&staging.dir().join(&json_name), text.as_bytes())?;
    staging.publish(&[&html_name, &json_name])?;
    Ok(report)
}
