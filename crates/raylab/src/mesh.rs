//! Triangle meshes as loaded from files: positions, triangles in file order, optional normals and
//! texture coordinates, and materials.
//!
//! Every loader (`scene::obj`, `scene::ply`) produces a [`Mesh`]. Triangles keep the order of the
//! file, polygons fan-triangulated as `(p0, pk, pk+1)`, so that triangle `i` of a mesh is triangle
//! `i` of any other tool that follows the same convention (the ray-set benchmark's primitive ids
//! depend on it). Real meshes are dirty: zero-area triangles and unused vertices are kept as they
//! are; ray queries never hit a zero-area triangle, and [`Mesh::bounds`] ignores unused vertices.

use glam::{Vec2, Vec3, Vec4};

use crate::material::MaterialTextures;

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

impl<T> CornerAttribute<T> {
    /// One value per vertex: each corner's index is its vertex's (as PLY and glTF store them).
    pub fn per_vertex(values: Vec<T>, triangles: &[[u32; 3]]) -> CornerAttribute<T> {
        CornerAttribute { values, triangles: triangles.to_vec() }
    }
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
    /// Textures (`map_Kd`, glTF's `baseColorTexture` and `metallicRoughnessTexture`).
    pub textures: MaterialTextures,
    /// glTF's metallic-roughness parameters; `None` (OBJ, PLY) for a diffuse surface.
    pub pbr: Option<PbrParameters>,
}

/// glTF's metallic-roughness parameters (the base colour is [`MeshMaterial::diffuse`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PbrParameters {
    /// `metallicFactor`, in `[0, 1]`.
    pub metallic: f32,
    /// `roughnessFactor`, in `[0, 1]`.
    pub roughness: f32,
    /// `KHR_materials_transmission`'s factor: above ½ the surface is glass.
    pub transmission: f32,
    /// `KHR_materials_ior` (1.5 unless it says otherwise).
    pub ior: f32,
}

impl MeshMaterial {
    /// The colour of surfaces that name no material: a neutral grey of reflectance 0.75.
    pub const DEFAULT_DIFFUSE: Vec3 = Vec3::splat(0.75);
}

/// A mesh a model draws in several places: its triangles once, in its own space, and where
/// each copy goes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct InstancedMesh {
    /// The triangles in the mesh's own space. Its material ids index the loaded mesh's
    /// materials (`LoadedMesh::mesh`); its own `materials` are empty.
    pub mesh: Mesh,
    /// Each copy's transform, from the mesh's space into the model's.
    pub transforms: Vec<glam::Affine3A>,
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
    /// Tangents for normal maps (xyz, and in w the sign of the bitangent `w · n × t`), from the
    /// file (glTF's TANGENT) or [`generate_tangents`](Self::generate_tangents).
    pub tangents: Option<CornerAttribute<Vec4>>,
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

    /// Appends `other`'s triangles moved by `transform`, with their materials (indices into
    /// the same table) and corner attributes (normals and tangents turned with the transform);
    /// a side that lacks an attribute the other has gets zeros (zero normals and tangents are
    /// "none"). A mirroring transform turns the corners so that the front side stays outside.
    pub fn append_transformed(&mut self, other: &Mesh, transform: &glam::Affine3A) {
        let mirrored = transform.matrix3.determinant() < 0.0;
        let turn = |[a, b, c]: [u32; 3]| if mirrored { [a, c, b] } else { [a, b, c] };
        let before = self.triangles.len();
        let base = self.positions.len() as u32;
        self.positions.extend(other.positions.iter().map(|&p| transform.transform_point3(p)));
        self.triangles.extend(other.triangles.iter().map(|&t| turn(t).map(|v| base + v)));
        if !(self.material_ids.is_empty() && other.material_ids.is_empty()) {
            self.material_ids.resize(before, None);
            self.material_ids.extend(
                (0..other.triangles.len()).map(|i| other.material_ids.get(i).copied().flatten()),
            );
        }
        let span = (before, self.triangles.len());
        let normal_matrix = glam::Mat3::from(transform.matrix3).inverse().transpose();
        append_corners(&mut self.normals, other.normals.as_ref(), span, turn, |n| {
            (normal_matrix * n).normalize_or_zero()
        });
        append_corners(&mut self.uvs, other.uvs.as_ref(), span, turn, |uv| uv);
        let sign = if mirrored { -1.0 } else { 1.0 };
        append_corners(&mut self.tangents, other.tangents.as_ref(), span, turn, |t: Vec4| {
            (transform.matrix3 * t.truncate()).normalize_or_zero().extend(t.w * sign)
        });
    }

    /// The bounding box `(min, max)` of the vertices that some triangle uses, or `None` for a
    /// mesh without triangles.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        bounds_of(self.triangles.iter().flatten().map(|&v| self.positions[v as usize]))
    }

    /// Generates tangents as MikkTSpace defines them (Mikkelsen 2008, the convention glTF's
    /// normal maps are baked in): at each corner the direction of `∂p/∂u` made perpendicular to
    /// the normal, averaged (weighted by the corner's angle) over the corners that share a
    /// position, normal, texture coordinate and handedness, with `w` the sign that makes
    /// `w · n × t` point along `∂p/∂v`. Corners whose triangles have no texture area get a
    /// tangent perpendicular to the normal. Returns `false`, leaving the mesh as it was, without
    /// texture coordinates.
    ///
    /// Not the `mikktspace` crate: fuzzing found it reading out of bounds on degenerate
    /// triangles. The results agree with it on smooth, well-mapped meshes, not bit for bit.
    pub fn generate_tangents(&mut self) -> bool {
        let Some(uvs) = &self.uvs else { return false };
        let normal_at = |f: usize, c: usize| {
            let given =
                self.normals.as_ref().map_or(Vec3::ZERO, |n| n.values[n.triangles[f][c] as usize]);
            if given == Vec3::ZERO || !given.is_finite() {
                crate::triangle::geometric_normal(self.triangle(f))
            } else {
                given.normalize_or_zero()
            }
        };
        // The corners that share a vertex: position, normal, texture coordinate and handedness.
        type Key = (u32, [u32; 3], [u32; 2], bool);
        let mut sums: std::collections::HashMap<Key, (Vec3, Vec3)> = Default::default();
        let mut keys = Vec::with_capacity(self.triangles.len());
        for (f, t) in self.triangles.iter().enumerate() {
            let p = t.map(|v| self.positions[v as usize]);
            let uv = uvs.triangles[f].map(|k| uvs.values[k as usize]);
            let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
            let (d1, d2) = (uv[1] - uv[0], uv[2] - uv[0]);
            let r = d1.x * d2.y - d2.x * d1.y;
            // ∂p/∂u and ∂p/∂v of the triangle (zero where the mapping is degenerate).
            let (s, tv) = if r != 0.0 && r.is_finite() {
                ((e1 * d2.y - e2 * d1.y) / r, (e2 * d1.x - e1 * d2.x) / r)
            } else {
                (Vec3::ZERO, Vec3::ZERO)
            };
            let (s, tv) =
                if s.is_finite() && tv.is_finite() { (s, tv) } else { (Vec3::ZERO, Vec3::ZERO) };
            let corner_keys: [Key; 3] = std::array::from_fn(|c| {
                let n = normal_at(f, c).to_array().map(f32::to_bits);
                (t[c], n, uv[c].to_array().map(f32::to_bits), r < 0.0)
            });
            for c in 0..3 {
                let (a, b) = (p[(c + 1) % 3] - p[c], p[(c + 2) % 3] - p[c]);
                let angle = a.angle_between(b);
                let angle = if angle.is_finite() { angle } else { 0.0 };
                let sum = sums.entry(corner_keys[c]).or_default();
                sum.0 += s * angle;
                sum.1 += tv * angle;
            }
            keys.push(corner_keys);
        }
        let values: Vec<Vec4> = keys
            .iter()
            .enumerate()
            .flat_map(|(f, corner_keys)| {
                let sums = &sums;
                (0..3).map(move |c| (f, c, sums[&corner_keys[c]]))
            })
            .map(|(f, c, (s, tv))| {
                let n = normal_at(f, c);
                let t = (s - n * n.dot(s)).normalize_or_zero();
                if t == Vec3::ZERO || !t.is_finite() {
                    let (t, _) = crate::sampling::orthonormal_basis(n);
                    return t.extend(1.0);
                }
                let sign = if n.cross(t).dot(tv) < 0.0 { -1.0 } else { 1.0 };
                t.extend(sign)
            })
            .collect();
        let triangles =
            (0..self.triangles.len() as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
        self.tangents = Some(CornerAttribute { values, triangles });
        true
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

/// Appends the corner values `other` has for the triangles `before..after` just appended
/// (zeros where it has none but `own` has some), mapping each value by `map` and each
/// triangle's corners by `turn`.
fn append_corners<T: Copy + Default>(
    own: &mut Option<CornerAttribute<T>>,
    other: Option<&CornerAttribute<T>>,
    (before, after): (usize, usize),
    turn: impl Fn([u32; 3]) -> [u32; 3],
    map: impl Fn(T) -> T,
) {
    if own.is_none() && other.is_none() {
        return;
    }
    let own = own.get_or_insert_with(CornerAttribute::default);
    let pad = |own: &mut CornerAttribute<T>, until: usize| {
        if own.triangles.len() < until {
            let zero = own.values.len() as u32;
            own.values.push(T::default());
            own.triangles.resize(until, [zero; 3]);
        }
    };
    pad(own, before);
    if let Some(other) = other {
        let base = own.values.len() as u32;
        own.values.extend(other.values.iter().map(|&v| map(v)));
        own.triangles.extend(other.triangles.iter().map(|&t| turn(t).map(|k| base + k)));
    }
    pad(own, after);
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

    /// A unit square in z = 0 (normal +z) with texture coordinates `uv(x, y)` at its corners.
    fn square(uv: impl Fn(f32, f32) -> Vec2) -> Mesh {
        let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)];
        let triangles = vec![[0, 1, 2], [2, 1, 3]];
        Mesh {
            positions: corners.iter().map(|&(x, y)| Vec3::new(x, y, 0.0)).collect(),
            uvs: Some(CornerAttribute {
                values: corners.iter().map(|&(x, y)| uv(x, y)).collect(),
                triangles: triangles.clone(),
            }),
            triangles,
            ..Mesh::default()
        }
    }

    #[test]
    fn tangents_follow_u_and_their_sign_follows_v() {
        // (tangent, sign) expected for each mapping: the tangent along ∂p/∂u, and the sign
        // that makes w · n × t point along ∂p/∂v (n = +z: n × x = +y).
        type Mapping = dyn Fn(f32, f32) -> Vec2;
        let cases: [(&Mapping, Vec3, f32); 4] = [
            (&|x, y| Vec2::new(x, y), Vec3::X, 1.0),
            (&|x, y| Vec2::new(x, -y), Vec3::X, -1.0),
            (&|x, y| Vec2::new(-x, y), Vec3::NEG_X, -1.0),
            (&|x, y| Vec2::new(y, -x), Vec3::Y, 1.0),
        ];
        for (i, (uv, tangent, sign)) in cases.into_iter().enumerate() {
            let mut mesh = square(uv);
            assert!(mesh.generate_tangents());
            for t in &mesh.tangents.as_ref().unwrap().values {
                assert!(t.truncate().abs_diff_eq(tangent, 1e-6) && t.w == sign, "case {i}: {t}");
            }
        }
    }

    #[test]
    fn degenerate_triangles_get_finite_tangents() {
        // Repeated corners, no texture area, NaN texture coordinates: unit tangents, no panic.
        let mut mesh = square(|_, _| Vec2::ZERO);
        mesh.triangles.push([0, 0, 1]);
        mesh.uvs.as_mut().unwrap().triangles.push([0, 1, 2]);
        mesh.uvs.as_mut().unwrap().values[3] = Vec2::NAN;
        assert!(mesh.generate_tangents());
        let tangents = mesh.tangents.unwrap();
        assert_eq!(tangents.triangles.len(), 3);
        for t in tangents.values {
            assert!(t.is_finite() && (t.truncate().length() - 1.0).abs() < 1e-5, "{t}");
        }
        assert!(!Mesh::default().generate_tangents(), "no texture coordinates");
    }

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
