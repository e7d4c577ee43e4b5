//! Area lights: a triangle whose material emits, one-sided as Mitsuba's `area` emitter (it
//! emits from its front, counter-clockwise side only), its radiance constant or shaped by an
//! emission texture.
//!
//! Points on it are sampled uniformly by area, as Mitsuba does, and their density converted to
//! solid angle at the shading point, `p(ω) = d² / (cos θ_light · A)`; or, with
//! [`TriangleSampling::SolidAngle`], uniformly in the solid angle it subtends (Arvo 1995) where
//! that is neither tiny nor nearly a hemisphere (PBR 4th ed.'s bounds), `p(ω) = 1/Ω`.

use std::f32::consts::PI;
use std::sync::Arc;

use glam::{Vec2, Vec3};

use super::sample::{Emission, LightSample, SHADOW_RAY_LENGTH};
use crate::interaction::SurfaceInteraction;
use crate::ray::{SurfacePoint, offset_ray_origin};
use crate::sampling::{
    sample_spherical_triangle, spherical_triangle_area, square_to_uniform_triangle,
};
use crate::texture::{Texture, TextureQuery};
use crate::unknown_name::UnknownName;

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

/// Solid angles within which triangle lights are sampled by solid angle (PBR 4th ed.,
/// `MinSphericalSampleArea` and `MaxSphericalSampleArea`).
const SOLID_ANGLE_SAMPLING: std::ops::Range<f32> = 3e-4..6.22;

/// An emission texture on a triangle light, with the texture coordinates at its corners.
#[derive(Clone, Debug)]
pub struct EmissionPattern {
    /// Multiplies the light's radiance.
    pub texture: Texture,
    /// The texture coordinates at the corners.
    pub uvs: [Vec2; 3],
}

/// An emitting triangle: its corners, unit normal (the side it emits from), a bound on the
/// rounding of its points ([`Geometry::point_error_bound`]), its area, its radiance and its
/// emission texture where it has one.
///
/// [`Geometry::point_error_bound`]: crate::geometry::Geometry::point_error_bound
#[derive(Clone, Debug)]
pub struct TriangleLight {
    /// The corners, counter-clockwise seen from the front.
    pub corners: [Vec3; 3],
    /// The unit normal of the front.
    pub normal: Vec3,
    /// A bound on the rounding error of points on it.
    pub error: Vec3,
    /// Its area (positive).
    pub area: f32,
    /// The radiance it emits from its front (times the pattern, where it has one).
    pub radiance: Vec3,
    /// Its emission texture.
    pub pattern: Option<Arc<EmissionPattern>>,
    /// How points on it are sampled.
    pub sampling: TriangleSampling,
}

impl TriangleLight {
    /// Its power, for choosing among lights: `π A L̄`, with `L̄` the mean of the radiance's
    /// channels, or with a pattern the mean of radiance times pattern over the triangle
    /// (estimated on a grid, and kept above 1% of the plain radiance's).
    pub fn power(&self) -> f32 {
        let mean = match &self.pattern {
            None => mean(self.radiance),
            Some(p) => mean_over(&p.texture, self.radiance, self.corners, p.uvs),
        };
        PI * self.area * mean
    }

    /// The solid angle it subtends from `p`, where it is sampled by solid angle from there.
    #[inline]
    fn solid_angle(&self, p: Vec3) -> Option<f32> {
        if self.sampling == TriangleSampling::Area {
            return None;
        }
        let omega = spherical_triangle_area(self.corners, p);
        SOLID_ANGLE_SAMPLING.contains(&omega).then_some(omega)
    }

    /// A point on it that `u` picks, seen from `point`: the direction, radiance, density per
    /// unit solid angle and the shadow ray (between the two surfaces, stopping short of the
    /// light). `None` where `point` sees its back or nothing of it.
    #[inline]
    pub fn sample(&self, point: &SurfacePoint, u: Vec2) -> Option<LightSample> {
        let [v0, v1, v2] = self.corners;
        let solid_angle = self.solid_angle(point.p);
        let ([b0, b1, b2], solid_angle_pdf) = match solid_angle {
            Some(_) => sample_spherical_triangle(self.corners, point.p, u)?,
            None => (square_to_uniform_triangle(u), 0.0),
        };
        let target = b0 * v0 + b1 * v1 + b2 * v2;
        let to_light = target - point.p;
        let distance_squared = to_light.length_squared();
        let direction = to_light / distance_squared.sqrt();
        // One-sided: the light must face the point.
        let cos_light = -direction.dot(self.normal);
        if cos_light <= 0.0 || !distance_squared.is_normal() {
            return None;
        }
        // Both ends leave their surfaces (PBR 4th ed.'s `SpawnRayTo` between two surface
        // points): the light's end by its own rounding bound, which for an instance far from
        // where it is stored can outgrow the relative shortening.
        let end = SurfacePoint { p: target, error: self.error, normal: self.normal };
        let mut shadow_ray = point.spawn_ray_to(offset_ray_origin(&end, point.p - target));
        shadow_ray.t_max = SHADOW_RAY_LENGTH;
        let pdf = match solid_angle {
            Some(_) => solid_angle_pdf,
            None => distance_squared / (cos_light * self.area),
        };
        Some(LightSample {
            direction,
            radiance: self.radiance_at((b1, b2), target),
            pdf,
            delta: false,
            shadow_ray,
        })
    }

    /// Its radiance at barycentrics `(b1, b2)`, point `p`: the radiance times its pattern
    /// there, where it has one.
    #[inline]
    fn radiance_at(&self, (b1, b2): (f32, f32), p: Vec3) -> Vec3 {
        let Some(pattern) = &self.pattern else {
            return self.radiance;
        };
        let [t0, t1, t2] = pattern.uvs;
        let uv = (1.0 - b1 - b2) * t0 + b1 * t1 + b2 * t2;
        self.radiance * pattern.texture.rgb(&TextureQuery { uv, p, footprint: 0.0 }).max(Vec3::ZERO)
    }

    /// What a ray from `origin` sees at `hit` on it: its radiance there and the density with
    /// which [`sample`](Self::sample) picks that direction from `origin`; [`Emission::NONE`]
    /// from behind.
    #[inline]
    pub fn eval_pdf(&self, origin: Vec3, hit: &SurfaceInteraction) -> Emission {
        let to_light = hit.point.p - origin;
        let distance_squared = to_light.length_squared();
        let cos_light = -to_light.dot(self.normal) / distance_squared.sqrt();
        if cos_light <= 0.0 {
            return Emission::NONE;
        }
        let pdf = match self.solid_angle(origin) {
            Some(omega) => 1.0 / omega,
            None => distance_squared / (cos_light * self.area),
        };
        Emission { radiance: self.eval(hit), pdf }
    }

    /// The radiance it emits at `hit` (front or back alike: [`eval_pdf`](Self::eval_pdf)
    /// says which side is seen).
    #[inline]
    pub fn eval(&self, hit: &SurfaceInteraction) -> Vec3 {
        match &self.pattern {
            None => self.radiance,
            Some(p) => self.radiance * p.texture.rgb(&hit.texture_query()).max(Vec3::ZERO),
        }
    }

    /// The density with which [`sample`](Self::sample) picks the direction from `origin` to
    /// the point `hit` on it (zero from behind).
    #[inline]
    pub fn pdf(&self, origin: Vec3, hit: &SurfaceInteraction) -> f32 {
        self.eval_pdf(origin, hit).pdf
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
mod tests {
    use super::*;

    /// `mean_over` weighs the texture by the emission channel by channel, finds a pattern's
    /// share of the triangle, and keeps a floor for a pattern its points miss.
    #[test]
    fn a_textured_emitter_s_power_is_its_mean_emission() {
        use crate::texture::{ImageTexture, TextureImage, Wrap};
        use std::sync::Arc;
        let image = |texels: Vec<[f32; 4]>, width: u32| {
            let image = TextureImage::from_rgba_f32("t", width, 1, texels);
            let texture = ImageTexture::new(Arc::new(image));
            Texture::Image(ImageTexture { wrap: [Wrap::Clamp; 2], ..texture })
        };
        let corners = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let uvs = [Vec2::ZERO, Vec2::X, Vec2::Y];
        // A constant texture scales the emission.
        let grey = image(vec![[0.5, 0.25, 1.0, 1.0]], 1);
        let emission = Vec3::new(2.0, 4.0, 1.0);
        let expected = mean(emission * Vec3::new(0.5, 0.25, 1.0));
        assert!((mean_over(&grey, emission, corners, uvs) - expected).abs() < 1e-6);
        // Red emission through a blue texture emits nothing: only the floor remains.
        let blue = image(vec![[0.0, 0.0, 1.0, 1.0]], 1);
        let red = Vec3::new(3.0, 0.0, 0.0);
        assert_eq!(mean_over(&blue, red, corners, uvs), 0.01 * mean(red));
        // White where u < ½ (256 texels): the triangle's part with u < ½ is ¾ of its area.
        let texels = (0..256).map(|x| if x < 128 { [1.0; 4] } else { [0.0, 0.0, 0.0, 1.0] });
        let half = image(texels.collect(), 256);
        let share = mean_over(&half, Vec3::ONE, corners, uvs);
        assert!((share - 0.75).abs() < 0.02, "{share}");
    }
}
