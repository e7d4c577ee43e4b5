//! Axis-aligned bounding boxes and the robust ray/box slab test.

use glam::{Vec3, Vec3A};

use crate::float::gamma;
use crate::ray::Ray;

/// An axis-aligned box `[min, max]`. The empty box has `min = +∞`, `max = −∞`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// Lowest corner.
    pub min: Vec3,
    /// Highest corner.
    pub max: Vec3,
}

impl Default for Bounds {
    fn default() -> Self {
        Bounds::EMPTY
    }
}

impl Bounds {
    /// Contains nothing; the identity of [`union`](Self::union).
    pub const EMPTY: Bounds = Bounds { min: Vec3::INFINITY, max: Vec3::NEG_INFINITY };

    /// The box around a triangle.
    #[inline]
    pub fn of_triangle([a, b, c]: [Vec3; 3]) -> Bounds {
        Bounds { min: a.min(b).min(c), max: a.max(b).max(c) }
    }

    /// The smallest box containing both.
    #[inline]
    pub fn union(self, other: Bounds) -> Bounds {
        Bounds { min: self.min.min(other.min), max: self.max.max(other.max) }
    }

    /// The smallest box containing this one and `p`.
    #[inline]
    pub fn grow(self, p: Vec3) -> Bounds {
        Bounds { min: self.min.min(p), max: self.max.max(p) }
    }

    /// Whether the box contains nothing.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    /// The centre.
    #[inline]
    pub fn centroid(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// Half the surface area (the SAH only ever compares areas); zero for an empty box.
    #[inline]
    pub fn half_area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let d = self.max - self.min;
        d.x * d.y + d.y * d.z + d.z * d.x
    }

    /// The axis along which the box is longest (ties to the lowest axis).
    #[inline]
    pub fn longest_axis(&self) -> usize {
        let d = self.max - self.min;
        if d.x >= d.y && d.x >= d.z {
            0
        } else if d.y >= d.z {
            1
        } else {
            2
        }
    }
}

/// The per-ray part of the slab test, computed once per ray.
///
/// The test is conservative, so a bounding box never loses a hit on a triangle inside it (a BVH
/// must not open the cracks the watertight triangle test closes):
/// - the far distance is scaled up by `1 + 2γ₃`, which covers the rounding of `(b − o)·(1/d)` in
///   both distances (Ize, "Robust BVH Ray Traversal", JCGT 2(2), 2013);
/// - a direction component of ±0 gives `1/d = ±∞`, and a plane through the origin then gives
///   `0·∞ = NaN`. That axis must not constrain the ray (it runs inside the plane), so every
///   `min`/`max` below ignores a NaN operand, as IEEE `minNum`/`maxNum` and x86's `minps`/`maxps`
///   (NaN in the first operand) do.
#[derive(Clone, Copy, Debug)]
pub struct RayBoxTest {
    /// The ray's origin.
    pub origin: Vec3,
    /// `1 / direction`, per axis (±∞ for a zero component).
    pub inv_direction: Vec3,
    /// Per axis, whether the direction is negative (then the box's `max` plane is met first).
    pub negative: [bool; 3],
    /// The ray's `t_min`, clamped to be at least 0.
    pub t_min: f32,
    /// The ray's dominant axis, as the watertight triangle test picks it.
    pub dominant_axis: usize,
}

/// The factor on far distances that makes the slab test conservative.
pub const FAR_SCALE: f32 = 1.0 + 2.0 * gamma(3);

/// [`RayBoxTest::margin`]'s factor on the ray's reach `R`.
pub(crate) const MARGIN_SCALE: f32 = (SLAB_PAD + 4.0 * gamma(3)) * FAR_SCALE;

impl RayBoxTest {
    /// Prepares `ray`.
    #[inline]
    pub fn new(ray: &Ray) -> Self {
        let d = ray.direction;
        RayBoxTest {
            origin: ray.origin,
            // One division instruction for the three axes (`1.0 / d` exactly, per axis).
            inv_direction: Vec3::from(Vec3A::from(d).recip()),
            negative: [d.x.is_sign_negative(), d.y.is_sign_negative(), d.z.is_sign_negative()],
            t_min: ray.t_min.max(0.0),
            dominant_axis: crate::triangle::dominant_axis(d),
        }
    }

    /// The entry distance of the ray into `bounds` if it meets the box within `[t_min, t_max]`,
    /// both moved out by `SLAB_PAD` (see there).
    ///
    /// This is the box test of packets ([`Frustum`] is its superset); single rays use the
    /// leaner [`enter_with_margin`](Self::enter_with_margin). The ray must have a finite origin
    /// and a non-zero direction.
    #[inline]
    pub fn enter(&self, bounds: &Bounds, t_max: f32) -> Option<f32> {
        let mut near = self.t_min;
        let mut far = t_max;
        let mut reach = 0.0;
        for axis in 0..3 {
            let (near_plane, far_plane) = self.planes(bounds, axis);
            let inv = self.inv_direction[axis];
            let o = self.origin[axis];
            let t_near = (near_plane - o) * inv;
            let t_far = (far_plane - o) * inv;
            // `f32::max`/`min` return the other operand when one is NaN.
            near = t_near.max(near);
            far = (t_far * FAR_SCALE).min(far);
            if axis == self.dominant_axis {
                reach = t_near.abs().max(t_far.abs());
            }
        }
        let pad = reach * SLAB_PAD;
        let (near, far) = (near - pad, far + pad);
        (near <= far).then_some(near)
    }

    /// The box's near and far plane on `axis`: its `min` first for a positive direction.
    #[inline(always)]
    fn planes(&self, bounds: &Bounds, axis: usize) -> (f32, f32) {
        slab_planes(bounds, self.negative, axis)
    }

    /// The margin of [`enter_with_margin`](Self::enter_with_margin) for every box inside
    /// `root`.
    ///
    /// [`enter`](Self::enter) pays at every box for two margins that only depend on how far
    /// along the ray the box lies: the rounding of its slab distances (`FAR_SCALE`, relative to
    /// the distance) and the triangle test's error (`SLAB_PAD`, relative to the box's reach on
    /// the dominant axis). Inside `root` both are bounded once per ray by `R = L / |d_k|`, `L`
    /// the sum over the axes of the origin's greatest distance to the root's planes (at least
    /// the distance from the origin to any point of the root) and `d_k` the dominant component
    /// (at most `|d|`):
    /// - where the ray meets a box inside `root` exactly, it is inside `root`, so every slab
    ///   distance that decides the box's entry or exit is at most `R` in magnitude, and each
    ///   errs by at most `γ₃·R` (a subtraction and two products, the reciprocal included);
    /// - a box's reach on the dominant axis is at most `R` too.
    ///
    /// The margin is `(SLAB_PAD + 4γ₃)·R`, the rounding share taken four times (twice what the
    /// distances need, to cover the margin's own arithmetic with room to spare), scaled by
    /// `FAR_SCALE` for the rounding of `R`. A ray whose origin is far outside `root` gets a
    /// wider margin, never a wrong answer (an infinite one enters every box). An empty root has
    /// nothing inside it and gets none.
    #[inline(always)]
    pub fn margin(&self, root: &Bounds) -> f32 {
        if root.is_empty() {
            return 0.0;
        }
        let o = Vec3A::from(self.origin);
        let farthest = (Vec3A::from(root.min) - o).abs().max((Vec3A::from(root.max) - o).abs());
        let l = farthest.x + farthest.y + farthest.z;
        let r = l * crate::triangle::coordinate(self.inv_direction, self.dominant_axis).abs();
        r * MARGIN_SCALE
    }

    /// The entry distance into `bounds` if the ray meets it within `[t_min, t_limit]`, both
    /// moved out by `margin` ([`margin`](Self::margin) of a root box around `bounds`): the
    /// single-ray box test. It never prunes a box that [`enter`](Self::enter) would enter
    /// (the tests check it), at five operations per axis fewer.
    ///
    /// This is the portable node kernel and the scalar twin of the SSE2 one (and of the AVX2 and
    /// AVX-512 ones for rays without a fused form, [`FusedSlabs`]): they compute the same values
    /// in the same order of operations. The ray must have a finite origin and a non-zero
    /// direction.
    #[inline]
    pub fn enter_with_margin(&self, bounds: &Bounds, t_limit: f32, margin: f32) -> Option<f32> {
        let mut near = self.t_min;
        let mut far = t_limit;
        for axis in 0..3 {
            let (near_plane, far_plane) = self.planes(bounds, axis);
            let inv = self.inv_direction[axis];
            let o = self.origin[axis];
            // `f32::max`/`min` return the other operand when one is NaN.
            near = ((near_plane - o) * inv).max(near);
            far = ((far_plane - o) * inv).min(far);
        }
        let (near, far) = (near - margin, far + margin);
        (near <= far).then_some(near)
    }
}

/// The single-ray slab test in fused multiply-add form: per axis `t = plane·(1/d) + c` in one
/// rounding, with `c = −o·(1/d) ∓ m` (Embree's form, `fmsub(plane, rdir, org_rdir)`), so that a
/// node's boxes cost one FMA per plane and the ray's margin costs nothing per box.
///
/// The plain form `(plane − o)·(1/d)` errs by a few roundings of the distance itself; this one
/// errs also by a rounding of `o·(1/d)`, which may be far larger than the distance when the
/// scene lies far from the world's origin. So each axis gets its own margin
/// `m = (M + 4γ₃·|o·(1/d)|)·FAR_SCALE`, `M` the plain test's margin ([`RayBoxTest::margin`]):
/// the distance errs by at most `2u·(R + |o·(1/d)| + m)` to first order (the rounding of
/// `o·(1/d)`, of the addend, of the FMA, and of `1/d` within `R`), which `m`'s share beyond
/// `SLAB_PAD·R` covers with room to spare, as the plain margin covers its own.
///
/// Rays for which that bound does not hold in floating point — a zero, subnormal or infinite
/// `1/d` on some axis, or `o·(1/d)`, the margin or an addend overflowing — have no fused form
/// ([`RayBoxTest::fused`] is `None`) and use the plain test. So do rays whose origin lies so far
/// from the world's origin that `4γ₃·|o|` exceeds the plain margin in world units (`M·|d_k|`
/// on the dominant axis): there the fused margin would loosen every box by more than the plain
/// test's, in a scene far from the world's origin many times over. With every term finite no
/// distance is NaN, so the order of the `min`s and `max`s does not matter: near and far are
/// each reduced as a tree, one level shallower than a chain.
///
/// The scalar twin of the AVX2 and AVX-512 node kernels (`f32::mul_add` is the same single
/// rounding as their FMA).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FusedSlabs {
    /// `1/d` per axis (finite, non-zero).
    pub inv_direction: Vec3,
    /// `−o·(1/d) − m` per axis: the near planes' addend.
    pub near_add: Vec3,
    /// `−o·(1/d) + m` per axis: the far planes' addend.
    pub far_add: Vec3,
    /// `t_min − M`.
    pub t_min: f32,
    /// `M`, added to a query's limit.
    pub margin: f32,
    /// Per axis, whether the direction is negative.
    pub negative: [bool; 3],
}

impl RayBoxTest {
    /// The fused form of this ray's test with margin `margin` ([`margin`](Self::margin)), or
    /// `None` where its error bound does not hold (see [`FusedSlabs`]).
    #[inline]
    pub fn fused(&self, margin: f32) -> Option<FusedSlabs> {
        // The fused margin's world-space share, `4γ₃·|o|`, against the plain margin's, both in
        // units of `t` along the dominant axis (a product rather than the plain margin's
        // division by `|1/d_k|`).
        let inv_dominant = crate::triangle::coordinate(self.inv_direction, self.dominant_axis);
        if 4.0 * gamma(3) * self.origin.abs().max_element() * inv_dominant.abs() > margin {
            return None;
        }
        // The three axes at once (the same operations per axis as one at a time).
        let inv = Vec3A::from(self.inv_direction);
        let q = Vec3A::from(self.origin) * inv;
        let m = (Vec3A::splat(margin) + Vec3A::splat(4.0 * gamma(3)) * q.abs()) * FAR_SCALE;
        let (near, far) = (-q - m, -q + m);
        // Finite addends mean a finite `q` and margin.
        let usable = inv.is_finite_mask()
            & inv.abs().cmpge(Vec3A::splat(f32::MIN_POSITIVE))
            & near.is_finite_mask()
            & far.is_finite_mask();
        if !usable.all() {
            return None;
        }
        let (near_add, far_add) = (Vec3::from(near), Vec3::from(far));
        let t_min = self.t_min - margin;
        t_min.is_finite().then_some(FusedSlabs {
            inv_direction: self.inv_direction,
            near_add,
            far_add,
            t_min,
            margin,
            negative: self.negative,
        })
    }
}

impl FusedSlabs {
    /// The entry distance into `bounds` (moved out by the margins) if the ray may meet it
    /// within `[t_min, t_limit]`: never `None` where [`RayBoxTest::enter`] enters (the tests
    /// check it).
    #[inline]
    pub fn enter(&self, bounds: &Bounds, t_limit: f32) -> Option<f32> {
        let mut tn = [0.0f32; 3];
        let mut tf = [0.0f32; 3];
        for axis in 0..3 {
            let (near_plane, far_plane) = slab_planes(bounds, self.negative, axis);
            let inv = self.inv_direction[axis];
            tn[axis] = near_plane.mul_add(inv, self.near_add[axis]);
            tf[axis] = far_plane.mul_add(inv, self.far_add[axis]);
        }
        let near = tn[0].max(tn[1]).max(tn[2].max(self.t_min));
        let far = tf[0].min(tf[1]).min(tf[2].min(t_limit + self.margin));
        (near <= far).then_some(near)
    }
}

/// The slab test of a whole packet of rays at once: a box passes if any ray of the packet may
/// enter it, as [`RayBoxTest::enter`] decides for each ray (Reshetov et al., "Multi-Level Ray
/// Tracing Algorithm", 2005, and Wald et al., "Ray Tracing Deformable Scenes Using Dynamic
/// Bounding Volume Hierarchies", 2007, bound a packet by its interval arithmetic).
///
/// Per axis it holds the intervals of the rays' origins and of their `1/d`, which must not
/// change sign within the packet. Each ray's slab distance `(plane − o)·(1/d)` then lies between
/// the least and the greatest of the four corner products, *also after rounding*, because
/// rounding is monotonic: so the packet's entry is at most each ray's entry, its exit at least
/// each ray's exit, and its margin at least each ray's `SLAB_PAD` margin. The packet test is
/// thus a superset of every member's test, in floating point, and can never prune a box that
/// one of its rays would enter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frustum {
    /// Per axis, the least origin coordinate.
    pub origin_lo: Vec3,
    /// Per axis, the greatest origin coordinate.
    pub origin_hi: Vec3,
    /// Per axis, the least `1/d` (all of one sign, finite and non-zero).
    pub inv_lo: Vec3,
    /// Per axis, the greatest `1/d`.
    pub inv_hi: Vec3,
    /// Per axis, whether the directions are negative.
    pub negative: [bool; 3],
    /// The least `t_min`.
    pub t_min: f32,
    /// The axes that are some ray's dominant axis: the margin is taken over these.
    pub pad_axes: [bool; 3],
}

impl Frustum {
    /// The bound of the rays, or `None` if they cannot share one: no rays, a direction whose
    /// signs differ from the first ray's, or a direction component that is zero or so small
    /// that `1/d` is infinite (such rays are traced one by one).
    pub fn of(rays: impl IntoIterator<Item = RayBoxTest>) -> Option<Frustum> {
        let mut rays = rays.into_iter().peekable();
        let first = *rays.peek()?;
        let mut f = Frustum {
            origin_lo: first.origin,
            origin_hi: first.origin,
            inv_lo: first.inv_direction,
            inv_hi: first.inv_direction,
            negative: first.negative,
            t_min: first.t_min,
            pad_axes: [false; 3],
        };
        for ray in rays {
            if !Frustum::can_join(&ray) || ray.negative != f.negative {
                return None;
            }
            f.origin_lo = f.origin_lo.min(ray.origin);
            f.origin_hi = f.origin_hi.max(ray.origin);
            f.inv_lo = f.inv_lo.min(ray.inv_direction);
            f.inv_hi = f.inv_hi.max(ray.inv_direction);
            f.t_min = f.t_min.min(ray.t_min);
            f.pad_axes[ray.dominant_axis] = true;
        }
        Some(f)
    }

    /// Whether a ray may be part of a packet: a finite origin and a finite, non-zero `1/d` on
    /// every axis (so that no slab product is NaN).
    #[inline]
    pub fn can_join(ray: &RayBoxTest) -> bool {
        ray.origin.is_finite()
            && ray.inv_direction.is_finite()
            && ray.inv_direction.cmpne(Vec3::ZERO).all()
            && ray.t_min.is_finite()
    }

    /// The packet's entry distance into `bounds`, if some ray of the packet may enter it within
    /// `[t_min, t_max]`; `t_max` must be at least every member's own limit.
    ///
    /// The scalar twin of the SIMD frustum kernels, which compute the same values in the same
    /// order.
    #[inline]
    pub fn enter(&self, bounds: &Bounds, t_max: f32) -> Option<f32> {
        let mut near = self.t_min;
        let mut far = t_max;
        let mut reach = 0.0f32;
        for axis in 0..3 {
            let (near_plane, far_plane) = slab_planes(bounds, self.negative, axis);
            let (o_lo, o_hi) = (self.origin_lo[axis], self.origin_hi[axis]);
            let (i_lo, i_hi) = (self.inv_lo[axis], self.inv_hi[axis]);
            let (tn_lo, tn_hi) = interval_product(near_plane - o_hi, near_plane - o_lo, i_lo, i_hi);
            let (tf_lo, tf_hi) = interval_product(far_plane - o_hi, far_plane - o_lo, i_lo, i_hi);
            near = tn_lo.max(near);
            far = (tf_hi * FAR_SCALE).min(far);
            if self.pad_axes[axis] {
                reach = reach.max(tn_lo.abs().max(tn_hi.abs()).max(tf_lo.abs().max(tf_hi.abs())));
            }
        }
        let pad = reach * SLAB_PAD;
        let (near, far) = (near - pad, far + pad);
        (near <= far).then_some(near)
    }
}

/// A box's near and far plane on `axis` for rays whose directions have the signs `negative`:
/// its `min` first for a positive direction.
#[inline(always)]
fn slab_planes(bounds: &Bounds, negative: [bool; 3], axis: usize) -> (f32, f32) {
    if negative[axis] {
        (bounds.max[axis], bounds.min[axis])
    } else {
        (bounds.min[axis], bounds.max[axis])
    }
}

/// The least and greatest of the products of `[a_lo, a_hi]` and `[i_lo, i_hi]`: the bounds of
/// a product over the two intervals (its extremes are at corners).
#[inline(always)]
fn interval_product(a_lo: f32, a_hi: f32, i_lo: f32, i_hi: f32) -> (f32, f32) {
    let (p0, p1, p2, p3) = (a_lo * i_lo, a_lo * i_hi, a_hi * i_lo, a_hi * i_hi);
    (p0.min(p1).min(p2.min(p3)), p0.max(p1).max(p2.max(p3)))
}

/// The relative margin, on the box's reach along the ray's dominant axis, by which box entry
/// and exit are moved out.
///
/// The slab test's own rounding is covered by [`FAR_SCALE`], but a BVH must also never prune a
/// box whose triangle the watertight test would hit at a `t` that rounds below the box's entry
/// (or above its exit, against a segment's end). That test's error in `t` grows with the
/// vertices' distance from the origin along the dominant axis (PBR 4th ed. §6.8.4: `δt` is
/// proportional to `max |zᵢ|`), which for a triangle inside the box is at most the box's reach
/// `max(|t_near|, |t_far|)` on that axis. Flat, axis-aligned triangles seen along another axis
/// err by about 1e-6 of that reach; the margin is 32 units of `f32::EPSILON` (3.8e-6).
pub const SLAB_PAD: f32 = 32.0 * f32::EPSILON;

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box() -> Bounds {
        Bounds { min: Vec3::ZERO, max: Vec3::ONE }
    }

    /// An entry distance: `expected`, moved out by at most the pad on a reach of `reach`.
    fn assert_entry(entry: Option<f32>, expected: f32, reach: f32) {
        let entry = entry.expect("the box is entered");
        assert!(
            entry <= expected && entry >= expected - 2.0 * SLAB_PAD * reach,
            "{entry} vs {expected}"
        );
    }

    #[test]
    fn enters_at_the_near_face_from_any_direction() {
        let b = unit_box();
        let from_left = RayBoxTest::new(&Ray::new(Vec3::new(-1.0, 0.5, 0.5), Vec3::X));
        assert_entry(from_left.enter(&b, f32::INFINITY), 1.0, 2.0);
        let from_right = RayBoxTest::new(&Ray::new(Vec3::new(3.0, 0.5, 0.5), -Vec3::X));
        assert_entry(from_right.enter(&b, f32::INFINITY), 2.0, 3.0);
        assert_eq!(from_right.enter(&b, 1.9), None);
        let inside = RayBoxTest::new(&Ray::new(Vec3::splat(0.5), Vec3::Y));
        assert_entry(inside.enter(&b, f32::INFINITY), 0.0, 0.5);
        let behind = RayBoxTest::new(&Ray::new(Vec3::new(2.0, 0.5, 0.5), Vec3::X));
        assert_eq!(behind.enter(&b, f32::INFINITY), None);
    }

    #[test]
    fn axis_parallel_rays_in_a_face_plane_hit_with_either_signed_zero() {
        let b = unit_box();
        // The ray runs inside the plane x = 0, which is the box's face: 0·∞ = NaN must not reject.
        for dx in [0.0, -0.0] {
            for dy in [0.0, -0.0] {
                let ray = Ray::new(Vec3::new(0.0, 0.0, -1.0), Vec3::new(dx, dy, 1.0));
                assert_entry(RayBoxTest::new(&ray).enter(&b, f32::INFINITY), 1.0, 2.0);
                let outside = Ray::new(Vec3::new(-1e-3, 0.5, -1.0), Vec3::new(dx, dy, 1.0));
                assert_eq!(RayBoxTest::new(&outside).enter(&b, f32::INFINITY), None);
            }
        }
    }

    #[test]
    fn flat_boxes_are_hit() {
        let flat = Bounds { min: Vec3::new(0.0, 0.0, 1.0), max: Vec3::new(1.0, 1.0, 1.0) };
        let ray = Ray::new(Vec3::new(0.5, 0.5, 0.0), Vec3::Z);
        assert_entry(RayBoxTest::new(&ray).enter(&flat, f32::INFINITY), 1.0, 1.0);
    }

    #[test]
    fn the_empty_box_is_never_hit() {
        let ray = Ray::new(Vec3::ZERO, Vec3::ONE);
        assert_eq!(RayBoxTest::new(&ray).enter(&Bounds::EMPTY, f32::INFINITY), None);
        assert_eq!(Bounds::EMPTY.half_area(), 0.0);
    }
}
