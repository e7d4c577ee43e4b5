//! The one place that turns a choice of integrator ([`IntegratorKind`], a scene file's or the
//! command line's `integrator`) into the integrator that computes it: for `raylab render` (the
//! render session) and `raylab view` alike. Only the chosen integrator is built.

use glam::Vec3;

use super::Integrator;
use super::aov::Aov;
use super::lab::{Lab, Stage};
use super::light_sampler::LightSet;
use super::path::{PathScalar, PathSettings};
use super::wavefront::Path;
use crate::accel::Accelerator;
use crate::camera::Camera;
use crate::ray::Ray;
use crate::sampling::{Sampler, SamplerKind};
use crate::scene::Scene;
use crate::settings::IntegratorKind;

/// What the chosen integrator needs beside the scene: the lab's stage, the path tracer's
/// settings, and lights made before where the caller keeps them (`raylab view` moves the
/// point light and keeps the set from frame to frame).
#[derive(Clone, Copy, Debug)]
pub struct Choice<'a> {
    /// Which integrator.
    pub kind: IntegratorKind,
    /// The lab's stage (for [`IntegratorKind::Lab`]).
    pub stage: Stage,
    /// The path tracers' settings.
    pub path: PathSettings,
    /// The path tracers' lights; `None`: made from the scene with `path`'s light and
    /// environment sampling (a set given keeps its own).
    pub lights: Option<&'a LightSet>,
}

/// The integrator a [`Choice`] names, built for one camera.
pub enum Chosen<'a, A: ?Sized> {
    /// The lab's light model.
    Lab(Lab<'a, A>),
    /// The path tracer (the wavefront).
    Path(Path<'a, A>),
    /// The path tracer one path at a time.
    PathScalar(PathScalar<'a, A>),
    /// A first-hit quantity.
    Aov(Aov<'a, A>),
}

impl<'a, A: Accelerator + ?Sized> Chosen<'a, A> {
    /// The integrator `choice` names, for `scene` (whose triangles `accel` holds) seen by
    /// `camera`.
    pub fn new(choice: &Choice<'a>, scene: &'a Scene, accel: &'a A, camera: &Camera) -> Self {
        match (choice.kind, choice.lights) {
            (IntegratorKind::Lab, _) => {
                Chosen::Lab(Lab::new(scene, accel, choice.stage).for_camera(camera))
            }
            (IntegratorKind::Path, None) => Chosen::Path(Path::new(scene, accel, choice.path)),
            (IntegratorKind::Path, Some(lights)) => {
                Chosen::Path(Path::with_lights(scene, accel, lights, choice.path))
            }
            (IntegratorKind::PathScalar, None) => {
                Chosen::PathScalar(PathScalar::new(scene, accel, choice.path))
            }
            (IntegratorKind::PathScalar, Some(lights)) => {
                Chosen::PathScalar(PathScalar::with_lights(scene, accel, lights, choice.path))
            }
            (IntegratorKind::Aov(kind), _) => Chosen::Aov(Aov::new(scene, accel, kind)),
        }
    }

    /// Moves the lab's point light to `position` (`raylab view`'s controller moves it); the
    /// path tracers take theirs from their [`LightSet`]. Nothing for the others.
    pub fn move_lab_light(&mut self, position: Vec3) {
        if let Chosen::Lab(lab) = self {
            lab.light.position = position;
        }
    }

    /// As the trait object it is.
    pub fn as_dyn(&self) -> &(dyn Integrator + 'a) {
        match self {
            Chosen::Lab(i) => i,
            Chosen::Path(i) => i,
            Chosen::PathScalar(i) => i,
            Chosen::Aov(i) => i,
        }
    }
}

impl<A: Accelerator + ?Sized> Integrator for Chosen<'_, A> {
    fn radiance(&self, ray: &Ray, sampler: &mut Sampler) -> Vec3 {
        self.as_dyn().radiance(ray, sampler)
    }

    fn radiance_each(&self, rays: &[Ray], samplers: &mut [Sampler], out: &mut [Vec3]) {
        self.as_dyn().radiance_each(rays, samplers, out)
    }

    fn tile_width(&self) -> u32 {
        self.as_dyn().tile_width()
    }

    fn sampler_kind(&self) -> SamplerKind {
        self.as_dyn().sampler_kind()
    }

    fn draws_numbers(&self) -> bool {
        self.as_dyn().draws_numbers()
    }

    fn discarded_samples(&self) -> u64 {
        self.as_dyn().discarded_samples()
    }

    fn layer_count(&self) -> usize {
        self.as_dyn().layer_count()
    }

    fn radiance_and_layers_each(
        &self,
        rays: &[Ray],
        samplers: &mut [Sampler],
        out: &mut [Vec3],
        layers: &mut [Vec3],
    ) {
        self.as_dyn().radiance_and_layers_each(rays, samplers, out, layers)
    }
}
