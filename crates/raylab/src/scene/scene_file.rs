//! Scene files: a small TOML format for camera, materials, shapes, lights and render settings
//! (the reference is `docs/scene-format.md`).
//!
//! Scene files are **y-up**, as Mitsuba, glTF and Blender are; the loader turns everything into
//! the lab's y-down frame with [`model_to_lab`](super::model_to_lab). Materials keep Mitsuba's
//! names and parameters. Every mistake is one line naming the file, the line and the column, and
//! what was expected.

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::{Affine3A, Vec3};
use serde::Deserialize;
use toml::Spanned;

use super::{CameraSettings, FovAxis, Keyframe, LoadOptions, LoadedMesh, RenderSettings, Scene};
use crate::camera::Camera;
use crate::filter::Filter;
use crate::geometry::Geometry;
use crate::material::Material;
use crate::mesh::Mesh;
use crate::sampling::SamplerKind;
use crate::settings::{IntegratorKind, MaxDepth};

/// The most bytes a scene file may have (it holds no geometry, only references to it).
const MAX_SCENE_FILE_BYTES: u64 = 16 << 20;

/// Loads a scene file; meshes it names are read relative to its folder, with the default
/// [`LoadOptions`] (so the small instanced meshes of a glTF file are copied into their places:
/// [`Instancing::Auto`](super::Instancing::Auto)).
pub fn load_scene_file(path: &Path) -> std::result::Result<Scene, SceneFileError> {
    load_scene_file_with(path, &LoadOptions::default())
}

/// Loads a scene file; meshes it names are read relative to its folder, as `options` say.
pub fn load_scene_file_with(
    path: &Path,
    options: &LoadOptions,
) -> std::result::Result<Scene, SceneFileError> {
    let whole = |message: String| SceneFileError { path: path.into(), line: 1, column: 1, message };
    let metadata = std::fs::metadata(path).map_err(|e| whole(format!("cannot read: {e}")))?;
    if metadata.len() > MAX_SCENE_FILE_BYTES {
        return Err(whole(format!("{} bytes is too large for a scene file", metadata.len())));
    }
    let text = std::fs::read_to_string(path).map_err(|e| whole(format!("cannot read: {e}")))?;
    parse_scene_with(&text, path, options)
}

/// Parses a scene file's text; `path` names it in messages and meshes are found beside it,
/// loaded with the default [`LoadOptions`] ([`Instancing::Auto`](super::Instancing::Auto)).
pub fn parse_scene(text: &str, path: &Path) -> std::result::Result<Scene, SceneFileError> {
    parse_scene_with(text, path, &LoadOptions::default())
}

/// Parses a scene file's text; `path` names it in messages and meshes are found beside it,
/// loaded as `options` say.
pub fn parse_scene_with(
    text: &str,
    path: &Path,
    options: &LoadOptions,
) -> std::result::Result<Scene, SceneFileError> {
    parse_scene_with_meshes(text, path, options, &BTreeMap::new())
}

/// [`parse_scene_with`], where a `mesh` shape whose `file` is a key of `meshes` takes that mesh
/// instead of reading a file: a scene made in a program (the Python package's `Scene`) whose
/// meshes are already in memory.
pub fn parse_scene_with_meshes(
    text: &str,
    path: &Path,
    options: &LoadOptions,
    meshes: &BTreeMap<String, LoadedMesh>,
) -> std::result::Result<Scene, SceneFileError> {
    let at = |span: Option<Range<usize>>, message: String| {
        let offset = span.map_or(0, |s| s.start).min(text.len());
        let before = &text[..offset];
        let line = before.matches('\n').count() + 1;
        let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        SceneFileError { path: path.into(), line, column, message }
    };
    if let Some((span, key, value)) = super::finite::first_non_finite(text) {
        return Err(at(Some(span), format!("{key} = {value} is not a finite number")));
    }
    let document: Document =
        toml::from_str(text).map_err(|e| at(e.span(), e.message().trim().replace('\n', " ")))?;
    let folder = path.parent().unwrap_or(Path::new("."));
    let builder = Builder {
        at: &at,
        folder,
        options,
        warnings: Default::default(),
        shared_meshes: Default::default(),
        in_memory: meshes,
    };
    builder.build(document, path)
}

// ---------------------------------------------------------------------------------------------
// The document, as written.

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Document {
    render: Option<Spanned<RenderDoc>>,
    camera: Option<Spanned<CameraDoc>>,
    keyframes: Option<Vec<Spanned<CameraDoc>>>,
    #[serde(default)]
    materials: BTreeMap<String, Spanned<MaterialDoc>>,
    #[serde(default)]
    shapes: Vec<Spanned<ShapeDoc>>,
    #[serde(default)]
    lights: Vec<Spanned<lights::LightDoc>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RenderDoc {
    size: Option<[u32; 2]>,
    spp: Option<u32>,
    max_depth: Option<i64>,
    seed: Option<u64>,
    integrator: Option<Spanned<String>>,
    sampler: Option<Spanned<String>>,
    filter: Option<Spanned<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraDoc {
    /// Only in `[[keyframes]]`: the frame the camera is for.
    frame: Option<u32>,
    position: [f32; 3],
    target: Option<[f32; 3]>,
    up: Option<Spanned<[f32; 3]>>,
    yaw: Option<f32>,
    pitch: Option<f32>,
    roll: Option<f32>,
    fov: Option<f32>,
    fov_axis: Option<Spanned<String>>,
    aperture_radius: Option<f32>,
    focus_distance: Option<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ShapeDoc {
    #[serde(rename = "type")]
    kind: Spanned<String>,
    /// For `mesh`: the file.
    file: Option<Spanned<String>>,
    /// The material; for meshes, `None` keeps the file's own (MTL) materials.
    material: Option<Spanned<String>>,
    /// Radiance emitted from the front side: makes the shape an area light.
    emission: Option<[f32; 3]>,
    /// A 4×4 matrix, row by row (Mitsuba's `to_world`), applied after the rest.
    to_world: Option<[[f32; 4]; 4]>,
    scale: Option<Spanned<toml::Value>>,
    rotate: Option<RotateDoc>,
    translate: Option<[f32; 3]>,
    /// For `sphere`.
    center: Option<[f32; 3]>,
    radius: Option<f32>,
}

// ---------------------------------------------------------------------------------------------
// Building the scene.

impl<F: Fn(Option<Range<usize>>, String) -> SceneFileError> Builder<'_, F> {
    fn build(&self, document: Document, path: &Path) -> Result<Scene> {
        let name = path.file_name().map_or("scene".into(), |n| n.to_string_lossy().into_owned());
        let mut scene = Scene { name, ..Scene::default() };
        let mut material_index = BTreeMap::new();
        for (name, doc) in &document.materials {
            let material = self.material(name, doc.get_ref(), doc.span())?;
            material_index.insert(name.clone(), scene.materials.len() as u32);
            scene.materials.push(material);
        }
        let mut uses = BTreeMap::<PathBuf, usize>::new();
        let mesh_files = document.shapes.iter().map(|shape| shape.get_ref());
        let mesh_files = mesh_files.filter(|shape| shape.kind.get_ref() == "mesh");
        for file in mesh_files.filter_map(|shape| shape.file.as_ref()) {
            *uses.entry(self.folder.join(file.get_ref())).or_default() += 1;
        }
        *self.shared_meshes.borrow_mut() =
            uses.into_iter().filter(|&(_, n)| n > 1).map(|(path, n)| (path, (n, None))).collect();
        let mut geometry = Geometry::new();
        for shape in &document.shapes {
            self.shape(shape, &mut scene.materials, &material_index, &mut geometry)?;
        }
        scene.geometry = geometry;
        for light in &document.lights {
            scene.lights.push(self.light(light)?);
        }
        if let Some(camera) = &document.camera {
            if camera.get_ref().frame.is_some() {
                return self.error(camera.span(), "camera: frame belongs in [[keyframes]]");
            }
            scene.camera = Some(self.camera(camera)?);
        }
        for key in document.keyframes.iter().flatten() {
            let Some(frame) = key.get_ref().frame else {
                return self.error(key.span(), "a keyframe needs its frame (a whole number)");
            };
            let camera = self.camera(key)?;
            if let Some(last) = scene.keyframes.last()
                && last.camera.fov_axis != camera.fov_axis
            {
                return self.error(key.span(), "keyframes must all have the same fov_axis");
            }
            if scene.keyframes.last().is_some_and(|last| last.frame >= frame) {
                return self.error(
                    key.span(),
                    format!("keyframe {frame}: keyframes must be in order of frame, each once"),
                );
            }
            scene.keyframes.push(Keyframe { frame, camera });
        }
        if let Some(render) = &document.render {
            scene.settings = self.render(render)?;
        }
        scene.validate().map_err(|e| (self.at)(None, e.to_string()))?;
        scene.warnings = self.warnings.take();
        Ok(scene)
    }

    fn shape(
        &self,
        shape: &Spanned<ShapeDoc>,
        materials: &mut Vec<Material>,
        index: &BTreeMap<String, u32>,
        geometry: &mut Geometry,
    ) -> Result<()> {
        let doc = shape.get_ref();
        let kind = doc.kind.get_ref().as_str();
        if !["rectangle", "cube", "sphere", "mesh", "cornell"].contains(&kind) {
            return self.error(
                doc.kind.span(),
                format!(
                    "unknown shape type '{kind}': expected rectangle, cube, sphere, mesh or cornell"
                ),
            );
        }
        if kind == "cornell" {
            return self.lab_cornell_box(shape, index, geometry);
        }
        let transform = super::model::model_to_lab_transform() * self.transform(doc)?;
        // The named material, with the shape's emission if it has one (a copy per shape).
        let mut material = match &doc.material {
            Some(name) => match index.get(name.get_ref()) {
                Some(&m) => Some(m),
                None => {
                    let known: Vec<&str> = index.keys().map(String::as_str).collect();
                    return self.error(
                        name.span(),
                        format!(
                            "no material named '{}' (defined: {})",
                            name.get_ref(),
                            known.join(", ")
                        ),
                    );
                }
            },
            None => None,
        };
        if let Some(emission) = doc.emission {
            let base = material.map_or_else(
                || Material::diffuse("emitter", Vec3::ZERO),
                |m| materials[m as usize].clone(),
            );
            let emission = Vec3::from_array(emission);
            if !emission.is_finite() || emission.min_element() < 0.0 {
                return self.error(
                    shape.span(),
                    format!("emission {emission} must be finite and not negative"),
                );
            }
            material = Some(materials.len() as u32);
            materials.push(Material {
                emission,
                name: format!("{} (emitting)", base.name),
                ..base
            });
        }
        let mesh = match kind {
            "rectangle" => rectangle(),
            "cube" => cube(),
            "sphere" => {
                let centre = Vec3::from_array(doc.center.unwrap_or([0.0; 3]));
                let radius = doc.radius.unwrap_or(1.0);
                if !(radius > 0.0 && radius.is_finite() && centre.is_finite()) {
                    return self.error(
                        shape.span(),
                        "a sphere needs a finite center and a radius above 0",
                    );
                }
                sphere(centre, radius)
            }
            "mesh" => {
                let Some(file) = &doc.file else {
                    return self.error(
                        shape.span(),
                        "a mesh needs `file = \"…\"` (.obj, .ply, optionally .gz; .gltf, .glb)",
                    );
                };
                let mut loaded = self.mesh_file(file)?;
                self.options.instancing.apply(&mut loaded);
                if material.is_none() {
                    // The file's own materials, as diffuse with their Kd and Ke.
                    let base = materials.len() as u32;
                    materials
                        .extend(loaded.mesh.materials.iter().map(super::model::scene_material));
                    let default = materials.len() as u32;
                    let grey = crate::mesh::MeshMaterial::DEFAULT_DIFFUSE;
                    materials.push(Material::diffuse("default", grey));
                    geometry.add_model(&loaded.mesh, &loaded.instanced, &transform, |id| {
                        id.map_or(default, |m| base + m)
                    });
                    return Ok(());
                }
                if let Some(material) = material {
                    let mesh = Mesh { name: kind.to_string(), ..loaded.mesh };
                    geometry.add_model(&mesh, &loaded.instanced, &transform, |_| material);
                    return Ok(());
                }
                loaded.mesh
            }
            other => {
                return self.error(
                    doc.kind.span(),
                    format!(
                        "unknown shape type '{other}': expected rectangle, cube, sphere or mesh"
                    ),
                );
            }
        };
        let Some(material) = material else {
            return self.error(
                shape.span(),
                format!("a {kind} needs `material = \"name\"` or `emission`"),
            );
        };
        geometry.add_mesh(&Mesh { name: kind.to_string(), ..mesh }, &transform, |_| material);
        Ok(())
    }

    /// The mesh in `file` (relative to the scene's folder). A file that several shapes place is
    /// read on its first use and copied for the others (`shared_meshes`); its warnings are
    /// reported once.
    fn mesh_file(&self, file: &Spanned<String>) -> Result<LoadedMesh> {
        if let Some(mesh) = self.in_memory.get(file.get_ref()) {
            return Ok(mesh.clone());
        }
        let path = self.folder.join(file.get_ref());
        let mut shared = self.shared_meshes.borrow_mut();
        if let Some((uses, kept)) = shared.get_mut(&path) {
            debug_assert!(*uses > 0, "a shared mesh file's uses were counted");
            *uses -= 1;
            if *uses == 0
                && let Some(loaded) = kept.take()
            {
                return Ok(loaded);
            }
            if let Some(loaded) = kept {
                return Ok(loaded.clone());
            }
        }
        let loaded =
            super::load_mesh(&path).map_err(|e| (self.at)(Some(file.span()), e.to_string()))?;
        self.warnings.borrow_mut().extend(loaded.warnings.iter().cloned());
        if let Some((uses, kept)) = shared.get_mut(&path)
            && *uses > 0
        {
            *kept = Some(loaded.clone());
        }
        Ok(loaded)
    }

    /// The lab's Cornell box (30 triangles in `[−1, 1]³`), each face with the scene's material
    /// named after its lab colour (red, yellow, green, cyan, blue, purple, white).
    fn lab_cornell_box(
        &self,
        shape: &Spanned<ShapeDoc>,
        index: &BTreeMap<String, u32>,
        geometry: &mut Geometry,
    ) -> Result<()> {
        let doc = shape.get_ref();
        if doc.material.is_some() || doc.emission.is_some() || doc.file.is_some() {
            return self.error(shape.span(), "the cornell shape takes its materials by colour name, not `material`, `emission` or `file`");
        }
        let lab = super::cornell_box();
        let mut corners = Vec::new();
        for i in 0..lab.geometry.len() {
            let colour = &lab.materials[lab.geometry.material_id(i) as usize].name;
            let Some(&material) = index.get(colour) else {
                return self.error(
                    shape.span(),
                    format!("the cornell shape needs a material named '{colour}'"),
                );
            };
            // Back to the file's y-up frame (the half turn is its own inverse).
            corners.push((lab.geometry.triangle(i).map(super::model_to_lab), material));
        }
        let mut triangles = Geometry::new();
        triangles.add_triangles("cornell", corners);
        let transform = super::model::model_to_lab_transform() * self.transform(doc)?;
        let mesh = Mesh {
            name: "cornell".into(),
            positions: (0..triangles.len()).flat_map(|i| triangles.triangle(i)).collect(),
            triangles: (0..triangles.len() as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect(),
            ..Mesh::default()
        };
        geometry.add_mesh(&mesh, &transform, |i| triangles.material_id(i));
        Ok(())
    }

    /// scale, then rotate, then translate, then `to_world`: in the file's y-up frame.
    fn transform(&self, doc: &ShapeDoc) -> Result<Affine3A> {
        self.placement(doc.scale.as_ref(), doc.rotate.as_ref(), doc.translate, doc.to_world)
    }

    fn camera(&self, camera: &Spanned<CameraDoc>) -> Result<CameraSettings> {
        let doc = camera.get_ref();
        let position = Vec3::from_array(doc.position);
        let (yaw, pitch, roll) = match (doc.target, doc.yaw, doc.pitch, doc.roll) {
            (Some(target), None, None, None) => {
                let forward = super::model_to_lab(Vec3::from_array(target) - position);
                if forward.length_squared() == 0.0 || !forward.is_finite() {
                    return self.error(camera.span(), "the camera's target is its position");
                }
                let forward = forward.normalize();
                let yaw = forward.x.atan2(forward.z);
                let pitch = (-forward.y).clamp(-1.0, 1.0).asin();
                // The roll that turns the picture's up toward `up`, about the view direction.
                let up = doc.up.as_ref().map_or(Vec3::Y, |u| Vec3::from_array(*u.get_ref()));
                let up = super::model_to_lab(up);
                let across = up - up.dot(forward) * forward;
                if !across.is_finite() || across.length() < 1e-4 * up.length() {
                    let span = doc.up.as_ref().map_or(camera.span(), |u| u.span());
                    return self
                        .error(span, "camera: up must not be zero or along the view direction");
                }
                let level = Camera { yaw, pitch, ..Camera::lab(1, 1) }.rotation() * Vec3::NEG_Y;
                let across = across.normalize();
                (yaw, pitch, forward.dot(level.cross(across)).atan2(level.dot(across)))
            }
            (None, yaw, pitch, roll) => (
                yaw.unwrap_or(0.0).to_radians(),
                pitch.unwrap_or(0.0).to_radians(),
                roll.unwrap_or(0.0).to_radians(),
            ),
            _ => {
                return self.error(
                    camera.span(),
                    "camera: give either target (and up) or yaw/pitch/roll, not both",
                );
            }
        };
        let fov_deg = doc.fov.unwrap_or(53.130_1);
        if !(fov_deg > 0.0 && fov_deg < 180.0) {
            return self
                .error(camera.span(), format!("fov {fov_deg} must be between 0 and 180 degrees"));
        }
        let fov_axis = match doc.fov_axis.as_ref().map(|s| (s.get_ref().as_str(), s.span())) {
            None | Some(("x", _)) => FovAxis::X,
            Some(("y", _)) => FovAxis::Y,
            Some(("smaller", _)) => FovAxis::Smaller,
            Some(("larger", _)) => FovAxis::Larger,
            Some((other, span)) => {
                return self.error(
                    span,
                    format!("unknown fov_axis '{other}': expected x, y, smaller or larger"),
                );
            }
        };
        let aperture_radius = doc.aperture_radius.unwrap_or(0.0);
        let focus_distance = doc.focus_distance.unwrap_or(1.0);
        let finite =
            position.is_finite() && aperture_radius.is_finite() && focus_distance.is_finite();
        if !(finite && aperture_radius >= 0.0 && focus_distance > 0.0) {
            return self.error(
                camera.span(),
                "camera: position, aperture_radius (≥ 0) and focus_distance (> 0) must be finite",
            );
        }
        Ok(CameraSettings {
            position: super::model_to_lab(position),
            yaw,
            pitch,
            roll,
            fov_deg,
            fov_axis,
            aperture_radius,
            focus_distance,
        })
    }

    fn render(&self, render: &Spanned<RenderDoc>) -> Result<RenderSettings> {
        let doc = render.get_ref();
        let mut settings = RenderSettings {
            size: doc.size.map(|[w, h]| (w, h)),
            spp: doc.spp,
            seed: doc.seed,
            ..RenderSettings::default()
        };
        if let Some((w, h)) = settings.size
            && (w == 0 || h == 0 || w > 1 << 16 || h > 1 << 16)
        {
            return self
                .error(render.span(), format!("size {w}×{h}: each side must be 1 to 65536"));
        }
        if settings.spp == Some(0) {
            return self.error(render.span(), "spp must be at least 1");
        }
        settings.max_depth = match doc.max_depth {
            None => None,
            Some(-1) => Some(MaxDepth::Unlimited),
            Some(d) if (0..=1 << 16).contains(&d) => Some(MaxDepth::Segments(d as u32)),
            Some(d) => {
                return self.error(
                    render.span(),
                    format!("max_depth {d}: expected -1 (unlimited) or 0 to 65536"),
                );
            }
        };
        if let Some(integrator) = &doc.integrator {
            match integrator.get_ref().parse::<IntegratorKind>() {
                Ok(kind) => settings.integrator = Some(kind),
                Err(error) => return self.error(integrator.span(), error.to_string()),
            }
        }
        if let Some(sampler) = &doc.sampler {
            settings.sampler = Some(
                sampler
                    .get_ref()
                    .parse::<SamplerKind>()
                    .map_err(|e| (self.at)(Some(sampler.span()), e.to_string()))?,
            );
        }
        if let Some(filter) = &doc.filter {
            match filter.get_ref().parse::<Filter>() {
                Ok(parsed) => settings.filter = Some(parsed),
                Err(error) => return self.error(filter.span(), error.to_string()),
            }
        }
        Ok(settings)
    }
}

mod builder;
mod lights;
mod materials;
mod shapes;
mod textures;

pub use builder::SceneFileError;
use builder::{Builder, Result, RotateDoc};
use materials::MaterialDoc;
use shapes::{cube, rectangle, sphere};

#[cfg(test)]
mod tests;
