//! Random numbers from a seed: O'Neill's PCG32 and SplitMix64's mix, the independent stream
//! behind [`Sampler`](super::Sampler)'s `independent` kind and the diffuse ray sets.

/// SplitMix64's finalizer: a bijective 64-bit mix with full avalanche.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A 32-bit integer hash with full avalanche (Wellons' `lowbias32`): the samplers' seeds per
/// dimension and `multijitter`'s jitter.
#[inline(always)]
pub(super) fn hash32(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^ (x >> 16)
}

/// O'Neill's PCG32 (XSH-RR 64/32), as `pcg32_srandom_r` / `pcg32_random_r`; the same sequence as
/// `rand_pcg::Pcg32::new(initstate, initseq)`.
#[derive(Clone, Debug)]
pub struct Pcg32 {
    state: u64,
    increment: u64,
}

impl Pcg32 {
    const MULTIPLIER: u64 = 6364136223846793005;

    /// Seeds the generator with a start state and a stream selector.
    pub fn new(initstate: u64, initseq: u64) -> Self {
        let mut rng = Pcg32 { state: 0, increment: (initseq << 1) | 1 };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(initstate);
        rng.next_u32();
        rng
    }

    /// The next 32 random bits.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(Self::MULTIPLIER).wrapping_add(self.increment);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rotation = (old >> 59) as u32;
        xorshifted.rotate_right(rotation)
    }

    /// A uniform number in `[0, 1)` with 24 random bits: `(next >> 8) · 2⁻²⁴`, exact in `f32`.
    #[inline]
    pub fn next_unit(&mut self) -> f64 {
        (self.next_u32() >> 8) as f64 * (1.0 / (1u64 << 24) as f64)
    }

    /// A uniform `f32` in `[0, 1)`.
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        u32_to_unit(self.next_u32())
    }
}

/// The top 24 bits of `x` as a number in `[0, 1)`, exact in `f32`.
#[inline]
pub(super) fn u32_to_unit(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pcg32_matches_the_reference_sequence() {
        // pcg32-demo's first outputs for pcg32_srandom_r(42, 54).
        let mut rng = Pcg32::new(42, 54);
        let first: Vec<u32> = (0..6).map(|_| rng.next_u32()).collect();
        assert_eq!(first, [0xa15c02b7, 0x7b47f409, 0xba1d3330, 0x83d2f293, 0xbfa4784b, 0xcbed606e]);
    }
}
