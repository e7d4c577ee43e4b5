//! The numbers behind a path's random decisions.
//!
//! A [`Sampler`] is made for one sample of one pixel from `(seed, pixel, sample index)` alone, and
//! hands out numbers in `[0, 1)` dimension by dimension: the pixel position first (two
//! dimensions), then the lens, then six per path vertex (a pair for the light and the point on
//! it, one for the BSDF's lobe, a pair for its direction, one for Russian roulette). Nothing
//! else goes in, so a picture is the same whatever the thread count, the tiling or the order of
//! the work.
//!
//! Four kinds ([`SamplerKind`]):
//! - `lab`: the lab's pixel sampling (`sample_offset`: the centre, then
//!   R₂), independent numbers after it. One sample per pixel is the lab's frame.
//! - `independent`: every number from a PCG32 stream seeded by a hash of the triple.
//! - `sobol` (the default for path tracing): each pair of dimensions is a 2D Sobol' point set,
//!   Owen-scrambled, with its sample order shuffled by a different hash per pair ("padded"
//!   Sobol'; Burley, "Practical Hash-based Owen Scrambling", JCGT 2020). Every power-of-two
//!   prefix of a pixel's samples is stratified in each pair, so it converges faster than
//!   independent samples, and the scrambling keeps it unbiased.
//! - `multijitter`: each pair of dimensions is a correlated multi-jittered pattern of the
//!   render's sample count (Kensler 2013; Mitsuba 3's best sampler for most scenes; see
//!   `multijitter.rs`): lower error than `sobol` where pixels integrate edges, higher where they
//!   integrate smooth functions. It needs the sample count up front ([`Sampler::counted`]); made
//!   without one, or for a sample beyond it, a sampler of this kind is a `sobol` one.

use glam::Vec2;

use super::multijitter::{self, Grid};
use super::pcg::{Pcg32, hash32, mix64, u32_to_unit};
use super::sobol::{laine_karras_permutation, shuffled_scrambled_sobol_2d};
use super::{pixel_hash, sample_offset};
use crate::cpu::Isa;
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
    /// Correlated multi-jittered points of the render's sample count per pair of dimensions.
    MultiJitter,
}

impl SamplerKind {
    /// Every kind with its command-line name.
    pub const ALL: [(&'static str, SamplerKind); 4] = [
        ("lab", SamplerKind::Lab),
        ("independent", SamplerKind::Independent),
        ("sobol", SamplerKind::Sobol),
        ("multijitter", SamplerKind::MultiJitter),
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
            .ok_or_else(|| UnknownName::new("sampler", s, "lab, independent, sobol or multijitter"))
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
    /// The `multijitter` kind's grid of the render's samples.
    grid: Grid,
    /// The independent numbers' stream, started at its first use (the lab's one sample per
    /// pixel never draws one).
    rng: Option<Pcg32>,
}

impl Sampler {
    /// The sampler of sample `index` of pixel `(x, y)` in a render with `seed`. A `multijitter`
    /// sampler made here, without the render's sample count, is a `sobol` one
    /// ([`counted`](Self::counted) gives it the count).
    #[inline]
    pub fn new(kind: SamplerKind, seed: u64, pixel: (u32, u32), index: u32) -> Sampler {
        Self::counted(kind, seed, pixel, index, Grid::new(1))
    }

    /// [`new`](Self::new) for a render of `grid.count()` samples per pixel, the pattern that
    /// `multijitter` stratifies (`Grid::new(spp)`, made once per render); a sample beyond the
    /// count, or a count of one, makes a `multijitter` sampler a `sobol` one.
    #[inline]
    pub fn counted(
        kind: SamplerKind,
        seed: u64,
        pixel: (u32, u32),
        index: u32,
        grid: Grid,
    ) -> Sampler {
        Self::with_pixel_seed(kind, Self::pixel_seed(seed, pixel), pixel, index, grid)
    }

    /// [`counted`](Self::counted) for the samples `indices` of one pixel, in order: the
    /// pixel's hash made once (per sample it was a quarter of the camera band's own time,
    /// `Band::add`, in the materials scene's profile).
    #[inline]
    pub fn counted_range(
        kind: SamplerKind,
        seed: u64,
        pixel: (u32, u32),
        indices: std::ops::Range<u32>,
        grid: Grid,
    ) -> impl Iterator<Item = Sampler> {
        let pixel_seed = Self::pixel_seed(seed, pixel);
        indices.map(move |index| Self::with_pixel_seed(kind, pixel_seed, pixel, index, grid))
    }

    /// The hash of (seed, pixel) that roots a pixel's samplers.
    #[inline(always)]
    fn pixel_seed(seed: u64, pixel: (u32, u32)) -> u64 {
        mix64(pixel_hash(pixel.0, pixel.1) ^ mix64(seed))
    }

    /// [`counted`](Self::counted) for a pixel whose [`pixel_seed`](Self::pixel_seed) is made.
    #[inline(always)]
    fn with_pixel_seed(
        kind: SamplerKind,
        pixel_seed: u64,
        pixel: (u32, u32),
        index: u32,
        grid: Grid,
    ) -> Sampler {
        let reversed_index = index.reverse_bits();
        let kind = match kind {
            SamplerKind::MultiJitter if grid.count() < 2 || index >= grid.count() => {
                SamplerKind::Sobol
            }
            kind => kind,
        };
        Sampler { kind, pixel, index, pixel_seed, reversed_index, dimension: 0, grid, rng: None }
    }

    /// What it hands out: the kind it was made with, or `sobol` for a `multijitter` sampler
    /// made without its count ([`counted`](Self::counted)).
    pub fn kind(&self) -> SamplerKind {
        self.kind
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

    /// The pixel seed folded to 32 bits: the root of the dimensions' seeds.
    #[inline]
    fn seed_base(&self) -> u32 {
        (self.pixel_seed as u32) ^ (self.pixel_seed >> 32) as u32
    }

    /// [`next_1d`](Self::next_1d) of the samplers `lanes` picks, into `out` (`out[k]` for
    /// `samplers[lanes[k]]`): the same numbers, drawn sixteen at a time (`sobol` kind, where the
    /// CPU has AVX-512 or AVX2: the same arithmetic in vector registers, so the same bits).
    ///
    /// # Panics
    /// If `out` is shorter than `lanes`, or a lane is out of range.
    pub fn next_1d_each(samplers: &mut [Sampler], lanes: &[usize], out: &mut [f32]) {
        each_with::<OneD>(samplers, lanes, out, Isa::detect());
    }

    /// [`next_2d`](Self::next_2d) of the samplers `lanes` picks, into `out`, as
    /// [`next_1d_each`](Self::next_1d_each) draws `next_1d`.
    ///
    /// # Panics
    /// If `out` is shorter than `lanes`, or a lane is out of range.
    pub fn next_2d_each(samplers: &mut [Sampler], lanes: &[usize], out: &mut [Vec2]) {
        each_with::<TwoD>(samplers, lanes, out, Isa::detect());
    }

    /// A path vertex's numbers ([`VertexNumbers`]: `next_2d`, `next_1d`, `next_2d`, `next_1d`,
    /// in that order) of the samplers `lanes` picks, into `out`: the four draws of
    /// [`next_1d_each`](Self::next_1d_each) and [`next_2d_each`](Self::next_2d_each) in one
    /// pass over the samplers, sixteen lanes at a time.
    ///
    /// # Panics
    /// If `out` is shorter than `lanes`, or a lane is out of range.
    pub fn next_vertex_each(samplers: &mut [Sampler], lanes: &[usize], out: &mut [VertexNumbers]) {
        each_with::<VertexDraw>(samplers, lanes, out, Isa::detect());
    }
}

/// The numbers a path tracer draws at a vertex, in the order it draws them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VertexNumbers {
    /// Picks the light and the point on it.
    pub point: Vec2,
    /// Picks the BSDF's lobe.
    pub lobe: f32,
    /// Picks the BSDF's direction.
    pub direction: Vec2,
    /// Plays Russian roulette.
    pub roulette: f32,
}

/// Lanes per batch.
const LANES: usize = 16;

/// A point set whose numbers are a function of a pixel's folded seed, a sample's index word
/// and a dimension alone, so that sixteen lanes draw them in one loop.
trait Points: Copy {
    /// What a sampler contributes as the index word.
    fn index_word(sampler: &Sampler) -> u32;
    /// One dimension.
    fn one(self, base: u32, index_word: u32, dimension: u32) -> f32;
    /// Two dimensions.
    fn two(self, base: u32, index_word: u32, dimension: u32) -> Vec2;
}

/// The `sobol` kind's points (the index word is the bit-reversed index).
#[derive(Clone, Copy)]
struct SobolPoints;

impl Points for SobolPoints {
    #[inline(always)]
    fn index_word(sampler: &Sampler) -> u32 {
        sampler.reversed_index
    }
    #[inline(always)]
    fn one(self, base: u32, reversed_index: u32, dimension: u32) -> f32 {
        sobol_1d(base, reversed_index, dimension)
    }
    #[inline(always)]
    fn two(self, base: u32, reversed_index: u32, dimension: u32) -> Vec2 {
        sobol_2d(base, reversed_index, dimension)
    }
}

/// The `multijitter` kind's points on a grid whose sides are powers of two (16, 32, 64, 128
/// or 256 samples...), where they need no division and no walk: straight-line code for lanes.
#[derive(Clone, Copy)]
struct GridPoints(Grid);

impl Points for GridPoints {
    #[inline(always)]
    fn index_word(sampler: &Sampler) -> u32 {
        sampler.index
    }
    #[inline(always)]
    fn one(self, base: u32, index: u32, dimension: u32) -> f32 {
        multijitter::point_1d_pow2(index, &self.0, dimension_seeds(base, dimension))
    }
    #[inline(always)]
    fn two(self, base: u32, index: u32, dimension: u32) -> Vec2 {
        multijitter::point_2d_pow2(index, &self.0, dimension_seeds(base, dimension))
    }
}

/// A draw of one or two dimensions, as a function of a sampler's state alone.
trait SobolDraw {
    type Number: Copy + Default;
    /// The dimensions a draw takes.
    const DIMENSIONS: u32;
    /// The draw of `points` for a pixel's folded seed, a sample's index word and a dimension.
    fn draw<P: Points>(points: P, base: u32, index_word: u32, dimension: u32) -> Self::Number;
    /// The same draw by a sampler of any kind, one at a time.
    fn one_by_one(sampler: &mut Sampler) -> Self::Number;
}

/// [`Sampler::next_1d`].
struct OneD;

impl SobolDraw for OneD {
    type Number = f32;
    const DIMENSIONS: u32 = 1;
    #[inline(always)]
    fn draw<P: Points>(points: P, base: u32, index_word: u32, dimension: u32) -> f32 {
        points.one(base, index_word, dimension)
    }
    fn one_by_one(sampler: &mut Sampler) -> f32 {
        sampler.next_1d()
    }
}

/// [`Sampler::next_2d`].
struct TwoD;

impl SobolDraw for TwoD {
    type Number = Vec2;
    const DIMENSIONS: u32 = 2;
    #[inline(always)]
    fn draw<P: Points>(points: P, base: u32, index_word: u32, dimension: u32) -> Vec2 {
        points.two(base, index_word, dimension)
    }
    fn one_by_one(sampler: &mut Sampler) -> Vec2 {
        sampler.next_2d()
    }
}

/// [`Sampler::next_vertex_each`]: a 2D, a 1D, a 2D and a 1D draw.
struct VertexDraw;

impl SobolDraw for VertexDraw {
    type Number = VertexNumbers;
    const DIMENSIONS: u32 = 6;
    #[inline(always)]
    fn draw<P: Points>(points: P, base: u32, index_word: u32, dimension: u32) -> VertexNumbers {
        VertexNumbers {
            point: points.two(base, index_word, dimension),
            lobe: points.one(base, index_word, dimension + 2),
            direction: points.two(base, index_word, dimension + 3),
            roulette: points.one(base, index_word, dimension + 5),
        }
    }
    fn one_by_one(sampler: &mut Sampler) -> VertexNumbers {
        VertexNumbers {
            point: sampler.next_2d(),
            lobe: sampler.next_1d(),
            direction: sampler.next_2d(),
            roulette: sampler.next_1d(),
        }
    }
}

fn each_with<D: SobolDraw>(
    samplers: &mut [Sampler],
    lanes: &[usize],
    out: &mut [D::Number],
    isa: Isa,
) {
    let out = &mut out[..lanes.len()];
    for (lanes, out) in lanes.chunks(LANES).zip(out.chunks_mut(LANES)) {
        let first = &samplers[lanes[0]];
        let same = |kind| lanes.iter().all(|&i| samplers[i].kind == kind);
        if same(SamplerKind::Sobol) {
            chunk_with::<D, _>(SobolPoints, samplers, lanes, out, isa);
        } else if same(SamplerKind::MultiJitter)
            && first.grid.is_power_of_two()
            && lanes.iter().all(|&i| samplers[i].grid == first.grid)
        {
            let points = GridPoints(first.grid);
            chunk_with::<D, _>(points, samplers, lanes, out, isa);
        } else {
            for (&i, number) in lanes.iter().zip(out.iter_mut()) {
                *number = D::one_by_one(&mut samplers[i]);
            }
        }
    }
}

/// Up to sixteen lanes' draws of `points`, in one loop.
#[inline(always)]
fn chunk_with<D: SobolDraw, P: Points>(
    points: P,
    samplers: &mut [Sampler],
    lanes: &[usize],
    out: &mut [D::Number],
    isa: Isa,
) {
    let mut base = [0u32; LANES];
    let mut index_word = [0u32; LANES];
    let mut dimension = [0u32; LANES];
    for (k, &i) in lanes.iter().enumerate() {
        let sampler = &mut samplers[i];
        (base[k], index_word[k], dimension[k]) =
            (sampler.seed_base(), P::index_word(sampler), sampler.dimension);
        sampler.dimension += D::DIMENSIONS;
    }
    let mut numbers = [D::Number::default(); LANES];
    match isa {
        // SAFETY: `Isa::detect` picks a set only where the CPU has it (the tests pick the sets
        // this CPU supports).
        #[cfg(target_arch = "x86_64")]
        Isa::Avx512 => unsafe {
            lanes_avx512::<D, P>(points, &base, &index_word, &dimension, &mut numbers)
        },
        // SAFETY: as above.
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 => unsafe {
            lanes_avx2::<D, P>(points, &base, &index_word, &dimension, &mut numbers)
        },
        _ => lanes_of::<D, P>(points, &base, &index_word, &dimension, &mut numbers),
    }
    out.copy_from_slice(&numbers[..out.len()]);
}

/// Sixteen draws at once: a plain loop that the compiler turns into vector code where it is
/// compiled with vector instructions (the wrappers below); its scalar compilation is the twin.
#[inline(always)]
fn lanes_of<D: SobolDraw, P: Points>(
    points: P,
    base: &[u32; LANES],
    index_word: &[u32; LANES],
    dimension: &[u32; LANES],
    out: &mut [D::Number; LANES],
) {
    for k in 0..LANES {
        out[k] = D::draw(points, base[k], index_word[k], dimension[k]);
    }
}

/// [`lanes_of`] compiled for AVX-512.
///
/// # Safety
/// The CPU must support AVX2 and AVX-512 F and VL ([`Isa::Avx512`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f,avx512vl")]
unsafe fn lanes_avx512<D: SobolDraw, P: Points>(
    points: P,
    base: &[u32; LANES],
    index_word: &[u32; LANES],
    dimension: &[u32; LANES],
    out: &mut [D::Number; LANES],
) {
    lanes_of::<D, P>(points, base, index_word, dimension, out)
}

/// [`lanes_of`] compiled for AVX2.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn lanes_avx2<D: SobolDraw, P: Points>(
    points: P,
    base: &[u32; LANES],
    index_word: &[u32; LANES],
    dimension: &[u32; LANES],
    out: &mut [D::Number; LANES],
) {
    lanes_of::<D, P>(points, base, index_word, dimension, out)
}

/// The scrambling seeds of a dimension, for a pixel whose folded seed is `base`: three
/// well-mixed 32-bit words (the index shuffle and the two coordinates' scrambles).
#[inline(always)]
fn dimension_seeds(base: u32, dimension: u32) -> [u32; 3] {
    let d = dimension.wrapping_mul(0x9e37_79b9);
    [hash32(base ^ d), hash32(base.wrapping_add(d) ^ 0x5bd1_e995), hash32(base ^ d ^ 0x68e3_1da4)]
}

/// Dimension `dimension` of the Sobol' sample whose bit-reversed index is `reversed_index`, for
/// the pixel whose folded seed is `base`: the first Sobol' dimension (the bit-reversed index),
/// its points shuffled and Owen-scrambled by the dimension's seeds.
#[inline(always)]
fn sobol_1d(base: u32, reversed_index: u32, dimension: u32) -> f32 {
    let [shuffle, scramble, _] = dimension_seeds(base, dimension);
    // nested_uniform_scramble(index, shuffle), its first reversal done in `Sampler::new`.
    let index = laine_karras_permutation(reversed_index, shuffle).reverse_bits();
    // The first Sobol' dimension is the bit-reversed index; Owen-scrambling it is
    // reverse(LK(reverse(reverse(index)))) = reverse(LK(index)).
    u32_to_unit(laine_karras_permutation(index, scramble).reverse_bits())
}

/// Dimensions `dimension` and `dimension + 1`: a 2D Sobol' point, shuffled and scrambled.
#[inline(always)]
fn sobol_2d(base: u32, reversed_index: u32, dimension: u32) -> Vec2 {
    let p = shuffled_scrambled_sobol_2d(reversed_index, dimension_seeds(base, dimension));
    Vec2::new(u32_to_unit(p[0]), u32_to_unit(p[1]))
}

impl Sampler {
    /// The next number in `[0, 1)`.
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        match self.kind {
            SamplerKind::Sobol => {
                let number = sobol_1d(self.seed_base(), self.reversed_index, self.dimension);
                self.dimension += 1;
                number
            }
            SamplerKind::MultiJitter => {
                let seeds = dimension_seeds(self.seed_base(), self.dimension);
                self.dimension += 1;
                multijitter::point_1d(self.index, &self.grid, seeds)
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
                let point = sobol_2d(self.seed_base(), self.reversed_index, self.dimension);
                self.dimension += 2;
                point
            }
            SamplerKind::MultiJitter => {
                let seeds = dimension_seeds(self.seed_base(), self.dimension);
                self.dimension += 2;
                multijitter::point_2d(self.index, &self.grid, seeds)
            }
            _ => {
                self.dimension += 2;
                let rng = self.rng();
                Vec2::new(rng.next_f32(), rng.next_f32())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Draws of `D` by `each_with` on `isa` against one by one, bit for bit: 37 samplers of
    /// `kind` at different dimensions and indices, every other one drawn, in a shuffled order,
    /// three times; then the samplers go on as if drawn one by one.
    fn check_each<D: SobolDraw>(isa: Isa, kind: SamplerKind, grid: Grid)
    where
        D::Number: PartialEq + std::fmt::Debug,
    {
        let make = || -> Vec<Sampler> {
            (0..37u32)
                .map(|i| {
                    let seed = u64::MAX - u64::from(i).wrapping_mul(0x9e37_79b9_7f4a_7c15);
                    // `multijitter`'s samples within its count (beyond it, it is `sobol`).
                    let index = match kind {
                        SamplerKind::MultiJitter => i * 5 % grid.count(),
                        _ => i * 1_000_003,
                    };
                    let mut s = Sampler::counted(kind, seed, (i * 7, i * 3), index, grid);
                    for _ in 0..i % 5 {
                        s.next_1d();
                    }
                    s
                })
                .collect()
        };
        let (mut one_by_one, mut batched) = (make(), make());
        let lanes: Vec<usize> = (0..37).rev().filter(|i| i % 2 == 0 || i % 3 == 0).collect();
        for _ in 0..3 {
            let mut out = vec![D::Number::default(); lanes.len()];
            each_with::<D>(&mut batched, &lanes, &mut out, isa);
            for (k, &i) in lanes.iter().enumerate() {
                // Compared as values: every draw is a finite number in [0, 1), where equal
                // values are equal bits.
                assert_eq!(out[k], D::one_by_one(&mut one_by_one[i]), "{isa:?} {kind:?} lane {i}");
            }
        }
        for (a, b) in one_by_one.iter_mut().zip(&mut batched) {
            assert_eq!(a.next_2d(), b.next_2d());
        }
    }

    #[test]
    fn batched_draws_are_the_draws_one_by_one_on_every_instruction_set() {
        // Every set this CPU supports (on this machine: AVX-512, AVX2, SSE2 and scalar; SSE2
        // runs the scalar loop).
        for isa in Isa::ALL.into_iter().filter(|isa| isa.is_supported()) {
            // `multijitter` in lanes where its grid's sides are powers of two (64, 32): the
            // lanes' plumbing (seeds, dimensions, index words) against one by one; where they
            // are not (49) the chunk goes one by one, which this checks goes on right.
            let kinds = [
                (SamplerKind::Sobol, 64),
                (SamplerKind::Independent, 64),
                (SamplerKind::MultiJitter, 64),
                (SamplerKind::MultiJitter, 32),
                (SamplerKind::MultiJitter, 49),
            ];
            for (kind, count) in kinds {
                let grid = Grid::new(count);
                check_each::<OneD>(isa, kind, grid);
                check_each::<TwoD>(isa, kind, grid);
                check_each::<VertexDraw>(isa, kind, grid);
            }
        }
    }

    /// A pixel's samplers made together are each made alone: the same numbers, every kind,
    /// indices below and beyond a grid's count (where `multijitter` becomes `sobol`).
    #[test]
    fn a_pixels_samplers_made_together_are_each_made_alone() {
        for (_, kind) in SamplerKind::ALL {
            for (seed, pixel, indices, grid) in [
                (7u64, (3u32, 5u32), 0..16u32, Grid::new(16)),
                (u64::MAX, (u32::MAX, 0), 14..20, Grid::new(16)),
                (0, (1, 1), 3..4, Grid::new(1)),
            ] {
                let together: Vec<Sampler> =
                    Sampler::counted_range(kind, seed, pixel, indices.clone(), grid).collect();
                assert_eq!(together.len(), indices.len());
                for (mut a, index) in together.into_iter().zip(indices) {
                    let mut b = Sampler::counted(kind, seed, pixel, index, grid);
                    assert_eq!(a.kind(), b.kind());
                    for _ in 0..8 {
                        assert_eq!(a.next_2d(), b.next_2d(), "{kind:?} {pixel:?} {index}");
                        assert_eq!(a.next_1d(), b.next_1d(), "{kind:?} {pixel:?} {index}");
                    }
                }
            }
        }
    }

    #[test]
    fn samplers_depend_on_seed_pixel_and_index_alone() {
        for (_, kind) in SamplerKind::ALL {
            let draw = |seed, pixel, index| {
                let mut s = Sampler::counted(kind, seed, pixel, index, Grid::new(16));
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
