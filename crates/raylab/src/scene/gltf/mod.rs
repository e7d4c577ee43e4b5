//! glTF 2.0 (`.gltf` with external or embedded buffers, and `.glb`) via the `gltf` crate.
//!
//! The default scene's node hierarchy is walked. A mesh that one node uses is added with the
//! node's world transform; a mesh that several nodes use is kept once, in its own space, with
//! each node's transform ([`InstancedMesh`]: instancing, under a two-level BVH). Triangles keep
//! the file's order (nodes depth first, then primitives), positions and normals are
//! transformed (normals by the inverse transpose), and a transform that mirrors reverses the
//! winding, so that front faces stay front faces. Each primitive's material gives a
//! [`MeshMaterial`](crate::mesh::MeshMaterial): the metallic-roughness material's base colour factor as the diffuse
//! colour, the emissive factor (times `KHR_materials_emissive_strength`) as emission, and
//! their textures (base colour, metallic-roughness, normal, emissive). The first perspective
//! camera, in node order, becomes the scene's camera, and `KHR_lights_punctual` lights become
//! point, spot and directional lights (`punctual_light`).
//!
//! Mistakes are one line naming the file and the part: a primitive that is not triangles
//! (points, lines, strips are refused, not guessed at), an accessor whose data lies outside its
//! buffer, an index beyond the vertices, a missing buffer file, a truncated `.glb`.

mod material;

use std::collections::HashMap;
use std::f32::consts::PI;
use std::path::Path;

use glam::{Affine3A, Mat3, Mat4, Vec2, Vec3, Vec4};

use super::mesh_file::{InstancedMesh, LoadError, LoadedMesh, mesh_name};
use super::{CameraSettings, FovAxis, model_to_lab};
use crate::light::{DirectionalLight, Light, PointLight, SpotLight, SpotProfile};
use crate::mesh::{CornerAttribute, Mesh};
use material::Images;

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
    // Images the `gltf` crate's `Image::source` would unwrap on (found by fuzzing): a buffer
    // view without a MIME type, or neither a buffer view nor a URI.
    let mut broken_images = HashMap::new();
    for (i, image) in root.images.iter().enumerate() {
        let problem = match (&image.buffer_view, &image.uri, &image.mime_type) {
            (Some(view), _, _) if view.value() >= root.buffer_views.len() => {
                Some(format!("image {i}: buffer view {} does not exist", view.value()))
            }
            (Some(_), _, None) => Some(format!("image {i}: a buffer view without a mimeType")),
            (None, None, _) => Some(format!("image {i}: neither a uri nor a buffer view")),
            _ => None,
        };
        if let Some(problem) = problem {
            broken_images.insert(i, problem);
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
    let mut warnings = Vec::new();
    let mut images = Images::new(folder, &buffers, broken_images);
    builder.mesh.materials = material::read_materials(&mut images, document, path, &mut warnings);
    let mut lights = Vec::new();
    // Each node that draws a mesh: the mesh and the node's world transform.
    let mut draws: Vec<(gltf::Mesh, Mat4)> = Vec::new();
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
        if let Some(light) = node.light() {
            let place = format!("node {}: light {}", node.index(), light.index());
            lights.push(
                punctual_light(&light, &world).map_err(|p| invalid(format!("{place}: {p}")))?,
            );
        }
        if let Some(mesh) = node.mesh() {
            draws.push((mesh, world));
        }
        let children: Vec<_> = node.children().map(|c| (c, world)).collect();
        stack.extend(children.into_iter().rev());
    }
    // A mesh that several nodes draw is stored once, in its own space, with each node's
    // transform (instancing); one drawn once is placed into the model's space.
    let mut uses: HashMap<usize, usize> = HashMap::new();
    for (mesh, _) in &draws {
        *uses.entry(mesh.index()).or_default() += 1;
    }
    let add = |builder: &mut Builder, mesh: &gltf::Mesh, world: &Mat4| {
        for primitive in mesh.primitives() {
            let place = format!("mesh {} primitive {}", mesh.index(), primitive.index());
            builder
                .add(&primitive, &buffers, world)
                .map_err(|problem| invalid(format!("{place}: {problem}")))?;
        }
        Ok::<(), LoadError>(())
    };
    let mut instanced: Vec<(usize, InstancedMesh)> = Vec::new();
    for (mesh, world) in &draws {
        if uses[&mesh.index()] == 1 {
            add(&mut builder, mesh, world)?;
            continue;
        }
        let transform = Affine3A::from_mat4(*world);
        if let Some((_, part)) = instanced.iter_mut().find(|(i, _)| *i == mesh.index()) {
            part.transforms.push(transform);
            continue;
        }
        let mut part = Builder::default();
        part.mesh.name =
            mesh.name().map_or_else(|| format!("mesh {}", mesh.index()), str::to_string);
        add(&mut part, mesh, &Mat4::IDENTITY)?;
        let mesh_of_part = part.finish().0;
        instanced.push((
            mesh.index(),
            InstancedMesh { mesh: mesh_of_part, transforms: vec![transform] },
        ));
    }
    let (mut mesh, camera) = builder.finish();
    // Normal maps need tangents: MikkTSpace's, as glTF asks, where the file gives none.
    let mapped = mesh.materials.iter().any(|m| m.textures.normal.is_some());
    let mut instanced: Vec<InstancedMesh> = instanced.into_iter().map(|(_, part)| part).collect();
    let meshes = std::iter::once(&mut mesh).chain(instanced.iter_mut().map(|part| &mut part.mesh));
    let untangled = meshes
        .filter(|m| mapped && !m.triangles.is_empty())
        .map(|m| !complete_tangents(m))
        .fold(false, |any, failed| any | failed);
    if untangled {
        warnings.push(format!(
            "{}: normal maps are ignored: no tangents could be made (the mesh needs texture \
             coordinates)",
            path.display()
        ));
    }
    Ok(LoadedMesh { mesh, instanced, warnings, camera, lights })
}

/// A `KHR_lights_punctual` light placed by its node's `world` transform, in the lab's frame.
/// Colours times intensities: a point or spot light's in candela (lm/sr, read as W/sr: a point
/// light of power P radiates P/(4π) per steradian), a directional light's in lux (lm/m², read
/// as W/m²). Spot and directional lights shine along the node's −z; a spot's cone falls off as
/// the extension recommends between its inner and outer angles ([`SpotProfile::Gltf`]).
/// `range` is ignored, as the extension allows.
fn punctual_light(light: &gltf::khr_lights_punctual::Light, world: &Mat4) -> Result<Light, String> {
    use gltf::khr_lights_punctual::Kind;
    let colour = Vec3::from_array(light.color()) * light.intensity();
    if !(colour.is_finite() && colour.min_element() >= 0.0) {
        return Err(format!("its colour times intensity {colour} must be finite and not negative"));
    }
    let position = model_to_lab(world.transform_point3(Vec3::ZERO));
    if !position.is_finite() {
        return Err(format!("its node places it at {position}, not a finite point"));
    }
    let axis = model_to_lab(world.transform_vector3(-Vec3::Z));
    match light.kind() {
        Kind::Point => Ok(Light::Point(PointLight { position, power: 4.0 * PI * colour })),
        Kind::Spot { inner_cone_angle, outer_cone_angle } => {
            SpotLight::new(position, axis, colour, outer_cone_angle, inner_cone_angle, SpotProfile::Gltf)
                .map(Light::Spot).ok_or_else(|| {
                    format!(
                        "a spot light needs 0 ≤ innerConeAngle ≤ outerConeAngle ≤ π and a node \
                         that does not flatten its −z (here {inner_cone_angle} and {outer_cone_angle})"
                    )
                })
        }
        Kind::Directional => match axis.try_normalize() {
            Some(direction) => Ok(Light::Directional(DirectionalLight { direction, irradiance: colour })),
            None => Err("a directional light's node flattens its −z".into()),
        },
    }
}

/// Gives every triangle of `mesh` that has no tangents (no TANGENT in its primitive) generated
/// ones, in glTF's convention; returns `false` if some need them and none can be made (no
/// texture coordinates).
///
/// [`Mesh::generate_tangents`] follows MikkTSpace on the coordinates as given, its bitangent
/// `w · n × t` along `∂p/∂v`. glTF's texture space runs `v` down the image while its normal
/// maps' green channel points up it (the Khronos sample viewer's bitangent is `n × t` with `t`
/// along `∂p/∂u`: along `−∂p/∂v`), so the sign is turned.
fn complete_tangents(mesh: &mut Mesh) -> bool {
    let missing = |t: &CornerAttribute<Vec4>, i: usize| {
        t.triangles[i].iter().all(|&k| t.values[k as usize].truncate() == Vec3::ZERO)
    };
    let given = mesh.tangents.take();
    if given.as_ref().is_some_and(|t| (0..t.triangles.len()).all(|i| !missing(t, i))) {
        mesh.tangents = given;
        return true;
    }
    if !mesh.generate_tangents() {
        mesh.tangents = given;
        return false;
    }
    let generated = mesh.tangents.take().expect("generated");
    let flip = |t: Vec4| Vec4::new(t.x, t.y, t.z, -t.w);
    let Some(mut given) = given else {
        let values = generated.values.into_iter().map(flip).collect();
        mesh.tangents = Some(CornerAttribute { values, triangles: generated.triangles });
        return true;
    };
    for i in 0..given.triangles.len() {
        if missing(&given, i) {
            let base = given.values.len() as u32;
            given.values.extend(generated.triangles[i].map(|k| flip(generated.values[k as usize])));
            given.triangles[i] = [base, base + 1, base + 2];
        }
    }
    mesh.tangents = Some(given);
    true
}

/// Checks what the `gltf` crate's readers take for granted (and panic on otherwise, found by
/// fuzzing): each attribute read has the type and component types the specification gives it,
/// and its buffer view's stride is no shorter than one element.
fn check_accessors(primitive: &gltf::Primitive) -> Result<(), String> {
    use gltf::accessor::{DataType as T, Dimensions as D};
    let float = &[T::F32][..];
    let expected: [(gltf::Semantic, D, &[T]); 4] = [
        (gltf::Semantic::Positions, D::Vec3, float),
        (gltf::Semantic::Normals, D::Vec3, float),
        (gltf::Semantic::Tangents, D::Vec4, float),
        (gltf::Semantic::TexCoords(0), D::Vec2, &[T::F32, T::U8, T::U16]),
    ];
    let used = expected
        .iter()
        .filter_map(|(semantic, d, t)| {
            Some((format!("{semantic:?}"), primitive.get(semantic)?, *d, *t))
        })
        .chain(
            primitive
                .indices()
                .map(|a| ("indices".to_string(), a, D::Scalar, &[T::U8, T::U16, T::U32][..])),
        );
    for (name, accessor, dimensions, types) in used {
        if accessor.dimensions() != dimensions || !types.contains(&accessor.data_type()) {
            return Err(format!(
                "{name}: accessor {} is {:?} of {:?}, not {dimensions:?} of {types:?}",
                accessor.index(),
                accessor.dimensions(),
                accessor.data_type()
            ));
        }
        if let Some(stride) = accessor.view().and_then(|v| v.stride())
            && stride < accessor.size()
        {
            return Err(format!(
                "{name}: accessor {}'s buffer view has a stride of {stride} bytes, shorter than \
                 its {}-byte elements",
                accessor.index(),
                accessor.size()
            ));
        }
    }
    Ok(())
}

/// One line from a `gltf` error (its messages can span lines).
fn describe(error: gltf::Error) -> String {
    error.to_string().lines().next().unwrap_or("invalid glTF").to_string()
}

#[derive(Default)]
struct Builder {
    mesh: Mesh,
    normals: CornerAttribute<Vec3>,
    tangents: CornerAttribute<Vec4>,
    has_tangents: bool,
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
        check_accessors(primitive)?;
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
        let tangents: Option<Vec<Vec4>> = match primitive.get(&gltf::Semantic::Tangents) {
            None => None,
            Some(_) => Some(
                reader
                    .read_tangents()
                    .ok_or_else(|| outside("TANGENT"))?
                    .map(Vec4::from_array)
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
        match tangents {
            Some(tangents) if tangents.len() == count => {
                self.fill_missing_tangents(first_triangle);
                let start = self.tangents.values.len() as u32;
                // In the surface: they turn with the node; a mirror flips the bitangent's side.
                let linear = Mat3::from_mat4(*world);
                let sign = if mirrored { -1.0 } else { 1.0 };
                self.tangents.values.extend(tangents.iter().map(|t| {
                    (linear * t.truncate()).normalize_or_zero().extend(t.w.signum() * sign)
                }));
                self.tangents.triangles.extend(local.iter().map(|t| t.map(|i| i + start)));
                self.has_tangents = true;
            }
            Some(tangents) => {
                return Err(format!("TANGENT has {} values for {count} vertices", tangents.len()));
            }
            None if self.has_tangents => self.fill_missing_tangents(self.mesh.triangles.len()),
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
        if self.has_tangents {
            self.fill_missing_tangents(n);
            self.mesh.tangents = Some(std::mem::take(&mut self.tangents));
        }
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

    /// Gives every triangle before `until` that has no tangents a zero tangent (none).
    fn fill_missing_tangents(&mut self, until: usize) {
        if self.tangents.triangles.len() < until {
            let zero = self.tangents.values.len() as u32;
            self.tangents.values.push(Vec4::ZERO);
            self.tangents.triangles.resize(until, [zero; 3]);
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A primitive with TANGENT keeps the file's; one without (zeros) gets generated ones, in
    /// glTF's sign: the two halves of a quad mapped the same way end up alike.
    #[test]
    fn tangents_are_completed_where_a_primitive_has_none() {
        // u along +x, v down the image along −y: the bitangent runs along +y = z × x, w = 1.
        let given = Vec4::new(1.0, 0.0, 0.0, 1.0);
        let mut mesh = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            uvs: Some(CornerAttribute {
                values: vec![Vec2::new(0.0, 1.0), Vec2::ONE, Vec2::X, Vec2::ZERO],
                triangles: vec![[0, 1, 2], [0, 2, 3]],
            }),
            normals: Some(CornerAttribute { values: vec![Vec3::Z], triangles: vec![[0; 3]; 2] }),
            tangents: Some(CornerAttribute {
                values: vec![given, Vec4::ZERO],
                triangles: vec![[0; 3], [1; 3]],
            }),
            ..Mesh::default()
        };
        assert!(complete_tangents(&mut mesh));
        let t = mesh.tangents.unwrap();
        let corner = |i: usize, c: usize| t.values[t.triangles[i][c] as usize];
        for c in 0..3 {
            assert_eq!(corner(0, c), given, "the file's tangent is kept");
            assert!(corner(1, c).abs_diff_eq(given, 1e-6), "generated: {}", corner(1, c));
        }
        // Without texture coordinates nothing can be made.
        let mut bare = Mesh { uvs: None, tangents: None, ..quad_without_uvs() };
        assert!(!complete_tangents(&mut bare));
    }

    fn quad_without_uvs() -> Mesh {
        Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            triangles: vec![[0, 1, 2]],
            ..Mesh::default()
        }
    }
}
