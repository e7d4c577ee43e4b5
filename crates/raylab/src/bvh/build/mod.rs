//! The binned SAH build of a binary BVH (Wald, "On fast Construction of SAH-based Bounding Volume
//! Hierarchies", 2007; the same scheme as pbrt-v4's `BVHAggregate`).
//!
//! Each node's primitives are sorted by centroid into `bins` equal slabs along each axis; the split
//! between two slabs that minimizes the surface area heuristic
//! `C_trav + (A_L·cost(n_L) + A_R·cost(n_R)) / A` is taken, or a leaf is made when that is cheaper.
//! Because a leaf record's triangles (up to eight, `bvh/leaf`) are tested in one pass, a leaf
//! of `n` triangles costs `⌈n/8⌉` record tests (Embree's rule for its blocks of four, with
//! records of eight; `⌈n/4⌉` for the small scenes' leaves of up to four, see
//! [`unit_shift`](bins::unit_shift)): against `⌈n/4⌉` on large meshes the tree has fewer nodes,
//! and shadow and diffuse rays are faster.
//!
//! Large nodes are binned in parallel and their two children built in parallel (rayon), so the
//! build uses every thread of the pool it runs in; on a pool of one thread it is sequential.

use glam::{Vec3, Vec3A, Vec4};

mod bins;
mod collapse;
mod optimal;
mod settings;
mod sweep;

pub(crate) use collapse::collapse;
pub(crate) use optimal::{Costs, collapse_optimal};
pub use settings::{BuildSettings, Collapse};

use crate::bvh::bounds::Bounds;
use crate::bvh::leaf::RECORD_TRIANGLES;
use crate::triangle::is_degenerate;
use bins::{Aabb, Bin, records, unit_shift};
use sweep::sweep;

/// Whether a triangle can be hit at all: finite vertices and non-zero area. The build leaves
/// the others out, and refit parks triangles that become so.
pub(crate) fn hittable(triangle: [Vec3; 3]) -> bool {
    triangle.iter().all(|v| v.is_finite()) && !is_degenerate(triangle)
}

/// A node of the binary BVH in depth-first order: an interior node's left child follows it, its
/// right child is at `right`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BinaryNode {
    pub bounds: Bounds,
    /// Leaf: index of the first primitive in the build's order. Interior: the right child.
    pub first_or_right: u32,
    /// Leaf: number of primitives (≥ 1). Interior: 0.
    pub count: u32,
}

impl BinaryNode {
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }
}

/// A binary BVH over primitives given by their bounds.
pub(crate) struct BinaryBvh {
    /// Depth-first; the root is node 0.
    pub nodes: Vec<BinaryNode>,
    /// Primitive indices in leaf order.
    pub order: Vec<u32>,
}

/// Nodes of up to this many bins bin on the stack.
const STACK_BINS: usize = 32;
/// Nodes with more primitives than this bin and build their children in parallel.
const PARALLEL_MIN: usize = 16 * 1024;

/// Whether a node of `n` primitives is worth splitting into parallel work: large enough, and a
/// pool with more than one thread to run it (on one thread the parallel paths only add the
/// merging of partial bins and the copying of subtrees).
#[inline]
fn in_parallel(n: usize) -> bool {
    n >= PARALLEL_MIN && rayon::current_num_threads() > 1
}
/// Beyond this depth nodes are split in the middle, which bounds the depth (and so the traversal
/// stack) whatever the input.
const MAX_SAH_DEPTH: usize = 48;

/// Builds over `prims` (the bounds of each primitive; primitives whose index is not in `indices`
/// are left out).
#[cfg(test)]
pub(crate) fn build(prims: &[Bounds], indices: Vec<u32>, settings: &BuildSettings) -> BinaryBvh {
    let refs = indices
        .iter()
        .map(|&id| {
            let b = prims[id as usize];
            PrimRef::new(Aabb { min: b.min.into(), max: b.max.into() }, id)
        })
        .collect();
    build_refs(refs, settings)
}

/// Builds over the triangles that can be hit (finite vertices, non-zero area); the others are
/// left out of the tree, and of [`BinaryBvh::order`].
pub(crate) fn build_triangles(triangles: &[[Vec3; 3]], settings: &BuildSettings) -> BinaryBvh {
    // One pass from the triangles to the build records (no array of boxes in between).
    let refs = (0u32..)
        .zip(triangles)
        .filter(|&(_, &t)| hittable(t))
        .map(|(id, &[a, b, c])| {
            let (a, b, c) = (Vec3A::from(a), Vec3A::from(b), Vec3A::from(c));
            PrimRef::new(Aabb { min: a.min(b).min(c), max: a.max(b).max(c) }, id)
        })
        .collect();
    build_refs(refs, settings)
}

/// Builds over `refs`, which it reorders into the leaves' order.
fn build_refs(mut refs: Vec<PrimRef>, settings: &BuildSettings) -> BinaryBvh {
    // The build moves the primitives' boxes themselves, not indices into them: binning and
    // partitioning then read memory in order (on the 871k-triangle dragon, indirection through
    // shuffled indices made most reads cache misses).
    let builder = Builder { settings };
    let mut nodes = Vec::with_capacity(2 * refs.len() / settings.max_leaf_size.max(1) + 1);
    if !refs.is_empty() {
        let (bounds, centroid_bounds) = builder.bounds_of(&refs);
        builder.build_node(&mut refs, 0, bounds, centroid_bounds, 0, &mut nodes);
    }
    BinaryBvh { nodes, order: refs.iter().map(PrimRef::id).collect() }
}

/// A primitive during the build: its box and its index, in 32 bytes (the index rides in the
/// unused fourth lane of the box's minimum, as float bits that are only ever copied). Binning and
/// partitioning stream these records: at 48 bytes (a separate index field, padded) the dragon's
/// 871k records were 42 MB, at 32 bytes they are 28 MB.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
struct PrimRef {
    /// `min.x, min.y, min.z`, then the index's bits.
    min_id: Vec4,
    max: Vec3A,
}

impl PrimRef {
    #[inline]
    fn new(bounds: Aabb, id: u32) -> PrimRef {
        PrimRef { min_id: bounds.min.extend(f32::from_bits(id)), max: bounds.max }
    }

    #[inline]
    fn bounds(&self) -> Aabb {
        Aabb { min: Vec3A::from_vec4(self.min_id), max: self.max }
    }

    #[inline]
    fn id(&self) -> u32 {
        self.min_id.w.to_bits()
    }

    #[inline]
    fn centroid(&self) -> Vec3A {
        let b = self.bounds();
        0.5 * (b.min + b.max)
    }
}

struct Builder<'a> {
    settings: &'a BuildSettings,
}

/// The best split found by binning.
struct Split {
    axis: usize,
    /// Primitives in bins `< bin` go left.
    bin: usize,
    cost: f32,
    left: Aabb,
    right: Aabb,
}

/// Maps centroids to bins: `bin = ⌊(c − min)·scale⌋`, clamped to the last bin.
#[derive(Clone, Copy)]
struct Binning {
    min: Vec3A,
    scale: Vec3A,
    /// The last bin's index, as a float on every axis.
    last: Vec3A,
}

impl Binning {
    fn new(centroid_bounds: &Aabb, bins: usize) -> Self {
        let extent = centroid_bounds.max - centroid_bounds.min;
        // Slightly fewer than `bins` per extent, so that the maximum lands in the last bin.
        let per_extent = bins as f32 * (1.0 - 1e-6);
        let scale = Vec3A::select(extent.cmpgt(Vec3A::ZERO), per_extent / extent, Vec3A::ZERO);
        Binning { min: centroid_bounds.min, scale, last: Vec3A::splat((bins - 1) as f32) }
    }

    /// The bins of a centroid along the three axes.
    ///
    /// The position is clamped to the last bin before it is truncated, which gives the same bin
    /// as truncating first (the position is never negative: `c >= min`), and lets x86-64 convert
    /// all three axes in one instruction instead of three saturating scalar conversions.
    #[inline]
    fn bins(&self, c: Vec3A) -> glam::UVec3 {
        let position = ((c - self.min) * self.scale).min(self.last);
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{__m128, _mm_cvttps_epi32, _mm_storeu_si128};
            let mut bins = [0u32; 4];
            // SAFETY: SSE2 is part of x86-64; the store writes 16 bytes into `bins`.
            unsafe {
                _mm_storeu_si128(bins.as_mut_ptr().cast(), _mm_cvttps_epi32(__m128::from(position)))
            };
            glam::UVec3::new(bins[0], bins[1], bins[2])
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            position.as_uvec3()
        }
    }

    /// Adds primitive `r` to the bins of its centroid on each axis.
    #[inline]
    fn add(&self, bins: &mut [[Bin; 3]], r: &PrimRef) {
        let b = r.bounds();
        let k = self.bins(r.centroid());
        for (axis, bin) in [k.x, k.y, k.z].into_iter().enumerate() {
            let bin = &mut bins[bin as usize][axis];
            bin.bounds = bin.bounds.union(b);
            bin.count += 1;
        }
    }
}

impl Builder<'_> {
    fn bounds_of(&self, refs: &[PrimRef]) -> (Aabb, Aabb) {
        let fold = |(b, c): (Aabb, Aabb), r: &PrimRef| (b.union(r.bounds()), c.grow(r.centroid()));
        let empty = (Aabb::EMPTY, Aabb::EMPTY);
        if in_parallel(refs.len()) {
            use rayon::prelude::*;
            refs.par_chunks(4096)
                .map(|chunk| chunk.iter().fold(empty, fold))
                .reduce(|| empty, |(a, b), (c, d)| (a.union(c), b.union(d)))
        } else {
            refs.iter().fold(empty, fold)
        }
    }

    /// Builds the subtree over `refs` (which start at `first` in the final order) into `out`.
    fn build_node(
        &self,
        refs: &mut [PrimRef],
        first: u32,
        bounds: Aabb,
        centroid_bounds: Aabb,
        depth: usize,
        out: &mut Vec<BinaryNode>,
    ) {
        let n = refs.len();
        let leaf = BinaryNode { bounds: bounds.bounds(), first_or_right: first, count: n as u32 };
        if n <= 1 {
            out.push(leaf);
            return;
        }
        let max_leaf = self.settings.max_leaf_size;
        // A node that fits one leaf record is a leaf without binning where the SAH would make it
        // one anyway: as a leaf it costs one record test, split at least a traversal step (no
        // cheaper than a record test, as in every preset) plus two children's area terms.
        if n <= RECORD_TRIANGLES.min(max_leaf)
            && self.settings.traversal_cost >= self.settings.record_cost
        {
            out.push(leaf);
            return;
        }
        let split = if depth < MAX_SAH_DEPTH {
            self.best_split(refs, &bounds, &centroid_bounds)
        } else {
            None
        };
        let (mid, left, right) = match split {
            Some(split) => {
                let leaf_cost = records(n as u32, unit_shift(max_leaf)) * self.settings.record_cost;
                if n <= max_leaf && leaf_cost <= split.cost {
                    out.push(leaf);
                    return;
                }
                let (mid, left_centroids, right_centroids) =
                    self.partition(refs, &split, &centroid_bounds);
                (mid, (split.left, left_centroids), (split.right, right_centroids))
            }
            None => {
                // All centroids coincide (or the depth limit is reached): no split separates
                // anything, so cut the list in half if it is too long for a leaf.
                if n <= max_leaf {
                    out.push(leaf);
                    return;
                }
                let mid = n / 2;
                (mid, self.bounds_of(&refs[..mid]), self.bounds_of(&refs[mid..]))
            }
        };

        let node_index = out.len();
        out.push(BinaryNode { bounds: bounds.bounds(), first_or_right: 0, count: 0 });
        let (left_refs, right_refs) = refs.split_at_mut(mid);
        let right_first = first + mid as u32;
        if in_parallel(n) {
            let (mut left_nodes, mut right_nodes) = (Vec::new(), Vec::new());
            rayon::join(
                || self.build_node(left_refs, first, left.0, left.1, depth + 1, &mut left_nodes),
                || {
                    let (b, c) = right;
                    self.build_node(right_refs, right_first, b, c, depth + 1, &mut right_nodes)
                },
            );
            append_relocated(out, &left_nodes);
            out[node_index].first_or_right = out.len() as u32;
            append_relocated(out, &right_nodes);
        } else {
            self.build_node(left_refs, first, left.0, left.1, depth + 1, out);
            out[node_index].first_or_right = out.len() as u32;
            self.build_node(right_refs, right_first, right.0, right.1, depth + 1, out);
        }
    }

    fn best_split(&self, refs: &[PrimRef], bounds: &Aabb, centroid_bounds: &Aabb) -> Option<Split> {
        let bins = self.settings.bins;
        let binning = Binning::new(centroid_bounds, bins);
        let extent = centroid_bounds.max - centroid_bounds.min;
        // Nodes binned on one thread with at most `STACK_BINS` bins (nearly all of them) use an
        // array on the stack; large nodes bin into vectors in parallel, and so do builds with
        // more bins than the array holds (on a node below `PARALLEL_MIN` that is one chunk).
        let mut on_stack = [[Bin::default(); 3]; STACK_BINS];
        let heap: Vec<[Bin; 3]>;
        let binned: &[[Bin; 3]] = if in_parallel(refs.len()) || bins > STACK_BINS {
            use rayon::prelude::*;
            let empty = || vec![[Bin::default(); 3]; bins];
            let merge = |mut a: Vec<[Bin; 3]>, b: Vec<[Bin; 3]>| {
                merge_bins(&mut a, &b);
                a
            };
            heap = refs
                .par_chunks(8192)
                .map(|chunk| {
                    let mut acc = empty();
                    bin_all(&mut acc, chunk, &binning);
                    acc
                })
                .reduce(empty, merge);
            &heap
        } else {
            bin_all(&mut on_stack[..bins], refs, &binning);
            &on_stack[..bins]
        };

        // A flat node has zero area; its splits are then compared among themselves only.
        let parent_area = bounds.half_area().max(f32::MIN_POSITIVE);
        let unit = unit_shift(self.settings.max_leaf_size);
        let mut best =
            sweep(binned, extent.cmpgt(Vec3A::ZERO).into(), unit).map(|(axis, bin, cost)| {
                // The winner's boxes, from its bins (not kept for every candidate).
                let side = |bins: &[[Bin; 3]]| {
                    bins.iter().fold(Aabb::EMPTY, |b, x| b.union(x[axis].bounds))
                };
                Split { axis, bin, cost, left: side(&binned[..bin]), right: side(&binned[bin..]) }
            });
        // The candidates were compared by their area terms alone; the cost proper (which scales
        // and offsets them alike) is computed once, for the winner.
        if let Some(split) = best.as_mut() {
            split.cost =
                self.settings.traversal_cost + split.cost * self.settings.record_cost / parent_area;
        }
        best
    }

    /// Moves the primitives of bins `< split.bin` to the front; returns how many there are and
    /// the bounds of the two sides' centroids.
    ///
    /// Without branches on the side (Lomuto's scheme with an unconditional swap): which side a
    /// primitive goes to is as unpredictable as a coin, and a mispredicted branch per primitive
    /// cost more than the swap.
    fn partition(
        &self,
        refs: &mut [PrimRef],
        split: &Split,
        centroid_bounds: &Aabb,
    ) -> (usize, Aabb, Aabb) {
        let binning = Binning::new(centroid_bounds, self.settings.bins);
        let (mut left, mut right) = (Aabb::EMPTY, Aabb::EMPTY);
        let mut lo = 0;
        // Invariant: `refs[..lo]` go left, `refs[lo..i]` go right.
        for i in 0..refs.len() {
            let r = refs[i];
            let c = r.centroid();
            let goes_left = (binning.bins(c)[split.axis] as usize) < split.bin;
            refs[i] = refs[lo];
            refs[lo] = r;
            lo += goes_left as usize;
            let side = glam::BVec3A::splat(goes_left);
            left.min = Vec3A::select(side, left.min.min(c), left.min);
            left.max = Vec3A::select(side, left.max.max(c), left.max);
            right.min = Vec3A::select(side, right.min, right.min.min(c));
            right.max = Vec3A::select(side, right.max, right.max.max(c));
        }
        (lo, left, right)
    }
}

/// Bins `refs` into `bins` ([`Binning::add`]). Long lists go into two sets of bins in turn, merged
/// after: neighbours in a node's list often fall into the same bins, and with one set each update
/// waited for the store of the one before (the binning's hottest instruction was that load). The
/// bins are the same either way: unions and counts do not depend on the order.
fn bin_all(bins: &mut [[Bin; 3]], refs: &[PrimRef], binning: &Binning) {
    /// Shorter lists use one set (the second's clearing would cost more than it saves).
    const TWO_SETS_MIN: usize = 256;
    if refs.len() < TWO_SETS_MIN {
        for r in refs {
            binning.add(bins, r);
        }
        return;
    }
    let mut on_stack = [[Bin::default(); 3]; STACK_BINS];
    let mut on_heap: Vec<[Bin; 3]>;
    let other: &mut [[Bin; 3]] = if bins.len() <= STACK_BINS {
        &mut on_stack[..bins.len()]
    } else {
        on_heap = vec![[Bin::default(); 3]; bins.len()];
        &mut on_heap
    };
    let mut pairs = refs.chunks_exact(2);
    for pair in &mut pairs {
        binning.add(bins, &pair[0]);
        binning.add(other, &pair[1]);
    }
    for r in pairs.remainder() {
        binning.add(bins, r);
    }
    merge_bins(bins, other);
}

/// Adds the primitives and boxes of bins `from` to `into`, bin by bin.
fn merge_bins(into: &mut [[Bin; 3]], from: &[[Bin; 3]]) {
    for (x, y) in into.iter_mut().zip(from) {
        for axis in 0..3 {
            x[axis].bounds = x[axis].bounds.union(y[axis].bounds);
            x[axis].count += y[axis].count;
        }
    }
}

/// Appends a subtree built on its own (node indices relative to its start) to `out`.
fn append_relocated(out: &mut Vec<BinaryNode>, subtree: &[BinaryNode]) {
    let offset = out.len() as u32;
    out.extend(subtree.iter().map(|node| {
        let mut node = *node;
        if !node.is_leaf() {
            node.first_or_right += offset;
        }
        node
    }));
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    fn check_tree(bvh: &BinaryBvh, prims: &[Bounds], max_leaf: usize) {
        // Every primitive appears exactly once, every node contains its subtree.
        let mut seen = vec![false; prims.len()];
        for &i in &bvh.order {
            assert!(!seen[i as usize]);
            seen[i as usize] = true;
        }
        fn visit(
            bvh: &BinaryBvh,
            prims: &[Bounds],
            node: usize,
            max_leaf: usize,
            leaves: &mut usize,
        ) -> Bounds {
            let n = bvh.nodes[node];
            let inner = if n.is_leaf() {
                assert!(n.count as usize <= max_leaf.max(1));
                *leaves += n.count as usize;
                let range = n.first_or_right as usize..(n.first_or_right + n.count) as usize;
                bvh.order[range].iter().fold(Bounds::EMPTY, |b, &i| b.union(prims[i as usize]))
            } else {
                let l = visit(bvh, prims, node + 1, max_leaf, leaves);
                let r = visit(bvh, prims, n.first_or_right as usize, max_leaf, leaves);
                l.union(r)
            };
            assert_eq!(inner, n.bounds, "node {node}");
            inner
        }
        let mut leaves = 0;
        visit(bvh, prims, 0, max_leaf, &mut leaves);
        assert_eq!(leaves, bvh.order.len());
    }

    fn random_prims(n: usize, seed: u64) -> Vec<Bounds> {
        let mut state = seed;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 40) as f32) / (1u64 << 24) as f32
        };
        (0..n)
            .map(|_| {
                let p = Vec3::new(next(), next(), next()) * 10.0;
                let q = p + Vec3::new(next(), next(), next()) * 0.5;
                Bounds { min: p, max: q }
            })
            .collect()
    }

    #[test]
    fn trees_cover_their_primitives_for_every_preset() {
        for settings in BuildSettings::PRESETS.map(|(_, s)| s) {
            for n in [1, 2, 3, 5, 17, 1000, 40_000] {
                let prims = random_prims(n, n as u64);
                let bvh = build(&prims, (0..n as u32).collect(), &settings);
                check_tree(&bvh, &prims, settings.max_leaf_size);
            }
        }
    }

    fn prim_refs(n: usize, seed: u64) -> Vec<PrimRef> {
        (0u32..)
            .zip(random_prims(n, seed))
            .map(|(id, b)| PrimRef::new(Aabb { min: b.min.into(), max: b.max.into() }, id))
            .collect()
    }

    /// Binning into two sets in turn gives the bins of one set, bit for bit: lists above and
    /// below the two-set length, odd and even, with 8, 32 and 256 bins (on the stack and not).
    #[test]
    fn two_sets_of_bins_give_the_bins_of_one() {
        for (n, bins) in [(255, 8), (256, 32), (1001, 32), (4000, 256)] {
            let refs = prim_refs(n, n as u64);
            let (_, centroids) = Builder { settings: &BuildSettings::HIGH }.bounds_of(&refs);
            let binning = Binning::new(&centroids, bins);
            let mut one = vec![[Bin::default(); 3]; bins];
            for r in &refs {
                binning.add(&mut one, r);
            }
            let mut two = vec![[Bin::default(); 3]; bins];
            bin_all(&mut two, &refs, &binning);
            for (a, b) in one.iter().flatten().zip(two.iter().flatten()) {
                assert_eq!(a.count, b.count, "{n} refs, {bins} bins");
                assert_eq!(a.bounds.bounds(), b.bounds.bounds(), "{n} refs, {bins} bins");
            }
            assert_eq!(one.iter().map(|b| b[0].count).sum::<u32>(), n as u32);
        }
    }

    /// The partition puts every primitive of the split's left bins first and the rest after,
    /// loses none, and returns each side's centroid bounds.
    #[test]
    fn the_partition_separates_the_bins_and_keeps_every_primitive() {
        let settings = BuildSettings::MEDIUM;
        let builder = Builder { settings: &settings };
        for n in [2, 3, 100, 5000] {
            let mut refs = prim_refs(n, 7 + n as u64);
            let (bounds, centroids) = builder.bounds_of(&refs);
            let split = builder.best_split(&refs, &bounds, &centroids).expect("a split");
            let mut before: Vec<u32> = refs.iter().map(PrimRef::id).collect();
            let (mid, left, right) = builder.partition(&mut refs, &split, &centroids);
            let binning = Binning::new(&centroids, settings.bins);
            let goes_left =
                |r: &PrimRef| (binning.bins(r.centroid())[split.axis] as usize) < split.bin;
            assert!(refs[..mid].iter().all(goes_left) && !refs[mid..].iter().any(goes_left));
            assert!(0 < mid && mid < n, "{n}: both sides hold primitives");
            let mut after: Vec<u32> = refs.iter().map(PrimRef::id).collect();
            before.sort_unstable();
            after.sort_unstable();
            assert_eq!(before, after);
            let side =
                |refs: &[PrimRef]| refs.iter().fold(Aabb::EMPTY, |b, r| b.grow(r.centroid()));
            assert_eq!((side(&refs[..mid]), side(&refs[mid..])), (left, right));
        }
    }

    #[test]
    fn primitive_records_keep_their_index_bits_and_box() {
        assert_eq!(size_of::<PrimRef>(), 32);
        let bounds = Aabb { min: Vec3A::new(-1.0, 2.0, 3.0), max: Vec3A::new(4.0, 5.0, 6.5) };
        // Indices whose bits are NaNs (quiet and signalling) and infinities as floats too.
        for id in [0, 1, 0x7f80_0000, 0x7f80_0001, 0x7fc0_0000, 0xff80_0001, u32::MAX] {
            let r = PrimRef::new(bounds, id);
            assert_eq!(r.id(), id);
            assert_eq!(r.bounds().bounds(), bounds.bounds());
            assert_eq!(Vec3::from(r.centroid()), Vec3::new(1.5, 3.5, 4.75));
        }
    }

    #[test]
    fn identical_primitives_are_split_in_half() {
        let prims = vec![Bounds { min: Vec3::ZERO, max: Vec3::ONE }; 100];
        let settings = BuildSettings::default();
        let bvh = build(&prims, (0..100).collect(), &settings);
        check_tree(&bvh, &prims, settings.max_leaf_size);
        assert!(bvh.nodes.len() > 1);
    }

    #[test]
    fn exponentially_spaced_primitives_stay_shallow() {
        // The SAH may peel one primitive at a time; the depth limit must still hold the tree.
        let prims: Vec<Bounds> = (0..2000)
            .map(|i| {
                let x = 1.01f32.powi(i);
                Bounds { min: Vec3::splat(x), max: Vec3::splat(x) }
            })
            .collect();
        let settings = BuildSettings::default();
        let bvh = build(&prims, (0..2000).collect(), &settings);
        check_tree(&bvh, &prims, settings.max_leaf_size);
        fn depth(bvh: &BinaryBvh, node: usize) -> usize {
            let n = bvh.nodes[node];
            if n.is_leaf() {
                1
            } else {
                1 + depth(bvh, node + 1).max(depth(bvh, n.first_or_right as usize))
            }
        }
        assert!(depth(&bvh, 0) <= MAX_SAH_DEPTH + 12);
    }
}
