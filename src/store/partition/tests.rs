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
