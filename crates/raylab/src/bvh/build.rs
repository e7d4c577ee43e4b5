//! The binned SAH build of a binary BVH (Wald, "On fast Construction of SAH-based Bounding Volume
//! Hierarchies", 2007; the same scheme as pbrt-v4's `BVHAggregate`).
//!
//! Each node's primitives are sorted by centroid into `bins` equal slabs along each axis; the split
//! between two slabs that minimizes the surface area heuristic
//! `C_trav + (A_L·cost(n_L) + A_R·cost(n_R)) / A` is taken, or a leaf is made when that is cheaper.
//! Because leaves are intersected four triangles at a time, a leaf of `n` triangles costs
//! `⌈n/4⌉` block tests (Embree's rule), which favours leaves of 4 and 8.
//!
//! Large nodes are binned in parallel and their two children built in parallel (rayon), so the
//! build uses every thread of the pool it runs in; on a pool of one thread it is sequential.

use glam::Vec3A;

use super::BuildSettings;
use super::bounds::Bounds;

/// Triangles per leaf block: leaves are tested four at a time.
pub(crate) const BLOCK: usize = 4;

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

/// Nodes with more primitives than this bin and build their children in parallel.
const PARALLEL_MIN: usize = 16 * 1024;
/// Beyond this depth nodes are split in the middle, which bounds the depth (and so the traversal
/// stack) whatever the input.
const MAX_SAH_DEPTH: usize = 48;

/// Builds over `prims` (the bounds of each primitive; primitives whose index is not in `indices`
/// are left out).
pub(crate) fn build(prims: &[Bounds], indices: Vec<u32>, settings: &BuildSettings) -> BinaryBvh {
    let boxes: Vec<Aabb> =
        prims.iter().map(|b| Aabb { min: b.min.into(), max: b.max.into() }).collect();
    let centroids: Vec<Vec3A> = boxes.iter().map(|b| 0.5 * (b.min + b.max)).collect();
    let builder = Builder { prims: &boxes, centroids: &centroids, settings };
    let mut order = indices;
    let mut nodes = Vec::with_capacity(2 * order.len() / settings.max_leaf_size.max(1) + 1);
    if !order.is_empty() {
        let (bounds, centroid_bounds) = builder.bounds_of(&order);
        builder.build_node(&mut order, 0, bounds, centroid_bounds, 0, &mut nodes);
    }
    BinaryBvh { nodes, order }
}

/// A box in SIMD-friendly form, for the build only.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Aabb {
    min: Vec3A,
    max: Vec3A,
}

impl Default for Aabb {
    fn default() -> Self {
        Aabb::EMPTY
    }
}

impl Aabb {
    const EMPTY: Aabb = Aabb { min: Vec3A::INFINITY, max: Vec3A::NEG_INFINITY };

    #[inline]
    fn union(self, other: Aabb) -> Aabb {
        Aabb { min: self.min.min(other.min), max: self.max.max(other.max) }
    }

    #[inline]
    fn grow(self, p: Vec3A) -> Aabb {
        Aabb { min: self.min.min(p), max: self.max.max(p) }
    }

    #[inline]
    fn half_area(&self) -> f32 {
        self.bounds().half_area()
    }

    #[inline]
    fn bounds(&self) -> Bounds {
        Bounds { min: self.min.into(), max: self.max.into() }
    }
}

struct Builder<'a> {
    prims: &'a [Aabb],
    centroids: &'a [Vec3A],
    settings: &'a BuildSettings,
}

/// Per-bin bounds of primitives, and counts.
#[derive(Clone, Copy, Default)]
struct Bin {
    bounds: Aabb,
    count: u32,
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

/// How many leaf blocks `n` primitives fill.
#[inline]
fn blocks(n: u32) -> f32 {
    n.div_ceil(BLOCK as u32) as f32
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
}

impl Builder<'_> {
    fn bounds_of(&self, indices: &[u32]) -> (Aabb, Aabb) {
        let fold = |(b, c): (Aabb, Aabb), &i: &u32| {
            (b.union(self.prims[i as usize]), c.grow(self.centroids[i as usize]))
        };
        let empty = (Aabb::EMPTY, Aabb::EMPTY);
        if indices.len() >= PARALLEL_MIN {
            use rayon::prelude::*;
            indices
                .par_chunks(4096)
                .map(|chunk| chunk.iter().fold(empty, fold))
                .reduce(|| empty, |(a, b), (c, d)| (a.union(c), b.union(d)))
        } else {
            indices.iter().fold(empty, fold)
        }
    }

    /// Builds the subtree over `indices` (which start at `first` in the final order) into `out`.
    fn build_node(
        &self,
        indices: &mut [u32],
        first: u32,
        bounds: Aabb,
        centroid_bounds: Aabb,
        depth: usize,
        out: &mut Vec<BinaryNode>,
    ) {
        let n = indices.len();
        let leaf = BinaryNode { bounds: bounds.bounds(), first_or_right: first, count: n as u32 };
        if n <= 1 {
            out.push(leaf);
            return;
        }
        let max_leaf = self.settings.max_leaf_size;
        let split = if depth < MAX_SAH_DEPTH {
            self.best_split(indices, &bounds, &centroid_bounds)
        } else {
            None
        };
        let (mid, left, right) = match split {
            Some(split) => {
                let leaf_cost = blocks(n as u32) * self.settings.block_cost;
                if n <= max_leaf && leaf_cost <= split.cost {
                    out.push(leaf);
                    return;
                }
                let (mid, left_centroids, right_centroids) =
                    self.partition(indices, &split, &centroid_bounds);
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
                (mid, self.bounds_of(&indices[..mid]), self.bounds_of(&indices[mid..]))
            }
        };

        let node_index = out.len();
        out.push(BinaryNode { bounds: bounds.bounds(), first_or_right: 0, count: 0 });
        let (left_indices, right_indices) = indices.split_at_mut(mid);
        let right_first = first + mid as u32;
        if n >= PARALLEL_MIN {
            let (mut left_nodes, mut right_nodes) = (Vec::new(), Vec::new());
            rayon::join(
                || self.build_node(left_indices, first, left.0, left.1, depth + 1, &mut left_nodes),
                || {
                    let (b, c) = right;
                    self.build_node(right_indices, right_first, b, c, depth + 1, &mut right_nodes)
                },
            );
            append_relocated(out, &left_nodes);
            out[node_index].first_or_right = out.len() as u32;
            append_relocated(out, &right_nodes);
        } else {
            self.build_node(left_indices, first, left.0, left.1, depth + 1, out);
            out[node_index].first_or_right = out.len() as u32;
            self.build_node(right_indices, right_first, right.0, right.1, depth + 1, out);
        }
    }

    fn best_split(&self, indices: &[u32], bounds: &Aabb, centroid_bounds: &Aabb) -> Option<Split> {
        let bins = self.settings.bins;
        let binning = Binning::new(centroid_bounds, bins);
        let extent = centroid_bounds.max - centroid_bounds.min;
        let fill = |mut acc: Vec<[Bin; 3]>, &i: &u32| {
            let b = self.prims[i as usize];
            let k = binning.bins(self.centroids[i as usize]);
            for (axis, bin) in [k.x, k.y, k.z].into_iter().enumerate() {
                let bin = &mut acc[bin as usize][axis];
                bin.bounds = bin.bounds.union(b);
                bin.count += 1;
            }
            acc
        };
        let merge = |mut a: Vec<[Bin; 3]>, b: Vec<[Bin; 3]>| {
            for (x, y) in a.iter_mut().zip(&b) {
                for axis in 0..3 {
                    x[axis].bounds = x[axis].bounds.union(y[axis].bounds);
                    x[axis].count += y[axis].count;
                }
            }
            a
        };
        let empty = || vec![[Bin::default(); 3]; bins];
        let binned = if indices.len() >= PARALLEL_MIN {
            use rayon::prelude::*;
            indices
                .par_chunks(8192)
                .map(|chunk| chunk.iter().fold(empty(), fill))
                .reduce(empty, merge)
        } else {
            indices.iter().fold(empty(), fill)
        };

        // A flat node has zero area; its splits are then compared among themselves only.
        let parent_area = bounds.half_area().max(f32::MIN_POSITIVE);
        let mut best: Option<Split> = None;
        let mut right_sweep = vec![(Aabb::EMPTY, 0u32); bins];
        for axis in 0..3 {
            if extent[axis] <= 0.0 {
                continue;
            }
            // Sweep from the right: right_sweep[k] covers bins k..bins.
            let mut acc = (Aabb::EMPTY, 0u32);
            for k in (1..bins).rev() {
                let bin = &binned[k][axis];
                acc = (acc.0.union(bin.bounds), acc.1 + bin.count);
                right_sweep[k] = acc;
            }
            let mut left = (Aabb::EMPTY, 0u32);
            for k in 1..bins {
                let bin = &binned[k - 1][axis];
                left = (left.0.union(bin.bounds), left.1 + bin.count);
                let right = right_sweep[k];
                if left.1 == 0 || right.1 == 0 {
                    continue;
                }
                let cost = self.settings.traversal_cost
                    + (left.0.half_area() * blocks(left.1) + right.0.half_area() * blocks(right.1))
                        * self.settings.block_cost
                        / parent_area;
                if best.as_ref().is_none_or(|b| cost < b.cost) {
                    best = Some(Split { axis, bin: k, cost, left: left.0, right: right.0 });
                }
            }
        }
        best
    }

    /// Moves the primitives of bins `< split.bin` to the front; returns how many there are and
    /// the bounds of the two sides' centroids.
    fn partition(
        &self,
        indices: &mut [u32],
        split: &Split,
        centroid_bounds: &Aabb,
    ) -> (usize, Aabb, Aabb) {
        let binning = Binning::new(centroid_bounds, self.settings.bins);
        let (mut left, mut right) = (Aabb::EMPTY, Aabb::EMPTY);
        let (mut lo, mut hi) = (0, indices.len());
        while lo < hi {
            let c = self.centroids[indices[lo] as usize];
            if (binning.bins(c)[split.axis] as usize) < split.bin {
                left = left.grow(c);
                lo += 1;
            } else {
                right = right.grow(c);
                hi -= 1;
                indices.swap(lo, hi);
            }
        }
        (lo, left, right)
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
