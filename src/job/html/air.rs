//! The page's parts for the air: the reflectance and transmittances at a
//! sensor above the surface, and the emission's budget of the air.

use super::{pixel_spectra, plot, Axes, Curve, RunReport};
use crate::error::Result;
use crate::scene::Scene;
use std::fmt::Write as _;
use std::path::Path;

/// With the sensor above the surface: the reflectance at the sensor rho_t
/// at the five pixels R_rs is shown at (± 1 standard error, from the L_t
/// standard-error cube), with the path reflectance pi L_path / (E_0 mu_0)
/// beside it; and the transmittances of the air per band.
pub(super) fn at_sensor(
    h: &mut String,
    scene: &Scene,
    report: &RunReport,
    files: &Path,
    nm: &[f64],
) -> Result<()> {
    let Some(a) = report
        .atmosphere
        .as_ref()
        .filter(|a| a.altitude_m.is_some())
    else {
        return Ok(());
    };
    let altitude = a.altitude_m.unwrap_or(0.0);
    let _ = writeln!(h, "<h2>At the sensor, {altitude:.0} m up</h2>");
    let mu0 = scene.sun.zenith_rad.cos();
    let to_rho: Vec<f64> = a
        .toa_irradiance
        .iter()
        .map(|&e| crate::render::reflectance_factor(e, mu0))
        .collect();
    let mut curves = pixel_spectra(report, files, nm, "rhot", &to_rho)?;
    curves.push(Curve {
        label: "path reflectance (± 1 standard error)".into(),
        x: nm.to_vec(),
        y: a.L_path.iter().zip(&to_rho).map(|(l, f)| l * f).collect(),
        err: Some(
            a.L_path_stderr
                .iter()
                .zip(&to_rho)
                .map(|(l, f)| l * f)
                .collect(),
        ),
    });
    h.push_str(&plot(
        &Axes {
            title: "Reflectance at the sensor rho_t = pi L_t / (E_0 cos theta_s) at five pixels",
            x_label: "wavelength (nm)",
            y_label: "rho_t",
            depth: false,
        },
        &curves,
    )?);
    let series = |label: &str, y: &[f64]| Curve {
        label: label.into(),
        x: nm.to_vec(),
        y: y.to_vec(),
        err: None,
    };
    h.push_str(&plot(
        &Axes {
            title: "Transmittances of the air",
            x_label: "wavelength (nm)",
            y_label: "transmittance",
            depth: false,
        },
        &[
            series("t_direct, sun to surface", &a.t_direct),
            series("t_down, sun to surface, direct and diffuse", &a.t_down),
            series("t_view, surface to sensor, direct", &a.t_view),
            series("t_up, surface to sensor, direct and diffuse", &a.t_up),
        ],
    )?);
    Ok(())
}

/// The air's budget over the domain, as fractions of the sun's power at
/// the top.
pub(super) fn air_budget(
    h: &mut String,
    air: &crate::emit::report::AirBudget,
    nm: &[f64],
) -> Result<()> {
    let parts: [(&str, &[f64]); 5] = [
        ("reached the surface", &air.to_surface),
        ("sent up by the surface", &air.surface_up),
        ("left the top", &air.to_space),
        ("absorbed in the air", &air.absorbed_air),
        ("residual", &air.residual),
    ];
    let curves: Vec<Curve> = parts
        .iter()
        .map(|(label, v)| Curve {
            label: (*label).into(),
            x: nm.to_vec(),
            y: v.iter()
                .zip(&air.top)
                .map(|(p, t)| if *t > 0.0 { p / t } else { 0.0 })
                .collect(),
            err: None,
        })
        .collect();
    h.push_str(&plot(
        &Axes {
            title: "The air over the domain: the sun's power at the top of the atmosphere and what became of it, per band",
            x_label: "wavelength (nm)",
            y_label: "fraction of the power at the top",
            depth: false,
        },
        &curves,
    )?);
    let _ = writeln!(
        h,
        "<p>The air's closure (the top and the surface's upward light against the surface, the top and the air's absorption): largest |residual| over the bands {:.2} standard errors.</p>",
        air.closure_sigma
    );
    Ok(())
}
