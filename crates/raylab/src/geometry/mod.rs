//! The scene's geometry: triangle meshes, built into an accelerator, and what a hit on them is.
//!
//! Meshes are appended into one table of triangles, so that a hit's primitive index
//! ([`Hit::triangle`](crate::accel::Hit::triangle)) names one triangle of the whole scene;
//! [`Geometry::meshes`] says which mesh it came from. Each triangle has three indices into
//! shared positions, a material, and optionally shading normals and texture coordinates at its
//! corners.
//!
//! **Front faces.** A triangle's geometric normal is `normalize((v1 − v0) × (v2 − v0))`: its
//! front side is the one from which its corners run counter-clockwise, as in OBJ, PLY, glTF,
//! Mitsuba and pbrt. (The lab's `Triangle::normal` is the opposite vector; the lab integrator turns
//! every normal toward the viewer, so both give the same pictures.)
//!
//! A mesh drawn in several places is stored once, with an [`Instance`] for each place (see
//! [`instance`]): triangle indices everywhere else are the scene's, and the world corners of
//! scene triangle `i` are [`Geometry::triangle(i)`](Geometry::triangle).
//!
//! [`Geometry::interaction`] (in `surface.rs`, with the parts of it the path tracer's shortcut
//! asks for) turns a ray and its hit into a
//! [`SurfaceInteraction`](crate::interaction::SurfaceInteraction): the point with its
//! rounding-error bound, the normals, the texture coordinates and the material. Every
//! integrator shades through it.

mod corners;
pub mod instance;
mod lines;
mod surface;

use glam::{Affine3A, Vec2, Vec3, Vec4};

use corners::CornerTable;
pub use instance::{Instance, Placement};
pub(crate) use lines::TriangleLine;
use lines::{LazyLines, MOST_LINES};

use crate::mesh::Mesh;
use crate::triangle::geometric_normal;

/// Which stored triangles of a [`Geometry`] one mesh added.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshRange {
    /// The mesh's name, for messages.
    pub name: String,
    /// Its first stored triangle.
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
    /// Where the scene's triangles come from, in order: one for each mesh drawn once, one per
    /// place for a mesh drawn in several.
    instances: Vec<Instance>,
    /// Whether some instance has a placement (else scene and stored indices are the same).
    placed: bool,
    /// The number of scene triangles.
    scene_triangles: usize,
    /// Each triangle in one cache line, made on first use ([`triangle_lines`](Self::triangle_lines)).
    lines: LazyLines,
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
        put(&mut self.instances.iter().flat_map(|instance| {
            let placement = instance.placement.iter().flat_map(Placement::bits);
            [instance.first, instance.stored_first, instance.count].into_iter().chain(placement)
        }));
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
        material_of: impl FnMut(usize) -> u32,
    ) {
        let stored_first = self.store_mesh(mesh, transform, material_of);
        self.push_instance(stored_first, mesh.triangles.len() as u32, None);
    }

    /// Appends a mesh drawn in several places: stored once, in its own space, and drawn through
    /// each of `transforms` (see [`instance`]); otherwise as [`add_mesh`](Self::add_mesh). A
    /// transform that is not invertible (a node scaled to nothing) draws a flattened copy.
    ///
    /// # Panics
    /// As [`add_mesh`](Self::add_mesh).
    pub fn add_instanced_mesh(
        &mut self,
        mesh: &Mesh,
        transforms: &[Affine3A],
        mut material_of: impl FnMut(usize) -> u32,
    ) {
        let placements: Vec<Option<Placement>> =
            transforms.iter().map(|&t| Placement::new(t)).collect();
        let count = mesh.triangles.len() as u32;
        let stored = placements
            .iter()
            .any(Option::is_some)
            .then(|| self.store_mesh(mesh, &Affine3A::IDENTITY, &mut material_of));
        for (transform, placement) in transforms.iter().zip(placements) {
            match (placement, stored) {
                (Some(placement), Some(first)) => self.push_instance(first, count, Some(placement)),
                // Flattened as the loaders flatten (a mirror keeps the front side outside).
                _ => {
                    let mut flat = Mesh { name: mesh.name.clone(), ..Mesh::default() };
                    flat.append_transformed(mesh, transform);
                    self.add_mesh(&flat, &Affine3A::IDENTITY, &mut material_of);
                }
            }
        }
    }

    fn push_instance(&mut self, stored_first: u32, count: u32, placement: Option<Placement>) {
        self.lines.forget();
        if count == 0 {
            return;
        }
        self.placed |= placement.is_some();
        let first = self.scene_triangles as u32;
        self.instances.push(Instance { first, stored_first, count, placement });
        self.scene_triangles += count as usize;
    }

    /// Stores a mesh's triangles through `transform`; returns its first stored triangle.
    fn store_mesh(
        &mut self,
        mesh: &Mesh,
        transform: &Affine3A,
        mut material_of: impl FnMut(usize) -> u32,
    ) -> u32 {
        self.lines.forget();
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
        first as u32
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

    /// The bytes its tables take (their lengths, not their spare capacity), the triangles'
    /// lines included once made.
    pub fn bytes(&self) -> u64 {
        use std::mem::size_of_val;
        let bytes = size_of_val(self.positions.as_slice())
            + size_of_val(self.triangles.as_slice())
            + size_of_val(self.normals.as_slice())
            + self.shading_normals.bytes()
            + self.uvs.bytes()
            + self.tangents.bytes()
            + size_of_val(self.material_ids.as_slice())
            + size_of_val(self.instances.as_slice())
            + self.lines.bytes();
        bytes as u64
    }

    /// The number of scene triangles (each instance's).
    #[inline]
    pub fn len(&self) -> usize {
        self.scene_triangles
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.scene_triangles == 0
    }

    /// The number of stored triangles: each mesh's once, however many places draw it.
    pub fn stored_len(&self) -> usize {
        self.triangles.len()
    }

    /// Where the scene's triangles come from, in order (see [`instance`]).
    pub fn instances(&self) -> &[Instance] {
        &self.instances
    }

    /// Whether some mesh is drawn through a placement (else scene triangle `i` is stored
    /// triangle `i`, in world space).
    pub fn is_instanced(&self) -> bool {
        self.placed
    }

    /// Scene triangle `i`'s stored triangle and the placement that draws it.
    #[inline]
    fn locate(&self, i: usize) -> (usize, Option<&Placement>) {
        if !self.placed {
            return (i, None);
        }
        let k = self.instances.partition_point(|x| x.first as usize <= i) - 1;
        let instance = &self.instances[k];
        (
            instance.stored_first as usize + (i - instance.first as usize),
            instance.placement.as_ref(),
        )
    }

    /// The three corners of stored triangle `s`, in its own space.
    #[inline(always)]
    pub fn stored_triangle(&self, s: usize) -> [Vec3; 3] {
        // Written out: `array::map` here compiles to a loop through `try_from_fn` that is not
        // inlined into the lab's tile shading.
        let [a, b, c] = self.triangles[s];
        [self.positions[a as usize], self.positions[b as usize], self.positions[c as usize]]
    }

    /// Scene triangle `i`'s world corners, geometric normal and material where the geometry is
    /// not instanced (scene triangle `i` is stored triangle `i`): what [`triangle`](Self::triangle),
    /// [`normal`](Self::normal) and [`material_id`](Self::material_id) give, without locating
    /// an instance three times. `None` when some mesh is instanced.
    #[inline(always)]
    pub(crate) fn flat_triangle(&self, i: usize) -> Option<([Vec3; 3], Vec3, u32)> {
        // An `if`, not `bool::then`: its closure was not inlined into the lab's AVX2 loop.
        if self.placed {
            return None;
        }
        Some((self.stored_triangle(i), self.normals[i], self.material_ids[i]))
    }

    /// Where the geometry is not instanced and has at most 2^20 triangles, each triangle's
    /// corners, normal and material in one cache line ([`TriangleLine`]), scene triangle `i`
    /// at `i`: made on first use (64 bytes per triangle) and kept until the geometry changes.
    pub(crate) fn triangle_lines(&self) -> Option<&[TriangleLine]> {
        if self.placed || self.triangles.len() > MOST_LINES {
            return None;
        }
        Some(self.lines.get_or_make(|| {
            (0..self.triangles.len())
                .map(|i| {
                    TriangleLine::new(
                        self.stored_triangle(i),
                        self.normals[i],
                        self.material_ids[i],
                    )
                })
                .collect()
        }))
    }

    /// The three world corners of scene triangle `i`.
    #[inline]
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        let (s, placement) = self.locate(i);
        let corners = self.stored_triangle(s);
        placement.map_or(corners, |p| p.triangle(corners))
    }

    /// Values at stored triangle `s`'s corners, in the order of the scene triangle `placement`
    /// draws.
    #[inline]
    fn corner_values<T: Copy>(
        table: &CornerTable<T>,
        s: usize,
        placement: Option<&Placement>,
    ) -> Option<[T; 3]> {
        let values = table.get(s)?;
        Some(placement.map_or(values, |p| p.corners(values)))
    }

    /// Every triangle's corners, in order: what accelerators are built from.
    pub fn vertices(&self) -> Vec<[Vec3; 3]> {
        (0..self.len()).map(|i| self.triangle(i)).collect()
    }

    /// The unit geometric normal of scene triangle `i` (zero for a zero-area triangle).
    #[inline]
    pub fn normal(&self, i: usize) -> Vec3 {
        match self.locate(i) {
            (s, None) => self.normals[s],
            (s, Some(p)) => geometric_normal(p.triangle(self.stored_triangle(s))),
        }
    }

    /// The material of scene triangle `i`.
    #[inline]
    pub fn material_id(&self, i: usize) -> u32 {
        self.material_ids[self.locate(i).0]
    }

    /// Every stored triangle's material, in order (every place that draws a mesh shares them).
    pub fn material_ids(&self) -> &[u32] {
        &self.material_ids
    }

    /// Sets the material of every stored triangle (for scenes that restyle loaded meshes).
    pub fn material_ids_mut(&mut self) -> &mut [u32] {
        self.lines.forget();
        &mut self.material_ids
    }

    /// The area of triangle `i`.
    pub fn area(&self, i: usize) -> f32 {
        let [v0, v1, v2] = self.triangle(i);
        0.5 * (v1 - v0).cross(v2 - v0).length()
    }

    /// The stored meshes, in the order they were added.
    pub fn meshes(&self) -> &[MeshRange] {
        &self.meshes
    }

    /// The mesh that scene triangle `i` belongs to.
    pub fn mesh_of(&self, i: u32) -> Option<&MeshRange> {
        if i as usize >= self.len() {
            return None;
        }
        let s = self.locate(i as usize).0 as u32;
        let index = self.meshes.partition_point(|m| m.first + m.count <= s);
        self.meshes.get(index)
    }

    /// The stored vertex positions (some may be unused), an instanced mesh's in its own space.
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// The same geometry scaled by `factor` about the origin, instances included.
    pub fn scaled(&self, factor: f32) -> Geometry {
        let mut geometry = self.map_positions(|p| p * factor);
        for instance in &mut geometry.instances {
            instance.placement = instance.placement.map(|p| p.scaled(factor));
        }
        geometry
    }

    /// The same geometry with every stored position moved by `f` (normals recomputed); an
    /// instanced mesh's positions are in its own space.
    pub fn map_positions(&self, f: impl Fn(Vec3) -> Vec3) -> Geometry {
        // (A clone starts without the triangles' lines.)
        let mut geometry = self.clone();
        for p in &mut geometry.positions {
            *p = f(*p);
        }
        for (i, n) in geometry.normals.iter_mut().enumerate() {
            *n = geometric_normal(self.triangles[i].map(|v| geometry.positions[v as usize]));
        }
        geometry
    }

    /// The bounding box `(min, max)` of every scene triangle's corners, or `None` without
    /// triangles.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        if self.placed {
            return crate::mesh::bounds_of((0..self.len()).flat_map(|i| self.triangle(i)));
        }
        crate::mesh::bounds_of(self.triangles.iter().flatten().map(|&v| self.positions[v as usize]))
    }
}

/// Texture coordinates of a triangle that has none: its barycentric `(b1, b2)`.
const DEFAULT_UVS: [Vec2; 3] = [Vec2::ZERO, Vec2::X, Vec2::Y];

#[cfg(test)]
mod tests;
