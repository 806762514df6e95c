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

    /// An exponential free path of rate `rate` (1/m): an Exp(1) deviate
    /// ([`Pcg32::exp1`]) over the rate, or infinity (drawing nothing) when
    /// the rate is not positive.
    #[inline]
    pub fn exponential(&mut self, rate: f64) -> f64 {
        if rate > 0.0 {
            self.exp1() / rate
        } else {
            f64::INFINITY
        }
    }

    /// An Exp(1) deviate, by the ziggurat method (`rand_distr`'s `Exp1`,
    /// Marsaglia and Tsang's 256 layers): exact in distribution like
    /// -ln(u), and in about 99 % of draws one 64-bit word, a table lookup
    /// and a comparison instead of a logarithm.
    #[inline]
    pub fn exp1(&mut self) -> f64 {
        rand_distr::Distribution::<f64>::sample(&rand_distr::Exp1, self)
    }

    /// A standard normal deviate, by the ziggurat method (`rand_distr`'s
    /// `StandardNormal`, Doornik's ZIGNOR variant): no logarithm, square
    /// root or sine in about 99 % of draws, where Box–Muller needs all three.
    #[inline]
    pub fn normal(&mut self) -> f64 {
        rand_distr::Distribution::<f64>::sample(&rand_distr::StandardNormal, self)
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

/// What `rand_distr` draws from: the next two 32-bit outputs, the first in
/// the high half.
impl rand_core::TryRng for Pcg32 {
    type Error = std::convert::Infallible;

    #[inline]
    fn try_next_u32(&mut self) -> Result<u32, Self::Error> {
        Ok(self.next_u32())
    }

    #[inline]
    fn try_next_u64(&mut self) -> Result<u64, Self::Error> {
        let hi = self.next_u32() as u64;
        Ok((hi << 32) | self.next_u32() as u64)
    }

    fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), Self::Error> {
        for chunk in dst.chunks_mut(4) {
            let bytes = self.next_u32().to_le_bytes();
            chunk.copy_from_slice(&bytes[..chunk.len()]);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
