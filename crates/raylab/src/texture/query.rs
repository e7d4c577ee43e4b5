//! Where a texture is read ([`TextureQuery`]): the point, its texture coordinates and its
//! footprint.

use glam::{Vec2, Vec3};

/// Where a texture is read: what a [`Texture`](super::Texture) needs to know about a hit.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TextureQuery {
    /// The texture coordinates.
    pub uv: Vec2,
    /// The point in the scene (for solid textures).
    pub p: Vec3,
    /// How wide the pixel's footprint is, in texture-coordinate units (0: a point).
    pub footprint: f32,
}
