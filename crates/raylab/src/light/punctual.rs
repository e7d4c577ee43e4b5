//! Lights from one direction or one point: the lab's point light, Mitsuba 3's `directional`
//! and `spot`, glTF's spot profile, and a sun disc of physical size. Each samples the
//! direction toward it from a shading point (`sample`, with the shadow ray).
//!
//! - [`PointLight`]: an isotropic point of power `P`, radiant intensity `I = P/4π`. A delta
//!   light.
//! - [`DirectionalLight`]: parallel light of irradiance `E` (W/m² per channel on a surface
//!   facing it), travelling along `direction`, as Mitsuba's `directional`. A delta light: only
//!   light sampling finds it.
//! - [`SpotLight`]: a point of radiant intensity `I` (W/sr at the beam's centre) shining in a
//!   cone, as Mitsuba's `spot`: full intensity within `beam_width` of the axis, then falling
//!   linearly in angle to zero at `cutoff_angle` (`src/emitters/spot.cpp`, `falloff_curve`); or
//!   glTF's profile (`KHR_lights_punctual`'s recommended falloff), smooth in the cosine between
//!   the inner and outer cone angles. A delta light.
//! - [`SunLight`]: a disc of constant radiance `L` and angular radius `α`, infinitely far away.
//!   It gives a surface facing it the irradiance `E = L·π·sin²α`; sampled uniformly in the cone
//!   it subtends, it casts soft-edged shadows, and as `α → 0` with `E` fixed it becomes a
//!   directional light. Rays that leave the scene toward it see it.
//!
//! Tests: `light::punctual::tests` (the point light's falloff, the profiles at known angles,
//! the sun's irradiance) and
//! `sampling::tests` (chi-square of the cone).

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use super::sample::{DirectionSample, Emission, LightSample};
use crate::ray::SurfacePoint;
use crate::sampling::{orthonormal_basis, square_to_uniform_cone, uniform_cone_pdf};

/// An isotropic point light of power `P` (watts per channel).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    /// Where the light is.
    pub position: Vec3,
    /// Power `P` per colour channel.
    pub power: Vec3,
}

impl PointLight {
    /// The lab's light: at (0, −0.5, −0.7), power 14 in every channel.
    pub fn lab() -> Self {
        PointLight { position: Vec3::new(0.0, -0.5, -0.7), power: Vec3::splat(14.0) }
    }

    /// The radiant intensity `I = P/4π` (watts per steradian per channel).
    #[inline]
    pub fn intensity(&self) -> Vec3 {
        self.power / (4.0 * PI)
    }

    /// Power per unit area arriving at `point` on a surface with unit normal `normal`, ignoring
    /// occlusion. Lab eq. (27): `D = P·max(r̂·n̂, 0) / (4πr²)`.
    #[inline]
    pub fn direct(&self, point: Vec3, normal: Vec3) -> Vec3 {
        let to_light = self.position - point;
        let r2 = to_light.length_squared();
        if r2 == 0.0 {
            return Vec3::ZERO;
        }
        // max(r̂·n̂, 0)/(4πr²) = max(r·n, 0)/(4πr³): one square root and one division.
        let r_dot_n = to_light.dot(normal).max(0.0);
        self.power * (r_dot_n / (4.0 * PI * r2 * r2.sqrt()))
    }

    /// The light seen from `point`: `I/d²` along the direction toward it (a delta light, of
    /// density 1); `None` at the light itself.
    #[inline]
    pub fn sample(&self, point: &SurfacePoint) -> Option<LightSample> {
        let (direction, distance_squared) = toward(self.position, point)?;
        Some(LightSample {
            direction,
            radiance: self.intensity() / distance_squared,
            pdf: 1.0,
            delta: true,
            shadow_ray: point.spawn_ray_to(self.position),
        })
    }

    /// Its power, the mean of its channels, for choosing among lights: `4π Ī`.
    pub fn mean_power(&self) -> f32 {
        4.0 * PI * (self.intensity().element_sum() / 3.0)
    }
}

/// The unit direction from `point` toward a light at `position`, and the distance squared;
/// `None` at the light itself.
#[inline]
fn toward(position: Vec3, point: &SurfacePoint) -> Option<(Vec3, f32)> {
    let to_light = position - point.p;
    let distance_squared = to_light.length_squared();
    if distance_squared == 0.0 {
        return None;
    }
    Some((to_light / distance_squared.sqrt(), distance_squared))
}

/// Parallel light from infinitely far away, as Mitsuba 3's `directional`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectionalLight {
    /// The way the light travels (unit).
    pub direction: Vec3,
    /// The irradiance on a surface facing the light, per channel.
    pub irradiance: Vec3,
}

impl DirectionalLight {
    /// The light seen from `point`: its irradiance, from the direction it comes from (a delta
    /// light, of density 1).
    #[inline]
    pub fn sample(&self, point: &SurfacePoint) -> LightSample {
        let toward = -self.direction.normalize_or_zero();
        LightSample {
            direction: toward,
            radiance: self.irradiance,
            pdf: 1.0,
            delta: true,
            shadow_ray: point.spawn_ray(toward),
        }
    }

    /// Its power, the mean of its channels, for choosing among lights: its irradiance through
    /// a disk of area `through_scene` the size of the scene (PBR 4th ed. §12.5).
    pub fn power(&self, through_scene: f32) -> f32 {
        through_scene * (self.irradiance.element_sum() / 3.0)
    }
}

/// How a spot light's intensity falls off away from its axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpotProfile {
    /// Mitsuba 3's: full within the beam width, then linear in the angle to zero at the cutoff.
    Mitsuba,
    /// glTF's (`KHR_lights_punctual`): `t²` with `t` the cosine's place between the outer
    /// cone's (0) and the inner's (1), clamped.
    Gltf,
}

/// A point light shining in a cone (Mitsuba 3's `spot`, glTF's spot light).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotLight {
    position: Vec3,
    axis: Vec3,
    intensity: Vec3,
    cutoff: f32,
    beam_width: f32,
    cos_cutoff: f32,
    cos_beam_width: f32,
    profile: SpotProfile,
}

impl SpotLight {
    /// A spot at `position` shining along `axis` (any length but zero) with intensity
    /// `intensity` at the centre, full within `beam_width` radians of the axis and dark beyond
    /// `cutoff` radians (`0 ≤ beam_width ≤ cutoff ≤ π`; `None` otherwise), falling off between
    /// as `profile` says.
    pub fn new(
        position: Vec3,
        axis: Vec3,
        intensity: Vec3,
        cutoff: f32,
        beam_width: f32,
        profile: SpotProfile,
    ) -> Option<SpotLight> {
        let valid = (0.0..=PI).contains(&cutoff) && (0.0..=cutoff).contains(&beam_width);
        let axis = axis.try_normalize()?;
        valid.then(|| SpotLight {
            position,
            axis,
            intensity,
            cutoff,
            beam_width,
            cos_cutoff: cutoff.cos(),
            cos_beam_width: beam_width.cos(),
            profile,
        })
    }

    /// Where the light is.
    pub fn position(&self) -> Vec3 {
        self.position
    }

    /// The beam's axis (unit).
    pub fn axis(&self) -> Vec3 {
        self.axis
    }

    /// The intensity at the beam's centre.
    pub fn intensity(&self) -> Vec3 {
        self.intensity
    }

    /// The cutoff angle and the beam width, in radians.
    pub fn angles(&self) -> (f32, f32) {
        (self.cutoff, self.beam_width)
    }

    /// The profile.
    pub fn profile(&self) -> SpotProfile {
        self.profile
    }

    /// The same light moved to `position`.
    pub fn moved_to(self, position: Vec3) -> SpotLight {
        SpotLight { position, ..self }
    }

    /// The same light with intensity `intensity`.
    pub fn with_intensity(self, intensity: Vec3) -> SpotLight {
        SpotLight { intensity, ..self }
    }

    /// The fraction of the centre's intensity sent at `cos_theta` from the axis.
    #[inline]
    pub fn falloff(&self, cos_theta: f32) -> f32 {
        match self.profile {
            SpotProfile::Mitsuba => {
                if cos_theta <= self.cos_cutoff {
                    0.0
                } else if cos_theta >= self.cos_beam_width {
                    1.0
                } else {
                    let angle = cos_theta.clamp(-1.0, 1.0).acos();
                    ((self.cutoff - angle) / (self.cutoff - self.beam_width)).clamp(0.0, 1.0)
                }
            }
            SpotProfile::Gltf => {
                let scale = 1.0 / (self.cos_beam_width - self.cos_cutoff).max(0.001);
                let t = ((cos_theta - self.cos_cutoff) * scale).clamp(0.0, 1.0);
                t * t
            }
        }
    }

    /// The intensity sent along the unit `direction` (from the light).
    #[inline]
    pub fn intensity_toward(&self, direction: Vec3) -> Vec3 {
        self.intensity * self.falloff(self.axis.dot(direction))
    }

    /// The light seen from `point`: the intensity it sends that way over `d²` (a delta light,
    /// of density 1); `None` at the light itself and outside its cone.
    #[inline]
    pub fn sample(&self, point: &SurfacePoint) -> Option<LightSample> {
        let (direction, distance_squared) = toward(self.position, point)?;
        let intensity = self.intensity_toward(-direction);
        if intensity == Vec3::ZERO {
            return None;
        }
        Some(LightSample {
            direction,
            radiance: intensity / distance_squared,
            pdf: 1.0,
            delta: true,
            shadow_ray: point.spawn_ray_to(self.position),
        })
    }

    /// The power it sends, about: the centre's intensity over the solid angle of a cone half way
    /// between the beam width and the cutoff (pbrt-v4's `SpotLight::Phi`), averaged over the
    /// channels. For choosing among lights.
    pub fn power(&self) -> f32 {
        let solid_angle = 2.0 * PI * (1.0 - 0.5 * (self.cos_cutoff + self.cos_beam_width));
        self.intensity.element_sum() / 3.0 * solid_angle
    }
}

/// A disc of constant radiance infinitely far away: the sun, with soft shadows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunLight {
    direction: Vec3,
    angular_radius: f32,
    radiance: Vec3,
    one_minus_cos: f32,
}

impl SunLight {
    /// The sun's apparent diameter from the earth, in degrees (Mitsuba 3's `sun_aperture`).
    pub const EARTH_APERTURE_DEG: f32 = 0.5338;

    /// A disc of `radiance` and angular radius `angular_radius` (radians, in `(0, π/2]`;
    /// `None` otherwise) whose light travels along `direction` (any length but zero).
    pub fn new(direction: Vec3, angular_radius: f32, radiance: Vec3) -> Option<SunLight> {
        let direction = direction.try_normalize()?;
        let valid = angular_radius > 0.0 && angular_radius <= 0.5 * PI;
        // 1 − cos α without the cancellation of a small α.
        let one_minus_cos = 2.0 * (0.5 * angular_radius).sin().powi(2);
        valid.then_some(SunLight { direction, angular_radius, radiance, one_minus_cos })
    }

    /// [`new`](Self::new) with the radiance that gives `irradiance` on a surface facing it:
    /// `L = E / (π sin²α)`.
    pub fn with_irradiance(
        direction: Vec3,
        angular_radius: f32,
        irradiance: Vec3,
    ) -> Option<SunLight> {
        let sin = angular_radius.sin();
        SunLight::new(direction, angular_radius, irradiance / (PI * sin * sin))
    }

    /// The way its light travels (unit).
    pub fn direction(&self) -> Vec3 {
        self.direction
    }

    /// The disc's angular radius, in radians.
    pub fn angular_radius(&self) -> f32 {
        self.angular_radius
    }

    /// The disc's radiance.
    pub fn radiance(&self) -> Vec3 {
        self.radiance
    }

    /// The irradiance on a surface facing it, `E = L·π·sin²α`.
    pub fn irradiance(&self) -> Vec3 {
        let sin = self.angular_radius.sin();
        self.radiance * (PI * sin * sin)
    }

    /// A unit direction toward the disc that `u ∈ [0, 1)²` picks, uniform in its solid angle,
    /// its radiance and that density.
    #[inline]
    pub fn sample_direction(&self, u: Vec2) -> DirectionSample {
        let toward = -self.direction;
        let local = square_to_uniform_cone(u, self.one_minus_cos);
        let (s, t) = orthonormal_basis(toward);
        let direction = (s * local.x + t * local.y + toward * local.z).normalize();
        DirectionSample {
            direction,
            radiance: self.radiance,
            pdf: uniform_cone_pdf(self.one_minus_cos),
        }
    }

    /// [`sample_direction`](Self::sample_direction), seen from `point`.
    #[inline]
    pub fn sample(&self, point: &SurfacePoint, u: Vec2) -> LightSample {
        self.sample_direction(u).seen_from(point)
    }

    /// Its power, the mean of its channels, for choosing among lights: its irradiance through
    /// a disk of area `through_scene` the size of the scene (PBR 4th ed. §12.5).
    pub fn power(&self, through_scene: f32) -> f32 {
        through_scene * (self.irradiance().element_sum() / 3.0)
    }

    /// What a ray leaving the scene along the unit `direction` sees of it, with the density
    /// of [`sample`](Self::sample); [`Emission::NONE`] off the disc.
    #[inline]
    pub fn eval_pdf(&self, direction: Vec3) -> Emission {
        if !self.sees(direction) {
            return Emission::NONE;
        }
        Emission { radiance: self.radiance, pdf: self.pdf(direction) }
    }

    /// Whether the unit `direction` looks at the disc: `1 − cos θ ≤ 1 − cos α`, with
    /// `1 − cos θ = |d − s|²/2` (no cancellation near the centre).
    #[inline]
    pub fn sees(&self, direction: Vec3) -> bool {
        (direction + self.direction).length_squared() <= 2.0 * self.one_minus_cos
    }

    /// The density with which [`sample`](Self::sample) picks the unit `direction`.
    #[inline]
    pub fn pdf(&self, direction: Vec3) -> f32 {
        if self.sees(direction) { uniform_cone_pdf(self.one_minus_cos) } else { 0.0 }
    }

    /// The radiance seen looking along the unit `direction`.
    #[inline]
    pub fn eval(&self, direction: Vec3) -> Vec3 {
        if self.sees(direction) { self.radiance } else { Vec3::ZERO }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn direct_light_falls_off_with_the_square_of_distance_and_the_cosine() {
        let light = PointLight { position: Vec3::new(0.0, 2.0, 0.0), power: Vec3::splat(4.0 * PI) };
        // r = 2, head on: D = 4π / (4π·4) = 1/4.
        assert!((light.direct(Vec3::ZERO, Vec3::Y) - Vec3::splat(0.25)).length() < 1e-6);
        // Tilted by 60°: half of it.
        let n = Vec3::new(3f32.sqrt() / 2.0, 0.5, 0.0);
        assert!((light.direct(Vec3::ZERO, n) - Vec3::splat(0.125)).length() < 1e-6);
        // Facing away: nothing.
        assert_eq!(light.direct(Vec3::ZERO, -Vec3::Y), Vec3::ZERO);
        // At the light itself: nothing rather than infinity.
        assert_eq!(light.direct(light.position, Vec3::Y), Vec3::ZERO);
    }

    /// Mitsuba's `falloff_curve` at sampled angles: 1 within the beam, linear in the angle to
    /// 0 at the cutoff, nothing beyond; glTF's is the square of the cosine's place.
    #[test]
    fn spot_profiles_at_known_angles() {
        let degrees = |d: f32| d.to_radians();
        let spot = |profile| {
            SpotLight::new(Vec3::ZERO, Vec3::Z, Vec3::ONE, degrees(20.0), degrees(15.0), profile)
                .unwrap()
        };
        let mitsuba = spot(SpotProfile::Mitsuba);
        for (angle, expected) in [
            (0.0, 1.0),
            (14.9, 1.0),
            (16.0, 0.8),
            (17.5, 0.5),
            (19.0, 0.2),
            (20.5, 0.0),
            (90.0, 0.0),
        ] {
            let got = mitsuba.falloff(degrees(angle).cos());
            assert!((got - expected).abs() < 1e-4, "{angle}°: {got} against {expected}");
        }
        let gltf = spot(SpotProfile::Gltf);
        let (inner, outer) = (degrees(15.0).cos(), degrees(20.0).cos());
        for angle in [0.0, 10.0, 15.5, 17.0, 19.9, 25.0] {
            let cos = degrees(angle).cos();
            let t = ((cos - outer) / (inner - outer)).clamp(0.0, 1.0);
            let got = gltf.falloff(cos);
            assert!((got - t * t).abs() < 1e-4, "{angle}°: {got} against {}", t * t);
        }
        assert_eq!(gltf.falloff(degrees(25.0).cos()), 0.0);
        // Along a direction: the axis is normalized, the intensity scaled.
        let off_axis = Vec3::new(degrees(17.5).sin(), 0.0, degrees(17.5).cos());
        let tilted = SpotLight::new(
            Vec3::ZERO,
            Vec3::Z * 3.0,
            Vec3::new(2.0, 4.0, 6.0),
            degrees(20.0),
            degrees(15.0),
            SpotProfile::Mitsuba,
        )
        .unwrap();
        let got = tilted.intensity_toward(off_axis);
        assert!((got - Vec3::new(1.0, 2.0, 3.0)).abs().max_element() < 1e-3, "{got}");
        // Bad angles and axes are refused.
        let new = |cutoff: f32, beam: f32, axis| {
            SpotLight::new(Vec3::ZERO, axis, Vec3::ONE, cutoff, beam, SpotProfile::Mitsuba)
        };
        assert!(new(0.3, 0.4, Vec3::Z).is_none());
        assert!(new(4.0, 0.4, Vec3::Z).is_none());
        assert!(new(0.3, 0.2, Vec3::ZERO).is_none());
        assert!(new(f32::NAN, 0.2, Vec3::Z).is_none());
        // A hard-edged spot (beam width = cutoff) is full inside and dark outside.
        let hard = new(0.3, 0.3, Vec3::Z).unwrap();
        assert_eq!((hard.falloff(0.29f32.cos()), hard.falloff(0.31f32.cos())), (1.0, 0.0));
    }

    /// The sun's irradiance is `L π sin²α`; its samples lie on its disc, which `sees` and
    /// `eval` agree on; tiny discs keep their precision.
    #[test]
    fn the_sun_gives_its_irradiance_and_samples_its_disc() {
        let direction = Vec3::new(0.3, -1.0, 0.2);
        for radius in [0.5f32, 0.01, (SunLight::EARTH_APERTURE_DEG / 2.0).to_radians(), 1e-4] {
            let sun =
                SunLight::with_irradiance(direction, radius, Vec3::new(1.0, 2.0, 3.0)).unwrap();
            assert!((sun.irradiance() - Vec3::new(1.0, 2.0, 3.0)).abs().max_element() < 1e-5);
            let pdf = (1.0 / (2.0 * std::f64::consts::PI * (1.0 - (radius as f64).cos()))) as f32;
            let mut rng = crate::sampling::Pcg32::new(3, 4);
            for _ in 0..1000 {
                let sample = sun.sample_direction(Vec2::new(rng.next_f32(), rng.next_f32()));
                let (d, p) = (sample.direction, sample.pdf);
                assert!((p - pdf).abs() <= 1e-3 * pdf, "α {radius}: {p} against {pdf}");
                let angle = (d.as_dvec3().cross(-direction.as_dvec3().normalize())).length().asin();
                assert!(angle <= radius as f64 * 1.001, "α {radius}: {angle}");
                // Inside the disc but for the rounding of its edge.
                if angle < radius as f64 * 0.999 {
                    assert!(sun.sees(d) && sun.eval(d) == sun.radiance(), "α {radius}");
                }
            }
            assert!(!sun.sees(direction.normalize()), "the sun is behind the light's direction");
        }
        assert!(SunLight::new(Vec3::Z, 0.0, Vec3::ONE).is_none());
        assert!(SunLight::new(Vec3::Z, 2.0, Vec3::ONE).is_none());
        assert!(SunLight::new(Vec3::ZERO, 0.1, Vec3::ONE).is_none());
    }
}
