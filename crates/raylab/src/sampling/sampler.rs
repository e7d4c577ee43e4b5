//! The numbers behind a path's random decisions.
//!
//! A [`Sampler`] is made for one sample of one pixel from `(seed, pixel, sample index)` alone, and
//! hands out numbers in `[0, 1)` dimension by dimension: the pixel position first (two
//! dimensions), then the lens, then two or three per bounce. Nothing else goes in, so a picture
//! is the same whatever the thread count, the tiling or the order of the work.
//!
//! Three kinds ([`SamplerKind`]):
//! - `lab`: the lab's pixel sampling (`sample_offset`: the centre, then
//!   R₂), independent numbers after it. One sample per pixel is the lab's frame.
//! - `independent`: every number from a PCG32 stream seeded by a hash of the triple.
//! - `sobol` (the default for path tracing): each pair of dimensions is a 2D Sobol' point set,
//!   Owen-scrambled, with its sample order shuffled by a different hash per pair ("padded"
//!   Sobol'; Burley, "Practical Hash-based Owen Scrambling", JCGT 2020). Every power-of-two
//!   prefix of a pixel's samples is stratified in each pair, so it converges faster than
//!   independent samples, and the scrambling keeps it unbiased.

use glam::Vec2;

use super::{pixel_hash, sample_offset};

/// SplitMix64's finalizer: a bijective 64-bit mix with full avalanche.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
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
fn u32_to_unit(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// Which numbers a [`Sampler`] hands out.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum SamplerKind {
    /// The lab's pixel positions (centre, then R₂), independent numbers after them.
    Lab,
    /// Independent uniform numbers.
    Independent,
    /// Owen-scrambled, shuffled 2D Sobol' points per pair of dimensions.
    #[default]
    Sobol,
}

impl SamplerKind {
    /// Every kind with its command-line name.
    pub const ALL: [(&'static str, SamplerKind); 3] = [
        ("lab", SamplerKind::Lab),
        ("independent", SamplerKind::Independent),
        ("sobol", SamplerKind::Sobol),
    ];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        Self::ALL.iter().find(|(_, kind)| *kind == self).map_or("?", |(name, _)| name)
    }
}

impl std::str::FromStr for SamplerKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .iter()
            .find(|(name, _)| *name == s)
            .map(|(_, kind)| *kind)
            .ok_or_else(|| format!("unknown sampler '{s}': expected lab, independent or sobol"))
    }
}

/// The numbers for one sample of one pixel (see the module documentation).
#[derive(Clone, Debug)]
pub struct Sampler {
    kind: SamplerKind,
    pixel: (u32, u32),
    index: u32,
    /// A hash of (seed, pixel): the scrambles' and the streams' root.
    pixel_seed: u64,
    /// `index` with its bits reversed: the Sobol' points' first step, done once per sample.
    reversed_index: u32,
    /// The next dimension to hand out.
    dimension: u32,
    /// The independent numbers' stream, started at its first use (the lab's one sample per
    /// pixel never draws one).
    rng: Option<Pcg32>,
}

impl Sampler {
    /// The sampler of sample `index` of pixel `(x, y)` in a render with `seed`.
    #[inline]
    pub fn new(kind: SamplerKind, seed: u64, pixel: (u32, u32), index: u32) -> Sampler {
        let pixel_seed = mix64(pixel_hash(pixel.0, pixel.1) ^ mix64(seed));
        let reversed_index = index.reverse_bits();
        Sampler { kind, pixel, index, pixel_seed, reversed_index, dimension: 0, rng: None }
    }

    /// The stream of independent numbers: per sample, its state per pixel.
    #[inline]
    fn rng(&mut self) -> &mut Pcg32 {
        let (pixel_seed, index) = (self.pixel_seed, self.index);
        self.rng.get_or_insert_with(|| Pcg32::new(pixel_seed, index as u64))
    }

    /// The sample index.
    pub fn index(&self) -> u32 {
        self.index
    }

    /// Where this sample goes through its pixel, in `[0, 1)²`: always the first two dimensions.
    #[inline]
    pub fn pixel_2d(&mut self) -> Vec2 {
        debug_assert_eq!(self.dimension, 0, "the pixel position comes first");
        match self.kind {
            SamplerKind::Lab => {
                self.dimension = 2;
                sample_offset(self.pixel.0, self.pixel.1, self.index)
            }
            _ => self.next_2d(),
        }
    }

    /// The scrambling seeds of a dimension: three well-mixed 32-bit words (the index shuffle and
    /// the two coordinates' scrambles).
    #[inline]
    fn dimension_seeds(&self, dimension: u32) -> [u32; 3] {
        let base = (self.pixel_seed as u32) ^ (self.pixel_seed >> 32) as u32;
        let d = dimension.wrapping_mul(0x9e37_79b9);
        [
            hash32(base ^ d),
            hash32(base.wrapping_add(d) ^ 0x5bd1_e995),
            hash32(base ^ d ^ 0x68e3_1da4),
        ]
    }

    /// The next number in `[0, 1)`.
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        match self.kind {
            SamplerKind::Sobol => {
                let [shuffle, scramble, _] = self.dimension_seeds(self.dimension);
                self.dimension += 1;
                // nested_uniform_scramble(index, shuffle), its first reversal done in `new`.
                let index = laine_karras_permutation(self.reversed_index, shuffle).reverse_bits();
                // The first Sobol' dimension is the bit-reversed index; Owen-scrambling it is
                // reverse(LK(reverse(reverse(index)))) = reverse(LK(index)).
                u32_to_unit(laine_karras_permutation(index, scramble).reverse_bits())
            }
            _ => {
                self.dimension += 1;
                self.rng().next_f32()
            }
        }
    }

    /// The next two numbers in `[0, 1)²`, stratified together for `sobol`.
    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        match self.kind {
            SamplerKind::Sobol => {
                let seeds = self.dimension_seeds(self.dimension);
                self.dimension += 2;
                let p = shuffled_scrambled_sobol_2d(self.reversed_index, seeds);
                Vec2::new(u32_to_unit(p[0]), u32_to_unit(p[1]))
            }
            _ => {
                self.dimension += 2;
                let rng = self.rng();
                Vec2::new(rng.next_f32(), rng.next_f32())
            }
        }
    }
}

/// A 32-bit integer hash with full avalanche (Wellons' `lowbias32`).
#[inline]
fn hash32(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^ (x >> 16)
}

/// The second dimension of the Sobol' sequence (the first is the bit reversal of the index),
/// as 32-bit fixed point: the XOR of the direction numbers of the index's set bits, a byte of
/// the index at a time from tables (no branch per bit).
#[cfg(test)]
fn sobol_second_dimension(index: u32) -> u32 {
    let [b0, b1, b2, b3] = index.to_le_bytes();
    SOBOL_SECOND_DIMENSION[0][b0 as usize]
        ^ SOBOL_SECOND_DIMENSION[1][b1 as usize]
        ^ SOBOL_SECOND_DIMENSION[2][b2 as usize]
        ^ SOBOL_SECOND_DIMENSION[3][b3 as usize]
}

/// `SOBOL_SECOND_DIMENSION[k][b]`: the XOR of the direction numbers of bits `8k..8k+8` set in `b`.
static SOBOL_SECOND_DIMENSION: [[u32; 256]; 4] = sobol_second_dimension_tables();

/// The tables, built at compile time from the direction numbers `v₀ = 2³¹`, `vₖ = vₖ₋₁ ⊕ (vₖ₋₁ ≫ 1)`.
const fn sobol_second_dimension_tables() -> [[u32; 256]; 4] {
    let mut directions = [0u32; 32];
    directions[0] = 1 << 31;
    let mut k = 1;
    while k < 32 {
        directions[k] = directions[k - 1] ^ (directions[k - 1] >> 1);
        k += 1;
    }
    let mut tables = [[0u32; 256]; 4];
    let mut byte = 0;
    while byte < 4 {
        let mut value = 0;
        while value < 256 {
            let mut result = 0;
            let mut bit = 0;
            while bit < 8 {
                if value & (1 << bit) != 0 {
                    result ^= directions[byte * 8 + bit];
                }
                bit += 1;
            }
            tables[byte][value] = result;
            value += 1;
        }
        byte += 1;
    }
    tables
}

/// Laine and Karras' hash-based permutation of the bits of `x` from high to low, each bit's flip
/// depending only on the bits below it (in reversed order: a nested uniform scramble).
#[inline]
fn laine_karras_permutation(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

/// An Owen scramble of a 32-bit fixed-point number (Burley 2020, listing 3).
#[cfg(test)]
fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    laine_karras_permutation(x.reverse_bits(), seed).reverse_bits()
}

/// Point `index` of a 2D Sobol' set whose order is shuffled and whose coordinates are
/// Owen-scrambled, each by its own seed (Burley 2020, listing 5), given `index` bit-reversed.
///
/// The same bits as `shuffled_scrambled_sobol_2d_reference` (tested), with three bit reversals
/// where the listing has five, two of them done as one 64-bit reversal: the shuffled index's
/// reversal is the permutation's input as it stands, and the second dimension's reversal is read
/// from a table of reversed direction numbers indexed by the permuted bits directly.
#[inline]
fn shuffled_scrambled_sobol_2d(
    reversed_index: u32,
    [shuffle, seed_x, seed_y]: [u32; 3],
) -> [u32; 2] {
    // nested_uniform_scramble(index, shuffle) = reverse(permuted).
    let permuted = laine_karras_permutation(reversed_index, shuffle);
    let index = permuted.reverse_bits();
    let [b0, b1, b2, b3] = permuted.to_le_bytes();
    // reverse(sobol_second_dimension(index)).
    let y_reversed = SOBOL_SECOND_DIMENSION_REVERSED[0][b0 as usize]
        ^ SOBOL_SECOND_DIMENSION_REVERSED[1][b1 as usize]
        ^ SOBOL_SECOND_DIMENSION_REVERSED[2][b2 as usize]
        ^ SOBOL_SECOND_DIMENSION_REVERSED[3][b3 as usize];
    let x = laine_karras_permutation(index, seed_x);
    let y = laine_karras_permutation(y_reversed, seed_y);
    // reverse(x) in the low half, reverse(y) in the high half.
    let both = ((x as u64) << 32 | y as u64).reverse_bits();
    [both as u32, (both >> 32) as u32]
}

/// Burley's listing 5 as written, the twin of [`shuffled_scrambled_sobol_2d`].
#[cfg(test)]
fn shuffled_scrambled_sobol_2d_reference(
    index: u32,
    [shuffle, seed_x, seed_y]: [u32; 3],
) -> [u32; 2] {
    let index = nested_uniform_scramble(index, shuffle);
    // x = reverse(index) scrambled: reverse(LK(reverse(reverse(index)))) = reverse(LK(index)).
    let x = laine_karras_permutation(index, seed_x).reverse_bits();
    let y = nested_uniform_scramble(sobol_second_dimension(index), seed_y);
    [x, y]
}

/// `SOBOL_SECOND_DIMENSION_REVERSED[k][b]`: `reverse(sobol_second_dimension(reverse(w)))` for the
/// word `w` whose byte `k` is `b` and whose other bytes are zero, so that for any `w` it is the
/// XOR of the entries of `w`'s four bytes.
static SOBOL_SECOND_DIMENSION_REVERSED: [[u32; 256]; 4] = sobol_second_dimension_reversed_tables();

const fn sobol_second_dimension_reversed_tables() -> [[u32; 256]; 4] {
    let mut tables = [[0u32; 256]; 4];
    let mut byte = 0;
    while byte < 4 {
        let mut value = 0;
        while value < 256 {
            // Byte `byte` of w reversed is byte `3 - byte` of reverse(w), its bits reversed.
            let reversed = (value as u8).reverse_bits() as usize;
            tables[byte][value] = SOBOL_SECOND_DIMENSION[3 - byte][reversed].reverse_bits();
            value += 1;
        }
        byte += 1;
    }
    tables
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

    #[test]
    fn the_second_sobol_dimension_tables_equal_the_bit_by_bit_definition() {
        let bit_by_bit = |mut index: u32| {
            let (mut v, mut result) = (1u32 << 31, 0);
            while index != 0 {
                if index & 1 != 0 {
                    result ^= v;
                }
                index >>= 1;
                v ^= v >> 1;
            }
            result
        };
        let mut rng = Pcg32::new(5, 6);
        for index in (0..4096).chain((0..10_000).map(|_| rng.next_u32())).chain([u32::MAX]) {
            assert_eq!(sobol_second_dimension(index), bit_by_bit(index), "{index}");
        }
    }

    #[test]
    fn the_fast_sobol_points_equal_burleys_listing() {
        let mut rng = Pcg32::new(8, 9);
        let mut indices: Vec<u32> = (0..2048).chain([u32::MAX]).collect();
        indices.extend((0..20_000).map(|_| rng.next_u32()));
        for i in indices {
            let seeds = [rng.next_u32(), rng.next_u32(), rng.next_u32()];
            assert_eq!(
                shuffled_scrambled_sobol_2d(i.reverse_bits(), seeds),
                shuffled_scrambled_sobol_2d_reference(i, seeds),
                "index {i}, seeds {seeds:?}"
            );
        }
    }

    #[test]
    fn the_second_sobol_dimension_is_the_known_sequence() {
        // Direction numbers 1/2, 3/4, 5/8, 15/16 (Joe and Kuo's dimension 2), combined by the
        // index's bits (not in Gray-code order): 0, 1/2, 3/4, 1/4, 5/8, 1/8, 3/8, 7/8, 15/16.
        let expected = [0.0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875, 0.9375];
        for (i, &e) in expected.iter().enumerate() {
            assert_eq!(sobol_second_dimension(i as u32) as f64 / 2f64.powi(32), e, "{i}");
        }
    }

    #[test]
    fn samplers_depend_on_seed_pixel_and_index_alone() {
        for kind in [SamplerKind::Lab, SamplerKind::Independent, SamplerKind::Sobol] {
            let draw = |seed, pixel, index| {
                let mut s = Sampler::new(kind, seed, pixel, index);
                let p = s.pixel_2d();
                [p.x, p.y, s.next_1d(), s.next_2d().x, s.next_2d().y]
            };
            assert_eq!(draw(1, (3, 4), 5), draw(1, (3, 4), 5), "{kind:?}");
            assert_ne!(draw(1, (3, 4), 5), draw(2, (3, 4), 5), "{kind:?}");
            assert_ne!(draw(1, (3, 4), 5), draw(1, (4, 3), 5), "{kind:?}");
            assert_ne!(draw(1, (3, 4), 5), draw(1, (3, 4), 6), "{kind:?}");
        }
        assert_eq!(Sampler::new(SamplerKind::Lab, 9, (2, 2), 0).pixel_2d(), Vec2::splat(0.5));
    }

    #[test]
    fn sobol_pairs_are_stratified_at_every_power_of_two() {
        // 2^m consecutive samples (from 0) put exactly one point in each cell of every
        // elementary interval shape 2^a × 2^(m−a) (a (0, m, 2)-net), after scrambling too.
        for (pixel, dimension_pairs) in [((0, 0), 3), ((17, 91), 3)] {
            for m in [2u32, 4, 6, 8] {
                let n = 1u32 << m;
                let points: Vec<Vec<Vec2>> = (0..n)
                    .map(|i| {
                        let mut s = Sampler::new(SamplerKind::Sobol, 7, pixel, i);
                        (0..dimension_pairs).map(|_| s.next_2d()).collect()
                    })
                    .collect();
                for pair in 0..dimension_pairs {
                    for a in 0..=m {
                        let (cx, cy) = (1u32 << a, 1u32 << (m - a));
                        let mut cells = vec![0u32; n as usize];
                        for p in &points {
                            let p = p[pair];
                            let (x, y) = ((p.x * cx as f32) as u32, (p.y * cy as f32) as u32);
                            cells[(y * cx + x) as usize] += 1;
                        }
                        assert!(cells.iter().all(|&c| c == 1), "pair {pair}, m {m}, a {a}");
                    }
                }
            }
        }
    }

    #[test]
    fn sobol_one_dimensional_samples_are_stratified() {
        for m in [3u32, 5, 7] {
            let n = 1u32 << m;
            let mut cells = vec![0u32; n as usize];
            for i in 0..n {
                let mut s = Sampler::new(SamplerKind::Sobol, 3, (5, 6), i);
                s.next_2d();
                cells[(s.next_1d() * n as f32) as usize] += 1;
            }
            assert!(cells.iter().all(|&c| c == 1), "{m}: {cells:?}");
        }
    }

    #[test]
    fn sampler_kinds_parse() {
        for (name, kind) in SamplerKind::ALL {
            assert_eq!(name.parse::<SamplerKind>(), Ok(kind));
            assert_eq!(kind.name(), name);
        }
        assert!("halton".parse::<SamplerKind>().unwrap_err().contains("sobol"));
    }
}
