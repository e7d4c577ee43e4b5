//! Texture images: texels as the file stores them (8-bit, sRGB-encoded or linear; deeper images
//! as linear floats), a mip-map pyramid, and filtered lookups with a wrap mode per axis.
//!
//! **Layout.** Level 0 is the image, rows from the top; level k+1 halves level k in each
//! direction (rounding down, at least 1), each texel the mean of the part of level k it covers
//! (a box filter), averaged in linear light (sRGB texels are decoded, averaged and encoded
//! again). Where a size is even that is the 2×2 texels above it; where it is odd (7 texels
//! become 3, each covering 7/3 of them) the texels at the seams count for the fraction each
//! covers, so that no row or column of the image is left out of the smaller levels. A texture of
//! 300×200 has levels 300×200, 150×100, 75×50, 37×25, 18×12, 9×6, 4×3, 2×1, 1×1.
//!
//! **Coordinates.** A lookup takes `(s, t)` in texture space: `s = 0` is the left edge of the
//! image and `s = 1` the right, `t = 0` the top row's top edge and `t = 1` the bottom's bottom
//! edge (glTF's convention; OBJ's `v` runs upward and its loader flips it). Texel `(x, y)` has
//! its centre at `((x + ½)/w, (y + ½)/h)`, so a bilinear lookup at a texel's centre returns that
//! texel exactly, and halfway between two centres their mean.
//!
//! **Wrapping** decides the texels beyond the edges, per axis ([`Wrap`]): `Repeat` tiles the
//! image, `Clamp` repeats the edge texel, `Mirror` tiles it mirrored every other time (glTF's
//! REPEAT, CLAMP_TO_EDGE and MIRRORED_REPEAT).

use std::sync::LazyLock;

use glam::{Vec2, Vec4};

use crate::color::{linear_to_srgb, srgb_to_linear};

/// How texture coordinates beyond `[0, 1]` find a texel, per axis (see the module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// The image tiles the plane.
    #[default]
    Repeat,
    /// The edge texels stretch outward.
    Clamp,
    /// The image tiles the plane mirrored every other time.
    Mirror,
}

impl Wrap {
    /// The texel index that index `i` of an unbounded row of `n` texels reads.
    #[inline]
    pub fn index(self, i: i64, n: u32) -> u32 {
        let n = i64::from(n);
        // Inside the row every mode reads `i` itself: no division (the common case).
        if (0..n).contains(&i) {
            return i as u32;
        }
        let wrapped = match self {
            Wrap::Repeat => i.rem_euclid(n),
            Wrap::Clamp => i.clamp(0, n - 1),
            Wrap::Mirror => {
                let m = i.rem_euclid(2 * n);
                if m >= n { 2 * n - 1 - m } else { m }
            }
        };
        wrapped as u32
    }
}

/// The linear value of each 8-bit sRGB code.
static SRGB_TO_LINEAR: LazyLock<[f32; 256]> =
    LazyLock::new(|| std::array::from_fn(|i| srgb_to_linear(i as f32 / 255.0)));

/// The texels of one level.
#[derive(Clone, PartialEq)]
pub enum Texels {
    /// 8 bits per channel, RGBA; sRGB-encoded colour when the image says so (alpha is linear).
    Rgba8(Vec<[u8; 4]>),
    /// Linear floats, RGBA (16-bit and float images).
    RgbaF32(Vec<[f32; 4]>),
}

/// One level of the pyramid.
#[derive(Clone, PartialEq)]
pub struct Level {
    width: u32,
    height: u32,
    texels: Texels,
}

impl Level {
    /// Its size in texels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }
}

/// A texture image with its mip-map pyramid (see the module documentation).
#[derive(Clone, PartialEq)]
pub struct TextureImage {
    /// Where it came from, for messages.
    pub name: String,
    /// Whether 8-bit colour is sRGB-encoded (colour textures) or linear (data: normals,
    /// roughness).
    srgb: bool,
    levels: Vec<Level>,
    /// XXH3 of the size, encoding and level-0 texels: scene hashes use it.
    hash: u64,
}

impl std::fmt::Debug for TextureImage {
    /// The size and a hash of the texels, not the texels: scenes are hashed through `Debug`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (w, h) = self.size();
        write!(f, "TextureImage({:?}, {w}×{h}, srgb {}, {:016x})", self.name, self.srgb, self.hash)
    }
}

impl TextureImage {
    /// An 8-bit RGBA image, rows from the top; `srgb` says whether its colour is sRGB-encoded.
    ///
    /// # Panics
    /// If `texels` does not hold `width × height` texels, or a side is 0.
    pub fn from_rgba8(
        name: &str,
        width: u32,
        height: u32,
        texels: Vec<[u8; 4]>,
        srgb: bool,
    ) -> TextureImage {
        Self::new(name, Level { width, height, texels: Texels::Rgba8(texels) }, srgb)
    }

    /// A linear float RGBA image, rows from the top.
    ///
    /// # Panics
    /// If `texels` does not hold `width × height` texels, or a side is 0.
    pub fn from_rgba_f32(
        name: &str,
        width: u32,
        height: u32,
        texels: Vec<[f32; 4]>,
    ) -> TextureImage {
        Self::new(name, Level { width, height, texels: Texels::RgbaF32(texels) }, false)
    }

    fn new(name: &str, base: Level, srgb: bool) -> TextureImage {
        let count = match &base.texels {
            Texels::Rgba8(t) => t.len(),
            Texels::RgbaF32(t) => t.len(),
        };
        assert!(base.width > 0 && base.height > 0, "{name}: an empty image");
        assert_eq!(count as u64, u64::from(base.width) * u64::from(base.height), "{name}");
        let mut hasher = xxhash_rust::xxh3::Xxh3::new();
        hasher.update(&[base.width.to_le_bytes(), base.height.to_le_bytes()].concat());
        hasher.update(&[u8::from(srgb)]);
        match &base.texels {
            Texels::Rgba8(t) => hasher.update(t.as_flattened()),
            Texels::RgbaF32(t) => {
                for v in t.as_flattened() {
                    hasher.update(&v.to_bits().to_le_bytes());
                }
            }
        }
        let mut image = TextureImage { name: name.to_string(), srgb, levels: vec![base], hash: 0 };
        image.hash = hasher.digest();
        while let Some(next) = image.halve(image.levels.len() - 1) {
            image.levels.push(next);
        }
        image
    }

    /// Level 0's size in texels.
    pub fn size(&self) -> (u32, u32) {
        self.levels[0].size()
    }

    /// The pyramid, level 0 first.
    pub fn levels(&self) -> &[Level] {
        &self.levels
    }

    /// Whether 8-bit colour is sRGB-encoded.
    pub fn is_srgb(&self) -> bool {
        self.srgb
    }

    /// The bytes its texels take, every level together.
    pub fn bytes(&self) -> u64 {
        self.levels
            .iter()
            .map(|l| match &l.texels {
                Texels::Rgba8(t) => 4 * t.len() as u64,
                Texels::RgbaF32(t) => 16 * t.len() as u64,
            })
            .sum()
    }

    /// Texel `(x, y)` of `level`, in linear light, RGBA.
    #[inline]
    pub fn texel(&self, level: usize, x: u32, y: u32) -> Vec4 {
        let [texel] = self.texels(level, [(x, y)]);
        texel
    }

    /// The texels at `(x, y)` in `level`, decoded as [`texel`](Self::texel) decodes them (the
    /// level's storage and the sRGB table looked up once for all of them).
    #[inline(always)]
    fn texels<const N: usize>(&self, level: usize, at: [(u32, u32); N]) -> [Vec4; N] {
        let l = &self.levels[level];
        let index = |(x, y): (u32, u32)| y as usize * l.width as usize + x as usize;
        match &l.texels {
            Texels::Rgba8(t) if self.srgb => {
                let table = &*SRGB_TO_LINEAR;
                at.map(|xy| {
                    let [r, g, b, a] = t[index(xy)];
                    let a = f32::from(a) / 255.0;
                    Vec4::new(table[r as usize], table[g as usize], table[b as usize], a)
                })
            }
            Texels::Rgba8(t) => at.map(|xy| {
                let [r, g, b, a] = t[index(xy)];
                Vec4::new(f32::from(r), f32::from(g), f32::from(b), f32::from(a)) / 255.0
            }),
            Texels::RgbaF32(t) => at.map(|xy| Vec4::from_array(t[index(xy)])),
        }
    }

    /// The bilinear lookup at `st` in `level` (see the module documentation for coordinates).
    /// Non-finite coordinates read texel (0, 0)'s neighbourhood rather than fail.
    #[inline]
    pub fn bilinear(&self, level: usize, st: Vec2, wrap: [Wrap; 2]) -> Vec4 {
        let (w, h) = self.levels[level].size();
        // Texel centres at (i + ½)/n: texel space shifted by half a texel.
        let x = st.x * w as f32 - 0.5;
        let y = st.y * h as f32 - 0.5;
        let (x0, y0) = (crate::float::floor(x), crate::float::floor(y));
        let (fx, fy) = (x - x0, y - y0);
        // `as` saturates (and maps NaN to 0), so absurd coordinates stay in range.
        let (ix, iy) = (x0 as i64, y0 as i64);
        let (xa, xb) = (wrap[0].index(ix, w), wrap[0].index(ix.saturating_add(1), w));
        let (ya, yb) = (wrap[1].index(iy, h), wrap[1].index(iy.saturating_add(1), h));
        let (fx, fy) = if fx.is_finite() && fy.is_finite() { (fx, fy) } else { (0.0, 0.0) };
        let [a, b, c, d] = self.texels(level, [(xa, ya), (xb, ya), (xa, yb), (xb, yb)]);
        let top = a * (1.0 - fx) + b * fx;
        let bottom = c * (1.0 - fx) + d * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// The trilinear lookup for a footprint `width` texture-space units across: the two levels
    /// whose texels are nearest that size, blended (level `log2(width · max(w, h))`); a
    /// footprint of 0 (or below a texel) is the bilinear lookup in level 0.
    #[inline]
    pub fn filtered(&self, st: Vec2, width: f32, wrap: [Wrap; 2]) -> Vec4 {
        let (w, h) = self.size();
        let texels = width * w.max(h) as f32;
        // (NaN included.)
        if texels.partial_cmp(&1.0) != Some(std::cmp::Ordering::Greater) {
            return self.bilinear(0, st, wrap);
        }
        let last = self.levels.len() - 1;
        let level = texels.log2().min(last as f32);
        let lower = level.floor() as usize;
        if lower >= last {
            return self.bilinear(last, st, wrap);
        }
        let f = level - lower as f32;
        self.bilinear(lower, st, wrap) * (1.0 - f) + self.bilinear(lower + 1, st, wrap) * f
    }

    /// Level `k + 1` from level `k`, or `None` once level `k` is one texel.
    fn halve(&self, k: usize) -> Option<Level> {
        let above = &self.levels[k];
        if above.width == 1 && above.height == 1 {
            return None;
        }
        let (width, height) = ((above.width / 2).max(1), (above.height / 2).max(1));
        let mean = |x: u32, y: u32| -> Vec4 {
            let mut sum = Vec4::ZERO;
            for (j, wy) in footprint(y, height, above.height) {
                for (i, wx) in footprint(x, width, above.width) {
                    sum += self.texel(k, i, j) * (wx * wy);
                }
            }
            sum
        };
        let positions = (0..height).flat_map(|y| (0..width).map(move |x| (x, y)));
        let texels = match &above.texels {
            Texels::Rgba8(_) => {
                let encode = |v: f32, srgb: bool| {
                    let v = if srgb { linear_to_srgb(v) } else { v };
                    (v.clamp(0.0, 1.0) * 255.0).round() as u8
                };
                Texels::Rgba8(
                    positions
                        .map(|(x, y)| {
                            let m = mean(x, y);
                            [
                                encode(m.x, self.srgb),
                                encode(m.y, self.srgb),
                                encode(m.z, self.srgb),
                                encode(m.w, false),
                            ]
                        })
                        .collect(),
                )
            }
            Texels::RgbaF32(_) => {
                Texels::RgbaF32(positions.map(|(x, y)| mean(x, y).to_array()).collect())
            }
        };
        Some(Level { width, height, texels })
    }
}

/// The texels of a row (or column) of `n_in` that texel `x` of a row of `n_out` covers, each
/// with the fraction of `x`'s width it takes (the weights sum to 1): output texel `x` spans
/// `[x·r, (x+1)·r)` of the input, `r = n_in / n_out`.
fn footprint(x: u32, n_out: u32, n_in: u32) -> impl Iterator<Item = (u32, f32)> {
    let r = f64::from(n_in) / f64::from(n_out);
    let (a, b) = (f64::from(x) * r, f64::from(x + 1) * r);
    let (first, end) = (a.floor() as u32, (b.ceil() as u32).min(n_in));
    (first..end).map(move |i| {
        let covered = b.min(f64::from(i) + 1.0) - a.max(f64::from(i));
        (i, (covered / r) as f32)
    })
}
