//! The scene's geometry: triangle meshes, built into an accelerator, and what a hit on them is.
//!
//! Meshes are appended into one table of triangles, so that a hit's primitive index
//! ([`Hit::triangle`]) names one triangle of the whole scene; [`Geometry::meshes`] says which mesh
//! it came from. Each triangle has three indices into shared positions, a material, and
//! optionally shading normals and texture coordinates at its corners.
//!
//! **Front faces.** A triangle's geometric normal is `normalize((v1 − v0) × (v2 − v0))`: its
//! front side is the one from which its corners run counter-clockwise, as in OBJ, PLY, glTF,
//! Mitsuba and pbrt. (The lab's `Triangle::normal` is the opposite vector; the lab integrator turns
//! every normal toward the viewer, so both give the same pictures.)
//!
//! [`Geometry::interaction`] turns a ray and its hit into a [`SurfaceInteraction`]: the point with
//! its rounding-error bound, the normals, the texture coordinates and the material. Every
//! integrator shades through it.

use glam::{Affine3A, Vec2, Vec3, Vec4};

use crate::accel::Hit;
use crate::float::gamma;
use crate::mesh::Mesh;
use crate::ray::{Ray, SurfacePoint};
use crate::texture::TextureQuery;

/// Which triangles of a [`Geometry`] one mesh added.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshRange {
    /// The mesh's name, for messages.
    pub name: String,
    /// Its first triangle.
    pub first: u32,
    /// How many triangles it has.
    pub count: u32,
}

/// Triangle meshes appended into one table (see the module documentation).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Geometry {
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    normals: Vec<Vec3>,
    /// Shading normals at each triangle's corners: empty when no mesh has any; a triangle without
    /// them has zero vectors.
    shading_normals: CornerTable<Vec3>,
    /// Texture coordinates at each triangle's corners: empty when no mesh has any.
    uvs: CornerTable<Vec2>,
    /// Tangents (w: the bitangent's sign) at each triangle's corners: empty when no mesh has
    /// any; a triangle without them has zero vectors.
    tangents: CornerTable<Vec4>,
    material_ids: Vec<u32>,
    meshes: Vec<MeshRange>,
}

/// Values at triangles' corners, indexed as the meshes give them: each value stored once
/// however many corners share it (a normal per vertex costs 12 bytes a vertex, not 36 a
/// triangle).
#[derive(Clone, Debug, Default, PartialEq)]
struct CornerTable<T> {
    values: Vec<T>,
    /// Each triangle's three indices into `values`; empty when no mesh has the attribute.
    corners: Vec<[u32; 3]>,
}

impl<T: Copy> CornerTable<T> {
    /// Triangle `i`'s three values, if the table has them.
    #[inline]
    fn get(&self, i: usize) -> Option<[T; 3]> {
        let corners = self.corners.get(i)?;
        Some(corners.map(|k| self.values[k as usize]))
    }

    /// Gives every triangle before `until` that has no values the corners `fill`.
    fn pad(&mut self, until: usize, fill: [T; 3]) {
        if self.corners.len() < until {
            let base = self.values.len() as u32;
            self.values.extend(fill);
            self.corners.resize(until, [base, base + 1, base + 2]);
        }
    }

    /// Appends a mesh's values and its triangles' indices into them.
    fn append(&mut self, values: impl IntoIterator<Item = T>, corners: &[[u32; 3]]) {
        let base = self.values.len() as u32;
        self.values.extend(values);
        self.corners.extend(corners.iter().map(|c| c.map(|k| base + k)));
    }

    fn bytes(&self) -> usize {
        std::mem::size_of_val(self.values.as_slice())
            + std::mem::size_of_val(self.corners.as_slice())
    }
}

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

impl Geometry {
    /// Feeds every triangle's vertices, normals, shading normals, texture coordinates and
    /// material into `hasher`, as their bits.
    pub(crate) fn hash_into(&self, hasher: &mut xxhash_rust::xxh3::Xxh3) {
        let mut buffer = Vec::with_capacity(1 << 16);
        let mut put = |words: &mut dyn Iterator<Item = u32>| {
            for word in words {
                buffer.extend_from_slice(&word.to_le_bytes());
                if buffer.len() >= 1 << 16 {
                    hasher.update(&buffer);
                    buffer.clear();
                }
            }
            // A separator, so that arrays of different lengths cannot run into each other.
            buffer.extend_from_slice(&u32::MAX.to_le_bytes());
        };
        let bits = |v: &Vec3| v.to_array().map(f32::to_bits);
        put(&mut self.positions.iter().flat_map(bits));
        put(&mut self.triangles.iter().flatten().copied());
        put(&mut self.normals.iter().flat_map(bits));
        put(&mut self.shading_normals.values.iter().flat_map(bits));
        put(&mut self.shading_normals.corners.iter().flatten().copied());
        put(&mut self.uvs.values.iter().flat_map(|v| v.to_array().map(f32::to_bits)));
        put(&mut self.uvs.corners.iter().flatten().copied());
        put(&mut self.tangents.values.iter().flat_map(|v| v.to_array().map(f32::to_bits)));
        put(&mut self.tangents.corners.iter().flatten().copied());
        put(&mut self.material_ids.iter().copied());
        hasher.update(&buffer);
    }

    /// No triangles.
    pub fn new() -> Geometry {
        Geometry::default()
    }

    /// Appends a mesh: its positions through `transform`, its triangles with the materials
    /// `material_of(i)` gives, and its normals and texture coordinates if it has them (its own
    /// materials are the caller's to map).
    ///
    /// # Panics
    /// If an index is out of range of the mesh's positions or attributes (loaders check them).
    pub fn add_mesh(
        &mut self,
        mesh: &Mesh,
        transform: &Affine3A,
        mut material_of: impl FnMut(usize) -> u32,
    ) {
        let (name, positions, triangles) = (&mesh.name, &mesh.positions, &mesh.triangles);
        let (normals, uvs) = (mesh.normals.as_ref(), mesh.uvs.as_ref());
        let base = self.positions.len() as u32;
        let first = self.triangles.len();
        self.positions.extend(positions.iter().map(|&p| transform.transform_point3(p)));
        for (i, t) in triangles.iter().enumerate() {
            self.triangles.push(t.map(|v| base + v));
            self.material_ids.push(material_of(i));
        }
        self.normals.extend(
            self.triangles[first..]
                .iter()
                .map(|t| geometric_normal(t.map(|v| self.positions[v as usize]))),
        );
        // Normals transform by the inverse transpose.
        let normal_matrix = transform.matrix3.inverse().transpose();
        let all = self.triangles.len();
        if let Some(normals) = normals {
            self.shading_normals.pad(first, [Vec3::ZERO; 3]);
            let values = normals.values.iter().map(|&n| (normal_matrix * n).normalize_or_zero());
            self.shading_normals.append(values, &normals.triangles);
        } else if !self.shading_normals.corners.is_empty() {
            self.shading_normals.pad(all, [Vec3::ZERO; 3]);
        }
        if let Some(tangents) = &mesh.tangents {
            // Tangents lie in the surface: they turn with the transform; a mirror flips the
            // bitangent's side.
            let sign = transform.matrix3.determinant().signum();
            self.tangents.pad(first, [Vec4::ZERO; 3]);
            let values = tangents
                .values
                .iter()
                .map(|v| (transform.matrix3 * v.truncate()).normalize_or_zero().extend(v.w * sign));
            self.tangents.append(values, &tangents.triangles);
        } else if !self.tangents.corners.is_empty() {
            self.tangents.pad(all, [Vec4::ZERO; 3]);
        }
        if let Some(uvs) = uvs {
            self.uvs.pad(first, DEFAULT_UVS);
            self.uvs.append(uvs.values.iter().copied(), &uvs.triangles);
        } else if !self.uvs.corners.is_empty() {
            self.uvs.pad(all, DEFAULT_UVS);
        }
        self.meshes.push(MeshRange {
            name: name.clone(),
            first: first as u32,
            count: triangles.len() as u32,
        });
    }

    /// Appends triangles given by their corners (no shared vertices), each with its material.
    pub fn add_triangles(
        &mut self,
        name: &str,
        triangles: impl IntoIterator<Item = ([Vec3; 3], u32)>,
    ) {
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        let mut materials = Vec::new();
        for (corners, material) in triangles {
            let base = positions.len() as u32;
            positions.extend(corners);
            indices.push([base, base + 1, base + 2]);
            materials.push(material);
        }
        let mesh =
            Mesh { name: name.to_string(), positions, triangles: indices, ..Mesh::default() };
        self.add_mesh(&mesh, &Affine3A::IDENTITY, |i| materials[i]);
    }

    /// The bytes its tables take (their lengths, not their spare capacity).
    pub fn bytes(&self) -> u64 {
        use std::mem::size_of_val;
        let bytes = size_of_val(self.positions.as_slice())
            + size_of_val(self.triangles.as_slice())
            + size_of_val(self.normals.as_slice())
            + self.shading_normals.bytes()
            + self.uvs.bytes()
            + self.tangents.bytes()
            + size_of_val(self.material_ids.as_slice());
        bytes as u64
    }

    /// The number of triangles.
    #[inline]
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The three corners of triangle `i`.
    #[inline]
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        self.triangles[i].map(|v| self.positions[v as usize])
    }

    /// Every triangle's corners, in order: what accelerators are built from.
    pub fn vertices(&self) -> Vec<[Vec3; 3]> {
        (0..self.len()).map(|i| self.triangle(i)).collect()
    }

    /// The unit geometric normal of triangle `i` (zero for a zero-area triangle).
    #[inline]
    pub fn normal(&self, i: usize) -> Vec3 {
        self.normals[i]
    }

    /// The material of triangle `i`.
    #[inline]
    pub fn material_id(&self, i: usize) -> u32 {
        self.material_ids[i]
    }

    /// Every triangle's material, in order.
    pub fn material_ids(&self) -> &[u32] {
        &self.material_ids
    }

    /// Sets the material of every triangle (for scenes that restyle loaded meshes).
    pub fn material_ids_mut(&mut self) -> &mut [u32] {
        &mut self.material_ids
    }

    /// The area of triangle `i`.
    pub fn area(&self, i: usize) -> f32 {
        let [v0, v1, v2] = self.triangle(i);
        0.5 * (v1 - v0).cross(v2 - v0).length()
    }

    /// The meshes, in the order they were added.
    pub fn meshes(&self) -> &[MeshRange] {
        &self.meshes
    }

    /// The mesh that triangle `i` belongs to.
    pub fn mesh_of(&self, i: u32) -> Option<&MeshRange> {
        let index = self.meshes.partition_point(|m| m.first + m.count <= i);
        self.meshes.get(index)
    }

    /// The vertex positions (some may be unused).
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// The same geometry with every position moved by `f` (normals recomputed).
    pub fn map_positions(&self, f: impl Fn(Vec3) -> Vec3) -> Geometry {
        let mut geometry = self.clone();
        for p in &mut geometry.positions {
            *p = f(*p);
        }
        for (i, n) in geometry.normals.iter_mut().enumerate() {
            *n = geometric_normal(self.triangles[i].map(|v| geometry.positions[v as usize]));
        }
        geometry
    }

    /// The bounding box `(min, max)` of every triangle's corners, or `None` without triangles.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        crate::mesh::bounds_of(self.triangles.iter().flatten().map(|&v| self.positions[v as usize]))
    }

    /// The point of `hit` with its rounding-error bound and the geometric normal: the part of
    /// [`interaction`](Self::interaction) that the lab's light model needs.
    #[inline]
    pub fn surface_point(&self, hit: &Hit) -> SurfacePoint {
        let i = hit.triangle as usize;
        let [v0, v1, v2] = self.triangle(i);
        // PBR 4th ed. §6.8.5: interpolating the vertices errs by at most γ₇ Σ|bᵢ·pᵢ|.
        let (a, b, c) = (hit.b0() * v0, hit.b1 * v1, hit.b2 * v2);
        SurfacePoint {
            p: a + b + c,
            error: gamma(7) * (a.abs() + b.abs() + c.abs()),
            normal: self.normals[i],
        }
    }

    /// Where `ray` meets the surface at `hit` (which an accelerator over [`vertices`](Self::vertices)
    /// found for it).
    #[inline]
    pub fn interaction(&self, _ray: &Ray, hit: &Hit) -> SurfaceInteraction {
        let i = hit.triangle as usize;
        let [v0, v1, v2] = self.triangle(i);
        let (b0, b1, b2) = (hit.b0(), hit.b1, hit.b2);
        // PBR 4th ed. §6.8.5: interpolating the vertices errs by at most γ₇ Σ|bᵢ·pᵢ|.
        let (a, b, c) = (b0 * v0, b1 * v1, b2 * v2);
        let normal = self.normals[i];
        let point =
            SurfacePoint { p: a + b + c, error: gamma(7) * (a.abs() + b.abs() + c.abs()), normal };
        let mut shading_normal = normal;
        if let Some(corners) = self.shading_normals.get(i)
            && corners[0] != Vec3::ZERO
        {
            let n = (b0 * corners[0] + b1 * corners[1] + b2 * corners[2]).normalize_or_zero();
            if n != Vec3::ZERO {
                // As the mesh gives it (as Mitsuba keeps it), even against the winding: the
                // side a one-sided material shows is the normals' side.
                shading_normal = n;
            }
        }
        // Without UVs, the barycentric parametrization: uv = (b1, b2) and dp/du = v1 − v0.
        let (uv, dp_du) = match self.uvs.get(i) {
            Some(t) => (b0 * t[0] + b1 * t[1] + b2 * t[2], dp_du([v0, v1, v2], t)),
            None => (Vec2::new(b1, b2), v1 - v0),
        };
        let tangent = match self.tangents.get(i) {
            Some(t) => b0 * t[0] + b1 * t[1] + b2 * t[2],
            None => Vec4::ZERO,
        };
        SurfaceInteraction {
            point,
            shading_normal,
            uv,
            dp_du,
            tangent,
            material: self.material_ids[i],
            triangle: hit.triangle,
            t: hit.t,
        }
    }
}

impl SurfaceInteraction {
    /// Where textures are read here, at a point (footprint 0): the path tracer's lookups.
    #[inline]
    pub fn texture_query(&self) -> TextureQuery {
        TextureQuery { uv: self.uv, p: self.point.p, footprint: 0.0 }
    }
}

impl Geometry {
    /// How many texture-coordinate units a unit of length spans on triangle `i`:
    /// `sqrt(uv area / area)` (0 for a triangle without area or without texture area).
    #[inline]
    pub fn uv_per_length(&self, i: usize) -> f32 {
        let [v0, v1, v2] = self.triangle(i);
        let area = (v1 - v0).cross(v2 - v0).length();
        let [t0, t1, t2] = self.uvs.get(i).unwrap_or(DEFAULT_UVS);
        let uv_area = (t1 - t0).perp_dot(t2 - t0).abs();
        let ratio = (uv_area / area).sqrt();
        if ratio.is_finite() { ratio } else { 0.0 }
    }

    /// Where textures are read for `ray` at `hit`, with the footprint of a ray cone that
    /// spreads by `spread` radians from the ray's origin (see [`crate::texture`]): `d · spread`
    /// across at distance `d`, `1/|cos θ|` longer on a slanted surface, in texture units.
    #[inline]
    pub fn texture_query(&self, ray: &Ray, hit: &Hit, spread: f32) -> TextureQuery {
        let i = hit.triangle as usize;
        let [v0, v1, v2] = self.triangle(i);
        let (b0, b1, b2) = (hit.b0(), hit.b1, hit.b2);
        let uv = match self.uvs.get(i) {
            Some(t) => b0 * t[0] + b1 * t[1] + b2 * t[2],
            None => Vec2::new(b1, b2),
        };
        let p = b0 * v0 + b1 * v1 + b2 * v2;
        let footprint = if spread > 0.0 {
            let length = ray.direction.length();
            let cos = (self.normals[i].dot(ray.direction) / length).abs().max(1e-4);
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

/// Texture coordinates of a triangle that has none: its barycentric `(b1, b2)`.
const DEFAULT_UVS: [Vec2; 3] = [Vec2::ZERO, Vec2::X, Vec2::Y];

/// The unit normal `(v1 − v0) × (v2 − v0)` of the counter-clockwise side, zero for zero area.
#[inline]
pub fn geometric_normal([v0, v1, v2]: [Vec3; 3]) -> Vec3 {
    (v1 - v0).cross(v2 - v0).normalize_or_zero()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::CornerAttribute;

    fn quad(name: &str) -> Mesh {
        Mesh {
            name: name.into(),
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            ..Mesh::default()
        }
    }

    #[test]
    fn meshes_append_with_offsets_transforms_and_materials() {
        let mut geometry = Geometry::new();
        geometry.add_mesh(&quad("a"), &Affine3A::IDENTITY, |_| 0);
        let moved = Affine3A::from_translation(Vec3::Z * 2.0);
        geometry.add_mesh(&quad("b"), &moved, |i| i as u32 + 1);
        assert_eq!(geometry.len(), 4);
        assert_eq!(
            geometry.triangle(3),
            [Vec3::Z * 2.0, Vec3::new(1.0, 1.0, 2.0), Vec3::new(0.0, 1.0, 2.0)]
        );
        assert_eq!(geometry.material_ids(), &[0, 0, 1, 2]);
        assert_eq!(geometry.normal(2), Vec3::Z, "counter-clockwise seen from +z");
        assert_eq!(geometry.mesh_of(1).unwrap().name, "a");
        assert_eq!(geometry.mesh_of(2).unwrap().name, "b");
        assert!(geometry.mesh_of(4).is_none());
        assert_eq!(geometry.bounds(), Some((Vec3::ZERO, Vec3::new(1.0, 1.0, 2.0))));
        assert_eq!(geometry.area(0), 0.5);
    }

    #[test]
    fn interactions_interpolate_normals_and_uvs() {
        let normals = CornerAttribute {
            values: vec![Vec3::Z, Vec3::new(1.0, 0.0, 1.0).normalize()],
            triangles: vec![[0, 1, 0], [0, 0, 0]],
        };
        let uvs = CornerAttribute {
            values: vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y],
            triangles: quad("").triangles,
        };
        let mut geometry = Geometry::new();
        // A mesh without attributes first: it gets defaults when the second brings some.
        geometry.add_mesh(&quad("plain"), &Affine3A::IDENTITY, |_| 7);
        let scale = Affine3A::from_scale(Vec3::new(2.0, 1.0, 1.0));
        let smooth = Mesh { normals: Some(normals), uvs: Some(uvs), ..quad("smooth") };
        geometry.add_mesh(&smooth, &scale, |_| 3);
        let ray = Ray::new(Vec3::new(2.0, 0.0, 1.0), -Vec3::Z);
        // Triangle 2 is (0,0)-(2,0)-(2,1); the hit is its corner v1.
        let hit = Hit { t: 1.0, triangle: 2, b1: 1.0, b2: 0.0 };
        let si = geometry.interaction(&ray, &hit);
        assert_eq!(si.point.p, Vec3::new(2.0, 0.0, 0.0));
        assert_eq!(si.material, 3);
        assert_eq!(si.uv, Vec2::X);
        // u runs along x, over 2 units of the scaled quad: dp/du = (2, 0, 0).
        assert!((si.dp_du - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-6, "{}", si.dp_du);
        // (1, 0, 1) through the inverse transpose of diag(2, 1, 1): (0.5, 0, 1), normalized.
        let expected = Vec3::new(0.5, 0.0, 1.0).normalize();
        assert!((si.shading_normal - expected).length() < 1e-6, "{}", si.shading_normal);
        // The plain mesh: geometric normal and barycentric uvs.
        let si = geometry.interaction(&ray, &Hit { t: 1.0, triangle: 0, b1: 0.25, b2: 0.5 });
        assert_eq!((si.shading_normal, si.uv, si.material), (Vec3::Z, Vec2::new(0.25, 0.5), 7));
        // Without UVs, Mitsuba's dp/du: the first edge.
        assert_eq!(si.dp_du, Vec3::X);
        assert!(si.point.error.max_element() < 1e-6);
    }

    #[test]
    fn shading_normals_are_kept_as_the_mesh_gives_them() {
        let normals = CornerAttribute { values: vec![-Vec3::Z], triangles: vec![[0, 0, 0]; 2] };
        let mut geometry = Geometry::new();
        let flipped = Mesh { normals: Some(normals), ..quad("flipped") };
        geometry.add_mesh(&flipped, &Affine3A::IDENTITY, |_| 0);
        let si = geometry.interaction(
            &Ray::new(Vec3::Z, -Vec3::Z),
            &Hit { t: 1.0, triangle: 0, b1: 0.3, b2: 0.3 },
        );
        assert_eq!(si.shading_normal, -Vec3::Z);
        assert_eq!(si.point.normal, Vec3::Z);
    }
}
