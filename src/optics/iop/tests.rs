use super::*;

fn spectra() -> BandSpectra {
    BandSpectra {
        a_w: vec![0.01, 0.4],
        b_w: vec![0.004, 0.001],
        a_phi_a: vec![0.04, 0.01],
        a_phi_e: vec![0.7, 0.9],
        cdom_shape: vec![1.0, 0.1],
        nap_shape: vec![1.0, 0.2],
        bp_shape: vec![1.2, 0.8],
    }
}

/// All bands at once equal the per-band IOPs (to rounding of exp/ln
/// against powf).
#[test]
fn all_bands_at_once_match_one_band_at_a_time() {
    let field = ConstituentField::Gradient {
        axis: 0,
        size_m: 10.0,
        from: Constituents {
            chl: 0.3,
            cdom_440: 0.05,
            nap_440: 0.2,
        },
        to: Constituents {
            chl: 8.0,
            cdom_440: 0.5,
            nap_440: 0.0,
        },
    };
    for bp_550 in [None, Some(0.4)] {
        let w = WaterModel::Constituents {
            spectra: Box::new(spectra()),
            field: field.clone(),
            bp_550,
        };
        let n = spectra().a_w.len();
        let mut all = vec![Iop::default(); n];
        for p in [Vec3::new(1.0, 2.0, -0.5), Vec3::new(7.0, 1.0, -3.0)] {
            w.iops(p, &mut all);
            for (b, got) in all.iter().enumerate() {
                let want = w.iop(p, b);
                for (g, e) in [(got.a, want.a), (got.b_w, want.b_w), (got.b_p, want.b_p)] {
                    assert!((g - e).abs() <= 1e-12 * e.abs().max(1.0), "{g} vs {e}");
                }
            }
        }
    }
}

#[test]
fn majorant_bounds_every_point_of_a_gradient() {
    let m = WaterModel::Constituents {
        spectra: Box::new(spectra()),
        field: ConstituentField::Gradient {
            axis: 0,
            size_m: 100.0,
            from: Constituents {
                chl: 0.5,
                cdom_440: 0.02,
                nap_440: 0.0,
            },
            to: Constituents {
                chl: 5.0,
                cdom_440: 0.3,
                nap_440: 0.05,
            },
        },
        bp_550: None,
    };
    for band in 0..2 {
        let maj = m.majorant(band);
        for i in 0..=100 {
            let c = m.iop(Vec3::new(i as f32, 3.0, -2.0), band).c();
            assert!(c <= maj * (1.0 + 1e-12), "band {band} x {i}");
        }
        assert!((m.iop(Vec3::new(100.0, 0.0, -1.0), band).c() - maj).abs() < 1e-12);
    }
    // The model: a at chl 5, band 0.
    let iop = m.iop(Vec3::new(100.0, 0.0, -1.0), 0);
    let want_a = 0.01 + 0.04 * 5f64.powf(0.7) + 0.3 + 0.05;
    assert!((iop.a - want_a).abs() < 1e-12);
    assert!((iop.b_p - 0.30 * 5f64.powf(0.62) * 1.2).abs() < 1e-12);
}

#[test]
fn grid_interpolates_trilinearly_and_clamps() {
    let c = |v: f64| Constituents {
        chl: v,
        cdom_440: 0.0,
        nap_440: 0.0,
    };
    let g = ConstituentGrid {
        xs: vec![0.0, 10.0],
        ys: vec![0.0, 10.0],
        depths: vec![0.0, 10.0],
        values: (0..8).map(|i| c(i as f64)).collect(),
    };
    let f = ConstituentField::Grid(g);
    // Trilinear of v = x + 2 y + 4 z in unit-cube coordinates.
    let at = f.at(Vec3::new(5.0, 2.5, -7.5)).chl;
    assert!((at - (0.5 + 2.0 * 0.25 + 4.0 * 0.75)).abs() < 1e-6);
    assert_eq!(f.at(Vec3::new(-5.0, -5.0, 5.0)).chl, 0.0);
    assert_eq!(f.at(Vec3::new(50.0, 50.0, -50.0)).chl, 7.0);
    assert_eq!(f.max().chl, 7.0);
}

#[test]
fn layers_override_the_base() {
    let c = |v: f64| Constituents {
        chl: v,
        cdom_440: 0.0,
        nap_440: 0.0,
    };
    let f = ConstituentField::Layers {
        base: c(1.0),
        layers: vec![(2.0, 4.0, c(3.0))],
    };
    assert_eq!(f.at(Vec3::new(0.0, 0.0, -1.0)).chl, 1.0);
    assert_eq!(f.at(Vec3::new(0.0, 0.0, -3.0)).chl, 3.0);
    assert_eq!(f.max().chl, 3.0);
}

/// Through depth layers the optical depth is exact: it matches the sum of
/// c times the slant length inside each layer, worked by hand, for a
/// segment crossing a whole layer and ending inside another; fields that
/// are not layered decline.
#[test]
fn layered_optical_depth_cuts_at_layer_boundaries() {
    let conc = |chl: f64| Constituents {
        chl,
        cdom_440: 0.1,
        nap_440: 0.0,
    };
    let w = WaterModel::Constituents {
        spectra: Box::new(spectra()),
        field: ConstituentField::Layers {
            base: conc(0.5),
            layers: vec![(2.0, 4.0, conc(8.0)), (5.0, 6.0, conc(3.0))],
        },
        bp_550: None,
    };
    let nb = spectra().a_w.len();
    let (mut tmp, mut got) = (vec![Iop::default(); nb], vec![0.0; nb]);
    // From 5.5 m up to the surface at 60 degrees from the vertical.
    let dir = Vec3::new(0.8660254, 0.0, 0.5);
    let x = Vec3::new(1.0, 1.0, -5.5);
    let len = 5.5 / 0.5;
    assert!(w.layered_optical_depth(x, dir, len, &mut tmp, &mut got));
    let c = |chl: f64, b: usize| {
        let probe = WaterModel::Constituents {
            spectra: Box::new(spectra()),
            field: ConstituentField::Uniform(conc(chl)),
            bp_550: None,
        };
        probe.iop(Vec3::ZERO, b).c()
    };
    for (b, g) in got.iter().enumerate() {
        // Vertical thicknesses: 0.5 m at chl 3, 1 + 2 m at chl 0.5, 2 m at chl 8.
        let want = (0.5 * c(3.0, b) + 3.0 * c(0.5, b) + 2.0 * c(8.0, b)) / 0.5;
        assert!((g - want).abs() <= 1e-6 * want, "band {b}: {g} vs {want}");
    }
    let gradient = WaterModel::Constituents {
        spectra: Box::new(spectra()),
        field: ConstituentField::Gradient {
            axis: 0,
            size_m: 10.0,
            from: conc(0.5),
            to: conc(8.0),
        },
        bp_550: None,
    };
    assert!(!gradient.layered_optical_depth(x, dir, len, &mut tmp, &mut got));
}

/// Through a gradient the optical depth is exact: it matches c summed at
/// a million midpoints along the segment within 1e-9, for segments
/// oblique to the gradient, across it and out of its span at either end
/// (where the concentrations hold), along it, level across it (no change
/// of chlorophyll) and with a fixed `bp_550`; chlorophyll at zero at an
/// end, and other fields, decline. Chlorophyll taken at each piece's
/// midpoint instead of its mean power was off by 1.7e-3 (band 0).
#[test]
fn gradient_optical_depth_is_exact() {
    let conc = |chl: f64, cdom_440: f64| Constituents {
        chl,
        cdom_440,
        nap_440: 0.05,
    };
    let gradient = |from: Constituents, bp_550| WaterModel::Constituents {
        spectra: Box::new(spectra()),
        field: ConstituentField::Gradient {
            axis: 0,
            size_m: 10.0,
            from,
            to: conc(8.0, 0.4),
        },
        bp_550,
    };
    let nb = spectra().a_w.len();
    let (mut tmp, mut got) = (vec![Iop::default(); nb], vec![0.0; nb]);
    let up = |x: f32, z: f32| Vec3::new(x, 0.0, z).normalize();
    let cases = [
        (
            Vec3::new(3.0, 1.0, -4.0),
            up(0.5, 1.0),
            4.0 / up(0.5, 1.0).z,
        ),
        (
            Vec3::new(1.0, 1.0, -6.0),
            up(-1.0, 1.0),
            6.0 / up(-1.0, 1.0).z,
        ),
        (
            Vec3::new(9.0, 1.0, -6.0),
            up(1.0, 1.0),
            6.0 / up(1.0, 1.0).z,
        ),
        (Vec3::new(-2.0, 1.0, -3.0), Vec3::X, 14.0),
        (Vec3::new(4.0, 1.0, -3.0), Vec3::Y, 5.0),
    ];
    for bp_550 in [None, Some(0.3)] {
        let w = gradient(conc(0.2, 0.02), bp_550);
        for &(x, dir, len) in &cases {
            assert!(w.gradient_optical_depth(x, dir, len, &mut got));
            let n = 1_000_000;
            let mut want = vec![0.0; nb];
            for i in 0..n {
                let p =
                    x.as_dvec3() + dir.as_dvec3() * (f64::from(len) * (i as f64 + 0.5) / n as f64);
                w.iops(p.as_vec3(), &mut tmp);
                for (o, iop) in want.iter_mut().zip(&tmp) {
                    *o += iop.c() * f64::from(len) / n as f64;
                }
            }
            for (b, (g, e)) in got.iter().zip(&want).enumerate() {
                assert!(
                    (g - e).abs() <= 1e-9 * e,
                    "{x} along {dir}, band {b}: {g} vs {e} ({:e})",
                    g / e - 1.0
                );
            }
        }
    }
    let x = Vec3::new(3.0, 1.0, -4.0);
    assert!(!gradient(conc(0.0, 0.02), None).gradient_optical_depth(x, Vec3::Z, 4.0, &mut got));
    let uniform = WaterModel::Constituents {
        spectra: Box::new(spectra()),
        field: ConstituentField::Uniform(conc(1.0, 0.1)),
        bp_550: None,
    };
    assert!(!uniform.gradient_optical_depth(x, Vec3::Z, 4.0, &mut got));
}
