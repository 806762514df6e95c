//! Validation of a parsed scene file into a `Scene`.

use super::file::*;
use super::locate::{Source, Step};
use super::*;
use crate::geometry::{Axis, GeometryBuilder};
use crate::optics::iop::{BandSpectra, ConstituentField, ConstituentGrid, Constituents, Iop};
use crate::optics::tables::{self, SolarSpectrum, Table};
use crate::Error;
use std::path::PathBuf;
use Step::{Index as I, Key as K};

mod atmosphere;
mod estimate;
mod floor;
mod light;
mod sensor;
mod water;

struct Ctx<'t> {
    src: Source<'t>,
    dir: PathBuf,
    bands: BandGrid,
    policy: OutOfRange,
    /// Every file the scene names, in the order it was read.
    inputs: std::cell::RefCell<Vec<PathBuf>>,
}

impl Ctx<'_> {
    fn err(&self, steps: &[Step], what: impl Into<String>) -> Error {
        self.src.error(steps, what)
    }

    /// Band averages of `table`, under the scene's out-of-range policy.
    fn per_band(&self, table: &Table, steps: &[Step]) -> Result<Vec<f64>> {
        let (lo, hi) = table.range_nm();
        let mut out = Vec::with_capacity(self.bands.len());
        for (&c, &w) in self.bands.centers_nm().iter().zip(self.bands.fwhm_nm()) {
            let c = c as f64;
            let v = if (c < lo || c > hi) && self.policy == OutOfRange::Clamp {
                table.at(c.clamp(lo, hi)).unwrap_or(0.0)
            } else {
                table.band_average(c, w as f64).map_err(|e| {
                    let hint =
                        "set spectral.out_of_range = \"clamp\" to use the nearest tabulated value";
                    self.err(steps, format!("{e} ({hint})"))
                })?
            };
            out.push(v);
        }
        Ok(out)
    }

    /// [`Ctx::per_band`] for a table littoral ships that every scene with
    /// constituents needs (pure water, phytoplankton): a band outside it
    /// is the band grid's doing, so the error names the end of the grid it
    /// falls beyond (`spectral.start_nm` or `spectral.end_nm`).
    fn per_band_shipped(&self, table: &Table) -> Result<Vec<f64>> {
        let (lo, _) = table.range_nm();
        let below = self
            .bands
            .centers_nm()
            .first()
            .is_some_and(|&c| f64::from(c) < lo);
        let end = if below { "start_nm" } else { "end_nm" };
        self.per_band(table, &[Step::Key("spectral"), Step::Key(end)])
    }

    /// The path of a file the scene names (relative to the scene's
    /// directory), recorded as an input of the scene.
    fn path(&self, name: &str) -> PathBuf {
        let p = Path::new(name);
        let path = if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.dir.join(p)
        };
        self.inputs.borrow_mut().push(path.clone());
        path
    }

    /// The path of a file the scene names at `steps` (see [`Ctx::path`]),
    /// refused naming the scene's line and key when it cannot be read.
    fn file(&self, name: &str, steps: &[Step]) -> Result<PathBuf> {
        let path = self.path(name);
        match std::fs::metadata(&path) {
            Ok(m) if m.is_file() => Ok(path),
            Ok(_) => Err(self.err(steps, format!("{} is not a file", path.display()))),
            Err(e) => Err(self.err(steps, format!("cannot read {}: {e}", path.display()))),
        }
    }

    /// Refuse `v` outside [lo, hi], saying which bound it breaks: `low`
    /// when it is below `lo`, "must be at most `hi` `unit`" above, and
    /// that it must be a number for NaN.
    fn within(
        &self,
        steps: &[Step],
        v: f64,
        lo: f64,
        hi: f64,
        low: &str,
        unit: &str,
    ) -> Result<()> {
        match range_error(v, lo, hi, low, unit) {
            None => Ok(()),
            Some(what) => Err(self.err(steps, what)),
        }
    }

    /// A reflectance per band: constant, bottom-table name or CSV path.
    fn reflectance(&self, r: &Reflectance, steps: &[Step]) -> Result<Vec<f64>> {
        let values = match r {
            Reflectance::Constant(v) => vec![*v; self.bands.len()],
            Reflectance::Named(name) => {
                if tables::BOTTOM_TYPES.contains(&name.as_str()) {
                    let t = tables::bottom_reflectance(name)
                        .map_err(|e| self.err(steps, e.to_string()))?;
                    self.per_band(t, steps)?
                } else if name.ends_with(".csv") {
                    let t = Table::from_csv_file(
                        &self.file(name, steps)?,
                        &super::locate::key_name(steps),
                    )?;
                    self.per_band(&t, steps)?
                } else {
                    return Err(self.err(
                        steps,
                        format!(
                            "'{name}' is neither a number, a bottom type ({}) nor a .csv file",
                            tables::BOTTOM_TYPES.join(", ")
                        ),
                    ));
                }
            }
        };
        if let Some(v) = values.iter().find(|v| !(**v >= 0.0 && **v <= 1.0)) {
            return Err(self.err(steps, format!("reflectance {v} is outside [0, 1]")));
        }
        Ok(values)
    }
}

fn finite_in(v: f64, lo: f64, hi: f64) -> bool {
    v.is_finite() && v >= lo && v <= hi
}

/// What is wrong with `v` outside [lo, hi] (`None` inside): `low` below,
/// the upper bound above, or that it is not a number.
fn range_error(v: f64, lo: f64, hi: f64, low: &str, unit: &str) -> Option<String> {
    let unit = if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    };
    if v.is_nan() {
        Some(format!("{low}{unit}; nan is not a number"))
    } else if v < lo {
        Some(format!("{low}{unit}, not {v}"))
    } else if v > hi {
        if hi == f64::MAX {
            Some(format!("must be finite{unit}, not {v}"))
        } else {
            Some(format!("must be at most {hi}{unit}, not {v}"))
        }
    } else {
        None
    }
}

/// `[water]` and `[photons]`: required for a sea, refused for a
/// Lambertian ground (`[surface] kind = "lambertian"`: no water, nothing to
/// emit), where they are filled with defaults nothing reads.
fn ground_tables(src: &Source, f: &mut SceneFile) -> Result<()> {
    let ground = f.lambertian_ground();
    for (table, given) in [
        ("water", f.water.is_some()),
        ("photons", f.photons.is_some()),
    ] {
        match (ground, given) {
            (false, false) => {
                return Err(src.error(
                    &[K(table)],
                    format!(
                        "[{table}] is missing (a scene without water has [surface] kind = \"lambertian\")"
                    ),
                ))
            }
            (true, true) => {
                return Err(src.error(
                    &[K(table)],
                    format!("a Lambertian ground ([surface] kind = \"lambertian\") has no water: remove [{table}]"),
                ))
            }
            _ => {}
        }
    }
    if ground {
        f.water = Some(Default::default());
        f.photons = Some(crate::scene::file::PhotonsFile {
            count: 1,
            store_direct: false,
            upward_split: 1,
            target_split: 1,
        });
    }
    Ok(())
}

/// The most photons a scene may trace: 10^12. The stored map holds about
/// 16 bytes per stored photon (several per traced photon), so 10^12 is a map
/// of tens of terabytes and, at a few million photons per second per core,
/// weeks on a cluster; anything larger would never finish.
pub const MAX_PHOTONS: u64 = 1_000_000_000_000;

/// The longest scene name: outputs are named `NAME.json`, `.NAME.parts`,
/// `NAME.profiles.csv` and so on, and a file name has at most 255 bytes.
pub const MAX_NAME_BYTES: usize = 200;

/// The scene file's text as typed values, with the command line's
/// overrides applied. Type errors (a wrong type, an unknown variant with
/// the allowed ones listed, an unknown or missing key) are named by the key
/// whose value the error points into; text that is not TOML at all is
/// "syntax".
fn parse(src: &Source, text: &str, path: &Path, ov: &Overrides) -> Result<SceneFile> {
    let mut f: SceneFile = toml::from_str(text).map_err(|e| {
        let at = e.span().map(|s| s.start);
        Error::Scene {
            path: path.to_path_buf(),
            line: at.map_or(1, |a| src.line_of(a)),
            key: at
                .and_then(|a| src.key_at(a))
                .unwrap_or_else(|| "syntax".into()),
            what: e.message().replace('\n', " ").trim().to_string(),
        }
    })?;
    ground_tables(src, &mut f)?;
    if let Some(p) = ov.photons {
        // The command line's count is at fault, not the file's line.
        if p == 0 || p > MAX_PHOTONS {
            return Err(Error::invalid(
                "--photons",
                format!("{p} photons: must be from 1 to {MAX_PHOTONS} (10^12); split the work over more runs"),
            ));
        }
        if let Some(ph) = f.photons.as_mut() {
            ph.count = p;
        }
    }
    if let Some(s) = ov.seed {
        f.seed = s;
    }
    if ov.no_atmosphere {
        if let Some(sensor) = f.sensor.as_mut() {
            sensor.altitude_m = None;
        }
    }
    if let Some(on) = ov.inelastic.filter(|_| !f.lambertian_ground()) {
        // On: every process the water supports (fluorescence needs
        // constituents), at the scene's quantum yield where it gives one.
        let water = f.water.as_mut().expect("ground_tables fills [water]");
        water.raman = Some(on);
        let constituents = water.iop.is_none() && water.iop_file.is_none();
        water.fluorescence = (on && constituents).then(|| {
            let given = water.fluorescence.take().unwrap_or_default();
            crate::scene::file::FluorescenceFile {
                chl_quantum_yield: given.chl_quantum_yield,
                cdom: Some(true),
            }
        });
    }
    if let Some(b) = ov.bands {
        // Over the scene's own range: its start and end, or the span of its
        // explicit centres; 400-700 nm only for a scene that gives neither.
        if let Some(c) = f.spectral.centers_nm.take() {
            let lo = c.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = c.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            if lo.is_finite() && hi.is_finite() {
                f.spectral.start_nm = Some(lo);
                f.spectral.end_nm = Some(hi);
            }
        }
        f.spectral.bands = Some(b);
        f.spectral.fwhm_nm = None;
        f.spectral.start_nm.get_or_insert(400.0);
        f.spectral.end_nm.get_or_insert(700.0);
    }
    Ok(f)
}

/// The band grid of `[spectral]`: even from start, end and count, or
/// explicit centres and widths.
fn band_grid(src: &Source, sp: &SpectralFile) -> Result<BandGrid> {
    let spk = |k| [K("spectral"), K(k)];
    let bands = match (&sp.centers_nm, sp.bands) {
        (Some(c), None) => {
            let fwhm = sp
                .fwhm_nm
                .clone()
                .ok_or_else(|| src.error(&spk("fwhm_nm"), "required with centers_nm"))?;
            BandGrid::explicit(
                c.iter().map(|&v| v as f32).collect(),
                fwhm.iter().map(|&v| v as f32).collect(),
            )
            .map_err(|e| src.error(&spk("centers_nm"), e.to_string()))?
        }
        (None, Some(n)) => {
            let (Some(a), Some(b)) = (sp.start_nm, sp.end_nm) else {
                return Err(src.error(&spk("bands"), "needs start_nm and end_nm"));
            };
            BandGrid::even(a as f32, b as f32, n)
                .map_err(|e| src.error(&spk("bands"), e.to_string()))?
        }
        _ => {
            return Err(src.error(
                &[K("spectral")],
                "give either start_nm, end_nm and bands, or centers_nm and fwhm_nm",
            ))
        }
    };
    Ok(bands)
}

/// `[domain]`: its size and edges.
fn domain(ctx: &Ctx, f: &SceneFile) -> Result<Domain> {
    let size = f.domain.size_m;
    for v in size {
        ctx.within(
            &[K("domain"), K("size_m")],
            v,
            1e-3,
            1e7,
            "sizes must be positive",
            "m",
        )?;
    }
    let periodic = f.domain.edges.unwrap_or_default() == Edges::Periodic;
    let domain = Domain {
        size_m: size,
        periodic,
    };
    Ok(domain)
}

/// `[georef]`: where the scene's frame sits on a map.
fn georef(ctx: &Ctx, f: &SceneFile) -> Result<Georef> {
    let georef = Georef {
        origin_m: f.georef.origin_m.unwrap_or([0.0, 0.0]),
        epsg: f.georef.epsg,
    };
    if !georef.origin_m.iter().all(|v| v.is_finite()) {
        return Err(ctx.err(&[K("georef"), K("origin_m")], "must be finite"));
    }
    if georef.epsg.is_some() && georef.utm_zone().is_none() {
        return Err(ctx.err(
            &[K("georef"), K("epsg")],
            "must be a WGS 84 / UTM zone, 32601-32660 (north) or 32701-32760 (south); leave it out for a local metric frame",
        ));
    }
    let pinhole = f
        .sensor
        .as_ref()
        .and_then(|s| s.kind)
        .is_some_and(|k| k == SensorKindName::Pinhole);
    let given = f.georef.origin_m.is_some() || f.georef.epsg.is_some();
    if pinhole && given {
        // A perspective image has no map grid; taking [georef] silently
        // and writing none would mislead.
        return Err(ctx.err(
            &[K("georef")],
            "a pinhole camera's image has no map grid to georeference: remove [georef], or use sensor.kind = \"orthographic\"",
        ));
    }
    Ok(georef)
}

/// `[photons]` (count, upward and target splitting) and `[tally]`: the tally
/// depths, sorted, each above the floor's deepest point.
fn photons_and_tallies(ctx: &Ctx, f: &SceneFile, deepest_floor_m: Option<f64>) -> Result<Vec<f64>> {
    let photons = f.photons();
    if photons.count == 0 {
        return Err(ctx.err(&[K("photons"), K("count")], "must be at least 1"));
    }
    if photons.count > MAX_PHOTONS {
        return Err(ctx.err(
            &[K("photons"), K("count")],
            format!(
                "{} photons would never finish: at most {MAX_PHOTONS} (10^12); split the work over more runs",
                photons.count
            ),
        ));
    }
    let split = photons.upward_split;
    if !(split.is_power_of_two() && split <= 64) {
        return Err(ctx.err(
            &[K("photons"), K("upward_split")],
            format!("{split} is not a power of two from 1 to 64"),
        ));
    }
    let target_split = photons.target_split;
    if !(target_split.is_power_of_two() && target_split <= 64) {
        return Err(ctx.err(
            &[K("photons"), K("target_split")],
            format!("{target_split} is not a power of two from 1 to 64"),
        ));
    }
    let mut tally_depths = f.tally.depths_m.clone();
    for (i, &d) in tally_depths.iter().enumerate() {
        let steps = [K("tally"), K("depths_m"), I(i)];
        ctx.within(&steps, d, 0.0, 1e5, "depths must be >= 0", "m")?;
        // Below the deepest point of the floor no photon ever crosses the
        // depth: the tally would read 0. Between the shallowest and the
        // deepest point it is in the water over part of the domain.
        if let Some(deepest) = deepest_floor_m {
            if d > deepest + 1e-6 * deepest.max(1.0) {
                return Err(ctx.err(
                    &steps,
                    format!(
                        "{d} m is below the floor everywhere (deepest point {deepest} m): no light reaches it"
                    ),
                ));
            }
        }
    }
    tally_depths.sort_by(f64::total_cmp);
    tally_depths.dedup();
    Ok(tally_depths)
}

pub(super) fn build(text: &str, path: &Path, ov: &Overrides) -> Result<Scene> {
    let src = Source::new(text, path);
    let f = parse(&src, text, path, ov)?;
    let dir = path
        .parent()
        .map_or_else(|| PathBuf::from("."), Path::to_path_buf);

    let bands = band_grid(&src, &f.spectral)?;
    let policy = f.spectral.out_of_range.unwrap_or_default();
    let ctx = Ctx {
        src,
        dir,
        bands,
        policy,
        inputs: Default::default(),
    };

    let has_air = f.atmosphere.is_some();
    let ground = light::ground(&ctx, &f, ov)?;
    let surroundings = light::surroundings(&ctx, &f, text, path, ov)?;
    let sun = light::sun(&ctx, &f.sun, has_air)?;
    let sky = light::sky(&ctx, &f.sky, &sun, has_air)?;
    let (sun, sky, atmosphere) = match &f.atmosphere {
        None => (sun, sky, None),
        Some(a) => {
            let spec = atmosphere::spec(&ctx, a)?;
            let (sun, sky, light) = atmosphere::light(
                &ctx,
                a,
                spec,
                &sun,
                f.sun.day_of_year,
                f.seed,
                // The air's reach is kilometres: around a small domain it
                // exchanges light with the surroundings.
                surroundings
                    .as_ref()
                    .and_then(Surroundings::reflectance)
                    .or(ground.as_deref()),
            )?;
            (sun, sky, Some(light))
        }
    };
    light::check_emits(&ctx, &f, &sun, &sky)?;
    let (surface, water_index) = light::surface(&ctx, &f.surface)?;

    let domain = domain(&ctx, &f)?;
    let size = domain.size_m;

    let water_phase = PhaseFunction::rayleigh(crate::optics::phase::RAYLEIGH_Q_WATER)
        .expect("the pure-water q is valid");
    let (water, particle_phase) = water::water(&ctx, f.water(), &domain, &water_phase)?;
    let inelastic = water::inelastic(&ctx, f.water(), &water)?;

    // Geometry: floor and targets.
    let mut geo = GeometryBuilder::new([size[0] as f32, size[1] as f32]);
    let (bottom, shape) = floor::bottom(&ctx, f.bottom.as_ref(), &mut geo)?.unzip();
    let deepest_floor_m = shape.as_ref().map(|s| s.deepest_m);
    let land = floor::land(&ctx, &f, shape.as_ref())?;
    let (target_reflectance, extents) = floor::targets(&ctx, &f.target, &mut geo)?;
    let geometry = geo.build();
    floor::place_targets(&ctx, &f.target, &extents, &domain, &geometry)?;
    let (sensor, radiometers) = sensor::sensor_and_radiometers(&ctx, &f, &domain, &geometry, ov)?;
    if let (Some(l), SensorKind::Pinhole { position, .. }) = (&land, &sensor.kind) {
        if position.z <= l.top_m {
            return Err(ctx.err(
                &[K("sensor"), K("position_m")],
                format!(
                    "z = {} m is not above the land's highest point ({} m): a pinhole camera looks at land from above it",
                    position.z, l.top_m
                ),
            ));
        }
    }
    let atmosphere = atmosphere.map(|mut a| {
        if sensor.altitude_m.is_some() {
            a.view = Some(atmosphere::view(&a, &sun, &sensor, f.seed));
        }
        std::sync::Arc::new(a)
    });
    let (estimate, mut render) = estimate::estimate_and_render(&ctx, &f, ov)?;
    if ground.is_some() {
        // Nothing for a photon map to hold: the ground's radiance is
        // exact (`render::ground`), rendered the path integrator's way.
        render.integrator = IntegratorMode::Path;
    }
    let georef = georef(&ctx, &f)?;
    let mut inputs = ctx.inputs.take();
    inputs.sort();
    inputs.dedup();

    let tally_depths = photons_and_tallies(&ctx, &f, deepest_floor_m)?;
    if f.name.trim().is_empty()
        || f.name.contains(['/', '\\'])
        || f.name.chars().any(char::is_control)
        || f.name == "."
        || f.name == ".."
    {
        return Err(ctx.err(
            &[K("name")],
            "must be a non-empty name without path separators or control characters (it names the output files)",
        ));
    }
    if f.name.len() > MAX_NAME_BYTES {
        return Err(ctx.err(
            &[K("name")],
            format!(
                "{} bytes is too long: at most {MAX_NAME_BYTES} (it names the output files, NAME.json and so on)",
                f.name.len()
            ),
        ));
    }

    let photons = f.photons();
    let (count, store_direct) = (photons.count, photons.store_direct);
    let (upward_split, target_split) = (photons.upward_split, photons.target_split);
    Ok(Scene {
        name: f.name,
        seed: f.seed,
        bands: ctx.bands.clone(),
        sun,
        sky,
        atmosphere,
        reflected_sky: std::sync::OnceLock::new(),
        surface,
        ground,
        surroundings,
        water_index,
        domain,
        water,
        particle_phase,
        water_phase,
        inelastic,
        bottom,
        land,
        target_reflectance,
        split_footprints: if target_split > 1 {
            extents.iter().map(split_footprint).collect()
        } else {
            Vec::new()
        },
        target_extents: extents,
        target_split: target_split as usize,
        geometry,
        photons: count,
        store_direct,
        upward_split: upward_split as usize,
        tally_depths,
        sensor,
        radiometers,
        estimate,
        render,
        georef,
        inputs,
        origin: SceneOrigin {
            text: text.to_string(),
            path: path.to_path_buf(),
            overrides: *ov,
        },
    })
}

/// Where paths entering the water split over a target (`[photons]
/// target_split`): its horizontal extent widened by the depth of its top
/// and [`TARGET_SPLIT_MARGIN_M`], which holds the refracted sun's offset
/// at that depth (0.4 of it below a sun at 30 degrees) and most of the
/// light scattered on the way down.
fn split_footprint(b: &crate::bounds::Aabb) -> Footprint {
    let margin = (-f64::from(b.max.z)).max(0.0) + crate::scene::settings::TARGET_SPLIT_MARGIN_M;
    Footprint {
        min: [f64::from(b.min.x) - margin, f64::from(b.min.y) - margin],
        max: [f64::from(b.max.x) + margin, f64::from(b.max.y) + margin],
    }
}
