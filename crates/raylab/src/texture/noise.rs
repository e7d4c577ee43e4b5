//! Procedural textures: Perlin's gradient noise, its fractal sum (fBm) and the classic patterns
//! built on them (clouds, marble, wood), read at the point in space (solid textures: no
//! texture coordinates needed, no seams).
//!
//! **Noise** is Ken Perlin's improved noise (Perlin 2002, "Improving Noise"): at every integer
//! lattice point a pseudo-random gradient from the twelve edge directions of a cube, blended
//! with the quintic fade `6t⁵ − 15t⁴ + 10t³`, so that it is 0 at the lattice points and smooth
//! (its second derivative continuous) everywhere. The permutation that picks the gradients is
//! shuffled from a seed, so that two textures can differ.
//!
//! **fBm** (fractional Brownian motion) adds `octaves` layers, each at twice the frequency and
//! half the amplitude of the one before: `Σ ½ⁱ noise(2ⁱ p)`. **Turbulence** adds their absolute
//! values instead, which gives the creases of marble veins.
//!
//! **Patterns** turn a value in `[0, 1]` into a blend of two colours (or two numbers, for
//! roughness):
//! - `perlin`: `½ + ½ noise(p)`;
//! - `fbm`: `½ + ½ fbm(p)`;
//! - `clouds`: fBm with more contrast, `½ + fbm(p)`, clamped;
//! - `marble`: veins along x, `½ + ½ sin(π (x + turbulence · turb(p)))`;
//! - `wood`: rings about the y axis, `fract(r + turbulence · fbm(p))` with `r = √(x² + z²)`.
//!
//! Each pattern reads `p · scale`: `scale` is the number of noise cells per unit of length.

use glam::{Vec3, Vec4};

use super::query::TextureQuery;
use crate::sampling::Pcg32;

/// Perlin's improved noise with a seeded permutation.
#[derive(Clone)]
pub struct Perlin {
    seed: u64,
    /// The permutation of 0..256, twice, so that indices up to 511 need no wrapping (shared:
    /// textures are cloned with their materials).
    permutation: std::sync::Arc<[u8; 512]>,
}

impl std::fmt::Debug for Perlin {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Perlin(seed {})", self.seed)
    }
}

impl PartialEq for Perlin {
    fn eq(&self, other: &Self) -> bool {
        self.seed == other.seed
    }
}

impl Perlin {
    /// The noise of `seed` (a Fisher-Yates shuffle of 0..256 by [`Pcg32`]).
    pub fn new(seed: u64) -> Perlin {
        let mut values: [u8; 256] = std::array::from_fn(|i| i as u8);
        let mut rng = Pcg32::new(seed, 0x5eed);
        for i in (1..256).rev() {
            let j = (rng.next_u32() % (i as u32 + 1)) as usize;
            values.swap(i, j);
        }
        let permutation = std::sync::Arc::new(std::array::from_fn(|i| values[i % 256]));
        Perlin { seed, permutation }
    }

    /// The noise at `p`, in about `[−1, 1]`; 0 at every integer lattice point.
    pub fn noise(&self, p: Vec3) -> f32 {
        // The lattice cell (wrapped to 256: the noise repeats every 256 units) and the point in it.
        let floor = p.floor();
        let cell = |v: f32| (v as i64).rem_euclid(256) as usize;
        let (x, y, z) = (cell(floor.x), cell(floor.y), cell(floor.z));
        let f = p - floor;
        let (u, v, w) = (fade(f.x), fade(f.y), fade(f.z));
        let perm = &*self.permutation;
        let a = perm[x] as usize + y;
        let (aa, ab) = (perm[a] as usize + z, perm[a + 1] as usize + z);
        let b = perm[x + 1] as usize + y;
        let (ba, bb) = (perm[b] as usize + z, perm[b + 1] as usize + z);
        let g = |hash: usize, dx: f32, dy: f32, dz: f32| gradient(perm[hash], dx, dy, dz);
        let (fx, fy, fz) = (f.x, f.y, f.z);
        lerp(
            w,
            lerp(
                v,
                lerp(u, g(aa, fx, fy, fz), g(ba, fx - 1.0, fy, fz)),
                lerp(u, g(ab, fx, fy - 1.0, fz), g(bb, fx - 1.0, fy - 1.0, fz)),
            ),
            lerp(
                v,
                lerp(u, g(aa + 1, fx, fy, fz - 1.0), g(ba + 1, fx - 1.0, fy, fz - 1.0)),
                lerp(u, g(ab + 1, fx, fy - 1.0, fz - 1.0), g(bb + 1, fx - 1.0, fy - 1.0, fz - 1.0)),
            ),
        )
    }

    /// `Σ ½ⁱ noise(2ⁱ p)` over `octaves` octaves: at most `2 − 2^(1−octaves)` in magnitude.
    pub fn fbm(&self, p: Vec3, octaves: u32) -> f32 {
        let (mut sum, mut amplitude, mut frequency) = (0.0, 1.0, 1.0);
        for _ in 0..octaves {
            sum += amplitude * self.noise(p * frequency);
            amplitude *= 0.5;
            frequency *= 2.0;
        }
        sum
    }

    /// `Σ ½ⁱ |noise(2ⁱ p)|` over `octaves` octaves.
    pub fn turbulence(&self, p: Vec3, octaves: u32) -> f32 {
        let (mut sum, mut amplitude, mut frequency) = (0.0, 1.0, 1.0);
        for _ in 0..octaves {
            sum += amplitude * self.noise(p * frequency).abs();
            amplitude *= 0.5;
            frequency *= 2.0;
        }
        sum
    }
}

/// `6t⁵ − 15t⁴ + 10t³`.
#[inline]
fn fade(t: f32) -> f32 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

#[inline]
fn lerp(t: f32, a: f32, b: f32) -> f32 {
    a + t * (b - a)
}

/// The dot product of `(dx, dy, dz)` with one of the twelve cube-edge gradients (Perlin 2002).
#[inline]
fn gradient(hash: u8, dx: f32, dy: f32, dz: f32) -> f32 {
    let h = hash & 15;
    let u = if h < 8 { dx } else { dy };
    let v = if h < 4 {
        dy
    } else if h == 12 || h == 14 {
        dx
    } else {
        dz
    };
    (if h & 1 == 0 { u } else { -u }) + (if h & 2 == 0 { v } else { -v })
}

/// A procedural pattern (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pattern {
    /// Noise alone.
    Perlin,
    /// Fractal noise.
    Fbm,
    /// Fractal noise with more contrast.
    Clouds,
    /// Veins along x.
    Marble,
    /// Rings about the y axis.
    Wood,
}

impl Pattern {
    /// The names scene files use.
    pub const NAMES: [&'static str; 5] = ["perlin", "fbm", "clouds", "marble", "wood"];

    /// The pattern of a name in [`NAMES`](Self::NAMES).
    pub fn from_name(name: &str) -> Option<Pattern> {
        Some(match name {
            "perlin" => Pattern::Perlin,
            "fbm" => Pattern::Fbm,
            "clouds" => Pattern::Clouds,
            "marble" => Pattern::Marble,
            "wood" => Pattern::Wood,
            _ => return None,
        })
    }
}

/// A pattern blending two colours over space.
#[derive(Clone, Debug, PartialEq)]
pub struct NoiseTexture {
    /// Which pattern.
    pub pattern: Pattern,
    /// The noise it is made of.
    pub noise: Perlin,
    /// Noise cells per unit of length.
    pub scale: f32,
    /// Octaves of fBm and turbulence.
    pub octaves: u32,
    /// How much the noise bends marble's veins and wood's rings.
    pub turbulence: f32,
    /// The colours at 0 and at 1.
    pub colors: [Vec3; 2],
}

impl NoiseTexture {
    /// The pattern's value in `[0, 1]` at `p` (before `scale`).
    pub fn value(&self, p: Vec3) -> f32 {
        let p = p * self.scale;
        let noise = &self.noise;
        let t = match self.pattern {
            Pattern::Perlin => 0.5 + 0.5 * noise.noise(p),
            Pattern::Fbm => 0.5 + 0.5 * noise.fbm(p, self.octaves),
            Pattern::Clouds => 0.5 + noise.fbm(p, self.octaves),
            Pattern::Marble => {
                let bend = self.turbulence * noise.turbulence(p, self.octaves);
                0.5 + 0.5 * (std::f32::consts::PI * (p.x + bend)).sin()
            }
            Pattern::Wood => {
                let r = (p.x * p.x + p.z * p.z).sqrt();
                (r + self.turbulence * noise.fbm(p, self.octaves)).rem_euclid(1.0)
            }
        };
        if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 }
    }

    /// The colour at the query's point.
    pub fn eval(&self, query: &TextureQuery) -> Vec4 {
        self.colors[0].lerp(self.colors[1], self.value(query.p)).extend(1.0)
    }
}
