//! Small scenes without a tree: every triangle tested, sixteen per instruction.
//!
//! A scene of a few dozen triangles (the Cornell boxes) costs a tree more than the tree saves. A
//! diffuse ray in Mitsuba's 36-triangle box enters the root, sorts and pushes three or four
//! children, pops them and tests a leaf block of four triangles in each, every step a branch that
//! incoherent rays mispredict. Three AVX-512 watertight tests of sixteen triangles cover the same
//! scene with no branch but the loop's. So for scenes of at most
//! [`BuildSettings::flat_limit`](crate::bvh::BuildSettings::flat_limit) triangles a [`Bvh`](crate::bvh::Bvh)
//! also keeps [`Flat`]: the triangles in index order, sixteen to a block, and answers single rays
//! from it (and batches of incoherent rays, in lanes: `flat_rays.rs`).
//!
//! ## Layout, worked through
//! A block is the vertices of sixteen triangles coordinate by coordinate,
//! `vertices[j][axis][lane]` (j = 0, 1, 2 the corners), 9 rows of 16 floats, each row one 64-byte
//! AVX-512 register and one cache line; then the sixteen triangle indices and a bit mask of the
//! lanes in use. Mitsuba's box, triangles 0–35, all of non-zero area:
//!
//! | block | lanes 0–15 hold triangles | `lanes` |
//! |---|---|---|
//! | 0 | 0–15 | `0xffff` |
//! | 1 | 16–31 | `0xffff` |
//! | 2 | 32–35, then NaN vertices | `0x000f` |
//!
//! 704 bytes a block, 2,112 for the box: it stays in the first-level cache. Triangles of zero
//! area or with a non-finite vertex can never be hit and are left out (their index is simply
//! skipped), as in the tree.
//!
//! Beside the blocks the list keeps the same triangles as indices into their distinct corners
//! ([`SharedCorners`]: the box's 108 triangle corners are 36 distinct ones; 1,008 bytes more),
//! which the rays in lanes read, putting each corner in their frames once (`flat_rays.rs`).
//!
//! ## The answer is the tree's and brute force's
//! Each lane runs the watertight test's own arithmetic ([`watertight_lanes_with`](crate::bvh::simd::watertight_lanes_with)),
//! lanes whose edge functions round to zero go to [`WatertightRay::intersect`]'s double-precision
//! path, and hits are merged in index order, keeping the smallest `t` and, at equal `t`, the lowest
//! index. So `t`, triangle and barycentrics are bit for bit [`BruteForce`](crate::BruteForce)'s.
//! AVX2 tests a block in two halves of eight and SSE2 in four quarters; the scalar twin tests it
//! lane by lane ([`WatertightRay::block_candidates`], then `intersect`).

use glam::Vec3;

use super::can_hit;
use crate::accel::Hit;
use crate::ray::Ray;
use crate::triangle::{TriangleBlock, WatertightRay};

/// Triangles per block: one AVX-512 register per coordinate row.
pub(crate) const FLAT_LANES: usize = 16;

/// Sixteen triangles and their indices (see the module documentation).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(crate) struct FlatBlock {
    triangles: TriangleBlock<FLAT_LANES>,
    ids: [u32; FLAT_LANES],
    /// Bit `k` is set where lane `k` holds a triangle.
    lanes: u32,
}

/// Every triangle of a small scene, in index order, in blocks of sixteen; and the same
/// triangles as corners shared between them, for the rays in lanes.
#[derive(Clone, Debug, Default)]
pub(crate) struct Flat {
    blocks: Vec<FlatBlock>,
    shared: SharedCorners,
}

/// The flat list's triangles as indices into its distinct corners, in index order (see
/// `flat_rays.rs`: a corner is put in each ray's frame once, not once per triangle that has it).
///
/// Corners are the same when their bits are, so a triangle's corners are exactly its own.
#[derive(Clone, Debug, Default)]
pub(crate) struct SharedCorners {
    /// The distinct corners.
    pub(crate) corners: Vec<Vec3>,
    /// Each triangle's corners (indices into `corners`) and its index in the scene.
    pub(crate) triangles: Vec<([u32; 3], u32)>,
}

impl SharedCorners {
    /// The triangles of `blocks`, in order, with their corners shared.
    fn new(blocks: &[FlatBlock]) -> SharedCorners {
        let mut shared = SharedCorners::default();
        let mut seen = std::collections::HashMap::<[u32; 3], u32>::new();
        for block in blocks {
            let mut lanes = block.lanes;
            while lanes != 0 {
                let lane = lanes.trailing_zeros() as usize;
                lanes &= lanes - 1;
                let corners = block.triangles.triangle(lane).map(|p| {
                    *seen.entry(p.to_array().map(f32::to_bits)).or_insert_with(|| {
                        shared.corners.push(p);
                        // At most three a triangle, and a BVH holds fewer than 2^27.
                        (shared.corners.len() - 1) as u32
                    })
                });
                shared.triangles.push((corners, block.ids[lane]));
            }
        }
        shared
    }

    /// The corners that `corners` (a triangle's indices) name.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    #[inline(always)]
    pub(crate) fn triangle(&self, [a, b, c]: [u32; 3]) -> [Vec3; 3] {
        [self.corners[a as usize], self.corners[b as usize], self.corners[c as usize]]
    }
}

impl Flat {
    /// The triangles `indices` (ascending, each of non-zero area with finite vertices).
    pub(crate) fn new(triangles: &[[Vec3; 3]], indices: &[u32]) -> Flat {
        debug_assert!(indices.windows(2).all(|w| w[0] < w[1]), "indices ascend");
        let blocks: Vec<FlatBlock> = indices
            .chunks(FLAT_LANES)
            .map(|chunk| {
                let mut block = FlatBlock {
                    triangles: TriangleBlock::EMPTY,
                    ids: [u32::MAX; FLAT_LANES],
                    lanes: 0,
                };
                for (lane, &i) in chunk.iter().enumerate() {
                    block.triangles.set(lane, triangles[i as usize]);
                    block.ids[lane] = i;
                    block.lanes |= 1 << lane;
                }
                block
            })
            .collect();
        let shared = SharedCorners::new(&blocks);
        Flat { blocks, shared }
    }

    /// The triangles in index order with their corners shared (for the lanes of
    /// `flat_rays.rs`).
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    #[inline(always)]
    pub(crate) fn shared(&self) -> &SharedCorners {
        &self.shared
    }

    /// Bytes of the blocks and the shared corners.
    pub(crate) fn bytes(&self) -> usize {
        self.blocks.len() * size_of::<FlatBlock>()
            + self.shared.corners.len() * size_of::<Vec3>()
            + self.shared.triangles.len() * size_of::<([u32; 3], u32)>()
    }

    /// Moves each lane's triangle to `moved(index)`, and shares the new corners.
    pub(crate) fn move_triangles(&mut self, moved: impl Fn(u32) -> [Vec3; 3]) {
        for block in &mut self.blocks {
            let mut lanes = block.lanes;
            while lanes != 0 {
                let lane = lanes.trailing_zeros() as usize;
                lanes &= lanes - 1;
                block.triangles.set(lane, moved(block.ids[lane]));
            }
        }
        self.shared = SharedCorners::new(&self.blocks);
    }
}

/// The scalar twin: every block lane by lane, the batched pre-test, then the full test.
pub(crate) fn closest_hit_scalar(flat: &Flat, ray: &Ray) -> Option<Hit> {
    if !can_hit(ray) {
        return None;
    }
    let watertight = WatertightRay::new(ray);
    let mut best = None;
    for block in &flat.blocks {
        // Blocks ascend in index, so a later block's hit must be strictly nearer: the limit is
        // the best `t` itself.
        let limit = best.map_or(ray.t_max, |b: Hit| b.t);
        let mut candidates = watertight.block_candidates(&block.triangles, limit);
        candidates &= block.lanes;
        while candidates != 0 {
            let lane = candidates.trailing_zeros() as usize;
            candidates &= candidates - 1;
            let [v0, v1, v2] = block.triangles.triangle(lane);
            if let Some(h) = watertight.intersect(v0, v1, v2, limit) {
                Hit { t: h.t, triangle: block.ids[lane], b1: h.b1, b2: h.b2 }.keep_first(&mut best);
            }
        }
    }
    best
}

/// The scalar twin of occlusion.
pub(crate) fn occluded_scalar(flat: &Flat, ray: &Ray) -> bool {
    if !can_hit(ray) {
        return false;
    }
    let watertight = WatertightRay::new(ray);
    flat.blocks.iter().any(|block| {
        let mut candidates = watertight.block_candidates(&block.triangles, ray.t_max);
        candidates &= block.lanes;
        while candidates != 0 {
            let lane = candidates.trailing_zeros() as usize;
            candidates &= candidates - 1;
            let [v0, v1, v2] = block.triangles.triangle(lane);
            if watertight.intersect(v0, v1, v2, ray.t_max).is_some() {
                return true;
            }
        }
        false
    })
}

#[cfg(target_arch = "x86_64")]
pub(crate) use x86::{closest_hit_lanes, occluded_lanes};

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::*;
    use crate::bvh::simd::{LaneHits, LaneMask, Lanes, RayBroadcast, watertight_lanes_with};

    /// The lane test of lanes `first..first + W` of `block` for hits below `t_max`.
    ///
    /// # Safety
    /// The CPU must support `V`'s instruction set, `V` must hold `W` floats, and `first` must
    /// be a multiple of `W` below [`FLAT_LANES`] (rows are 64-byte aligned, so every load is
    /// aligned to the register's size).
    #[inline(always)]
    unsafe fn test<V: Lanes, const W: usize>(
        ray: &RayBroadcast<V>,
        block: &FlatBlock,
        first: usize,
        t_max: f32,
    ) -> LaneHits<V> {
        debug_assert!(first.is_multiple_of(W) && first + W <= FLAT_LANES);
        let [kx, ky, kz] = ray.k;
        let rows = &block.triangles.vertices;
        // SAFETY: the caller's guarantee; `first + W <= 16` keeps every load in its row.
        unsafe {
            let row = |j: usize, axis: usize| V::load(rows[j][axis][first..].as_ptr());
            let lanes = ray.with_vertices(
                [
                    [row(0, kx), row(0, ky), row(0, kz)],
                    [row(1, kx), row(1, ky), row(1, kz)],
                    [row(2, kx), row(2, ky), row(2, kz)],
                ],
                t_max,
            );
            let mask = (block.lanes >> first) & ((1u32 << W) - 1);
            watertight_lanes_with::<V, true>(&lanes, mask)
        }
    }

    /// The closest hit with `W`-lane registers `V`.
    ///
    /// Every block is tested against the ray's own range (not the best hit so far, so the
    /// blocks' tests do not wait for each other); a block without a candidate skips the rest of
    /// its test (rays in a small room miss most blocks). Each lane keeps the nearest of its
    /// hits in registers, the earlier block winning
    /// at equal `t` (blocks ascend in index), with no branch on which lanes hit; one reduction
    /// at the end picks the nearest lane, the lowest index among equals. Lanes only the
    /// double-precision test can decide (rare) are merged alongside.
    ///
    /// # Safety
    /// The CPU must support `V`'s instruction set, and `V` must hold `W` floats.
    #[inline(always)]
    pub(crate) unsafe fn closest_hit_lanes<V: Lanes, const W: usize>(
        flat: &Flat,
        ray: &Ray,
    ) -> Option<Hit> {
        if !can_hit(ray) {
            return None;
        }
        let watertight = WatertightRay::new(ray);
        // SAFETY: (the whole body) the caller's guarantee; `first` steps by `W` below 16, ids
        // are as aligned as the rows, and every store writes `W` floats into an array of `W`.
        unsafe {
            let lanes = RayBroadcast::<V>::new(&watertight);
            let mut best_t = V::splat(f32::INFINITY);
            let mut best_b1 = V::splat(0.0);
            let mut best_b2 = V::splat(0.0);
            // Triangle indices ride along as float bits: only ever selected, never computed.
            let mut best_id = V::splat(f32::from_bits(u32::MAX));
            // Hits only the double-precision test could decide.
            let mut rare = None;
            for block in &flat.blocks {
                for first in (0..FLAT_LANES).step_by(W) {
                    let decided = test::<V, W>(&lanes, block, first, ray.t_max);
                    let nearer = decided.hit_mask.and(decided.t.lt(best_t));
                    best_t = V::select(nearer, decided.t, best_t);
                    best_b1 = V::select(nearer, decided.b1, best_b1);
                    best_b2 = V::select(nearer, decided.b2, best_b2);
                    let ids = V::load(block.ids[first..].as_ptr().cast::<f32>());
                    best_id = V::select(nearer, ids, best_id);
                    let mut undecided = decided.undecided;
                    while undecided != 0 {
                        let lane = undecided.trailing_zeros() as usize;
                        undecided &= undecided - 1;
                        let [v0, v1, v2] = block.triangles.triangle(first + lane);
                        if let Some(h) = watertight.intersect(v0, v1, v2, ray.t_max) {
                            let id = block.ids[first + lane];
                            Hit { t: h.t, triangle: id, b1: h.b1, b2: h.b2 }.keep_first(&mut rare);
                        }
                    }
                }
            }
            let t = best_t.reduce_min();
            let mut best = None;
            if t < f32::INFINITY {
                let (mut ids, mut b1, mut b2) = ([0.0f32; W], [0.0f32; W], [0.0f32; W]);
                best_id.store(ids.as_mut_ptr());
                best_b1.store(b1.as_mut_ptr());
                best_b2.store(b2.as_mut_ptr());
                let mut nearest = best_t.eq(V::splat(t)).bits();
                let mut lane = nearest.trailing_zeros() as usize;
                nearest &= nearest - 1;
                // Equal `t` in several lanes (a shared edge or vertex): the lowest index.
                while nearest != 0 {
                    let other = nearest.trailing_zeros() as usize;
                    nearest &= nearest - 1;
                    if ids[other].to_bits() < ids[lane].to_bits() {
                        lane = other;
                    }
                }
                best = Some(Hit { t, triangle: ids[lane].to_bits(), b1: b1[lane], b2: b2[lane] });
            }
            if let Some(h) = rare {
                h.keep_first(&mut best);
            }
            best
        }
    }

    /// Whether anything is hit, with `W`-lane registers `V`.
    ///
    /// # Safety
    /// As for [`closest_hit_lanes`].
    #[inline(always)]
    pub(crate) unsafe fn occluded_lanes<V: Lanes, const W: usize>(flat: &Flat, ray: &Ray) -> bool {
        if !can_hit(ray) {
            return false;
        }
        let watertight = WatertightRay::new(ray);
        // SAFETY: the caller's guarantee.
        let lanes = unsafe { RayBroadcast::<V>::new(&watertight) };
        for block in &flat.blocks {
            for first in (0..FLAT_LANES).step_by(W) {
                // SAFETY: the caller's guarantee; `first` steps by `W` below 16.
                let decided = unsafe { test::<V, W>(&lanes, block, first, ray.t_max) };
                if decided.hits != 0
                    || watertight.any_lane_hits(
                        &block.triangles,
                        first,
                        decided.undecided,
                        ray.t_max,
                    )
                {
                    return true;
                }
            }
        }
        false
    }
}
