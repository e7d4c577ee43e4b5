//! `path`: unidirectional path tracing with next-event estimation and multiple importance
//! sampling — the lab's "indirect illumination by multiple bounces", unbiased.
//!
//! The estimator is Mitsuba 3's `path` integrator, so that the two renderers converge to the same
//! image:
//! - At every vertex, a light is sampled (next-event estimation) and the BSDF is sampled; light
//!   reached both ways is weighted by the power heuristic (Veach 1997), so area lights and glossy
//!   surfaces are both rendered with low noise. Delta lights and delta BSDF lobes get weight 1.
//! - `max_depth` counts path segments including the camera's: 1 shows only emitters seen directly,
//!   2 adds direct lighting, and so on; `None` is unlimited.
//! - Points on area lights are sampled uniformly by area, as Mitsuba does, or by solid angle
//!   (`light_sampling`), which is less noisy for large lights close to what they light.
//! - Russian roulette from `rr_depth` (5) vertices on: a path continues with probability
//!   `q = min(max(throughput)·η², 0.95)` and its throughput is divided by `q`.
//!
//! Surfaces follow their materials' sidedness: one-sided materials are black from behind, and
//! area lights emit from their front side only.

use std::borrow::Cow;
use std::sync::atomic::{AtomicU64, Ordering};

use glam::{Vec2, Vec3};

use super::Integrator;
use super::light_sampler::{EnvironmentSampling, LightSet, TriangleSampling};
use crate::accel::{Accelerator, Hit};
use crate::interaction::SurfaceInteraction;
use crate::material::{Bsdf, Material};
use crate::ray::{Ray, SurfacePoint};
use crate::sampling::{Sampler, orthonormal_basis, power_heuristic};
use crate::scene::Scene;

/// The path tracer's settings, with Mitsuba's names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PathSettings {
    /// The longest path in segments (camera segment included); `None` for no limit.
    pub max_depth: Option<u32>,
    /// The depth from which Russian roulette may end paths.
    pub rr_depth: u32,
    /// How points on triangle lights are sampled.
    pub light_sampling: TriangleSampling,
    /// How directions toward environment maps are sampled.
    pub environment_sampling: EnvironmentSampling,
}

impl Default for PathSettings {
    /// Unlimited depth (Mitsuba's default, `max_depth = -1`), roulette from depth 5.
    fn default() -> Self {
        PathSettings {
            max_depth: None,
            rr_depth: 5,
            light_sampling: TriangleSampling::Area,
            environment_sampling: EnvironmentSampling::Importance,
        }
    }
}

/// The path tracer over a scene and an accelerator built from its vertices.
pub struct PathScalar<'a, A: ?Sized> {
    scene: &'a Scene,
    accel: &'a A,
    lights: Cow<'a, LightSet>,
    settings: PathSettings,
    /// Samples that were not a finite, non-negative colour and counted as black.
    discarded: AtomicU64,
}

impl<'a, A: Accelerator + ?Sized> PathScalar<'a, A> {
    /// A path tracer for `scene`, whose [`vertices`](Scene::vertices) `accel` holds.
    pub fn new(scene: &'a Scene, accel: &'a A, settings: PathSettings) -> Self {
        let lights = LightSet::new(scene)
            .with_triangle_sampling(settings.light_sampling)
            .with_environment_sampling(settings.environment_sampling);
        PathScalar {
            scene,
            accel,
            lights: Cow::Owned(lights),
            settings,
            discarded: AtomicU64::new(0),
        }
    }

    /// A path tracer with lights made before (`raylab view` keeps them from frame to frame).
    pub fn with_lights(
        scene: &'a Scene,
        accel: &'a A,
        lights: &'a LightSet,
        settings: PathSettings,
    ) -> Self {
        PathScalar {
            scene,
            accel,
            lights: Cow::Borrowed(lights),
            settings,
            discarded: AtomicU64::new(0),
        }
    }

    /// The lights it samples.
    pub fn lights(&self) -> &LightSet {
        &self.lights
    }

    /// How many samples so far were not a finite, non-negative colour (a NaN from a degenerate
    /// triangle, an overflow) and counted as black: `raylab render` warns when there are any.
    pub fn discarded_samples(&self) -> u64 {
        self.discarded.load(Ordering::Relaxed)
    }
}

/// A shading frame: the shading normal and two tangents.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Frame {
    pub(crate) tangent: Vec3,
    pub(crate) bitangent: Vec3,
    pub(crate) normal: Vec3,
}

impl Frame {
    /// Mitsuba's shading frame: the tangent is `dp_du` made perpendicular to the normal (so
    /// anisotropic materials align with the surface's `u` direction, as in Mitsuba), the
    /// bitangent `n × s`; Duff et al.'s basis where `dp_du` is along the normal.
    #[inline]
    pub(crate) fn new(normal: Vec3, dp_du: Vec3) -> Frame {
        let s = (dp_du - normal * normal.dot(dp_du)).normalize_or_zero();
        if s == Vec3::ZERO {
            return Frame::about(normal);
        }
        Frame { tangent: s, bitangent: normal.cross(s), normal }
    }

    /// A frame about the normal alone (Duff et al.'s basis), for BSDFs that are the same for
    /// every tangent.
    #[inline]
    pub(crate) fn about(normal: Vec3) -> Frame {
        let (tangent, bitangent) = orthonormal_basis(normal);
        Frame { tangent, bitangent, normal }
    }

    #[inline]
    pub(crate) fn to_local(self, w: Vec3) -> Vec3 {
        Vec3::new(w.dot(self.tangent), w.dot(self.bitangent), w.dot(self.normal))
    }

    #[inline]
    pub(crate) fn to_world(self, w: Vec3) -> Vec3 {
        w.x * self.tangent + w.y * self.bitangent + w.z * self.normal
    }
}

/// One path's state between its vertices.
#[derive(Clone, Copy, Debug)]
pub(super) struct PathState {
    /// The ray to trace next.
    pub ray: Ray,
    /// The light gathered so far.
    pub radiance: Vec3,
    pub throughput: Vec3,
    /// The product of the relative indices of refraction crossed (for the roulette).
    pub eta: f32,
    /// Segments traced so far.
    pub depth: u32,
    /// The previous vertex's BSDF sample: for the MIS weight of emitters found by it.
    pub previous_pdf: f32,
    pub previous_delta: bool,
    /// The previous vertex: where light sampling would have sampled from.
    pub previous_point: Vec3,
}

impl PathState {
    /// A path starting with a camera ray.
    pub fn new(camera_ray: &Ray) -> PathState {
        PathState { ray: *camera_ray, previous_point: camera_ray.origin, ..PathState::START }
    }

    /// The paths starting with `camera_rays`, in order.
    ///
    /// Made as copies of one template whose ray is then set: building each state whole (as
    /// `new` does) compiles to a state assembled on the stack and read back across two of its
    /// stores, which stalls store-to-load forwarding once per path.
    pub fn starting(camera_rays: &[Ray]) -> Vec<PathState> {
        let mut states = vec![PathState::START; camera_rays.len()];
        for (state, ray) in states.iter_mut().zip(camera_rays) {
            state.ray = *ray;
            state.previous_point = ray.origin;
        }
        states
    }

    /// A path before its camera ray is set.
    const START: PathState = PathState {
        ray: Ray { origin: Vec3::ZERO, direction: Vec3::Z, t_min: 0.0, t_max: f32::INFINITY },
        radiance: Vec3::ZERO,
        throughput: Vec3::ONE,
        eta: 1.0,
        depth: 0,
        previous_pdf: 1.0,
        previous_delta: true,
        previous_point: Vec3::ZERO,
    };
}

/// A path's vertex, ready to scatter: its BSDF, in the shading frame.
pub(super) struct Vertex<'s> {
    pub point: SurfacePoint,
    pub frame: Frame,
    /// Whether the directions are mirrored into the front of a two-sided material.
    pub flip: bool,
    /// The direction toward the viewer, local.
    pub wi: Vec3,
    pub bsdf: Cow<'s, Bsdf>,
}

impl Vertex<'_> {
    /// A world direction in the BSDF's local frame (mirrored for a two-sided back side).
    #[inline]
    fn to_local(&self, w: Vec3) -> Vec3 {
        let mut local = self.frame.to_local(w);
        if self.flip {
            local.z = -local.z;
        }
        local
    }
}

/// A vertex's shading frame, whether its directions are mirrored into a two-sided material's
/// front, and the direction toward the viewer in the frame (mirrored).
#[inline(always)]
fn shading_frame(
    material: &Material,
    ray: &Ray,
    interaction: &SurfaceInteraction,
) -> (Frame, bool, Vec3) {
    // Only anisotropic BSDFs care which way the tangent points: they get Mitsuba's (dp/du);
    // the rest the cheaper basis of the normal alone (the same distribution of directions).
    let normal = material.shading_normal(interaction, -ray.direction);
    let frame = if material.bsdf.is_anisotropic() {
        Frame::new(normal, interaction.dp_du)
    } else {
        Frame::about(normal)
    };
    facing(material.two_sided, ray.direction, frame)
}

/// [`shading_frame`]'s second half: the direction toward the viewer of a ray along `direction`
/// in `frame`, mirrored into the front for a `two_sided` material, and whether it was (the
/// wavefront's lanes run it too).
#[inline(always)]
pub(super) fn facing(two_sided: bool, direction: Vec3, frame: Frame) -> (Frame, bool, Vec3) {
    let mut wi = frame.to_local(-direction.normalize());
    // Two-sided materials scatter on both sides: mirror the directions into the front.
    let flip = two_sided && wi.z < 0.0;
    if flip {
        wi.z = -wi.z;
    }
    (frame, flip, wi)
}

impl<A: Accelerator + ?Sized> Integrator for PathScalar<'_, A> {
    fn discarded_samples(&self) -> u64 {
        PathScalar::discarded_samples(self)
    }

    fn radiance(&self, camera_ray: &Ray, sampler: &mut Sampler) -> Vec3 {
        let max_depth = self.settings.max_depth.unwrap_or(u32::MAX);
        if max_depth == 0 {
            return Vec3::ZERO;
        }
        let mut state = PathState::new(camera_ray);
        loop {
            let hit = super::closest_opaque_hit(self.scene, self.accel, &state.ray);
            let Some(interaction) = self.arrive(&mut state, hit.as_ref()) else { break };
            if state.depth + 1 >= max_depth {
                break;
            }
            let vertex = self.vertex(&state.ray, &interaction);
            if let Some((shadow_ray, contribution)) =
                self.sample_light(&vertex, sampler, state.throughput)
                && !super::occluded_opaque(self.scene, self.accel, &shadow_ray)
            {
                state.radiance += contribution;
            }
            if !self.scatter(&mut state, &vertex, sampler) {
                break;
            }
        }
        self.finish(state.radiance)
    }
}

/// The steps of a path, shared by [`PathScalar::radiance`] and the wavefront
/// ([`Path`](super::Path)), which runs them stage by stage over many paths:
/// the same code, so the same bits.
impl<'a, A: Accelerator + ?Sized> PathScalar<'a, A> {
    /// The scene.
    pub(super) fn scene(&self) -> &'a Scene {
        self.scene
    }

    /// The accelerator.
    pub(super) fn accel(&self) -> &'a A {
        self.accel
    }

    /// The settings.
    pub(super) fn settings(&self) -> PathSettings {
        self.settings
    }

    /// The path's ray has found `hit` (or nothing): adds the light it finds there, weighted
    /// against light sampling (which could have found it too, unless the camera or a delta lobe
    /// chose the ray), and returns the surface it reached, or `None` where it left the scene.
    #[inline]
    pub(super) fn arrive(
        &self,
        state: &mut PathState,
        hit: Option<&Hit>,
    ) -> Option<SurfaceInteraction> {
        let (unweighted, previous_pdf) =
            (state.depth == 0 || state.previous_delta, state.previous_pdf);
        let found = |light_pdf: f32| {
            if unweighted { 1.0 } else { power_heuristic(previous_pdf, light_pdf) }
        };
        let Some(hit) = hit else {
            let direction = state.ray.direction.normalize();
            self.lights.escaped(direction, |light| {
                let weight = found(light.pdf);
                state.radiance += state.throughput * light.radiance * weight;
            });
            return None;
        };
        let interaction = self.scene.interaction(&state.ray, hit);
        let light = self.lights.emitted(state.previous_point, &interaction);
        if light.radiance != Vec3::ZERO {
            let weight = found(light.pdf);
            state.radiance += state.throughput * light.radiance * weight;
        }
        Some(interaction)
    }

    /// [`arrive`](Self::arrive) for the paths `paths` of `states` that left the scene, to the
    /// bit: the light they find, their infinite lights' lookups made together
    /// ([`LightSet::escaped_each`]). `scratch` has room for an emission per path.
    #[inline]
    pub(super) fn escape_each(
        &self,
        states: &mut [PathState],
        paths: &[usize],
        directions: &mut Vec<Vec3>,
        scratch: &mut Vec<crate::light::Emission>,
    ) {
        directions.clear();
        directions.extend(paths.iter().map(|&i| states[i].ray.direction.normalize()));
        scratch.clear();
        scratch.resize(paths.len(), crate::light::Emission::NONE);
        self.lights.escaped_each(directions, scratch, |lane, light| {
            let state = &mut states[paths[lane]];
            let unweighted = state.depth == 0 || state.previous_delta;
            let weight =
                if unweighted { 1.0 } else { power_heuristic(state.previous_pdf, light.pdf) };
            state.radiance += state.throughput * light.radiance * weight;
        });
    }

    /// The vertex at `interaction`, reached along `ray`: its material's BSDF in its shading
    /// frame.
    #[inline]
    pub(super) fn vertex(&self, ray: &Ray, interaction: &SurfaceInteraction) -> Vertex<'a> {
        let material = self.scene.material(interaction);
        let (frame, flip, wi) = shading_frame(material, ray, interaction);
        let bsdf = material.bsdf_at(&interaction.texture_query());
        Vertex { point: interaction.point, frame, flip, wi, bsdf }
    }

    /// Next-event estimation at `vertex`: draws a light sample, and returns the shadow ray and
    /// the light (weighted by MIS, times `throughput`) that arrives if nothing blocks the ray.
    #[inline]
    pub(super) fn sample_light(
        &self,
        vertex: &Vertex,
        sampler: &mut Sampler,
        throughput: Vec3,
    ) -> Option<(Ray, Vec3)> {
        let u = sampler.next_2d();
        self.sample_light_with(vertex, u, throughput)
    }

    /// [`sample_light`](Self::sample_light) with its numbers drawn: `u` picks the light and the
    /// point on it ([`LightSet::sample`]).
    #[inline]
    pub(super) fn sample_light_with(
        &self,
        vertex: &Vertex,
        u: Vec2,
        throughput: Vec3,
    ) -> Option<(Ray, Vec3)> {
        if !vertex.bsdf.is_smooth() {
            return None;
        }
        let light = self.lights.sample(&vertex.point, u)?;
        let wo = vertex.to_local(light.direction);
        let f = vertex.bsdf.eval(vertex.wi, wo);
        if f == Vec3::ZERO {
            return None;
        }
        let weight = if light.delta {
            1.0
        } else {
            power_heuristic(light.pdf, vertex.bsdf.pdf(vertex.wi, wo))
        };
        Some((light.shadow_ray, throughput * f * light.radiance * (weight / light.pdf)))
    }

    /// Samples the BSDF at `vertex` for the path's next segment, then plays Russian roulette:
    /// whether the path goes on.
    #[inline]
    pub(super) fn scatter(
        &self,
        state: &mut PathState,
        vertex: &Vertex,
        sampler: &mut Sampler,
    ) -> bool {
        let u_lobe = sampler.next_1d();
        let u_direction: Vec2 = sampler.next_2d();
        if !self.bounce(state, vertex, u_lobe, u_direction) {
            return false;
        }
        let u = sampler.next_1d();
        self.survives_roulette(state, u)
    }

    /// The BSDF sample of [`scatter`](Self::scatter) for `u_lobe` and `u_direction`: the next
    /// segment, or `false` where the path ends (no sample, or a throughput that is zero or not
    /// finite).
    #[inline]
    pub(super) fn bounce(
        &self,
        state: &mut PathState,
        vertex: &Vertex,
        u_lobe: f32,
        u_direction: Vec2,
    ) -> bool {
        let Some(sample) = vertex.bsdf.sample(vertex.wi, u_lobe, u_direction) else {
            return false;
        };
        let mut wo = sample.wo;
        if vertex.flip {
            wo.z = -wo.z;
        }
        let direction = vertex.frame.to_world(wo);
        state.throughput *= sample.weight;
        state.eta *= sample.eta;
        state.previous_pdf = sample.pdf;
        state.previous_delta = sample.delta;
        state.previous_point = vertex.point.p;
        state.ray = vertex.point.spawn_ray(direction);
        state.depth += 1;
        let throughput_max = state.throughput.max_element();
        throughput_max > 0.0 && throughput_max.is_finite()
    }

    /// Russian roulette after a [`bounce`](Self::bounce), as Mitsuba's: from `rr_depth` on, the
    /// path goes on with probability `q = min(max(throughput)·η², 0.95)` (`u` below it), its
    /// throughput divided by `q`.
    #[inline]
    pub(super) fn survives_roulette(&self, state: &mut PathState, u: f32) -> bool {
        let throughput_max = state.throughput.max_element();
        if state.depth >= self.settings.rr_depth {
            let q = (throughput_max * state.eta * state.eta).min(0.95);
            if u >= q {
                return false;
            }
            state.throughput /= q;
        }
        true
    }

    /// A finished path's sample: a sample that is not a finite, non-negative colour (a
    /// degenerate triangle's NaN, an overflow) would spoil its pixel for good, so it counts as
    /// black instead, and is counted.
    #[inline]
    pub(super) fn finish(&self, radiance: Vec3) -> Vec3 {
        if radiance.is_finite() && radiance.min_element() >= 0.0 {
            radiance
        } else {
            self.discarded.fetch_add(1, Ordering::Relaxed);
            Vec3::ZERO
        }
    }
}
