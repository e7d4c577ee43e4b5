//! `albedo`, `normals`, `depth`: what the camera sees first, as images (arbitrary output
//! variables) for denoisers, compositing and debugging.
//!
//! - `albedo`: the first surface's [`Bsdf::albedo`](crate::Bsdf::albedo) (black where nothing is
//!   hit);
//! - `normals`: its shading normal, on the side the camera sees, in the lab's frame (x right, y
//!   down, z forward), components in `[−1, 1]`;
//! - `depth`: the distance along the ray to it (0 where nothing is hit).

use glam::Vec3;

use super::Integrator;
use crate::accel::Accelerator;
use crate::ray::Ray;
use crate::sampling::Sampler;
use crate::scene::Scene;

/// Which first-hit quantity to show.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AovKind {
    /// The surface's albedo.
    Albedo,
    /// The shading normal facing the camera.
    Normals,
    /// The distance to the surface.
    Depth,
}

/// An AOV integrator over a scene and an accelerator built from its vertices.
pub struct Aov<'a, A: ?Sized> {
    scene: &'a Scene,
    accel: &'a A,
    kind: AovKind,
}

impl<'a, A: Accelerator + ?Sized> Aov<'a, A> {
    /// Shows `kind` of `scene`.
    pub fn new(scene: &'a Scene, accel: &'a A, kind: AovKind) -> Self {
        Aov { scene, accel, kind }
    }
}

impl<A: Accelerator + ?Sized> Integrator for Aov<'_, A> {
    fn radiance(&self, ray: &Ray, _sampler: &mut Sampler) -> Vec3 {
        let Some(hit) = super::closest_opaque_hit(self.scene, self.accel, ray) else {
            return Vec3::ZERO;
        };
        let interaction = self.scene.interaction(ray, &hit);
        match self.kind {
            AovKind::Albedo => {
                self.scene.material(&interaction).albedo_at(&interaction.texture_query())
            }
            AovKind::Normals => {
                let n =
                    self.scene.material(&interaction).shading_normal(&interaction, -ray.direction);
                if n.dot(ray.direction) > 0.0 { -n } else { n }
            }
            AovKind::Depth => Vec3::splat(hit.t * ray.direction.length()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::BruteForce;
    use crate::sampling::SamplerKind;

    #[test]
    fn the_lab_box_back_wall_straight_ahead() {
        let scene = Scene::built_in("cornell").unwrap();
        let accel = BruteForce::new(&scene.vertices());
        // Just above the blocks, straight ahead: the back wall at z = 1, 4 from the camera.
        let ray = Ray::new(Vec3::new(0.0, -0.9, -3.0), Vec3::Z);
        let mut sampler = Sampler::new(SamplerKind::Independent, 0, (0, 0), 0);
        let value = |kind| Aov::new(&scene, &accel, kind).radiance(&ray, &mut sampler.clone());
        assert_eq!(value(AovKind::Albedo), Vec3::splat(0.75));
        assert!((value(AovKind::Normals) - Vec3::NEG_Z).length() < 1e-6);
        assert!((value(AovKind::Depth) - Vec3::splat(4.0)).length() < 1e-5);
        let miss = Ray::new(Vec3::new(0.0, 0.0, -3.0), Vec3::NEG_Z);
        let aov = Aov::new(&scene, &accel, AovKind::Depth);
        assert_eq!(aov.radiance(&miss, &mut sampler), Vec3::ZERO);
    }
}
