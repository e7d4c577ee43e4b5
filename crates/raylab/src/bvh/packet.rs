//! Coherent packets: up to [`PACKET`] rays traced through the tree together.
//!
//! Interior nodes are tested once per packet, against the packet's [`Frustum`] (an interval
//! bound of its rays that is conservative in floating point), so the cost of the upper tree is
//! shared by all the rays. A leaf's box is then tested per ray, exactly as single-ray traversal
//! tests it, and its triangles are tested against the rays that enter it by the same watertight
//! test, several rays per instruction ([`NodeKernel::packet_leaf`]). Every ray gets exactly the
//! answer that [`closest_hit`] or [`occluded`] gives it alone: no box that one of its rays enters
//! is ever pruned, and ties at equal `t` go to the lowest triangle index as always.
//!
//! A packet's rays share their direction octant and dominant axis, so that the slab test's near
//! planes and the watertight test's axis permutation are the same for all of them. A chunk of
//! rays is split by these first; rays that cannot join a packet (a zero direction component,
//! nothing to hit) or that are alone in their group are traced one by one.

use glam::Vec3;

use super::bounds::{Bounds, FAR_SCALE, Frustum, RayBoxTest};
use super::bundle::LineBundle;
use super::kernels::{NodeKernel, prepare_triangle_ray};
use super::packet_setup;
use super::traverse::{Closest, Stack, can_hit, closest_hit, leaf_occluded, occluded};
use super::wide::{Child, WideBvh, decode};
use crate::accel::Hit;
use crate::float::next_float_up;
use crate::ray::Ray;
use crate::triangle::WatertightRay;

/// The most rays traced together: an 8×8 tile of camera rays.
pub(crate) const PACKET: usize = 64;

/// The rays of one packet, lane by lane (structure of arrays), with their search state.
/// Lanes from `len` on hold stale values and are never counted.
#[derive(Clone)]
#[repr(C, align(64))]
pub(crate) struct PacketRays {
    /// Origins, per world axis.
    pub origin: [[f32; PACKET]; 3],
    /// `1/d`, per world axis.
    pub inv_direction: [[f32; PACKET]; 3],
    /// The slab test's `t_min` ([`RayBoxTest::t_min`]).
    pub box_t_min: [f32; PACKET],
    /// The watertight test's shear, `shear_x`, `shear_y`, `shear_z`.
    pub shear: [[f32; PACKET]; 3],
    /// The watertight test's `t_min` ([`WatertightRay`]).
    pub triangle_t_min: [f32; PACKET],
    /// Triangles are accepted below this (see [`Closest`]).
    pub triangle_limit: [f32; PACKET],
    /// Boxes are entered up to this.
    pub box_limit: [f32; PACKET],
    /// The closest hit so far (`+∞` for none), its triangle (`u32::MAX` for none) and
    /// barycentrics.
    pub best_t: [f32; PACKET],
    pub best_triangle: [u32; PACKET],
    pub best_b1: [f32; PACKET],
    pub best_b2: [f32; PACKET],
    /// The rays in the packet.
    pub len: usize,
    /// Shared by all rays: the direction's signs, and the watertight test's `kx, ky, kz`
    /// (whose `kz` is the dominant axis).
    pub negative: [bool; 3],
    pub k: [usize; 3],
    /// The rays' lines, when they share their origin: culls a leaf's triangles for all of them.
    pub bundle: Option<LineBundle>,
}

impl PacketRays {
    /// An empty packet, to be filled.
    pub(super) fn new() -> PacketRays {
        PacketRays {
            origin: [[0.0; PACKET]; 3],
            inv_direction: [[0.0; PACKET]; 3],
            box_t_min: [0.0; PACKET],
            shear: [[0.0; PACKET]; 3],
            triangle_t_min: [0.0; PACKET],
            triangle_limit: [0.0; PACKET],
            box_limit: [0.0; PACKET],
            best_t: [0.0; PACKET],
            best_triangle: [0; PACKET],
            best_b1: [0.0; PACKET],
            best_b2: [0.0; PACKET],
            len: 0,
            negative: [false; 3],
            k: [0, 1, 2],
            bundle: None,
        }
    }

    /// Prepares `ray` in lane `i`, and returns its group (direction octant and dominant axis,
    /// `0..24`) with what the group's rays share, or `None` if it cannot join a packet.
    ///
    /// The scalar twin of [`packet_setup::fill`], which fills every lane at once.
    #[cfg_attr(not(test), expect(dead_code, reason = "the scalar twin of `fill`"))]
    pub(super) fn set_lane(&mut self, i: usize, ray: &Ray) -> Option<(usize, Shared)> {
        let box_ray = RayBoxTest::new(ray);
        if !can_hit(ray) || !Frustum::can_join(&box_ray) {
            return None;
        }
        let triangle_ray = WatertightRay::with_inverse(ray, box_ray.inv_direction);
        for axis in 0..3 {
            self.origin[axis][i] = box_ray.origin[axis];
            self.inv_direction[axis][i] = box_ray.inv_direction[axis];
        }
        self.box_t_min[i] = box_ray.t_min;
        self.shear[0][i] = triangle_ray.shear_x;
        self.shear[1][i] = triangle_ray.shear_y;
        self.shear[2][i] = triangle_ray.shear_z;
        self.triangle_t_min[i] = triangle_ray.t_min;
        self.triangle_limit[i] = ray.t_max;
        self.box_limit[i] = ray.t_max * FAR_SCALE;
        self.best_t[i] = f32::INFINITY;
        self.best_triangle[i] = u32::MAX;
        let n = box_ray.negative;
        let group = (n[0] as usize | (n[1] as usize) << 1 | (n[2] as usize) << 2) * 3
            + box_ray.dominant_axis;
        Some((group, (n, [triangle_ray.kx, triangle_ray.ky, triangle_ray.kz])))
    }

    /// Copies lane `j` of `from` (before tracing) into lane `i`.
    #[inline(always)]
    fn copy_lane(&mut self, i: usize, from: &PacketRays, j: usize) {
        for axis in 0..3 {
            self.origin[axis][i] = from.origin[axis][j];
            self.inv_direction[axis][i] = from.inv_direction[axis][j];
            self.shear[axis][i] = from.shear[axis][j];
        }
        self.box_t_min[i] = from.box_t_min[j];
        self.triangle_t_min[i] = from.triangle_t_min[j];
        self.triangle_limit[i] = from.triangle_limit[j];
        self.box_limit[i] = from.box_limit[j];
        self.best_t[i] = from.best_t[j];
        self.best_triangle[i] = from.best_triangle[j];
    }

    /// Ray `i`'s slab test.
    #[inline(always)]
    pub fn box_ray(&self, i: usize) -> RayBoxTest {
        RayBoxTest {
            origin: Vec3::new(self.origin[0][i], self.origin[1][i], self.origin[2][i]),
            inv_direction: Vec3::new(
                self.inv_direction[0][i],
                self.inv_direction[1][i],
                self.inv_direction[2][i],
            ),
            negative: self.negative,
            t_min: self.box_t_min[i],
            dominant_axis: self.k[2],
        }
    }

    /// Ray `i`'s watertight test.
    #[inline(always)]
    pub fn triangle_ray(&self, i: usize) -> WatertightRay {
        WatertightRay {
            origin: Vec3::new(self.origin[0][i], self.origin[1][i], self.origin[2][i]),
            t_min: self.triangle_t_min[i],
            kx: self.k[0],
            ky: self.k[1],
            kz: self.k[2],
            shear_x: self.shear[0][i],
            shear_y: self.shear[1][i],
            shear_z: self.shear[2][i],
        }
    }

    /// Ray `i`'s closest hit so far.
    #[inline(always)]
    fn best(&self, i: usize) -> Option<Hit> {
        (self.best_triangle[i] != u32::MAX).then(|| Hit {
            t: self.best_t[i],
            triangle: self.best_triangle[i],
            b1: self.best_b1[i],
            b2: self.best_b2[i],
        })
    }

    /// Offers ray `i` a hit: kept if nearer than its best, or as near with a lower index.
    #[inline(always)]
    pub fn offer(&mut self, i: usize, t: f32, triangle: u32, b1: f32, b2: f32) {
        if t < self.best_t[i] || (t == self.best_t[i] && triangle < self.best_triangle[i]) {
            self.best_t[i] = t;
            self.best_triangle[i] = triangle;
            self.best_b1[i] = b1;
            self.best_b2[i] = b2;
            self.triangle_limit[i] = next_float_up(t);
            self.box_limit[i] = t * FAR_SCALE;
        }
    }

    /// The greatest box limit of the rays: the packet's. (Rays that are done have their limit
    /// set to `-∞` by [`close`](Self::close).)
    #[inline(always)]
    fn limit(&self) -> f32 {
        highest(&self.box_limit[..self.len])
    }

    /// Takes the rays in `done` out of the packet's limit.
    #[inline(always)]
    fn close(&mut self, mut done: u64) {
        while done != 0 {
            self.box_limit[done.trailing_zeros() as usize] = f32::NEG_INFINITY;
            done &= done - 1;
        }
    }

    /// The packet's frustum: what [`Frustum::of`] gives for its rays, computed from the lanes
    /// (the rays were checked by [`Frustum::can_join`] and share their octant and dominant axis).
    #[inline(always)]
    fn frustum(&self) -> Frustum {
        let n = self.len;
        let mut pad_axes = [false; 3];
        pad_axes[self.k[2]] = true;
        // Written out axis by axis: `[0, 1, 2].map(..)` is not inlined into the instruction
        // set's entry point (its closure is compiled without the entry's target features).
        let (o, inv) = (&self.origin, &self.inv_direction);
        Frustum {
            origin_lo: Vec3::new(lowest(&o[0][..n]), lowest(&o[1][..n]), lowest(&o[2][..n])),
            origin_hi: Vec3::new(highest(&o[0][..n]), highest(&o[1][..n]), highest(&o[2][..n])),
            inv_lo: Vec3::new(lowest(&inv[0][..n]), lowest(&inv[1][..n]), lowest(&inv[2][..n])),
            inv_hi: Vec3::new(highest(&inv[0][..n]), highest(&inv[1][..n]), highest(&inv[2][..n])),
            negative: self.negative,
            t_min: lowest(&self.box_t_min[..n]),
            pad_axes,
        }
    }

    /// The lines of the packet, if they meet in one point: the shared origin, or the rays'
    /// common point at `t = 1` (shadow rays toward a point light).
    #[inline(always)]
    fn bundle(&self, frustum: &Frustum) -> Option<LineBundle> {
        if let Some(bundle) = LineBundle::of(frustum) {
            return Some(bundle);
        }
        let n = self.len;
        let mut end = [[0.0f32; PACKET]; 3];
        for (axis, end) in end.iter_mut().enumerate() {
            let lanes = self.origin[axis].iter().zip(&self.inv_direction[axis]);
            for (end, (&o, &inv)) in end.iter_mut().zip(lanes) {
                *end = o + 1.0 / inv;
            }
        }
        let lo = Vec3::new(lowest(&end[0][..n]), lowest(&end[1][..n]), lowest(&end[2][..n]));
        let hi = Vec3::new(highest(&end[0][..n]), highest(&end[1][..n]), highest(&end[2][..n]));
        LineBundle::through_ends(frustum, lo, hi)
    }

    /// The mask of all rays of the packet.
    #[inline(always)]
    fn all(&self) -> u64 {
        if self.len == PACKET { u64::MAX } else { (1 << self.len) - 1 }
    }
}

/// The least of finite values, eight lanes at a time (a form the compiler vectorizes).
#[inline(always)]
fn lowest(values: &[f32]) -> f32 {
    reduce(values, f32::INFINITY, |a, b| if b < a { b } else { a })
}

/// The greatest of finite values.
#[inline(always)]
fn highest(values: &[f32]) -> f32 {
    reduce(values, f32::NEG_INFINITY, |a, b| if b > a { b } else { a })
}

/// Folds `values` by `pick` in eight columns, then the columns and the rest.
#[inline(always)]
fn reduce(values: &[f32], start: f32, pick: impl Fn(f32, f32) -> f32 + Copy) -> f32 {
    let mut columns = [start; 8];
    let chunks = values.chunks_exact(8);
    let rest = chunks.remainder();
    for chunk in chunks {
        for (c, &v) in columns.iter_mut().zip(chunk) {
            *c = pick(*c, v);
        }
    }
    columns.into_iter().chain(rest.iter().copied()).fold(start, pick)
}

/// The scalar twin of [`NodeKernel::packet_leaf`]: ray by ray, the single-ray tests.
///
/// # Safety
/// The CPU must support `K`'s instruction set.
#[inline(always)]
pub(crate) unsafe fn packet_leaf_scalar<K: NodeKernel>(
    rays: &mut PacketRays,
    open: &mut u64,
    occlusion: bool,
    bvh: &WideBvh,
    bounds: &Bounds,
    first_block: u32,
    blocks: u32,
) {
    let mut rest = *open;
    while rest != 0 {
        let i = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        if rays.box_ray(i).enter(bounds, rays.box_limit[i]).is_none() {
            continue;
        }
        // SAFETY: the caller guarantees `K`'s instruction set.
        let triangle_ray = &unsafe { prepare_triangle_ray::<K>(&rays.triangle_ray(i)) };
        if occlusion {
            // SAFETY: the caller guarantees `K`'s instruction set.
            let t_max = rays.triangle_limit[i];
            if unsafe { leaf_occluded::<K>(bvh, first_block, blocks, triangle_ray, t_max) } {
                *open &= !(1 << i);
            }
        } else {
            let mut closest = Closest {
                best: rays.best(i),
                triangle_limit: rays.triangle_limit[i],
                box_limit: rays.box_limit[i],
            };
            // SAFETY: the caller guarantees `K`'s instruction set.
            unsafe { closest.leaf::<K>(bvh, first_block, blocks, triangle_ray) };
            if let Some(h) = closest.best {
                rays.offer(i, h.t, h.triangle, h.b1, h.b2);
            }
        }
    }
}

/// What the rays of a group share: their direction signs and the watertight test's
/// `kx, ky, kz`.
type Shared = ([bool; 3], [usize; 3]);

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
    fn new() -> Chunk {
        Chunk {
            lanes: PacketRays::new(),
            groups: [0; 24],
            present: 0,
            shared: [([false; 3], [0, 1, 2]); 24],
            alone: 0,
            gathered: None,
        }
    }

    /// Prepares `rays` (at most [`PACKET`]).
    #[inline(always)]
    fn prepare(&mut self, rays: &[Ray]) {
        self.groups = [0; 24];
        self.present = 0;
        self.alone = 0;
        let groups = packet_setup::fill(&mut self.lanes, rays);
        for (i, &group) in groups[..rays.len()].iter().enumerate() {
            if group == packet_setup::ALONE {
                self.alone |= 1 << i;
            } else {
                self.groups[group as usize] |= 1 << i;
                self.present |= 1 << group;
            }
        }
        for group in bits(self.present as u64) {
            self.shared[group] = packet_setup::shared(group as u8);
        }
    }

    /// Answers every ray of the chunk in `out`, by `Q`: alone or in packets.
    ///
    /// # Safety
    /// The CPU must support `K`'s instruction set.
    #[inline(always)]
    unsafe fn trace<K: NodeKernel, Q: Query>(
        &mut self,
        bvh: &WideBvh,
        rays: &[Ray],
        out: &mut [Q::Answer],
    ) {
        // SAFETY: the caller guarantees `K`'s instruction set.
        for i in bits(self.alone) {
            out[i] = unsafe { Q::alone::<K>(bvh, &rays[i]) };
        }
        let all = self.lanes.all();
        for group in bits(self.present as u64) {
            let members = self.groups[group];
            if members.count_ones() == 1 {
                let i = members.trailing_zeros() as usize;
                // SAFETY: the caller guarantees `K`'s instruction set.
                out[i] = unsafe { Q::alone::<K>(bvh, &rays[i]) };
                continue;
            }
            let (negative, k) = self.shared[group];
            if members == all {
                // The common case for camera and shadow rays: the whole chunk is one packet.
                self.lanes.negative = negative;
                self.lanes.k = k;
                // SAFETY: the caller guarantees `K`'s instruction set.
                let traced = unsafe { Q::packet::<K>(bvh, &mut self.lanes) };
                for (i, out) in out.iter_mut().enumerate() {
                    *out = Q::answer(&self.lanes, traced, i);
                }
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
                out[i] = Q::answer(gathered, traced, j);
            }
        }
    }
}

/// A query traced in packets: closest hit or occlusion. (A trait rather than closures, so that
/// everything inlines into the instruction set's entry point.)
trait Query {
    type Answer;
    /// # Safety
    /// The CPU must support `K`'s instruction set (for this whole trait).
    unsafe fn alone<K: NodeKernel>(bvh: &WideBvh, ray: &Ray) -> Self::Answer;
    /// Traces a packet of at least two rays; returns what [`answer`](Self::answer) needs.
    unsafe fn packet<K: NodeKernel>(bvh: &WideBvh, rays: &mut PacketRays) -> u64;
    /// The answer of lane `j` of a traced packet.
    fn answer(rays: &PacketRays, traced: u64, j: usize) -> Self::Answer;
}

/// [`closest_hits`].
struct ClosestHits;

impl Query for ClosestHits {
    type Answer = Option<Hit>;

    #[inline(always)]
    unsafe fn alone<K: NodeKernel>(bvh: &WideBvh, ray: &Ray) -> Option<Hit> {
        // SAFETY: the caller's guarantee.
        unsafe { closest_hit::<K>(bvh, ray) }
    }

    #[inline(always)]
    unsafe fn packet<K: NodeKernel>(bvh: &WideBvh, rays: &mut PacketRays) -> u64 {
        // SAFETY: the caller's guarantee.
        unsafe { closest_packet::<K>(bvh, rays) };
        0
    }

    #[inline(always)]
    fn answer(rays: &PacketRays, _: u64, j: usize) -> Option<Hit> {
        rays.best(j)
    }
}

/// [`occluded_each`].
struct OccludedEach;

impl Query for OccludedEach {
    type Answer = bool;

    #[inline(always)]
    unsafe fn alone<K: NodeKernel>(bvh: &WideBvh, ray: &Ray) -> bool {
        // SAFETY: the caller's guarantee.
        unsafe { occluded::<K>(bvh, ray) }
    }

    /// The rays still open: not occluded.
    #[inline(always)]
    unsafe fn packet<K: NodeKernel>(bvh: &WideBvh, rays: &mut PacketRays) -> u64 {
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
pub(crate) unsafe fn closest_hits<K: NodeKernel>(
    bvh: &WideBvh,
    rays: &[Ray],
    out: &mut [Option<Hit>],
) {
    assert_eq!(rays.len(), out.len(), "one answer per ray");
    let mut chunk = Chunk::new();
    for (rays, out) in rays.chunks(PACKET).zip(out.chunks_mut(PACKET)) {
        chunk.prepare(rays);
        // SAFETY: the caller guarantees `K`'s instruction set.
        unsafe { chunk.trace::<K, ClosestHits>(bvh, rays, out) };
    }
}

/// Traces a packet of at least two rays to their closest hits.
///
/// # Safety
/// The CPU must support `K`'s instruction set.
#[inline(always)]
unsafe fn closest_packet<K: NodeKernel>(bvh: &WideBvh, rays: &mut PacketRays) {
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
                Child::Leaf { first_block, blocks } => {
                    let bounds = bvh.nodes[(place / 8) as usize].bounds((place % 8) as usize);
                    let mut open = all;
                    // SAFETY: the caller guarantees `K`'s instruction set.
                    unsafe {
                        K::packet_leaf(rays, &mut open, false, bvh, &bounds, first_block, blocks)
                    };
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
pub(crate) unsafe fn occluded_each<K: NodeKernel>(bvh: &WideBvh, rays: &[Ray], out: &mut [bool]) {
    assert_eq!(rays.len(), out.len(), "one answer per ray");
    let mut chunk = Chunk::new();
    for (rays, out) in rays.chunks(PACKET).zip(out.chunks_mut(PACKET)) {
        chunk.prepare(rays);
        // SAFETY: the caller guarantees `K`'s instruction set.
        unsafe { chunk.trace::<K, OccludedEach>(bvh, rays, out) };
    }
}

/// Traces a packet of at least two rays for occlusion; returns the mask of rays not occluded.
///
/// # Safety
/// The CPU must support `K`'s instruction set.
#[inline(always)]
unsafe fn occluded_packet<K: NodeKernel>(bvh: &WideBvh, rays: &mut PacketRays) -> u64 {
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
                Child::Leaf { first_block, blocks } => {
                    let before = open;
                    // SAFETY: the caller guarantees `K`'s instruction set.
                    unsafe {
                        K::packet_leaf(
                            rays,
                            &mut open,
                            true,
                            bvh,
                            &node.bounds(k),
                            first_block,
                            blocks,
                        )
                    };
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
