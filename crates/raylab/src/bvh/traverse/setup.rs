//! A single ray's kernels ([`Kernel`]: the node test and the leaf records' test of one
//! instruction set), the queries run on them ([`Query`]), and the ray's set-up.
//!
//! The set-up is what every query of one ray computes before it tests the root. That
//! is the box test's form and margin ([`RayBoxTest`],
//! [`FusedSlabs`](crate::bvh::bounds::FusedSlabs)), the watertight test's frame and shear
//! ([`WatertightRay`]), and both broadcast into the kernels' registers.
//!
//! [`setup_portable`] builds it from those types, axis by axis. It is the set-up of the
//! portable and SSE2 kernels, and the twin of [`query_avx2`], the AVX2 and AVX-512 kernels'
//! set-up. That one computes the same values in SSE registers, three axes at once. It permutes
//! the origin, the direction and `1/d` into the ray's frame with one `vpermilps` each, where
//! the portable code picks coordinates by indexed loads from the stack. It broadcasts each
//! value once. Rays without a fused form (a zero, tiny or huge `1/d`, an origin far from the
//! world's origin) go to the plain test, set up as [`setup_portable`] does.
//!
//! Every operation is the portable code's, in the same order, so the two agree bit for bit; the
//! tests below check it on hostile rays.

use crate::bvh::bounds::RayBoxTest;
use crate::bvh::leaf::TriangleRay;
use crate::bvh::leaf::kernel::{RecordKernel, prepare_triangle_ray};
use crate::bvh::node::WideBvh;
use crate::bvh::node::kernel::{BoxRay, NodeKernel, NodeRay};
use crate::ray::Ray;
use crate::triangle::WatertightRay;

/// A single ray's kernels: the node test and the leaf records' test of one instruction set,
/// and the ray's set-up for both (this file).
pub(crate) trait Kernel: NodeKernel + RecordKernel {
    /// Sets `ray` up and runs `query` on it, or answers `None` if it can hit nothing
    /// ([`can_hit`]). The query runs in the branch that set the ray up, fused or plain, so that
    /// the set-up's values reach the traversal in registers rather than through a merged
    /// struct, which the compiler copies field by field.
    ///
    /// The default is the portable set-up ([`setup_portable`]).
    ///
    /// # Safety
    /// The CPU must support the kernels' instruction set.
    #[inline(always)]
    unsafe fn query<Q: Query<Self>>(bvh: &WideBvh, ray: &Ray, query: Q) -> Option<Q::Output> {
        // SAFETY: the caller's guarantee.
        let prepared = unsafe { setup_portable::<Self>(bvh, ray) }?;
        // SAFETY: the caller's guarantee.
        Some(unsafe { run_prepared(bvh, &prepared, query) })
    }
}

/// What a single-ray query does once its ray is set up: a traversal, for either form of the
/// box test.
pub(crate) trait Query<K: Kernel> {
    type Output;

    /// # Safety
    /// The CPU must support `K`'s instruction set.
    unsafe fn run<B: BoxRay>(
        self,
        bvh: &WideBvh,
        box_ray: &B,
        triangle_ray: &TriangleRay<K::RecordRay>,
        t_max: f32,
    ) -> Self::Output;
}

/// `query` on a prepared ray, in its fused or plain form.
///
/// # Safety
/// The CPU must support `K`'s instruction set.
#[inline(always)]
pub(crate) unsafe fn run_prepared<K: Kernel, Q: Query<K>>(
    bvh: &WideBvh,
    prepared: &Prepared<K>,
    query: Q,
) -> Q::Output {
    let (triangle_ray, t_max) = (&prepared.triangle_ray, prepared.t_max);
    match &prepared.box_ray {
        NodeRay::Fused(b) => {
            // SAFETY: the caller's guarantee.
            unsafe { query.run(bvh, b, triangle_ray, t_max) }
        }
        NodeRay::Plain(b) => {
            // SAFETY: the caller's guarantee.
            unsafe { query.run(bvh, b, triangle_ray, t_max) }
        }
    }
}

impl Kernel for crate::bvh::isa::Scalar {}

#[cfg(target_arch = "x86_64")]
impl Kernel for crate::bvh::isa::Sse {}

#[cfg(target_arch = "x86_64")]
impl Kernel for crate::bvh::isa::Avx2 {
    #[inline(always)]
    unsafe fn query<Q: Query<Self>>(bvh: &WideBvh, ray: &Ray, query: Q) -> Option<Q::Output> {
        // SAFETY: the caller's guarantee (AVX2 and FMA).
        unsafe { query_avx2::<Self, Q>(bvh, ray, query) }
    }
}

#[cfg(target_arch = "x86_64")]
impl Kernel for crate::bvh::isa::Avx512 {
    #[inline(always)]
    unsafe fn query<Q: Query<Self>>(bvh: &WideBvh, ray: &Ray, query: Q) -> Option<Q::Output> {
        // SAFETY: the caller's guarantee (AVX-512 implies AVX2 and FMA).
        unsafe { query_avx2::<Self, Q>(bvh, ray, query) }
    }
}

/// Whether the ray can hit anything at all: an empty or NaN range, a non-finite origin, or a zero
/// or NaN direction never hit a triangle (the triangle test rejects them too); the slab kernels
/// may then assume a finite origin and a finite `1/d` on the dominant axis.
#[inline(always)]
pub(crate) fn can_hit(ray: &Ray) -> bool {
    ray.t_min <= ray.t_max
        && ray.origin.is_finite()
        && !ray.direction.is_nan()
        && ray.direction != glam::Vec3::ZERO
}

/// A single ray prepared for `K`'s kernels, kept for several queries (`tree_rays.rs`).
#[derive(Clone, Copy)]
pub(crate) struct Prepared<K: Kernel> {
    pub(crate) box_ray: NodeRay<K::Fused, K::Plain>,
    pub(crate) triangle_ray: TriangleRay<K::RecordRay>,
    pub(crate) t_max: f32,
}

impl<K: Kernel> Prepared<K> {
    /// `ray` prepared, or `None` if it can hit nothing ([`can_hit`]).
    ///
    /// # Safety
    /// The CPU must support `K`'s instruction set.
    #[inline(always)]
    pub(crate) unsafe fn new(bvh: &WideBvh, ray: &Ray) -> Option<Self> {
        // SAFETY: the caller's guarantee.
        unsafe { setup_portable::<K>(bvh, ray) }
    }
}

/// `ray` set up for `K`'s kernels from the scalar types, or `None` if it can hit nothing
/// ([`can_hit`]).
///
/// # Safety
/// The CPU must support `K`'s instruction set.
#[inline(always)]
pub(crate) unsafe fn setup_portable<K: Kernel>(bvh: &WideBvh, ray: &Ray) -> Option<Prepared<K>> {
    if !can_hit(ray) {
        return None;
    }
    let box_ray = RayBoxTest::new(ray);
    let margin = box_ray.margin(&bvh.root);
    let triangle_ray = WatertightRay::with_inverse(ray, box_ray.inv_direction);
    // SAFETY: (both) the caller guarantees `K`'s instruction set.
    let triangle_ray = unsafe { prepare_triangle_ray::<K>(&triangle_ray) };
    // SAFETY: as above.
    let box_ray = unsafe { K::prepare(&box_ray, margin) };
    Some(Prepared { box_ray, triangle_ray, t_max: ray.t_max })
}

#[cfg(target_arch = "x86_64")]
pub(crate) use x86::query_avx2;

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    use super::*;
    use crate::bvh::bounds::{FAR_SCALE, MARGIN_SCALE};
    use crate::bvh::leaf::TriangleRay;
    use crate::bvh::node::kernel::{Broadcast, FusedBroadcast, NodeKernel, broadcast3};
    use crate::bvh::simd::RayBroadcast;
    use crate::float::gamma;

    /// The ray's frame for each dominant axis `kz` and sign of the direction on it (index
    /// `2·kz + negative`): the `vpermilps` control that puts `kx`, `ky`, `kz` in lanes 0 to 2,
    /// and `[kx, ky, kz]`. As [`WatertightRay`] picks them: `kx` and `ky` follow `kz`
    /// cyclically, swapped where the direction is negative on `kz`.
    const FRAMES: [([i32; 4], [usize; 3]); 6] = [
        ([1, 2, 0, 3], [1, 2, 0]),
        ([2, 1, 0, 3], [2, 1, 0]),
        ([2, 0, 1, 3], [2, 0, 1]),
        ([0, 2, 1, 3], [0, 2, 1]),
        ([0, 1, 2, 3], [0, 1, 2]),
        ([1, 0, 2, 3], [1, 0, 2]),
    ];

    /// The `_mm_shuffle_ps`/`_mm_permute_ps` control taking lanes `[a, b, c, d]`.
    const fn pick(a: i32, b: i32, c: i32, d: i32) -> i32 {
        a | b << 2 | c << 4 | d << 6
    }

    /// [`Kernel::query`] for the AVX2 and AVX-512 kernels: the ray set up as [`setup_portable`]
    /// does, in SSE registers (see the module documentation), and `query` run on it.
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA (and `K`'s instruction set).
    #[inline(always)]
    pub(crate) unsafe fn query_avx2<K, Q: Query<K>>(
        bvh: &WideBvh,
        ray: &Ray,
        query: Q,
    ) -> Option<Q::Output>
    where
        K: Kernel
            + NodeKernel<Fused = FusedBroadcast, Plain = Broadcast<__m256>>
            + crate::bvh::leaf::kernel::RecordKernel<RecordRay = RayBroadcast<__m256>>,
    {
        // SAFETY: the caller guarantees AVX2; both loads read 16 bytes inside the `Ray`
        // (`repr(C)`: origin at byte 0, direction at 12, `t_min` at 24, 32 bytes in all),
        // through a pointer to the whole `Ray`.
        unsafe {
            let base = (ray as *const Ray).cast::<f32>();
            // Lanes: `o = (ox, oy, oz, dx)`, `d = (dx, dy, dz, t_min)`; lane 3 is never used.
            let o = _mm_loadu_ps(base);
            let d = _mm_loadu_ps(base.add(3));
            let (t_min, t_max) = (ray.t_min, ray.t_max);
            let zero = _mm_setzero_ps();
            let abs_bits = _mm_castsi128_ps(_mm_set1_epi32(i32::MAX));
            let abs = |v: __m128| _mm_and_ps(v, abs_bits);
            let bits = |mask: __m128| _mm_movemask_ps(mask) as usize & 7;
            let infinity = _mm_set1_ps(f32::INFINITY);

            // `can_hit`: an ordered range, a finite origin, a direction neither NaN nor zero.
            let origin_finite = bits(_mm_cmplt_ps(abs(o), infinity)) == 7;
            let direction_ordered = bits(_mm_cmpord_ps(d, d)) == 7;
            let direction_nonzero = bits(_mm_cmpneq_ps(d, zero)) != 0;
            if !(t_min <= t_max && origin_finite && direction_ordered && direction_nonzero) {
                return None;
            }

            // `RayBoxTest::new`: `1/d` in one division, the signs, the dominant axis.
            let inv = _mm_div_ps(_mm_set1_ps(1.0), d);
            let octant = _mm_movemask_ps(d) as usize & 7;
            let abs_d = abs(d);
            let next = bits(_mm_cmpge_ps(abs_d, _mm_permute_ps::<{ pick(1, 2, 0, 3) }>(abs_d)));
            let prev = bits(_mm_cmpge_ps(abs_d, _mm_permute_ps::<{ pick(2, 0, 1, 3) }>(abs_d)));
            // `dominant_axis`: 0 where x is the longest, else 1 where y is at least z, else 2.
            let x_longest = next & prev & 1;
            let y_over_z = next >> 1 & 1;
            let kz = (1 - x_longest) * (2 - y_over_z);

            // `WatertightRay::with_inverse`: the frame, and the shear from `shear_z = 1/d[kz]`.
            let (control, [kx, ky, _]) = FRAMES[2 * kz + (octant >> kz & 1)];
            let control = _mm_loadu_si128(control.as_ptr().cast());
            let origin = _mm_permutevar_ps(o, control);
            let shear_z = _mm_permute_ps::<{ pick(2, 2, 2, 2) }>(_mm_permutevar_ps(inv, control));
            let shear =
                _mm_blend_ps::<0b0100>(_mm_mul_ps(_mm_permutevar_ps(d, control), shear_z), shear_z);
            let abs_shear = abs(shear);
            let shear_z = _mm_cvtss_f32(shear_z);
            let mut sheared = [0.0f32; 4];
            _mm_storeu_ps(sheared.as_mut_ptr(), shear);
            let triangle_t_min = if t_min.is_nan() { f32::INFINITY } else { t_min };
            let watertight = WatertightRay {
                origin: ray.origin,
                t_min: triangle_t_min,
                kx,
                ky,
                kz,
                shear_x: sheared[0],
                shear_y: sheared[1],
                shear_z,
            };
            let [abs_shear_x, abs_shear_y, _] = broadcast3(abs_shear);
            let lanes = RayBroadcast {
                origin: broadcast3(origin),
                shear: broadcast3(shear),
                abs_shear: [abs_shear_x, abs_shear_y],
                t_min: _mm256_set1_ps(triangle_t_min),
                k: [kx, ky, kz],
            };

            // `RayBoxTest::margin`: the origin's greatest distances to the root's planes.
            let root = &bvh.root;
            let margin = if root.is_empty() {
                0.0
            } else {
                let min = _mm_setr_ps(root.min.x, root.min.y, root.min.z, 0.0);
                let max = _mm_setr_ps(root.max.x, root.max.y, root.max.z, 0.0);
                let farthest = _mm_max_ps(abs(_mm_sub_ps(min, o)), abs(_mm_sub_ps(max, o)));
                let l = _mm_cvtss_f32(farthest)
                    + _mm_cvtss_f32(_mm_movehdup_ps(farthest))
                    + _mm_cvtss_f32(_mm_movehl_ps(farthest, farthest));
                l * shear_z.abs() * MARGIN_SCALE
            };

            // `RayBoxTest::fused`: the addends with their margins, where the bound holds.
            let abs_o = abs(o);
            let greatest = _mm_max_ps(abs_o, _mm_permute_ps::<{ pick(2, 2, 2, 2) }>(abs_o));
            let greatest = _mm_max_ps(greatest, _mm_permute_ps::<{ pick(1, 1, 1, 1) }>(greatest));
            let far_origin = 4.0 * gamma(3) * _mm_cvtss_f32(greatest) * shear_z.abs() > margin;
            let q = _mm_mul_ps(o, inv);
            let m = _mm_mul_ps(
                _mm_add_ps(_mm_set1_ps(margin), _mm_mul_ps(_mm_set1_ps(4.0 * gamma(3)), abs(q))),
                _mm_set1_ps(FAR_SCALE),
            );
            let minus_q = _mm_xor_ps(_mm_set1_ps(-0.0), q);
            let (near_add, far_add) = (_mm_sub_ps(minus_q, m), _mm_add_ps(minus_q, m));
            let usable = _mm_and_ps(
                _mm_and_ps(
                    _mm_cmplt_ps(abs(inv), infinity),
                    _mm_cmpge_ps(abs(inv), _mm_set1_ps(f32::MIN_POSITIVE)),
                ),
                _mm_and_ps(
                    _mm_cmplt_ps(abs(near_add), infinity),
                    _mm_cmplt_ps(abs(far_add), infinity),
                ),
            );
            let fused_t_min = t_min.max(0.0) - margin;
            if far_origin || bits(usable) != 7 || !fused_t_min.is_finite() {
                // No fused form: the plain test, set up as the other kernels do (rare).
                let box_ray = RayBoxTest::new(ray);
                let margin = box_ray.margin(&bvh.root);
                let watertight = WatertightRay::with_inverse(ray, box_ray.inv_direction);
                let triangle_ray = prepare_triangle_ray::<K>(&watertight);
                let plain = Broadcast::<__m256>::new(&box_ray, margin);
                return Some(query.run(bvh, &plain, &triangle_ray, t_max));
            }
            let box_ray =
                FusedBroadcast::from_lanes([inv, near_add, far_add], fused_t_min, margin, octant);
            let triangle_ray = TriangleRay { ray: watertight, lanes };
            Some(query.run(bvh, &box_ray, &triangle_ray, t_max))
        }
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::bvh::Isa;
    use crate::bvh::bounds::Bounds;
    use crate::bvh::isa::Avx2;
    use crate::bvh::leaf::TriangleRay;
    use crate::bvh::leaf::kernel::RecordKernel;
    use crate::bvh::node::kernel::BoxRay;
    use crate::bvh::traverse::run_prepared;

    /// A set-up as text, every float by its bits' value (`Debug` keeps the sign of zeros),
    /// the box test's form by its type's name.
    struct Describe;
    impl Query<Avx2> for Describe {
        type Output = String;
        unsafe fn run<B: BoxRay>(
            self,
            _: &WideBvh,
            box_ray: &B,
            t: &TriangleRay<<Avx2 as RecordKernel>::RecordRay>,
            t_max: f32,
        ) -> String {
            format!("{box_ray:?}\n{:?}\n{:?}\n{t_max}", t.ray, t.lanes)
        }
    }

    #[target_feature(enable = "avx2,fma")]
    fn both(bvh: &WideBvh, ray: &Ray) -> (Option<String>, Option<String>) {
        // SAFETY: compiled with AVX2 and FMA, called only after detection.
        let portable = unsafe { setup_portable::<Avx2>(bvh, ray) };
        // SAFETY: as above.
        let portable = portable.map(|p| unsafe { run_prepared(bvh, &p, Describe) });
        // SAFETY: as above.
        let vector = unsafe { query_avx2::<Avx2, _>(bvh, ray, Describe) };
        (portable, vector)
    }

    /// The AVX2 set-up gives the portable one's values bit for bit: on rays along and near the
    /// axes (zero, subnormal and huge components of either sign, ties between axes), from
    /// origins near, inside and far from the root, with empty, NaN and reversed ranges.
    #[test]
    fn the_avx2_setup_is_the_portable_one_bit_for_bit() {
        if !Isa::Avx2.is_supported() {
            eprintln!("skipped: this CPU has no AVX2");
            return;
        }
        let mut next = crate::bvh::tests::xorshift(0x2545_F491_4F6C_DD1Du64);
        let specials = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            1e-40,
            -1e-40,
            f32::MIN_POSITIVE,
            1e-30,
            3e38,
            -3e38,
            f32::INFINITY,
            f32::NAN,
            0.5,
            -0.5,
        ];
        let component = |next: &mut dyn FnMut() -> u64, scale: f32| {
            let r = next();
            if r.is_multiple_of(4) {
                specials[(r >> 8) as usize % specials.len()]
            } else {
                ((r >> 40) as f32 / (1u64 << 24) as f32 - 0.5) * scale
            }
        };
        let roots = [
            Bounds { min: Vec3::splat(-1.0), max: Vec3::splat(1.0) },
            Bounds { min: Vec3::new(1e4, -3.0, 2e5), max: Vec3::new(1.1e4, 5.0, 2.1e5) },
            Bounds::EMPTY,
        ];
        let (mut fused, mut plain, mut none) = (0, 0, 0);
        for case in 0..200_000 {
            let root = roots[case % roots.len()];
            let bvh = WideBvh { nodes: Vec::new(), leaves: Default::default(), root };
            let scale = [4.0, 1e5, 1e-3][case / 3 % 3];
            let origin = Vec3::new(
                component(&mut next, scale),
                component(&mut next, scale),
                component(&mut next, scale),
            );
            let mut direction = Vec3::new(
                component(&mut next, 2.0),
                component(&mut next, 2.0),
                component(&mut next, 2.0),
            );
            if case % 7 == 0 {
                // Ties between the axes' magnitudes.
                direction = Vec3::new(direction.x, -direction.x, direction.z);
            }
            let mut ray = Ray::new(origin, direction);
            ray.t_min = [0.0, 1e-4, -1.0, f32::NAN, 2.0][case % 5];
            ray.t_max = [f32::INFINITY, 1.0, 1e-5, f32::NAN][case / 5 % 4];
            // SAFETY: AVX2 support was checked above.
            let (portable, vector) = unsafe { both(&bvh, &ray) };
            assert_eq!(portable, vector, "{ray:?}, root {root:?}");
            match &portable {
                Some(p) if p.starts_with("FusedBroadcast") => fused += 1,
                Some(_) => plain += 1,
                None => none += 1,
            }
        }
        assert!(fused > 25_000 && plain > 25_000 && none > 25_000, "{fused} {plain} {none}");
    }
}
