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
use super::kernels::NodeKernel;
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
#[repr(C, align(32))]
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
}

impl PacketRays {
    /// An empty packet, to be [`fill`](Self::fill)ed.
    fn new() -> PacketRays {
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
        }
    }

    /// Makes the packet of `members` of `rays` (at least one; all of one octant and dominant
    /// axis, and able to join a packet).
    #[inline(always)]
    fn fill(&mut self, rays: &[Ray], members: &[u8]) {
        self.len = members.len();
        for (i, &m) in members.iter().enumerate() {
            let ray = &rays[m as usize];
            let box_ray = RayBoxTest::new(ray);
            let triangle_ray = WatertightRay::new(ray);
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
            if i == 0 {
                self.negative = box_ray.negative;
                self.k = [triangle_ray.kx, triangle_ray.ky, triangle_ray.kz];
            }
        }
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

    /// The greatest box limit of the rays in `open`: the packet's.
    #[inline(always)]
    fn limit(&self, open: u64) -> f32 {
        let mut limit = f32::NEG_INFINITY;
        for (i, &l) in self.box_limit[..self.len].iter().enumerate() {
            if open & (1 << i) != 0 {
                limit = limit.max(l);
            }
        }
        limit
    }

    /// The packet's frustum: what [`Frustum::of`] gives for its rays, computed from the lanes
    /// (the rays were checked by [`Frustum::can_join`] and share their octant and dominant axis).
    #[inline(always)]
    fn frustum(&self) -> Frustum {
        let n = self.len;
        let mut pad_axes = [false; 3];
        pad_axes[self.k[2]] = true;
        Frustum {
            origin_lo: Vec3::from_array([0, 1, 2].map(|a| lowest(&self.origin[a][..n]))),
            origin_hi: Vec3::from_array([0, 1, 2].map(|a| highest(&self.origin[a][..n]))),
            inv_lo: Vec3::from_array([0, 1, 2].map(|a| lowest(&self.inv_direction[a][..n]))),
            inv_hi: Vec3::from_array([0, 1, 2].map(|a| highest(&self.inv_direction[a][..n]))),
            negative: self.negative,
            t_min: lowest(&self.box_t_min[..n]),
            pad_axes,
        }
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
        let triangle_ray = &rays.triangle_ray(i);
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

/// The rays of a chunk grouped by direction octant and dominant axis; rays that cannot join a
/// packet are left out.
struct Groups {
    members: [[u8; PACKET]; 24],
    counts: [usize; 24],
}

impl Groups {
    /// Groups `rays` (at most [`PACKET`]); calls `alone(i)` for each ray that must be traced
    /// alone.
    #[inline(always)]
    fn of(rays: &[Ray], mut alone: impl FnMut(usize)) -> Groups {
        let mut groups = Groups { members: [[0; PACKET]; 24], counts: [0; 24] };
        for (i, ray) in rays.iter().enumerate() {
            let box_ray = RayBoxTest::new(ray);
            if !can_hit(ray) || !Frustum::can_join(&box_ray) {
                alone(i);
                continue;
            }
            let n = box_ray.negative;
            let key = (n[0] as usize | (n[1] as usize) << 1 | (n[2] as usize) << 2) * 3
                + box_ray.dominant_axis;
            groups.members[key][groups.counts[key]] = i as u8;
            groups.counts[key] += 1;
        }
        groups
    }

    /// The non-empty groups.
    fn each(&self) -> impl Iterator<Item = &[u8]> {
        (0..24).map(|g| &self.members[g][..self.counts[g]]).filter(|m| !m.is_empty())
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
    let mut packet = PacketRays::new();
    for (rays, out) in rays.chunks(PACKET).zip(out.chunks_mut(PACKET)) {
        // SAFETY (all three): the caller guarantees `K`'s instruction set.
        let groups = Groups::of(rays, |i| out[i] = unsafe { closest_hit::<K>(bvh, &rays[i]) });
        for members in groups.each() {
            if let [single] = members {
                let i = *single as usize;
                out[i] = unsafe { closest_hit::<K>(bvh, &rays[i]) };
            } else {
                packet.fill(rays, members);
                unsafe { closest_packet::<K>(bvh, &mut packet) };
                for (i, &m) in members.iter().enumerate() {
                    out[m as usize] = packet.best(i);
                }
            }
        }
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
    let mut limit = rays.limit(all);
    // SAFETY: the caller guarantees `K`'s instruction set.
    let frustum = unsafe { K::prepare_frustum(&frustum) };

    let mut stack = Stack::<Entry>::new();
    let mut top = 0;
    let mut node = 0u32;
    loop {
        // SAFETY: the caller guarantees `K`'s instruction set.
        let (mut mask, near) =
            unsafe { K::enter_frustum(&bvh.nodes[node as usize], &frustum, limit) };
        let children = &bvh.nodes[node as usize].children;
        if mask.count_ones() == 1 {
            if let Child::Node(index) = decode(children[mask.trailing_zeros() as usize]) {
                node = index;
                continue;
            }
        }
        // Nearest entry on top, as in single-ray traversal.
        let first = top;
        while mask != 0 {
            let k = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            stack
                .push_sorted(&mut top, first, (children[k], near[k], 8 * node + k as u32), |e| e.1);
        }
        loop {
            if top == 0 {
                return;
            }
            top -= 1;
            let (child, near, place) = stack.get(top);
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
                    limit = rays.limit(all);
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
    let mut packet = PacketRays::new();
    for (rays, out) in rays.chunks(PACKET).zip(out.chunks_mut(PACKET)) {
        // SAFETY (all three): the caller guarantees `K`'s instruction set.
        let groups = Groups::of(rays, |i| out[i] = unsafe { occluded::<K>(bvh, &rays[i]) });
        for members in groups.each() {
            if let [single] = members {
                let i = *single as usize;
                out[i] = unsafe { occluded::<K>(bvh, &rays[i]) };
            } else {
                packet.fill(rays, members);
                let open = unsafe { occluded_packet::<K>(bvh, &mut packet) };
                for (i, &m) in members.iter().enumerate() {
                    out[m as usize] = open & (1 << i) == 0;
                }
            }
        }
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
    let mut limit = rays.limit(open);
    // SAFETY: the caller guarantees `K`'s instruction set.
    let frustum = unsafe { K::prepare_frustum(&frustum) };

    let mut stack = Stack::<u32>::new();
    let mut top = 0;
    stack.set(top, 0);
    top += 1;
    while top > 0 {
        top -= 1;
        let node = &bvh.nodes[stack.get(top) as usize];
        // SAFETY: the caller guarantees `K`'s instruction set.
        let (mut mask, _) = unsafe { K::enter_frustum(node, &frustum, limit) };
        while mask != 0 {
            let k = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            match decode(node.children[k]) {
                Child::Node(index) => {
                    stack.set(top, index);
                    top += 1;
                }
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
                        limit = rays.limit(open);
                    }
                }
                Child::Empty => {}
            }
        }
    }
    open
}
