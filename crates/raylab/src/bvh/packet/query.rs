//! What a chunk of rays is traced for, and where its rays come from and its answers go: the
//! queries (closest hit, occlusion: the trait here, each one's tracing beside the packet
//! traversals in `mod.rs`, so that this file needs nothing from there), the rays as records or
//! rows, and the answers as a slice, as rows of hits or as a mask.

use super::leaf::PacketKernel;
use super::rays::PacketRays;
use crate::accel::{Hit, HitRows, RayRows};
use crate::bvh::node::WideBvh;
use crate::ray::Ray;

/// A query traced in packets: closest hit or occlusion. (A trait rather than closures, so that
/// everything inlines into the instruction set's entry point.)
pub(super) trait Query {
    type Answer;
    /// # Safety
    /// The CPU must support `K`'s instruction set (for this whole trait).
    unsafe fn alone<K: PacketKernel>(bvh: &WideBvh, ray: &Ray) -> Self::Answer;
    /// Traces a packet of at least two rays; returns what [`answer`](Self::answer) needs.
    unsafe fn packet<K: PacketKernel>(bvh: &WideBvh, rays: &mut PacketRays) -> u64;
    /// The answer of lane `j` of a traced packet.
    fn answer(rays: &PacketRays, traced: u64, j: usize) -> Self::Answer;
}

/// Where a chunk's rays are read one at a time (those traced alone): records or rows.
pub(super) trait Rays {
    fn ray(&self, i: usize) -> Ray;
}

impl Rays for [Ray] {
    #[inline(always)]
    fn ray(&self, i: usize) -> Ray {
        self[i]
    }
}

impl Rays for RayRows {
    #[inline(always)]
    fn ray(&self, i: usize) -> Ray {
        RayRows::ray(self, i)
    }
}

/// Where a chunk's answers by `Q` go: answer `i` for ray `i`.
pub(super) trait Answers<Q: Query> {
    fn put(&mut self, i: usize, answer: Q::Answer);

    /// The answers of a packet of the whole chunk (lane `i` for ray `i`).
    #[inline(always)]
    fn put_packet(&mut self, rays: &PacketRays, traced: u64) {
        for i in 0..rays.len {
            self.put(i, Q::answer(rays, traced, i));
        }
    }
}

impl<Q: Query> Answers<Q> for [Q::Answer] {
    #[inline(always)]
    fn put(&mut self, i: usize, answer: Q::Answer) {
        self[i] = answer;
    }

    /// Lane by lane (the slice is the chunk's: one answer per lane).
    #[inline(always)]
    fn put_packet(&mut self, rays: &PacketRays, traced: u64) {
        for (i, out) in self.iter_mut().enumerate() {
            *out = Q::answer(rays, traced, i);
        }
    }
}

/// Closest hits in rows: a packet's best hits are rows already, copied as they are (misses
/// given `HitRows`' values).
impl Answers<ClosestHits> for HitRows {
    #[inline(always)]
    fn put(&mut self, i: usize, answer: Option<Hit>) {
        self.set(i, answer);
    }

    #[inline(always)]
    fn put_packet(&mut self, rays: &PacketRays, _: u64) {
        let n = rays.len.min(crate::accel::ROWS);
        for i in 0..n {
            let miss = rays.best_triangle[i] == HitRows::MISS;
            self.t[i] = if miss { f32::INFINITY } else { rays.best_t[i] };
            self.triangle[i] = rays.best_triangle[i];
            self.b1[i] = if miss { 0.0 } else { rays.best_b1[i] };
            self.b2[i] = if miss { 0.0 } else { rays.best_b2[i] };
        }
    }
}

/// Occlusion as a mask: bit `i` set where ray `i` is occluded.
pub(super) struct OccludedMask(pub(super) u64);

impl Answers<OccludedEach> for OccludedMask {
    #[inline(always)]
    fn put(&mut self, i: usize, occluded: bool) {
        self.0 |= (occluded as u64) << i;
    }

    #[inline(always)]
    fn put_packet(&mut self, rays: &PacketRays, open: u64) {
        self.0 |= rays.all() & !open;
    }
}

/// [`closest_hits`](super::closest_hits) (its `Query` is beside the packet traversals).
pub(super) struct ClosestHits;

/// [`occluded_each`](super::occluded_each) (its `Query` is beside the packet traversals).
pub(super) struct OccludedEach;
