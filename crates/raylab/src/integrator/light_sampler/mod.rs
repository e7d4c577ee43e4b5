//! Light sampling for the path tracer: every light of a scene in one set, chosen by power, the
//! environments half the time beside other lights.
//!
//! [`LightSet`] gathers the scene's point, spot and directional lights, suns, its emissive
//! triangles (area lights) and its environments (constant or mapped), picks one in proportion to
//! its power (the environments, unless black, half the time when there are other lights), and
//! samples a direction toward it with its density per unit solid angle (next-event
//! estimation). A ray that leaves the scene finds the infinite lights (environments and suns)
//! with their densities, for multiple importance sampling ([`LightSet::escaped`]). One pair of numbers picks the light (its first
//! number, rescaled within the light's share) and the point on it, as in Mitsuba. A material's
//! emission texture makes a triangle shine in a pattern: its radiance is read at the sampled
//! point (and where a ray hits it), and its power for choosing among lights is the texture's
//! mean over the triangle, estimated on a grid.

use std::f32::consts::PI;
use std::sync::Arc;

use glam::{Vec2, Vec3};

use crate::interaction::SurfaceInteraction;
use crate::light::{EnvironmentMap, Light, SpotLight, SunLight};
use crate::ray::{Ray, SurfacePoint, offset_ray_origin};
use crate::sampling::{
    DiscreteDistribution, sample_spherical_triangle, spherical_triangle_area,
    square_to_uniform_sphere, square_to_uniform_triangle, uniform_sphere_pdf,
};
use crate::scene::Scene;
use crate::texture::{Texture, TextureQuery};
use crate::unknown_name::UnknownName;

/// Every light of a scene, ready to be sampled: point lights, the emissive triangles (area
/// lights) and the environment, chosen by power (the environment half the time beside others).
///
/// A triangle light is one-sided, as Mitsuba's `area` emitter: it emits its material's
/// `emission` from its front (counter-clockwise) side only. Points on it are sampled uniformly by
/// area and their density converted to solid angle at the shading point.
#[derive(Clone, Debug)]
pub struct LightSet {
    lights: Vec<SampledLight>,
    /// Each light as the lanes take it ([`pick_for_lanes`](Self::pick_for_lanes)).
    lane_lights: Vec<LaneLight>,
    /// By power, the environment's share apart; `None` without lights.
    distribution: Option<DiscreteDistribution>,
    /// For each triangle, the index of its light, or `u32::MAX`.
    triangle_light: Vec<u32>,
    /// The lights that rays leaving the scene find: environments and suns.
    infinite: Vec<u32>,
    /// How points on triangle lights are chosen.
    triangle_sampling: TriangleSampling,
    /// How directions toward environment maps are chosen.
    environment_sampling: EnvironmentSampling,
    /// The emission texture of each textured triangle light, with the texture coordinates at
    /// its corners ([`TriangleLight::texture`] indexes it).
    textures: Vec<(Texture, [Vec2; 3])>,
}

/// How points on triangle lights are chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "io", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "io", serde(rename_all = "kebab-case"))]
pub enum TriangleSampling {
    /// Uniformly by area (Mitsuba's choice): simple, noisy for large lights close by.
    #[default]
    Area,
    /// Uniformly in the solid angle the triangle subtends (Arvo 1995), where that is neither
    /// tiny nor nearly a hemisphere (PBR 4th ed.'s bounds); by area elsewhere.
    SolidAngle,
}

impl std::str::FromStr for TriangleSampling {
    type Err = UnknownName;
    fn from_str(s: &str) -> Result<Self, UnknownName> {
        match s {
            "area" => Ok(TriangleSampling::Area),
            "solid-angle" => Ok(TriangleSampling::SolidAngle),
            _ => Err(UnknownName::new("light sampling", s, "area or solid-angle")),
        }
    }
}

/// How directions toward an environment map are chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum EnvironmentSampling {
    /// In proportion to its luminance ([`EnvironmentMap::sample`]): what renders use.
    #[default]
    Importance,
    /// Uniformly over the sphere, whatever the map holds: only to measure what importance
    /// sampling is worth.
    Uniform,
}

/// Solid angles within which triangle lights are sampled by solid angle (PBR 4th ed.,
/// `MinSphericalSampleArea` and `MaxSphericalSampleArea`).
const SOLID_ANGLE_SAMPLING: std::ops::Range<f32> = 3e-4..6.22;

#[derive(Clone, Debug)]
enum SampledLight {
    Point {
        position: Vec3,
        intensity: Vec3,
    },
    Triangle(TriangleLight),
    Environment {
        radiance: Vec3,
    },
    EnvironmentMap(Arc<EnvironmentMap>),
    /// `toward`: the unit direction toward the light (against the way its light travels).
    Directional {
        toward: Vec3,
        irradiance: Vec3,
    },
    Spot(SpotLight),
    Sun(SunLight),
}

/// An emitting triangle. `texture`: an index into [`LightSet::textures`], or `u32::MAX` for an
/// even emitter; `error`: a bound on the rounding of its points
/// ([`Geometry::point_error_bound`]).
///
/// [`Geometry::point_error_bound`]: crate::geometry::Geometry::point_error_bound
#[derive(Clone, Debug)]
pub(super) struct TriangleLight {
    pub corners: [Vec3; 3],
    pub normal: Vec3,
    pub error: Vec3,
    pub area: f32,
    pub radiance: Vec3,
    pub texture: u32,
}

/// A point sampled on a light, seen from a shading point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// The unit direction from the shading point toward the light.
    pub direction: Vec3,
    /// The radiance arriving from it (unoccluded).
    pub radiance: Vec3,
    /// The density per unit solid angle of this direction, times the light's selection
    /// probability; for a point light, just that probability.
    pub pdf: f32,
    /// A point light: no other strategy can find it.
    pub delta: bool,
    /// The ray to test visibility with (from the shading point, ending just before the light).
    pub shadow_ray: Ray,
}

/// How the lanes take a light ([`LaneLight::role`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) enum LaneRole {
    /// No light: nothing to sample.
    #[default]
    Nothing,
    /// A triangle the lanes sample uniformly by area, with a constant radiance.
    Triangle,
    /// The constant environment, which the lanes sample by [`square_to_uniform_sphere`].
    Environment,
    /// A light the lanes leave to [`LightSet::sample`].
    Other,
}

/// A light as the lanes copy it into their rows, whatever its kind: a triangle's corners,
/// normal, rounding bound, area and radiance; the environment's radiance (its other fields
/// zero); and its role. One record for every kind, so that a lane takes its light without a
/// branch on the kind: the lights a chunk's lanes pick are random, and where they are of
/// several kinds a branch on each lane's kind goes the wrong way often (in the materials
/// scene, an area light and the environment each picked about half the time, it took a fifth
/// of `shade_lanes`).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct LaneLight {
    pub corners: [Vec3; 3],
    pub normal: Vec3,
    pub error: Vec3,
    pub area: f32,
    pub radiance: Vec3,
    pub role: LaneRole,
}

/// No light, for [`LightSet::pick_for_lanes`] without lights.
static NO_LIGHT: LaneLight = LaneLight {
    corners: [Vec3::ZERO; 3],
    normal: Vec3::ZERO,
    error: Vec3::ZERO,
    area: 0.0,
    radiance: Vec3::ZERO,
    role: LaneRole::Nothing,
};

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

/// The fraction of a shadow ray toward a point on a surface light that is tested: the rest
/// (a relative 10⁻⁴) keeps the light's own triangle out of the test (PBR 4th ed.'s
/// `ShadowEpsilon`).
pub(super) const SHADOW_RAY_LENGTH: f32 = 1.0 - 1e-4;

impl LightSet {
    /// The lights of `scene`.
    pub fn new(scene: &Scene) -> LightSet {
        let mut lights = Vec::new();
        let mut triangle_light = vec![u32::MAX; scene.geometry.len()];
        let mut environment = None;
        for light in &scene.lights {
            match light {
                Light::EnvironmentMap(map) => {
                    lights.push(SampledLight::EnvironmentMap(map.clone()))
                }
                Light::Directional(light) => lights.push(SampledLight::Directional {
                    toward: -light.direction.normalize_or_zero(),
                    irradiance: light.irradiance,
                }),
                Light::Spot(spot) => lights.push(SampledLight::Spot(*spot)),
                Light::Sun(sun) => lights.push(SampledLight::Sun(*sun)),
                Light::Point(point) => lights.push(SampledLight::Point {
                    position: point.position,
                    intensity: point.intensity(),
                }),
                // Several environments shine as one: their radiances add.
                Light::Environment { radiance } => match environment {
                    Some((sum, index)) => {
                        let sum = sum + *radiance;
                        environment = Some((sum, index));
                        lights[index as usize] = SampledLight::Environment { radiance: sum };
                    }
                    None => {
                        environment = Some((*radiance, lights.len() as u32));
                        lights.push(SampledLight::Environment { radiance: *radiance });
                    }
                },
            }
        }
        let mut textures = Vec::new();
        let mut texture_means = Vec::new();
        for (i, slot) in triangle_light.iter_mut().enumerate() {
            let material = &scene.materials[scene.geometry.material_id(i) as usize];
            let area = scene.geometry.area(i);
            if material.is_emissive() && area > 0.0 {
                *slot = lights.len() as u32;
                let corners = scene.geometry.triangle(i);
                let texture = match &material.textures.emission {
                    None => u32::MAX,
                    Some(texture) => {
                        let uvs = scene.geometry.corner_uvs(i);
                        texture_means.push(mean_over(texture, material.emission, corners, uvs));
                        textures.push((texture.clone(), uvs));
                        textures.len() as u32 - 1
                    }
                };
                lights.push(SampledLight::Triangle(TriangleLight {
                    corners,
                    normal: scene.geometry.normal(i),
                    error: scene.geometry.point_error_bound(i),
                    area,
                    radiance: material.emission,
                    texture,
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
        let mut powers: Vec<f32> = lights
            .iter()
            .map(|light| match light {
                SampledLight::Point { intensity, .. } => 4.0 * PI * mean(*intensity),
                SampledLight::Triangle(TriangleLight { area, radiance, texture, .. }) => {
                    let textured = texture_means.get(*texture as usize).copied();
                    PI * area * textured.unwrap_or_else(|| mean(*radiance))
                }
                SampledLight::Directional { irradiance, .. } => through_scene * mean(*irradiance),
                SampledLight::Sun(sun) => through_scene * mean(sun.irradiance()),
                SampledLight::Spot(spot) => spot.power(),
                SampledLight::Environment { .. } | SampledLight::EnvironmentMap(_) => 0.0,
            })
            .map(|power: f32| power.min(1e30))
            .collect();
        // The environments are picked half the time when there are other lights, and always
        // without (pbrt-v4's `BVHLightSampler`, Mitsuba's uniform choice among two emitters); a
        // black one never. Their power through a disk the size of the scene (PBR 4th ed. §12.5)
        // ranks them by the floor around the scene's subject, so on the materials scene
        // (`tests/data/mitsuba-materials`) it took most picks from the light above the spheres
        // and gave more error than picking the environments half the time. The others
        // are summed as `DiscreteDistribution::new` sums them (in f64, negatives as zero). Several
        // environments share their half by their mean radiance.
        let environments: Vec<(usize, f32)> = lights
            .iter()
            .enumerate()
            .filter_map(|(i, light)| match light {
                SampledLight::Environment { radiance } => Some((i, mean(*radiance))),
                SampledLight::EnvironmentMap(map) => Some((i, mean(map.mean()))),
                _ => None,
            })
            .filter(|(_, power)| *power > 0.0)
            .collect();
        let others: f64 = powers.iter().map(|&p| p.max(0.0) as f64).sum();
        let share = if others > 0.0 { others as f32 } else { 1.0 };
        let sum: f32 = environments.iter().map(|(_, p)| p).sum();
        for &(i, power) in &environments {
            powers[i] = if environments.len() == 1 { share } else { share * (power / sum) };
        }
        let infinite = (0..lights.len() as u32)
            .filter(|&i| {
                matches!(
                    lights[i as usize],
                    SampledLight::Environment { .. }
                        | SampledLight::EnvironmentMap(_)
                        | SampledLight::Sun(_)
                )
            })
            .collect();
        LightSet {
            lights,
            lane_lights: Vec::new(),
            distribution: DiscreteDistribution::new(&powers),
            triangle_light,
            infinite,
            triangle_sampling: TriangleSampling::Area,
            environment_sampling: EnvironmentSampling::Importance,
            textures,
        }
        .with_lane_lights()
    }

    /// The lights' records for the lanes ([`LaneLight`]), as the triangle sampling says.
    fn with_lane_lights(mut self) -> LightSet {
        let lane_light = |light: &SampledLight| match light {
            SampledLight::Triangle(light)
                if self.triangle_sampling == TriangleSampling::Area
                    && self.textures.get(light.texture as usize).is_none() =>
            {
                LaneLight {
                    corners: light.corners,
                    normal: light.normal,
                    error: light.error,
                    area: light.area,
                    radiance: light.radiance,
                    role: LaneRole::Triangle,
                }
            }
            SampledLight::Environment { radiance } => LaneLight {
                radiance: *radiance,
                role: LaneRole::Environment,
                ..LaneLight::default()
            },
            _ => LaneLight { role: LaneRole::Other, ..LaneLight::default() },
        };
        self.lane_lights = self.lights.iter().map(lane_light).collect();
        self
    }

    /// A triangle light's radiance at barycentrics `(b1, b2)`, point `p`: `radiance` times its
    /// texture there, if it has one.
    #[inline]
    fn radiance_at(&self, radiance: Vec3, texture: u32, (b1, b2): (f32, f32), p: Vec3) -> Vec3 {
        let Some((texture, [t0, t1, t2])) = self.textures.get(texture as usize) else {
            return radiance;
        };
        let uv = (1.0 - b1 - b2) * *t0 + b1 * *t1 + b2 * *t2;
        radiance * texture.rgb(&TextureQuery { uv, p, footprint: 0.0 }).max(Vec3::ZERO)
    }

    /// The same lights, with triangle lights sampled as `sampling` says.
    pub fn with_triangle_sampling(mut self, sampling: TriangleSampling) -> LightSet {
        self.triangle_sampling = sampling;
        self.with_lane_lights()
    }

    /// The same lights, with directions toward environment maps chosen as `sampling` says.
    pub fn with_environment_sampling(mut self, sampling: EnvironmentSampling) -> LightSet {
        self.environment_sampling = sampling;
        self
    }

    /// A direction toward `map` that `u` picks, the radiance arriving along it and its density
    /// (as [`environment_sampling`](Self::with_environment_sampling) says).
    #[inline]
    fn sample_map(&self, map: &EnvironmentMap, u: Vec2) -> Option<(Vec3, Vec3, f32)> {
        match self.environment_sampling {
            EnvironmentSampling::Importance => map.sample(u),
            EnvironmentSampling::Uniform => {
                let direction = square_to_uniform_sphere(u);
                Some((direction, map.eval(direction), uniform_sphere_pdf(direction)))
            }
        }
    }

    /// The radiance arriving from `map` along `direction` and the density with which
    /// [`sample_map`](Self::sample_map) picks that direction.
    #[inline]
    fn map_eval_pdf(&self, map: &EnvironmentMap, direction: Vec3) -> (Vec3, f32) {
        match self.environment_sampling {
            EnvironmentSampling::Importance => map.eval_pdf(direction),
            EnvironmentSampling::Uniform => (map.eval(direction), uniform_sphere_pdf(direction)),
        }
    }

    /// The solid angle of a triangle light seen from `p`, when it is sampled by solid angle.
    #[inline]
    fn solid_angle(&self, corners: [Vec3; 3], p: Vec3) -> Option<f32> {
        if self.triangle_sampling == TriangleSampling::Area {
            return None;
        }
        let omega = spherical_triangle_area(corners, p);
        SOLID_ANGLE_SAMPLING.contains(&omega).then_some(omega)
    }

    /// Moves the first point light to `position` (as `raylab view` moves the light); nothing
    /// without a point light.
    pub fn move_first_point_light(&mut self, position: Vec3) {
        if let Some(SampledLight::Point { position: at, .. }) =
            self.lights.iter_mut().find(|l| matches!(l, SampledLight::Point { .. }))
        {
            *at = position;
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

    /// The light that `u.x` picks, its probability, and `u` with `u.x` rescaled to `[0, 1)`
    /// within the light's share, to pick the point on it.
    ///
    /// One pair of numbers does both, as Mitsuba's `Scene::sample_emitter_direction` does: the
    /// pairs that fall to a light are a stretched strip of the sampler's stratified pairs, so each
    /// light's points stay stratified. A separate number for the choice scatters a random subset
    /// of the pairs onto each light; on the materials scene (an area light and the environment,
    /// `tests/data/mitsuba-materials`) it had 8 % more RMSE at 64 spp (0.0128 against 0.0118).
    /// The price: a light of tiny probability `p` sees its first number in steps of about
    /// `2⁻²⁴/p` (Mitsuba's too), which stratification, not resolution, matters for here.
    #[inline]
    fn pick(&self, u: Vec2) -> Option<(usize, f32, Vec2)> {
        let (index, selection, x) = self.distribution.as_ref()?.sample(u.x);
        Some((index, selection, Vec2::new(x, u.y)))
    }

    /// Picks a light and a point on it with `u`, as seen from `point`: `u.x` picks the light and,
    /// rescaled to `[0, 1)` within the light's share, places the point with `u.y` (Mitsuba's
    /// emitter sampling; each light's points stay stratified). `None` when there is nothing to
    /// sample or the point sees the light's back or nothing of it.
    #[inline]
    pub fn sample(&self, point: &SurfacePoint, u: Vec2) -> Option<LightSample> {
        let (index, selection, u) = self.pick(u)?;
        match self.lights[index] {
            SampledLight::Point { position, intensity } => {
                let to_light = position - point.p;
                let distance_squared = to_light.length_squared();
                if distance_squared == 0.0 {
                    return None;
                }
                Some(LightSample {
                    direction: to_light / distance_squared.sqrt(),
                    radiance: intensity / distance_squared,
                    pdf: selection,
                    delta: true,
                    shadow_ray: point.spawn_ray_to(position),
                })
            }
            SampledLight::Triangle(TriangleLight {
                corners,
                normal,
                error,
                area,
                radiance,
                texture,
            }) => {
                let [v0, v1, v2] = corners;
                let solid_angle = self.solid_angle(corners, point.p);
                let ([b0, b1, b2], solid_angle_pdf) = match solid_angle {
                    Some(_) => sample_spherical_triangle(corners, point.p, u)?,
                    None => (square_to_uniform_triangle(u), 0.0),
                };
                let target = b0 * v0 + b1 * v1 + b2 * v2;
                let to_light = target - point.p;
                let distance_squared = to_light.length_squared();
                let direction = to_light / distance_squared.sqrt();
                // One-sided: the light must face the point.
                let cos_light = -direction.dot(normal);
                if cos_light <= 0.0 || !distance_squared.is_normal() {
                    return None;
                }
                // Both ends leave their surfaces (PBR 4th ed.'s `SpawnRayTo` between two
                // surface points): the light's end by its own rounding bound, which for an
                // instance far from where it is stored can outgrow the relative shortening.
                let end = SurfacePoint { p: target, error, normal };
                let mut shadow_ray = point.spawn_ray_to(offset_ray_origin(&end, point.p - target));
                shadow_ray.t_max = SHADOW_RAY_LENGTH;
                let pdf = match solid_angle {
                    Some(_) => solid_angle_pdf,
                    None => distance_squared / (cos_light * area),
                };
                Some(LightSample {
                    direction,
                    radiance: self.radiance_at(radiance, texture, (b1, b2), target),
                    pdf: selection * pdf,
                    delta: false,
                    shadow_ray,
                })
            }
            SampledLight::Environment { radiance } => {
                let direction = square_to_uniform_sphere(u);
                Some(LightSample {
                    direction,
                    radiance,
                    pdf: selection * uniform_sphere_pdf(direction),
                    delta: false,
                    shadow_ray: point.spawn_ray(direction),
                })
            }
            SampledLight::EnvironmentMap(ref map) => {
                let (direction, radiance, pdf) = self.sample_map(map, u)?;
                Some(LightSample {
                    direction,
                    radiance,
                    pdf: selection * pdf,
                    delta: false,
                    shadow_ray: point.spawn_ray(direction),
                })
            }
            SampledLight::Sun(sun) => {
                let (direction, pdf) = sun.sample(u);
                Some(LightSample {
                    direction,
                    radiance: sun.radiance(),
                    pdf: selection * pdf,
                    delta: false,
                    shadow_ray: point.spawn_ray(direction),
                })
            }
            SampledLight::Directional { toward, irradiance } => Some(LightSample {
                direction: toward,
                radiance: irradiance,
                pdf: selection,
                delta: true,
                shadow_ray: point.spawn_ray(toward),
            }),
            SampledLight::Spot(spot) => {
                let to_light = spot.position() - point.p;
                let distance_squared = to_light.length_squared();
                if distance_squared == 0.0 {
                    return None;
                }
                let direction = to_light / distance_squared.sqrt();
                let intensity = spot.intensity_toward(-direction);
                if intensity == Vec3::ZERO {
                    return None;
                }
                Some(LightSample {
                    direction,
                    radiance: intensity / distance_squared,
                    pdf: selection,
                    delta: true,
                    shadow_ray: point.spawn_ray_to(spot.position()),
                })
            }
        }
    }

    /// The light that `u.x` picks ([`pick`](Self::pick)), as the wavefront's lanes take it: a
    /// triangle sampled uniformly by area with a constant radiance, or the constant environment,
    /// which the lanes sample as [`sample`](Self::sample) does (`u.x` rescaled in lanes by
    /// [`rescaled`](crate::sampling::rescaled) of the light's `start` and `selection`); any
    /// other light, which a lane leaves to `sample`; or nothing, without lights.
    #[inline(always)]
    pub(super) fn pick_for_lanes(&self, u: Vec2) -> LanePick<'_> {
        let Some(distribution) = &self.distribution else {
            return LanePick { light: &NO_LIGHT, selection: 0.0, start: 0.0 };
        };
        let (index, selection, start) = distribution.pick(u.x);
        LanePick { light: &self.lane_lights[index], selection, start }
    }

    /// The radiance a ray from `origin` (the previous path vertex's point) sees at `hit` on an
    /// emissive triangle, and the density with which [`sample`](Self::sample) would have chosen
    /// that direction from `origin`; zero and zero for a triangle that does not emit or is seen
    /// from behind.
    #[inline]
    pub fn emitted(&self, origin: Vec3, hit: &SurfaceInteraction) -> (Vec3, f32) {
        // `plain_surface` in `wavefront/surface.rs` relies on this: only the triangles of lights emit.
        let light = self.triangle_light[hit.triangle as usize];
        if light == u32::MAX {
            return (Vec3::ZERO, 0.0);
        }
        let SampledLight::Triangle(TriangleLight {
            corners, normal, area, radiance, texture, ..
        }) = self.lights[light as usize]
        else {
            unreachable!("triangle_light indexes triangle lights");
        };
        let to_light = hit.point.p - origin;
        let distance_squared = to_light.length_squared();
        let cos_light = -to_light.dot(normal) / distance_squared.sqrt();
        if cos_light <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        let selection = self.distribution.as_ref().map_or(0.0, |d| d.pmf(light as usize));
        let pdf = match self.solid_angle(corners, origin) {
            Some(omega) => 1.0 / omega,
            None => distance_squared / (cos_light * area),
        };
        let radiance = match self.textures.get(texture as usize) {
            None => radiance,
            Some((pattern, _)) => radiance * pattern.rgb(&hit.texture_query()).max(Vec3::ZERO),
        };
        (radiance, selection * pdf)
    }

    /// Whether triangle `i` is (part of) a light: the only triangles [`emitted`](Self::emitted)
    /// finds light on.
    #[inline]
    pub fn is_light_triangle(&self, i: u32) -> bool {
        self.triangle_light[i as usize] != u32::MAX
    }

    /// The light a ray leaving the scene along the unit `direction` finds: `found(radiance,
    /// pdf)` for each infinite light (environment, environment map, sun) that sends some along
    /// it, with the density with which [`sample`](Self::sample) would have chosen that
    /// direction toward it (for the caller's MIS weight).
    #[inline]
    pub fn escaped(&self, direction: Vec3, mut found: impl FnMut(Vec3, f32)) {
        for &index in &self.infinite {
            let selection = || self.distribution.as_ref().map_or(0.0, |d| d.pmf(index as usize));
            let (radiance, pdf) = match &self.lights[index as usize] {
                SampledLight::Environment { radiance } => {
                    (*radiance, selection() * uniform_sphere_pdf(direction))
                }
                SampledLight::EnvironmentMap(map) => {
                    let (radiance, pdf) = self.map_eval_pdf(map, direction);
                    if radiance == Vec3::ZERO {
                        continue;
                    }
                    (radiance, selection() * pdf)
                }
                SampledLight::Sun(sun) => {
                    if !sun.sees(direction) {
                        continue;
                    }
                    (sun.radiance(), selection() * sun.pdf(direction))
                }
                _ => unreachable!("infinite indexes environments and suns"),
            };
            if radiance != Vec3::ZERO {
                found(radiance, pdf);
            }
        }
    }
}

/// The mean of a colour's channels.
#[inline]
fn mean(c: Vec3) -> f32 {
    c.element_sum() / 3.0
}

/// The mean of `radiance` times a texture over a triangle (the mean of its channels): the
/// power estimate that picks among lights. The texture is read at the centres of the 64
/// triangles of an 8 × 8 subdivision, each through a footprint as wide as one of them (a
/// mip-mapped image averages over it, so a small bright spot between centres still counts),
/// and the estimate is kept above 1% of the untextured power, so that an emitter the grid
/// misses is still sampled now and then (the choice among lights only steers samples: any
/// positive power leaves the estimate unbiased).
fn mean_over(texture: &Texture, radiance: Vec3, corners: [Vec3; 3], uvs: [Vec2; 3]) -> f32 {
    const N: u32 = 8;
    let uv_area = 0.5 * (uvs[1] - uvs[0]).perp_dot(uvs[2] - uvs[0]).abs();
    let footprint = (2.0 * uv_area).sqrt() / N as f32;
    let mut sum = 0.0;
    let mut read = |b1: f32, b2: f32| {
        let b0 = 1.0 - b1 - b2;
        let uv = b0 * uvs[0] + b1 * uvs[1] + b2 * uvs[2];
        let p = b0 * corners[0] + b1 * corners[1] + b2 * corners[2];
        let value = texture.rgb(&TextureQuery { uv, p, footprint }).max(Vec3::ZERO);
        sum += mean(radiance * value);
    };
    // Cell (i, j) of the subdivision: its upright triangle's centre, and where it has one,
    // its inverted neighbour's.
    let n = N as f32;
    for i in 0..N {
        for j in 0..N - i {
            let (i, j) = (i as f32, j as f32);
            read((i + 1.0 / 3.0) / n, (j + 1.0 / 3.0) / n);
            if i + j + 2.0 <= n {
                read((i + 2.0 / 3.0) / n, (j + 2.0 / 3.0) / n);
            }
        }
    }
    let estimate = sum / (N * N) as f32;
    let floor = 0.01 * mean(radiance);
    if estimate.is_finite() { estimate.max(floor) } else { floor }
}

#[cfg(test)]
mod tests;
