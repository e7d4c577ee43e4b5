//! The GGX (Trowbridge–Reitz) microfacet distribution, anisotropic, with Smith's shadowing and
//! visible-normal sampling (Walter et al. 2007; Heitz 2014; Heitz, "Sampling the GGX
//! Distribution of Visible Normals", JCGT 2018). Mitsuba's `roughconductor` and
//! `roughdielectric` use it with `alpha_u`, `alpha_v` along the shading frame's tangents.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use crate::sampling::sin_cos_turns;

/// A GGX distribution of microfacet normals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    /// Roughness along the tangent (x).
    pub alpha_u: f32,
    /// Roughness along the bitangent (y).
    pub alpha_v: f32,
}

/// The smallest roughness the distribution is evaluated with: below it, floating point loses
/// the lobe (the BSDF is then all but a mirror, which the smooth materials render exactly).
pub const MIN_ALPHA: f32 = 1e-4;

impl Ggx {
    /// A distribution with roughness `alpha_u` × `alpha_v` (each clamped to [`MIN_ALPHA`]).
    pub fn new(alpha_u: f32, alpha_v: f32) -> Ggx {
        Ggx { alpha_u: alpha_u.max(MIN_ALPHA), alpha_v: alpha_v.max(MIN_ALPHA) }
    }

    /// The density of microfacet normals `m` (upper hemisphere), per unit projected area:
    /// `D(m) = 1 / (π αu αv (mx²/αu² + my²/αv² + mz²)²)`.
    #[inline(always)]
    pub fn d(&self, m: Vec3) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let t = (m.x / self.alpha_u).powi(2) + (m.y / self.alpha_v).powi(2) + m.z * m.z;
        let d = 1.0 / (PI * self.alpha_u * self.alpha_v * t * t);
        if d.is_finite() { d } else { 0.0 }
    }

    /// Smith's Λ for direction `w`.
    #[inline(always)]
    fn lambda(&self, w: Vec3) -> f32 {
        let a2_tan2 = ((self.alpha_u * w.x).powi(2) + (self.alpha_v * w.y).powi(2)) / (w.z * w.z);
        if !a2_tan2.is_finite() {
            return f32::INFINITY;
        }
        ((1.0 + a2_tan2).sqrt() - 1.0) / 2.0
    }

    /// Smith's masking of direction `w` by microfacets of normal `m`: zero when `w` sees the
    /// back of `m`.
    #[inline(always)]
    pub fn g1(&self, w: Vec3, m: Vec3) -> f32 {
        if w.dot(m) * w.z <= 0.0 {
            return 0.0;
        }
        1.0 / (1.0 + self.lambda(w))
    }

    /// Separable masking-shadowing `G1(wi)·G1(wo)` (Mitsuba's choice).
    #[inline(always)]
    pub fn g(&self, wi: Vec3, wo: Vec3, m: Vec3) -> f32 {
        self.g1(wi, m) * self.g1(wo, m)
    }

    /// The density of visible normals seen from `wi` (upper hemisphere):
    /// `G1(wi) max(wi·m, 0) D(m) / cos θi`.
    #[inline(always)]
    pub fn visible_pdf(&self, wi: Vec3, m: Vec3) -> f32 {
        if wi.z <= 0.0 {
            return 0.0;
        }
        self.g1(wi, m) * wi.dot(m).max(0.0) * self.d(m) / wi.z
    }

    /// A microfacet normal visible from `wi` (upper hemisphere), distributed as
    /// [`visible_pdf`](Self::visible_pdf) (Heitz 2018's listing).
    #[inline(always)]
    pub fn sample_visible(&self, wi: Vec3, u: Vec2) -> Vec3 {
        // The view direction in the hemisphere configuration of unit roughness.
        let vh = Vec3::new(self.alpha_u * wi.x, self.alpha_v * wi.y, wi.z).normalize();
        // An orthonormal basis about it.
        let length_squared = vh.x * vh.x + vh.y * vh.y;
        let t1 = if length_squared > 0.0 {
            Vec3::new(-vh.y, vh.x, 0.0) / length_squared.sqrt()
        } else {
            Vec3::X
        };
        let t2 = vh.cross(t1);
        // A point on the projected disk, squeezed on the side the view hides.
        let r = u.x.sqrt();
        // The polynomial sine and cosine of 2π·u.y (the lanes' and the scalar code's bits).
        let (sin, cos) = sin_cos_turns(u.y);
        let p1 = r * cos;
        let s = 0.5 * (1.0 + vh.z);
        let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * sin;
        let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
        // Back to the ellipsoid configuration.
        Vec3::new(self.alpha_u * nh.x, self.alpha_v * nh.y, nh.z.max(1e-6)).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Pcg32;
    use crate::sampling::chi2::{self, Sphere};

    fn distributions() -> [Ggx; 3] {
        [Ggx::new(0.3, 0.3), Ggx::new(0.1, 0.1), Ggx::new(0.6, 0.15)]
    }

    #[test]
    fn d_is_normalized_over_projected_area() {
        // ∫ D(m) cos θm dω = 1, by midpoint integration over the hemisphere.
        for ggx in distributions() {
            let n = 1200;
            let mut sum = 0.0f64;
            for i in 0..n {
                for j in 0..n / 2 {
                    // cos θ from the u-grid squared, to resolve sharp peaks near the pole.
                    let u = (i as f64 + 0.5) / n as f64;
                    let cos_theta = 1.0 - u * u;
                    let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / (n / 2) as f64;
                    let sin_theta = (1.0 - cos_theta * cos_theta).sqrt();
                    let m = Vec3::new(
                        (sin_theta * phi.cos()) as f32,
                        (sin_theta * phi.sin()) as f32,
                        cos_theta as f32,
                    );
                    let jacobian = 2.0 * u / n as f64 * 2.0 * std::f64::consts::PI / (n / 2) as f64;
                    sum += ggx.d(m) as f64 * cos_theta * jacobian;
                }
            }
            assert!((sum - 1.0).abs() < 0.01, "{ggx:?}: {sum}");
        }
    }

    #[test]
    fn visible_normals_fit_their_density() {
        let incident = [
            Vec3::Z,
            Vec3::new(0.5, 0.2, 0.843).normalize(),
            Vec3::new(-0.95, 0.1, 0.29).normalize(),
        ];
        let tests = distributions().len() * incident.len();
        for ggx in distributions() {
            for wi in incident {
                chi2::run(
                    &Sphere,
                    (16, 32),
                    300_000,
                    3,
                    |rng: &mut Pcg32| {
                        Some(ggx.sample_visible(wi, Vec2::new(rng.next_f32(), rng.next_f32())))
                    },
                    |m| ggx.visible_pdf(wi, m),
                )
                .assert_fits(
                    &format!("GGX {ggx:?} visible normals from {wi}"),
                    tests,
                    5e-3,
                );
            }
        }
    }

    #[test]
    fn masking_is_one_head_on_and_falls_at_grazing_angles() {
        let ggx = Ggx::new(0.5, 0.5);
        assert!((ggx.g1(Vec3::Z, Vec3::Z) - 1.0).abs() < 1e-6);
        let grazing = Vec3::new(0.999, 0.0, 0.0447).normalize();
        assert!(ggx.g1(grazing, Vec3::Z) < 0.2);
        // A direction that sees the back of the microfacet is masked.
        assert_eq!(ggx.g1(Vec3::new(0.6, 0.0, 0.8), Vec3::new(-0.9, 0.0, 0.436).normalize()), 0.0);
    }
}
