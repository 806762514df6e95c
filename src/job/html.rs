//! The run's HTML report, `NAME.html` beside the JSON: one self-contained
//! page (no scripts, no network: the quicklook is a data URI, the plots
//! inline SVG drawn by plotters) for a person to look at.
//!
//! It shows the quicklook; R_rs at five pixels (the centre and the four
//! quarter points) and L / E_d(0+) at each radiometer, each with a band of
//! plus and minus one standard error; with the sensor above the surface,
//! the reflectance at the sensor rho_t at the same pixels beside the path
//! reflectance, and the air's transmittances; E_d, E_u, E_ou and L_u against depth
//! and K_d per band (photon-map runs: the emission's tallies); the energy
//! budget per band as fractions of the emitted power; the cache, timing and
//! memory figures; and the run's settings.
//!
//! Choices: a pixel's R_rs standard error is the L_t standard-error cube
//! over E_d(0+) (the surface-reflected part adds only sampling noise of
//! its own, which that cube also holds). Profiles show at most five bands,
//! evenly spread over the grid. Text in the SVG is laid out with DejaVu
//! Sans (embedded, `data/fonts`) and drawn by the browser's sans-serif.
//!
//! Not for: numbers a program reads (the JSON report has them all).

use super::report::RunReport;
use crate::emit::report::EmissionReport;
use crate::error::{Error, Result};
use crate::scene::Scene;
use base64::Engine;
use plotters::prelude::*;
use std::fmt::Write as _;
use std::path::Path;
use std::sync::Once;

/// The font plotters measures text with.
static FONT: &[u8] = include_bytes!("../../data/fonts/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

const WIDTH: u32 = 720;
const HEIGHT: u32 = 380;
/// Line colours (Okabe–Ito, distinguishable with colour-blindness).
const COLOURS: [RGBColor; 7] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(0, 0, 0),
];

/// One curve: a label, x values, y values and an optional half-width band.
struct Curve {
    label: String,
    x: Vec<f64>,
    y: Vec<f64>,
    err: Option<Vec<f64>>,
}

/// Axes of one plot.
struct Axes<'a> {
    title: &'a str,
    x_label: &'a str,
    y_label: &'a str,
    /// Depth plots put x (the quantity) on a log scale and y (depth) down.
    depth: bool,
}

/// Write `NAME.html` for a finished render at `path`, reading the files
/// the report lists from `files` (where they are before publication: the
/// names in the report are the final ones).
pub fn write(scene: &Scene, report: &RunReport, files: &Path, path: &Path) -> Result<()> {
    let page = page(scene, report, files)?;
    crate::output::write_atomic(path, page.as_bytes())
}

/// The file the report lists as `listed`, in `files`.
fn listed_in(files: &Path, listed: &str) -> std::path::PathBuf {
    files.join(Path::new(listed).file_name().unwrap_or_default())
}

/// The page's HTML (the files the report lists read from `files`).
pub fn page(scene: &Scene, report: &RunReport, files: &Path) -> Result<String> {
    let nm: Vec<f64> = scene.bands.centers_nm().iter().map(|&c| c as f64).collect();
    let mut h = String::new();
    let title = format!("littoral: {}", scene.name);
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <title>{}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n<h1>{}</h1>\n<p>{}</p>\n",
        esc(&title),
        esc(&title),
        esc(&report.summary())
    );

    // The quicklook.
    let png_path = listed_in(files, &report.outputs.png);
    let png = std::fs::read(&png_path).map_err(|e| Error::io(&png_path, "read", e))?;
    let _ = write!(
        h,
        "<h2>Quicklook</h2>\n<img alt=\"quicklook of {}\" src=\"data:image/png;base64,{}\">\n\
         <p class=\"note\">Row 0 (top) is the high-y (north) edge of the scene.</p>\n",
        esc(&scene.name),
        base64::engine::general_purpose::STANDARD.encode(png)
    );

    reflectance(&mut h, report, files, &nm)?;
    air::at_sensor(&mut h, scene, report, files, &nm)?;
    match &report.emission {
        Some(e) => emission(&mut h, e, &nm)?,
        None => h.push_str(
            "<h2>Light field against depth</h2>\n<p class=\"note\">The path integrator traces \
             no photons, so this run has no depth tallies, K_d or energy budget.</p>\n",
        ),
    }

    // Figures and settings.
    h.push_str("<h2>Run</h2>\n");
    h.push_str(&table("Timing", &timing_rows(report)));
    h.push_str(&table("Memory and photon cache", &memory_rows(report)));
    h.push_str(&table("Settings", &settings_rows(scene, report)?));
    h.push_str("<h2>Files</h2>\n");
    h.push_str(&table("Outputs", &flatten_json(&report.outputs)?));
    h.push_str("</body>\n</html>\n");
    Ok(h)
}

/// R_rs at five pixels and L / E_d(0+) at the radiometers.
fn reflectance(h: &mut String, report: &RunReport, files: &Path, nm: &[f64]) -> Result<()> {
    h.push_str("<h2>Remote-sensing reflectance</h2>\n");
    h.push_str(&plot(
        &Axes {
            title: "R_rs at five pixels (± 1 standard error)",
            x_label: "wavelength (nm)",
            y_label: "R_rs (sr^-1)",
            depth: false,
        },
        &pixel_rrs(report, files, nm)?,
    )?);
    if report.radiometers.is_empty() {
        h.push_str("<p class=\"note\">The scene has no radiometers.</p>\n");
    } else {
        let curves: Vec<Curve> = report
            .radiometers
            .iter()
            .map(|r| Curve {
                label: format!(
                    "{} m, looking {} at ({}, {}) m",
                    r.depth_m, r.view, r.position_m[0], r.position_m[1]
                ),
                x: nm.to_vec(),
                y: per_ed(&r.L, &report.Ed_above_surface),
                err: Some(per_ed(&r.stderr, &report.Ed_above_surface)),
            })
            .collect();
        h.push_str(&plot(
            &Axes {
                title: "Radiometers: L / E_d(0+) (± 1 standard error)",
                x_label: "wavelength (nm)",
                y_label: "L / E_d(0+) (sr^-1)",
                depth: false,
            },
            &curves,
        )?);
    }
    Ok(())
}

/// The emission's tallies: the profiles against depth, K_d and the energy
/// budget.
fn emission(h: &mut String, e: &EmissionReport, nm: &[f64]) -> Result<()> {
    h.push_str("<h2>Light field against depth</h2>\n");
    if e.tally.is_empty() {
        h.push_str(
            "<p class=\"note\">The scene sets no <code>[tally] depths_m</code>, so \
             this run has no depth profiles or K_d.</p>\n",
        );
    } else {
        profiles(h, e, nm)?;
    }
    h.push_str("<h2>Energy budget</h2>\n");
    let en = &e.energy;
    let shifted_out: Vec<f64> = en
        .inelastic_out
        .iter()
        .zip(&en.inelastic_lost)
        .map(|(a, b)| a + b)
        .collect();
    let mut parts: Vec<(&str, &[f64])> = vec![
        ("escaped", &en.escaped),
        ("absorbed in water", &en.absorbed_water),
        ("absorbed by floor and targets", &en.absorbed_surfaces),
        ("lost at the edges", &en.lost_edges),
    ];
    if en.on_land.iter().any(|&p| p != 0.0) {
        parts.push(("fell on land", &en.on_land));
    }
    if en
        .inelastic_in
        .iter()
        .chain(&shifted_out)
        .any(|&p| p != 0.0)
    {
        parts.push(("inelastic out (Raman, fluorescence)", &shifted_out));
        parts.push(("inelastic in", &en.inelastic_in));
    }
    parts.push(("residual", &en.residual));
    let curves: Vec<Curve> = parts
        .iter()
        .map(|(label, v)| Curve {
            label: (*label).into(),
            x: nm.to_vec(),
            y: v.iter().zip(&en.emitted).map(|(p, t)| p / t).collect(),
            err: None,
        })
        .collect();
    h.push_str(&plot(
        &Axes {
            title: "Where the emitted power went, per band",
            x_label: "wavelength (nm)",
            y_label: "fraction of the emitted power",
            depth: false,
        },
        &curves,
    )?);
    let _ = writeln!(
        h,
        "<p>Energy closure: largest |residual| over the bands {:.2} standard errors.</p>",
        en.closure_sigma
    );
    if let Some(air) = &e.air {
        air::air_budget(h, air, nm)?;
    }
    if en.water_leaving_inelastic.iter().any(|&p| p > 0.0) {
        let share = Curve {
            label: "inelastic share".into(),
            x: nm.to_vec(),
            y: en
                .water_leaving_inelastic
                .iter()
                .zip(&en.water_leaving)
                .map(|(i, w)| if *w > 0.0 { i / w } else { 0.0 })
                .collect(),
            err: None,
        };
        h.push_str(&plot(
            &Axes {
                title: "Inelastic light (Raman, fluorescence) in the water-leaving light, per band",
                x_label: "wavelength (nm)",
                y_label: "share of the power leaving the water",
                depth: false,
            },
            &[share],
        )?);
    }
    Ok(())
}

/// E_d, E_u, E_ou and L_u against depth at a few bands, and K_d per band.
fn profiles(h: &mut String, e: &EmissionReport, nm: &[f64]) -> Result<()> {
    let shown = shown_bands(nm.len());
    type Field = fn(&crate::emit::report::DepthTally) -> &[f64];
    let quantities: [(&str, &str, Field); 4] = [
        ("E_d", "W m^-2 nm^-1", |d| &d.Ed),
        ("E_u", "W m^-2 nm^-1", |d| &d.Eu),
        ("E_ou", "W m^-2 nm^-1", |d| &d.Eou),
        ("L_u", "W m^-2 sr^-1 nm^-1", |d| &d.Lu),
    ];
    h.push_str("<div class=\"grid\">\n");
    for (name, unit, get) in quantities {
        let curves: Vec<Curve> = shown
            .iter()
            .map(|&b| Curve {
                label: format!("{:.0} nm", nm[b]),
                x: e.tally.iter().map(|d| get(d)[b]).collect(),
                y: e.tally.iter().map(|d| d.depth_m).collect(),
                err: None,
            })
            .collect();
        let title = format!("{name} against depth");
        let x_label = format!("{name} ({unit})");
        h.push_str(&plot(
            &Axes {
                title: &title,
                x_label: &x_label,
                y_label: "depth (m)",
                depth: true,
            },
            &curves,
        )?);
    }
    h.push_str("</div>\n");
    let shares: Vec<String> = e
        .tally
        .iter()
        .map(|d| {
            format!(
                "{} m {:.0} %",
                depth_label(d.depth_m),
                100.0 * d.water_fraction
            )
        })
        .collect();
    let _ = writeln!(
        h,
        "<p class=\"note\">Each profile is the emission's tally, a mean over the water present at \
         its depth (the share of the domain that is water: {}); K_d is taken between those means.</p>",
        esc(&shares.join(", "))
    );
    let kd: Vec<Curve> =
        e.kd.iter()
            .map(|k| Curve {
                label: format!("{} to {} m", k.from_m, k.to_m),
                x: nm.to_vec(),
                y: k.Kd.clone(),
                err: None,
            })
            .collect();
    h.push_str(&plot(
        &Axes {
            title: "Diffuse attenuation K_d per band",
            x_label: "wavelength (nm)",
            y_label: "K_d (m^-1)",
            depth: false,
        },
        &kd,
    )?);
    Ok(())
}

const STYLE: &str = "body{font-family:sans-serif;max-width:1500px;margin:1em auto;padding:0 1em;\
color:#222}h1{font-size:1.5em}h2{margin-top:1.6em;border-bottom:1px solid #ccc}\
img{image-rendering:pixelated;width:512px;max-width:100%;border:1px solid #ccc}\
.grid{display:flex;flex-wrap:wrap;gap:8px}svg{border:1px solid #eee}\
table{border-collapse:collapse;margin:0.6em 0 1.2em 0}td,th{border:1px solid #ccc;\
padding:2px 8px;text-align:left;font-size:0.9em}caption{text-align:left;font-weight:bold}\
.note{color:#555;font-size:0.9em}figure{margin:0;max-width:724px}.legend{font-size:0.85em;margin:2px 0 6px 70px}\
.legend span{margin-right:12px;white-space:nowrap}";

/// R_rs at the centre and the quarter points, from the `rrs` product cube,
/// with the L_t standard-error cube over E_d(0+) as the band (none with the
/// sensor above the surface, where that cube is the error at the sensor).
fn pixel_rrs(report: &RunReport, files: &Path, nm: &[f64]) -> Result<Vec<Curve>> {
    let above = report
        .atmosphere
        .as_ref()
        .is_some_and(|a| a.altitude_m.is_some());
    let per_ed: Vec<f64> = if above {
        Vec::new()
    } else {
        report.Ed_above_surface.iter().map(|e| 1.0 / e).collect()
    };
    pixel_spectra(report, files, nm, "rrs", &per_ed)
}

/// Product `product` at the centre and the quarter points, with the L_t
/// standard-error cube times `error_scale` per band as the band (none when
/// `error_scale` is empty or there is no such cube).
fn pixel_spectra(
    report: &RunReport,
    files: &Path,
    nm: &[f64],
    product: &str,
    error_scale: &[f64],
) -> Result<Vec<Curve>> {
    let listed = report
        .outputs
        .products
        .iter()
        .find(|p| p.product == product)
        .ok_or_else(|| Error::invalid("report", format!("no {product} product cube")))?;
    let cube = crate::cube::EnviCube::open(&listed_in(files, &listed.hdr))?;
    let stderr = match &report.outputs.stderr_hdr {
        Some(p) if !error_scale.is_empty() => {
            Some(crate::cube::EnviCube::open(&listed_in(files, p))?)
        }
        _ => None,
    };
    let (w, l) = (cube.samples(), cube.lines());
    let points = [
        (w / 2, l / 2),
        (w / 4, l / 4),
        (3 * w / 4, l / 4),
        (w / 4, 3 * l / 4),
        (3 * w / 4, 3 * l / 4),
    ];
    let mut curves = Vec::new();
    for (x, y) in points {
        let err = match &stderr {
            Some(s) => {
                let e = s.spectrum(x, y)?;
                Some(
                    e.iter()
                        .zip(error_scale)
                        .map(|(&v, f)| v as f64 * f)
                        .collect(),
                )
            }
            None => None,
        };
        curves.push(Curve {
            label: format!("pixel ({x}, {y})"),
            x: nm.to_vec(),
            y: cube.spectrum(x, y)?.iter().map(|&v| v as f64).collect(),
            err,
        });
    }
    Ok(curves)
}

/// `v / ed`, band by band.
fn per_ed(v: &[f64], ed: &[f64]) -> Vec<f64> {
    v.iter().zip(ed).map(|(v, e)| v / e).collect()
}

/// At most five band indices, evenly spread over `n` bands.
fn shown_bands(n: usize) -> Vec<usize> {
    let k = n.min(5);
    if k <= 1 {
        return vec![0; k];
    }
    (0..k).map(|i| i * (n - 1) / (k - 1)).collect()
}

/// One SVG plot of `curves` (non-finite points left out; on a log axis,
/// non-positive ones too).
fn plot(axes: &Axes, curves: &[Curve]) -> Result<String> {
    REGISTER.call_once(|| {
        // The font is part of the binary; a failure here is a build defect.
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
            .unwrap_or_else(|_| panic!("the embedded DejaVu Sans font does not parse"));
    });
    let usable = |x: f64, y: f64| x.is_finite() && y.is_finite() && (!axes.depth || x > 0.0);
    let mut xs = Vec::new();
    let mut ys = Vec::new();
    for c in curves {
        for (i, (&x, &y)) in c.x.iter().zip(&c.y).enumerate() {
            if !usable(x, y) {
                continue;
            }
            xs.push(x);
            ys.push(y);
            if let Some(e) = c
                .err
                .as_ref()
                .and_then(|e| e.get(i))
                .filter(|e| e.is_finite())
            {
                ys.push(y - e);
                ys.push(y + e);
            }
        }
    }
    if xs.is_empty() {
        return Ok(format!(
            "<p class=\"note\">{}: no finite values to plot.</p>\n",
            esc(axes.title)
        ));
    }
    let (x0, x1) = span(&xs, axes.depth);
    let (y0, y1) = span(&ys, false);
    let mut svg = String::new();
    let drawn = (|| -> std::result::Result<(), Box<dyn std::error::Error>> {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut builder = ChartBuilder::on(&root);
        builder
            .caption(axes.title, ("sans-serif", 17))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(70);
        if axes.depth {
            // Depth grows downward: y runs from the deepest (bottom) to 0.
            let mut chart = builder.build_cartesian_2d((x0..x1).log_scale(), -y1..-y0)?;
            chart
                .configure_mesh()
                .x_desc(axes.x_label)
                .y_desc(axes.y_label)
                .y_label_formatter(&|v| depth_label(-v))
                .x_label_formatter(&|v| format!("{v:.2e}"))
                .draw()?;
            for (i, c) in curves.iter().enumerate() {
                let colour = COLOURS[i % COLOURS.len()];
                let pts: Vec<(f64, f64)> =
                    c.x.iter()
                        .zip(&c.y)
                        .filter(|&(&x, &y)| usable(x, y))
                        .map(|(&x, &y)| (x, -y))
                        .collect();
                chart.draw_series(LineSeries::new(pts, colour.stroke_width(2)))?;
            }
        } else {
            let mut chart = builder.build_cartesian_2d(x0..x1, y0..y1)?;
            chart
                .configure_mesh()
                .x_desc(axes.x_label)
                .y_desc(axes.y_label)
                .y_label_formatter(&|v| format!("{v:.3e}"))
                .draw()?;
            for (i, c) in curves.iter().enumerate() {
                let colour = COLOURS[i % COLOURS.len()];
                let pts: Vec<(f64, f64, f64)> =
                    c.x.iter()
                        .zip(&c.y)
                        .enumerate()
                        .filter(|&(_, (&x, &y))| usable(x, y))
                        .map(|(j, (&x, &y))| {
                            let e = c.err.as_ref().and_then(|e| e.get(j)).copied();
                            (x, y, e.filter(|e| e.is_finite()).unwrap_or(0.0))
                        })
                        .collect();
                if c.err.is_some() && pts.len() > 1 {
                    let mut band: Vec<(f64, f64)> = pts.iter().map(|p| (p.0, p.1 + p.2)).collect();
                    band.extend(pts.iter().rev().map(|p| (p.0, p.1 - p.2)));
                    chart.draw_series(std::iter::once(Polygon::new(band, colour.mix(0.2))))?;
                }
                let line = pts.iter().map(|p| (p.0, p.1));
                chart.draw_series(LineSeries::new(line, colour.stroke_width(2)))?;
            }
        }
        root.present()?;
        Ok(())
    })();
    drawn.map_err(|e| Error::invalid("HTML report", format!("plot '{}': {e}", axes.title)))?;
    Ok(format!(
        "<figure>{svg}\n{}{}</figure>\n",
        legend(curves),
        dropped_note(axes, curves)
    ))
}

/// The curves' legend under the plot, in HTML, so that it never covers a
/// curve.
fn legend(curves: &[Curve]) -> String {
    if curves.is_empty() {
        return String::new();
    }
    let mut h = String::from("<figcaption class=\"legend\">");
    for (i, c) in curves.iter().enumerate() {
        let RGBColor(r, g, b) = COLOURS[i % COLOURS.len()];
        let _ = write!(
            h,
            "<span><b style=\"color:#{r:02x}{g:02x}{b:02x}\">&#9473;&#9473;</b> {}</span> ",
            esc(&c.label)
        );
    }
    h.push_str("</figcaption>\n");
    h
}

/// On a profile's log axis, what could not be drawn: each curve's depths
/// where its value is 0 (no light of that band reaches them) or missing.
fn dropped_note(axes: &Axes, curves: &[Curve]) -> String {
    if !axes.depth {
        return String::new();
    }
    let mut parts = Vec::new();
    for c in curves {
        let depths: Vec<String> =
            c.x.iter()
                .zip(&c.y)
                .filter(|&(&x, &y)| y.is_finite() && !(x.is_finite() && x > 0.0))
                .map(|(_, &y)| depth_label(y))
                .collect();
        if !depths.is_empty() {
            parts.push(format!("{} at {} m", c.label, depths.join(", ")));
        }
    }
    if parts.is_empty() {
        return String::new();
    }
    format!(
        "<p class=\"note\">Not drawn on the log axis (zero: no light of the band reaches the depth, or none tallied): {}.</p>\n",
        esc(&parts.join("; "))
    )
}

/// A depth tick or value in metres with no more decimals than it needs
/// (0, 0.5, 1, 12.25), so that neighbouring ticks never read the same.
fn depth_label(v: f64) -> String {
    let r = (v * 100.0).round() / 100.0 + 0.0;
    format!("{r}")
}

/// The range of `v` with a margin (a log axis keeps its lower bound
/// positive); a single value gets a range around it.
fn span(v: &[f64], log: bool) -> (f64, f64) {
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if log {
        return if hi > lo {
            (lo / 1.2, hi * 1.2)
        } else {
            (lo / 2.0, lo * 2.0)
        };
    }
    let pad = if hi > lo {
        0.05 * (hi - lo)
    } else {
        0.5 * lo.abs().max(1e-12)
    };
    (lo - pad, hi + pad)
}

/// An HTML table of name/value rows under a caption.
fn table(caption: &str, rows: &[(String, String)]) -> String {
    let mut t = format!("<table>\n<caption>{}</caption>\n", esc(caption));
    for (k, v) in rows {
        let _ = writeln!(t, "<tr><th>{}</th><td>{}</td></tr>", esc(k), esc(v));
    }
    t.push_str("</table>\n");
    t
}

fn timing_rows(r: &RunReport) -> Vec<(String, String)> {
    let t = &r.timings_s;
    vec![
        ("load the scene (s)".into(), format!("{:.2}", t.scene)),
        (
            if r.reused_map {
                "open the reused map (s)".into()
            } else {
                "emit photons (s)".into()
            },
            format!("{:.2}", t.emit),
        ),
        ("render (s)".into(), format!("{:.2}", t.render)),
        ("total (s)".into(), format!("{:.2}", t.total)),
    ]
}

fn memory_rows(r: &RunReport) -> Vec<(String, String)> {
    let mib = |b: u64| format!("{:.1} MiB", b as f64 / (1u64 << 20) as f64);
    let c = &r.cache;
    let mut rows = vec![
        ("memory budget".into(), mib(r.memory.budget_bytes)),
        (
            "peak anonymous memory (bounded by the budget)".into(),
            mib(r.peak_memory.anon_bytes),
        ),
        (
            "peak mapped file pages (the photon map; not charged)".into(),
            mib(r.peak_memory.file_bytes),
        ),
        ("tile cache share".into(), mib(r.memory.tile_cache_bytes)),
        ("cache hits".into(), c.hits.to_string()),
        ("cache misses".into(), c.misses.to_string()),
        ("cache evictions".into(), c.evictions.to_string()),
        ("tiles decoded".into(), c.decodes.to_string()),
        ("decoded photon bytes".into(), mib(c.decoded_bytes)),
        ("peak resident tiles".into(), mib(c.peak_resident_bytes)),
    ];
    if let Some(m) = &r.map {
        rows.push(("map photons".into(), m.photons.to_string()));
        rows.push(("map tiles".into(), m.tiles.to_string()));
        rows.push(("map size on disk".into(), mib(m.file_bytes)));
        rows.push((
            "bytes per photon".into(),
            format!("{:.2}", m.bytes_per_photon),
        ));
        rows.push(("map reused".into(), r.reused_map.to_string()));
    }
    rows
}

fn settings_rows(scene: &Scene, r: &RunReport) -> Result<Vec<(String, String)>> {
    let bands = &scene.bands;
    let mut rows = vec![
        ("scene".to_string(), scene.name.clone()),
        (
            "scene files".into(),
            scene
                .inputs
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", "),
        ),
        ("integrator".into(), format!("{:?}", r.integrator)),
        ("seed".into(), scene.seed.to_string()),
        ("photons".into(), scene.photons.to_string()),
        ("upward split".into(), scene.upward_split.to_string()),
        (
            "bands".into(),
            format!(
                "{} from {:.1} to {:.1} nm",
                bands.len(),
                bands.centers_nm().first().copied().unwrap_or(f32::NAN),
                bands.centers_nm().last().copied().unwrap_or(f32::NAN)
            ),
        ),
        (
            "sun zenith, azimuth (deg)".into(),
            format!(
                "{:.2}, {:.2}",
                scene.sun.zenith_rad.to_degrees(),
                scene.sun.azimuth_rad.to_degrees()
            ),
        ),
        ("sky".into(), format!("{:?}", scene.sky.model)),
        (
            "surface".into(),
            format!(
                "refractive index {:.5} to {:.5} over the bands, slope variance {}",
                scene
                    .water_index
                    .iter()
                    .copied()
                    .fold(f64::INFINITY, f64::min),
                scene
                    .water_index
                    .iter()
                    .copied()
                    .fold(f64::NEG_INFINITY, f64::max),
                scene.surface.slope_variance
            ),
        ),
        (
            "domain (m)".into(),
            format!(
                "{} x {}{}",
                scene.domain.size_m[0],
                scene.domain.size_m[1],
                if scene.domain.periodic {
                    ", periodic"
                } else {
                    ""
                }
            ),
        ),
    ];
    for (k, v) in flatten_json(&r.estimate)? {
        rows.push((format!("estimate.{k}"), v));
    }
    for (k, v) in flatten_json(&r.sensor)? {
        rows.push((format!("sensor.{k}"), v));
    }
    Ok(rows)
}

/// `value` as rows of dotted field path and JSON text.
fn flatten_json<T: serde::Serialize>(value: &T) -> Result<Vec<(String, String)>> {
    fn walk(prefix: &str, v: &serde_json::Value, rows: &mut Vec<(String, String)>) {
        match v {
            serde_json::Value::Object(m) => {
                for (k, v) in m {
                    let p = if prefix.is_empty() {
                        k.clone()
                    } else {
                        format!("{prefix}.{k}")
                    };
                    walk(&p, v, rows);
                }
            }
            serde_json::Value::String(s) => rows.push((prefix.into(), s.clone())),
            other => rows.push((prefix.into(), other.to_string())),
        }
    }
    let v = serde_json::to_value(value).map_err(|e| Error::invalid("report", e.to_string()))?;
    let mut rows = Vec::new();
    walk("", &v, &mut rows);
    Ok(rows)
}

/// Escape text for HTML.
fn esc(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            _ => o.push(c),
        }
    }
    o
}

mod air;

#[cfg(test)]
mod tests;
