//! Textures: values that vary over a surface, read where a ray hits it.
//!
//! A [`Texture`] is a material input (a colour, a roughness, a normal map's normals) evaluated
//! at a [`TextureQuery`]: the hit's texture coordinates, its position, and the footprint the
//! ray's pixel covers there. Image textures ([`ImageTexture`]) read a [`TextureImage`] (PNG or
//! JPEG, [`decode_texture`]) through a transform of the coordinates (OBJ's upward `v`, glTF's
//! `KHR_texture_transform`), with a wrap mode per axis, scaled by a factor (glTF's
//! `baseColorFactor`). Procedural textures ([`NoiseTexture`]: Perlin noise, fBm, clouds,
//! marble, wood) are read at the point in space.
//!
//! **Filtering.** The footprint picks the mip-map level (trilinear filtering): at one sample per
//! pixel (the lab's integrator, `raylab view`) a checkerboard in the distance turns grey instead
//! of shimmering. The footprint comes from a ray cone (Akenine-Möller et al. 2019, "Texture Level
//! of Detail Strategies for Real-Time Ray Tracing"): a camera ray's pixel spreads by the angle
//! one pixel subtends, so at distance `d` it is `d · angle` wide, `1/|cos θ|` longer on a slanted
//! surface, and `sqrt(uv area / world area)` of the triangle turns that into texture units
//! (`Geometry::uv_per_length`). The path tracer averages many samples per
//! pixel, which filters the texture by itself: it reads level 0 bilinearly (footprint 0), as
//! Mitsuba 3 does, so that the two converge to the same image.

mod image;
#[cfg(feature = "io")]
mod load;
mod noise;
mod query;

use std::sync::Arc;

use glam::{Affine2, Vec2, Vec3, Vec4};

pub use image::{Level, Texels, TextureImage, Wrap};
#[cfg(feature = "io")]
pub use load::{
    MAX_TEXTURE_SIDE, MAX_TEXTURE_TEXELS, TextureError, check_size, decode_texture, load_texture,
};
pub use noise::{NoiseTexture, Pattern, Perlin};
pub use query::TextureQuery;

/// An image read through a coordinate transform, a wrap mode per axis and a factor.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageTexture {
    /// The image, shared by every material that uses it.
    pub image: Arc<TextureImage>,
    /// How `s` and `t` wrap.
    pub wrap: [Wrap; 2],
    /// From the mesh's `uv` to the image's `(s, t)` (see [`TextureImage`]'s coordinates).
    pub transform: Affine2,
    /// Multiplies every texel (RGBA).
    pub factor: Vec4,
}

impl ImageTexture {
    /// The image as glTF reads it: `(s, t) = uv`, repeating, factor 1.
    pub fn new(image: Arc<TextureImage>) -> ImageTexture {
        ImageTexture {
            image,
            wrap: [Wrap::Repeat; 2],
            transform: Affine2::IDENTITY,
            factor: Vec4::ONE,
        }
    }

    /// The image as OBJ reads it: `v` runs upward from the bottom row, so `t = 1 − v`.
    pub fn obj(image: Arc<TextureImage>) -> ImageTexture {
        let flip = Affine2::from_cols(Vec2::X, -Vec2::Y, Vec2::Y);
        ImageTexture { transform: flip, ..ImageTexture::new(image) }
    }

    /// The filtered value at `query` (RGBA, linear).
    #[inline]
    pub fn eval(&self, query: &TextureQuery) -> Vec4 {
        let st = self.transform.transform_point2(query.uv);
        // The transform stretches the footprint by up to its larger column.
        let m = self.transform.matrix2;
        // (A point lookup, the path tracer's, skips the square roots: 0 times any length is 0
        // or NaN, and `filtered` reads level 0 bilinearly for both.)
        let footprint = if query.footprint == 0.0 {
            0.0
        } else {
            query.footprint * m.x_axis.length().max(m.y_axis.length())
        };
        self.image.filtered(st, footprint, self.wrap) * self.factor
    }
}

/// A material input that varies over the surface.
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    /// An image.
    Image(ImageTexture),
    /// A procedural pattern in space.
    Noise(NoiseTexture),
}

impl Texture {
    /// The value at `query`: RGBA, linear.
    #[inline]
    pub fn eval(&self, query: &TextureQuery) -> Vec4 {
        match self {
            Texture::Image(image) => image.eval(query),
            Texture::Noise(noise) => noise.eval(query),
        }
    }

    /// The colour at `query`, without alpha.
    #[inline]
    pub fn rgb(&self, query: &TextureQuery) -> Vec3 {
        self.eval(query).truncate()
    }
}

#[cfg(test)]
mod tests;
