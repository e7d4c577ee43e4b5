//! Triangle meshes as loaded from files: positions, triangles in file order, optional normals and
//! texture coordinates, and materials.
//!
//! Every loader (`scene::obj`, `scene::ply`) produces a [`Mesh`]. Triangles keep the order of the
//! file, polygons fan-triangulated as `(p0, pk, pk+1)`, so that triangle `i` of a mesh is triangle
//! `i` of any other tool that follows the same convention (the ray-set benchmark's primitive ids
//! depend on it). Real meshes are dirty: zero-area triangles and unused vertices are kept as they
//! are; ray queries never hit a zero-area triangle, and [`Mesh::bounds`] ignores unused vertices.

use glam::{Vec2, Vec3};

/// A per-corner attribute (normals or texture coordinates) with its own index triples, as OBJ
/// stores them (`f v/vt/vn`). For formats with per-vertex attributes (PLY) the triples equal the
/// position triples.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CornerAttribute<T> {
    /// The distinct values.
    pub values: Vec<T>,
    /// For each triangle, the index into `values` of each of its three corners.
    pub triangles: Vec<[u32; 3]>,
}

/// A surface description from an MTL file (or a default).
#[derive(Clone, Debug, PartialEq)]
pub struct MeshMaterial {
    /// The name the file gives it.
    pub name: String,
    /// Diffuse reflectance (`Kd`).
    pub diffuse: Vec3,
    /// Emitted radiance (`Ke`); zero for surfaces that do not emit.
    pub emission: Vec3,
}

impl MeshMaterial {
    /// The colour of surfaces that name no material: a neutral grey of reflectance 0.75.
    pub const DEFAULT_DIFFUSE: Vec3 = Vec3::splat(0.75);
}

/// A triangle mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// A short name for messages, usually the file name.
    pub name: String,
    /// Vertex positions. Some may be unused.
    pub positions: Vec<Vec3>,
    /// Each triangle's three indices into `positions`, in file order.
    pub triangles: Vec<[u32; 3]>,
    /// Shading normals, if the file has them.
    pub normals: Option<CornerAttribute<Vec3>>,
    /// Texture coordinates, if the file has them.
    pub uvs: Option<CornerAttribute<Vec2>>,
    /// Each triangle's index into `materials`, or `None` where the file names no material.
    /// Empty when the file has no materials at all.
    pub material_ids: Vec<Option<u32>>,
    /// The materials the file defines, in the order it defines them.
    pub materials: Vec<MeshMaterial>,
}

impl Mesh {
    /// The three vertices of triangle `i`.
    #[inline]
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        self.triangles[i].map(|v| self.positions[v as usize])
    }

    /// Every triangle's vertices, in order.
    pub fn triangle_vertices(&self) -> impl ExactSizeIterator<Item = [Vec3; 3]> + '_ {
        self.triangles.iter().map(|t| t.map(|v| self.positions[v as usize]))
    }

    /// The bounding box `(min, max)` of the vertices that some triangle uses, or `None` for a
    /// mesh without triangles.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        bounds_of(self.triangles.iter().flatten().map(|&v| self.positions[v as usize]))
    }

    /// The material of triangle `i`, if it has one.
    pub fn material(&self, i: usize) -> Option<&MeshMaterial> {
        let id = (*self.material_ids.get(i)?)?;
        self.materials.get(id as usize)
    }

    /// The number of triangles with exactly zero area (all cross products zero).
    pub fn zero_area_triangles(&self) -> usize {
        self.triangle_vertices().filter(|&t| crate::triangle::is_degenerate(t)).count()
    }
}

/// The bounding box `(min, max)` of some points, or `None` for none.
pub fn bounds_of(points: impl IntoIterator<Item = Vec3>) -> Option<(Vec3, Vec3)> {
    let mut points = points.into_iter();
    let first = points.next()?;
    Some(points.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p))))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounds_ignore_unused_vertices() {
        let mesh = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::splat(100.0)],
            triangles: vec![[0, 1, 2]],
            ..Mesh::default()
        };
        assert_eq!(mesh.bounds(), Some((Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0))));
        assert_eq!(Mesh::default().bounds(), None);
    }

    #[test]
    fn zero_area_triangles_are_counted() {
        let mesh = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::X * 2.0],
            triangles: vec![[0, 1, 2], [0, 1, 3], [1, 1, 2]],
            ..Mesh::default()
        };
        assert_eq!(mesh.zero_area_triangles(), 2);
        assert_eq!(mesh.triangle(1), [Vec3::ZERO, Vec3::X, Vec3::X * 2.0]);
    }
}
