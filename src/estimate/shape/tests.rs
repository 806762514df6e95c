use super::*;
use crate::bounds::Aabb;
use crate::photon::{volume_layer, Photon};
use crate::rng::Pcg32;
use crate::spectral::BandGrid;
use crate::store::InMemoryMap;

/// Band shares of photons travelling up and down above and below 4 m.
const UP_SHALLOW: [f64; 4] = [0.4, 0.3, 0.2, 0.1];
const DOWN_SHALLOW: [f64; 4] = [0.1, 0.2, 0.3, 0.4];
const UP_DEEP: [f64; 4] = [0.25, 0.25, 0.25, 0.25];
const DOWN_DEEP: [f64; 4] = [0.7, 0.1, 0.1, 0.1];

/// Weight 1 for photons travelling toward the viewer's side, else 0: the
/// grid then holds each hemisphere's band shares.
fn hemisphere(p: &Photon, view: usize) -> f64 {
    f64::from(u8::from((p.direction.z > 0.0) == (view == VIEW_UP)))
}

/// `photons` in the 10 x 10 x 8 m test box, over `bands` bands of
/// 500-530 nm.
fn box_map(photons: impl IntoIterator<Item = (Photon, u16)>, bands: usize) -> InMemoryMap {
    let bounds = Aabb {
        min: Vec3::new(0.0, 0.0, -8.0),
        max: Vec3::new(10.0, 10.0, 0.0),
    };
    InMemoryMap::new(
        photons,
        BandGrid::even(500.0, 530.0, bands).unwrap(),
        bounds,
    )
    .unwrap()
}

/// A grid over the 10 m x 10 m test domain, without target columns.
fn plan(voxels: usize, boundaries_m: &[f64], views: usize) -> GridPlan<'_> {
    GridPlan {
        size_m: [10.0, 10.0],
        voxels,
        layers_only: false,
        boundaries_m,
        columns: &[],
        views,
    }
}

fn pick(shares: &[f64; 4], u: f64) -> u16 {
    let mut acc = 0.0;
    for (i, s) in shares.iter().enumerate() {
        acc += s;
        if u < acc {
            return i as u16;
        }
    }
    3
}

/// `n` photons uniform in a 10 x 10 x 8 m box, half travelling up, with
/// the band shares above per hemisphere and depth.
fn map(n: u64) -> InMemoryMap {
    let photons = (0..n).map(|i| {
        let mut rng = Pcg32::new(5, i);
        let p = Vec3::new(
            10.0 * rng.uniform_f32(),
            10.0 * rng.uniform_f32(),
            -8.0 * rng.uniform_f32(),
        );
        let up = rng.uniform_f64() < 0.5;
        let shares = match (up, p.z > -4.0) {
            (true, true) => &UP_SHALLOW,
            (false, true) => &DOWN_SHALLOW,
            (true, false) => &UP_DEEP,
            (false, false) => &DOWN_DEEP,
        };
        let photon = Photon {
            position: p,
            direction: if up { Vec3::Z } else { -Vec3::Z },
            band: pick(shares, rng.uniform_f64()),
            power: 1.0,
            group: 0,
        };
        (photon, volume_layer(photon.direction))
    });
    box_map(photons, 4)
}

/// Away from the 4 m change (more than a layer's height), the grid reads
/// each viewing direction's band shares (weighted here by hemisphere) within four standard errors of a
/// multinomial share over the photons of the voxels it interpolates (a
/// lower bound on that count: one voxel's).
#[test]
fn grid_reads_the_band_shares_of_each_hemisphere() {
    let n = 400_000;
    let m = map(n);
    let voxels = 64;
    let g = BandShapeGrid::build(&m, &plan(voxels, &[], 2), &hemisphere).unwrap();
    let [nx, ny, nz] = g.dims();
    assert!(nx * ny * nz >= 32 && nz >= 3, "{:?}", g.dims());
    let per_voxel_hemisphere = n as f64 / (nx * ny * nz) as f64 / 2.0;
    let mut out = [0.0; 4];
    for (x, up, want) in [
        (Vec3::new(5.0, 5.0, -0.5), true, UP_SHALLOW),
        (Vec3::new(2.0, 7.0, -0.8), false, DOWN_SHALLOW),
        (Vec3::new(8.0, 3.0, -7.5), true, UP_DEEP),
        (Vec3::new(5.0, 5.0, -7.2), false, DOWN_DEEP),
    ] {
        assert!(g.shape_at(x, up, &mut out));
        assert!((out.iter().sum::<f64>() - 1.0).abs() < 1e-6);
        for (o, w) in out.iter().zip(want) {
            let se = (w * (1.0 - w) / per_voxel_hemisphere).sqrt();
            assert!(
                (o - w).abs() < 4.0 * se,
                "{x} up {up}: {out:?} against {want:?}"
            );
        }
    }
}

/// The grid refines as photons are added (its smoothing shrinks), within
/// its bound; a direction with no weight has no shape.
#[test]
fn voxels_follow_the_photon_count() {
    let a = BandShapeGrid::planned_voxels(512_000, 128, 400, 1 << 20);
    let b = BandShapeGrid::planned_voxels(4_096_000, 128, 400, 1 << 20);
    assert_eq!(b, 8 * a);
    assert_eq!(
        BandShapeGrid::planned_voxels(u64::MAX / 2, 128, 400, 500),
        500
    );
    assert_eq!(BandShapeGrid::planned_voxels(10, 128, 400, 500), 1);
    let photons = (0..1000).map(|i| {
        let p = Photon {
            position: Vec3::new(i as f32 % 10.0, 5.0, -1.0 - (i % 7) as f32),
            direction: -Vec3::Z,
            band: (i % 4) as u16,
            power: 1.0,
            group: 0,
        };
        (p, volume_layer(p.direction))
    });
    let m = box_map(photons, 4);
    let g = BandShapeGrid::build(&m, &plan(8, &[], 2), &hemisphere).unwrap();
    let mut out = [0.0; 4];
    assert!(!g.shape_at(Vec3::new(5.0, 5.0, -3.0), true, &mut out));
    assert!(g.shape_at(Vec3::new(5.0, 5.0, -3.0), false, &mut out));
}

/// Where the IOPs jump at a depth, a layer ends there and shapes are not
/// blended across it: above a jump at 2 m every photon is band 0, below it
/// band 1, and a site just above (or below) the jump gets its own side's
/// shape exactly, where a layer across the jump would mix the two.
#[test]
fn shapes_are_not_blended_across_an_iop_jump() {
    let photons = (0..4000).map(|i| {
        let z = -0.001 - 3.998 * ((i as f32 + 0.5) / 4000.0);
        let p = Photon {
            position: Vec3::new((i % 10) as f32 + 0.5, 5.0, z),
            direction: -Vec3::Z,
            band: u16::from(z < -2.0),
            power: 1.0,
            group: (i % 16) as u8,
        };
        (p, volume_layer(p.direction))
    });
    let bounds = Aabb {
        min: Vec3::new(0.0, 0.0, -4.0),
        max: Vec3::new(10.0, 10.0, 0.0),
    };
    let m = InMemoryMap::new(photons, BandGrid::even(500.0, 530.0, 2).unwrap(), bounds).unwrap();
    let mut out = [0.0; 2];
    for (x_z, want) in [(-1.95, [1.0, 0.0]), (-2.05, [0.0, 1.0])] {
        let g = BandShapeGrid::build(&m, &plan(4, &[2.0], 2), &hemisphere).unwrap();
        assert!(g.shape_at(Vec3::new(5.0, 5.0, x_z), false, &mut out));
        // Exact but for the rounding of the profile's scaling.
        assert!(
            out.iter().zip(want).all(|(o, w)| (o - w).abs() < 1e-12),
            "at z = {x_z}: {out:?}"
        );
        // One layer without the jump mixes them.
        let blind = BandShapeGrid::build(&m, &plan(1, &[], 2), &hemisphere).unwrap();
        assert!(blind.shape_at(Vec3::new(5.0, 5.0, x_z), false, &mut out));
        assert!(out[0] > 0.0 && out[1] > 0.0, "{out:?}");
    }
}

/// A third viewing direction holds its own weights' shares: with photons
/// of four bands travelling up, the view that weighs only band 2 (as a
/// wider truncated peak weighs some photons less than another) reads
/// [0, 0, 1, 0] where the plain view reads even shares, so an estimate
/// looking down at a target gets the band shape of its own phase weights.
#[test]
fn each_view_holds_its_own_shares() {
    let m = map(40_000);
    let weight = |p: &Photon, view: usize| match view {
        VIEW_UP_TARGET => f64::from(u8::from(p.band == 2 && p.direction.z > 0.0)),
        v => hemisphere(p, v),
    };
    let g = BandShapeGrid::build(&m, &plan(8, &[], 3), &weight).unwrap();
    assert_eq!(g.views(), 3);
    let x = Vec3::new(5.0, 5.0, -3.0);
    let mut out = [0.0; 4];
    assert!(g.shape_and_groups_at(x, VIEW_UP_TARGET, &mut out, None));
    assert_eq!(out, [0.0, 0.0, 1.0, 0.0]);
    assert!(g.shape_and_groups_at(x, VIEW_UP, &mut out, None));
    assert!(out.iter().all(|&s| s > 0.05), "{out:?}");
}

/// Cells end at a target's footprint and shapes are not blended across it:
/// with every photon over a 2 m square band 0 and every other photon band
/// 1, a site over the square reads [1, 0] and a site just beside it [0, 1]
/// exactly, where the even cells (5 m here) would mix the two.
#[test]
fn the_light_over_a_target_keeps_its_own_shape() {
    let photons = (0..20_000u64).map(|i| {
        let mut rng = Pcg32::new(9, i);
        let position = Vec3::new(
            10.0 * rng.uniform_f32(),
            10.0 * rng.uniform_f32(),
            -8.0 * rng.uniform_f32(),
        );
        let over = (4.0..6.0).contains(&position.x) && (4.0..6.0).contains(&position.y);
        let p = Photon {
            position,
            direction: Vec3::Z,
            band: u16::from(!over),
            power: 1.0,
            group: 0,
        };
        (p, volume_layer(p.direction))
    });
    let m = box_map(photons, 2);
    let target = [Aabb {
        min: Vec3::new(4.0, 4.0, -6.0),
        max: Vec3::new(6.0, 6.0, -5.0),
    }];
    let with_column = GridPlan {
        columns: &target,
        ..plan(8, &[], 2)
    };
    let g = BandShapeGrid::build(&m, &with_column, &hemisphere).unwrap();
    assert_eq!((g.dims(), g.columns()), ([2, 2, 2], 1));
    let mut out = [0.0; 2];
    for (x, y, want) in [
        (5.0, 5.0, [1.0, 0.0]),
        (4.1, 5.9, [1.0, 0.0]),
        (3.9, 5.0, [0.0, 1.0]),
        (5.0, 6.1, [0.0, 1.0]),
    ] {
        assert!(g.shape_at(Vec3::new(x, y, -2.0), true, &mut out));
        assert_eq!(out, want, "at ({x}, {y})");
    }
    // The even cells alone blend the square's light with its surroundings'.
    let blind = BandShapeGrid::build(&m, &plan(8, &[], 2), &hemisphere).unwrap();
    assert!(blind.shape_at(Vec3::new(5.0, 5.0, -2.0), true, &mut out));
    assert!(out[0] < 0.5 && out[1] > 0.5, "{out:?}");
    // A target across the periodic edge has its cells at both ends.
    let wrapped = [Aabb {
        min: Vec3::new(-1.0, 4.0, -6.0),
        max: Vec3::new(1.0, 6.0, -5.0),
    }];
    let plan = GridPlan {
        columns: &wrapped,
        ..plan(8, &[], 2)
    };
    assert_eq!(plan.most_cells(), (2 * 2 + 1) * 2);
    let g = BandShapeGrid::build(&m, &plan, &hemisphere).unwrap();
    let mut out = [0.0; 2];
    // Photons at x < 1 and x > 9 (y 4-6) are band 1 but fall in the
    // column: it reads them on both sides of the edge.
    for x in [0.5, 9.5] {
        assert!(g.shape_at(Vec3::new(x, 5.0, -2.0), true, &mut out));
        assert_eq!(out, [0.0, 1.0], "at x = {x}");
    }
    // Beside it, the even cells hold part of the square's band 0.
    assert!(g.shape_at(Vec3::new(1.5, 5.0, -2.0), true, &mut out));
    assert!(out[0] > 0.0, "{out:?}");
}

/// The bins partition every direction: light travelling down falls in the
/// cones around the sun by its angle to it, then by steepness; light
/// travelling up by its elevation.
#[test]
fn direction_bins_partition_the_sphere() {
    let sun = Vec3::new(0.37, 0.0, -0.93).normalize();
    let at = |deg: f32| {
        let t = deg.to_radians();
        // Turned from the sun toward the +y axis.
        (sun * t.cos() + Vec3::Y * t.sin()).normalize()
    };
    for (dir, want) in [
        (sun, 0),
        (at(10.0), 1),
        (at(20.0), 2),
        (at(40.0), 3),
        (-Vec3::Z, 2),
        (Vec3::new(-0.6, 0.0, -0.8), 4),
        (Vec3::new(0.0, 0.95, -0.31), 5),
        (Vec3::new(0.0, 0.9, 0.44), 6),
        (Vec3::new(0.0, 0.6, 0.8), 7),
        (Vec3::Z, 8),
    ] {
        assert_eq!(direction_bin(dir, sun), want, "{dir:?}");
    }
    let mut rng = Pcg32::new(3, 0);
    let mut seen = [0u32; DIRECTION_BINS];
    for _ in 0..10_000 {
        let z = 1.0 - 2.0 * rng.uniform_f32();
        let s = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * rng.uniform_f32();
        seen[direction_bin(Vec3::new(s * phi.cos(), s * phi.sin(), z), sun)] += 1;
    }
    assert!(seen.iter().all(|&n| n > 0), "{seen:?}");
}

/// Bins mixed by weight: with every photon of bin 0 in band 0 and every
/// other in band 1, weights 3 on bin 0's view and 1 on bin 8's read
/// [0.75, 0.25]; a bin without photons where the site is drops out.
#[test]
fn binned_shapes_mix_by_weight() {
    let sun = -Vec3::Z;
    let photons = (0..20_000u64).map(|i| {
        let mut rng = Pcg32::new(4, i);
        let position = Vec3::new(
            10.0 * rng.uniform_f32(),
            10.0 * rng.uniform_f32(),
            -8.0 * rng.uniform_f32(),
        );
        let direction = if i % 2 == 0 { sun } else { Vec3::Z };
        let p = Photon {
            position,
            direction,
            band: u16::from(direction_bin(direction, sun) != 0),
            power: 1.0,
            group: (i % 16) as u8,
        };
        (p, volume_layer(p.direction))
    });
    let m = box_map(photons, 2);
    let weight =
        |p: &Photon, view: usize| f64::from(u8::from(direction_bin(p.direction, sun) == view));
    let g = BandShapeGrid::build(&m, &plan(8, &[], DIRECTION_BINS), &weight).unwrap();
    let x = Vec3::new(5.0, 5.0, -3.0);
    let (mut out, mut groups, mut scratch) = ([0.0; 2], vec![0.0; GROUPS * 2], Vec::new());
    let weights = [(0, 3.0), (8, 1.0), (4, 5.0)];
    assert!(g.mixed_shape_and_groups_at(x, &weights, &mut out, Some(&mut groups), &mut scratch));
    assert!(
        (out[0] - 0.75).abs() < 1e-12 && (out[1] - 0.25).abs() < 1e-12,
        "{out:?}"
    );
    // Each bin's shape is exact here, so no group moves it.
    assert!(groups.iter().all(|d| d.abs() < 1e-6), "{groups:?}");
    assert!(!g.mixed_shape_and_groups_at(x, &[(4, 1.0)], &mut out, None, &mut scratch));
}

/// The rate of an exponential profile across a layer is recovered from
/// its mean place, and a profile averages 1 over its layer (within what
/// its f32 rate and scale hold: 6e-8 of rates up to 40 in the exponent).
#[test]
fn a_layers_profile_is_found_from_its_mean_place() {
    for x in [-30.0, -3.0, -0.5, -1e-5, 0.0, 1e-5, 0.7, 2.5, 12.0, 35.0] {
        let found = rate_of_mean(mean_place(x));
        assert!((found - x).abs() < 1e-6 * (1.0 + x.abs()), "{x}: {found}");
        // Midpoint rule over 10 000 slices.
        let n = 10_000;
        let mean = (0..n)
            .map(|i| Profile::new(x).at((i as f64 + 0.5) / n as f64))
            .sum::<f64>()
            / n as f64;
        assert!((mean - 1.0).abs() < 1e-5, "{x}: {mean}");
    }
    assert_eq!(rate_of_mean(0.0), rate_of_mean(mean_place(MAX_RATE)));
    assert_eq!(rate_pools(&[500.0, 507.5, 515.0]), [(0, 1), (1, 2), (2, 3)]);
    assert_eq!(rate_pools(&[500.0, 503.0, 506.0, 509.0])[1], (0, 4));
}

/// Light falling with depth at each band's own rate (0.2, 0.8, 1.6 and
/// 3 per m, as from the blue to the near infrared): the grid reads each
/// band's share at a depth, not its mean over the depth's layer. Over
/// eight independent maps the mean share is within four standard errors
/// of the exact one, at depths near the surface, mid-layer and near a
/// layer's edges; the layers' mean shares, which the grid read before,
/// miss it by many.
#[test]
fn shares_follow_light_falling_at_each_bands_own_rate() {
    const K: [f64; 4] = [0.2, 0.8, 1.6, 3.0];
    const DEPTH: f64 = 8.0;
    let exact = |d: f64| {
        let rho = K.map(|k| k * (-k * d).exp() / -(-k * DEPTH).exp_m1());
        let t: f64 = rho.iter().sum();
        rho.map(|r| r / t)
    };
    let (maps, n) = (8u64, 200_000u64);
    let depths = [0.05, 0.3, 0.6, 1.0, 1.5, 2.5];
    let mut reads = vec![[[0.0f64; 4]; 6]; maps as usize];
    let mut means = vec![[[0.0f64; 4]; 6]; maps as usize];
    for (m, (read, mean)) in reads.iter_mut().zip(&mut means).enumerate() {
        let photons = (0..n).map(|i| {
            let mut rng = Pcg32::new(11 + m as u64, i);
            let band = rng.below(4) as usize;
            // Depth from exp(-k d) truncated at DEPTH, by inversion.
            let u = rng.uniform_f64();
            let d = -(1.0 + u * (-K[band] * DEPTH).exp_m1()).ln() / K[band];
            let photon = Photon {
                position: Vec3::new(
                    10.0 * rng.uniform_f32(),
                    10.0 * rng.uniform_f32(),
                    -(d.min(DEPTH - 1e-3) as f32),
                ),
                direction: Vec3::Z,
                band: band as u16,
                power: 1.0,
                group: 0,
            };
            (photon, volume_layer(photon.direction))
        });
        let map = box_map(photons, 4);
        let layers = GridPlan {
            layers_only: true,
            ..plan(4, &[], 2)
        };
        let g = BandShapeGrid::build(&map, &layers, &hemisphere).unwrap();
        assert_eq!(g.dims(), [1, 1, 4]);
        for (j, &d) in depths.iter().enumerate() {
            let x = Vec3::new(5.0, 5.0, -d as f32);
            assert!(g.shape_at(x, true, &mut read[j]));
            let v = g.voxel_of(x);
            for (o, s) in mean[j].iter_mut().zip(&g.shapes[v * 2 * 4..][..4]) {
                *o = f64::from(*s);
            }
        }
    }
    let stats = |all: &[[[f64; 4]; 6]], j: usize, b: usize| {
        let v: Vec<f64> = all.iter().map(|r| r[j][b]).collect();
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (v.len() - 1) as f64;
        (mean, (var / v.len() as f64).sqrt())
    };
    let mut missed_before = 0;
    for (j, &d) in depths.iter().enumerate() {
        let want = exact(d);
        for (b, &want) in want.iter().enumerate() {
            let (got, se) = stats(&reads, j, b);
            assert!(
                (got - want).abs() <= 4.0 * se,
                "depth {d} band {b}: {got:.5} +- {se:.5} against {want:.5}"
            );
            let (layer_mean, se_mean) = stats(&means, j, b);
            if (layer_mean - want).abs() > 10.0 * (se + se_mean) {
                missed_before += 1;
            }
        }
    }
    assert!(
        missed_before >= 12,
        "the layers' means miss in {missed_before} of 24"
    );
}
