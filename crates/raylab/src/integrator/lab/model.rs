//! The lab's light model one hit at a time ([`Lab::shade`], [`Lab::finish`]), and its steps
//! ([`Stage`]); the tile shades 64 hits as these do, bit for bit (`tile.rs`).

use std::fmt;
use std::str::FromStr;

use glam::Vec3;

use crate::accel::{Accelerator, Hit};
use crate::camera::Camera;
use crate::light::PointLight;
use crate::ray::Ray;
use crate::scene::Scene;

/// One step of the lab, each adding one idea to the previous.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "io", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "io", serde(rename_all = "lowercase"))]
pub enum Stage {
    /// The colour ρ of the closest triangle, black where nothing is hit.
    Flat,
    /// The light's power per area `D` alone (eq. 27), no colour and no shadows.
    Direct,
    /// Reflected light `ρ ∗ D`, no shadows.
    Reflected,
    /// `ρ ∗ D` with shadow rays.
    Shadows,
    /// The full model `ρ ∗ (D + N)` with shadows (eq. 30).
    #[default]
    Ambient,
}

impl Stage {
    /// Every stage, in the lab's order.
    pub const ALL: [Stage; 5] =
        [Stage::Flat, Stage::Direct, Stage::Reflected, Stage::Shadows, Stage::Ambient];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Flat => "flat",
            Stage::Direct => "direct",
            Stage::Reflected => "reflected",
            Stage::Shadows => "shadows",
            Stage::Ambient => "ambient",
        }
    }

    /// What the stage shows, in a few words.
    pub fn description(self) -> &'static str {
        match self {
            Stage::Flat => "flat triangle colour ρ",
            Stage::Direct => "direct light D only (eq. 27)",
            Stage::Reflected => "reflected light ρ∗D",
            Stage::Shadows => "ρ∗D with shadows",
            Stage::Ambient => "ρ∗(D+N) with shadows and ambient (eq. 30)",
        }
    }
}

impl fmt::Display for Stage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The stage name was not one of [`Stage::ALL`].
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
#[error("unknown stage '{0}': expected one of flat, direct, reflected, shadows, ambient (or 1–5)")]
pub struct UnknownStage(pub String);

impl FromStr for Stage {
    type Err = UnknownStage;

    /// A stage by name or by its number in the lab's order, 1 to 5.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Stage::ALL
            .into_iter()
            .enumerate()
            .find(|(i, stage)| s == stage.name() || s == (i + 1).to_string())
            .map(|(_, stage)| stage)
            .ok_or_else(|| UnknownStage(s.to_string()))
    }
}

/// The lab's integrator over a scene and an accelerator built from its
/// [`vertices`](Scene::vertices).
#[derive(Debug)]
pub struct Lab<'a, A: ?Sized> {
    pub(super) scene: &'a Scene,
    pub(super) accel: &'a A,
    pub(super) stage: Stage,
    /// The point light: the scene's, unless moved (as `raylab view` moves it).
    pub light: PointLight,
    /// The constant indirect light `N` of eq. (30).
    pub ambient: Vec3,
    /// The angle one pixel subtends, in radians ([`Camera::pixel_spread`]): textures are
    /// filtered over the ray cone it gives (see [`crate::texture`]), so that one sample per
    /// pixel does not alias. 0 reads them at a point.
    pub pixel_spread: f32,
}

// By hand: the derive would ask `A: Copy`, but a `Lab` only holds a reference to it.
impl<A: ?Sized> Clone for Lab<'_, A> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<A: ?Sized> Copy for Lab<'_, A> {}

impl<'a, A: Accelerator + ?Sized> Lab<'a, A> {
    /// The lab's model at `stage`, with the scene's [`lab_light`](Scene::lab_light) and the lab's
    /// ambient light `N = 0.5`.
    pub fn new(scene: &'a Scene, accel: &'a A, stage: Stage) -> Self {
        Lab {
            scene,
            accel,
            stage,
            light: scene.lab_light(),
            ambient: Vec3::splat(0.5),
            pixel_spread: 0.0,
        }
    }

    /// Reads textures over the ray cone of a camera's pixels ([`pixel_spread`](Self::pixel_spread)).
    pub fn for_camera(mut self, camera: &Camera) -> Self {
        self.pixel_spread = camera.pixel_spread();
        self
    }

    /// The colour of material `id` where `ray` meets `hit`.
    #[inline]
    pub(super) fn albedo(&self, ray: &Ray, hit: &Hit, id: u32) -> Vec3 {
        let material = &self.scene.materials[id as usize];
        if material.textures.is_empty() {
            material.bsdf.albedo()
        } else {
            material.albedo_at(&self.scene.geometry.texture_query(ray, hit, self.pixel_spread))
        }
    }
}

/// What a camera ray sees before the shadow test: the colour, the light's `D` and the shadow
/// ray that decides whether `D` counts.
pub(super) struct Shading {
    pub(super) albedo: Vec3,
    pub(super) direct: Vec3,
    pub(super) shadow_ray: Option<Ray>,
}

impl Shading {
    /// Nothing seen.
    pub(super) const NONE: Shading =
        Shading { albedo: Vec3::ZERO, direct: Vec3::ZERO, shadow_ray: None };
}

/// Rays shaded together: one tile of
/// [`Integrator::radiance_each`](crate::integrator::Integrator::radiance_each).
pub(super) const TILE: usize = 64;

impl<A: Accelerator + ?Sized> Lab<'_, A> {
    /// Shades a hit up to the shadow test (inlined into the tile loop: it returns a large
    /// value, which a call would copy through memory).
    #[inline(always)]
    pub(super) fn shade(&self, ray: &Ray, hit: Option<Hit>) -> Shading {
        let Some(hit) = hit else {
            return Shading::NONE;
        };
        // The lab needs the point, its normal and the colour: not the whole interaction.
        let geometry = &self.scene.geometry;
        let albedo = self.albedo(ray, &hit, geometry.material_id(hit.triangle as usize));
        if self.stage == Stage::Flat {
            return Shading { albedo, direct: Vec3::ZERO, shadow_ray: None };
        }
        let mut point = geometry.surface_point(&hit);
        // Triangles are hit from both sides: light the side the ray sees. (With a one-sided
        // normal, a wall seen from behind would be lit through itself by a light on its front.)
        // A grazing ray (a zero product) gets the lab's own normal `(v2 − v0) × (v1 − v0)`, the
        // opposite of the geometric one.
        if point.normal.dot(ray.direction) >= 0.0 {
            point.normal = -point.normal;
        }
        let light = &self.light;
        // Lab eq. (27): D = P max(r̂·n̂, 0) / (4πr²).
        let direct = light.direct(point.p, point.normal);
        let shadows = matches!(self.stage, Stage::Shadows | Stage::Ambient);
        let shadow_ray =
            (shadows && direct != Vec3::ZERO).then(|| point.spawn_ray_to(light.position));
        Shading { albedo, direct, shadow_ray }
    }

    /// The colour of a shaded hit, given whether its shadow ray is blocked.
    #[inline]
    pub(super) fn finish(&self, hit: bool, shading: &Shading, occluded: bool) -> Vec3 {
        if !hit {
            return Vec3::ZERO;
        }
        let direct = if occluded { Vec3::ZERO } else { shading.direct };
        match self.stage {
            Stage::Flat => shading.albedo,
            Stage::Direct => direct,
            Stage::Reflected | Stage::Shadows => shading.albedo * direct,
            // Lab eq. (30): R = ρ ∗ (D + N).
            Stage::Ambient => shading.albedo * (direct + self.ambient),
        }
    }
}
