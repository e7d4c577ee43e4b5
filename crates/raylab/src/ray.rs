//! Rays, and spawning secondary rays from a surface without self-intersection.
//!
//! A shadow ray that starts exactly on the surface it leaves can hit that same surface again
//! because of rounding: "shadow acne". The lab's usual fix, a fixed magic epsilon, fails for scenes
//! much larger or smaller than the one it was tuned for. raylab instead carries a conservative
//! bound on the rounding error of every hit point ([`SurfacePoint::error`]) and moves the origin
//! just past that bound along the normal ([`offset_ray_origin`]), the method of PBR 4th ed.
//! §6.8.6 (the same idea as Wächter & Binder, "A Fast and Robust Method for Avoiding
//! Self-Intersection", Ray Tracing Gems ch. 6). It is scale-aware: it works at 10⁻³ and 10³ alike.

use glam::Vec3;

use crate::float::{next_float_down, next_float_up};

/// A ray `origin + t·direction` for `t` in `[t_min, t_max)`, and always `t > 0`.
///
/// `direction` need not be normalized; `t` is measured in multiples of it. Rays made here start at
/// `t_min = 0` (the intersection test keeps `t` conservatively above zero); a positive `t_min` is
/// for callers that bring their own epsilon, such as the ray-set benchmark's files.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Ray {
    /// Where the ray starts.
    pub origin: Vec3,
    /// Where it goes; any non-zero length.
    pub direction: Vec3,
    /// Hits at `t < t_min` are ignored.
    pub t_min: f32,
    /// Hits at `t >= t_max` are ignored.
    pub t_max: f32,
}

impl Ray {
    /// An unbounded ray.
    #[inline]
    pub fn new(origin: Vec3, direction: Vec3) -> Self {
        Ray { origin, direction, t_min: 0.0, t_max: f32::INFINITY }
    }

    /// A ray limited to `t < t_max`.
    #[inline]
    pub fn segment(origin: Vec3, direction: Vec3, t_max: f32) -> Self {
        Ray { origin, direction, t_min: 0.0, t_max }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.direction
    }
}

/// A point on a surface with a conservative per-axis bound on its rounding error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// The computed point.
    pub p: Vec3,
    /// The exact point lies within `p ± error` on each axis.
    pub error: Vec3,
    /// The surface's geometric normal (unit length).
    pub normal: Vec3,
}

impl SurfacePoint {
    /// A ray from this point toward `target`, ending at `target` (`t_max = 1`), that cannot hit
    /// the surface it starts on: the ray to test a point light's visibility.
    #[inline]
    pub fn spawn_ray_to(&self, target: Vec3) -> Ray {
        let origin = offset_ray_origin(self, target - self.p);
        Ray::segment(origin, target - origin, 1.0)
    }

    /// A ray from this point in `direction` that cannot hit the surface it starts on.
    #[inline]
    pub fn spawn_ray(&self, direction: Vec3) -> Ray {
        Ray::new(offset_ray_origin(self, direction), direction)
    }
}

/// Moves a surface point off its surface, to the side that `w` points to, by just more than the
/// point's rounding-error bound (PBR 4th ed. §6.8.6, `OffsetRayOrigin`).
///
/// The offset is `(|n|·error)·n`, then each coordinate is rounded one more float away from the
/// surface, so the origin is guaranteed to be on the correct side whatever the scene's scale.
#[inline(always)]
pub fn offset_ray_origin(point: &SurfacePoint, w: Vec3) -> Vec3 {
    match offset_ray_origin_finite(point, w) {
        (origin, true) => origin,
        (_, false) => {
            let (po, offset) = offset_point(point, w);
            offset_ray_origin_scalar(po, offset)
        }
    }
}

/// [`offset_ray_origin`] without a branch, for lanes: the origin, and whether the moved point
/// was finite (where it was not, the origin is wrong and `offset_ray_origin` must be called).
#[inline(always)]
pub(crate) fn offset_ray_origin_finite(point: &SurfacePoint, w: Vec3) -> (Vec3, bool) {
    let (po, offset) = offset_point(point, w);
    let origin =
        Vec3::new(step_away(po.x, offset.x), step_away(po.y, offset.y), step_away(po.z, offset.z));
    (origin, po.is_finite())
}

/// The point moved by `(|n|·error)·n` to the side `w` points to, and the move.
#[inline(always)]
fn offset_point(point: &SurfacePoint, w: Vec3) -> (Vec3, Vec3) {
    let n = point.normal;
    let d = n.abs().dot(point.error);
    let mut offset = d * n;
    if w.dot(n) < 0.0 {
        offset = -offset;
    }
    (point.p + offset, offset)
}

/// [`offset_ray_origin`]'s last step on one axis: `value` (finite) moved one float further in the
/// direction of `offset`, or kept where `offset` is zero. Without a branch: the bit pattern of a
/// finite float steps by ±1 (its magnitude grows when it moves away from zero), after a zero has
/// taken the sign of the step.
#[inline(always)]
pub(crate) fn step_away(value: f32, offset: f32) -> f32 {
    let direction = (offset > 0.0) as i32 - (offset < 0.0) as i32;
    let value = if value == 0.0 && direction != 0 { 0.0f32.copysign(offset) } else { value };
    let away_from_zero = (value.is_sign_negative() == (direction < 0)) as i32;
    // +1 to grow the magnitude, −1 to shrink it, 0 where the axis did not move.
    let delta = direction.abs() * (2 * away_from_zero - 1);
    f32::from_bits((value.to_bits() as i32).wrapping_add(delta) as u32)
}

/// [`offset_ray_origin`]'s rounding step with the general `next_float_up`/`down` (which keep
/// infinities): its twin, for points that are not finite.
fn offset_ray_origin_scalar(mut po: Vec3, offset: Vec3) -> Vec3 {
    for axis in 0..3 {
        if offset[axis] > 0.0 {
            po[axis] = next_float_up(po[axis]);
        } else if offset[axis] < 0.0 {
            po[axis] = next_float_down(po[axis]);
        }
    }
    po
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_moves_to_the_side_of_w() {
        let point =
            SurfacePoint { p: Vec3::new(1.0, 2.0, 3.0), error: Vec3::splat(1e-6), normal: Vec3::Y };
        let up = offset_ray_origin(&point, Vec3::new(0.3, 1.0, 0.0));
        let down = offset_ray_origin(&point, Vec3::new(0.3, -1.0, 0.0));
        assert!(up.y > 2.0 + 1e-6, "{up}");
        assert!(down.y < 2.0 - 1e-6, "{down}");
        assert_eq!(up.x, 1.0);
        assert_eq!(up.z, 3.0);
    }

    #[test]
    fn offset_is_zero_without_error_and_tiny_with_tiny_error() {
        let point = SurfacePoint { p: Vec3::ZERO, error: Vec3::ZERO, normal: Vec3::Z };
        // With no error the offset is zero and nothing is rounded: the point stays put.
        assert_eq!(offset_ray_origin(&point, Vec3::Z), Vec3::ZERO);
        let point = SurfacePoint { error: Vec3::splat(1e-30), ..point };
        assert!(offset_ray_origin(&point, Vec3::Z).z > 0.0);
        assert!(offset_ray_origin(&point, -Vec3::Z).z < 0.0);
    }

    #[test]
    fn the_branchless_step_equals_next_float_up_and_down() {
        let mut rng = crate::sampling::Pcg32::new(1, 2);
        let special = [
            0.0f32,
            -0.0,
            1.0,
            -1.0,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            1e-45,
            -1e-45,
            3.3e38,
            -3.3e38,
        ];
        let mut values: Vec<f32> = special.to_vec();
        values
            .extend((0..20_000).map(|_| f32::from_bits(rng.next_u32())).filter(|v| v.is_finite()));
        for &p in &values {
            for offset in [1e-7f32, -1e-7, 0.0, 2.0, -3.0] {
                let point = SurfacePoint {
                    p: Vec3::splat(p),
                    error: Vec3::splat(offset.abs()),
                    normal: Vec3::new(1.0, 0.0, -1.0).normalize(),
                };
                let w = Vec3::new(offset.signum(), 0.0, 0.0);
                let fast = offset_ray_origin(&point, w);
                let n = point.normal;
                let mut moved = n.abs().dot(point.error) * n;
                if w.dot(n) < 0.0 {
                    moved = -moved;
                }
                let slow = offset_ray_origin_scalar(point.p + moved, moved);
                assert_eq!(
                    fast.to_array().map(f32::to_bits),
                    slow.to_array().map(f32::to_bits),
                    "{p:e} {offset}"
                );
            }
        }
    }

    #[test]
    fn spawn_ray_to_ends_at_the_target() {
        let point = SurfacePoint { p: Vec3::ZERO, error: Vec3::splat(1e-7), normal: Vec3::Y };
        let target = Vec3::new(0.0, 5.0, 0.0);
        let ray = point.spawn_ray_to(target);
        assert!((ray.at(ray.t_max) - target).length() < 1e-6);
    }
}
