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

use super::pcg::{Pcg32, mix64, u32_to_unit};
use super::sobol::{laine_karras_permutation, shuffled_scrambled_sobol_2d};
use super::{pixel_hash, sample_offset};
use crate::unknown_name::UnknownName;

/// Which numbers a [`Sampler`] hands out.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "io", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "io", serde(rename_all = "lowercase"))]
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
    type Err = UnknownName;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .iter()
            .find(|(name, _)| *name == s)
            .map(|(_, kind)| *kind)
            .ok_or_else(|| UnknownName::new("sampler", s, "lab, independent or sobol"))
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

#[cfg(test)]
mod tests {
    use super::*;

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
        assert!("halton".parse::<SamplerKind>().unwrap_err().to_string().contains("sobol"));
    }
}
