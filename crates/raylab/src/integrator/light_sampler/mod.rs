//! Light sampling for the path tracer: every light of a scene in one set, chosen by power, the
//! environments half the time beside other lights.
//!
//! [`LightSet`] gathers the scene's lights ([`Emitter`]s: point, spot and directional lights,
//! suns, its emissive triangles and its environments), picks one in proportion to its power
//! (the environments, unless black, half the time when there are other lights), and has it
//! sample a direction toward itself (next-event estimation); the density it returns is the
//! light's times the probability of having picked it. A ray that leaves the scene finds the
//! infinite lights (environments and suns) with their densities, for multiple importance
//! sampling ([`LightSet::escaped`]), and a ray that hits an emitting triangle finds its light
//! ([`LightSet::emitted`]). One pair of numbers picks the light (its first number, rescaled
//! within the light's share) and the point on it, as in Mitsuba. The set makes the area lights
//! from the scene's emitting triangles and knows which triangle is whose; otherwise it picks
//! by power, and each light samples and evaluates itself (the `light` module).

use std::f32::consts::PI;
use std::sync::Arc;

use glam::{Vec2, Vec3};

use crate::interaction::SurfaceInteraction;
use crate::light::lanes::{LaneLight, LaneRole};
use crate::light::{
    ConstantEnvironment, Emission, EmissionPattern, Emitter, Light, MapLight, TriangleLight,
};
pub use crate::light::{EnvironmentSampling, LightSample, TriangleSampling};
use crate::ray::SurfacePoint;
use crate::sampling::{DiscreteDistribution, SEARCH_LANES};
use crate::scene::Scene;

/// Every light of a scene, ready to be sampled: point lights, the emissive triangles (area
/// lights) and the environment, chosen by power (the environment half the time beside others).
#[derive(Clone, Debug)]
pub struct LightSet {
    lights: Vec<Emitter>,
    /// Each light as the lanes take it ([`pick_for_lanes`](Self::pick_for_lanes)).
    lane_lights: Vec<LaneLight>,
    /// By power, the environment's share apart; `None` without lights.
    distribution: Option<DiscreteDistribution>,
    /// For each triangle, the index of its light, or `u32::MAX`.
    triangle_light: Vec<u32>,
    /// The lights that rays leaving the scene find: environments and suns.
    infinite: Vec<u32>,
}

/// What [`LightSet::pick_for_lanes`] picked: the light by reference (the lanes copy its fields
/// straight into their rows), the probability of having picked it, and where its share of the
/// first number starts.
#[derive(Clone, Copy, Debug)]
pub(super) struct LanePick<'a> {
    pub light: &'a LaneLight,
    pub selection: f32,
    pub start: f32,
}

impl LanePick<'_> {
    /// How the lanes take the light.
    #[inline(always)]
    pub fn role(&self) -> LaneRole {
        self.light.role
    }
}

/// No light, for [`LightSet::pick_for_lanes`] without lights.
static NO_LIGHT: LaneLight = LaneLight::NONE;

impl LightSet {
    /// The lights of `scene`.
    pub fn new(scene: &Scene) -> LightSet {
        let mut lights = Vec::new();
        let mut triangle_light = vec![u32::MAX; scene.geometry.len()];
        let mut environment = None;
        for light in &scene.lights {
            match light {
                Light::EnvironmentMap(map) => lights.push(Emitter::EnvironmentMap(MapLight {
                    map: map.clone(),
                    sampling: EnvironmentSampling::Importance,
                })),
                Light::Directional(light) => lights.push(Emitter::Directional(*light)),
                Light::Spot(spot) => lights.push(Emitter::Spot(*spot)),
                Light::Sun(sun) => lights.push(Emitter::Sun(*sun)),
                Light::Point(point) => lights.push(Emitter::Point(*point)),
                // Several environments shine as one: their radiances add.
                Light::Environment { radiance } => match environment {
                    Some((sum, index)) => {
                        let sum = sum + *radiance;
                        environment = Some((sum, index));
                        lights[index as usize] =
                            Emitter::Environment(ConstantEnvironment { radiance: sum });
                    }
                    None => {
                        environment = Some((*radiance, lights.len() as u32));
                        lights.push(Emitter::Environment(ConstantEnvironment {
                            radiance: *radiance,
                        }));
                    }
                },
            }
        }
        for (i, slot) in triangle_light.iter_mut().enumerate() {
            let material = &scene.materials[scene.geometry.material_id(i) as usize];
            let area = scene.geometry.area(i);
            if material.is_emissive() && area > 0.0 {
                *slot = lights.len() as u32;
                let pattern = material.textures.emission.as_ref().map(|texture| {
                    let uvs = scene.geometry.corner_uvs(i);
                    Arc::new(EmissionPattern { texture: texture.clone(), uvs })
                });
                lights.push(Emitter::Triangle(TriangleLight {
                    corners: scene.geometry.triangle(i),
                    normal: scene.geometry.normal(i),
                    error: scene.geometry.point_error_bound(i),
                    area,
                    radiance: material.emission,
                    pattern,
                    sampling: TriangleSampling::Area,
                }));
            }
        }
        // Lights from infinitely far away send their power through a disk the size of the scene
        // (PBR 4th ed. §12.5).
        let scene_radius = scene
            .bounds()
            .map(|(min, max)| 0.5 * (max - min).length())
            .filter(|r| r.is_finite() && *r > 0.0)
            .unwrap_or(1.0);
        let through_scene = PI * scene_radius * scene_radius;
        // (Each kept below overflow: a sum that overflowed would leave no light to pick.)
        let mut powers: Vec<f32> =
            lights.iter().map(|light| light.power(through_scene).min(1e30)).collect();
        // The environments are picked half the time when there are other lights, and always
        // without (pbrt-v4's `BVHLightSampler`, Mitsuba's uniform choice among two emitters); a
        // black one never. Their power through a disk the size of the scene (PBR 4th ed. §12.5)
        // would rank them by the floor around the scene's subject, and take most picks from
        // the lights above it. The others are summed as `DiscreteDistribution::new` sums them
        // (in f64, negatives as zero). Several environments share their half by their mean
        // radiance.
        let environments: Vec<(usize, f32)> = lights
            .iter()
            .enumerate()
            .filter_map(|(i, light)| Some((i, light.environment_power()?)))
            .filter(|(_, power)| *power > 0.0)
            .collect();
        let others: f64 = powers.iter().map(|&p| p.max(0.0) as f64).sum();
        let share = if others > 0.0 { others as f32 } else { 1.0 };
        let sum: f32 = environments.iter().map(|(_, p)| p).sum();
        for &(i, power) in &environments {
            powers[i] = if environments.len() == 1 { share } else { share * (power / sum) };
        }
        let infinite =
            (0..lights.len() as u32).filter(|&i| lights[i as usize].is_infinite()).collect();
        LightSet {
            lights,
            lane_lights: Vec::new(),
            distribution: DiscreteDistribution::new(&powers),
            triangle_light,
            infinite,
        }
        .with_lane_lights()
    }

    /// The lights' records for the lanes ([`Emitter::lane_light`]).
    fn with_lane_lights(mut self) -> LightSet {
        self.lane_lights = self.lights.iter().map(Emitter::lane_light).collect();
        self
    }

    /// The same lights, with triangle lights sampled as `sampling` says.
    pub fn with_triangle_sampling(mut self, sampling: TriangleSampling) -> LightSet {
        for light in &mut self.lights {
            if let Emitter::Triangle(triangle) = light {
                triangle.sampling = sampling;
            }
        }
        self.with_lane_lights()
    }

    /// The same lights, with directions toward environment maps chosen as `sampling` says.
    pub fn with_environment_sampling(mut self, sampling: EnvironmentSampling) -> LightSet {
        for light in &mut self.lights {
            if let Emitter::EnvironmentMap(map) = light {
                map.sampling = sampling;
            }
        }
        self
    }

    /// Moves the first point light to `position` (as `raylab view` moves the light); nothing
    /// without a point light.
    pub fn move_first_point_light(&mut self, position: Vec3) {
        if let Some(Emitter::Point(light)) =
            self.lights.iter_mut().find(|l| matches!(l, Emitter::Point(_)))
        {
            light.position = position;
        }
    }

    /// The number of lights (each emissive triangle counts as one).
    pub fn len(&self) -> usize {
        self.lights.len()
    }

    /// Whether the scene has no light at all.
    pub fn is_empty(&self) -> bool {
        self.distribution.is_none()
    }

    /// The lights, in the order the set numbers them.
    pub fn lights(&self) -> &[Emitter] {
        &self.lights
    }

    /// The light that `u.x` picks, its probability, and `u` with `u.x` rescaled to `[0, 1)`
    /// within the light's share, to pick the point on it.
    ///
    /// One pair of numbers does both, as Mitsuba's `Scene::sample_emitter_direction` does: the
    /// pairs that fall to a light are a stretched strip of the sampler's stratified pairs, so each
    /// light's points stay stratified, where a separate number for the choice would scatter a
    /// random subset of the pairs onto each light. The price: a light of tiny probability `p`
    /// sees its first number in steps of about `2⁻²⁴/p` (Mitsuba's too), which stratification,
    /// not resolution, matters for here.
    #[inline]
    fn pick(&self, u: Vec2) -> Option<(usize, f32, Vec2)> {
        let (index, selection, x) = self.distribution.as_ref()?.sample(u.x);
        Some((index, selection, Vec2::new(x, u.y)))
    }

    /// Picks a light and a point on it with `u`, as seen from `point`: `u.x` picks the light and,
    /// rescaled to `[0, 1)` within the light's share, places the point with `u.y` (Mitsuba's
    /// emitter sampling; each light's points stay stratified). The density is the light's
    /// times the probability of having picked it. `None` when there is nothing to sample or the
    /// point sees the light's back or nothing of it.
    #[inline]
    pub fn sample(&self, point: &SurfacePoint, u: Vec2) -> Option<LightSample> {
        let (index, selection, u) = self.pick(u)?;
        let mut sample = self.lights[index].sample(point, u)?;
        sample.pdf *= selection;
        Some(sample)
    }

    /// [`sample`](Self::sample) for each point and pair of numbers (at most
    /// [`SEARCH_LANES`]), to the bit: the environment maps sampled by importance have their
    /// picks made together ([`EnvironmentMap::sample_each`](crate::light::EnvironmentMap)), so
    /// that their searches' loads overlap.
    ///
    /// # Panics
    /// If the slices differ in length or hold more than `SEARCH_LANES`.
    pub fn sample_each(
        &self,
        points: &[SurfacePoint],
        us: &[Vec2],
        out: &mut [Option<LightSample>],
    ) {
        let lanes = us.len();
        assert!(lanes <= SEARCH_LANES && points.len() == lanes && out.len() == lanes);
        // The lanes that picked a map by importance: (lane, light, selection, numbers).
        let mut maps = [(0usize, 0usize, 0.0f32, Vec2::ZERO); SEARCH_LANES];
        let mut count = 0;
        for (l, slot) in out.iter_mut().enumerate() {
            *slot = None;
            let Some((index, selection, u)) = self.pick(us[l]) else { continue };
            match &self.lights[index] {
                Emitter::EnvironmentMap(map) if map.sampling == EnvironmentSampling::Importance => {
                    maps[count] = (l, index, selection, u);
                    count += 1;
                }
                light => {
                    *slot = light.sample(&points[l], u).map(|mut sample| {
                        sample.pdf *= selection;
                        sample
                    })
                }
            }
        }
        // One map at a time (a scene has one, as a rule).
        let mut done = [false; SEARCH_LANES];
        for first in 0..count {
            if done[first] {
                continue;
            }
            let index = maps[first].1;
            let Emitter::EnvironmentMap(light) = &self.lights[index] else {
                unreachable!("maps holds environment maps");
            };
            let (mut these, mut numbers) = ([0usize; SEARCH_LANES], [Vec2::ZERO; SEARCH_LANES]);
            let mut n = 0;
            for (j, &(_, i, _, u)) in maps[..count].iter().enumerate() {
                if i == index {
                    (these[n], numbers[n]) = (j, u);
                    done[j] = true;
                    n += 1;
                }
            }
            let mut samples = [None; SEARCH_LANES];
            light.map.sample_each(&numbers[..n], &mut samples[..n]);
            for (&j, sample) in these[..n].iter().zip(samples) {
                let (l, _, selection, _) = maps[j];
                out[l] = sample.map(|sample| {
                    let mut sample = sample.seen_from(&points[l]);
                    sample.pdf *= selection;
                    sample
                });
            }
        }
    }

    /// The light that `u.x` picks ([`pick`](Self::pick)), as the wavefront's lanes take it
    /// ([`Emitter::lane_light`]), with the probability of having picked it and where its share
    /// of `u.x` starts (the lanes rescale `u.x` with
    /// [`rescaled`](crate::sampling::rescaled)); nothing, without lights.
    #[inline(always)]
    pub(super) fn pick_for_lanes(&self, u: Vec2) -> LanePick<'_> {
        let Some(distribution) = &self.distribution else {
            return LanePick { light: &NO_LIGHT, selection: 0.0, start: 0.0 };
        };
        let (index, selection, start) = distribution.pick(u.x);
        LanePick { light: &self.lane_lights[index], selection, start }
    }

    /// What a ray from `origin` (the previous path vertex's point) sees at `hit` on an emissive
    /// triangle: its radiance, and the density with which [`sample`](Self::sample) would have
    /// chosen that direction from `origin`; [`Emission::NONE`] for a triangle that does not
    /// emit or is seen from behind.
    #[inline]
    pub fn emitted(&self, origin: Vec3, hit: &SurfaceInteraction) -> Emission {
        // `plain_surface` in `wavefront/surface.rs` relies on this: only the triangles of lights emit.
        let light = self.triangle_light[hit.triangle as usize];
        if light == u32::MAX {
            return Emission::NONE;
        }
        let Emitter::Triangle(triangle) = &self.lights[light as usize] else {
            unreachable!("triangle_light indexes triangle lights");
        };
        let emission = triangle.eval_pdf(origin, hit);
        let selection = self.distribution.as_ref().map_or(0.0, |d| d.pmf(light as usize));
        Emission { radiance: emission.radiance, pdf: selection * emission.pdf }
    }

    /// [`escaped`](Self::escaped) for each of `directions` (unit): `found(lane, emission)` for
    /// each infinite light, in the set's order, that sends some along `directions[lane]`; each
    /// lane's finds come in the order `escaped` gives them. `scratch` holds a lane's emission
    /// (its length is the lanes').
    ///
    /// # Panics
    /// If `scratch` and `directions` differ in length.
    #[inline]
    pub fn escaped_each(
        &self,
        directions: &[Vec3],
        scratch: &mut [Emission],
        mut found: impl FnMut(usize, Emission),
    ) {
        for &index in &self.infinite {
            self.lights[index as usize].escaped_each(directions, scratch);
            let selection = self.distribution.as_ref().map_or(0.0, |d| d.pmf(index as usize));
            for (lane, emission) in scratch.iter().enumerate() {
                if emission.radiance != Vec3::ZERO {
                    found(
                        lane,
                        Emission { radiance: emission.radiance, pdf: selection * emission.pdf },
                    );
                }
            }
        }
    }

    /// Whether triangle `i` is (part of) a light: the only triangles [`emitted`](Self::emitted)
    /// finds light on.
    #[inline]
    pub fn is_light_triangle(&self, i: u32) -> bool {
        self.triangle_light[i as usize] != u32::MAX
    }

    /// The light a ray leaving the scene along the unit `direction` finds: `found` of each
    /// infinite light (environment, environment map, sun) that sends some along it, with the
    /// density with which [`sample`](Self::sample) would have chosen that direction toward it
    /// (for the caller's MIS weight).
    #[inline]
    pub fn escaped(&self, direction: Vec3, mut found: impl FnMut(Emission)) {
        for &index in &self.infinite {
            let emission = self.lights[index as usize].escaped(direction);
            if emission.radiance != Vec3::ZERO {
                let selection = self.distribution.as_ref().map_or(0.0, |d| d.pmf(index as usize));
                found(Emission { radiance: emission.radiance, pdf: selection * emission.pdf });
            }
        }
    }
}

#[cfg(test)]
mod tests;
