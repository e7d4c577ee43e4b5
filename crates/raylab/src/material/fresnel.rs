//! Fresnel reflectance of dielectric and conducting interfaces, and the helpers that reflect and
//! refract directions (PBR 4th ed. §9.3, §9.5).

use glam::Vec3;

/// The fraction of light a smooth dielectric interface reflects, for the cosine `cos_theta_i` of
/// the incident direction with the normal and the relative index of refraction `eta` (inside
/// over outside). A negative cosine means the light arrives from inside; beyond the critical
/// angle the reflection is total (1).
#[inline(always)]
pub fn fresnel_dielectric(cos_theta_i: f32, eta: f32) -> f32 {
    let mut cos_i = cos_theta_i.clamp(-1.0, 1.0);
    let mut eta = eta;
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    (parallel * parallel + perpendicular * perpendicular) / 2.0
}

/// A complex number, for the conductor's Fresnel equations.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Complex {
    re: f32,
    im: f32,
}

impl Complex {
    #[inline(always)]
    fn new(re: f32, im: f32) -> Complex {
        Complex { re, im }
    }
    #[inline(always)]
    fn add(self, o: Complex) -> Complex {
        Complex::new(self.re + o.re, self.im + o.im)
    }
    #[inline(always)]
    fn sub(self, o: Complex) -> Complex {
        Complex::new(self.re - o.re, self.im - o.im)
    }
    #[inline(always)]
    fn mul(self, o: Complex) -> Complex {
        Complex::new(self.re * o.re - self.im * o.im, self.re * o.im + self.im * o.re)
    }
    #[inline(always)]
    fn scale(self, s: f32) -> Complex {
        Complex::new(self.re * s, self.im * s)
    }
    #[inline(always)]
    fn norm(self) -> f32 {
        self.re * self.re + self.im * self.im
    }
    #[inline(always)]
    fn div(self, o: Complex) -> Complex {
        let d = o.norm();
        Complex::new((self.re * o.re + self.im * o.im) / d, (self.im * o.re - self.re * o.im) / d)
    }
    #[inline(always)]
    fn sqrt(self) -> Complex {
        let n = self.norm().sqrt();
        if n == 0.0 {
            return Complex::new(0.0, 0.0);
        }
        let t1 = (0.5 * (n + self.re.abs())).sqrt();
        let t2 = 0.5 * self.im / t1;
        if self.re >= 0.0 {
            Complex::new(t1, t2)
        } else {
            Complex::new(t2.abs(), t1.copysign(self.im))
        }
    }
}

/// The reflectance of a conductor with complex index of refraction `eta + i·k` per channel
/// (relative to the outside medium), for an incident cosine in `[0, 1]`.
#[inline(always)]
pub fn fresnel_conductor(cos_theta_i: f32, eta: Vec3, k: Vec3) -> Vec3 {
    let cos_i = cos_theta_i.clamp(0.0, 1.0);
    // A function, not a closure, so that it can be inlined by force (the path tracer's lanes
    // need the whole BSDF inlined to become vector code).
    #[inline(always)]
    fn channel(cos_i: f32, eta: f32, k: f32) -> f32 {
        let eta = Complex::new(eta, k);
        let sin2_i = 1.0 - cos_i * cos_i;
        let sin2_t = Complex::new(sin2_i, 0.0).div(eta.mul(eta));
        let cos_t = Complex::new(1.0, 0.0).sub(sin2_t).sqrt();
        let ci = Complex::new(cos_i, 0.0);
        let parallel = eta.scale(cos_i).sub(cos_t).div(eta.scale(cos_i).add(cos_t));
        let perpendicular = ci.sub(eta.mul(cos_t)).div(ci.add(eta.mul(cos_t)));
        ((parallel.norm() + perpendicular.norm()) / 2.0).clamp(0.0, 1.0)
    }
    Vec3::new(channel(cos_i, eta.x, k.x), channel(cos_i, eta.y, k.y), channel(cos_i, eta.z, k.z))
}

/// `wi` mirrored about the unit normal `n`: `2(wi·n)n − wi`.
#[inline(always)]
pub fn reflect(wi: Vec3, n: Vec3) -> Vec3 {
    2.0 * wi.dot(n) * n - wi
}

/// `wi` refracted through an interface with unit normal `n` (on either side) and relative index
/// `eta` (the side `n` points away from, over the side it points to), with the relative index
/// `etap` the ray then sees (transmitted side over incident side); `None` for total internal
/// reflection.
#[inline(always)]
pub fn refract(wi: Vec3, n: Vec3, eta: f32) -> Option<(Vec3, f32)> {
    let mut cos_i = n.dot(wi);
    let (mut eta, mut n) = (eta, n);
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    Some((-wi / eta + (cos_i / eta - cos_t) * n, eta))
}

/// The hemispherical average of [`fresnel_dielectric`] weighted by the cosine,
/// `∫₀¹ 2μ F(μ, η) dμ`: the fraction of diffuse light an interface reflects (from the side that
/// sees the relative index `eta`). For `η < 1` (light inside a denser medium, as under a
/// plastic's coating) it is Egan and Hilgeman's fit (1973), as Mitsuba computes it, so that
/// plastics match Mitsuba's exactly (the fit is within 0.1 % of the integral for 1/η up to 1.5);
/// for `η ≥ 1`, the integral by midpoint quadrature.
pub fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    if eta < 1.0 {
        return -1.4399 * eta * eta + 0.7099 * eta + 0.6681 + 0.0636 / eta;
    }
    fresnel_diffuse_reflectance_integral(eta)
}

/// `∫₀¹ 2μ F(μ, η) dμ` by midpoint quadrature.
pub fn fresnel_diffuse_reflectance_integral(eta: f32) -> f32 {
    const N: usize = 2048;
    let sum: f64 = (0..N)
        .map(|i| {
            let mu = (i as f64 + 0.5) / N as f64;
            2.0 * mu * fresnel_dielectric(mu as f32, eta) as f64
        })
        .sum();
    (sum / N as f64) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dielectric_reflectance_matches_known_values() {
        // Head on: ((η − 1)/(η + 1))², 4 % for glass of 1.5.
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!((fresnel_dielectric(-1.0, 1.5) - 0.04).abs() < 1e-6);
        // Grazing: everything.
        assert!((fresnel_dielectric(1e-6, 1.5) - 1.0).abs() < 1e-4);
        // Brewster's angle, tan θ = η: only the perpendicular part, 0.07388 for η = 1.5 at 56.31°.
        let brewster = 1.5f32.atan();
        assert!((fresnel_dielectric(brewster.cos(), 1.5) - 0.073_96).abs() < 2e-4);
        // Inside, beyond the critical angle asin(1/1.5) = 41.8°: total internal reflection.
        assert_eq!(fresnel_dielectric(-(45f32.to_radians().cos()), 1.5), 1.0);
        assert!(fresnel_dielectric(-(40f32.to_radians().cos()), 1.5) < 1.0);
        // Matched indices: nothing.
        assert!(fresnel_dielectric(0.3, 1.0) < 1e-12);
    }

    #[test]
    fn conductor_reflectance_reduces_to_known_cases() {
        // k = 0 is a dielectric.
        for cos in [1.0f32, 0.7, 0.2] {
            let f = fresnel_conductor(cos, Vec3::splat(1.5), Vec3::ZERO);
            assert!((f.x - fresnel_dielectric(cos, 1.5)).abs() < 1e-5, "{cos}");
        }
        // Head on: ((η−1)² + k²)/((η+1)² + k²).
        let (eta, k) = (0.2f32, 3.0f32);
        let expected = ((eta - 1.0).powi(2) + k * k) / ((eta + 1.0).powi(2) + k * k);
        assert!(
            (fresnel_conductor(1.0, Vec3::splat(eta), Vec3::splat(k)).x - expected).abs() < 1e-5
        );
        // Grazing: 1.
        assert!((fresnel_conductor(0.0, Vec3::splat(eta), Vec3::splat(k)).x - 1.0).abs() < 1e-4);
    }

    #[test]
    fn snell_s_law_and_total_internal_reflection() {
        let theta: f32 = 30f32.to_radians();
        let wi = Vec3::new(theta.sin(), 0.0, theta.cos());
        let (wt, etap) = refract(wi, Vec3::Z, 1.5).unwrap();
        assert_eq!(etap, 1.5);
        // sin θt = sin θi / η, on the other side, in the plane of incidence.
        assert!((wt.x - (-theta.sin() / 1.5)).abs() < 1e-6 && wt.z < 0.0 && wt.y == 0.0);
        assert!((wt.length() - 1.0).abs() < 1e-6);
        // From inside at 30°: sin θt = 1.5 sin 30° = 0.75.
        let (wt, etap) = refract(-wi, Vec3::Z, 1.5).unwrap();
        assert!((etap - 1.0 / 1.5).abs() < 1e-7 && (wt.x - 0.75).abs() < 1e-6 && wt.z > 0.0);
        // From inside at 45°: total internal reflection.
        let steep = 45f32.to_radians();
        assert!(refract(Vec3::new(steep.sin(), 0.0, -steep.cos()), Vec3::Z, 1.5).is_none());
        assert_eq!(reflect(wi, Vec3::Z), Vec3::new(-wi.x, 0.0, wi.z));
    }

    #[test]
    fn diffuse_fresnel_reflectance_matches_the_literature() {
        // Egan & Hilgeman's fit for η < 1 (light inside a medium of 1/η), accurate to 0.1 %.
        for inside in [1.33f32, 1.5] {
            let eta = 1.0 / inside;
            let fit = fresnel_diffuse_reflectance(eta);
            assert!((fresnel_diffuse_reflectance_integral(eta) - fit).abs() < 0.003, "{inside}");
        }
        // Mitsuba's value for a plastic of 1.49 (its fit at 1/1.49).
        assert!((fresnel_diffuse_reflectance(1.0 / 1.49) - 0.590_73).abs() < 1e-4);
        // From outside glass: about 9 %.
        assert!((fresnel_diffuse_reflectance(1.5) - 0.0918).abs() < 0.002);
    }
}
