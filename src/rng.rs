//! Counter-keyed random streams (PCG32, as pbrt-v4 uses).
//!
//! Every photon, pixel or sample owns a stream chosen by its index and the
//! run seed, so results never depend on which thread did the work or in what
//! order. This is not a general-purpose RNG crate: it exists because the
//! stream-per-index contract is part of littoral's determinism guarantee.

const PCG_MULT: u64 = 0x5851_f42d_4c95_7f2d;

/// SplitMix64 finaliser: a bijective 64-bit mix used to decorrelate keys.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// PCG-XSH-RR 64/32 generator with a selectable sequence.
#[derive(Clone, Debug)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Pcg32 {
    /// The stream for item `index` of a run seeded with `seed`.
    pub fn new(seed: u64, index: u64) -> Self {
        let mut rng = Pcg32 {
            state: 0,
            inc: (mix64(index) << 1) | 1,
        };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(mix64(seed ^ 0x6c69_7474_6f72_616c));
        rng.next_u32();
        rng
    }

    /// Next 32 uniformly distributed bits.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(PCG_MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1) with 24 bits of precision.
    #[inline]
    pub fn uniform_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// Uniform in [0, 1) with 53 bits of precision.
    #[inline]
    pub fn uniform_f64(&mut self) -> f64 {
        let hi = (self.next_u32() >> 5) as u64;
        let lo = (self.next_u32() >> 6) as u64;
        ((hi << 26) | lo) as f64 * (1.0 / 9_007_199_254_740_992.0)
    }

    /// Uniform integer in [0, n) without modulo bias (Lemire's method).
    #[inline]
    pub fn below(&mut self, n: u32) -> u32 {
        debug_assert!(n > 0);
        let threshold = n.wrapping_neg() % n;
        loop {
            let m = self.next_u32() as u64 * n as u64;
            if (m as u32) >= threshold {
                return (m >> 32) as u32;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_pure_functions_of_seed_and_index() {
        let draw = |seed, index| {
            let mut rng = Pcg32::new(seed, index);
            (0..8).map(|_| rng.next_u32()).collect::<Vec<_>>()
        };
        assert_eq!(draw(7, 42), draw(7, 42));
        assert_ne!(draw(7, 42), draw(7, 43));
        assert_ne!(draw(7, 42), draw(8, 42));
    }

    /// Mean of U(0,1) is 1/2 with standard error 1/sqrt(12 n).
    #[test]
    fn uniform_mean_within_standard_error() {
        let n = 200_000;
        let mut rng = Pcg32::new(1, 0);
        let mean: f64 = (0..n).map(|_| rng.uniform_f64()).sum::<f64>() / n as f64;
        let se = 1.0 / (12.0 * n as f64).sqrt();
        assert!((mean - 0.5).abs() < 4.0 * se, "mean {mean}");
    }

    /// Each of 10 bins holds n/10 draws; chi-square with 9 dof stays below 27.9 (p = 0.001).
    #[test]
    fn below_is_uniform() {
        let n = 100_000;
        let mut counts = [0u32; 10];
        let mut rng = Pcg32::new(3, 9);
        for _ in 0..n {
            counts[rng.below(10) as usize] += 1;
        }
        let e = n as f64 / 10.0;
        let chi2: f64 = counts.iter().map(|&c| (c as f64 - e).powi(2) / e).sum();
        assert!(chi2 < 27.9, "chi2 {chi2}");
    }
}
