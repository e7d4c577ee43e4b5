//! `envmap`: light arriving from every direction that leaves the scene, read from an
//! equirectangular (latitude–longitude) HDR image, as Mitsuba 3's `envmap` emitter.
//!
//! # Conventions
//! Mitsuba 3's (`src/emitters/envmap.cpp`), so that the same image and `to_world` light a scene
//! from the same directions in both renderers. In the map's own frame (y up), a unit direction
//! `d = (x, y, z)` falls on
//!
//! ```text
//! u = atan2(x, −z) / 2π   (wrapped to [0, 1)),     v = acos(y) / π,
//! d = (sin φ sin θ, cos θ, −cos φ sin θ)   with φ = 2πu, θ = πv:
//! ```
//!
//! the image's top row is straight up (+y), its left edge looks along −z, and a quarter of the
//! way across it looks along +x. `to_world` (a rotation, possibly with a mirror) turns the map's
//! frame into the scene file's y-up world, which the lab's frame flips (`model_to_lab`).
//!
//! # Lookup
//! Bilinear between texel centres, as Mitsuba's: texel `(x, y)` sits at `u = (x + ½)/w`,
//! `v = y/(h − 1)` (the first and last rows lie on the poles), and the columns wrap around.
//! The radiance is the texel's value times `scale`. Texels must be finite; negative ones (an
//! OpenEXR file's out-of-gamut colours) count as black.
//!
//! # Sampling
//! As Mitsuba's: in proportion to the bilinear interpolant of `f = luminance × sin θ` at the
//! texel centres, over `(u − ½/w, v)`. The patches between four neighbouring texel centres
//! (`w × (h − 1)` of them, the last column's wrapping to the first) are chosen by a
//! [`PiecewiseConstant2D`] of the interpolant's integrals over them (the means of their
//! corners), and a point within the chosen patch by [`sample_bilinear`]: within a patch the
//! density follows the radiance, so a small bright sun adds little noise. `sin θ` is kept
//! above `sin(π/4(h − 1))` on the poles' rows, so that a patch in which the map is not black
//! has a positive density wherever it is not black. The density per unit solid angle is
//! `p(ω) = p(u, v) / (2π² sin θ)`, the Jacobian of the map from the square to the sphere (PBR
//! 3rd ed. §14.2.4, "Infinite Area Lights").
//!
//! # Memory
//! 12 bytes per texel for the radiance and about 4 for the density: an 8k × 4k map takes
//! 512 MiB. The density is built on every core.
//!
//! Tests: `light::envmap::tests` (the convention's known directions, the lookup between texel
//! centres, chi-square goodness of fit of the sampling against its density) and
//! `tests/lights.rs` (a furnace inside a constant map, a map with one bright texel lighting
//! the scene from the direction Mitsuba's convention gives).

use std::f32::consts::{FRAC_1_PI, PI};

use glam::{Mat3, Vec2, Vec3};
use rayon::prelude::*;

use super::error::LightError;
use super::sample::{DirectionSample, Emission};
use crate::color::luminance;
use crate::film::Film;
use crate::sampling::{
    PiecewiseConstant2D, atan2_polynomial, bilinear_pdf, sample_bilinear, sin_cos_turns,
};

/// An equirectangular environment map: its radiance, its orientation, and the density that
/// samples it. Its `Debug` shows its size, orientation and a hash of its texels, not its name:
/// `Scene::content_hash` tells maps apart by what they hold, wherever their files are, without
/// printing millions of texels.
#[derive(Clone, PartialEq)]
pub struct EnvironmentMap {
    /// Where the image came from, for messages.
    name: String,
    width: usize,
    /// At least 2 (a one-row image is doubled).
    height: usize,
    /// Radiance (the image times `scale`), row by row from the top (+y).
    texels: Vec<Vec3>,
    /// From the lab's frame to the map's.
    to_local: Mat3,
    /// From the map's frame to the lab's.
    to_lab: Mat3,
    /// Over the `w × (h − 1)` bilinear patches, in `(u − ½/w, v)`.
    patches: PiecewiseConstant2D,
    /// `sin θ` of each row of texels, kept off zero on the poles' rows.
    row_sin: Vec<f32>,
    /// The radiance averaged over the sphere (`∫ L dω / 4π`), per channel.
    mean: Vec3,
    /// XXH3 of the rows' XXH3s of the texels' bits.
    texel_hash: u64,
}

impl std::fmt::Debug for EnvironmentMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EnvironmentMap")
            .field("size", &(self.width, self.height))
            .field("to_lab", &self.to_lab)
            .field("texel_hash", &format_args!("{:016x}", self.texel_hash))
            .finish()
    }
}

/// The brightest radiance a texel may have after scaling: four of them summed stay far from
/// overflow.
const MAX_RADIANCE: f32 = 1e30;

/// `m`'s columns made orthonormal by Gram–Schmidt, the third keeping its side (a mirror stays
/// a mirror).
fn orthonormalized(m: Mat3) -> Mat3 {
    let x = m.x_axis.normalize();
    let y = (m.y_axis - m.y_axis.dot(x) * x).normalize();
    let z = x.cross(y);
    Mat3::from_cols(x, y, if z.dot(m.z_axis) < 0.0 { -z } else { z })
}

/// `u, v ∈ [0, 1]` of a unit direction in the map's frame (the module's convention).
#[inline]
pub fn direction_to_uv(d: Vec3) -> Vec2 {
    let u = atan2_polynomial(d.x, -d.z) * (0.5 * FRAC_1_PI);
    let u = if u < 0.0 { u + 1.0 } else { u };
    // θ = acos(y), by the arctangent: as precise near the poles as elsewhere.
    let sin_theta = (d.x * d.x + d.z * d.z).sqrt();
    Vec2::new(u, atan2_polynomial(sin_theta, d.y) * FRAC_1_PI)
}

/// The unit direction in the map's frame at `u, v` (the inverse of [`direction_to_uv`]).
#[inline]
pub fn uv_to_direction(uv: Vec2) -> Vec3 {
    // θ = πv is half a turn of v; φ = 2πu is u turns (the samplers' polynomial, within 3·10⁻⁷).
    let (sin_theta, cos_theta) = sin_cos_turns(0.5 * uv.y);
    let (sin_phi, cos_phi) = sin_cos_turns(uv.x);
    Vec3::new(sin_phi * sin_theta, cos_theta, -cos_phi * sin_theta)
}

/// The lab's frame to the scene files' y-up world and back (`scene::model_to_lab`, a half turn
/// about x: its own inverse).
const LAB_TO_WORLD: Mat3 = Mat3::from_diagonal(Vec3::new(1.0, -1.0, -1.0));

impl EnvironmentMap {
    /// The map of `image` (row 0 at the top), its values times `scale`, turned into the scene
    /// files' world by `to_world`; `name` names it in messages.
    ///
    /// Fails for a `scale` that is negative or not finite, a `to_world` that is not a rotation
    /// (possibly with a mirror), and a texel that is not finite (named by its column and row).
    pub fn new(
        name: impl Into<String>,
        image: Film,
        scale: f32,
        to_world: Mat3,
    ) -> Result<EnvironmentMap, LightError> {
        let name = name.into();
        let error = |problem: String| LightError { light: name.clone(), problem };
        if !(scale.is_finite() && scale >= 0.0) {
            return Err(error(format!("scale {scale} must be finite and not negative")));
        }
        let gram = to_world.transpose() * to_world;
        if !to_world.is_finite() || !gram.abs_diff_eq(Mat3::IDENTITY, 1e-4) {
            return Err(error(
                "to_world must be a rotation (an orthonormal matrix; a mirror is allowed)".into(),
            ));
        }
        let (width, height) = (image.width() as usize, image.height() as usize);
        if width == 0 || height == 0 || height > width {
            return Err(error(format!(
                "a {width}×{height} image is no equirectangular map (at least one texel, and at \
                 least as wide as tall: a map of the sphere is twice as wide)"
            )));
        }
        let mut texels = image.into_pixels();
        if let Some(i) = texels.iter().position(|t| !t.is_finite()) {
            return Err(error(format!(
                "texel ({}, {}) is {} (every texel must be finite)",
                i % width,
                i / width,
                texels[i]
            )));
        }
        texels.par_iter_mut().for_each(|t| *t = t.max(Vec3::ZERO) * scale);
        // Sums of four luminances must stay finite for the density.
        if let Some(i) = texels.iter().position(|t| t.max_element() > MAX_RADIANCE) {
            return Err(error(format!(
                "texel ({}, {}) times scale {scale} is {}: more than {MAX_RADIANCE:e}",
                i % width,
                i / width,
                texels[i]
            )));
        }
        let height = if height == 1 {
            texels.extend_from_within(..);
            2
        } else {
            height
        };
        let row_sin = (0..height)
            .map(|y| {
                let floor = 0.25 * PI / (height - 1) as f32;
                (PI * y as f32 / (height - 1) as f32).sin().max(floor.sin())
            })
            .collect::<Vec<f32>>();
        let patches = patch_density(&texels, &row_sin, width);
        let mean = mean_radiance(&texels, width, height);
        let row_hashes: Vec<u64> = texels
            .par_chunks(width)
            .map(|row| {
                let bytes: Vec<u8> =
                    row.iter().flat_map(|t| t.to_array()).flat_map(f32::to_le_bytes).collect();
                xxhash_rust::xxh3::xxh3_64(&bytes)
            })
            .collect();
        let hash_bytes: Vec<u8> = row_hashes.iter().flat_map(|h| h.to_le_bytes()).collect();
        let texel_hash = xxhash_rust::xxh3::xxh3_64(&hash_bytes);
        // Orthonormal to the float (it was within 10⁻⁴), so that its inverse is its transpose
        // and directions stay unit.
        let to_lab = LAB_TO_WORLD * orthonormalized(to_world);
        Ok(EnvironmentMap {
            name,
            width,
            height,
            texels,
            to_local: to_lab.transpose(),
            to_lab,
            patches,
            row_sin,
            mean,
            texel_hash,
        })
    }

    /// Where the image came from.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The image's width and height in texels (a one-row image counts two).
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// The radiance averaged over the sphere, `∫ L dω / 4π`, per channel: the value a constant
    /// environment of the same power would have.
    pub fn mean(&self) -> Vec3 {
        self.mean
    }

    /// The bytes the map holds: its texels and its density.
    pub fn memory_bytes(&self) -> usize {
        let (w, h) = self.patches.size();
        self.texels.len() * size_of::<Vec3>()
            + ((w + 1) * h + h + 1 + self.row_sin.len()) * size_of::<f32>()
    }

    /// The unit direction in the lab's frame that `u, v` of the image looks along.
    pub fn direction(&self, uv: Vec2) -> Vec3 {
        self.to_lab * uv_to_direction(uv)
    }

    /// The radiance arriving along the unit direction `-direction`, that is, seen looking along
    /// `direction` (the lab's frame).
    #[inline]
    pub fn eval(&self, direction: Vec3) -> Vec3 {
        self.lookup(direction_to_uv(self.to_local * direction))
    }

    /// The radiance at `u, v`: bilinear between texel centres (`u` wraps around).
    #[inline]
    pub fn lookup(&self, uv: Vec2) -> Vec3 {
        let (w, h) = (self.width, self.height);
        let x = uv.x * w as f32 - 0.5;
        let x_floor = x.floor();
        let fx = x - x_floor;
        let x0 = (x_floor as i64).rem_euclid(w as i64) as usize;
        let x1 = if x0 + 1 == w { 0 } else { x0 + 1 };
        let y = (uv.y * (h - 1) as f32).clamp(0.0, (h - 1) as f32);
        let y0 = (y as usize).min(h - 2);
        let fy = y - y0 as f32;
        let row0 = &self.texels[y0 * w..(y0 + 1) * w];
        let row1 = &self.texels[(y0 + 1) * w..(y0 + 2) * w];
        let top = row0[x0] * (1.0 - fx) + row0[x1] * fx;
        let bottom = row1[x0] * (1.0 - fx) + row1[x1] * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// `f = luminance × sin θ` at the corners of patch `(column, row)`: `[f(0, 0), f(1, 0),
    /// f(0, 1), f(1, 1)]`, the first index across.
    #[inline]
    fn corners(&self, column: usize, row: usize) -> [f32; 4] {
        let w = self.width;
        let next = if column + 1 == w { 0 } else { column + 1 };
        let (top, bottom) = (row * w, (row + 1) * w);
        let (sin_top, sin_bottom) = (self.row_sin[row], self.row_sin[row + 1]);
        [
            luminance(self.texels[top + column]) * sin_top,
            luminance(self.texels[top + next]) * sin_top,
            luminance(self.texels[bottom + column]) * sin_bottom,
            luminance(self.texels[bottom + next]) * sin_bottom,
        ]
    }

    /// A direction (the lab's frame, toward the light) that `u ∈ [0, 1)²` picks, in proportion
    /// to the map's luminance, with the radiance arriving along it and its density per unit
    /// solid angle; `None` on a pole, where the density is not finite.
    #[inline]
    pub fn sample(&self, u: Vec2) -> Option<DirectionSample> {
        let ((column, row), probability, rest) = self.patches.sample_bin(u);
        self.sample_in_patch((column, row), probability, rest)
    }

    /// [`sample`](Self::sample) for each of `us` (at most
    /// [`SEARCH_LANES`](crate::sampling::SEARCH_LANES)), to the bit: the patches picked with
    /// the lanes' searches taken in step, so that their loads overlap.
    ///
    /// # Panics
    /// If the slices differ in length or hold more than `SEARCH_LANES`.
    pub fn sample_each(&self, us: &[Vec2], out: &mut [Option<DirectionSample>]) {
        let mut bins = [((0, 0), 0.0, Vec2::ZERO); crate::sampling::SEARCH_LANES];
        self.patches.sample_bin_each(us, &mut bins[..us.len()]);
        for (slot, &(patch, probability, rest)) in out.iter_mut().zip(&bins) {
            *slot = self.sample_in_patch(patch, probability, rest);
        }
    }

    /// The rest of [`sample`](Self::sample) once the patch `(column, row)` of probability
    /// `probability` is picked, `rest` the numbers rescaled within it.
    #[inline]
    fn sample_in_patch(
        &self,
        (column, row): (usize, usize),
        probability: f32,
        rest: Vec2,
    ) -> Option<DirectionSample> {
        let (columns, rows) = (self.width, self.height - 1);
        let f = self.corners(column, row);
        let within = sample_bilinear(rest, f);
        let pdf_uv = probability * (columns * rows) as f32 * bilinear_pdf(within, f);
        let mut map_u = (column as f32 + within.x + 0.5) / columns as f32;
        if map_u >= 1.0 {
            map_u -= 1.0;
        }
        let uv = Vec2::new(map_u, (row as f32 + within.y) / rows as f32);
        let local = uv_to_direction(uv);
        let sin_theta = (local.x * local.x + local.z * local.z).sqrt();
        if !(sin_theta > 0.0 && pdf_uv > 0.0) {
            return None;
        }
        let pdf = pdf_uv / (2.0 * PI * PI * sin_theta);
        Some(DirectionSample { direction: self.to_lab * local, radiance: self.lookup(uv), pdf })
    }

    /// The density per unit solid angle with which [`sample`](Self::sample) picks the unit
    /// `direction` (the lab's frame).
    #[inline]
    pub fn pdf(&self, direction: Vec3) -> f32 {
        self.eval_pdf(direction).pdf
    }

    /// [`eval`](Self::eval) and [`pdf`](Self::pdf) together, the direction's place on the map
    /// found once: what a ray that leaves the scene needs.
    #[inline]
    pub fn eval_pdf(&self, direction: Vec3) -> Emission {
        self.eval_pdf_inline(direction)
    }

    /// [`eval_pdf`](Self::eval_pdf), written so that a loop over many directions becomes
    /// vector code (`envmap/lanes.rs`): no branch but selects, no call, and loads at indices
    /// clamped into the tables, so without bounds checks. Its numbers are those of the plain
    /// reading (`lookup`, then the density at `uv`), which the tests keep as a twin: `uv`
    /// comes from [`direction_to_uv`], so `u ∈ [0, 1]` (or NaN), and there the remainders of
    /// the wrap-around are the selects written here.
    #[inline(always)]
    pub(crate) fn eval_pdf_inline(&self, direction: Vec3) -> Emission {
        let local = self.to_local * direction;
        let uv = direction_to_uv(local);
        let radiance = self.lookup_wrapped(uv);
        let sin_theta = (local.x * local.x + local.z * local.z).sqrt();
        let pdf = self.pdf_at(uv, sin_theta);
        Emission { radiance, pdf: if sin_theta <= 0.0 { 0.0 } else { pdf } }
    }

    /// [`lookup`](Self::lookup) for `u ∈ [0, 1]` (or NaN), as [`eval_pdf_inline`] reads it:
    /// there `x = u·w − ½` has `⌊x⌋ ∈ [−1, w − 1]`, whose remainder modulo `w` is itself or,
    /// for −1, `w − 1` (NaN converts to 0 in both); the row is clamped as `lookup` clamps it.
    ///
    /// [`eval_pdf_inline`]: Self::eval_pdf_inline
    #[inline(always)]
    fn lookup_wrapped(&self, uv: Vec2) -> Vec3 {
        let (w, h) = (self.width, self.height);
        let x = uv.x * w as f32 - 0.5;
        let x_floor = x.floor();
        let fx = x - x_floor;
        let xi = x_floor as i32;
        let x0 = (if xi < 0 { xi + w as i32 } else { xi }).clamp(0, w as i32 - 1) as usize;
        let x1 = if x0 + 1 == w { 0 } else { x0 + 1 };
        let y = (uv.y * (h - 1) as f32).clamp(0.0, (h - 1) as f32);
        let y0 = ((y as i32).max(0) as usize).min(h - 2);
        let fy = y - y0 as f32;
        // SAFETY: `x0, x1 < w` and `y0 ≤ h − 2` (clamped above), and `texels` holds `w × h`.
        let texel = |i: usize| unsafe { *self.texels.get_unchecked(i) };
        let (row0, row1) = (y0 * w, (y0 + 1) * w);
        let top = texel(row0 + x0) * (1.0 - fx) + texel(row0 + x1) * fx;
        let bottom = texel(row1 + x0) * (1.0 - fx) + texel(row1 + x1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// The density per unit solid angle at `uv` (`u ∈ [0, 1]` or NaN), where `sin θ` is
    /// `sin_theta` (not zero). Written for vector code, as [`lookup_wrapped`]: there
    /// `x = u·w − ½ ∈ [−½, w − ½]`, whose `rem_euclid(w)` is `x`, or `x + w` below zero.
    ///
    /// [`lookup_wrapped`]: Self::lookup_wrapped
    #[inline(always)]
    fn pdf_at(&self, uv: Vec2, sin_theta: f32) -> f32 {
        let (columns, rows) = (self.width, self.height - 1);
        let x = uv.x * columns as f32 - 0.5;
        let x = if x < 0.0 { x + columns as f32 } else { x };
        let y = uv.y * rows as f32;
        let column = ((x as i32).max(0) as usize).min(columns - 1);
        let row = ((y as i32).max(0) as usize).min(rows - 1);
        let within = Vec2::new(x - column as f32, y - row as f32).clamp(Vec2::ZERO, Vec2::ONE);
        let f = self.corners_unchecked(column, row);
        // SAFETY: `column < w` and `row < h − 1`, the table's size (clamped above).
        let probability = unsafe { self.patches.probability_unchecked(column, row) };
        let pdf_uv = probability * (columns * rows) as f32 * bilinear_pdf(within, f);
        pdf_uv / (2.0 * PI * PI * sin_theta)
    }

    /// [`corners`](Self::corners) without bounds checks: `column < w`, `row < h − 1`.
    #[inline(always)]
    fn corners_unchecked(&self, column: usize, row: usize) -> [f32; 4] {
        let w = self.width;
        let next = if column + 1 == w { 0 } else { column + 1 };
        let (top, bottom) = (row * w, (row + 1) * w);
        // SAFETY: the callers' `column < w` and `row < h − 1`: every index read below is under
        // `w × h`, the texels' count.
        let texel = |i: usize| unsafe { *self.texels.get_unchecked(i) };
        // SAFETY: as above, `row + 1 < h`, the rows' count.
        let sin = |r: usize| unsafe { *self.row_sin.get_unchecked(r) };
        let (sin_top, sin_bottom) = (sin(row), sin(row + 1));
        [
            luminance(texel(top + column)) * sin_top,
            luminance(texel(top + next)) * sin_top,
            luminance(texel(bottom + column)) * sin_bottom,
            luminance(texel(bottom + next)) * sin_bottom,
        ]
    }
}

/// The density over the bilinear patches of `texels` (`width` across, a row per entry of
/// `row_sin`): each patch's integral of the interpolant of `luminance × sin θ` (its corners'
/// mean).
fn patch_density(texels: &[Vec3], row_sin: &[f32], width: usize) -> PiecewiseConstant2D {
    let rows = row_sin.len() - 1;
    let mut weights = vec![0.0f32; width * rows];
    weights.par_chunks_mut(width).enumerate().for_each(|(j, row)| {
        let top = &texels[j * width..(j + 1) * width];
        let bottom = &texels[(j + 1) * width..(j + 2) * width];
        let (sin_top, sin_bottom) = (row_sin[j], row_sin[j + 1]);
        for (i, weight) in row.iter_mut().enumerate() {
            let next = if i + 1 == width { 0 } else { i + 1 };
            let upper = (luminance(top[i]) + luminance(top[next])) * sin_top;
            let lower = (luminance(bottom[i]) + luminance(bottom[next])) * sin_bottom;
            *weight = 0.25 * (upper + lower);
        }
    });
    PiecewiseConstant2D::new(&weights, width, rows)
}

/// The radiance of `texels` (`width × height`, `height ≥ 2`) averaged over the sphere: the
/// exact integral of the interpolant over each patch. Across a patch the interpolant is the
/// mean of its two columns, and down it, linear in θ from the top row's value to the bottom
/// row's, so with `θ = θ₀ + tΔ` the rows weigh `I₀ = ∫₀¹ (1 − t) sin θ Δ dt` and
/// `I₁ = ∫₀¹ t sin θ Δ dt = (sin θ₁ − sin θ₀)/Δ − cos θ₁` (by parts), `I₀ + I₁ = cos θ₀ − cos θ₁`.
fn mean_radiance(texels: &[Vec3], width: usize, height: usize) -> Vec3 {
    use std::f64::consts::PI;
    let rows = height - 1;
    let step = PI / rows as f64;
    let sums: Vec<[f64; 3]> = (0..rows)
        .into_par_iter()
        .map(|j| {
            let (theta0, theta1) = (j as f64 * step, (j + 1) as f64 * step);
            let i1 = (theta1.sin() - theta0.sin()) / step - theta1.cos();
            let i0 = theta0.cos() - theta1.cos() - i1;
            let top = &texels[j * width..(j + 1) * width];
            let bottom = &texels[(j + 1) * width..(j + 2) * width];
            let mut sum = [0.0f64; 3];
            for i in 0..width {
                let next = if i + 1 == width { 0 } else { i + 1 };
                let upper = (0.5 * (top[i] + top[next])).as_dvec3();
                let lower = (0.5 * (bottom[i] + bottom[next])).as_dvec3();
                let integral = upper * i0 + lower * i1;
                for (s, c) in sum.iter_mut().zip(integral.to_array()) {
                    *s += c;
                }
            }
            sum
        })
        .collect();
    let total = sums.iter().fold([0.0f64; 3], |a, s| [a[0] + s[0], a[1] + s[1], a[2] + s[2]]);
    // Each patch spans 2π/w in φ; the mean divides by the sphere's 4π.
    Vec3::from_array(total.map(|t| (t * (2.0 * PI / width as f64) / (4.0 * PI)) as f32))
}

mod lanes;
#[cfg(test)]
mod tests;
