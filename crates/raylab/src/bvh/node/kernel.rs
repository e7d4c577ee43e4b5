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

/// One ray's test of a node's eight boxes, prepared for one kernel.
pub(crate) trait BoxRay: Copy + std::fmt::Debug {
    /// The mask of children entered within `[t_min, t_limit]` (bit `k` for child `k`), and each
    /// child's entry distance (meaningful only where the bit is set), as the kernel's scalar
    /// twin decides them ([`RayBoxTest::enter_with_margin`] for the plain form,
    /// [`FusedSlabs::enter`] for the fused one).
    ///
    /// # Safety
    /// The CPU must support the instruction set of the kernel that prepared the ray (checked
    /// once when a BVH picks it).
    unsafe fn enter(&self, node: &WideNode, t_limit: f32) -> (u32, [f32; WIDTH]);
}

/// A single ray prepared for a node kernel: its fused form ([`FusedSlabs`]) where the kernel
/// and the ray have one, its plain form otherwise. The traversals branch on it once per ray, so
/// that the node loop of either form tests no flag.
#[derive(Clone, Copy)]
pub(crate) enum NodeRay<F, P> {
    Fused(F),
    Plain(P),
}

/// The fused form of a kernel that has none: no value, so its traversal compiles away.
#[derive(Clone, Copy, Debug)]
pub(crate) enum NoFusedForm {}

impl BoxRay for NoFusedForm {
    #[inline(always)]
    unsafe fn enter(&self, _: &WideNode, _: f32) -> (u32, [f32; WIDTH]) {
        match *self {}
    }
}

/// Which children a ray enters, and where.
pub(crate) trait NodeKernel: Sized {
    /// A ray's fused form ([`FusedSlabs`]), for the kernels that have one.
    type Fused: BoxRay;
    /// A ray's plain form ([`RayBoxTest::enter_with_margin`]).
    type Plain: BoxRay;

    /// Prepares a ray for the boxes inside a root box whose [`RayBoxTest::margin`] is `margin`.
    ///
    /// # Safety
    /// The CPU must support the kernel's instruction set (checked once when a BVH picks it).
    unsafe fn prepare(ray: &RayBoxTest, margin: f32) -> NodeRay<Self::Fused, Self::Plain>;

    /// A packet's bound, prepared for this kernel once per packet.
    type Frustum: Copy;

    /// Prepares a packet's bound.
    ///
    /// # Safety
    /// As for [`prepare`](Self::prepare).
    unsafe fn prepare_frustum(frustum: &Frustum) -> Self::Frustum;

    /// The mask of children that some ray of the packet may enter within `[t_min, t_limit]`,
    /// and the packet's entry distance into each, as [`Frustum::enter`] (the scalar twin)
    /// computes them.
    ///
    /// # Safety
    /// As for [`prepare`](Self::prepare).
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

/// The portable kernel's ray: the plain test, one box at a time.
impl BoxRay for (RayBoxTest, f32) {
    #[inline(always)]
    unsafe fn enter(&self, node: &WideNode, t_limit: f32) -> (u32, [f32; WIDTH]) {
        let (ray, margin) = self;
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
}

impl NodeKernel for Scalar {
    type Fused = NoFusedForm;
    type Plain = (RayBoxTest, f32);

    #[inline(always)]
    unsafe fn prepare(ray: &RayBoxTest, margin: f32) -> NodeRay<NoFusedForm, (RayBoxTest, f32)> {
        NodeRay::Plain((*ray, margin))
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
pub(crate) use x86::{Broadcast, FusedBroadcast, broadcast3};

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    use super::*;
    use crate::bvh::bounds::{FAR_SCALE, SLAB_PAD};
    use crate::bvh::isa::{Avx2, Avx512, Sse};
    use crate::bvh::simd::Lanes;

    /// A ray broadcast into vector registers, with its box margin.
    #[derive(Clone, Copy, Debug)]
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
        pub(crate) unsafe fn new(ray: &RayBoxTest, margin: f32) -> Self {
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

    /// SSE2's plain test: a node's eight boxes in two halves.
    impl BoxRay for Broadcast<__m128> {
        #[inline(always)]
        unsafe fn enter(&self, node: &WideNode, t_limit: f32) -> (u32, [f32; WIDTH]) {
            let mut out = [0.0f32; WIDTH];
            // SAFETY: the caller guarantees SSE2 (part of x86-64); 0 and 4 are the halves of
            // a node.
            let mask = unsafe {
                Broadcast::enter(self, node, t_limit, 0, &mut out)
                    | Broadcast::enter(self, node, t_limit, 4, &mut out)
            };
            (mask, out)
        }
    }

    /// AVX2's plain test, for the rays without a fused form.
    impl BoxRay for Broadcast<__m256> {
        #[inline(always)]
        unsafe fn enter(&self, node: &WideNode, t_limit: f32) -> (u32, [f32; WIDTH]) {
            let mut out = [0.0f32; WIDTH];
            // SAFETY: the caller guarantees AVX2; 0 is the start of a node's rows.
            let mask = unsafe { Broadcast::enter(self, node, t_limit, 0, &mut out) };
            (mask, out)
        }
    }

    impl NodeKernel for Sse {
        type Fused = NoFusedForm;
        type Plain = Broadcast<__m128>;
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
        unsafe fn prepare(ray: &RayBoxTest, margin: f32) -> NodeRay<NoFusedForm, Self::Plain> {
            // SAFETY: SSE2 is part of x86-64.
            NodeRay::Plain(unsafe { Broadcast::new(ray, margin) })
        }
    }

    /// Byte offsets in a node of the near and far plane rows per axis, for each octant of
    /// directions (bit `a` set where the direction is negative on axis `a`): rows as
    /// [`plane_rows`] numbers them, 32 bytes each.
    const ROW_OFFSETS: [([usize; 3], [usize; 3]); 8] = {
        let mut table = [([0; 3], [0; 3]); 8];
        let mut octant = 0;
        while octant < 8 {
            let mut axis = 0;
            while axis < 3 {
                let negative = octant >> axis & 1;
                table[octant].0[axis] = (axis + 3 * negative) * 32;
                table[octant].1[axis] = (axis + 3 * (1 - negative)) * 32;
                axis += 1;
            }
            octant += 1;
        }
        table
    };

    /// A ray broadcast for the fused slab test ([`FusedSlabs`]), its twin.
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct FusedBroadcast {
        inv: [__m256; 3],
        near_add: [__m256; 3],
        far_add: [__m256; 3],
        t_min: __m256,
        margin: f32,
        /// Byte offsets of the near and far plane rows per axis ([`ROW_OFFSETS`]).
        near_rows: [usize; 3],
        far_rows: [usize; 3],
    }

    impl FusedBroadcast {
        /// Broadcasts `f`.
        ///
        /// # Safety
        /// The CPU must support AVX2.
        #[inline(always)]
        pub(crate) unsafe fn new(f: &FusedSlabs) -> Self {
            let lanes = |v: glam::Vec3| glam::Vec4::from((v, 0.0)).into();
            let octant = (0..3).fold(0, |o, axis| o | usize::from(f.negative[axis]) << axis);
            // SAFETY: the caller's guarantee.
            unsafe {
                Self::from_lanes(
                    [lanes(f.inv_direction), lanes(f.near_add), lanes(f.far_add)],
                    f.t_min,
                    f.margin,
                    octant,
                )
            }
        }

        /// Broadcasts the fused form whose `1/d`, near and far addends are lanes 0 to 2 of
        /// `[inv, near_add, far_add]`, for a direction in `octant` (bit `a` set where it is
        /// negative on axis `a`).
        ///
        /// # Safety
        /// The CPU must support AVX2; `octant < 8`.
        #[inline(always)]
        pub(crate) unsafe fn from_lanes(
            [inv, near_add, far_add]: [__m128; 3],
            t_min: f32,
            margin: f32,
            octant: usize,
        ) -> Self {
            let (near_rows, far_rows) = ROW_OFFSETS[octant & 7];
            // SAFETY: the caller's guarantee.
            unsafe {
                FusedBroadcast {
                    inv: broadcast3(inv),
                    near_add: broadcast3(near_add),
                    far_add: broadcast3(far_add),
                    t_min: _mm256_set1_ps(t_min),
                    margin,
                    near_rows,
                    far_rows,
                }
            }
        }
    }

    /// Lanes 0, 1 and 2 of `v`, each in all lanes of a register.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[inline(always)]
    pub(crate) unsafe fn broadcast3(v: __m128) -> [__m256; 3] {
        // SAFETY: the caller's guarantee; `vpermps` with indices below 4 reads only the low
        // half, the 128 bits cast in.
        unsafe {
            let wide = _mm256_castps128_ps256(v);
            [
                _mm256_broadcastss_ps(v),
                _mm256_permutevar8x32_ps(wide, _mm256_set1_epi32(1)),
                _mm256_permutevar8x32_ps(wide, _mm256_set1_epi32(2)),
            ]
        }
    }

    /// The fused test of eight boxes at once.
    impl BoxRay for FusedBroadcast {
        #[inline(always)]
        unsafe fn enter(&self, node: &WideNode, t_limit: f32) -> (u32, [f32; WIDTH]) {
            // SAFETY: the caller guarantees AVX2 and FMA; every load reads one 32-byte aligned
            // row of 8 floats of `node`, at a byte offset of `ROW_OFFSETS` (below 192).
            unsafe {
                let (n, f) = (&self.near_rows, &self.far_rows);
                let base = node.planes.as_ptr().cast::<u8>();
                // A pointer only: a closure calling an intrinsic would not inherit the target
                // features.
                let row = |offset: usize| base.add(offset).cast::<f32>();
                let n0 = _mm256_fmadd_ps(_mm256_load_ps(row(n[0])), self.inv[0], self.near_add[0]);
                let n1 = _mm256_fmadd_ps(_mm256_load_ps(row(n[1])), self.inv[1], self.near_add[1]);
                let n2 = _mm256_fmadd_ps(_mm256_load_ps(row(n[2])), self.inv[2], self.near_add[2]);
                let f0 = _mm256_fmadd_ps(_mm256_load_ps(row(f[0])), self.inv[0], self.far_add[0]);
                let f1 = _mm256_fmadd_ps(_mm256_load_ps(row(f[1])), self.inv[1], self.far_add[1]);
                let f2 = _mm256_fmadd_ps(_mm256_load_ps(row(f[2])), self.inv[2], self.far_add[2]);
                let limit = _mm256_set1_ps(t_limit + self.margin);
                let near = _mm256_max_ps(_mm256_max_ps(n0, n1), _mm256_max_ps(n2, self.t_min));
                let far = _mm256_min_ps(_mm256_min_ps(f0, f1), _mm256_min_ps(f2, limit));
                let hit = _mm256_cmp_ps::<_CMP_LE_OQ>(near, far);
                let mut out = [0.0f32; WIDTH];
                _mm256_storeu_ps(out.as_mut_ptr(), near);
                (_mm256_movemask_ps(hit) as u32, out)
            }
        }
    }

    impl NodeKernel for Avx2 {
        type Fused = FusedBroadcast;
        type Plain = Broadcast<__m256>;
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
        unsafe fn prepare(
            ray: &RayBoxTest,
            margin: f32,
        ) -> NodeRay<FusedBroadcast, Broadcast<__m256>> {
            match ray.fused(margin) {
                // SAFETY: the caller checked AVX2 support (this function's contract).
                Some(f) => NodeRay::Fused(unsafe { FusedBroadcast::new(&f) }),
                // SAFETY: as above.
                None => NodeRay::Plain(unsafe { Broadcast::new(ray, margin) }),
            }
        }
    }

    /// AVX2's node kernel (eight boxes fill one AVX register).
    impl NodeKernel for Avx512 {
        type Fused = <Avx2 as NodeKernel>::Fused;
        type Plain = <Avx2 as NodeKernel>::Plain;
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
        unsafe fn prepare(ray: &RayBoxTest, margin: f32) -> NodeRay<Self::Fused, Self::Plain> {
            // SAFETY: as above.
            unsafe { Avx2::prepare(ray, margin) }
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
