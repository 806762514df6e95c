use super::*;
use crate::rng::Pcg32;

#[test]
fn cells_are_balanced_for_crowded_points() {
    let mut rng = Pcg32::new(9, 0);
    let mut pts: Vec<Vec3> = (0..40_000)
        .map(|_| {
            let z = if rng.uniform_f32() < 0.25 {
                -10.0
            } else {
                -(-(1.0 - rng.uniform_f32()).ln() * 2.0).min(9.99)
            };
            Vec3::new(rng.uniform_f32() * 100.0, rng.uniform_f32() * 100.0, z)
        })
        .collect();
    let all = pts.clone();
    let part = Partition::from_pilot(&mut pts, 16);
    assert_eq!(part.cells(), 16);
    let mut counts = vec![0usize; 16];
    for p in &all {
        counts[part.cell_of(*p) as usize] += 1;
    }
    let (lo, hi) = (counts.iter().min().unwrap(), counts.iter().max().unwrap());
    assert!(*hi < 2 * *lo + 100, "{counts:?}");
    let back = Partition::from_nodes(part.nodes().to_vec()).unwrap();
    assert_eq!(back, part);
}

#[test]
fn malformed_node_lists_are_rejected() {
    use PartitionNode::*;
    assert!(Partition::from_nodes(vec![]).is_none());
    assert!(Partition::from_nodes(vec![
        Split {
            axis: 0,
            value: 1.0
        },
        Leaf
    ])
    .is_none());
    assert!(Partition::from_nodes(vec![Leaf, Leaf]).is_none());
    assert!(Partition::from_nodes(vec![
        Split {
            axis: 5,
            value: 1.0
        },
        Leaf,
        Leaf
    ])
    .is_none());
}

/// The lockstep descent finds the cell of the one-point descent: random
/// points inside and far outside, points on, just below and just above
/// every split plane, NaN coordinates, batches of every length.
#[test]
fn lockstep_descents_find_the_cells_single_descents_find() {
    let mut rng = Pcg32::new(3, 1);
    let crowded = |rng: &mut Pcg32| {
        let z = -(-(1.0 - rng.uniform_f32()).ln() * 2.0).min(14.99);
        Vec3::new(rng.uniform_f32() * 200.0, rng.uniform_f32() * 200.0, z)
    };
    let mut pilot: Vec<Vec3> = (0..100_000).map(|_| crowded(&mut rng)).collect();
    // A flat floor shared by many points, as at the sea floor.
    pilot.extend((0..10_000).map(|_| Vec3::new(rng.uniform_f32() * 200.0, 50.0, -15.0)));
    for cells in [1usize, 2, 7, 1000, 18_500] {
        let part = Partition::from_pilot(&mut pilot.clone(), cells);
        let mut points: Vec<Vec3> = (0..20_000)
            .map(|_| {
                Vec3::new(
                    rng.uniform_f32() * 260.0 - 30.0,
                    rng.uniform_f32() * 260.0 - 30.0,
                    rng.uniform_f32() * 30.0 - 22.0,
                )
            })
            .collect();
        points.extend(pilot.iter().step_by(7));
        for node in part.nodes() {
            if let PartitionNode::Split { axis, value } = *node {
                for v in [next_up(value), value, -next_up(-value)] {
                    let mut p = crowded(&mut rng);
                    p[axis as usize] = v;
                    points.push(p);
                }
            }
        }
        points.extend([
            Vec3::splat(f32::MAX),
            Vec3::splat(f32::NAN),
            Vec3::new(f32::NAN, 1.0, -1.0),
            Vec3::new(1e30, f32::NEG_INFINITY, 0.0),
        ]);
        let want: Vec<u32> = points.iter().map(|&p| part.cell_of(p)).collect();
        assert!(cells == 1 || want.iter().any(|&c| c != want[0]));
        for batch in [1usize, 5, 16, 64, 1000] {
            let mut got = vec![u32::MAX; points.len()];
            for (p, g) in points.chunks(batch).zip(got.chunks_mut(batch)) {
                part.cells_of(p, g);
            }
            assert_eq!(got, want, "{cells} cells, batches of {batch}");
        }
    }
}
