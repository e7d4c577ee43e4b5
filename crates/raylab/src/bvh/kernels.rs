//! Ray/box tests of one ray against the eight children of a [`WideNode`].
//!
//! Each kernel computes, for every child, the same values as [`RayBoxTest::enter_with_margin`]
//! (the scalar twin) in the same order of operations: per axis `tn = (near plane − o)·(1/d)`
//! folded into `near = max(tn, near)` and `tf = (far plane − o)·(1/d)` into `far = min(tf, far)`,
//! then `near − margin <= far + margin`, with the ray's one margin for every box. x86's
//! `maxps`/`minps` return their second operand when the first is NaN, which is how the scalar
//! `f32::max`/`min` treat a NaN `tn`/`tf` (a ray inside a box's face plane): the tests in
//! `bvh/tests.rs` check that all kernels agree bit for bit.

use super::bounds::{Bounds, FAR_SCALE, Frustum, RayBoxTest, SLAB_PAD};
use super::build::BLOCK;
use super::bundle::LineBundle;
use super::packet::{PACKET, PacketRays, packet_leaf_scalar};
use super::wide::{WIDTH, WideBvh, WideNode};
use crate::triangle::{TriangleBlock, WatertightRay};

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
    /// child's entry distance (meaningful only where the bit is set), as
    /// [`RayBoxTest::enter_with_margin`] decides them.
    ///
    /// # Safety
    /// The CPU must support the kernel's instruction set (checked once when a BVH picks it).
    unsafe fn enter(node: &WideNode, ray: &Self::Ray, t_limit: f32) -> (u32, [f32; WIDTH]);

    /// Tests the rays of a packet in `open` that enter `bounds` against the triangles of the
    /// leaf inside it: for the closest hit (`occlusion` false: each ray's best hit is offered
    /// every hit), or for occlusion (rays hit are taken out of `open`). Decides exactly as the
    /// single-ray tests do; the scalar twin is [`packet_leaf_scalar`].
    ///
    /// # Safety
    /// As for [`enter`](Self::enter).
    #[inline(always)]
    unsafe fn packet_leaf(
        rays: &mut PacketRays,
        open: &mut u64,
        occlusion: bool,
        bvh: &WideBvh,
        bounds: &Bounds,
        first_block: u32,
        blocks: u32,
    ) {
        // SAFETY: the caller's guarantee.
        unsafe {
            packet_leaf_scalar::<Self>(rays, open, occlusion, bvh, bounds, first_block, blocks)
        }
    }

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

    /// What a ray's triangle tests need, in this kernel's registers, prepared once per ray.
    type BlockRay: Copy;

    /// Prepares a ray for [`block_hits`](Self::block_hits).
    ///
    /// # Safety
    /// As for [`enter`](Self::enter).
    unsafe fn prepare_block_ray(ray: &WatertightRay) -> Self::BlockRay;

    /// The hits of a ray on the triangles of `block` below `t_max`, as
    /// [`WatertightRay::intersect`] decides them. The blocks must hold no zero-area triangles
    /// (the BVH leaves them out). The scalar twin is [`block_hits_scalar`].
    ///
    /// # Safety
    /// As for [`enter`](Self::enter).
    unsafe fn block_hits(
        ray: &TriangleRay<Self::BlockRay>,
        block: &TriangleBlock<BLOCK>,
        t_max: f32,
    ) -> BlockHits;
}

/// A ray prepared for the triangle tests of a kernel whose per-ray form is `B`: the scalar test's
/// setup (for the lanes a kernel leaves undecided) and the kernel's.
#[derive(Clone, Copy)]
pub(crate) struct TriangleRay<B> {
    pub ray: WatertightRay,
    pub block: B,
}

/// Prepares `ray` for `K`'s triangle tests.
///
/// # Safety
/// As for [`NodeKernel::enter`].
#[inline(always)]
pub(crate) unsafe fn prepare_triangle_ray<K: NodeKernel>(
    ray: &WatertightRay,
) -> TriangleRay<K::BlockRay> {
    // SAFETY: the caller's guarantee.
    TriangleRay { ray: *ray, block: unsafe { K::prepare_block_ray(ray) } }
}

/// What a block test decides for each of its four lanes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct BlockHits {
    /// Lanes hit, with their `t` and barycentrics below, exactly as `intersect` computes them.
    pub hits: u32,
    /// Lanes that only [`WatertightRay::intersect`] can decide (an edge function rounded to zero
    /// and must be recomputed in double precision).
    pub undecided: u32,
    /// Ray parameter per lane (meaningful where `hits` has the bit).
    pub t: [f32; BLOCK],
    /// Barycentric weight of `v1` per lane.
    pub b1: [f32; BLOCK],
    /// Barycentric weight of `v2` per lane.
    pub b2: [f32; BLOCK],
}

/// The scalar twin of the block kernels: the batched pre-test, then the full scalar test on each
/// candidate. Decides every lane.
#[inline(always)]
pub(crate) fn block_hits_scalar(
    ray: &WatertightRay,
    block: &TriangleBlock<BLOCK>,
    t_max: f32,
) -> BlockHits {
    let mut out = BlockHits::default();
    let mut candidates = ray.block_candidates(block, t_max);
    while candidates != 0 {
        let lane = candidates.trailing_zeros() as usize;
        candidates &= candidates - 1;
        let [v0, v1, v2] = block.triangle(lane);
        if let Some(h) = ray.intersect(v0, v1, v2, t_max) {
            out.hits |= 1 << lane;
            out.t[lane] = h.t;
            out.b1[lane] = h.b1;
            out.b2[lane] = h.b2;
        }
    }
    out
}

/// Plane rows of the near and far planes per axis: the box's min for a positive direction.
#[inline(always)]
fn plane_rows(negative: [bool; 3]) -> ([usize; 3], [usize; 3]) {
    // Written out rather than `[0, 1, 2].map(..)`, whose closure is not inlined into the
    // instruction sets' entry points (it lacks their target features).
    let near = |axis: usize| if negative[axis] { 3 + axis } else { axis };
    let far = |axis: usize| if negative[axis] { axis } else { 3 + axis };
    ([near(0), near(1), near(2)], [far(0), far(1), far(2)])
}

/// The scalar twin: [`RayBoxTest::enter_with_margin`] per child.
pub(crate) struct Scalar;

impl NodeKernel for Scalar {
    type Ray = (RayBoxTest, f32);
    type BlockRay = ();

    #[inline(always)]
    unsafe fn prepare_block_ray(_: &WatertightRay) {}

    #[inline(always)]
    unsafe fn block_hits(
        ray: &TriangleRay<()>,
        block: &TriangleBlock<BLOCK>,
        t_max: f32,
    ) -> BlockHits {
        block_hits_scalar(&ray.ray, block, t_max)
    }

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
pub(crate) use x86::{Avx2, Avx512, Sse};
#[cfg(all(test, target_arch = "x86_64"))]
pub(crate) use x86::{SseBlockRay, block_hits_sse};
#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    use super::*;
    use crate::bvh::lanes::{Lanes, WatertightLanes, watertight_lanes};

    /// Eight children with two 4-wide SSE halves: every x86-64 CPU has SSE2.
    pub(crate) struct Sse;

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
    }

    /// The lanes of a packet row from `base` on.
    ///
    /// # Safety
    /// The CPU must support `V`'s instruction set, and `base` plus the register's lanes must
    /// not pass `PACKET`.
    #[inline(always)]
    unsafe fn lanes<V: Lanes>(row: &[f32; PACKET], base: usize) -> V {
        debug_assert!(base < PACKET);
        // SAFETY: the caller's guarantee.
        unsafe { V::loadu(row.as_ptr().add(base)) }
    }

    /// [`NodeKernel::packet_leaf`] with `L` rays per register `V`: the slab test of the leaf's box
    /// and the watertight test of each of its triangles, for `L` rays at a time, by the same
    /// operations as the single-ray tests ([`RayBoxTest::enter`], [`watertight_lanes`]).
    ///
    /// # Safety
    /// The CPU must support `V`'s instruction set, which holds `L` (4, 8 or 16) floats.
    #[inline(always)]
    unsafe fn packet_leaf_lanes<V: Lanes, const L: usize>(
        rays: &mut PacketRays,
        open: &mut u64,
        occlusion: bool,
        bvh: &WideBvh,
        bounds: &Bounds,
        first_block: u32,
        blocks: u32,
    ) {
        let negative = rays.negative;
        // Per axis, not `[0, 1, 2].map(..)` (see `plane_rows`).
        let (lo, hi) = (bounds.min, bounds.max);
        let near_planes = [
            if negative[0] { hi.x } else { lo.x },
            if negative[1] { hi.y } else { lo.y },
            if negative[2] { hi.z } else { lo.z },
        ];
        let far_planes = [
            if negative[0] { lo.x } else { hi.x },
            if negative[1] { lo.y } else { hi.y },
            if negative[2] { lo.z } else { hi.z },
        ];
        let [kx, ky, kz] = rays.k;
        // The leaf's triangles some line of the packet may cross (bit `4·block + lane`, at
        // most 16 blocks of 4): where the rays' lines meet in one point, the others are culled
        // once for the whole packet, when the first rays enter the leaf's box (in large meshes
        // most leaves the packet's frustum reaches are entered by none of its rays), and only
        // where the leaf is large beside the packet (`LineBundle::worth_culling`).
        let mut live = None;
        let culled = |bundle: &LineBundle| {
            let mut live = 0u64;
            for (k, b) in (first_block as usize..(first_block + blocks) as usize).enumerate() {
                live |= (bundle.may_cross_block(&bvh.blocks[b]) as u64) << (BLOCK * k);
            }
            live
        };
        // SAFETY: the caller's guarantee; every load reads `L` lanes from `base`, and
        // `base + L <= PACKET` because `PACKET` is a multiple of `L`.
        unsafe {
            for base in (0..rays.len).step_by(L) {
                let mut active = (*open >> base) as u32 & ((1 << L) - 1);
                if active == 0 {
                    continue;
                }
                // The slab test, as `RayBoxTest::enter` per lane (no operand is NaN: packet
                // rays have finite origins and `1/d`, and a leaf's box is finite).
                let mut near = lanes::<V>(&rays.box_t_min, base);
                let mut far = lanes::<V>(&rays.box_limit, base);
                let mut reach = V::splat(0.0);
                for axis in 0..3 {
                    let o = lanes::<V>(&rays.origin[axis], base);
                    let inv = lanes::<V>(&rays.inv_direction[axis], base);
                    let t_near = V::splat(near_planes[axis]).sub(o).mul(inv);
                    let t_far = V::splat(far_planes[axis]).sub(o).mul(inv);
                    near = t_near.max(near);
                    far = t_far.mul(V::splat(FAR_SCALE)).min(far);
                    if axis == kz {
                        reach = t_near.abs().max(t_far.abs());
                    }
                }
                let pad = reach.mul(V::splat(SLAB_PAD));
                active &= near.sub(pad).le_mask(far.add(pad));
                if active == 0 {
                    continue;
                }
                let live = *live.get_or_insert_with(|| match &rays.bundle {
                    Some(bundle) if bundle.worth_culling(bounds) => culled(bundle),
                    _ => u64::MAX,
                });
                if live == 0 {
                    return;
                }

                let shear = [
                    lanes::<V>(&rays.shear[0], base),
                    lanes::<V>(&rays.shear[1], base),
                    lanes::<V>(&rays.shear[2], base),
                ];
                let origin = [
                    lanes::<V>(&rays.origin[kx], base),
                    lanes::<V>(&rays.origin[ky], base),
                    lanes::<V>(&rays.origin[kz], base),
                ];
                let t_min = lanes::<V>(&rays.triangle_t_min, base);
                'blocks: for (k, b) in
                    (first_block as usize..(first_block + blocks) as usize).enumerate()
                {
                    let block = &bvh.blocks[b];
                    for (lane, &id) in bvh.ids[b].iter().enumerate() {
                        if id == u32::MAX || live & (1 << (BLOCK * k + lane)) == 0 {
                            continue;
                        }
                        let [p0, p1, p2] = &block.vertices;
                        let test = WatertightLanes {
                            origin,
                            shear,
                            abs_shear: [shear[0].abs(), shear[1].abs()],
                            t_min,
                            t_max: lanes::<V>(&rays.triangle_limit, base),
                            vertices: [
                                [
                                    V::splat(p0[kx][lane]),
                                    V::splat(p0[ky][lane]),
                                    V::splat(p0[kz][lane]),
                                ],
                                [
                                    V::splat(p1[kx][lane]),
                                    V::splat(p1[ky][lane]),
                                    V::splat(p1[kz][lane]),
                                ],
                                [
                                    V::splat(p2[kx][lane]),
                                    V::splat(p2[ky][lane]),
                                    V::splat(p2[kz][lane]),
                                ],
                            ],
                        };
                        let decided = watertight_lanes(&test, active);
                        let mut hits = decided.hits;
                        let (mut t, mut b1, mut b2) = ([0.0f32; L], [0.0f32; L], [0.0f32; L]);
                        if hits != 0 {
                            decided.t.store(t.as_mut_ptr());
                            decided.b1.store(b1.as_mut_ptr());
                            decided.b2.store(b2.as_mut_ptr());
                        }
                        let mut undecided = decided.undecided;
                        if undecided != 0 {
                            let [v0, v1, v2] = block.triangle(lane);
                            while undecided != 0 {
                                let j = undecided.trailing_zeros() as usize;
                                undecided &= undecided - 1;
                                let i = base + j;
                                let limit = rays.triangle_limit[i];
                                if let Some(h) = rays.triangle_ray(i).intersect(v0, v1, v2, limit) {
                                    hits |= 1 << j;
                                    (t[j], b1[j], b2[j]) = (h.t, h.b1, h.b2);
                                }
                            }
                        }
                        if hits == 0 {
                            continue;
                        }
                        if occlusion {
                            *open &= !((hits as u64) << base);
                            active &= !hits;
                            if active == 0 {
                                break 'blocks;
                            }
                        } else {
                            while hits != 0 {
                                let j = hits.trailing_zeros() as usize;
                                hits &= hits - 1;
                                rays.offer(base + j, t[j], id, b1[j], b2[j]);
                            }
                        }
                    }
                }
            }
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
        unsafe fn new(f: &Frustum) -> Self {
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

    impl NodeKernel for Sse {
        type Ray = Broadcast<__m128>;
        type Frustum = FrustumBroadcast<__m128>;

        #[inline(always)]
        unsafe fn packet_leaf(
            rays: &mut PacketRays,
            open: &mut u64,
            occlusion: bool,
            bvh: &WideBvh,
            bounds: &Bounds,
            first_block: u32,
            blocks: u32,
        ) {
            // SAFETY: the caller's guarantee.
            unsafe {
                packet_leaf_lanes::<__m128, 4>(
                    rays,
                    open,
                    occlusion,
                    bvh,
                    bounds,
                    first_block,
                    blocks,
                )
            }
        }

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

        type BlockRay = SseBlockRay;

        #[inline(always)]
        unsafe fn prepare_block_ray(ray: &WatertightRay) -> SseBlockRay {
            SseBlockRay::new(ray)
        }

        #[inline(always)]
        unsafe fn block_hits(
            ray: &TriangleRay<SseBlockRay>,
            block: &TriangleBlock<BLOCK>,
            t_max: f32,
        ) -> BlockHits {
            block_hits_sse(ray, block, t_max)
        }

        #[inline(always)]
        unsafe fn prepare(ray: &RayBoxTest, margin: f32) -> Self::Ray {
            // SAFETY: SSE2 is part of x86-64.
            unsafe { Broadcast::new(ray, margin) }
        }

        #[inline(always)]
        unsafe fn enter(node: &WideNode, ray: &Self::Ray, t_limit: f32) -> (u32, [f32; WIDTH]) {
            // SAFETY: SSE2 is part of x86-64; every load reads 4 floats inside a row of 8 of
            // `node`, which is 32-byte aligned, so offsets 0 and 4 are 16-byte aligned.
            unsafe {
                let limit = _mm_set1_ps(t_limit);
                let mut out = [0.0f32; WIDTH];
                let mut mask = 0u32;
                for half in 0..2 {
                    let mut near = ray.t_min;
                    let mut far = limit;
                    for axis in 0..3 {
                        let np = _mm_load_ps(node.planes[ray.near_rows[axis]][4 * half..].as_ptr());
                        let fp = _mm_load_ps(node.planes[ray.far_rows[axis]][4 * half..].as_ptr());
                        let tn = _mm_mul_ps(_mm_sub_ps(np, ray.origin[axis]), ray.inv[axis]);
                        let tf = _mm_mul_ps(_mm_sub_ps(fp, ray.origin[axis]), ray.inv[axis]);
                        near = _mm_max_ps(tn, near);
                        far = _mm_min_ps(tf, far);
                    }
                    let near = _mm_sub_ps(near, ray.margin);
                    let far = _mm_add_ps(far, ray.margin);
                    let hit = _mm_cmple_ps(near, far);
                    mask |= (_mm_movemask_ps(hit) as u32) << (4 * half);
                    _mm_storeu_ps(out[4 * half..].as_mut_ptr(), near);
                }
                (mask, out)
            }
        }
    }

    /// One row of a block.
    ///
    /// # Safety
    /// As for [`Lanes::load`]: SSE2 is part of x86-64 and a block's rows are 16-byte aligned.
    #[inline(always)]
    unsafe fn row(r: &[f32; BLOCK]) -> __m128 {
        // SAFETY: as above.
        unsafe { __m128::load(r.as_ptr()) }
    }

    /// A ray's triangle-test values broadcast into SSE registers, permuted to its `(kx, ky, kz)`.
    #[derive(Clone, Copy)]
    pub(crate) struct SseBlockRay {
        origin: [__m128; 3],
        shear: [__m128; 3],
        abs_shear: [__m128; 2],
        t_min: __m128,
        k: [usize; 3],
    }

    impl SseBlockRay {
        #[inline(always)]
        pub(crate) fn new(ray: &WatertightRay) -> Self {
            let (kx, ky, kz) = (ray.kx, ray.ky, ray.kz);
            // SAFETY: SSE2 is part of x86-64.
            unsafe {
                SseBlockRay {
                    origin: [
                        __m128::splat(ray.origin[kx]),
                        __m128::splat(ray.origin[ky]),
                        __m128::splat(ray.origin[kz]),
                    ],
                    shear: [
                        __m128::splat(ray.shear_x),
                        __m128::splat(ray.shear_y),
                        __m128::splat(ray.shear_z),
                    ],
                    abs_shear: [__m128::splat(ray.shear_x.abs()), __m128::splat(ray.shear_y.abs())],
                    t_min: __m128::splat(ray.t_min),
                    k: [kx, ky, kz],
                }
            }
        }
    }

    /// [`block_hits_scalar`] for four triangles with SSE2, by [`watertight_lanes`].
    #[inline(always)]
    pub(crate) fn block_hits_sse(
        ray: &TriangleRay<SseBlockRay>,
        block: &TriangleBlock<BLOCK>,
        t_max: f32,
    ) -> BlockHits {
        let r = &ray.block;
        let [kx, ky, kz] = r.k;
        // SAFETY: SSE2 is part of x86-64; each load reads one row of 4 floats of the block,
        // which is 16-byte aligned (`repr(align(16))`); stores go to arrays of 4 floats.
        unsafe {
            let [p0, p1, p2] = &block.vertices;
            let lanes = WatertightLanes {
                origin: r.origin,
                shear: r.shear,
                abs_shear: r.abs_shear,
                t_min: r.t_min,
                t_max: __m128::splat(t_max),
                vertices: [
                    [row(&p0[kx]), row(&p0[ky]), row(&p0[kz])],
                    [row(&p1[kx]), row(&p1[ky]), row(&p1[kz])],
                    [row(&p2[kx]), row(&p2[ky]), row(&p2[kz])],
                ],
            };
            let decided = watertight_lanes(&lanes, 0xF);
            let mut out = BlockHits {
                hits: decided.hits,
                undecided: decided.undecided,
                ..BlockHits::default()
            };
            if decided.hits != 0 {
                decided.t.store(out.t.as_mut_ptr());
                decided.b1.store(out.b1.as_mut_ptr());
                decided.b2.store(out.b2.as_mut_ptr());
            }
            out
        }
    }

    /// All eight children in one AVX2 register.
    pub(crate) struct Avx2;

    impl NodeKernel for Avx2 {
        type Ray = Broadcast<__m256>;
        type Frustum = FrustumBroadcast<__m256>;

        #[inline(always)]
        unsafe fn packet_leaf(
            rays: &mut PacketRays,
            open: &mut u64,
            occlusion: bool,
            bvh: &WideBvh,
            bounds: &Bounds,
            first_block: u32,
            blocks: u32,
        ) {
            // SAFETY: the caller's guarantee.
            unsafe {
                packet_leaf_lanes::<__m256, 8>(
                    rays,
                    open,
                    occlusion,
                    bvh,
                    bounds,
                    first_block,
                    blocks,
                )
            }
        }

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

        type BlockRay = SseBlockRay;

        #[inline(always)]
        unsafe fn prepare_block_ray(ray: &WatertightRay) -> SseBlockRay {
            SseBlockRay::new(ray)
        }

        #[inline(always)]
        unsafe fn block_hits(
            ray: &TriangleRay<SseBlockRay>,
            block: &TriangleBlock<BLOCK>,
            t_max: f32,
        ) -> BlockHits {
            block_hits_sse(ray, block, t_max)
        }

        #[inline(always)]
        unsafe fn prepare(ray: &RayBoxTest, margin: f32) -> Self::Ray {
            // SAFETY: the caller checked AVX2 support (this function's contract).
            unsafe { Broadcast::new(ray, margin) }
        }

        #[inline(always)]
        unsafe fn enter(node: &WideNode, ray: &Self::Ray, t_limit: f32) -> (u32, [f32; WIDTH]) {
            // SAFETY: the caller checked AVX2 support; every load reads one 32-byte aligned row
            // of 8 floats of `node`.
            unsafe {
                let mut near = ray.t_min;
                let mut far = _mm256_set1_ps(t_limit);
                for axis in 0..3 {
                    let np = _mm256_load_ps(node.planes[ray.near_rows[axis]].as_ptr());
                    let fp = _mm256_load_ps(node.planes[ray.far_rows[axis]].as_ptr());
                    let tn = _mm256_mul_ps(_mm256_sub_ps(np, ray.origin[axis]), ray.inv[axis]);
                    let tf = _mm256_mul_ps(_mm256_sub_ps(fp, ray.origin[axis]), ray.inv[axis]);
                    near = _mm256_max_ps(tn, near);
                    far = _mm256_min_ps(tf, far);
                }
                let near = _mm256_sub_ps(near, ray.margin);
                let far = _mm256_add_ps(far, ray.margin);
                let hit = _mm256_cmp_ps::<_CMP_LE_OQ>(near, far);
                let mut out = [0.0f32; WIDTH];
                _mm256_storeu_ps(out.as_mut_ptr(), near);
                (_mm256_movemask_ps(hit) as u32, out)
            }
        }
    }

    /// AVX2's node and block kernels, and packet leaves 16 rays per instruction with AVX-512.
    pub(crate) struct Avx512;

    impl NodeKernel for Avx512 {
        type Ray = <Avx2 as NodeKernel>::Ray;
        type Frustum = <Avx2 as NodeKernel>::Frustum;

        #[inline(always)]
        unsafe fn packet_leaf(
            rays: &mut PacketRays,
            open: &mut u64,
            occlusion: bool,
            bvh: &WideBvh,
            bounds: &Bounds,
            first_block: u32,
            blocks: u32,
        ) {
            // SAFETY: the caller checked AVX-512 F support (this function's contract).
            unsafe {
                packet_leaf_lanes::<__m512, 16>(
                    rays,
                    open,
                    occlusion,
                    bvh,
                    bounds,
                    first_block,
                    blocks,
                )
            }
        }

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

        type BlockRay = SseBlockRay;

        #[inline(always)]
        unsafe fn prepare_block_ray(ray: &WatertightRay) -> SseBlockRay {
            SseBlockRay::new(ray)
        }

        #[inline(always)]
        unsafe fn block_hits(
            ray: &TriangleRay<SseBlockRay>,
            block: &TriangleBlock<BLOCK>,
            t_max: f32,
        ) -> BlockHits {
            block_hits_sse(ray, block, t_max)
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
}
