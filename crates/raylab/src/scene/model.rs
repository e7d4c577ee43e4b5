//! Scenes made from loaded models: a mesh turned into the lab's frame, with a light that lights
//! it and a camera that frames it.
//!
//! Model files are y-up by convention (OBJ, PLY, glTF), with the viewer on the +z side; the lab's
//! frame is y-down with the camera looking along +z. A half turn about the x axis,
//! `(x, y, z) → (x, −y, −z)`, maps one to the other without mirroring, so a model appears upright
//! and seen from its front, and its handedness (and so its text and its chirality) is kept.

use glam::Vec3;

use glam::Affine3A;

use super::Scene;
#[cfg(feature = "io")]
use super::mesh_file::LoadedMesh;
use crate::camera::Camera;
use crate::geometry::Geometry;
use crate::light::{Light, PointLight};
use crate::material::{Bsdf, Dielectric, Ggx, Material, Pbr, RoughDielectric};
use crate::mesh::InstancedMesh;
use crate::mesh::{Mesh, MeshMaterial};

/// A y-up model point in the lab's y-down frame (a half turn about x).
#[inline]
pub fn model_to_lab(p: Vec3) -> Vec3 {
    Vec3::new(p.x, -p.y, -p.z)
}

/// [`model_to_lab`] as a transform, for meshes (their normals turn with it).
pub(crate) fn model_to_lab_transform() -> Affine3A {
    Affine3A::from_mat3(glam::Mat3::from_diagonal(Vec3::new(1.0, -1.0, -1.0)))
}

impl Scene {
    /// The mesh in the lab's frame with its materials: diffuse with the file's colour (grey where
    /// a triangle names none), emitting its `Ke`. Lit by [`Scene::default_light`] unless some
    /// material emits.
    pub fn from_mesh(mesh: &Mesh) -> Scene {
        Scene::from_meshes(mesh, &[])
    }

    /// [`from_mesh`](Self::from_mesh) with meshes drawn in several places, each stored once.
    fn from_meshes(mesh: &Mesh, instanced: &[InstancedMesh]) -> Scene {
        let mut materials: Vec<Material> = mesh.materials.iter().map(scene_material).collect();
        let default = materials.len() as u32;
        materials.push(Material::diffuse("default", MeshMaterial::DEFAULT_DIFFUSE));
        let mut geometry = Geometry::new();
        let to_lab = model_to_lab_transform();
        geometry.add_model(mesh, instanced, &to_lab, |id| id.unwrap_or(default));
        let mut scene = Scene { name: mesh.name.clone(), geometry, materials, ..Scene::default() };
        if !scene.has_area_lights() {
            scene.lights.push(Light::Point(scene.default_light()));
        }
        scene
    }

    #[cfg(feature = "io")]
    /// A loaded model file as a scene ([`from_mesh`](Self::from_mesh), its instanced meshes
    /// stored once) with the file's camera and, where it has some, its lights instead of the
    /// default light.
    pub fn from_loaded(loaded: &LoadedMesh) -> Scene {
        let mut scene = Scene::from_meshes(&loaded.mesh, &loaded.instanced);
        scene.camera = loaded.camera;
        if !loaded.lights.is_empty() {
            scene.lights.retain(|light| !matches!(light, Light::Point(_)));
            scene.lights.extend(loaded.lights.iter().cloned());
        }
        scene
    }

    /// A light above the scene, a little to the right and in front of it (toward a camera that
    /// looks along +z), as far from the centre as the box's diagonal, with the power that gives
    /// an irradiance of 1 at the centre (`P = 4πr²`): the model is lit like the lab's box,
    /// whatever its size.
    pub fn default_light(&self) -> PointLight {
        let Some((lo, hi)) = self.bounds() else { return PointLight::lab() };
        let centre = 0.5 * (lo + hi);
        let diagonal = (hi - lo).length().max(f32::MIN_POSITIVE);
        let offset = Vec3::new(0.3, -0.8, -0.6).normalize() * diagonal;
        let r2 = offset.length_squared();
        PointLight {
            position: centre + offset,
            power: Vec3::splat(4.0 * std::f32::consts::PI * r2),
        }
    }
}

impl Geometry {
    /// Appends a loaded model through `transform`: `mesh`'s triangles, and each of `instanced`
    /// stored once and drawn in each of its places; `material` maps a triangle's material in
    /// the file (`None` where it names none) to the scene's.
    pub fn add_model(
        &mut self,
        mesh: &Mesh,
        instanced: &[InstancedMesh],
        transform: &Affine3A,
        material: impl Fn(Option<u32>) -> u32,
    ) {
        let ids = &mesh.material_ids;
        self.add_mesh(mesh, transform, |i| material(ids.get(i).copied().flatten()));
        for part in instanced {
            let transforms: Vec<Affine3A> =
                part.transforms.iter().map(|t| *transform * *t).collect();
            let ids = &part.mesh.material_ids;
            self.add_instanced_mesh(&part.mesh, &transforms, |i| {
                material(ids.get(i).copied().flatten())
            });
        }
    }
}

impl Camera {
    /// A camera looking along +z (yaw 0) that frames the box `(lo, hi)`: the whole box is in view
    /// with a margin of about 5 %, at the distance where its nearest face just fits the field of
    /// view across and down. `f = width`, as the lab's camera.
    pub fn framing(lo: Vec3, hi: Vec3, width: u32, height: u32) -> Camera {
        let mut camera = Camera::lab(width, height);
        let centre = 0.5 * (lo + hi);
        let half = 0.5 * (hi - lo);
        let tan_x = (camera.fov_x_deg().to_radians() / 2.0).tan();
        let tan_y = (camera.fov_y_deg().to_radians() / 2.0).tan();
        // Every corner is at most `half.z` nearer than the centre, so the distance from the
        // centre that fits the front face also fits the rest of the box.
        let fit = (half.x / tan_x).max(half.y / tan_y) * 1.1 + half.z;
        camera.position = centre - Vec3::Z * fit.max(f32::MIN_POSITIVE);
        camera
    }
}

/// A loaded mesh's material as a scene's material, emitting its `Ke` (glTF's emission):
/// diffuse with the file's colour and textures (OBJ, PLY); with glTF's parameters, the
/// metallic-roughness [`Pbr`] BSDF, or glass (smooth or GGX-rough, of its index of refraction)
/// where it transmits.
pub(crate) fn scene_material(mesh_material: &MeshMaterial) -> Material {
    let mut material = Material {
        emission: mesh_material.emission,
        textures: mesh_material.textures.clone(),
        ..Material::diffuse(&mesh_material.name, mesh_material.diffuse)
    };
    let Some(p) = mesh_material.pbr else { return material };
    let unit = |v: f32| if v.is_finite() { v.clamp(0.0, 1.0) } else { 0.0 };
    material.bsdf = if p.transmission > 0.5 {
        let alpha = unit(p.roughness).powi(2);
        if alpha < 1e-3 {
            Bsdf::Dielectric(Dielectric { eta: p.ior })
        } else {
            Bsdf::RoughDielectric(RoughDielectric {
                eta: p.ior,
                distribution: Ggx::new(alpha, alpha),
            })
        }
    } else {
        Bsdf::Pbr(Pbr {
            base_color: mesh_material.diffuse.clamp(Vec3::ZERO, Vec3::ONE),
            metallic: unit(p.metallic),
            roughness: unit(p.roughness),
        })
    };
    material
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tent() -> Mesh {
        // A y-up tent: apex at the top (+y), base on y = 0, facing +z.
        Mesh {
            name: "tent".into(),
            positions: vec![
                Vec3::new(-1.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.0, 2.0, 0.5),
            ],
            triangles: vec![[0, 1, 2]],
            ..Mesh::default()
        }
    }

    #[test]
    fn models_stand_upright_and_keep_their_handedness() {
        let scene = Scene::from_mesh(&tent());
        let [v0, v1, v2] = scene.geometry.triangle(0);
        // The apex is above the base: smaller y in the lab's y-down frame.
        assert!(v2.y < v0.y);
        // Left stays left (no mirroring): x is unchanged.
        assert_eq!((v0.x, v1.x), (-1.0, 1.0));
        // The front (+z, counter-clockwise) side faces the camera, at −z in the lab's frame.
        assert!(scene.geometry.normal(0).z < 0.0);
        // A proper rotation: the determinant of the map is +1.
        let m = glam::Mat3::from_cols(
            model_to_lab(Vec3::X),
            model_to_lab(Vec3::Y),
            model_to_lab(Vec3::Z),
        );
        assert_eq!(m.determinant(), 1.0);
        let p = Vec3::new(0.25, -3.0, 7.5);
        assert_eq!(model_to_lab_transform().transform_point3(p), model_to_lab(p));
        let material = &scene.materials[scene.geometry.material_id(0) as usize];
        assert_eq!(material.bsdf.albedo(), MeshMaterial::DEFAULT_DIFFUSE);
    }

    #[test]
    fn the_camera_sees_the_whole_model_and_the_light_is_above() {
        let scene = Scene::from_mesh(&tent());
        let (lo, hi) = scene.bounds().unwrap();
        let camera = Camera::framing(lo, hi, 200, 100);
        for i in 0..scene.geometry.len() {
            for v in scene.geometry.triangle(i) {
                let p = camera.project(v).expect("in front of the camera");
                let (x, y) = (p.x, p.y);
                assert!((0.0..200.0).contains(&x) && (0.0..100.0).contains(&y), "{v} at {x},{y}");
            }
        }
        let light = scene.lab_light();
        assert!(light.position.y < lo.y, "the light is above the model");
        assert!(light.position.z < lo.z, "and in front of it");
        let centre = 0.5 * (lo + hi);
        let irradiance = light.power.x
            / (4.0 * std::f32::consts::PI * (light.position - centre).length_squared());
        assert!((irradiance - 1.0).abs() < 1e-4);
    }
}
