//! The watertight triangle test lane by lane, over any [`Lanes`] width.
//!
//! [`watertight_lanes_with`] is [`WatertightRay::intersect`] lane by lane, the same operations
//! in the same order, so every lane decides as the scalar test does. Its second half,
//! [`watertight_sheared`], starts from corners already in the ray's frame ([`shear_point`]), so
//! that a leaf record can transform each of its shared vertices once.

use super::{LaneMask, Lanes};
use crate::triangle::{WatertightRay, coordinate};

/// The watertight test's inputs, one test per lane: the lanes are either triangles against one
/// ray (a flat list's sixteen) or rays against one triangle (packets). Every
/// coordinate is already permuted to the ray's `(kx, ky, kz)`.
pub(crate) struct WatertightLanes<V> {
    /// The ray origin's `kx`, `ky`, `kz` coordinates.
    pub origin: [V; 3],
    /// `shear_x`, `shear_y`, `shear_z`.
    pub shear: [V; 3],
    /// `|shear_x|`, `|shear_y|`.
    pub abs_shear: [V; 2],
    /// The ray's `t_min` (see [`WatertightRay::intersect`]).
    pub t_min: V,
    /// Hits are accepted below this.
    pub t_max: V,
    /// `vertices[j]`: vertex `j`'s `kx`, `ky`, `kz` coordinates.
    pub vertices: [[V; 3]; 3],
}

/// What [`watertight_lanes_with`] decides per lane.
pub(crate) struct LaneHits<V: Lanes> {
    /// Lanes hit, with `t` and barycentrics below.
    pub hits: u32,
    /// `hits` as a comparison mask (lanes outside `lanes` included where their
    /// triangles are hit: padding lanes hold NaN vertices, which never are).
    pub hit_mask: V::Mask,
    /// Lanes that only [`WatertightRay::intersect`] can decide (an edge function is zero).
    pub undecided: u32,
    pub t: V,
    pub b1: V,
    pub b2: V,
}

/// [`WatertightRay::intersect`] lane by lane, for triangles of non-zero area (or NaN
/// vertices, which never hit). Every value is computed by the same operations in the same
/// order (no fused multiply-add), so every decision, `t` and barycentric is the same bit for
/// bit; lanes whose edge functions round to exactly zero are left `undecided` for the scalar
/// test's double-precision path. `lanes` masks the lanes that count.
///
/// # Safety
/// The CPU must support `V`'s instruction set.
#[inline(always)]
pub(crate) unsafe fn watertight_lanes_with<V: Lanes, const EARLY_OUT: bool>(
    x: &WatertightLanes<V>,
    lanes: u32,
) -> LaneHits<V> {
    // SAFETY: the caller's guarantee.
    unsafe {
        // No closures (`.map(..)`): they would not inherit the caller's target features.
        let [a, b, c] = x.vertices;
        let [ax, ay, az] = shear_point(x.origin, x.shear, a);
        let [bx, by, bz] = shear_point(x.origin, x.shear, b);
        let [cx, cy, cz] = shear_point(x.origin, x.shear, c);
        let sheared = ShearedLanes { x: [ax, bx, cx], y: [ay, by, cy], z: [az, bz, cz] };
        let ray = RayLanes {
            shear_z: x.shear[2],
            abs_shear: x.abs_shear,
            t_min: x.t_min,
            t_max: x.t_max,
        };
        watertight_sheared::<V, EARLY_OUT>(&sheared, &ray, lanes)
    }
}

/// A point (its `kx`, `ky`, `kz` coordinates) in the ray's frame, as
/// [`WatertightRay::intersect`] computes it: `[x − shear_x·z, y − shear_y·z, z]` of the point
/// relative to the ray's origin (`z` not yet scaled by `shear_z`).
///
/// # Safety
/// The CPU must support `V`'s instruction set.
#[inline(always)]
pub(crate) unsafe fn shear_point<V: Lanes>(origin: [V; 3], shear: [V; 3], p: [V; 3]) -> [V; 3] {
    // SAFETY: the caller's guarantee.
    unsafe {
        let (kx, ky, kz) = (p[0].sub(origin[0]), p[1].sub(origin[1]), p[2].sub(origin[2]));
        [kx.sub(shear[0].mul(kz)), ky.sub(shear[1].mul(kz)), kz]
    }
}

/// The corners of the lanes' triangles in the ray's frame ([`shear_point`]), corner by corner.
pub(crate) struct ShearedLanes<V> {
    pub x: [V; 3],
    pub y: [V; 3],
    pub z: [V; 3],
}

/// What [`watertight_sheared`] needs of the ray besides the sheared corners.
pub(crate) struct RayLanes<V> {
    pub shear_z: V,
    /// `|shear_x|`, `|shear_y|`.
    pub abs_shear: [V; 2],
    pub t_min: V,
    pub t_max: V,
}

/// [`watertight_lanes_with`] from the corners already in the ray's frame.
///
/// # Safety
/// The CPU must support `V`'s instruction set.
#[inline(always)]
pub(crate) unsafe fn watertight_sheared<V: Lanes, const EARLY_OUT: bool>(
    sheared: &ShearedLanes<V>,
    ray: &RayLanes<V>,
    lanes: u32,
) -> LaneHits<V> {
    // SAFETY: the caller's guarantee.
    unsafe {
        let sz = ray.shear_z;
        let scaled = [sz.mul(sheared.z[0]), sz.mul(sheared.z[1]), sz.mul(sheared.z[2])];
        watertight_sheared_scaled::<V, EARLY_OUT>(sheared, scaled, ray, lanes)
    }
}

/// [`watertight_sheared`] with the corners' `kz` coordinates already scaled by the ray's
/// `shear_z` (`scaled`): for corners put in the ray's frame once and tested in many triangles.
///
/// # Safety
/// The CPU must support `V`'s instruction set.
#[inline(always)]
pub(crate) unsafe fn watertight_sheared_scaled<V: Lanes, const EARLY_OUT: bool>(
    sheared: &ShearedLanes<V>,
    [az, bz, cz]: [V; 3],
    ray: &RayLanes<V>,
    lanes: u32,
) -> LaneHits<V> {
    use crate::float::gamma;
    // SAFETY: the caller's guarantee.
    unsafe {
        let [ax, bx, cx] = sheared.x;
        let [ay, by, cy] = sheared.y;
        let [a_kz, b_kz, c_kz] = sheared.z;
        let e0 = bx.mul(cy).sub(by.mul(cx));
        let e1 = cx.mul(ay).sub(cy.mul(ax));
        let e2 = ax.mul(by).sub(ay.mul(bx));
        let zero = V::splat(0.0);
        let any_zero = e0.eq(zero).or(e1.eq(zero)).or(e2.eq(zero));
        // The scalar test's `all >= 0 or all <= 0`, by sign bits: for edge functions none of
        // which is zero (the lanes that have one are decided apart) it holds exactly where
        // the three signs agree; NaN lanes are rejected below by the range test.
        let inside = e0.xor(e1).or_bits(e0.xor(e2)).sign_clear();
        let det = e0.add(e1).add(e2);
        let t_scaled = e0.mul(az).add(e1.mul(bz)).add(e2.mul(cz));
        let t_limit = ray.t_max.mul(det).mul(V::splat(crate::triangle::T_LIMIT_SLACK));
        // `det > 0 and 0 < t_scaled < t_limit`, or the same mirrored for `det < 0`: both as
        // one test on `t_scaled` and `t_limit` with `det`'s sign taken off (`det` = ±0
        // gives `t_limit` = ±0 or NaN, which admit nothing, as the scalar test's `det == 0`
        // rejection; a NaN `det` gives a NaN `t_limit`).
        let det_sign = det.sign();
        let t_scaled_unsigned = t_scaled.xor(det_sign);
        let t_limit_unsigned = t_limit.xor(det_sign);
        let in_range = t_scaled_unsigned.gt(zero).and(t_scaled_unsigned.lt(t_limit_unsigned));
        let candidate = any_zero.or(inside.and(in_range));
        let candidates = candidate.bits() & lanes;
        let undecided = candidates & any_zero.bits();
        let decidable = candidates & !undecided;
        if EARLY_OUT && decidable == 0 {
            let none = zero.lt(zero);
            return LaneHits { hits: 0, hit_mask: none, undecided, t: zero, b1: zero, b2: zero };
        }

        // The rest of `intersect`, for the lanes without a zero edge function.
        let inv_det = V::splat(1.0).div(det);
        let t = t_scaled.mul(inv_det);
        // `t.is_nan() || t >= t_max` rejects: accept `t < t_max` (false for NaN).
        let below_max = t.lt(ray.t_max);
        // With `t_min > 0`, `t < t_min` rejects; otherwise `t <= delta_t`.
        let explicit = ray.t_min.gt(zero);
        let explicit_bits = explicit.bits() & decidable;
        let mut accept = below_max.and(explicit).and(t.nlt(ray.t_min));
        if explicit_bits != decidable {
            // The same expression as `conservative_delta_t`.
            let max3 = |a: V, b: V, c: V| a.abs().max(b.abs()).max(c.abs());
            let max_zt = max3(az, bz, cz);
            let delta_z = V::splat(gamma(3)).mul(max_zt);
            let max_xt = max3(ax, bx, cx);
            let max_yt = max3(ay, by, cy);
            let max_unsheared_z = max3(a_kz, b_kz, c_kz);
            let delta_x = V::splat(gamma(5)).mul(max_xt.add(ray.abs_shear[0].mul(max_unsheared_z)));
            let delta_y = V::splat(gamma(5)).mul(max_yt.add(ray.abs_shear[1].mul(max_unsheared_z)));
            let delta_e = V::splat(2.0).mul(
                V::splat(gamma(2))
                    .mul(max_xt)
                    .mul(max_yt)
                    .add(delta_y.mul(max_xt))
                    .add(delta_x.mul(max_yt)),
            );
            let max_e = max3(e0, e1, e2);
            let sum = V::splat(gamma(3))
                .mul(max_e)
                .mul(max_zt)
                .add(delta_e.mul(max_zt))
                .add(delta_z.mul(max_e));
            let delta_t = V::splat(3.0).mul(sum).mul(inv_det.abs());
            accept = accept.or(below_max.and(t.nle(delta_t)).andnot_of(explicit));
        }
        let hit_mask = accept.and(candidate).andnot_of(any_zero);
        let hits = decidable & accept.bits();
        debug_assert_eq!(hits, hit_mask.bits() & lanes, "the mask is the bits");
        LaneHits { hits, hit_mask, undecided, t, b1: e1.mul(inv_det), b2: e2.mul(inv_det) }
    }
}

/// A ray's part of the watertight test broadcast into registers `V` once per query, permuted to
/// its `(kx, ky, kz)`: what the lane tests of leaf records and of the flat list start from.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RayBroadcast<V> {
    /// The origin's `kx`, `ky`, `kz` coordinates.
    pub origin: [V; 3],
    /// `shear_x`, `shear_y`, `shear_z`.
    pub shear: [V; 3],
    /// `|shear_x|`, `|shear_y|`.
    pub abs_shear: [V; 2],
    pub t_min: V,
    /// `kx`, `ky`, `kz`.
    pub k: [usize; 3],
}

impl<V: Lanes> RayBroadcast<V> {
    /// # Safety
    /// The CPU must support `V`'s instruction set.
    #[inline(always)]
    pub(crate) unsafe fn new(ray: &WatertightRay) -> Self {
        let (kx, ky, kz) = (ray.kx, ray.ky, ray.kz);
        // SAFETY: the caller's guarantee.
        unsafe {
            RayBroadcast {
                origin: [
                    V::splat(coordinate(ray.origin, kx)),
                    V::splat(coordinate(ray.origin, ky)),
                    V::splat(coordinate(ray.origin, kz)),
                ],
                shear: [V::splat(ray.shear_x), V::splat(ray.shear_y), V::splat(ray.shear_z)],
                abs_shear: [V::splat(ray.shear_x.abs()), V::splat(ray.shear_y.abs())],
                t_min: V::splat(ray.t_min),
                k: [kx, ky, kz],
            }
        }
    }

    /// What [`watertight_sheared`] needs of the ray besides the corners, below `t_max`.
    ///
    /// # Safety
    /// The CPU must support `V`'s instruction set.
    #[inline(always)]
    pub(crate) unsafe fn lanes(&self, t_max: f32) -> RayLanes<V> {
        RayLanes {
            shear_z: self.shear[2],
            abs_shear: self.abs_shear,
            t_min: self.t_min,
            // SAFETY: the caller's guarantee.
            t_max: unsafe { V::splat(t_max) },
        }
    }

    /// The whole test's inputs for the triangles whose corners are `vertices` (permuted).
    ///
    /// # Safety
    /// The CPU must support `V`'s instruction set.
    #[inline(always)]
    pub(crate) unsafe fn with_vertices(
        &self,
        vertices: [[V; 3]; 3],
        t_max: f32,
    ) -> WatertightLanes<V> {
        WatertightLanes {
            origin: self.origin,
            shear: self.shear,
            abs_shear: self.abs_shear,
            t_min: self.t_min,
            // SAFETY: the caller's guarantee.
            t_max: unsafe { V::splat(t_max) },
            vertices,
        }
    }
}
