//! glTF 2.0 (`.gltf` with external or embedded buffers, and `.glb`) via the `gltf` crate.
//!
//! The default scene's node hierarchy is walked and flattened: every mesh a node uses is added
//! with the node's world transform. Triangles keep the file's order (nodes depth first, then
//! primitives), positions and normals are transformed (normals by the inverse transpose), and a
//! transform that mirrors reverses the winding, so that front faces stay front faces. Each
//! primitive's material gives a [`MeshMaterial`]: the metallic-roughness material's base colour
//! factor as the diffuse colour, the emissive factor (times `KHR_materials_emissive_strength`)
//! as emission. The first perspective camera, in node order, becomes the scene's camera.
//!
//! Mistakes are one line naming the file and the part: a primitive that is not triangles
//! (points, lines, strips are refused, not guessed at), an accessor whose data lies outside its
//! buffer, an index beyond the vertices, a missing buffer file, a truncated `.glb`.

use std::path::Path;

use glam::{Mat3, Mat4, Vec2, Vec3};

use super::file::{LoadError, LoadedMesh, mesh_name};
use super::{CameraSettings, FovAxis, model_to_lab};
use crate::mesh::{CornerAttribute, Mesh, MeshMaterial};

/// Reads the glTF file `bytes`, found at `path` (external buffers are read beside it).
pub(crate) fn parse_gltf(path: &Path, bytes: &[u8]) -> Result<LoadedMesh, LoadError> {
    let invalid = |message: String| LoadError::Invalid { path: path.into(), message };
    // The `gltf` crate's own validation indexes the accessor a primitive's POSITION names
    // before checking that it exists (gltf-json 1.4, found by fuzzing): check that first.
    let unchecked =
        gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| invalid(describe(e)))?;
    let root = unchecked.document.as_json();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let used = primitive.attributes.values().chain(primitive.indices.iter());
            if let Some(bad) = used.map(|i| i.value()).find(|&i| i >= root.accessors.len()) {
                return Err(invalid(format!(
                    "mesh {m} primitive {p}: accessor {bad} does not exist (the file has {})",
                    root.accessors.len()
                )));
            }
        }
    }
    drop(unchecked);
    let gltf = gltf::Gltf::from_slice(bytes).map_err(|e| invalid(describe(e)))?;
    let folder = path.parent().unwrap_or(Path::new("."));
    let buffers = gltf::import_buffers(&gltf.document, Some(folder), gltf.blob.clone())
        .map_err(|e| invalid(describe(e)))?;
    let document = &gltf.document;
    let scene = document
        .default_scene()
        .or_else(|| document.scenes().next())
        .ok_or_else(|| invalid("no scene".into()))?;

    let mut builder = Builder::default();
    builder.mesh.name = mesh_name(path);
    builder.mesh.materials = document
        .materials()
        .map(|m| {
            let pbr = m.pbr_metallic_roughness();
            let [r, g, b, _] = pbr.base_color_factor();
            let strength = m.emissive_strength().unwrap_or(1.0);
            MeshMaterial {
                name: m
                    .name()
                    .map_or_else(|| format!("material {}", m.index().unwrap_or(0)), str::to_string),
                diffuse: Vec3::new(r, g, b),
                emission: Vec3::from_array(m.emissive_factor()) * strength,
            }
        })
        .collect();
    let mut stack: Vec<(gltf::Node, Mat4)> =
        scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect::<Vec<_>>();
    stack.reverse();
    let mut visited = 0usize;
    while let Some((node, parent)) = stack.pop() {
        visited += 1;
        if visited > 1 << 20 {
            return Err(invalid(
                "more than a million node visits: a cycle in the hierarchy?".into(),
            ));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if !world.is_finite() {
            return Err(invalid(format!("node {}: its transform is not finite", node.index())));
        }
        if let Some(camera) = node.camera()
            && builder.camera.is_none()
            && let gltf::camera::Projection::Perspective(p) = camera.projection()
        {
            builder.camera = Some(camera_settings(&world, p.yfov()));
        }
        if let Some(mesh) = node.mesh() {
            for primitive in mesh.primitives() {
                let place = format!("mesh {} primitive {}", mesh.index(), primitive.index());
                builder
                    .add(&primitive, &buffers, &world)
                    .map_err(|problem| invalid(format!("{place}: {problem}")))?;
            }
        }
        let children: Vec<_> = node.children().map(|c| (c, world)).collect();
        stack.extend(children.into_iter().rev());
    }
    let (mesh, camera) = builder.finish();
    Ok(LoadedMesh { mesh, warnings: Vec::new(), camera })
}

/// One line from a `gltf` error (its messages can span lines).
fn describe(error: gltf::Error) -> String {
    error.to_string().lines().next().unwrap_or("invalid glTF").to_string()
}

#[derive(Default)]
struct Builder {
    mesh: Mesh,
    normals: CornerAttribute<Vec3>,
    uvs: CornerAttribute<Vec2>,
    has_normals: bool,
    has_uvs: bool,
    camera: Option<CameraSettings>,
}

impl Builder {
    /// Adds a primitive's triangles with the node's world transform.
    fn add(
        &mut self,
        primitive: &gltf::Primitive,
        buffers: &[gltf::buffer::Data],
        world: &Mat4,
    ) -> Result<(), String> {
        if primitive.mode() != gltf::mesh::Mode::Triangles {
            return Err(format!("mode {:?}: only triangles are supported", primitive.mode()));
        }
        let reader = primitive.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
        let outside = |what: &str| format!("{what}: its accessor's data lies outside its buffer");
        let positions: Vec<Vec3> = reader
            .read_positions()
            .ok_or_else(|| {
                if primitive.get(&gltf::Semantic::Positions).is_none() {
                    "no POSITION attribute".to_string()
                } else {
                    outside("POSITION")
                }
            })?
            .map(Vec3::from_array)
            .collect();
        let count = positions.len();
        let indices: Vec<u32> = match primitive.indices() {
            None => (0..count as u32).collect(),
            Some(_) => {
                reader.read_indices().ok_or_else(|| outside("indices"))?.into_u32().collect()
            }
        };
        if !indices.len().is_multiple_of(3) {
            return Err(format!("{} indices, not a whole number of triangles", indices.len()));
        }
        if let Some(&bad) = indices.iter().find(|&&i| i as usize >= count) {
            return Err(format!("index {bad} beyond its {count} vertices"));
        }
        let normals: Option<Vec<Vec3>> = match primitive.get(&gltf::Semantic::Normals) {
            None => None,
            Some(_) => Some(
                reader
                    .read_normals()
                    .ok_or_else(|| outside("NORMAL"))?
                    .map(Vec3::from_array)
                    .collect(),
            ),
        };
        let uvs: Option<Vec<Vec2>> = match primitive.get(&gltf::Semantic::TexCoords(0)) {
            None => None,
            Some(_) => Some(
                reader
                    .read_tex_coords(0)
                    .ok_or_else(|| outside("TEXCOORD_0"))?
                    .into_f32()
                    .map(Vec2::from_array)
                    .collect(),
            ),
        };
        for (name, n) in
            [("NORMAL", normals.as_ref().map(Vec::len)), ("TEXCOORD_0", uvs.as_ref().map(Vec::len))]
        {
            if n.is_some_and(|n| n != count) {
                return Err(format!("{name} has {} values for {count} vertices", n.unwrap_or(0)));
            }
        }
        let base = self.mesh.positions.len() as u32;
        let mirrored = world.determinant() < 0.0;
        let normal_matrix = Mat3::from_mat4(*world).inverse().transpose();
        self.mesh.positions.extend(positions.iter().map(|&p| world.transform_point3(p)));
        let material = primitive.material().index().map(|i| i as u32);
        let first_triangle = self.mesh.triangles.len();
        // Each triangle's corners within the primitive.
        let local: Vec<[u32; 3]> = indices
            .chunks_exact(3)
            .map(|t| if mirrored { [t[0], t[2], t[1]] } else { [t[0], t[1], t[2]] })
            .collect();
        for corners in &local {
            self.mesh.triangles.push(corners.map(|i| base + i));
            self.mesh.material_ids.push(material);
        }
        // Corner attributes: per vertex here, indexed like the positions.
        let attribute_base = |values_len: usize| values_len as u32;
        match normals {
            Some(normals) => {
                self.fill_missing_normals(first_triangle);
                let start = attribute_base(self.normals.values.len());
                self.normals
                    .values
                    .extend(normals.iter().map(|&n| (normal_matrix * n).normalize_or_zero()));
                self.normals.triangles.extend(local.iter().map(|t| t.map(|i| i + start)));
                self.has_normals = true;
            }
            None if self.has_normals => self.fill_missing_normals(self.mesh.triangles.len()),
            None => {}
        }
        match uvs {
            Some(uvs) => {
                self.fill_missing_uvs(first_triangle);
                let start = attribute_base(self.uvs.values.len());
                self.uvs.values.extend(uvs);
                self.uvs.triangles.extend(local.iter().map(|t| t.map(|i| i + start)));
                self.has_uvs = true;
            }
            None if self.has_uvs => self.fill_missing_uvs(self.mesh.triangles.len()),
            None => {}
        }
        Ok(())
    }

    /// The mesh, its corner attributes complete.
    fn finish(mut self) -> (Mesh, Option<CameraSettings>) {
        let n = self.mesh.triangles.len();
        if self.has_normals {
            self.fill_missing_normals(n);
        }
        if self.has_uvs {
            self.fill_missing_uvs(n);
        }
        self.mesh.normals = self.has_normals.then_some(self.normals);
        self.mesh.uvs = self.has_uvs.then_some(self.uvs);
        (self.mesh, self.camera)
    }

    /// Gives every triangle before `until` that has no normals a zero normal (none).
    fn fill_missing_normals(&mut self, until: usize) {
        if self.normals.triangles.len() < until {
            let zero = self.normals.values.len() as u32;
            self.normals.values.push(Vec3::ZERO);
            self.normals.triangles.resize(until, [zero; 3]);
        }
    }

    /// Gives every triangle before `until` that has no texture coordinates (0, 0).
    fn fill_missing_uvs(&mut self, until: usize) {
        if self.uvs.triangles.len() < until {
            let zero = self.uvs.values.len() as u32;
            self.uvs.values.push(Vec2::ZERO);
            self.uvs.triangles.resize(until, [zero; 3]);
        }
    }
}

/// A glTF camera (looking along its −z, up its +y, in y-up model space) with the world
/// transform `world`, as a camera of the lab's frame; `yfov` is the vertical field of view.
fn camera_settings(world: &Mat4, yfov: f32) -> CameraSettings {
    let axis = |v: Vec3| model_to_lab(world.transform_vector3(v)).normalize();
    let rotation = Mat3::from_cols(axis(Vec3::X), -axis(Vec3::Y), axis(Vec3::NEG_Z));
    let (yaw, pitch, roll) = super::keyframes::yaw_pitch_roll(rotation);
    CameraSettings {
        position: model_to_lab(world.transform_point3(Vec3::ZERO)),
        yaw,
        pitch,
        roll,
        fov_deg: yfov.to_degrees(),
        fov_axis: FovAxis::Y,
        aperture_radius: 0.0,
        focus_distance: 1.0,
    }
}
