//! Instances: one stored mesh drawn in several places.
//!
//! A model often uses one part many times: 2CylinderEngine's 82 nodes draw 29 meshes, 14 of them
//! more than once, 121,496 triangles from 75,730 stored ones. [`Geometry`](super::Geometry)
//! keeps such a mesh once, in its own (object) space, and an [`Instance`] per place it is drawn:
//! a run of the scene's triangle indices and the [`Placement`] that takes the stored triangles
//! there. A mesh drawn once is stored in world space already, its instance without a placement.
//!
//! **Scene triangles.** Every other part of raylab sees only the scene's triangles, numbered
//! instance after instance: `Geometry::triangle(i)` gives the world corners of scene triangle
//! `i`, and hits name scene triangles. For example, a mesh `A` of 2 triangles drawn once, then a
//! mesh `B` of 3 triangles drawn twice:
//!
//! ```text
//!   stored triangles   0 1 | 2 3 4            (A in world space, B in its own space)
//!   instances          A: first 0, stored 0, count 2, no placement
//!                      B: first 2, stored 2, count 3, placement P
//!                      B: first 5, stored 2, count 3, placement Q
//!   scene triangles    0 1 | 2 3 4 | 5 6 7    (scene 6 is stored 3 placed by Q)
//! ```
//!
//! Without any placement (every mesh drawn once, the usual case) scene and stored indices are
//! the same and no lookup is made.
//!
//! **Mirrors.** A placement whose determinant is negative turns the triangles' winding, and so
//! their front side, inside out. As the flattening loaders do, raylab keeps the front side: a
//! mirrored instance's scene triangles have the stored corners `v0, v2, v1`, and everything at
//! the corners (normals, texture coordinates, tangents) follows that order. A hit found in object
//! space swaps its barycentric `b1` and `b2` to match ([`Placement::world_hit`]).

use glam::{Affine3A, Mat3, Vec3, Vec4};

use crate::accel::Hit;

/// How an instance's stored triangles reach the world: an invertible affine map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// Object space to world space.
    pub to_world: Affine3A,
    /// World space to object space: what rays are carried by.
    pub to_object: Affine3A,
    /// Normals turn by the inverse transpose.
    normal_matrix: Mat3,
    /// Whether the map is a mirror (negative determinant).
    pub mirrored: bool,
}

impl Placement {
    /// The placement `to_world`, or `None` if it is not finite or not invertible (a node scaled
    /// to nothing: its triangles are stored flattened instead).
    pub fn new(to_world: Affine3A) -> Option<Placement> {
        let det = to_world.matrix3.determinant();
        if !(to_world.is_finite() && det.is_normal()) {
            return None;
        }
        let to_object = to_world.inverse();
        to_object.is_finite().then(|| Placement {
            to_world,
            to_object,
            normal_matrix: to_world.matrix3.inverse().transpose().into(),
            mirrored: det < 0.0,
        })
    }

    /// Three values at a stored triangle's corners, in the scene triangle's order.
    #[inline]
    pub fn corners<T>(&self, [a, b, c]: [T; 3]) -> [T; 3] {
        if self.mirrored { [a, c, b] } else { [a, b, c] }
    }

    /// A stored triangle's corners in the world, in the scene triangle's order.
    #[inline]
    pub fn triangle(&self, corners: [Vec3; 3]) -> [Vec3; 3] {
        self.corners(corners.map(|p| self.to_world.transform_point3(p)))
    }

    /// A shading normal in the world (unit, or zero for none).
    #[inline]
    pub fn normal(&self, n: Vec3) -> Vec3 {
        (self.normal_matrix * n).normalize_or_zero()
    }

    /// A tangent in the world: it turns with the surface; a mirror flips the bitangent's side.
    #[inline]
    pub fn tangent(&self, t: Vec4) -> Vec4 {
        let sign = if self.mirrored { -1.0 } else { 1.0 };
        (self.to_world.matrix3 * t.truncate()).normalize_or_zero().extend(t.w * sign)
    }

    /// A hit on the stored triangle `local` (found in object space), as a hit on the scene
    /// triangle `scene`: the same `t` (object-space rays keep the world's parametrization), the
    /// barycentrics in the scene triangle's corner order.
    #[inline]
    pub fn world_hit(&self, hit: Hit, scene: u32) -> Hit {
        let (b1, b2) = if self.mirrored { (hit.b2, hit.b1) } else { (hit.b1, hit.b2) };
        Hit { t: hit.t, triangle: scene, b1, b2 }
    }

    /// The same placement for a scene scaled by `factor` about the origin, whose stored
    /// positions are scaled too: `S·M·S⁻¹` keeps the linear part and scales the translation.
    pub(super) fn scaled(&self, factor: f32) -> Placement {
        let mut to_world = self.to_world;
        to_world.translation *= factor;
        let mut scaled = *self;
        scaled.to_world = to_world;
        scaled.to_object = to_world.inverse();
        scaled
    }

    pub(super) fn bits(&self) -> impl Iterator<Item = u32> + '_ {
        self.to_world.to_cols_array().into_iter().map(f32::to_bits)
    }
}

/// A run of the scene's triangles drawn from stored ones (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    /// Its first scene triangle.
    pub first: u32,
    /// The first stored triangle it draws.
    pub stored_first: u32,
    /// How many triangles it draws.
    pub count: u32,
    /// How its stored triangles reach the world; `None`: they are stored in world space.
    pub placement: Option<Placement>,
}
