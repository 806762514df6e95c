use super::*;
use crate::rng::Pcg32;

/// Against the standard library's stable sort by the same bits, for
/// keys spread over every width, crowded on few values, all equal,
/// and with digits every key shares (skipped passes).
#[test]
fn sorts_like_a_stable_comparison_sort() {
    let mut rng = Pcg32::new(5, 2);
    let mut word = || (rng.next_u32() as u64) << 32 | rng.next_u32() as u64;
    let mut spare = Vec::new();
    for (n, bits) in [
        (0usize, 48u32),
        (1, 48),
        (2, 8),
        (1000, 48),
        (5000, 75),
        (8192, 126),
        (3000, 128),
        (65_536, 48),
        (777, 3),
    ] {
        for shape in 0..4 {
            let items: Vec<(u128, u32)> = (0..n)
                .map(|i| {
                    let wide = (word() as u128) << 64 | word() as u128;
                    let k = match shape {
                        0 => wide,
                        1 => wide % 7,
                        2 => 42,
                        // Only bits 16..24 and above 40 vary.
                        _ => wide & !0xff_ffff_00ff_ffff | 0x1200_0034,
                    };
                    (k, i as u32)
                })
                .collect();
            let mask = if bits >= 128 {
                u128::MAX
            } else {
                (1u128 << bits) - 1
            };
            let mut want = items.clone();
            want.sort_by_key(|x| x.0 & mask);
            let mut got = items.clone();
            sort_by_low_bits(&mut got, &mut spare, bits, |x| x.0);
            assert_eq!(got, want, "{n} keys of {bits} bits, shape {shape}");
        }
    }
}
