//! Scenes made from loaded models: a mesh turned into the lab's frame, with a light that lights
//! it and a camera that frames it.
//!
//! Model files are y-up by convention (OBJ, PLY, glTF), with the viewer on the +z side; the lab's
//! frame is y-down with the camera looking along +z. A half turn about the x axis,
//! `(x, y, z) → (x, −y, −z)`, maps one to the other without mirroring, so a model appears upright
//! and seen from its front, and its handedness (and so its text and its chirality) is kept.

use glam::Vec3;

use super::Scene;
use crate::camera::Camera;
use crate::light::PointLight;
use crate::mesh::{Material, Mesh};
use crate::triangle::Triangle;

/// A y-up model point in the lab's y-down frame (a half turn about x).
#[inline]
pub fn model_to_lab(p: Vec3) -> Vec3 {
    Vec3::new(p.x, -p.y, -p.z)
}

impl Scene {
    /// The mesh in the lab's frame, each triangle coloured by its material's diffuse colour (grey
    /// where it has none), lit by [`Scene::default_light`].
    pub fn from_mesh(mesh: &Mesh) -> Scene {
        let triangles: Vec<Triangle> = mesh
            .triangle_vertices()
            .enumerate()
            .map(|(i, t)| {
                let albedo = mesh.material(i).map_or(Material::DEFAULT_DIFFUSE, |m| m.diffuse);
                let [a, b, c] = t.map(model_to_lab);
                Triangle::new(a, b, c, albedo)
            })
            .collect();
        let mut scene = Scene { name: mesh.name.clone(), triangles, light: PointLight::lab() };
        scene.light = scene.default_light();
        scene
    }

    /// The bounding box `(min, max)` of every triangle, or `None` for an empty scene.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        crate::mesh::bounds_of(self.triangles.iter().flat_map(|t| [t.v0, t.v1, t.v2]))
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
        let t = scene.triangles[0];
        // The apex is above the base: smaller y in the lab's y-down frame.
        assert!(t.v2.y < t.v0.y);
        // Left stays left (no mirroring): x is unchanged.
        assert_eq!((t.v0.x, t.v1.x), (-1.0, 1.0));
        // A proper rotation: the determinant of the map is +1.
        let m = glam::Mat3::from_cols(
            model_to_lab(Vec3::X),
            model_to_lab(Vec3::Y),
            model_to_lab(Vec3::Z),
        );
        assert_eq!(m.determinant(), 1.0);
        assert_eq!(t.albedo, Material::DEFAULT_DIFFUSE);
    }

    #[test]
    fn the_camera_sees_the_whole_model_and_the_light_is_above() {
        let scene = Scene::from_mesh(&tent());
        let (lo, hi) = scene.bounds().unwrap();
        let camera = Camera::framing(lo, hi, 200, 100);
        for t in &scene.triangles {
            for v in [t.v0, t.v1, t.v2] {
                let p = camera.project(v).expect("in front of the camera");
                let (x, y) = (p.x, p.y);
                assert!((0.0..200.0).contains(&x) && (0.0..100.0).contains(&y), "{v} at {x},{y}");
            }
        }
        let light = scene.light;
        assert!(light.position.y < lo.y, "the light is above the model");
        assert!(light.position.z < lo.z, "and in front of it");
        let centre = 0.5 * (lo + hi);
        let irradiance = light.power.x
            / (4.0 * std::f32::consts::PI * (light.position - centre).length_squared());
        assert!((irradiance - 1.0).abs() < 1e-4);
    }
}
