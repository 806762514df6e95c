//! Validation of a parsed scene file into a `Scene`.

use super::file::*;
use super::locate::{Source, Step};
use super::*;
use crate::geometry::{Axis, GeometryBuilder};
use crate::optics::iop::{BandSpectra, ConstituentField, ConstituentGrid, Constituents};
use crate::optics::tables::{self, SolarSpectrum, Table};
use crate::Error;
use std::path::PathBuf;
use Step::{Index as I, Key as K};

mod sensor;
use sensor::render_settings;

/// What to do with a band centre outside a data table's range.
#[derive(Clone, Copy, PartialEq)]
enum RangePolicy {
    Error,
    Clamp,
}

struct Ctx<'t> {
    src: Source<'t>,
    dir: PathBuf,
    bands: BandGrid,
    policy: RangePolicy,
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
            let v = if (c < lo || c > hi) && self.policy == RangePolicy::Clamp {
                table.at(c.clamp(lo, hi)).unwrap_or(0.0)
            } else {
                table
                    .band_average(c, w as f64)
                    .map_err(|e| self.err(steps, format!("{e} (set spectral.out_of_range = \"clamp\" to use the nearest tabulated value)")))?
            };
            out.push(v);
        }
        Ok(out)
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
                    let t =
                        Table::from_csv_file(&self.path(name), &super::locate::key_name(steps))?;
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

pub(super) fn build(text: &str, path: &Path, ov: &Overrides) -> Result<Scene> {
    let src = Source::new(text, path);
    let mut f: SceneFile = toml::from_str(text).map_err(|e| {
        let line = e.span().map_or(1, |s| src.line_of(s.start));
        Error::Scene {
            path: path.to_path_buf(),
            line,
            key: "syntax".into(),
            what: e.message().replace('\n', " ").trim().to_string(),
        }
    })?;
    if let Some(p) = ov.photons {
        f.photons.count = p;
    }
    if let Some(s) = ov.seed {
        f.seed = s;
    }
    if let Some(b) = ov.bands {
        f.spectral.bands = Some(b);
        f.spectral.centers_nm = None;
        f.spectral.fwhm_nm = None;
        f.spectral.start_nm.get_or_insert(400.0);
        f.spectral.end_nm.get_or_insert(700.0);
    }
    let dir = path
        .parent()
        .map_or_else(|| PathBuf::from("."), Path::to_path_buf);

    // Spectral grid.
    let sp = &f.spectral;
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
    let policy = match sp.out_of_range.as_deref() {
        None | Some("error") => RangePolicy::Error,
        Some("clamp") => RangePolicy::Clamp,
        Some(o) => {
            return Err(src.error(
                &spk("out_of_range"),
                format!("'{o}': use \"error\" or \"clamp\""),
            ))
        }
    };
    let ctx = Ctx {
        src,
        dir,
        bands,
        policy,
        inputs: Default::default(),
    };
    let nb = ctx.bands.len();

    // Sun.
    let s = &f.sun;
    if !finite_in(s.zenith_deg, 0.0, 89.0) {
        return Err(ctx.err(
            &[K("sun"), K("zenith_deg")],
            "must be between 0 and 89 degrees",
        ));
    }
    if !s.azimuth_deg.is_finite() {
        return Err(ctx.err(&[K("sun"), K("azimuth_deg")], "must be a finite angle"));
    }
    let sun_irr = match (&s.spectrum, s.irradiance) {
        (Some(name), None) => match name.as_str() {
            "astm-g173-direct" => ctx.per_band(tables::solar(SolarSpectrum::DirectCircumsolar), &[K("sun"), K("spectrum")])?,
            "astm-g173-extraterrestrial" => ctx.per_band(tables::solar(SolarSpectrum::Extraterrestrial), &[K("sun"), K("spectrum")])?,
            csv if csv.ends_with(".csv") => {
                let t = Table::from_csv_file(&ctx.path(csv), "sun.spectrum")?;
                ctx.per_band(&t, &[K("sun"), K("spectrum")])?
            }
            other => return Err(ctx.err(&[K("sun"), K("spectrum")], format!("'{other}': use \"astm-g173-direct\", \"astm-g173-extraterrestrial\" or a .csv file"))),
        },
        (None, Some(e)) if finite_in(e, 0.0, f64::MAX) => vec![e; nb],
        (None, Some(_)) => return Err(ctx.err(&[K("sun"), K("irradiance")], "must be >= 0")),
        (None, None) => return Err(ctx.err(&[K("sun")], "give spectrum or irradiance")),
        (Some(_), Some(_)) => return Err(ctx.err(&[K("sun"), K("irradiance")], "give spectrum or irradiance, not both")),
    };
    let (zen, az) = (s.zenith_deg.to_radians(), s.azimuth_deg.to_radians());
    let toward_sun = Vec3::new(
        (zen.sin() * az.cos()) as f32,
        (zen.sin() * az.sin()) as f32,
        zen.cos() as f32,
    );
    let sun = Sun {
        zenith_rad: zen,
        azimuth_rad: az,
        direction: -toward_sun.normalize(),
        irradiance: sun_irr,
    };

    // Sky.
    let sky_irr = match (&f.sky.spectrum, f.sky.radiance) {
        (None, None) => vec![0.0; nb],
        (Some(n), None) if n == "none" => vec![0.0; nb],
        (Some(n), None) if n == "astm-g173-diffuse" => ctx.per_band(tables::sky_diffuse_irradiance(), &[K("sky"), K("spectrum")])?,
        (Some(n), None) if n.ends_with(".csv") => {
            let t = Table::from_csv_file(&ctx.path(n), "sky.spectrum")?;
            ctx.per_band(&t, &[K("sky"), K("spectrum")])?
        }
        (Some(n), None) => return Err(ctx.err(&[K("sky"), K("spectrum")], format!("'{n}': use \"none\", \"astm-g173-diffuse\" or a .csv file of horizontal irradiance"))),
        (None, Some(l)) if finite_in(l, 0.0, f64::MAX) => vec![std::f64::consts::PI * l; nb],
        (None, Some(_)) => return Err(ctx.err(&[K("sky"), K("radiance")], "must be >= 0")),
        (Some(_), Some(_)) => return Err(ctx.err(&[K("sky"), K("radiance")], "give spectrum or radiance, not both")),
    };
    let sky = Sky {
        irradiance: sky_irr,
    };

    // Surface.
    let n_water = f.surface.refractive_index.unwrap_or(1.34);
    if !finite_in(n_water, 1.0, 2.0) {
        return Err(ctx.err(
            &[K("surface"), K("refractive_index")],
            "must be between 1 and 2",
        ));
    }
    let wind = f.surface.wind_speed.unwrap_or(0.0);
    if !finite_in(wind, 0.0, 30.0) {
        return Err(ctx.err(
            &[K("surface"), K("wind_speed")],
            "must be between 0 and 30 m/s",
        ));
    }
    let surface = match f.surface.kind.as_deref() {
        None | Some("flat") => SeaSurface::flat(n_water),
        Some("cox-munk") => SeaSurface::cox_munk(n_water, wind),
        Some(o) => {
            return Err(ctx.err(
                &[K("surface"), K("kind")],
                format!("'{o}': use \"flat\" or \"cox-munk\""),
            ))
        }
    };

    // Domain.
    let size = f.domain.size_m;
    if !size.iter().all(|&v| finite_in(v, 1e-3, 1e7)) {
        return Err(ctx.err(&[K("domain"), K("size_m")], "sizes must be positive (m)"));
    }
    let periodic = match f.domain.edges.as_deref() {
        None | Some("periodic") => true,
        Some("open") => false,
        Some(o) => {
            return Err(ctx.err(
                &[K("domain"), K("edges")],
                format!("'{o}': use \"periodic\" or \"open\""),
            ))
        }
    };
    let domain = Domain {
        size_m: size,
        periodic,
    };

    let (water, particle_phase) = water(&ctx, &f.water, &domain)?;
    let water_phase = PhaseFunction::rayleigh(crate::optics::phase::RAYLEIGH_Q_WATER)
        .expect("the pure-water q is valid");

    // Geometry: floor and targets.
    let mut geo = GeometryBuilder::new([size[0] as f32, size[1] as f32]);
    let bottom = match &f.bottom {
        None => None,
        Some(b) => {
            let bk = |k| [K("bottom"), K(k)];
            match (b.depth_m, &b.slope, &b.heightfield) {
                (Some(d), None, None) => {
                    if !finite_in(d, 1e-3, 1e5) {
                        return Err(ctx.err(&bk("depth_m"), "must be a positive depth (m)"));
                    }
                    geo.flat_floor(d as f32, FLOOR);
                }
                (None, Some(s), None) => {
                    let sk = |k| [K("bottom"), K("slope"), K(k)];
                    for (k, v) in [
                        ("from_depth_m", s.from_depth_m),
                        ("to_depth_m", s.to_depth_m),
                    ] {
                        if !finite_in(v, 1e-3, 1e5) {
                            return Err(ctx.err(&sk(k), "must be a positive depth (m)"));
                        }
                    }
                    let axis = match s.axis.as_deref() {
                        None | Some("x") => Axis::X,
                        Some("y") => Axis::Y,
                        Some(o) => {
                            return Err(ctx.err(&sk("axis"), format!("'{o}': use \"x\" or \"y\"")))
                        }
                    };
                    geo.slope_floor(s.from_depth_m as f32, s.to_depth_m as f32, axis, FLOOR);
                }
                (None, None, Some(h)) => {
                    let (depths, nx, ny) = GeometryBuilder::heightfield_from_csv(&ctx.path(h))?;
                    geo.heightfield_floor(&depths, nx, ny, FLOOR)
                        .map_err(|e| ctx.err(&bk("heightfield"), e.to_string()))?;
                }
                _ => {
                    return Err(ctx.err(
                        &[K("bottom")],
                        "give exactly one of depth_m, slope or heightfield",
                    ))
                }
            }
            let refl = b.reflectance.clone().unwrap_or(Reflectance::Constant(0.2));
            let reflectance = ctx.reflectance(&refl, &bk("reflectance"))?;
            let mut patches = Vec::new();
            for (i, p) in b.patch.iter().enumerate() {
                let steps = [K("bottom"), K("patch"), I(i), K("reflectance")];
                if !(p.min_m[0] < p.max_m[0] && p.min_m[1] < p.max_m[1]) {
                    return Err(ctx.err(
                        &[K("bottom"), K("patch"), I(i), K("max_m")],
                        "max_m must exceed min_m",
                    ));
                }
                patches.push(Patch {
                    min_m: p.min_m,
                    max_m: p.max_m,
                    reflectance: ctx.reflectance(&p.reflectance, &steps)?,
                });
            }
            Some(Bottom {
                reflectance,
                patches,
            })
        }
    };
    let mut target_reflectance = Vec::new();
    for (i, t) in f.target.iter().enumerate() {
        let tk = |k| [K("target"), I(i), K(k)];
        let id = (i + 1) as SurfaceId;
        let c = Vec3::new(
            t.center_m[0] as f32,
            t.center_m[1] as f32,
            t.center_m[2] as f32,
        );
        if !c.is_finite() || c.z > 0.0 {
            return Err(ctx.err(&tk("center_m"), "must be finite and under water (z <= 0)"));
        }
        let size = t.size_m.clone().unwrap_or_default();
        let positive = size.iter().all(|&v| finite_in(v, 1e-4, 1e5));
        match t.kind.as_str() {
            "box" if size.len() == 3 && positive => geo.add_box(
                c,
                Vec3::new(size[0] as f32, size[1] as f32, size[2] as f32),
                id,
            ),
            "panel" if size.len() == 2 && positive => {
                geo.add_panel(c, [size[0] as f32, size[1] as f32], id)
            }
            "box" => return Err(ctx.err(&tk("size_m"), "a box needs size_m = [x, y, z] > 0")),
            "panel" => return Err(ctx.err(&tk("size_m"), "a panel needs size_m = [x, y] > 0")),
            "mesh" => {
                let file = t
                    .file
                    .as_ref()
                    .ok_or_else(|| ctx.err(&tk("file"), "a mesh needs file = \"mesh.obj\""))?;
                let scale = t.scale.unwrap_or(1.0);
                if !finite_in(scale, 1e-6, 1e6) {
                    return Err(ctx.err(&tk("scale"), "must be positive"));
                }
                geo.add_obj(&ctx.path(file), c, scale as f32, id)?;
            }
            o => {
                return Err(ctx.err(
                    &tk("kind"),
                    format!("'{o}': use \"box\", \"panel\" or \"mesh\""),
                ))
            }
        }
        target_reflectance.push(ctx.reflectance(&t.reflectance, &tk("reflectance"))?);
    }
    let geometry = geo.build();
    let (sensor, radiometers, estimate) = render_settings(&ctx, &f, &domain, ov)?;
    let mut inputs = ctx.inputs.take();
    inputs.sort();
    inputs.dedup();

    if f.photons.count == 0 {
        return Err(ctx.err(&[K("photons"), K("count")], "must be at least 1"));
    }
    let mut tally_depths = f.tally.depths_m.clone();
    for (i, d) in tally_depths.iter().enumerate() {
        if !finite_in(*d, 0.0, 1e5) {
            return Err(ctx.err(
                &[K("tally"), K("depths_m"), I(i)],
                "depths must be >= 0 (m)",
            ));
        }
    }
    tally_depths.sort_by(f64::total_cmp);
    tally_depths.dedup();
    if f.name.trim().is_empty() || f.name.contains(['/', '\\']) {
        return Err(ctx.err(
            &[K("name")],
            "must be a non-empty name without path separators",
        ));
    }

    Ok(Scene {
        name: f.name,
        seed: f.seed,
        bands: ctx.bands.clone(),
        sun,
        sky,
        surface,
        domain,
        water,
        particle_phase,
        water_phase,
        bottom,
        target_reflectance,
        geometry,
        photons: f.photons.count,
        store_direct: f.photons.store_direct,
        tally_depths,
        sensor,
        radiometers,
        estimate,
        inputs,
    })
}

fn phase(ctx: &Ctx, p: Option<&PhaseFile>) -> Result<PhaseFunction> {
    let Some(p) = p else {
        return PhaseFunction::fournier_forand(0.0183)
            .map_err(|e| ctx.err(&[K("water")], e.to_string()));
    };
    let pk = |k| [K("water"), K("phase"), K(k)];
    let wrap = |k, r: Result<PhaseFunction>| r.map_err(|e| ctx.err(&pk(k), e.to_string()));
    match p.kind.as_str() {
        "fournier-forand" => wrap("bb_ratio", PhaseFunction::fournier_forand(p.bb_ratio.unwrap_or(0.0183))),
        "petzold" => Ok(PhaseFunction::petzold()),
        "rayleigh" => wrap("q", PhaseFunction::rayleigh(p.q.unwrap_or(crate::optics::phase::RAYLEIGH_Q_WATER))),
        "isotropic" => Ok(PhaseFunction::isotropic()),
        "henyey-greenstein" => {
            let g = p.g.ok_or_else(|| ctx.err(&pk("g"), "henyey-greenstein needs g"))?;
            wrap("g", PhaseFunction::henyey_greenstein(g))
        }
        "table" => {
            let file = p.file.as_ref().ok_or_else(|| ctx.err(&pk("file"), "a table needs file = \"angle_deg,value CSV\""))?;
            let t = Table::from_csv_file(&ctx.path(file), "water.phase.file")?;
            let (angles, values) = (t.x_nm(), t.y());
            wrap("file", PhaseFunction::tabulated(angles, values, "water.phase.file"))
        }
        o => Err(ctx.err(&pk("kind"), format!("'{o}': use fournier-forand, petzold, rayleigh, isotropic, henyey-greenstein or table"))),
    }
}

fn water(ctx: &Ctx, w: &WaterFile, domain: &Domain) -> Result<(WaterModel, PhaseFunction)> {
    let wk = |k| [K("water"), K(k)];
    let particle_phase = phase(ctx, w.phase.as_ref())?;
    if let Some(iop) = &w.iop {
        let constituents = [w.chl, w.cdom_440, w.nap_440, w.bp_550]
            .iter()
            .any(Option::is_some)
            || w.gradient.is_some()
            || !w.layer.is_empty()
            || w.grid.is_some();
        if constituents {
            return Err(ctx.err(&wk("iop"), "explicit IOPs exclude constituents (chl, cdom_440, nap_440, bp_550, gradient, layer, grid)"));
        }
        if !finite_in(iop.a, 0.0, 1e4) || iop.a <= 0.0 && iop.b <= 0.0 {
            return Err(ctx.err(
                &[K("water"), K("iop"), K("a")],
                "must be >= 0 with a + b > 0 (1/m)",
            ));
        }
        if !finite_in(iop.b, 0.0, 1e4) {
            return Err(ctx.err(&[K("water"), K("iop"), K("b")], "must be >= 0 (1/m)"));
        }
        return Ok((WaterModel::Explicit { a: iop.a, b: iop.b }, particle_phase));
    }
    for (k, v) in [
        ("chl", w.chl),
        ("cdom_440", w.cdom_440),
        ("nap_440", w.nap_440),
        ("bp_550", w.bp_550),
    ] {
        if let Some(v) = v {
            if !finite_in(v, 0.0, 1e4) {
                return Err(ctx.err(&wk(k), "must be >= 0"));
            }
        }
    }
    for (k, v) in [
        ("cdom_slope", w.cdom_slope),
        ("nap_slope", w.nap_slope),
        ("bp_slope", w.bp_slope),
    ] {
        if let Some(v) = v {
            if !finite_in(v, 0.0, 10.0) {
                return Err(ctx.err(&wk(k), "must be between 0 and 10"));
            }
        }
    }
    let base = Constituents {
        chl: w.chl.unwrap_or(0.0),
        cdom_440: w.cdom_440.unwrap_or(0.0),
        nap_440: w.nap_440.unwrap_or(0.0),
    };
    let field = match (&w.gradient, w.layer.is_empty(), &w.grid) {
        (None, true, None) => ConstituentField::Uniform(base),
        (Some(g), true, None) => {
            let gk = |k| [K("water"), K("gradient"), K(k)];
            let axis = match g.axis.as_str() {
                "x" => 0,
                "y" => 1,
                o => return Err(ctx.err(&gk("axis"), format!("'{o}': use \"x\" or \"y\""))),
            };
            let pair = |k: &'static str, v: Option<[f64; 2]>, d: f64| -> Result<[f64; 2]> {
                let v = v.unwrap_or([d, d]);
                if v.iter().all(|&x| finite_in(x, 0.0, 1e4)) {
                    Ok(v)
                } else {
                    Err(ctx.err(&gk(k), "values must be >= 0"))
                }
            };
            let chl = pair("chl", g.chl, base.chl)?;
            let cdom = pair("cdom_440", g.cdom_440, base.cdom_440)?;
            let nap = pair("nap_440", g.nap_440, base.nap_440)?;
            ConstituentField::Gradient {
                axis,
                size_m: domain.size_m[axis],
                from: Constituents {
                    chl: chl[0],
                    cdom_440: cdom[0],
                    nap_440: nap[0],
                },
                to: Constituents {
                    chl: chl[1],
                    cdom_440: cdom[1],
                    nap_440: nap[1],
                },
            }
        }
        (None, false, None) => {
            let mut layers = Vec::new();
            for (i, l) in w.layer.iter().enumerate() {
                let lk = |k| [K("water"), K("layer"), I(i), K(k)];
                if !(finite_in(l.top_m, 0.0, 1e5)
                    && finite_in(l.bottom_m, 0.0, 1e5)
                    && l.bottom_m > l.top_m)
                {
                    return Err(ctx.err(&lk("bottom_m"), "need 0 <= top_m < bottom_m (m)"));
                }
                let c = Constituents {
                    chl: l.chl.unwrap_or(base.chl),
                    cdom_440: l.cdom_440.unwrap_or(base.cdom_440),
                    nap_440: l.nap_440.unwrap_or(base.nap_440),
                };
                if ![c.chl, c.cdom_440, c.nap_440]
                    .iter()
                    .all(|&v| finite_in(v, 0.0, 1e4))
                {
                    return Err(ctx.err(&lk("chl"), "concentrations must be >= 0"));
                }
                layers.push((l.top_m, l.bottom_m, c));
            }
            ConstituentField::Layers { base, layers }
        }
        (None, true, Some(g)) => ConstituentField::Grid(read_grid(&ctx.path(g))?),
        _ => {
            return Err(ctx.err(
                &[K("water")],
                "give at most one of gradient, layer and grid",
            ))
        }
    };
    let centers: Vec<f64> = ctx.bands.centers_nm().iter().map(|&c| c as f64).collect();
    let (a_phi_a, a_phi_e) = tables::bricaud_a_phi();
    let s_g = w.cdom_slope.unwrap_or(0.015);
    let s_nap = w.nap_slope.unwrap_or(0.011);
    let n_bp = w.bp_slope.unwrap_or(1.0);
    let spectra = BandSpectra {
        a_w: ctx.per_band(tables::water_absorption(), &wk("chl"))?,
        b_w: ctx.per_band(tables::seawater_scattering(), &wk("chl"))?,
        a_phi_a: ctx.per_band(a_phi_a, &wk("chl"))?,
        a_phi_e: ctx.per_band(a_phi_e, &wk("chl"))?,
        cdom_shape: centers.iter().map(|l| (-s_g * (l - 440.0)).exp()).collect(),
        nap_shape: centers
            .iter()
            .map(|l| (-s_nap * (l - 440.0)).exp())
            .collect(),
        bp_shape: centers.iter().map(|l| (550.0 / l).powf(n_bp)).collect(),
    };
    Ok((
        WaterModel::Constituents {
            spectra: Box::new(spectra),
            field,
            bp_550: w.bp_550,
        },
        particle_phase,
    ))
}

/// A constituent grid CSV: header `x_m,y_m,depth_m,chl,cdom_440,nap_440`,
/// one row per node of a full regular grid, in any order.
fn read_grid(path: &Path) -> Result<ConstituentGrid> {
    let csv = crate::csv::read(path, "water.grid")?;
    csv.expect_header(&["x_m", "y_m", "depth_m", "chl", "cdom_440", "nap_440"])?;
    let bad = |line: Option<usize>, what: String| csv.error(line, what);
    let mut rows: Vec<[f64; 6]> = Vec::new();
    for row in &csv.rows {
        let v = csv.numbers(row)?;
        if v[3..].iter().any(|&x| x < 0.0) {
            return Err(bad(Some(row.line), "concentrations must be >= 0".into()));
        }
        rows.push([v[0], v[1], v[2], v[3], v[4], v[5]]);
    }
    let axis = |k: usize| {
        let mut v: Vec<f64> = rows.iter().map(|r| r[k]).collect();
        v.sort_by(f64::total_cmp);
        v.dedup();
        v
    };
    let (xs, ys, ds) = (axis(0), axis(1), axis(2));
    if rows.is_empty() || xs.len() * ys.len() * ds.len() != rows.len() {
        return Err(bad(
            None,
            format!(
                "{} rows do not form a full {}x{}x{} grid",
                rows.len(),
                xs.len(),
                ys.len(),
                ds.len()
            ),
        ));
    }
    let mut values = vec![None; rows.len()];
    for r in &rows {
        let i = xs.partition_point(|&x| x < r[0]);
        let j = ys.partition_point(|&y| y < r[1]);
        let k = ds.partition_point(|&d| d < r[2]);
        let slot = &mut values[i + xs.len() * (j + ys.len() * k)];
        if slot.is_some() {
            return Err(bad(
                None,
                format!("node ({}, {}, {}) appears twice", r[0], r[1], r[2]),
            ));
        }
        *slot = Some(Constituents {
            chl: r[3],
            cdom_440: r[4],
            nap_440: r[5],
        });
    }
    Ok(ConstituentGrid {
        xs,
        ys,
        depths: ds,
        values: values.into_iter().map(|v| v.unwrap_or_default()).collect(),
    })
}
