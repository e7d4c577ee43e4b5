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

use glam::{Affine3A, DAffine3, DVec3, Mat3, Mat3A, Vec3, Vec4};

use crate::accel::Hit;
use crate::float::gamma;

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
    /// What [`world_point`](Self::world_point) needs to bound a ray's round trip through the
    /// placement (see there).
    round_trip: RoundTrip,
}

/// The rounding of a point carried into object space and back (see
/// [`Placement::world_point`]), for a placement `M = (A, T)` and its computed inverse
/// `M⁻¹ = (B, T')`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct RoundTrip {
    /// `|A|`, element by element: it takes an object-space error bound to the world.
    abs_linear: Mat3A,
    /// `‖B‖∞` and `‖T'‖∞`: the size of the terms `B·o + T'` rounds.
    inverse_norm: f32,
    inverse_translation: f32,
    /// `‖A·B − I‖∞` and `‖A·T' + T‖∞`, exactly (in f64, rounded up): how far `M·M⁻¹` is from
    /// the identity, the inverse being rounded.
    residual: f32,
    translation_residual: f32,
}

impl RoundTrip {
    fn of(to_world: &Affine3A, to_object: &Affine3A) -> RoundTrip {
        let wide = |m: &Affine3A| DAffine3::from_cols_array(&m.to_cols_array().map(f64::from));
        let (m, inverse) = (wide(to_world), wide(to_object));
        let product = m * inverse;
        let rows = product.matrix3.transpose();
        let residual = [rows.x_axis - DVec3::X, rows.y_axis - DVec3::Y, rows.z_axis - DVec3::Z]
            .map(|r| r.abs().element_sum())
            .into_iter()
            .fold(0.0, f64::max);
        let up = |x: f64| (x * (1.0 + 1e-6)) as f32;
        RoundTrip {
            abs_linear: Mat3A::from_cols(
                to_world.matrix3.x_axis.abs(),
                to_world.matrix3.y_axis.abs(),
                to_world.matrix3.z_axis.abs(),
            ),
            inverse_norm: max_row_sum(&to_object.matrix3),
            inverse_translation: to_object.translation.abs().max_element(),
            residual: up(residual),
            translation_residual: up(product.translation.abs().max_element()),
        }
    }
}

/// The infinity norm of `m`: its largest row sum of magnitudes (`‖m·v‖∞ ≤ ‖m‖∞·‖v‖∞`).
pub fn max_row_sum(m: &Mat3A) -> f32 {
    let rows = m.transpose();
    [rows.x_axis, rows.y_axis, rows.z_axis]
        .map(|r| r.abs().element_sum())
        .into_iter()
        .fold(0.0, f32::max)
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
            round_trip: RoundTrip::of(&to_world, &to_object),
        })
    }

    /// A point found in object space, `p` within `error` on each axis, placed in the world: the
    /// world point and a per-axis bound wide enough that a ray leaving it from just beyond the
    /// bound ([`offset_ray_origin`](crate::ray::offset_ray_origin)) is, once carried back into
    /// object space by the rounded `M⁻¹`, still on its side of the surface.
    ///
    /// Three roundings add up (PBR 4th ed. §6.8.5 for the first two): `M·p` itself,
    /// `γ₃ (|A|·|p| + |T|)`; the error already in `p`, taken to the world by `|A|`; and the ray
    /// origin's way back, `M⁻¹·o` rounding by `γ₃ (‖B‖·|o| + ‖T'‖)` in object space (that
    /// much times `|A|` in the world), with `M⁻¹` not quite the inverse of `M`
    /// (`‖A·B − I‖·|o| + ‖A·T' + T‖`). The last two matter where the stored coordinates are
    /// large and the placement brings them back near the origin (a CAD part modelled in place
    /// and moved): they are what a bound made from the world point alone misses.
    #[inline]
    pub fn world_point(&self, p: Vec3, error: Vec3) -> (Vec3, Vec3) {
        let r = &self.round_trip;
        let world = self.to_world.transform_point3(p);
        let placed = (1.0 + gamma(3)) * (r.abs_linear * error)
            + gamma(3) * (r.abs_linear * p.abs() + Vec3::from(self.to_world.translation.abs()));
        // The ray's origin: the world point moved off the surface by about `placed`.
        let origin = world.abs().max_element() + 2.0 * placed.max_element();
        let back = gamma(4) * (r.inverse_norm * origin + r.inverse_translation);
        let residual = r.residual * origin + r.translation_residual;
        (world, placed + r.abs_linear * Vec3::splat(back) + Vec3::splat(residual))
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
        scaled.round_trip = RoundTrip::of(&scaled.to_world, &scaled.to_object);
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
