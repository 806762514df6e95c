use super::*;
use crate::rng::Pcg32;

#[test]
fn morton_round_trips() {
    let mut rng = Pcg32::new(1, 2);
    for _ in 0..10_000 {
        let q = [
            rng.next_u32() as u16,
            rng.next_u32() as u16,
            rng.next_u32() as u16,
        ];
        assert_eq!(demorton3(morton3(q)), q);
    }
    assert_eq!(morton3([1, 0, 0]), 1);
    assert_eq!(morton3([0, 1, 0]), 2);
    assert_eq!(morton3([0, 0, 1]), 4);
    assert_eq!(morton3([0xffff; 3]), (1u64 << 48) - 1);
}

/// With z = 0 the 3-D code orders (x, y) in 2-D Z-order: the renderer's
/// image tiles go 0, 1 across, then 2, 3 below, quadrant by quadrant.
#[test]
fn planar_codes_follow_the_2d_z_order() {
    let order = |x: u16, y: u16| morton3([x, y, 0]);
    assert!(order(0, 0) < order(1, 0));
    assert!(order(1, 0) < order(0, 1));
    assert!(order(0, 1) < order(1, 1));
    assert!(order(1, 1) < order(2, 0));
    assert!(order(1, 1) < order(0, 2));
    assert!(order(3, 3) < order(4, 0));
}

#[test]
fn wide_codes_round_trip_and_interleave() {
    let mut rng = Pcg32::new(3, 4);
    let mask = (1u64 << WIDE_BITS) - 1;
    for _ in 0..10_000 {
        let mut q = [0u64; 3];
        for v in &mut q {
            *v = ((rng.next_u32() as u64) << 32 | rng.next_u32() as u64) & mask;
        }
        assert_eq!(demorton3_wide(morton3_wide(q)), q);
        // The low 16 bits of each axis interleave as the 48-bit code does.
        let low = [q[0] as u16, q[1] as u16, q[2] as u16];
        assert_eq!(morton3_wide(q) as u64 & ((1 << 48) - 1), morton3(low));
    }
    assert_eq!(morton3_wide([1 << 41, 0, 0]), 1u128 << 123);
    assert_eq!(morton3_wide([0, 0, 1 << 41]), 1u128 << 125);
    assert_eq!(morton3_wide([mask; 3]), (1u128 << 126) - 1);
    // Order follows the highest differing bit.
    assert!(morton3_wide([0, 1 << 30, 0]) > morton3_wide([(1 << 30) - 1, 0, 0]));
}
