use super::*;
use crate::optics::iop::ConstituentGrid;
use crate::rng::Pcg32;

fn spectra() -> BandSpectra {
    BandSpectra {
        a_w: vec![0.01, 0.4, 0.06],
        b_w: vec![0.004, 0.001, 0.002],
        a_phi_a: vec![0.04, 0.01, 0.02],
        a_phi_e: vec![0.7, 0.9, 0.65],
        cdom_shape: vec![1.0, 0.1, 0.4],
        nap_shape: vec![1.0, 0.2, 0.5],
        bp_shape: vec![1.2, 0.8, 1.0],
    }
}

fn conc(chl: f64, cdom_440: f64, nap_440: f64) -> Constituents {
    Constituents {
        chl,
        cdom_440,
        nap_440,
    }
}

fn model(field: ConstituentField, bp_550: Option<f64>) -> WaterModel {
    WaterModel::Constituents {
        spectra: Box::new(spectra()),
        field,
        bp_550,
    }
}

fn gradient() -> WaterModel {
    model(
        ConstituentField::Gradient {
            axis: 0,
            size_m: 200.0,
            from: conc(5.0, 0.3, 0.01),
            to: conc(0.5, 0.03, 0.2),
        },
        None,
    )
}

fn layers() -> WaterModel {
    model(
        ConstituentField::Layers {
            base: conc(0.5, 0.02, 0.01),
            layers: vec![
                (2.0, 5.0, conc(8.0, 0.2, 0.1)),
                (9.0, 12.0, conc(2.0, 0.5, 0.0)),
            ],
        },
        None,
    )
}

fn grid() -> WaterModel {
    let values = (0..8)
        .map(|i| conc(0.2 + i as f64, 0.01 * i as f64, 0.05))
        .collect();
    model(
        ConstituentField::Grid(ConstituentGrid {
            xs: vec![0.0, 100.0],
            ys: vec![0.0, 100.0],
            depths: vec![0.0, 20.0],
            values,
        }),
        Some(0.4),
    )
}

fn every_model() -> Vec<(&'static str, WaterModel)> {
    vec![
        ("gradient", gradient()),
        ("layers", layers()),
        ("grid", grid()),
        (
            "uniform",
            model(ConstituentField::Uniform(conc(1.0, 0.05, 0.01)), None),
        ),
        ("explicit", WaterModel::Explicit { a: 0.1, b: 0.5 }),
    ]
}

fn random_point(rng: &mut Pcg32) -> Vec3 {
    Vec3::new(
        (rng.uniform_f64() * 240.0 - 20.0) as f32,
        (rng.uniform_f64() * 240.0 - 20.0) as f32,
        (-rng.uniform_f64() * 16.0) as f32,
    )
}

#[test]
fn cells_follow_the_field() {
    let cells = |w: &WaterModel| MajorantGrid::new(w, 3).cells();
    assert_eq!(cells(&gradient()), GRADIENT_CELLS);
    // Faces at 2, 5, 9 and 12 m deep.
    assert_eq!(cells(&layers()), 5);
    assert_eq!(cells(&grid()), 1);
    assert_eq!(cells(&WaterModel::Explicit { a: 0.1, b: 0.5 }), 1);
}

/// The bounds of the cell a point falls in hold the point's IOPs, in
/// every band and every kind of field, including points outside the
/// domain and on cell faces.
#[test]
fn bounds_hold_the_iops_of_every_point() {
    let mut rng = Pcg32::new(7, 0);
    for (name, w) in every_model() {
        let g = MajorantGrid::new(&w, 3);
        let faces = [0.0f32, 200.0 / 64.0, 100.0, 200.0];
        let mut points: Vec<Vec3> = (0..20_000).map(|_| random_point(&mut rng)).collect();
        points.extend(faces.iter().map(|&x| Vec3::new(x, x, -2.0)));
        points.extend([-2.0f32, -5.0, -9.0, -12.0].map(|z| Vec3::new(1.0, 1.0, z)));
        for p in points {
            let cell = g.locate(p);
            for band in 0..3 {
                let b = g.bounds(band, cell);
                let iop = w.iop(p, band);
                let within = |x: f64, r: [f64; 2]| r[0] <= x && x <= r[1];
                assert!(within(iop.a, b.a), "{name} {p} band {band}: a");
                assert!(within(iop.a + iop.b_w, b.a_bw), "{name} {p}: a + b_w");
                assert!(within(iop.c(), b.c), "{name} {p}: c");
                assert!(b.majorant >= iop.c(), "{name} {p}: majorant");
            }
        }
    }
}

/// A gradient's cells are tight: where every concentration falls along
/// x, each cell's bounds are the IOPs at the faces of its three-cell
/// neighbourhood, to the widening.
#[test]
fn gradient_bounds_are_local() {
    let w = model(
        ConstituentField::Gradient {
            axis: 0,
            size_m: 200.0,
            from: conc(5.0, 0.3, 0.2),
            to: conc(0.5, 0.03, 0.01),
        },
        None,
    );
    let g = MajorantGrid::new(&w, 3);
    let step = 200.0 / GRADIENT_CELLS as f64;
    // The widening, and the outward rounding to f32 of all but the majorant.
    let close = |got: f64, want: f64| (got / want - 1.0).abs() <= 2.0 * WIDEN;
    let close32 = |got: f64, want: f64| (got / want - 1.0).abs() <= 2.0 * WIDEN + 1.2e-7;
    for band in 0..3 {
        assert!(close(g.global_majorant(band), w.majorant(band)));
        for cell in 0..g.cells() {
            let lo_x = step * cell.saturating_sub(1) as f64;
            let hi_x = step * (cell + 2).min(GRADIENT_CELLS) as f64;
            let hi = w.iop(Vec3::new(lo_x as f32, 0.0, -1.0), band);
            let lo = w.iop(Vec3::new(hi_x as f32, 0.0, -1.0), band);
            let b = g.bounds(band, cell);
            assert!(close(b.majorant, hi.c()), "band {band} cell {cell}");
            assert!(close32(b.c[0], lo.c()) && close(b.c[1], hi.c()));
            assert!(close32(b.a[0], lo.a) && close32(b.a[1], hi.a));
            assert!(close32(b.a_bw[0], lo.a + lo.b_w) && close32(b.a_bw[1], hi.a + hi.b_w));
        }
    }
}

/// Deciding from the bounds gives the exact decision, for random numbers
/// anywhere in [0, majorant) and right at the bounds.
#[test]
fn collisions_decide_as_the_exact_iops_do() {
    let mut rng = Pcg32::new(11, 0);
    for (name, w) in every_model() {
        let g = MajorantGrid::new(&w, 3);
        for _ in 0..20_000 {
            let p = random_point(&mut rng);
            let cell = g.locate(p);
            for band in 0..3 {
                let b = g.bounds(band, cell);
                let iop = w.iop(p, band);
                let mut xis = vec![rng.uniform_f64() * b.majorant];
                xis.extend(b.a.iter().chain(&b.a_bw).chain(&b.c).copied());
                xis.extend([iop.a, iop.a + iop.b_w, iop.c()]);
                for xi in xis {
                    assert_eq!(
                        g.collide(&w, band, cell, p, xi),
                        Collision::decide(&iop, xi),
                        "{name} {p} band {band} xi {xi}"
                    );
                }
            }
        }
    }
}

/// Delta tracking through the cells: the chance of a flight reaching
/// distance L without a real collision is exp(-integral of c), within
/// four standard errors, for an oblique ray across the gradient and a
/// vertical ray through the layers.
#[test]
fn delta_tracking_transmits_exp_minus_optical_depth() {
    let cases = [
        (
            "gradient",
            gradient(),
            Vec3::new(10.0, 50.0, -1.0),
            Vec3::new(0.8, 0.36, -0.48).normalize(),
            2.0,
        ),
        (
            "layers",
            layers(),
            Vec3::new(10.0, 50.0, -0.5),
            Vec3::new(0.2, 0.0, -1.0).normalize(),
            13.0,
        ),
        (
            "layers upward",
            layers(),
            Vec3::new(10.0, 50.0, -13.5),
            Vec3::new(-0.1, 0.1, 1.0).normalize(),
            12.0,
        ),
    ];
    let band = 0;
    for (name, w, start, dir, len) in cases {
        let g = MajorantGrid::new(&w, 3);
        // The optical depth by the midpoint rule (layer faces fall on step
        // boundaries or cost O(step)).
        let steps = 200_000;
        let h = len / steps as f64;
        let tau: f64 = (0..steps)
            .map(|i| w.iop(start + dir * ((i as f64 + 0.5) * h) as f32, band).c() * h)
            .sum();
        let want = (-tau).exp();
        let n = 100_000;
        let mut rng = Pcg32::new(3, 0);
        let mut through = 0u64;
        for _ in 0..n {
            let mut pos = start;
            let mut left = len;
            loop {
                let flight = g.free_path(band, pos, dir, left, rng.exponential(1.0));
                let Some((t, cell)) = flight else {
                    through += 1;
                    break;
                };
                pos += dir * t as f32;
                left -= t;
                let xi = rng.uniform_f64() * g.bounds(band, cell).majorant;
                if g.collide(&w, band, cell, pos, xi) != Collision::Null {
                    break;
                }
            }
        }
        crate::testing::assert_binomial(through, n, want, name);
    }
}

/// In uniform water the free path is the plain exponential one.
#[test]
fn one_cell_gives_the_plain_exponential() {
    let w = WaterModel::Explicit { a: 0.1, b: 0.5 };
    let g = MajorantGrid::new(&w, 1);
    let m = g.bounds(0, 0).majorant;
    for tau in [0.0, 0.3, 2.0, 9.0] {
        let got = g.free_path(0, Vec3::new(1.0, 2.0, -3.0), Vec3::Z, f64::INFINITY, tau);
        assert_eq!(got, Some((tau / m, 0)));
        assert_eq!(
            g.free_path(0, Vec3::ZERO, Vec3::X, tau / m * 0.999, tau),
            None
        );
    }
}
