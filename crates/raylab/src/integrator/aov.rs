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
use crate::sampling::{Sampler, SamplerKind};
use crate::scene::Scene;
pub use crate::settings::AovKind;

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
        self.value(ray)
    }
}

impl<A: Accelerator + ?Sized> Aov<'_, A> {
    /// The quantity seen along `ray` (it draws no random numbers).
    pub fn value(&self, ray: &Ray) -> Vec3 {
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

/// An integrator with extra layers: the colour of `inner`, and the first-hit quantities of
/// `aovs` from the same camera rays of the same samples (Mitsuba's `aov` integrator), so that
/// the layers cost no pass of their own and match the picture sample for sample. The colour is
/// exactly `inner`'s: the layers draw no random numbers.
pub struct WithAovs<'a, A: ?Sized> {
    inner: &'a dyn Integrator,
    aovs: Vec<Aov<'a, A>>,
}

impl<'a, A: Accelerator + ?Sized> WithAovs<'a, A> {
    /// `inner`'s colour with layers of `kinds`, in that order, over `scene` and `accel`.
    pub fn new(
        inner: &'a dyn Integrator,
        scene: &'a Scene,
        accel: &'a A,
        kinds: &[AovKind],
    ) -> Self {
        WithAovs { inner, aovs: kinds.iter().map(|&kind| Aov::new(scene, accel, kind)).collect() }
    }
}

impl<A: Accelerator + Sync + ?Sized> Integrator for WithAovs<'_, A> {
    fn radiance(&self, ray: &Ray, sampler: &mut Sampler) -> Vec3 {
        self.inner.radiance(ray, sampler)
    }

    fn radiance_each(&self, rays: &[Ray], samplers: &mut [Sampler], out: &mut [Vec3]) {
        self.inner.radiance_each(rays, samplers, out);
    }

    fn sampler_kind(&self) -> SamplerKind {
        self.inner.sampler_kind()
    }

    fn tile_width(&self) -> u32 {
        self.inner.tile_width()
    }

    fn layer_count(&self) -> usize {
        self.aovs.len()
    }

    fn discarded_samples(&self) -> u64 {
        self.inner.discarded_samples()
    }

    fn radiance_and_layers_each(
        &self,
        rays: &[Ray],
        samplers: &mut [Sampler],
        out: &mut [Vec3],
        layers: &mut [Vec3],
    ) {
        let count = self.aovs.len();
        assert_eq!(layers.len(), rays.len() * count, "the layers of each ray");
        self.inner.radiance_each(rays, samplers, out);
        for (ray, values) in rays.iter().zip(layers.chunks_exact_mut(count.max(1))) {
            for (aov, value) in self.aovs.iter().zip(values) {
                *value = aov.value(ray);
            }
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
