//! What a ray sees where it hits a surface: the [`SurfaceInteraction`] that the geometry
//! computes from a hit (`Geometry::interaction`) and that materials, lights and integrators read.

use glam::{Vec2, Vec3, Vec4};

use crate::ray::SurfacePoint;
use crate::texture::TextureQuery;

/// What a ray sees where it hits a surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceInteraction {
    /// The point, its error bound and the geometric normal (the triangle's front side).
    pub point: SurfacePoint,
    /// The shading normal: interpolated from the mesh's normals (which decide the front side of
    /// one-sided materials, as in Mitsuba); the geometric normal where the mesh has none.
    pub shading_normal: Vec3,
    /// Texture coordinates (the barycentric `(b1, b2)` where the mesh has none).
    pub uv: Vec2,
    /// How the point moves with `u`: the shading frame's tangent direction (before it is made
    /// perpendicular to the shading normal), as Mitsuba's `dp_du`; without UVs, `v1 − v0`.
    pub dp_du: Vec3,
    /// The interpolated tangent for normal maps (w: the bitangent's sign); zero where the mesh
    /// has none.
    pub tangent: Vec4,
    /// Index into the scene's materials.
    pub material: u32,
    /// The triangle hit.
    pub triangle: u32,
    /// Ray parameter of the hit.
    pub t: f32,
}

impl SurfaceInteraction {
    /// Where textures are read here, at a point (footprint 0): the path tracer's lookups.
    #[inline]
    pub fn texture_query(&self) -> TextureQuery {
        TextureQuery { uv: self.uv, p: self.point.p, footprint: 0.0 }
    }
}
