use super::*;

#[test]
fn bands_shown_are_spread_and_in_range() {
    assert_eq!(shown_bands(0), Vec::<usize>::new());
    assert_eq!(shown_bands(1), vec![0]);
    assert_eq!(shown_bands(3), vec![0, 1, 2]);
    assert_eq!(shown_bands(41), vec![0, 10, 20, 30, 40]);
}

#[test]
fn text_is_escaped() {
    assert_eq!(
        esc("<a href=\"x\">&</a>"),
        "&lt;a href=&quot;x&quot;&gt;&amp;&lt;/a&gt;"
    );
}

#[test]
fn spans_cover_their_values() {
    let (a, b) = span(&[1.0, 3.0], false);
    assert!(a < 1.0 && b > 3.0);
    let (a, b) = span(&[2.0], false);
    assert!(a < 2.0 && b > 2.0);
    let (a, b) = span(&[1e-3, 10.0], true);
    assert!(a > 0.0 && a < 1e-3 && b > 10.0);
}

#[test]
fn a_plot_is_svg_with_its_labels_and_skips_non_finite_points() {
    let curve = Curve {
        label: "pixel (1, 2)".into(),
        x: vec![400.0, 500.0, 600.0],
        y: vec![0.01, f64::NAN, 0.004],
        err: Some(vec![0.001, 0.001, f64::INFINITY]),
    };
    let svg = plot(
        &Axes {
            title: "R_rs",
            x_label: "wavelength (nm)",
            y_label: "R_rs (sr^-1)",
            depth: false,
        },
        &[curve],
    )
    .unwrap();
    assert!(
        svg.starts_with("<figure><svg"),
        "{}",
        &svg[..80.min(svg.len())]
    );
    assert!(svg.contains("pixel (1, 2)") && svg.contains("wavelength (nm)"));
    assert!(!svg.contains("NaN") && !svg.contains("inf"));
    let empty = plot(
        &Axes {
            title: "nothing",
            x_label: "x",
            y_label: "y",
            depth: true,
        },
        &[Curve {
            label: "none".into(),
            x: vec![0.0, -1.0],
            y: vec![1.0, 2.0],
            err: None,
        }],
    )
    .unwrap();
    assert!(empty.contains("no finite values"));
}

/// Depth ticks carry the decimals they need and no more (no two ticks of
/// one axis read the same); the legend is HTML under the plot, off the
/// curves; a profile that reaches 0 (no light of the band at that depth)
/// is named in a note, since a log axis cannot draw it.
#[test]
fn depth_plots_label_ticks_legends_and_what_they_cannot_draw() {
    assert_eq!(depth_label(0.0), "0");
    assert_eq!(depth_label(-0.0), "0");
    assert_eq!(depth_label(0.5), "0.5");
    assert_eq!(depth_label(2.0), "2");
    assert_eq!(depth_label(12.25), "12.25");
    let curves = [
        Curve {
            label: "500 nm".into(),
            x: vec![1.0, 0.5, 0.25],
            y: vec![0.0, 1.0, 2.0],
            err: None,
        },
        Curve {
            label: "800 nm".into(),
            x: vec![0.3, 0.0, 0.0],
            y: vec![0.0, 1.0, 2.0],
            err: None,
        },
    ];
    let html = plot(
        &Axes {
            title: "E_d against depth",
            x_label: "E_d",
            y_label: "depth (m)",
            depth: true,
        },
        &curves,
    )
    .unwrap();
    let svg_end = html.find("</svg>").unwrap();
    let legend = html.find("<figcaption class=\"legend\">").unwrap();
    assert!(legend > svg_end, "the legend follows the plot");
    assert!(html[legend..].contains("500 nm") && html[legend..].contains("800 nm"));
    assert!(html.contains("800 nm at 1, 2 m"), "{html}");
    assert!(!html.contains("500 nm at"));
}
