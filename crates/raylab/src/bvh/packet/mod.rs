//! Coherent packets: up to [`PACKET`] rays traced through the tree together.
//!
//! Interior nodes are tested once per packet, against the packet's [`Frustum`] (an interval
//! bound of its rays that is conservative in floating point), so the cost of the upper tree is
//! shared by all the rays. A leaf's box is then tested per ray, exactly as single-ray traversal
//! tests it, and its triangles are tested against the rays that enter it by the same watertight
//! test, several rays per instruction ([`PacketKernel::packet_leaf`]). Where the rays' lines meet
//! in one point, a leaf's triangles that no line crosses are culled for the whole packet, and
//! the lane kernels test a leaf far larger than the packet's footprint (a wall before a camera
//! tile) against every open ray without the per-ray box test, which gives the same answers
//! (`packet/lanes.rs`). Every ray gets exactly the answer that [`closest_hit`] or
//! [`occluded`] gives it alone: no box that one of its rays enters is ever pruned, and ties at
//! equal `t` go to the lowest triangle index as always.
//!
//! A packet's rays share their direction octant and dominant axis, so that the slab test's near
//! planes and the watertight test's axis permutation are the same for all of them. A chunk of
//! rays is split by these first; rays that cannot join a packet (a zero direction component,
//! nothing to hit) or that are alone in their group are traced one by one.

mod bundle;
#[cfg(target_arch = "x86_64")]
mod lanes;
pub(crate) mod leaf;
mod query;
pub(crate) mod rays;
mod rows;
mod setup;

use crate::accel::{Hit, HitRows, RayRows};
use crate::bvh::bounds::Frustum;
use crate::bvh::node::{Child, WideBvh, decode};
use crate::bvh::traverse::{Stack, closest_hit, occluded};
use crate::ray::Ray;
use leaf::PacketKernel;
use query::{Answers, ClosestHits, OccludedEach, OccludedMask, Query, Rays};
use rays::{PACKET, PacketRays, Shared};

/// A chunk of up to [`PACKET`] rays, prepared once (lane `i` for ray `i`) and sorted into
/// groups of one direction octant and dominant axis: the rays that can be traced together.
struct Chunk {
    lanes: PacketRays,
    /// The rays of each group, as bit masks.
    groups: [u64; 24],
    /// The groups with rays in them.
    present: u32,
    /// What each group's rays share.
    shared: [Shared; 24],
    /// The rays that must be traced alone (nothing to hit, or a zero direction component).
    alone: u64,
    /// A second packet for a group that is not the whole chunk, made when first needed.
    gathered: Option<PacketRays>,
    /// The rays' directions and ranges in rows, on their way into `lanes` ([`setup::fill`]).
    rows: rows::RestRows,
}

thread_local! {
    /// Each thread's spare [`Chunk`] (see [`Chunk::take`]).
    static SPARE: std::cell::Cell<Option<Box<Chunk>>> = const { std::cell::Cell::new(None) };
}

/// The indices of the bits set in `mask`, lowest first.
#[inline(always)]
fn bits(mut mask: u64) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let i = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            i
        })
    })
}

impl Chunk {
    /// This thread's chunk, or a new one: a fresh chunk is kilobytes of arrays to clear, which would
    /// cost a clearing per tile of 64 rays. Taken out of the thread-local
    /// slot rather than borrowed in a closure, so that the tracing stays inlined into the
    /// instruction set's entry point (a closure would not inherit its target features).
    #[inline(always)]
    fn take() -> Box<Chunk> {
        SPARE.take().unwrap_or_else(|| Box::new(Chunk::new()))
    }

    /// Keeps `chunk` for this thread's next call.
    #[inline(always)]
    fn give_back(chunk: Box<Chunk>) {
        SPARE.set(Some(chunk));
    }

    fn new() -> Chunk {
        Chunk {
            lanes: PacketRays::new(),
            groups: [0; 24],
            present: 0,
            shared: [([false; 3], [0, 1, 2]); 24],
            alone: 0,
            gathered: None,
            rows: [[0.0; PACKET]; 5],
        }
    }

    /// Prepares `rays` (at most [`PACKET`]).
    ///
    /// # Safety
    /// The CPU must support `K`'s instruction set.
    #[inline(always)]
    unsafe fn prepare<K: PacketKernel>(&mut self, rays: &[Ray]) {
        // SAFETY: the caller's guarantee.
        let groups = unsafe { setup::fill::<K>(&mut self.lanes, &mut self.rows, rays) };
        self.group(&groups[..rays.len()]);
    }

    /// Prepares rays given in rows (at most [`PACKET`]).
    #[inline(always)]
    fn prepare_rows(&mut self, rays: &RayRows) {
        let groups = setup::fill_rows(&mut self.lanes, rays);
        self.group(&groups[..rays.len]);
    }

    /// Sorts the prepared lanes into their `groups`.
    #[inline(always)]
    fn group(&mut self, groups: &[u8]) {
        self.groups = [0; 24];
        self.present = 0;
        self.alone = 0;
        // Camera and shadow rays are nearly always one group: found without a loop through
        // memory (each `|=` below waits on the one before it).
        let first = groups.first().copied().unwrap_or(setup::ALONE);
        let differ = groups.iter().fold(0u8, |differ, &group| differ | (group ^ first));
        if differ == 0 && first != setup::ALONE {
            self.groups[first as usize] = self.lanes.all();
            self.present = 1 << first;
        } else {
            let (mut present, mut alone) = (0u32, 0u64);
            for (i, &group) in groups.iter().enumerate() {
                if group == setup::ALONE {
                    alone |= 1 << i;
                } else {
                    self.groups[group as usize] |= 1 << i;
                    present |= 1 << group;
                }
            }
            (self.present, self.alone) = (present, alone);
        }
        for group in bits(self.present as u64) {
            self.shared[group] = setup::shared(group as u8);
        }
    }

    /// Answers every ray of the chunk in `out`, by `Q`: alone or in packets.
    ///
    /// # Safety
    /// The CPU must support `K`'s instruction set.
    #[inline(always)]
    unsafe fn trace<K: PacketKernel, Q: Query>(
        &mut self,
        bvh: &WideBvh,
        rays: &(impl Rays + ?Sized),
        out: &mut (impl Answers<Q> + ?Sized),
    ) {
        for i in bits(self.alone) {
            // SAFETY: the caller guarantees `K`'s instruction set.
            out.put(i, unsafe { Q::alone::<K>(bvh, &rays.ray(i)) });
        }
        let all = self.lanes.all();
        for group in bits(self.present as u64) {
            let members = self.groups[group];
            if members.count_ones() == 1 {
                let i = members.trailing_zeros() as usize;
                // SAFETY: the caller guarantees `K`'s instruction set.
                out.put(i, unsafe { Q::alone::<K>(bvh, &rays.ray(i)) });
                continue;
            }
            let (negative, k) = self.shared[group];
            if members == all {
                // The common case for camera and shadow rays: the whole chunk is one packet.
                self.lanes.negative = negative;
                self.lanes.k = k;
                // SAFETY: the caller guarantees `K`'s instruction set.
                let traced = unsafe { Q::packet::<K>(bvh, &mut self.lanes) };
                out.put_packet(&self.lanes, traced);
                continue;
            }
            let gathered = self.gathered.get_or_insert_with(PacketRays::new);
            for (j, i) in bits(members).enumerate() {
                gathered.copy_lane(j, &self.lanes, i);
            }
            gathered.len = members.count_ones() as usize;
            gathered.negative = negative;
            gathered.k = k;
            // SAFETY: the caller guarantees `K`'s instruction set.
            let traced = unsafe { Q::packet::<K>(bvh, gathered) };
            for (j, i) in bits(members).enumerate() {
                out.put(i, Q::answer(gathered, traced, j));
            }
        }
    }
}

impl Query for ClosestHits {
    type Answer = Option<Hit>;

    #[inline(always)]
    unsafe fn alone<K: PacketKernel>(bvh: &WideBvh, ray: &Ray) -> Option<Hit> {
        // SAFETY: the caller's guarantee.
        unsafe { closest_hit::<K>(bvh, ray) }
    }

    #[inline(always)]
    unsafe fn packet<K: PacketKernel>(bvh: &WideBvh, rays: &mut PacketRays) -> u64 {
        // SAFETY: the caller's guarantee.
        unsafe { closest_packet::<K>(bvh, rays) };
        0
    }

    #[inline(always)]
    fn answer(rays: &PacketRays, _: u64, j: usize) -> Option<Hit> {
        rays.best(j)
    }
}

impl Query for OccludedEach {
    type Answer = bool;

    #[inline(always)]
    unsafe fn alone<K: PacketKernel>(bvh: &WideBvh, ray: &Ray) -> bool {
        // SAFETY: the caller's guarantee.
        unsafe { occluded::<K>(bvh, ray) }
    }

    /// The rays still open: not occluded.
    #[inline(always)]
    unsafe fn packet<K: PacketKernel>(bvh: &WideBvh, rays: &mut PacketRays) -> u64 {
        // SAFETY: the caller's guarantee.
        unsafe { occluded_packet::<K>(bvh, rays) }
    }

    #[inline(always)]
    fn answer(_: &PacketRays, open: u64, j: usize) -> bool {
        open & (1 << j) == 0
    }
}

/// A stack entry: a child reference, the packet's entry distance, and where its box is
/// (`8·node + slot`).
type Entry = (u32, f32, u32);

/// The closest hit of every ray, exactly as [`closest_hit`] finds it.
///
/// # Safety
/// The CPU must support `K`'s instruction set.
#[inline(always)]
pub(crate) unsafe fn closest_hits<K: PacketKernel>(
    bvh: &WideBvh,
    rays: &[Ray],
    out: &mut [Option<Hit>],
) {
    assert_eq!(rays.len(), out.len(), "one answer per ray");
    let mut chunk = Chunk::take();
    for (rays, out) in rays.chunks(PACKET).zip(out.chunks_mut(PACKET)) {
        // SAFETY: the caller guarantees `K`'s instruction set.
        unsafe { chunk.prepare::<K>(rays) };
        // SAFETY: the caller guarantees `K`'s instruction set.
        unsafe { chunk.trace::<K, ClosestHits>(bvh, rays, out) };
    }
    Chunk::give_back(chunk);
}

/// [`closest_hits`] of at most [`PACKET`] rays, answered in rows.
///
/// # Safety
/// The CPU must support `K`'s instruction set.
#[inline(always)]
pub(crate) unsafe fn closest_hits_rows<K: PacketKernel>(
    bvh: &WideBvh,
    rays: &[Ray],
    out: &mut HitRows,
) {
    assert!(rays.len() <= PACKET, "at most {PACKET} rays in rows");
    let mut chunk = Chunk::take();
    // SAFETY: the caller guarantees `K`'s instruction set.
    unsafe { chunk.prepare::<K>(rays) };
    // SAFETY: the caller guarantees `K`'s instruction set.
    unsafe { chunk.trace::<K, ClosestHits>(bvh, rays, out) };
    Chunk::give_back(chunk);
}

/// Traces a packet of at least two rays to their closest hits.
///
/// # Safety
/// The CPU must support `K`'s instruction set.
#[inline(always)]
unsafe fn closest_packet<K: PacketKernel>(bvh: &WideBvh, rays: &mut PacketRays) {
    let all = rays.all();
    let frustum = rays.frustum();
    debug_assert_eq!(Some(frustum), Frustum::of((0..rays.len).map(|i| rays.box_ray(i))));
    rays.bundle = rays.bundle(&frustum);
    let mut limit = rays.limit();
    // SAFETY: the caller guarantees `K`'s instruction set.
    let frustum = unsafe { K::prepare_frustum(&frustum) };

    let mut stack = Stack::<Entry>::new();
    let mut node = 0u32;
    loop {
        // SAFETY: the caller guarantees `K`'s instruction set.
        let (mut mask, near) =
            unsafe { K::enter_frustum(&bvh.nodes[node as usize], &frustum, limit) };
        let children = &bvh.nodes[node as usize].children;
        if mask.count_ones() == 1
            && let Child::Node(index) = decode(children[mask.trailing_zeros() as usize])
        {
            node = index;
            continue;
        }
        // Nearest entry on top, as in single-ray traversal.
        let first = stack.len();
        while mask != 0 {
            let k = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            stack.push_sorted(first, (children[k], near[k], 8 * node + k as u32), |e| e.1);
        }
        loop {
            let Some((child, near, place)) = stack.pop() else {
                return;
            };
            if near > limit {
                continue;
            }
            match decode(child) {
                Child::Node(index) => {
                    node = index;
                    break;
                }
                Child::Leaf(offset) => {
                    let bounds = bvh.nodes[(place / 8) as usize].bounds((place % 8) as usize);
                    let mut open = all;
                    // SAFETY: the caller guarantees `K`'s instruction set.
                    unsafe { K::packet_leaf(rays, &mut open, false, bvh, &bounds, offset) };
                    limit = rays.limit();
                }
                Child::Empty => {}
            }
        }
    }
}

/// Whether each ray is occluded, exactly as [`occluded`] decides it.
///
/// # Safety
/// The CPU must support `K`'s instruction set.
#[inline(always)]
pub(crate) unsafe fn occluded_each<K: PacketKernel>(bvh: &WideBvh, rays: &[Ray], out: &mut [bool]) {
    assert_eq!(rays.len(), out.len(), "one answer per ray");
    let mut chunk = Chunk::take();
    for (rays, out) in rays.chunks(PACKET).zip(out.chunks_mut(PACKET)) {
        // SAFETY: the caller guarantees `K`'s instruction set.
        unsafe { chunk.prepare::<K>(rays) };
        // SAFETY: the caller guarantees `K`'s instruction set.
        unsafe { chunk.trace::<K, OccludedEach>(bvh, rays, out) };
    }
    Chunk::give_back(chunk);
}

/// Which of the rays in rows are occluded, as a mask (bit `i` for ray `i`), exactly as
/// [`occluded`] decides each.
///
/// # Safety
/// The CPU must support `K`'s instruction set.
#[inline(always)]
pub(crate) unsafe fn occluded_rows<K: PacketKernel>(bvh: &WideBvh, rays: &RayRows) -> u64 {
    let mut chunk = Chunk::take();
    chunk.prepare_rows(rays);
    let mut out = OccludedMask(0);
    // SAFETY: the caller guarantees `K`'s instruction set.
    unsafe { chunk.trace::<K, OccludedEach>(bvh, rays, &mut out) };
    Chunk::give_back(chunk);
    out.0
}

/// Traces a packet of at least two rays for occlusion; returns the mask of rays not occluded.
///
/// # Safety
/// The CPU must support `K`'s instruction set.
#[inline(always)]
unsafe fn occluded_packet<K: PacketKernel>(bvh: &WideBvh, rays: &mut PacketRays) -> u64 {
    let mut open = rays.all();
    let frustum = rays.frustum();
    debug_assert_eq!(Some(frustum), Frustum::of((0..rays.len).map(|i| rays.box_ray(i))));
    rays.bundle = rays.bundle(&frustum);
    let mut limit = rays.limit();
    // SAFETY: the caller guarantees `K`'s instruction set.
    let frustum = unsafe { K::prepare_frustum(&frustum) };

    let mut stack = Stack::<u32>::new();
    stack.push(0);
    while let Some(index) = stack.pop() {
        let node = &bvh.nodes[index as usize];
        // SAFETY: the caller guarantees `K`'s instruction set.
        let (mut mask, _) = unsafe { K::enter_frustum(node, &frustum, limit) };
        while mask != 0 {
            let k = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            match decode(node.children[k]) {
                Child::Node(index) => stack.push(index),
                Child::Leaf(offset) => {
                    let before = open;
                    // SAFETY: the caller guarantees `K`'s instruction set.
                    unsafe { K::packet_leaf(rays, &mut open, true, bvh, &node.bounds(k), offset) };
                    if open == 0 {
                        return 0;
                    }
                    if open != before {
                        rays.close(before & !open);
                        limit = rays.limit();
                    }
                }
                Child::Empty => {}
            }
        }
    }
    open
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::accel::Accelerator;
    use crate::bvh::{Bvh, Isa};
    use crate::scene::Scene;

    /// The lab's Cornell box, whose walls and boxes cover many tiles of camera and shadow
    /// rays: packets whose lane kernels test those leaves without their box test (counted, on
    /// every instruction set the CPU has) give every ray its single-ray answer, bit for bit.
    #[test]
    fn leaves_that_cover_a_packet_give_the_single_ray_answers() {
        let triangles = Scene::built_in("cornell").expect("built in").vertices();
        let scalar = Bvh::new(&triangles).with_isa(Isa::Scalar).expect("scalar");
        let light = Vec3::new(0.1, -0.6, 0.2);
        let mut tiles: Vec<Vec<Ray>> = Vec::new();
        for (c, origin) in [
            Vec3::new(0.0, 0.0, -3.0),
            Vec3::new(0.3, -0.4, -1.2),
            Vec3::new(-0.7, 0.8, 0.5),
            Vec3::new(0.999, 0.0, 0.0),
        ]
        .into_iter()
        .enumerate()
        {
            for ty in 0..12 {
                for tx in 0..12 {
                    // 8×8 pixels of a 96×96 image, some tiles across the view's axes.
                    let step = [0.02, 0.011, 0.035, 0.02][c];
                    let tile: Vec<Ray> = (0..64)
                        .map(|i| {
                            let x = (tx * 8 + i % 8) as f32 - 47.5;
                            let y = (ty * 8 + i / 8) as f32 - 47.5;
                            let d = Vec3::new(x * step, y * step, 1.0);
                            let d = if c == 2 { Vec3::new(d.z, d.y, -d.x) } else { d };
                            Ray::new(origin, d)
                        })
                        .collect();
                    // Shadow segments from the tile's hits toward the light.
                    let shadows: Vec<Ray> = tile
                        .iter()
                        .filter_map(|ray| scalar.closest_hit(ray).map(|h| ray.at(h.t * 0.9999)))
                        .map(|p| Ray::segment(p, light - p, 1.0))
                        .collect();
                    tiles.push(tile);
                    tiles.push(shadows);
                }
            }
        }
        let bits = |h: &Option<Hit>| {
            h.map(|h| (h.t.to_bits(), h.triangle, h.b1.to_bits(), h.b2.to_bits()))
        };
        let rays: usize = tiles.iter().map(Vec::len).sum();
        let mut hits = 0;
        for isa in Isa::ALL {
            let Some(bvh) = Bvh::new(&triangles).with_isa(isa) else {
                eprintln!("note: this CPU lacks {}: its packets are not tested here", isa.name());
                continue;
            };
            #[cfg(target_arch = "x86_64")]
            lanes::COVERING.set(0);
            for tile in &tiles {
                let mut closest = vec![None; tile.len()];
                let mut occluded = vec![false; tile.len()];
                bvh.closest_hits(tile, &mut closest);
                bvh.occluded_each(tile, &mut occluded);
                for (i, ray) in tile.iter().enumerate() {
                    let want = scalar.closest_hit(ray);
                    hits += (isa == Isa::Scalar && want.is_some()) as usize;
                    assert_eq!(bits(&closest[i]), bits(&want), "{} closest: {ray:?}", isa.name());
                    assert_eq!(
                        occluded[i],
                        scalar.occluded(ray),
                        "{} occluded: {ray:?}",
                        isa.name()
                    );
                }
            }
            // The lane kernels (every x86 set) took the path without the box test.
            #[cfg(target_arch = "x86_64")]
            if isa != Isa::Scalar {
                let covering = lanes::COVERING.get();
                assert!(covering > 1_000, "{}: {covering} covering leaves", isa.name());
            }
        }
        assert!(hits > rays / 2, "{hits} hits of {rays} rays");
    }
}
