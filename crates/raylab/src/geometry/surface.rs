//! What a hit on the geometry finds: the point with its rounding-error bound, the normals, the
//! texture coordinates and `dp/du` ([`Geometry::interaction`] builds them all; the path tracer's
//! shortcut asks for the parts it needs, [`Geometry::shaded_surface_point`], [`Geometry::uv`]
//! and [`Geometry::dp_du`], which compute them exactly as the interaction does), and where
//! textures are read.

use glam::{Vec2, Vec3, Vec4};

use super::instance::Placement;
use super::{DEFAULT_UVS, Geometry};
use crate::accel::Hit;
use crate::float::gamma;
use crate::interaction::SurfaceInteraction;
use crate::ray::{Ray, SurfacePoint};
use crate::texture::TextureQuery;
use crate::triangle::geometric_normal;

impl Geometry {
    /// The point of `hit` with its rounding-error bound and the geometric normal: the part of
    /// [`interaction`](Self::interaction) that the lab's light model needs.
    #[inline]
    pub fn surface_point(&self, hit: &Hit) -> SurfacePoint {
        let (s, placement) = self.locate(hit.triangle as usize);
        self.surface_point_at(s, placement, hit).0
    }

    /// [`surface_point`](Self::surface_point) on stored triangle `s` where `placement` puts it
    /// (as [`locate`](Self::locate) finds them), and the triangle's world corners
    /// ([`triangle`](Self::triangle)), which the placed point's normal needs anyway.
    #[inline(always)]
    fn surface_point_at(
        &self,
        s: usize,
        placement: Option<&Placement>,
        hit: &Hit,
    ) -> (SurfacePoint, [Vec3; 3]) {
        let corners = self.stored_triangle(s);
        match placement {
            None => {
                let (p, error) = interpolate_point(corners, hit);
                (SurfacePoint { p, error, normal: self.normals[s] }, corners)
            }
            // Interpolated where the hit was found, in object space, then placed with a bound
            // that covers the way there and back (`Placement::world_point`).
            Some(placement) => {
                let (p, error) = interpolate_point(placement.corners(corners), hit);
                let (p, error) = placement.world_point(p, error);
                let world = placement.triangle(corners);
                (SurfacePoint { p, error, normal: geometric_normal(world) }, world)
            }
        }
    }

    /// [`surface_point`](Self::surface_point), the shading normal and the material of a hit on
    /// a triangle that no instance places: exactly what [`interaction`](Self::interaction)
    /// gives there, without the texture coordinates, `dp/du` and tangent. `None` for a placed
    /// triangle. The path tracer's shortcut for vertices without a normal map (with
    /// [`uv`](Self::uv) and [`dp_du`](Self::dp_du) where their material needs them).
    #[inline]
    pub fn shaded_surface_point(&self, hit: &Hit) -> Option<(SurfacePoint, Vec3, u32)> {
        if self.placed {
            return None;
        }
        let s = hit.triangle as usize;
        let (p, error) = interpolate_point(self.stored_triangle(s), hit);
        let point = SurfacePoint { p, error, normal: self.normals[s] };
        let normal = self.shading_normals.get(s).and_then(|c| interpolated_normal(c, None, hit));
        Some((point, normal.unwrap_or(point.normal), self.material_ids[s]))
    }

    /// The texture coordinates of a hit, as [`interaction`](Self::interaction) gives them.
    #[inline]
    pub fn uv(&self, hit: &Hit) -> Vec2 {
        let (s, placement) = self.locate(hit.triangle as usize);
        interpolated_uv(Self::corner_values(&self.uvs, s, placement), hit)
    }

    /// `dp/du` at a hit, as [`interaction`](Self::interaction) gives it (the frame of an
    /// anisotropic BSDF follows it).
    #[inline]
    pub fn dp_du(&self, hit: &Hit) -> Vec3 {
        let (s, placement) = self.locate(hit.triangle as usize);
        // The world corners, as `surface_point_at` places them for the interaction (without
        // the point, which nothing here needs).
        let corners = self.stored_triangle(s);
        let [v0, v1, v2] = placement.map_or(corners, |p| p.triangle(corners));
        Self::corner_values(&self.uvs, s, placement).map_or(v1 - v0, |t| dp_du([v0, v1, v2], t))
    }

    /// A per-axis bound on the rounding error of [`surface_point`](Self::surface_point) for any
    /// point of scene triangle `i` (the largest at its corners: the bound grows with the
    /// coordinates' size).
    pub fn point_error_bound(&self, i: usize) -> Vec3 {
        [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]
            .map(|(b1, b2)| self.surface_point(&Hit { t: 0.0, triangle: i as u32, b1, b2 }).error)
            .into_iter()
            .fold(Vec3::ZERO, Vec3::max)
    }

    /// Where `ray` meets the surface at `hit` (which an accelerator over
    /// [`vertices`](Self::vertices) found for it).
    #[inline]
    pub fn interaction(&self, _ray: &Ray, hit: &Hit) -> SurfaceInteraction {
        // One lookup of the instance and one placing of the corners serve the point, its
        // normal and the parametrization (on the glTF boxes this was three and two).
        let (s, placement) = self.locate(hit.triangle as usize);
        let (point, [v0, v1, v2]) = self.surface_point_at(s, placement, hit);
        let (b0, b1, b2) = (hit.b0(), hit.b1, hit.b2);
        let shading_normal = Self::corner_values(&self.shading_normals, s, placement)
            .and_then(|corners| interpolated_normal(corners, placement, hit))
            .unwrap_or(point.normal);
        // Without UVs, the barycentric parametrization: uv = (b1, b2) and dp/du = v1 − v0.
        let uvs = Self::corner_values(&self.uvs, s, placement);
        let uv = interpolated_uv(uvs, hit);
        let dp_du = uvs.map_or(v1 - v0, |t| dp_du([v0, v1, v2], t));
        let tangent = match Self::corner_values(&self.tangents, s, placement) {
            Some(t) => {
                let t = placement.map_or(t, |p| t.map(|t| p.tangent(t)));
                b0 * t[0] + b1 * t[1] + b2 * t[2]
            }
            None => Vec4::ZERO,
        };
        SurfaceInteraction {
            point,
            shading_normal,
            uv,
            dp_du,
            tangent,
            material: self.material_ids[s],
            triangle: hit.triangle,
            t: hit.t,
        }
    }
}

/// The texture coordinates at `hit` from a triangle's corner UVs, or without them the
/// barycentric parametrization `(b1, b2)`.
#[inline(always)]
fn interpolated_uv(corners: Option<[Vec2; 3]>, hit: &Hit) -> Vec2 {
    match corners {
        Some(t) => hit.b0() * t[0] + hit.b1 * t[1] + hit.b2 * t[2],
        None => Vec2::new(hit.b1, hit.b2),
    }
}

/// The shading normal at `hit` interpolated from a triangle's corner normals (turned by
/// `placement`), as the mesh gives it (as Mitsuba keeps it), even against the winding: the side
/// a one-sided material shows is the normals' side. `None` where the corners are unset (zero: a
/// mesh with normals on some triangles only) or the interpolation has no direction.
#[inline(always)]
fn interpolated_normal(
    mut corners: [Vec3; 3],
    placement: Option<&Placement>,
    hit: &Hit,
) -> Option<Vec3> {
    if corners[0] == Vec3::ZERO {
        return None;
    }
    if let Some(p) = placement {
        corners = corners.map(|n| p.normal(n));
    }
    let n = (hit.b0() * corners[0] + hit.b1 * corners[1] + hit.b2 * corners[2]).normalize_or_zero();
    (n != Vec3::ZERO).then_some(n)
}

/// The point at `hit`'s barycentrics on a triangle's `corners`, and its rounding-error bound
/// (PBR 4th ed. §6.8.5: interpolating the vertices errs by at most γ₇ Σ|bᵢ·pᵢ|).
#[inline(always)]
fn interpolate_point([v0, v1, v2]: [Vec3; 3], hit: &Hit) -> (Vec3, Vec3) {
    let (a, b, c) = (hit.b0() * v0, hit.b1 * v1, hit.b2 * v2);
    (a + b + c, gamma(7) * (a.abs() + b.abs() + c.abs()))
}

impl Geometry {
    /// How many texture-coordinate units a unit of length spans on triangle `i`:
    /// `sqrt(uv area / area)` (0 for a triangle without area or without texture area).
    #[inline]
    pub fn uv_per_length(&self, i: usize) -> f32 {
        let [v0, v1, v2] = self.triangle(i);
        let area = (v1 - v0).cross(v2 - v0).length();
        let (s, placement) = self.locate(i);
        let [t0, t1, t2] = Self::corner_values(&self.uvs, s, placement).unwrap_or(DEFAULT_UVS);
        let uv_area = (t1 - t0).perp_dot(t2 - t0).abs();
        let ratio = (uv_area / area).sqrt();
        if ratio.is_finite() { ratio } else { 0.0 }
    }

    /// The texture coordinates at scene triangle `i`'s corners (its barycentric `(0, 0)`,
    /// `(1, 0)`, `(0, 1)` where the mesh has none).
    pub fn corner_uvs(&self, i: usize) -> [Vec2; 3] {
        let (s, placement) = self.locate(i);
        Self::corner_values(&self.uvs, s, placement).unwrap_or(DEFAULT_UVS)
    }

    /// Where textures are read for `ray` at `hit`, with the footprint of a ray cone that
    /// spreads by `spread` radians from the ray's origin (see [`crate::texture`]): `d · spread`
    /// across at distance `d`, `1/|cos θ|` longer on a slanted surface, in texture units.
    #[inline]
    pub fn texture_query(&self, ray: &Ray, hit: &Hit, spread: f32) -> TextureQuery {
        let i = hit.triangle as usize;
        let [v0, v1, v2] = self.triangle(i);
        let (s, placement) = self.locate(i);
        let uv = interpolated_uv(Self::corner_values(&self.uvs, s, placement), hit);
        let (b0, b1, b2) = (hit.b0(), hit.b1, hit.b2);
        let p = b0 * v0 + b1 * v1 + b2 * v2;
        let footprint = if spread > 0.0 {
            let length = ray.direction.length();
            let cos = (self.normal(i).dot(ray.direction) / length).abs().max(1e-4);
            hit.t * length * spread / cos * self.uv_per_length(i)
        } else {
            0.0
        };
        TextureQuery { uv, p, footprint }
    }
}

/// The partial derivative of position by `u` on a triangle with these corner UVs (Mitsuba's
/// `mesh.cpp`): `v1 − v0` for the default UVs; the first edge where the UVs are degenerate.
#[inline]
fn dp_du([v0, v1, v2]: [Vec3; 3], [uv0, uv1, uv2]: [Vec2; 3]) -> Vec3 {
    let (duv0, duv1) = (uv1 - uv0, uv2 - uv0);
    let (dp0, dp1) = (v1 - v0, v2 - v0);
    let det = duv0.x * duv1.y - duv0.y * duv1.x;
    if det == 0.0 || !det.is_finite() {
        return dp0;
    }
    (duv1.y * dp0 - duv0.y * dp1) / det
}
