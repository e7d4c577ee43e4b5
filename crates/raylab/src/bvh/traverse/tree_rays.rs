//! Incoherent rays through the tree in lanes: a path tracer's bounces and shadow rays, `W` at a
//! time (sixteen with AVX-512, eight with AVX2), as Embree's "hybrid" packets trace them
//! (Benthin, Wald, Woop, Ernst and Áfra, "Combining Single and Packet-Ray Tracing for Arbitrary
//! Ray Distributions on the Intel MIC Architecture", IEEE TVCG 18(9), 2012).
//!
//! # How
//! The rays of a group sit in the lanes of a register, each with its own direction: nothing is
//! assumed of their coherence, unlike the packets of `packet/`, whose rays share an octant and
//! are bounded by a frustum (which an environment light's shadow rays, pointing everywhere,
//! make as wide as the scene: shadow rays as such packets made the materials scene's render
//! twice as slow). Traversal keeps a stack of (child, the lanes that enter it, where each
//! enters):
//! - a node's eight boxes are tested one at a time against every open lane, each lane by
//!   [`RayBoxTest::enter_with_margin`](crate::bvh::RayBoxTest::enter_with_margin)'s own
//!   operations (its near and far planes picked by its direction's signs, its margin from the
//!   root box), and each interior child is pushed with the lanes that enter it (a leaf too
//!   for the closest hit; for occlusion a leaf is tested at once);
//! - a leaf's record puts each of its distinct corners in every lane's watertight frame once
//!   (`flat_rays.rs`'s permutation per lane) and tests its triangles sixteen rays per
//!   instruction ([`watertight_sheared_scaled`]);
//! - a node that at most [`NODE_SWITCH`] open lanes enter is left to them one by one (the
//!   single-ray traversal of its subtree, each lane's set-up made once per group), and so is a
//!   leaf that at most [`LEAF_SWITCH`] enter (the single-ray record kernel): below that, a
//!   register's work is mostly for lanes that are not there.
//!
//! A lane leaves the search where it is done: for occlusion at its first blocker, for the
//! closest hit at entries beyond its best hit so far (each entry keeps its lanes' entry
//! distances). Children are pushed in the node's order: sorting them by their nearest lane's
//! entry is slower.
//!
//! # The answers are the single-ray queries'
//! Every box and triangle decision of a lane is its ray's own, by the same operations in the
//! same order. The order of the search differs (the single ray goes nearest child first, the
//! lanes in the node's order), and so do the limits at a given box, but the answer does not
//! depend on either: a box that holds a hit at `t` is entered whenever the limit is at least
//! `t·FAR_SCALE`, which each lane's limit is until it has found that hit or a better one, as
//! the single ray's is (the property the single ray's agreement with brute force rests on).
//! A hit is kept as [`Closest::leaf`] keeps it ([`Hit::precedes`]: nearer, or as near with a
//! lower index), and a triangle's test accepts it for any limit above its `t`. The scalar twin
//! is the single-ray traversal, ray by ray ([`TreeRaysKernel`]'s default);
//! `bvh::tests::tree_rays_in_lanes_give_the_single_ray_answers` compares them bit for bit, and
//! `bvh::tests::the_lanes_box_test_is_each_rays_own` the box test lane by lane.
//!
//! AVX2 and AVX-512 trace groups in lanes; SSE2's four lanes do not pay, so it keeps single
//! rays. (BENCHMARKS.md has the nanoseconds per ray, single and in lanes, on a render's
//! recorded rays: `cargo bench -p raylab --bench path_rays -- SCENE 256 4 --isas`.)

use glam::Vec3;

use super::flat_rays::{RayRegisters, RayRows, blocked_rarely, corners_of};
use super::{
    Closest, Kernel, Prepared, closest_in_prepared, leaf_occluded as leaf_occluded_single,
    occluded_prepared,
};
use super::{STACK_SIZE, TreeRaysKernel};
use crate::accel::Hit;
use crate::bvh::bounds::FAR_SCALE;
use crate::bvh::bounds::MARGIN_SCALE;
use crate::bvh::isa::{Avx2, Avx512, Sse};
use crate::bvh::leaf::{RECORD_VERTICES, Record};
use crate::bvh::node::{Child, EMPTY, WIDTH, WideBvh, WideNode, decode};
use crate::bvh::simd::{Lanes, watertight_sheared_scaled};
use crate::float::next_float_up;
use crate::ray::Ray;
use crate::triangle::WatertightRay;
use std::arch::x86_64::{__m256, __m512};

/// A node that at most this many of a group's open rays enter is left to them one by one
/// (the single-ray traversal of its subtree). Whole renders hardly depend on it between 6 and
/// 10 (with [`LEAF_SWITCH`] 4 to 6); the materials scene's bounces want 5 or more.
const NODE_SWITCH: u32 = 6;
/// A leaf that at most this many open rays enter is tested ray by ray with the single-ray
/// record kernel (the same answers): a record's frames cost sixteen operations a vertex for
/// the whole register, worth it only when enough lanes share them.
const LEAF_SWITCH: u32 = 4;

/// The lanes' slab tests: each lane's ray as [`RayBoxTest`] and its margin prepare it.
struct BoxLanes<V: Lanes> {
    origin: [V; 3],
    inv: [V; 3],
    negative: [V::Mask; 3],
    t_min: V,
    margin: V,
}

impl<V: Lanes> BoxLanes<V> {
    /// # Safety
    /// The CPU must support `V`'s instruction set.
    #[inline(always)]
    unsafe fn new(rows: &RayRows, registers: &RayRegisters<V>, bvh: &WideBvh) -> Self {
        // SAFETY: the caller's guarantee; every row holds `MAX_LANES` floats.
        unsafe {
            let o = [
                V::loadu(rows.origin[0].as_ptr()),
                V::loadu(rows.origin[1].as_ptr()),
                V::loadu(rows.origin[2].as_ptr()),
            ];
            let one = V::splat(1.0);
            let inv = [
                one.div(V::loadu(rows.direction[0].as_ptr())),
                one.div(V::loadu(rows.direction[1].as_ptr())),
                one.div(V::loadu(rows.direction[2].as_ptr())),
            ];
            let zero = V::splat(0.0);
            // `RayBoxTest::margin`: `1/d` on the dominant axis is the watertight `shear_z`.
            let root = &bvh.root;
            let margin = if root.is_empty() {
                zero
            } else {
                // No closure: it would not inherit the caller's target features.
                let mut reach = [zero; 3];
                for axis in 0..3 {
                    let lo = V::splat(root.min[axis]).sub(o[axis]).abs();
                    let hi = V::splat(root.max[axis]).sub(o[axis]).abs();
                    reach[axis] = lo.max(hi);
                }
                let l = reach[0].add(reach[1]).add(reach[2]);
                l.mul(registers.ray.shear_z.abs()).mul(V::splat(MARGIN_SCALE))
            };
            BoxLanes {
                origin: o,
                inv,
                negative: [inv[0].lt(zero), inv[1].lt(zero), inv[2].lt(zero)],
                t_min: V::loadu(rows.t_min.as_ptr()).max(zero),
                margin,
            }
        }
    }

    /// The lanes that enter child `k`'s box within `[t_min, limit]`, as
    /// [`RayBoxTest::enter_with_margin`](crate::bvh::RayBoxTest::enter_with_margin) decides
    /// for each, and each lane's entry distance (less the margin).
    ///
    /// # Safety
    /// The CPU must support `V`'s instruction set.
    #[inline(always)]
    unsafe fn enter_near(&self, node: &WideNode, k: usize, limit: V) -> (u32, V) {
        // SAFETY: the caller's guarantee.
        unsafe {
            let mut near = self.t_min;
            let mut far = limit;
            for axis in 0..3 {
                let lo = V::splat(node.planes[axis][k]);
                let hi = V::splat(node.planes[3 + axis][k]);
                let near_plane = V::select(self.negative[axis], hi, lo);
                let far_plane = V::select(self.negative[axis], lo, hi);
                near = near_plane.sub(self.origin[axis]).mul(self.inv[axis]).max(near);
                far = far_plane.sub(self.origin[axis]).mul(self.inv[axis]).min(far);
            }
            let near = near.sub(self.margin);
            (near.le_mask(far.add(self.margin)), near)
        }
    }

    /// The lanes that enter child `k`'s box within `[t_min, limit]`, as
    /// [`RayBoxTest::enter_with_margin`](crate::bvh::RayBoxTest::enter_with_margin) decides
    /// for each (the entry distances of [`enter_near`](Self::enter_near) left unused).
    ///
    /// # Safety
    /// The CPU must support `V`'s instruction set.
    #[inline(always)]
    unsafe fn enter(&self, node: &WideNode, k: usize, limit: V) -> u32 {
        // SAFETY: the caller's guarantee.
        unsafe { self.enter_near(node, k, limit).0 }
    }
}

/// Whether each ray is blocked, `W` rays to a register `V`: exactly the single-ray answers.
///
/// # Safety
/// The CPU must support `V`'s and `K`'s instruction sets, and `V` must hold `W` floats, at
/// most sixteen (the rows of `RayRows`).
#[inline(always)]
pub(crate) unsafe fn occluded_lanes<V: Lanes, K: Kernel, const W: usize>(
    bvh: &WideBvh,
    rays: &[Ray],
    occluded: &mut [bool],
) {
    assert_eq!(rays.len(), occluded.len(), "one answer per ray");
    // The nodes still to visit and the lanes that enter each, on the heap (made once a batch).
    let mut stack: Vec<(u32, u32)> = Vec::with_capacity(STACK_SIZE);
    let mut frame = new_frame::<V>();
    for (rays, occluded) in rays.chunks(W).zip(occluded.chunks_mut(W)) {
        let rows = RayRows::new(rays);
        let mut blocked = 0u32;
        // SAFETY: the caller's guarantee.
        unsafe {
            let registers = RayRegisters::<V>::new(&rows);
            let boxes = BoxLanes::<V>::new(&rows, &registers, bvh);
            let limit = registers.ray.t_max;
            let mut singles = Singles::<K>::new();
            stack.clear();
            if rows.live != 0 {
                stack.push((0, rows.live));
            }
            while let Some((index, mask)) = stack.pop() {
                let open = mask & !blocked;
                if open == 0 {
                    continue;
                }
                if open.count_ones() <= NODE_SWITCH {
                    let mut rest = open;
                    while rest != 0 {
                        let lane = rest.trailing_zeros() as usize;
                        rest &= rest - 1;
                        let prepared = singles.get(bvh, rays, lane);
                        if occluded_prepared::<K, ()>(bvh, prepared, index, &mut ()) {
                            blocked |= 1 << lane;
                        }
                    }
                    continue;
                }
                let node = &bvh.nodes[index as usize];
                for k in 0..WIDTH {
                    let child = node.children[k];
                    if child == EMPTY {
                        continue;
                    }
                    let entered = boxes.enter(node, k, limit) & open & !blocked;
                    if entered == 0 {
                        continue;
                    }
                    match decode(child) {
                        Child::Node(i) => {
                            stack.push((i, entered));
                        }
                        Child::Leaf(offset) if entered.count_ones() <= LEAF_SWITCH => {
                            let mut rest = entered;
                            while rest != 0 {
                                let lane = rest.trailing_zeros() as usize;
                                rest &= rest - 1;
                                let p = singles.get(bvh, rays, lane);
                                if leaf_occluded_single::<K>(bvh, offset, &p.triangle_ray, p.t_max)
                                {
                                    blocked |= 1 << lane;
                                }
                            }
                        }
                        Child::Leaf(offset) => {
                            blocked |=
                                leaf_occluded(bvh, offset, &registers, rays, entered, &mut frame);
                        }
                        Child::Empty => {}
                    }
                }
            }
        }
        for (lane, occluded) in occluded.iter_mut().enumerate() {
            *occluded = blocked & (1 << lane) != 0;
        }
    }
}

/// Each lane's single-ray set-up, made when first needed.
struct Singles<K: Kernel> {
    prepared: [std::mem::MaybeUninit<Prepared<K>>; 16],
    made: u32,
}

impl<K: Kernel> Singles<K> {
    #[inline(always)]
    fn new() -> Self {
        Singles { prepared: [const { std::mem::MaybeUninit::uninit() }; 16], made: 0 }
    }

    /// Lane `lane`'s ray prepared; the lane must be live ([`RayRows`]: its ray can hit).
    ///
    /// # Safety
    /// The CPU must support `K`'s instruction set.
    #[inline(always)]
    unsafe fn get(&mut self, bvh: &WideBvh, rays: &[Ray], lane: usize) -> &Prepared<K> {
        if self.made & (1 << lane) == 0 {
            // SAFETY: the caller's guarantee.
            let prepared = unsafe { Prepared::<K>::new(bvh, &rays[lane]) };
            self.prepared[lane].write(prepared.expect("a live lane's ray can hit"));
            self.made |= 1 << lane;
        }
        // SAFETY: written above or before (bit `lane` of `made`).
        unsafe { self.prepared[lane].assume_init_ref() }
    }
}

/// A leaf record's corners in the lanes' ray frames: per corner its `kx`, `ky`, `kz`
/// coordinates and `kz` scaled by `shear_z` (`flat_rays.rs`), made once a batch (zeroing it
/// per leaf cost 4 KB of stores with AVX-512).
type Frame<V> = [[V; 4]; RECORD_VERTICES];

/// A frame for [`leaf_occluded`] and [`leaf_closest`] to fill.
#[inline(always)]
fn new_frame<V: Lanes>() -> Frame<V> {
    // SAFETY: any bits are a valid register of floats.
    [[unsafe { std::mem::zeroed::<V>() }; 4]; RECORD_VERTICES]
}

/// Each of `record`'s corners in every lane's ray frame (the first
/// [`vertices`](crate::bvh::leaf::Record::vertices) slots of `frame`).
///
/// # Safety
/// The CPU must support `V`'s instruction set.
#[inline(always)]
unsafe fn fill_frame<V: Lanes>(registers: &RayRegisters<V>, record: &Record, frame: &mut Frame<V>) {
    let [x, y, z] = record.rows();
    for (j, slot) in frame.iter_mut().enumerate().take(record.vertices()) {
        // SAFETY: the caller's guarantee.
        unsafe {
            let [a, b, c] = registers.corner(Vec3::new(x[j], y[j], z[j]));
            *slot = [a, b, c, registers.ray.shear_z.mul(c)];
        }
    }
}

/// The lanes of `open` that a triangle of the leaf at `offset` blocks.
///
/// # Safety
/// The CPU must support `V`'s instruction set.
#[inline(always)]
unsafe fn leaf_occluded<V: Lanes>(
    bvh: &WideBvh,
    offset: u32,
    registers: &RayRegisters<V>,
    rays: &[Ray],
    open: u32,
    frame: &mut Frame<V>,
) -> u32 {
    let mut blocked = 0;
    for record in bvh.leaves.leaf(offset) {
        let open = open & !blocked;
        if open == 0 {
            break;
        }
        // SAFETY: the caller's guarantee.
        unsafe { fill_frame(registers, &record, frame) };
        let [ca, cb, cc] = record.corner_rows();
        for t in 0..record.triangles() {
            let open = open & !blocked;
            if open == 0 {
                break;
            }
            // SAFETY: the corner indices are below the record's vertex count, whose frame
            // slots were just written; the caller's guarantee of the instruction set.
            unsafe {
                let corners = [u32::from(ca[t]), u32::from(cb[t]), u32::from(cc[t])];
                let (sheared, scaled) = corners_of(frame, corners);
                let decided =
                    watertight_sheared_scaled::<V, true>(&sheared, scaled, &registers.ray, open);
                blocked |= decided.hits;
                let mut undecided = decided.undecided;
                while undecided != 0 {
                    let lane = undecided.trailing_zeros() as usize;
                    undecided &= undecided - 1;
                    if blocked_rarely(&rays[lane], record.triangle(t)) {
                        blocked |= 1 << lane;
                    }
                }
            }
        }
    }
    blocked
}

/// Each lane's search for its closest hit, as [`Closest`] keeps a single ray's.
struct LaneClosest {
    closest: [Closest; 16],
    /// `closest[lane].triangle_limit` and `box_limit`, as rows for the registers.
    triangle_limit: [f32; 16],
    box_limit: [f32; 16],
}

impl LaneClosest {
    #[inline(always)]
    fn new(rays: &[Ray], live: u32) -> Self {
        let mut state = LaneClosest {
            closest: [Closest { best: None, triangle_limit: f32::NAN, box_limit: f32::NAN }; 16],
            triangle_limit: [f32::NAN; 16],
            box_limit: [f32::NAN; 16],
        };
        for (lane, ray) in rays.iter().enumerate() {
            if live & (1 << lane) != 0 {
                state.set(lane, Closest::new(ray));
            }
        }
        state
    }

    #[inline(always)]
    fn set(&mut self, lane: usize, closest: Closest) {
        self.closest[lane] = closest;
        self.triangle_limit[lane] = closest.triangle_limit;
        self.box_limit[lane] = closest.box_limit;
    }

    /// Offers `hit` to lane `lane`, as [`Closest::leaf`] does.
    #[inline(always)]
    fn offer(&mut self, lane: usize, hit: Hit) {
        let closest = &mut self.closest[lane];
        if closest.best.is_none_or(|best| hit.precedes(&best)) {
            closest.best = Some(hit);
            closest.triangle_limit = next_float_up(hit.t);
            closest.box_limit = hit.t * FAR_SCALE;
            self.triangle_limit[lane] = closest.triangle_limit;
            self.box_limit[lane] = closest.box_limit;
        }
    }
}

/// A node or leaf to visit, the lanes that enter it and where each enters.
#[derive(Clone, Copy)]
struct Entry<V> {
    child: u32,
    lanes: u32,
    near: V,
}

/// The closest hit of each ray, `W` rays to a register `V`: exactly the single-ray answers.
///
/// # Safety
/// The CPU must support `V`'s and `K`'s instruction sets, and `V` must hold `W` floats, at
/// most sixteen (the rows of `RayRows`).
#[inline(always)]
pub(crate) unsafe fn closest_hits_lanes<V: Lanes, K: Kernel, const W: usize>(
    bvh: &WideBvh,
    rays: &[Ray],
    hits: &mut [Option<Hit>],
) {
    assert_eq!(rays.len(), hits.len(), "one answer per ray");
    // The children still to visit, on the heap (made once a batch, not zeroed: entries of a
    // register and two words, 128 bytes with AVX-512).
    let mut stack: Vec<Entry<V>> = Vec::with_capacity(STACK_SIZE);
    let mut frame = new_frame::<V>();
    for (rays, hits) in rays.chunks(W).zip(hits.chunks_mut(W)) {
        let rows = RayRows::new(rays);
        let mut state = LaneClosest::new(rays, rows.live);
        // SAFETY: the caller's guarantee.
        unsafe {
            let registers = RayRegisters::<V>::new(&rows);
            let boxes = BoxLanes::<V>::new(&rows, &registers, bvh);
            let mut singles = Singles::<K>::new();
            stack.clear();
            if rows.live != 0 {
                stack.push(Entry { child: 0, lanes: rows.live, near: V::splat(f32::NEG_INFINITY) });
            }
            while let Some(entry) = stack.pop() {
                let box_limit = V::loadu(state.box_limit.as_ptr());
                let open = entry.lanes & entry.near.le_mask(box_limit);
                if open == 0 {
                    continue;
                }
                let few = match decode(entry.child) {
                    Child::Leaf(_) => open.count_ones() <= LEAF_SWITCH,
                    _ => open.count_ones() <= NODE_SWITCH,
                };
                if few {
                    let mut rest = open;
                    while rest != 0 {
                        let lane = rest.trailing_zeros() as usize;
                        rest &= rest - 1;
                        let p = singles.get(bvh, rays, lane);
                        let mut closest = state.closest[lane];
                        closest_in_prepared::<K, ()>(bvh, p, entry.child, &mut closest, &mut ());
                        state.set(lane, closest);
                    }
                    continue;
                }
                let index = match decode(entry.child) {
                    Child::Node(index) => index,
                    Child::Leaf(offset) => {
                        leaf_closest(bvh, offset, &registers, rays, open, &mut state, &mut frame);
                        continue;
                    }
                    Child::Empty => continue,
                };
                let node = &bvh.nodes[index as usize];
                // The children entered, in the node's order (sorting them by distance, the
                // nearest popped first, is slower).
                for k in 0..WIDTH {
                    let child = node.children[k];
                    if child == EMPTY {
                        continue;
                    }
                    let (entered, near) = boxes.enter_near(node, k, box_limit);
                    let entered = entered & open;
                    if entered != 0 {
                        stack.push(Entry { child, lanes: entered, near });
                    }
                }
            }
        }
        for (lane, hit) in hits.iter_mut().enumerate() {
            *hit = state.closest[lane].best;
        }
    }
}

/// The leaf at `offset` against the lanes of `open`, each hit offered to its lane.
///
/// # Safety
/// The CPU must support `V`'s instruction set.
#[inline(always)]
unsafe fn leaf_closest<V: Lanes>(
    bvh: &WideBvh,
    offset: u32,
    registers: &RayRegisters<V>,
    rays: &[Ray],
    open: u32,
    state: &mut LaneClosest,
    frame: &mut Frame<V>,
) {
    for record in bvh.leaves.leaf(offset) {
        // SAFETY: the caller's guarantee.
        unsafe { fill_frame(registers, &record, frame) };
        let [ca, cb, cc] = record.corner_rows();
        for t in 0..record.triangles() {
            // SAFETY: the corner indices are below the record's vertex count, whose frame
            // slots were just written; the caller's guarantee of the instruction set.
            unsafe {
                let corners = [u32::from(ca[t]), u32::from(cb[t]), u32::from(cc[t])];
                let (sheared, scaled) = corners_of(frame, corners);
                let ray = crate::bvh::simd::RayLanes {
                    t_max: V::loadu(state.triangle_limit.as_ptr()),
                    ..registers.ray
                };
                let decided = watertight_sheared_scaled::<V, true>(&sheared, scaled, &ray, open);
                let id = record.id(t);
                if decided.hits != 0 {
                    let (mut ts, mut b1, mut b2) = ([0.0f32; 16], [0.0f32; 16], [0.0f32; 16]);
                    decided.t.store(ts.as_mut_ptr());
                    decided.b1.store(b1.as_mut_ptr());
                    decided.b2.store(b2.as_mut_ptr());
                    let mut rest = decided.hits;
                    while rest != 0 {
                        let lane = rest.trailing_zeros() as usize;
                        rest &= rest - 1;
                        state.offer(
                            lane,
                            Hit { t: ts[lane], triangle: id, b1: b1[lane], b2: b2[lane] },
                        );
                    }
                }
                let mut undecided = decided.undecided;
                while undecided != 0 {
                    let lane = undecided.trailing_zeros() as usize;
                    undecided &= undecided - 1;
                    let ray = &rays[lane];
                    let [v0, v1, v2] = record.triangle(t);
                    let limit = state.triangle_limit[lane];
                    if let Some(h) = WatertightRay::new(ray).intersect(v0, v1, v2, limit) {
                        state.offer(lane, Hit { t: h.t, triangle: id, b1: h.b1, b2: h.b2 });
                    }
                }
            }
        }
    }
}

macro_rules! tree_rays_kernel {
    ($isa:ty, $register:ty, $lanes:literal) => {
        impl TreeRaysKernel for $isa {
            #[inline(always)]
            unsafe fn closest_hits(bvh: &WideBvh, rays: &[Ray], hits: &mut [Option<Hit>]) {
                // SAFETY: the caller's guarantee of the instruction set; the register holds
                // `$lanes` floats.
                unsafe { closest_hits_lanes::<$register, $isa, $lanes>(bvh, rays, hits) }
            }
            #[inline(always)]
            unsafe fn occluded_each(bvh: &WideBvh, rays: &[Ray], occluded: &mut [bool]) {
                // SAFETY: as above.
                unsafe { occluded_lanes::<$register, $isa, $lanes>(bvh, rays, occluded) }
            }
        }
    };
}
impl TreeRaysKernel for Sse {}
tree_rays_kernel!(Avx2, __m256, 8);
tree_rays_kernel!(Avx512, __m512, 16);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::RayBoxTest;
    use crate::bvh::bounds::Bounds;
    use crate::bvh::leaf::Leaves;
    use crate::bvh::tests::{hostile_cases, node_root};

    /// [`BoxLanes::enter_near`] with each register this CPU has: every lane's mask bit and
    /// entry distance are its ray's own [`RayBoxTest::enter_with_margin`], bit for bit (but
    /// for the sign of a zero entry), with
    /// the margin of a root box around the node (and none for an empty root): boxes that share
    /// the origin's planes, flat boxes, unused slots, ±0 and tiny direction components, `t_min`
    /// and finite limits (`bvh::tests::hostile_cases`), sixteen rays to a group.
    #[test]
    fn the_lanes_box_test_is_each_rays_own() {
        let cases = hostile_cases();
        let mut checked = [0usize; 2];
        let mut entered = 0;
        for (c, group) in cases.chunks(16).enumerate() {
            let (node, _, _) = &group[0];
            let root = if c % 5 == 4 { Bounds::EMPTY } else { node_root(node) };
            let bvh = WideBvh { nodes: Vec::new(), leaves: Leaves::default(), root };
            let rays: Vec<Ray> = group.iter().map(|(_, ray, _)| *ray).collect();
            let mut limits = [f32::NAN; 16];
            for (lane, (_, _, limit)) in group.iter().enumerate() {
                limits[lane] = *limit;
            }
            for k in 0..8 {
                let mut expected = (0u32, [0.0f32; 16]);
                for (lane, ray) in rays.iter().enumerate() {
                    if !crate::bvh::traverse::can_hit(ray) {
                        continue;
                    }
                    let test = RayBoxTest::new(ray);
                    let margin = test.margin(&bvh.root);
                    if let Some(near) =
                        test.enter_with_margin(&node.bounds(k), limits[lane], margin)
                    {
                        expected.0 |= 1 << lane;
                        expected.1[lane] = near;
                        entered += 1;
                    }
                }
                let rows = RayRows::new(&rays);
                if std::arch::is_x86_feature_detected!("avx512f")
                    && std::arch::is_x86_feature_detected!("avx512vl")
                {
                    checked[0] += 1;
                    // SAFETY: checked just above.
                    let got = unsafe { lanes_avx512(&rows, &bvh, node, k, &limits) };
                    compare(got, expected, rows.live, "AVX-512", c, k);
                }
                if std::arch::is_x86_feature_detected!("avx2") {
                    checked[1] += 1;
                    // SAFETY: checked just above.
                    let got = unsafe { lanes_avx2(&rows, &bvh, node, k, &limits) };
                    compare(got, expected, rows.live & 0xFF, "AVX2", c, k);
                }
            }
        }
        assert!(entered > 1000, "{entered} boxes entered");
        if checked[0] == 0 {
            eprintln!("note: this CPU lacks AVX-512: its lanes' box test is not tested here");
        }
        if checked[1] == 0 {
            eprintln!("note: this CPU lacks AVX2: its lanes' box test is not tested here");
        }
    }

    fn compare(
        (mask, near): (u32, [f32; 16]),
        expected: (u32, [f32; 16]),
        live: u32,
        isa: &str,
        group: usize,
        k: usize,
    ) {
        assert_eq!(mask & live, expected.0 & live, "{isa}: group {group}, child {k}");
        for (lane, (&a, &b)) in near.iter().zip(&expected.1).enumerate() {
            if mask & live & (1 << lane) != 0 {
                // Bit for bit, but for the sign of a zero entry (`f32::max` of ±0 may return
                // either; only comparisons read the entry, and they cannot tell).
                assert!(
                    a.to_bits() == b.to_bits() || (a == 0.0 && b == 0.0),
                    "{isa}: group {group}, child {k}, lane {lane}: {a:e} against {b:e}"
                );
            }
        }
    }

    macro_rules! lanes_with {
        ($name:ident, $register:ty, $features:literal) => {
            /// The lanes' box test of child `k`, mask and entry distances.
            ///
            /// # Safety
            /// The CPU must support the register's instruction set.
            #[target_feature(enable = $features)]
            unsafe fn $name(
                rows: &RayRows,
                bvh: &WideBvh,
                node: &WideNode,
                k: usize,
                limits: &[f32; 16],
            ) -> (u32, [f32; 16]) {
                // SAFETY: the caller's guarantee; the rows hold sixteen floats.
                unsafe {
                    let registers = RayRegisters::<$register>::new(rows);
                    let boxes = BoxLanes::<$register>::new(rows, &registers, bvh);
                    let limit = <$register as Lanes>::loadu(limits.as_ptr());
                    let (mask, near) = boxes.enter_near(node, k, limit);
                    let mut out = [0.0f32; 16];
                    near.store(out.as_mut_ptr());
                    (mask, out)
                }
            }
        };
    }
    lanes_with!(lanes_avx512, __m512, "avx2,avx512f,avx512vl");
    lanes_with!(lanes_avx2, __m256, "avx2");
}
