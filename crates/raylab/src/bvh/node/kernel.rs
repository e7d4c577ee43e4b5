//! The node kernels: one ray, or a packet's bound, against the eight boxes of a [`WideNode`].
//!
//! The SSE2 kernel computes, for every child, the same values as
//! [`RayBoxTest::enter_with_margin`] (its scalar twin, the portable kernel) in the same order of
//! operations: per axis `tn = (near plane − o)·(1/d)`
//! folded into `near = max(tn, near)` and `tf = (far plane − o)·(1/d)` into `far = min(tf, far)`,
//! then `near − margin <= far + margin`, with the ray's one margin for every box. x86's
//! `maxps`/`minps` return their second operand when the first is NaN, which is how the scalar
//! `f32::max`/`min` treat a NaN `tn`/`tf` (a ray inside a box's face plane). A packet's bound
//! is tested against the boxes as [`Frustum::enter`] does, with interval arithmetic. The AVX2
//! and AVX-512 kernels test single rays in the fused form ([`FusedSlabs`], one FMA per plane,
//! its scalar twin [`FusedSlabs::enter`]) where the ray has one, and as SSE2 does otherwise;
//! both forms are conservative, so the answers never depend on the form, only the boxes entered
//! at their margins' edge (a fraction of a percent more in the fused form). The tests in
//! `bvh/tests.rs` check every kernel against its twin bit for bit.
//!
//! The kernels are implemented for the instruction-set types of `bvh/isa.rs`; the leaf records'
//! kernels are in `leaf/kernel.rs`, the packet leaves' in `packet/leaf.rs`.

use super::{WIDTH, WideNode};
use crate::bvh::bounds::{Frustum, FusedSlabs, RayBoxTest};
use crate::bvh::isa::Scalar;

/// Which children a ray enters, and where.
pub(crate) trait NodeKernel: Sized {
    /// The ray, prepared for this kernel once per ray.
    type Ray: Copy;

    /// Prepares a ray for the boxes inside a root box whose [`RayBoxTest::margin`] is `margin`.
    ///
    /// # Safety
    /// As for [`enter`](Self::enter).
    unsafe fn prepare(ray: &RayBoxTest, margin: f32) -> Self::Ray;

    /// The mask of children entered within `[t_min, t_limit]` (bit `k` for child `k`), and each
    /// child's entry distance (meaningful only where the bit is set), as the kernel's scalar
    /// twin decides them ([`RayBoxTest::enter_with_margin`], or [`FusedSlabs::enter`] for the
    /// AVX2 and AVX-512 kernels on rays that have a fused form).
    ///
    /// # Safety
    /// The CPU must support the kernel's instruction set (checked once when a BVH picks it).
    unsafe fn enter(node: &WideNode, ray: &Self::Ray, t_limit: f32) -> (u32, [f32; WIDTH]);

    /// A packet's bound, prepared for this kernel once per packet.
    type Frustum: Copy;

    /// Prepares a packet's bound.
    ///
    /// # Safety
    /// As for [`enter`](Self::enter).
    unsafe fn prepare_frustum(frustum: &Frustum) -> Self::Frustum;

    /// The mask of children that some ray of the packet may enter within `[t_min, t_limit]`,
    /// and the packet's entry distance into each, as [`Frustum::enter`] (the scalar twin)
    /// computes them.
    ///
    /// # Safety
    /// As for [`enter`](Self::enter).
    unsafe fn enter_frustum(
        node: &WideNode,
        frustum: &Self::Frustum,
        t_limit: f32,
    ) -> (u32, [f32; WIDTH]);
}

/// Plane rows of the near and far planes per axis: the box's min for a positive direction.
#[inline(always)]
pub(super) fn plane_rows(negative: [bool; 3]) -> ([usize; 3], [usize; 3]) {
    // Written out rather than `[0, 1, 2].map(..)`, whose closure is not inlined into the
    // instruction sets' entry points (it lacks their target features).
    let near = |axis: usize| if negative[axis] { 3 + axis } else { axis };
    let far = |axis: usize| if negative[axis] { axis } else { 3 + axis };
    ([near(0), near(1), near(2)], [far(0), far(1), far(2)])
}

impl NodeKernel for Scalar {
    type Ray = (RayBoxTest, f32);

    #[inline(always)]
    unsafe fn prepare(ray: &RayBoxTest, margin: f32) -> (RayBoxTest, f32) {
        (*ray, margin)
    }

    #[inline(always)]
    unsafe fn enter(
        node: &WideNode,
        (ray, margin): &(RayBoxTest, f32),
        t_limit: f32,
    ) -> (u32, [f32; WIDTH]) {
        let mut mask = 0;
        let mut near = [0.0; WIDTH];
        for (k, slot) in near.iter_mut().enumerate() {
            if let Some(t) = ray.enter_with_margin(&node.bounds(k), t_limit, *margin) {
                mask |= 1 << k;
                *slot = t;
            }
        }
        (mask, near)
    }

    type Frustum = Frustum;

    #[inline(always)]
    unsafe fn prepare_frustum(frustum: &Frustum) -> Frustum {
        *frustum
    }

    #[inline(always)]
    unsafe fn enter_frustum(
        node: &WideNode,
        frustum: &Frustum,
        t_limit: f32,
    ) -> (u32, [f32; WIDTH]) {
        let mut mask = 0;
        let mut near = [0.0; WIDTH];
        for (k, slot) in near.iter_mut().enumerate() {
            if let Some(t) = frustum.enter(&node.bounds(k), t_limit) {
                mask |= 1 << k;
                *slot = t;
            }
        }
        (mask, near)
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    use super::*;
    use crate::bvh::bounds::{FAR_SCALE, SLAB_PAD};
    use crate::bvh::isa::{Avx2, Avx512, Sse};
    use crate::bvh::simd::Lanes;

    /// A ray broadcast into vector registers, with its box margin.
    #[derive(Clone, Copy)]
    pub(crate) struct Broadcast<V> {
        origin: [V; 3],
        inv: [V; 3],
        t_min: V,
        margin: V,
        near_rows: [usize; 3],
        far_rows: [usize; 3],
    }

    impl<V: Lanes> Broadcast<V> {
        /// Broadcasts `ray`.
        ///
        /// # Safety
        /// The CPU must support `V`'s instruction set.
        #[inline(always)]
        unsafe fn new(ray: &RayBoxTest, margin: f32) -> Self {
            let (near_rows, far_rows) = plane_rows(ray.negative);
            // SAFETY: the caller's guarantee.
            unsafe {
                Broadcast {
                    origin: [
                        V::splat(ray.origin[0]),
                        V::splat(ray.origin[1]),
                        V::splat(ray.origin[2]),
                    ],
                    inv: [
                        V::splat(ray.inv_direction[0]),
                        V::splat(ray.inv_direction[1]),
                        V::splat(ray.inv_direction[2]),
                    ],
                    t_min: V::splat(ray.t_min),
                    margin: V::splat(margin),
                    near_rows,
                    far_rows,
                }
            }
        }

        /// [`RayBoxTest::enter_with_margin`] for the children from `first` on that `V` holds:
        /// their mask (bit 0 for child `first`), and their entries written to `out[first..]`.
        ///
        /// # Safety
        /// The CPU must support `V`'s instruction set; `first` is 0, or 4 for a 4-lane `V`.
        #[inline(always)]
        unsafe fn enter(
            &self,
            node: &WideNode,
            t_limit: f32,
            first: usize,
            out: &mut [f32],
        ) -> u32 {
            // SAFETY: the caller's guarantee; loads read one register of a 32-byte aligned row
            // of 8 from `first`, which is aligned to the register size.
            unsafe {
                let mut near = self.t_min;
                let mut far = V::splat(t_limit);
                for axis in 0..3 {
                    let np = V::load(node.planes[self.near_rows[axis]][first..].as_ptr());
                    let fp = V::load(node.planes[self.far_rows[axis]][first..].as_ptr());
                    near = np.sub(self.origin[axis]).mul(self.inv[axis]).max(near);
                    far = fp.sub(self.origin[axis]).mul(self.inv[axis]).min(far);
                }
                let near = near.sub(self.margin);
                let far = far.add(self.margin);
                near.store(out[first..].as_mut_ptr());
                near.le_mask(far) << first
            }
        }
    }

    impl NodeKernel for Sse {
        type Ray = Broadcast<__m128>;
        type Frustum = FrustumBroadcast<__m128>;

        #[inline(always)]
        unsafe fn prepare_frustum(frustum: &Frustum) -> Self::Frustum {
            // SAFETY: SSE2 is part of x86-64.
            unsafe { FrustumBroadcast::new(frustum) }
        }

        #[inline(always)]
        unsafe fn enter_frustum(
            node: &WideNode,
            frustum: &Self::Frustum,
            t_limit: f32,
        ) -> (u32, [f32; WIDTH]) {
            let mut out = [0.0; WIDTH];
            // SAFETY: SSE2 is part of x86-64; 0 and 4 are the halves of a node.
            unsafe {
                let mask = frustum.enter(node, t_limit, 0, &mut out)
                    | frustum.enter(node, t_limit, 4, &mut out);
                (mask, out)
            }
        }

        #[inline(always)]
        unsafe fn prepare(ray: &RayBoxTest, margin: f32) -> Self::Ray {
            // SAFETY: SSE2 is part of x86-64.
            unsafe { Broadcast::new(ray, margin) }
        }

        #[inline(always)]
        unsafe fn enter(node: &WideNode, ray: &Self::Ray, t_limit: f32) -> (u32, [f32; WIDTH]) {
            let mut out = [0.0f32; WIDTH];
            // SAFETY: SSE2 is part of x86-64; 0 and 4 are the halves of a node.
            let mask = unsafe {
                ray.enter(node, t_limit, 0, &mut out) | ray.enter(node, t_limit, 4, &mut out)
            };
            (mask, out)
        }
    }

    /// A ray broadcast for the fused slab test ([`FusedSlabs`]), with the plain form beside
    /// it for the rays that have no fused one.
    #[derive(Clone, Copy)]
    pub(crate) struct FusedBroadcast {
        /// Whether the fused form holds; otherwise `plain` is tested.
        fused: bool,
        inv: [__m256; 3],
        near_add: [__m256; 3],
        far_add: [__m256; 3],
        t_min: __m256,
        margin: f32,
        near_rows: [usize; 3],
        far_rows: [usize; 3],
        /// The ray for the plain test, kept as scalars and broadcast by `plain_enter` where a
        /// ray has no fused form. (The compiler still hoists that broadcast out of the
        /// traversal loop into every ray's set-up; an out-of-line `plain_enter` that would stop
        /// it lengthened the loop instead: BENCHMARKS.md, "A leaner set-up".)
        plain: (RayBoxTest, f32),
    }

    impl NodeKernel for Avx2 {
        type Ray = FusedBroadcast;
        type Frustum = FrustumBroadcast<__m256>;

        #[inline(always)]
        unsafe fn prepare_frustum(frustum: &Frustum) -> Self::Frustum {
            // SAFETY: the caller checked AVX2 support (this function's contract).
            unsafe { FrustumBroadcast::new(frustum) }
        }

        #[inline(always)]
        unsafe fn enter_frustum(
            node: &WideNode,
            frustum: &Self::Frustum,
            t_limit: f32,
        ) -> (u32, [f32; WIDTH]) {
            let mut out = [0.0; WIDTH];
            // SAFETY: the caller checked AVX2 support; 0 is the start of a node's rows.
            unsafe {
                let mask = frustum.enter(node, t_limit, 0, &mut out);
                (mask, out)
            }
        }

        #[inline(always)]
        unsafe fn prepare(ray: &RayBoxTest, margin: f32) -> Self::Ray {
            let (near_rows, far_rows) = plane_rows(ray.negative);
            let fused = ray.fused(margin);
            let f = fused.unwrap_or(FusedSlabs {
                inv_direction: glam::Vec3::ONE,
                near_add: glam::Vec3::ZERO,
                far_add: glam::Vec3::ZERO,
                t_min: 0.0,
                margin: 0.0,
                negative: ray.negative,
            });
            // SAFETY: the caller checked AVX2 support (this function's contract).
            unsafe {
                FusedBroadcast {
                    fused: fused.is_some(),
                    inv: splat3(f.inv_direction),
                    near_add: splat3(f.near_add),
                    far_add: splat3(f.far_add),
                    t_min: _mm256_set1_ps(f.t_min),
                    margin: f.margin,
                    near_rows,
                    far_rows,
                    plain: (*ray, margin),
                }
            }
        }

        #[inline(always)]
        unsafe fn enter(node: &WideNode, ray: &Self::Ray, t_limit: f32) -> (u32, [f32; WIDTH]) {
            if !ray.fused {
                // SAFETY: the caller checked AVX2 support (this function's contract).
                return unsafe { plain_enter(node, &ray.plain, t_limit) };
            }
            // SAFETY: the caller checked AVX2 and FMA support; every load reads one 32-byte
            // aligned row of 8 floats of `node`.
            unsafe {
                let (n, f) = (&ray.near_rows, &ray.far_rows);
                let row = |r: usize| node.planes[r].as_ptr();
                let n0 = _mm256_fmadd_ps(_mm256_load_ps(row(n[0])), ray.inv[0], ray.near_add[0]);
                let n1 = _mm256_fmadd_ps(_mm256_load_ps(row(n[1])), ray.inv[1], ray.near_add[1]);
                let n2 = _mm256_fmadd_ps(_mm256_load_ps(row(n[2])), ray.inv[2], ray.near_add[2]);
                let f0 = _mm256_fmadd_ps(_mm256_load_ps(row(f[0])), ray.inv[0], ray.far_add[0]);
                let f1 = _mm256_fmadd_ps(_mm256_load_ps(row(f[1])), ray.inv[1], ray.far_add[1]);
                let f2 = _mm256_fmadd_ps(_mm256_load_ps(row(f[2])), ray.inv[2], ray.far_add[2]);
                let limit = _mm256_set1_ps(t_limit + ray.margin);
                let near = _mm256_max_ps(_mm256_max_ps(n0, n1), _mm256_max_ps(n2, ray.t_min));
                let far = _mm256_min_ps(_mm256_min_ps(f0, f1), _mm256_min_ps(f2, limit));
                let hit = _mm256_cmp_ps::<_CMP_LE_OQ>(near, far);
                let mut out = [0.0f32; WIDTH];
                _mm256_storeu_ps(out.as_mut_ptr(), near);
                (_mm256_movemask_ps(hit) as u32, out)
            }
        }
    }

    /// The plain test of a ray without a fused form, broadcast here.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[inline(always)]
    unsafe fn plain_enter(
        node: &WideNode,
        (ray, margin): &(RayBoxTest, f32),
        t_limit: f32,
    ) -> (u32, [f32; WIDTH]) {
        let mut out = [0.0f32; WIDTH];
        // SAFETY: the caller's guarantee; 0 is the start of a node's rows.
        let mask =
            unsafe { Broadcast::<__m256>::new(ray, *margin).enter(node, t_limit, 0, &mut out) };
        (mask, out)
    }

    /// AVX2's node kernel (eight boxes fill one AVX register).
    impl NodeKernel for Avx512 {
        type Ray = <Avx2 as NodeKernel>::Ray;
        type Frustum = <Avx2 as NodeKernel>::Frustum;

        #[inline(always)]
        unsafe fn prepare_frustum(frustum: &Frustum) -> Self::Frustum {
            // SAFETY: AVX-512 implies AVX2 (this function's contract).
            unsafe { Avx2::prepare_frustum(frustum) }
        }

        #[inline(always)]
        unsafe fn enter_frustum(
            node: &WideNode,
            frustum: &Self::Frustum,
            t_limit: f32,
        ) -> (u32, [f32; WIDTH]) {
            // SAFETY: as above.
            unsafe { Avx2::enter_frustum(node, frustum, t_limit) }
        }

        #[inline(always)]
        unsafe fn prepare(ray: &RayBoxTest, margin: f32) -> Self::Ray {
            // SAFETY: as above.
            unsafe { Avx2::prepare(ray, margin) }
        }

        #[inline(always)]
        unsafe fn enter(node: &WideNode, ray: &Self::Ray, t_limit: f32) -> (u32, [f32; WIDTH]) {
            // SAFETY: as above.
            unsafe { Avx2::enter(node, ray, t_limit) }
        }
    }

    /// A vector in three registers of equal lanes.
    ///
    /// # Safety
    /// The CPU must support `V`'s instruction set.
    #[inline(always)]
    unsafe fn splat3<V: Lanes>(v: glam::Vec3) -> [V; 3] {
        // SAFETY: the caller's guarantee.
        unsafe { [V::splat(v.x), V::splat(v.y), V::splat(v.z)] }
    }

    /// The least and greatest products of two intervals, as `bounds::interval_product`.
    ///
    /// # Safety
    /// The CPU must support `V`'s instruction set.
    #[inline(always)]
    unsafe fn interval_product<V: Lanes>(a_lo: V, a_hi: V, i_lo: V, i_hi: V) -> (V, V) {
        // SAFETY: the caller's guarantee.
        unsafe {
            let (p0, p1) = (a_lo.mul(i_lo), a_lo.mul(i_hi));
            let (p2, p3) = (a_hi.mul(i_lo), a_hi.mul(i_hi));
            (p0.min(p1).min(p2.min(p3)), p0.max(p1).max(p2.max(p3)))
        }
    }

    /// A packet's bound broadcast into vector registers.
    #[derive(Clone, Copy)]
    pub(crate) struct FrustumBroadcast<V> {
        origin_lo: [V; 3],
        origin_hi: [V; 3],
        inv_lo: [V; 3],
        inv_hi: [V; 3],
        t_min: V,
        near_rows: [usize; 3],
        far_rows: [usize; 3],
        pad_axes: [bool; 3],
    }

    impl<V: Lanes> FrustumBroadcast<V> {
        /// # Safety
        /// The CPU must support `V`'s instruction set.
        #[inline(always)]
        pub(super) unsafe fn new(f: &Frustum) -> Self {
            let (near_rows, far_rows) = plane_rows(f.negative);
            // SAFETY: the caller's guarantee.
            unsafe {
                FrustumBroadcast {
                    origin_lo: splat3(f.origin_lo),
                    origin_hi: splat3(f.origin_hi),
                    inv_lo: splat3(f.inv_lo),
                    inv_hi: splat3(f.inv_hi),
                    t_min: V::splat(f.t_min),
                    near_rows,
                    far_rows,
                    pad_axes: f.pad_axes,
                }
            }
        }

        /// [`Frustum::enter`] for the children from `first` on that `V` holds: their mask (bit 0 for child
        /// `first`), and their entries written to `out[first..]`.
        ///
        /// # Safety
        /// The CPU must support `V`'s instruction set; `first` is 0, or 4 for a 4-lane `V`.
        #[inline(always)]
        pub(super) unsafe fn enter(
            &self,
            node: &WideNode,
            t_limit: f32,
            first: usize,
            out: &mut [f32],
        ) -> u32 {
            // SAFETY: the caller's guarantee; loads read one register of a 32-byte aligned row
            // of 8 from `first`, which is aligned to the register size.
            unsafe {
                let scale = V::splat(FAR_SCALE);
                let mut near = self.t_min;
                let mut far = V::splat(t_limit);
                let mut reach = V::splat(0.0);
                for axis in 0..3 {
                    let np = V::load(node.planes[self.near_rows[axis]][first..].as_ptr());
                    let fp = V::load(node.planes[self.far_rows[axis]][first..].as_ptr());
                    let (o_lo, o_hi) = (self.origin_lo[axis], self.origin_hi[axis]);
                    let (i_lo, i_hi) = (self.inv_lo[axis], self.inv_hi[axis]);
                    let (tn_lo, tn_hi) = interval_product(np.sub(o_hi), np.sub(o_lo), i_lo, i_hi);
                    let (tf_lo, tf_hi) = interval_product(fp.sub(o_hi), fp.sub(o_lo), i_lo, i_hi);
                    near = tn_lo.max(near);
                    far = tf_hi.mul(scale).min(far);
                    if self.pad_axes[axis] {
                        let axis_reach =
                            tn_lo.abs().max(tn_hi.abs()).max(tf_lo.abs().max(tf_hi.abs()));
                        reach = reach.max(axis_reach);
                    }
                }
                let pad = reach.mul(V::splat(SLAB_PAD));
                let near = near.sub(pad);
                let far = far.add(pad);
                near.store(out[first..].as_mut_ptr());
                near.le_mask(far) << first
            }
        }
    }
}
