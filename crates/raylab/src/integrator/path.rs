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
use super::light_sampler::{LightSet, TriangleSampling};
use crate::accel::Accelerator;
use crate::interaction::SurfaceInteraction;
use crate::ray::Ray;
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
}

impl Default for PathSettings {
    /// Unlimited depth (Mitsuba's default, `max_depth = -1`), roulette from depth 5.
    fn default() -> Self {
        PathSettings { max_depth: None, rr_depth: 5, light_sampling: TriangleSampling::Area }
    }
}

/// The path tracer over a scene and an accelerator built from its vertices.
pub struct Path<'a, A: ?Sized> {
    scene: &'a Scene,
    accel: &'a A,
    lights: Cow<'a, LightSet>,
    settings: PathSettings,
    /// Samples that were not a finite, non-negative colour and counted as black.
    discarded: AtomicU64,
}

impl<'a, A: Accelerator + ?Sized> Path<'a, A> {
    /// A path tracer for `scene`, whose [`vertices`](Scene::vertices) `accel` holds.
    pub fn new(scene: &'a Scene, accel: &'a A, settings: PathSettings) -> Self {
        let lights = LightSet::new(scene).with_triangle_sampling(settings.light_sampling);
        Path { scene, accel, lights: Cow::Owned(lights), settings, discarded: AtomicU64::new(0) }
    }

    /// A path tracer with lights made before (`raylab view` keeps them from frame to frame).
    pub fn with_lights(
        scene: &'a Scene,
        accel: &'a A,
        lights: &'a LightSet,
        settings: PathSettings,
    ) -> Self {
        Path { scene, accel, lights: Cow::Borrowed(lights), settings, discarded: AtomicU64::new(0) }
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
    tangent: Vec3,
    bitangent: Vec3,
    normal: Vec3,
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

impl<A: Accelerator + ?Sized> Integrator for Path<'_, A> {
    fn radiance(&self, camera_ray: &Ray, sampler: &mut Sampler) -> Vec3 {
        let max_depth = self.settings.max_depth.unwrap_or(u32::MAX);
        if max_depth == 0 {
            return Vec3::ZERO;
        }
        let mut ray = *camera_ray;
        let mut radiance = Vec3::ZERO;
        let mut throughput = Vec3::ONE;
        let mut eta = 1.0f32;
        let mut depth = 0u32;
        // The previous vertex's BSDF sample: for the MIS weight of emitters found by it.
        let mut previous_pdf = 1.0f32;
        let mut previous_delta = true;
        // The previous vertex: where light sampling would have sampled from.
        let mut previous_point = camera_ray.origin;
        loop {
            // Light found by the camera or by BSDF sampling: weighted against light sampling,
            // which could have found it too unless the camera or a delta lobe chose the ray.
            let found = |depth: u32, previous_delta: bool, previous_pdf: f32, light_pdf: f32| {
                if depth == 0 || previous_delta {
                    1.0
                } else {
                    power_heuristic(previous_pdf, light_pdf)
                }
            };
            let Some(hit) = super::closest_opaque_hit(self.scene, self.accel, &ray) else {
                let (environment, light_pdf) = self.lights.environment(ray.direction.normalize());
                if environment != Vec3::ZERO {
                    let weight = found(depth, previous_delta, previous_pdf, light_pdf);
                    radiance += throughput * environment * weight;
                }
                break;
            };
            let interaction = self.scene.interaction(&ray, &hit);
            let (emitted, light_pdf) = self.lights.emitted(previous_point, &interaction);
            if emitted != Vec3::ZERO {
                let weight = found(depth, previous_delta, previous_pdf, light_pdf);
                radiance += throughput * emitted * weight;
            }
            if depth + 1 >= max_depth {
                break;
            }
            let Some(scattered) =
                self.scatter(&ray, &interaction, sampler, throughput, &mut radiance)
            else {
                break;
            };
            throughput *= scattered.weight;
            eta *= scattered.eta;
            previous_pdf = scattered.pdf;
            previous_delta = scattered.delta;
            previous_point = interaction.point.p;
            ray = scattered.ray;
            depth += 1;
            // Russian roulette, as Mitsuba's: q = min(max(throughput)·η², 0.95).
            let throughput_max = throughput.max_element();
            if throughput_max <= 0.0 || !throughput_max.is_finite() {
                break;
            }
            let u = sampler.next_1d();
            if depth >= self.settings.rr_depth {
                let q = (throughput_max * eta * eta).min(0.95);
                if u >= q {
                    break;
                }
                throughput /= q;
            }
        }
        // A sample that is not a finite, non-negative colour (a degenerate triangle's NaN, an
        // overflow) would spoil its pixel for good: it counts as black instead, and is counted.
        if radiance.is_finite() && radiance.min_element() >= 0.0 {
            radiance
        } else {
            self.discarded.fetch_add(1, Ordering::Relaxed);
            Vec3::ZERO
        }
    }
}

/// Where a path goes after a vertex.
struct Scattered {
    ray: Ray,
    weight: Vec3,
    pdf: f32,
    delta: bool,
    eta: f32,
}

impl<A: Accelerator + ?Sized> Path<'_, A> {
    /// At a vertex: adds the light sampled there (weighted by MIS) to `radiance`, then samples
    /// the BSDF for the next segment.
    #[inline]
    fn scatter(
        &self,
        ray: &Ray,
        interaction: &SurfaceInteraction,
        sampler: &mut Sampler,
        throughput: Vec3,
        radiance: &mut Vec3,
    ) -> Option<Scattered> {
        let material = self.scene.material(interaction);
        // Only anisotropic BSDFs care which way the tangent points: they get Mitsuba's (dp/du);
        // the rest the cheaper basis of the normal alone (the same distribution of directions).
        let normal = material.shading_normal(interaction, -ray.direction);
        let frame = if material.bsdf.is_anisotropic() {
            Frame::new(normal, interaction.dp_du)
        } else {
            Frame::about(normal)
        };
        let mut wi = frame.to_local(-ray.direction.normalize());
        // Two-sided materials scatter on both sides: mirror the directions into the front.
        let flip = material.two_sided && wi.z < 0.0;
        if flip {
            wi.z = -wi.z;
        }
        let to_local = |w: Vec3| {
            let mut local = frame.to_local(w);
            if flip {
                local.z = -local.z;
            }
            local
        };
        let bsdf = &*material.bsdf_at(&interaction.texture_query());

        // Next-event estimation.
        let u_light = sampler.next_1d();
        let u_point = sampler.next_2d();
        if bsdf.is_smooth()
            && let Some(light) = self.lights.sample(&interaction.point, u_light, u_point)
        {
            let wo = to_local(light.direction);
            let f = bsdf.eval(wi, wo);
            if f != Vec3::ZERO && !super::occluded_opaque(self.scene, self.accel, &light.shadow_ray)
            {
                let weight =
                    if light.delta { 1.0 } else { power_heuristic(light.pdf, bsdf.pdf(wi, wo)) };
                *radiance += throughput * f * light.radiance * (weight / light.pdf);
            }
        }

        // BSDF sampling.
        let u_lobe = sampler.next_1d();
        let u_direction: Vec2 = sampler.next_2d();
        let sample = bsdf.sample(wi, u_lobe, u_direction)?;
        let mut wo = sample.wo;
        if flip {
            wo.z = -wo.z;
        }
        let direction = frame.to_world(wo);
        Some(Scattered {
            ray: interaction.point.spawn_ray(direction),
            weight: sample.weight,
            pdf: sample.pdf,
            delta: sample.delta,
            eta: sample.eta,
        })
    }
}
