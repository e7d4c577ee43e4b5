//! Single-ray traversal of the wide BVH: closest hit (nearest child first) and any hit.
//!
//! Both are generic over the kernels ([`Kernel`]: the node test and the leaf records' test) and
//! `#[inline(always)]`, so each instruction set gets its
//! own copy compiled with that set enabled (the tables of `bvh/queries.rs`): the
//! triangle pre-test is then vectorized for the same set too.

pub(crate) mod flat;
pub(crate) mod flat_kernel;
#[cfg(target_arch = "x86_64")]
pub(crate) mod flat_rays;
mod setup;
#[cfg(target_arch = "x86_64")]
pub(crate) mod tree_rays;

pub(crate) use setup::{Kernel, Prepared, Query, can_hit, run_prepared};

use crate::accel::Hit;
use crate::bvh::bounds::FAR_SCALE;
use crate::bvh::leaf::Leaves;
use crate::bvh::leaf::TriangleRay;
use crate::bvh::node::kernel::BoxRay;
use crate::bvh::node::{Child, EMPTY, WIDTH, WideBvh, decode};
use crate::float::next_float_up;
use crate::ray::Ray;

/// Many incoherent rays through the tree at once, per instruction set: by default one by one
/// (the single-ray traversals, the scalar twin); the vector sets put them in lanes
/// (`tree_rays.rs`).
pub(crate) trait TreeRaysKernel: Kernel {
    /// The closest hit of each ray, `hits[i]` for `rays[i]`: exactly [`closest_hit`]'s answers.
    ///
    /// # Safety
    /// The CPU must support the kernel's instruction set.
    #[inline(always)]
    unsafe fn closest_hits(bvh: &WideBvh, rays: &[Ray], hits: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), hits.len(), "one answer per ray");
        for (ray, hit) in rays.iter().zip(hits) {
            // SAFETY: the caller's guarantee.
            *hit = unsafe { closest_hit::<Self>(bvh, ray) };
        }
    }

    /// Whether each ray is occluded, `occluded[i]` for `rays[i]`: exactly [`occluded`]'s
    /// answers.
    ///
    /// # Safety
    /// The CPU must support the kernel's instruction set.
    #[inline(always)]
    unsafe fn occluded_each(bvh: &WideBvh, rays: &[Ray], out: &mut [bool]) {
        assert_eq!(rays.len(), out.len(), "one answer per ray");
        for (ray, o) in rays.iter().zip(out) {
            // SAFETY: the caller's guarantee.
            *o = unsafe { occluded::<Self>(bvh, ray) };
        }
    }
}

impl TreeRaysKernel for crate::bvh::isa::Scalar {}

/// Stack entries: the wide tree is at most ~80 levels deep (the builder bounds the binary depth),
/// and each level pushes at most seven siblings.
pub(crate) const STACK_SIZE: usize = 640;

/// A traversal stack on the call stack, not initialized: zeroing 5 KB per ray would cost about as
/// much as tracing it.
///
/// Invariant: the entries below `len` are initialized. `push` writes entry `len` before counting
/// it, `pop` and `push_sorted` only move or read entries below `len`, so reads never see an
/// uninitialized entry and no other bookkeeping is needed.
pub(crate) struct Stack<T: Copy> {
    entries: [std::mem::MaybeUninit<T>; STACK_SIZE],
    len: usize,
}

impl<T: Copy> Stack<T> {
    #[inline(always)]
    pub(super) fn new() -> Self {
        // SAFETY: an array of `MaybeUninit` needs no initialization (the pattern of the
        // `MaybeUninit` documentation); `[MaybeUninit::uninit(); N]` compiles to a memset here.
        let entries = unsafe {
            std::mem::MaybeUninit::<[std::mem::MaybeUninit<T>; STACK_SIZE]>::uninit().assume_init()
        };
        Stack { entries, len: 0 }
    }

    /// The number of entries.
    #[inline(always)]
    pub(super) fn len(&self) -> usize {
        self.len
    }

    /// Pushes `value` on top. Panics when the stack is full (the builder bounds the depth so that
    /// it never is).
    #[inline(always)]
    pub(super) fn push(&mut self, value: T) {
        self.entries[self.len] = std::mem::MaybeUninit::new(value);
        self.len += 1;
    }

    /// Removes and returns the top entry.
    #[inline(always)]
    pub(super) fn pop(&mut self) -> Option<T> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: entries below the old `len` are initialized (the invariant).
        Some(unsafe { self.entries[self.len].assume_init() })
    }

    /// Pushes `entry`, moving it down past the entries above index `first` that are nearer (by
    /// `distance`), so that the run from `first` stays sorted with the nearest on top.
    #[inline(always)]
    pub(super) fn push_sorted(&mut self, first: usize, entry: T, distance: impl Fn(T) -> f32) {
        let top = self.len;
        // Bounds-checks the write at `top` before anything moves.
        self.entries[top] = std::mem::MaybeUninit::new(entry);
        let mut i = top;
        // SAFETY: (both reads) `first <= i - 1 < top`, below `len`, so initialized.
        while i > first && distance(unsafe { self.entries[i - 1].assume_init() }) < distance(entry)
        {
            self.entries[i] = self.entries[i - 1];
            i -= 1;
        }
        self.entries[i] = std::mem::MaybeUninit::new(entry);
        self.len = top + 1;
    }
}

/// What one traversal visits, summed over the queries it is passed to
/// ([`Bvh::closest_hit_counted`](super::Bvh::closest_hit_counted)): the cost of a ray in the
/// tree's own units, independent of the machine. Counted with the portable kernel's plain box
/// test; the AVX2 and AVX-512 kernels' fused test enters a fraction of a percent more boxes,
/// those at its margins' edge.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraversalStats {
    /// Queries counted.
    pub rays: u64,
    /// Wide nodes whose eight boxes were tested.
    pub nodes: u64,
    /// Leaves entered.
    pub leaves: u64,
    /// Records in the leaves entered (occlusion may stop inside a leaf: then its remaining
    /// records are counted without being tested). A record holds up to 8 triangles over up to
    /// 16 vertices (`bvh/leaf`).
    pub records: u64,
}

impl TraversalStats {
    /// Per query: nodes, leaves and records.
    pub fn per_ray(&self) -> [f64; 3] {
        let rays = self.rays.max(1) as f64;
        [self.nodes as f64 / rays, self.leaves as f64 / rays, self.records as f64 / rays]
    }
}

impl std::ops::Add for TraversalStats {
    type Output = TraversalStats;

    /// The counts of two sets of queries together.
    fn add(self, o: TraversalStats) -> TraversalStats {
        TraversalStats {
            rays: self.rays + o.rays,
            nodes: self.nodes + o.nodes,
            leaves: self.leaves + o.leaves,
            records: self.records + o.records,
        }
    }
}

/// What a traversal counts as it goes; `()` counts nothing and compiles away.
pub(crate) trait Counter {
    /// A node's boxes are tested.
    #[inline(always)]
    fn node(&mut self) {}
    /// The leaf at `offset` is entered.
    #[inline(always)]
    fn leaf(&mut self, _leaves: &Leaves, _offset: u32) {}
}

impl Counter for () {}

impl Counter for TraversalStats {
    #[inline(always)]
    fn node(&mut self) {
        self.nodes += 1;
    }
    #[inline(always)]
    fn leaf(&mut self, leaves: &Leaves, offset: u32) {
        self.leaves += 1;
        self.records += leaves.leaf(offset).count() as u64;
    }
}

/// The search state of one ray's closest hit.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Closest {
    pub best: Option<Hit>,
    /// Triangles are accepted for `t < triangle_limit`: the ray's end, then just past the best
    /// hit so that an equal `t` with a lower index can still win.
    pub triangle_limit: f32,
    /// Boxes are entered up to the best hit, conservatively: a box whose computed entry rounds
    /// just past a hit inside it must still be visited.
    pub box_limit: f32,
}

impl Closest {
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        Closest { best: None, triangle_limit: ray.t_max, box_limit: ray.t_max * FAR_SCALE }
    }

    /// Tests the ray against the triangles of a leaf, keeping the closest hit (ties at equal `t`
    /// to the lowest triangle index).
    ///
    /// # Safety
    /// The CPU must support `K`'s instruction set.
    #[inline(always)]
    pub unsafe fn leaf<K: Kernel>(
        &mut self,
        bvh: &WideBvh,
        offset: u32,
        triangle_ray: &TriangleRay<K::RecordRay>,
    ) {
        for record in bvh.leaves.leaf(offset) {
            // SAFETY: the caller guarantees `K`'s instruction set.
            let decided = unsafe { K::record_hits(triangle_ray, &record, self.triangle_limit) };
            let mut hits = decided.hits;
            let mut undecided = decided.undecided;
            while hits | undecided != 0 {
                let lane = (hits | undecided).trailing_zeros() as usize;
                let bit = 1 << lane;
                let (t, b1, b2) = if hits & bit != 0 {
                    hits &= !bit;
                    (decided.t[lane], decided.b1[lane], decided.b2[lane])
                } else {
                    undecided &= !bit;
                    let [v0, v1, v2] = record.triangle(lane);
                    match triangle_ray.ray.intersect_rarely(v0, v1, v2, self.triangle_limit) {
                        Some(h) => (h.t, h.b1, h.b2),
                        None => continue,
                    }
                };
                let hit = Hit { t, triangle: record.id(lane), b1, b2 };
                // The triangles of one record are all tested against the limit at its start.
                if self.best.is_none_or(|best| hit.precedes(&best)) {
                    self.best = Some(hit);
                    self.triangle_limit = next_float_up(t);
                    self.box_limit = t * FAR_SCALE;
                }
            }
        }
    }
}

/// Whether the ray hits any triangle of the leaf at `offset` below `t_max`.
///
/// # Safety
/// The CPU must support `K`'s instruction set.
#[inline(always)]
pub(crate) unsafe fn leaf_occluded<K: Kernel>(
    bvh: &WideBvh,
    offset: u32,
    triangle_ray: &TriangleRay<K::RecordRay>,
    t_max: f32,
) -> bool {
    for record in bvh.leaves.leaf(offset) {
        // SAFETY: the caller guarantees `K`'s instruction set.
        let decided = unsafe { K::record_hits(triangle_ray, &record, t_max) };
        if decided.hits != 0 || record.any_hit(triangle_ray.ray, decided.undecided, t_max) {
            return true;
        }
    }
    false
}

/// The closest hit; ties at equal `t` go to the lowest triangle index, as in
/// [`BruteForce`](crate::BruteForce), so the answer never depends on the tree.
///
/// # Safety
/// The CPU must support `K`'s instruction set.
#[inline(always)]
pub(crate) unsafe fn closest_hit<K: Kernel>(bvh: &WideBvh, ray: &Ray) -> Option<Hit> {
    // SAFETY: the caller's guarantee.
    unsafe { closest_hit_counted::<K, ()>(bvh, ray, &mut ()) }
}

/// [`closest_hit`], counting what it visits into `counter`.
///
/// # Safety
/// The CPU must support `K`'s instruction set.
#[inline(always)]
pub(crate) unsafe fn closest_hit_counted<K: Kernel, C: Counter>(
    bvh: &WideBvh,
    ray: &Ray,
    counter: &mut C,
) -> Option<Hit> {
    let mut closest = Closest::new(ray);
    let query = ClosestQuery { start: 0, closest: &mut closest, counter };
    // SAFETY: the caller guarantees `K`'s instruction set.
    unsafe { K::query(bvh, ray, query) }?;
    closest.best
}

/// The closest hit in the subtree of `start` ([`closest_in`]), kept in `closest`.
struct ClosestQuery<'a, C> {
    start: u32,
    closest: &'a mut Closest,
    counter: &'a mut C,
}

impl<K: Kernel, C: Counter> Query<K> for ClosestQuery<'_, C> {
    type Output = ();
    #[inline(always)]
    unsafe fn run<B: BoxRay>(
        self,
        bvh: &WideBvh,
        box_ray: &B,
        triangle_ray: &TriangleRay<K::RecordRay>,
        _: f32,
    ) {
        let (start, closest, counter) = (self.start, self.closest, self.counter);
        // SAFETY: the caller's guarantee.
        unsafe { closest_in::<K, B, C>(bvh, box_ray, triangle_ray, start, closest, counter) }
    }
}

/// [`closest_in`] for a prepared ray, in its fused or plain form.
///
/// # Safety
/// The CPU must support `K`'s instruction set.
#[inline(always)]
pub(crate) unsafe fn closest_in_prepared<K: Kernel, C: Counter>(
    bvh: &WideBvh,
    prepared: &Prepared<K>,
    start: u32,
    closest: &mut Closest,
    counter: &mut C,
) {
    // SAFETY: the caller's guarantee.
    unsafe { run_prepared(bvh, prepared, ClosestQuery { start, closest, counter }) }
}

/// The closest hit in the subtree of child reference `start` (an interior node or a leaf),
/// for a ray set up for `K`'s kernels, kept in `closest` (which may already hold a hit).
///
/// # Safety
/// The CPU must support `K`'s instruction set.
#[inline(always)]
pub(crate) unsafe fn closest_in<K: Kernel, B: BoxRay, C: Counter>(
    bvh: &WideBvh,
    box_ray: &B,
    triangle_ray: &TriangleRay<K::RecordRay>,
    start: u32,
    closest: &mut Closest,
    counter: &mut C,
) {
    let mut stack = Stack::<(u32, f32)>::new();
    // The child being descended into: an interior node or a leaf (never `EMPTY`).
    let mut current = start;
    loop {
        // Descend through interior nodes, into the nearest child entered, pushing the others.
        while let Child::Node(index) = decode(current) {
            counter.node();
            let node = &bvh.nodes[index as usize];
            // SAFETY: the caller guarantees `K`'s instruction set.
            let (mut mask, near) = unsafe { box_ray.enter(node, closest.box_limit) };
            if mask == 0 {
                current = EMPTY;
                break;
            }
            let children = &node.children;
            let k0 = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            if mask == 0 {
                // One child entered (common deep in the tree): no stack.
                current = children[k0];
                continue;
            }
            let k1 = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            if mask == 0 {
                // Two: go to the nearer, push the other.
                let (near_k, far_k) = if near[k1] < near[k0] { (k1, k0) } else { (k0, k1) };
                prefetch_child(bvh, children[far_k]);
                stack.push((children[far_k], near[far_k]));
                current = children[near_k];
                continue;
            }
            // Three or more: push all sorted, farthest deepest, and take the nearest.
            let first = stack.len();
            for k in [k0, k1] {
                prefetch_child(bvh, children[k]);
                stack.push_sorted(first, (children[k], near[k]), |e| e.1);
            }
            while mask != 0 {
                let k = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                prefetch_child(bvh, children[k]);
                stack.push_sorted(first, (children[k], near[k]), |e| e.1);
            }
            current = stack.pop().map_or(EMPTY, |e| e.0);
        }
        if let Child::Leaf(offset) = decode(current) {
            counter.leaf(&bvh.leaves, offset);
            // SAFETY: the caller guarantees `K`'s instruction set.
            unsafe { closest.leaf::<K>(bvh, offset, triangle_ray) };
        }
        // Pop the next child still in reach.
        loop {
            let Some((child, near)) = stack.pop() else {
                return;
            };
            if near <= closest.box_limit {
                current = child;
                break;
            }
        }
    }
}

/// Asks the cache for the four lines of a child (a node's planes and references, or a leaf's
/// first record, 256 bytes at most for a record of 16 vertices) while its siblings are sorted
/// and tested, or, in occlusion, while the other children are: a hint, with no effect on the
/// answers. It pays on trees larger than the caches.
#[inline(always)]
fn prefetch_child(bvh: &WideBvh, child: u32) {
    use crate::memory::prefetch;
    let address = match decode(child) {
        Child::Node(index) => bvh.nodes.as_ptr().wrapping_add(index as usize).cast::<u8>(),
        Child::Leaf(offset) => bvh.leaves.address(offset).cast::<u8>(),
        Child::Empty => return,
    };
    for line in 0..4 {
        prefetch(address.wrapping_add(64 * line));
    }
}

/// Whether anything is hit; stops at the first hit found.
///
/// # Safety
/// The CPU must support `K`'s instruction set.
#[inline(always)]
pub(crate) unsafe fn occluded<K: Kernel>(bvh: &WideBvh, ray: &Ray) -> bool {
    // SAFETY: the caller's guarantee.
    unsafe { occluded_counted::<K, ()>(bvh, ray, &mut ()) }
}

/// [`occluded`], counting what it visits into `counter`.
///
/// # Safety
/// The CPU must support `K`'s instruction set.
#[inline(always)]
pub(crate) unsafe fn occluded_counted<K: Kernel, C: Counter>(
    bvh: &WideBvh,
    ray: &Ray,
    counter: &mut C,
) -> bool {
    let query = OccludedQuery { start: 0, counter };
    // SAFETY: the caller guarantees `K`'s instruction set.
    unsafe { K::query(bvh, ray, query) }.unwrap_or(false)
}

/// Whether anything is hit in the subtree of node `start` ([`occluded_in`]).
struct OccludedQuery<'a, C> {
    start: u32,
    counter: &'a mut C,
}

impl<K: Kernel, C: Counter> Query<K> for OccludedQuery<'_, C> {
    type Output = bool;
    #[inline(always)]
    unsafe fn run<B: BoxRay>(
        self,
        bvh: &WideBvh,
        box_ray: &B,
        triangle_ray: &TriangleRay<K::RecordRay>,
        t_max: f32,
    ) -> bool {
        let (start, counter) = (self.start, self.counter);
        // SAFETY: the caller's guarantee.
        unsafe { occluded_in::<K, B, C>(bvh, box_ray, triangle_ray, t_max, start, counter) }
    }
}

/// [`occluded_counted`] for a prepared ray, in the subtree of node `start` only.
///
/// # Safety
/// The CPU must support `K`'s instruction set.
#[inline(always)]
pub(crate) unsafe fn occluded_prepared<K: Kernel, C: Counter>(
    bvh: &WideBvh,
    prepared: &Prepared<K>,
    start: u32,
    counter: &mut C,
) -> bool {
    // SAFETY: the caller's guarantee.
    unsafe { run_prepared(bvh, prepared, OccludedQuery { start, counter }) }
}

/// Whether the ray, set up for `K`'s kernels, hits anything below `t_max` in the subtree of
/// node `start`.
///
/// # Safety
/// The CPU must support `K`'s instruction set.
#[inline(always)]
unsafe fn occluded_in<K: Kernel, B: BoxRay, C: Counter>(
    bvh: &WideBvh,
    box_ray: &B,
    triangle_ray: &TriangleRay<K::RecordRay>,
    t_max: f32,
    start: u32,
    counter: &mut C,
) -> bool {
    let box_limit = t_max;
    let mut stack = Stack::<u32>::new();
    let mut index = start;
    loop {
        counter.node();
        let node = &bvh.nodes[index as usize];
        // SAFETY: the caller guarantees `K`'s instruction set.
        let (mut mask, _) = unsafe { box_ray.enter(node, box_limit) };
        // Leaves are tested at once (a hit ends the search); the first interior child is
        // visited next without going through the stack, the others pushed.
        let mut next = None;
        while mask != 0 {
            let k = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            match decode(node.children[k]) {
                Child::Node(child) => {
                    prefetch_child(bvh, node.children[k]);
                    if let Some(other) = next.replace(child) {
                        stack.push(other);
                    }
                }
                Child::Leaf(offset) => {
                    counter.leaf(&bvh.leaves, offset);
                    // SAFETY: the caller guarantees `K`'s instruction set.
                    if unsafe { leaf_occluded::<K>(bvh, offset, triangle_ray, t_max) } {
                        return true;
                    }
                }
                Child::Empty => {}
            }
        }
        match next.or_else(|| stack.pop()) {
            Some(child) => index = child,
            None => return false,
        }
    }
}

const _: () = assert!(WIDTH == 8);
