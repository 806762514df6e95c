//! Validation of the water column: `[water]` (explicit IOPs or
//! constituents, their gradient, layers or grid) and the particle phase
//! function.

use super::*;
use crate::optics::inelastic::{Inelastic, Kind, CHL_QUANTUM_YIELD};

fn phase(ctx: &Ctx, p: Option<&PhaseFile>) -> Result<PhaseFunction> {
    let Some(p) = p else {
        return PhaseFunction::fournier_forand(0.0183)
            .map_err(|e| ctx.err(&[K("water")], e.to_string()));
    };
    let pk = |k| [K("water"), K("phase"), K(k)];
    let wrap = |k, r: Result<PhaseFunction>| r.map_err(|e| ctx.err(&pk(k), e.to_string()));
    match p.kind {
        PhaseKind::FournierForand => wrap(
            "bb_ratio",
            PhaseFunction::fournier_forand(p.bb_ratio.unwrap_or(0.0183)),
        ),
        PhaseKind::Petzold => Ok(PhaseFunction::petzold()),
        PhaseKind::Rayleigh => wrap(
            "q",
            PhaseFunction::rayleigh(p.q.unwrap_or(crate::optics::phase::RAYLEIGH_Q_WATER)),
        ),
        PhaseKind::Isotropic => Ok(PhaseFunction::isotropic()),
        PhaseKind::HenyeyGreenstein => {
            let g =
                p.g.ok_or_else(|| ctx.err(&pk("g"), "henyey-greenstein needs g"))?;
            wrap("g", PhaseFunction::henyey_greenstein(g))
        }
        PhaseKind::Table => {
            let file = p.file.as_ref().ok_or_else(|| {
                ctx.err(&pk("file"), "a table needs file = \"angle_deg,value CSV\"")
            })?;
            let t = Table::from_csv_file(&ctx.file(file, &pk("file"))?, "water.phase.file")?;
            let (angles, values) = (t.x_nm(), t.y());
            wrap(
                "file",
                PhaseFunction::tabulated(angles, values, "water.phase.file"),
            )
        }
    }
}

/// Explicit IOPs exclude every constituent setting.
fn reject_constituents(ctx: &Ctx, w: &WaterFile, key: &'static str) -> Result<()> {
    let constituents = [w.chl, w.cdom_440, w.nap_440, w.bp_550]
        .iter()
        .any(Option::is_some)
        || w.gradient.is_some()
        || !w.layer.is_empty()
        || w.grid.is_some();
    if constituents {
        let what = "explicit IOPs exclude constituents (chl, cdom_440, nap_440, bp_550, gradient, layer, grid)";
        return Err(ctx.err(&[K("water"), K(key)], what));
    }
    Ok(())
}

/// `[water] iop_file`: a, b and (optionally) bb/b against wavelength,
/// band-averaged like every spectrum of the scene (b_b = b bb/b averaged,
/// so a band's bb/b is its average b_b over its average b), split between
/// the two phase functions by [`Iop::with_backscatter_fraction`]. Without a
/// bb_ratio column all scattering uses the particle phase function, as
/// `iop = { a, b }` does.
fn iop_table(
    ctx: &Ctx,
    file: &str,
    water_phase: &PhaseFunction,
    particle_phase: &PhaseFunction,
) -> Result<Vec<Iop>> {
    let steps = [K("water"), K("iop_file")];
    let path = ctx.file(file, &steps)?;
    let field = "water.iop_file";
    let t = crate::csv::read(&path, field)?;
    let col = |name: &str| t.column(name);
    let (cx, ca, cb) = (col("wavelength_nm")?, col("a")?, col("b")?);
    let cr = t
        .header
        .as_ref()
        .is_some_and(|(_, h)| h.iter().any(|c| c == "bb_ratio"))
        .then(|| col("bb_ratio"))
        .transpose()?;
    let (mut x, mut a, mut b, mut bb) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for row in &t.rows {
        let num = |c| t.number(row, c);
        let (nm, av, bv) = (num(cx)?, num(ca)?, num(cb)?);
        if av < 0.0 || bv < 0.0 {
            return Err(t.error(Some(row.line), "a and b must be >= 0 (1/m)"));
        }
        let r = match cr {
            Some(c) => {
                let r = num(c)?;
                if !(0.0..=1.0).contains(&r) {
                    return Err(t.error(Some(row.line), "bb_ratio must lie in [0, 1]"));
                }
                r
            }
            None => particle_phase.backscatter_fraction(),
        };
        x.push(nm);
        a.push(av);
        b.push(bv);
        bb.push(bv * r);
    }
    let table = |name: &str, y: Vec<f64>| {
        crate::optics::tables::Table::new(name, x.clone(), y)
            .map_err(|e| ctx.err(&steps, e.to_string()))
    };
    let a = ctx.per_band(&table("a", a)?, &steps)?;
    let b = ctx.per_band(&table("b", b)?, &steps)?;
    let bb = ctx.per_band(&table("bb", bb)?, &steps)?;
    let (r_w, r_p) = (
        water_phase.backscatter_fraction(),
        particle_phase.backscatter_fraction(),
    );
    let mut iops = Vec::with_capacity(a.len());
    for (band, ((&a, &b), &bb)) in a.iter().zip(&b).zip(&bb).enumerate() {
        if a + b <= 0.0 {
            return Err(ctx.err(&steps, format!("band {band}: a + b must be > 0 (1/m)")));
        }
        if cr.is_none() {
            iops.push(Iop {
                a,
                b_w: 0.0,
                b_p: b,
            });
            continue;
        }
        let r = if b > 0.0 { bb / b } else { r_p };
        let nm = ctx.bands.centers_nm()[band];
        iops.push(
            Iop::with_backscatter_fraction(a, b, r, r_w, r_p)
                .map_err(|e| ctx.err(&steps, format!("{file}, band {band} ({nm} nm): {e}")))?,
        );
    }
    Ok(iops)
}

pub(super) fn water(
    ctx: &Ctx,
    w: &WaterFile,
    domain: &Domain,
    water_phase: &PhaseFunction,
) -> Result<(WaterModel, PhaseFunction)> {
    let wk = |k| [K("water"), K(k)];
    let particle_phase = phase(ctx, w.phase.as_ref())?;
    if let Some(file) = &w.iop_file {
        if w.iop.is_some() {
            return Err(ctx.err(&wk("iop_file"), "give iop or iop_file, not both"));
        }
        let iops = iop_table(ctx, file, water_phase, &particle_phase)?;
        reject_constituents(ctx, w, "iop_file")?;
        return Ok((WaterModel::Bands(iops), particle_phase));
    }
    if let Some(iop) = &w.iop {
        reject_constituents(ctx, w, "iop")?;
        let (ak, bk) = (
            [K("water"), K("iop"), K("a")],
            [K("water"), K("iop"), K("b")],
        );
        ctx.within(&ak, iop.a, 0.0, 1e4, "must be >= 0", "1/m")?;
        ctx.within(&bk, iop.b, 0.0, 1e4, "must be >= 0", "1/m")?;
        if iop.a <= 0.0 && iop.b <= 0.0 {
            return Err(ctx.err(&ak, "a + b must be > 0 (1/m)"));
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
            ctx.within(&wk(k), v, 0.0, 1e4, "must be >= 0", "")?;
        }
    }
    for (k, v) in [
        ("cdom_slope", w.cdom_slope),
        ("nap_slope", w.nap_slope),
        ("bp_slope", w.bp_slope),
    ] {
        if let Some(v) = v {
            ctx.within(&wk(k), v, 0.0, 10.0, "must be >= 0", "")?;
        }
    }
    let base = Constituents {
        chl: w.chl.unwrap_or(0.0),
        cdom_440: w.cdom_440.unwrap_or(0.0),
        nap_440: w.nap_440.unwrap_or(0.0),
    };
    let field = match (&w.gradient, w.layer.is_empty(), &w.grid) {
        (None, true, None) => ConstituentField::Uniform(base),
        (Some(g), true, None) => gradient(ctx, g, &base, domain)?,
        (None, false, None) => layers(ctx, &w.layer, base)?,
        (None, true, Some(g)) => ConstituentField::Grid(read_grid(&ctx.file(g, &wk("grid"))?)?),
        _ => {
            return Err(ctx.err(
                &[K("water")],
                "give at most one of gradient, layer and grid",
            ))
        }
    };
    let spectra = band_spectra(ctx, w)?;
    Ok((
        WaterModel::Constituents {
            spectra: Box::new(spectra),
            field,
            bp_550: w.bp_550,
        },
        particle_phase,
    ))
}

/// `[water.gradient]`: the constituents varying linearly along x or y
/// (each end defaulting to the water's own values).
fn gradient(
    ctx: &Ctx,
    g: &GradientFile,
    base: &Constituents,
    domain: &Domain,
) -> Result<ConstituentField> {
    let gk = |k| [K("water"), K("gradient"), K(k)];
    let axis = match g.axis {
        Axis::X => 0,
        Axis::Y => 1,
    };
    let pair = |k: &'static str, v: Option<[f64; 2]>, d: f64| -> Result<[f64; 2]> {
        let v = v.unwrap_or([d, d]);
        for x in v {
            ctx.within(&gk(k), x, 0.0, 1e4, "values must be >= 0", "")?;
        }
        Ok(v)
    };
    let chl = pair("chl", g.chl, base.chl)?;
    let cdom = pair("cdom_440", g.cdom_440, base.cdom_440)?;
    let nap = pair("nap_440", g.nap_440, base.nap_440)?;
    Ok(ConstituentField::Gradient {
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
    })
}

/// `[[water.layer]]`: depth layers of their own constituents over `base`,
/// not overlapping.
fn layers(ctx: &Ctx, file: &[LayerFile], base: Constituents) -> Result<ConstituentField> {
    let mut layers = Vec::new();
    for (i, l) in file.iter().enumerate() {
        let lk = |k| [K("water"), K("layer"), I(i), K(k)];
        ctx.within(&lk("top_m"), l.top_m, 0.0, 1e5, "must be a depth >= 0", "m")?;
        ctx.within(
            &lk("bottom_m"),
            l.bottom_m,
            0.0,
            1e5,
            "must be a depth >= 0",
            "m",
        )?;
        if l.bottom_m <= l.top_m {
            return Err(ctx.err(&lk("bottom_m"), "need top_m < bottom_m (m)"));
        }
        for (k, v) in [
            ("chl", l.chl),
            ("cdom_440", l.cdom_440),
            ("nap_440", l.nap_440),
        ] {
            if let Some(v) = v {
                ctx.within(&lk(k), v, 0.0, 1e4, "concentrations must be >= 0", "")?;
            }
        }
        let c = Constituents {
            chl: l.chl.unwrap_or(base.chl),
            cdom_440: l.cdom_440.unwrap_or(base.cdom_440),
            nap_440: l.nap_440.unwrap_or(base.nap_440),
        };
        // Layers may not overlap: which one would hold the water
        // between?
        if let Some((j, (top, bottom, _))) = layers
            .iter()
            .enumerate()
            .find(|(_, (t, b, _))| l.top_m < *b && *t < l.bottom_m)
        {
            return Err(ctx.err(
                &lk("top_m"),
                format!(
                    "water.layer[{i}] ({} to {} m) overlaps water.layer[{j}] ({top} to {bottom} m)",
                    l.top_m, l.bottom_m
                ),
            ));
        }
        layers.push((l.top_m, l.bottom_m, c));
    }
    Ok(ConstituentField::Layers { base, layers })
}

/// The constituents' spectra on the band grid: pure water's absorption and
/// scattering, Bricaud's phytoplankton absorption, and the CDOM, NAP and
/// particle-scattering shapes.
fn band_spectra(ctx: &Ctx, w: &WaterFile) -> Result<BandSpectra> {
    let centers: Vec<f64> = ctx.bands.centers_nm().iter().map(|&c| c as f64).collect();
    let (a_phi_a, a_phi_e) = tables::bricaud_a_phi();
    let s_g = w.cdom_slope.unwrap_or(0.015);
    let s_nap = w.nap_slope.unwrap_or(0.011);
    let n_bp = w.bp_slope.unwrap_or(1.0);
    let spectra = BandSpectra {
        a_w: ctx.per_band_shipped(tables::water_absorption())?,
        b_w: ctx.per_band_shipped(tables::seawater_scattering())?,
        a_phi_a: ctx.per_band_shipped(a_phi_a)?,
        a_phi_e: ctx.per_band_shipped(a_phi_e)?,
        cdom_shape: centers.iter().map(|l| (-s_g * (l - 440.0)).exp()).collect(),
        nap_shape: centers
            .iter()
            .map(|l| (-s_nap * (l - 440.0)).exp())
            .collect(),
        bp_shape: centers.iter().map(|l| (550.0 / l).powf(n_bp)).collect(),
    };
    Ok(spectra)
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

/// `[water] raman` and `[water.fluorescence]`: the inelastic processes on
/// the band grid, or None. Each is part of the water's absorption
/// (`optics::inelastic`), so water absorbing less than b_R somewhere in a
/// band is refused, and fluorescence needs water given by its
/// constituents (it draws on their absorption).
pub(super) fn inelastic(ctx: &Ctx, w: &WaterFile, water: &WaterModel) -> Result<Option<Inelastic>> {
    let mut kinds = Vec::new();
    // Raman scattering is the water's own: on by default where the water
    // is given by its constituents. Water given by its IOPs stands for a
    // medium whose absorption the user measured or chose, whose inelastic
    // part littoral cannot know; it stays elastic unless asked.
    let constituents = matches!(water, WaterModel::Constituents { .. });
    if w.raman.unwrap_or(constituents) {
        kinds.push(Kind::Raman);
    }
    let mut chl_yield = CHL_QUANTUM_YIELD;
    if let Some(f) = &w.fluorescence {
        if !constituents {
            return Err(ctx.err(
                &[K("water"), K("fluorescence")],
                "fluorescence draws on the light phytoplankton and CDOM absorb: it needs water given by its constituents (chl, cdom_440), not by iop or iop_file",
            ));
        }
        if let Some(y) = f.chl_quantum_yield {
            if !(0.0..=1.0).contains(&y) {
                return Err(ctx.err(
                    &[K("water"), K("fluorescence"), K("chl_quantum_yield")],
                    format!("{y}: a quantum yield lies from 0 to 1"),
                ));
            }
            chl_yield = y;
        }
        if chl_yield > 0.0 {
            kinds.push(Kind::Chlorophyll);
        }
        if f.cdom.unwrap_or(false) {
            kinds.push(Kind::Cdom);
        }
    }
    if kinds.is_empty() {
        return Ok(None);
    }
    let mut r = Inelastic::new(&ctx.bands, &kinds, chl_yield);
    if let Some(raman) = r.process(Kind::Raman) {
        for (b, &b_r) in raman.scale.iter().enumerate() {
            let a = water.absorption_minorant(b);
            if a < b_r {
                return Err(ctx.err(
                    &[K("water"), K("raman")],
                    format!(
                        "the water absorbs {a:.3e} 1/m at {} nm somewhere, less than the Raman scattering coefficient {b_r:.3e} 1/m that is part of its absorption",
                        ctx.bands.centers_nm()[b]
                    ),
                ));
            }
        }
    }
    let max: Vec<_> = (0..ctx.bands.len())
        .map(|b| water.absorbers_max(b))
        .collect();
    r.bound_gains(&max);
    Ok(Some(r))
}
