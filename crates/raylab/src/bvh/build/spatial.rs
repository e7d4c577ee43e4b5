//! Spatial splits: the binned SAH build that may also cut a node's space in two across its
//! triangles (Stich, Friedrich and Dietrich, "Spatial Splits in Bounding Volume Hierarchies",
//! HPG 2009; Embree's `BVH8BuilderFastSpatialSAH` bins them as this file does).
//!
//! An object split puts each triangle on one side, so two children overlap wherever long or
//! slanted triangles reach across; a ray through the overlap must enter both. A spatial split
//! at a plane instead puts each triangle's part on each side into that side: the children do not
//! overlap, at the price of triangles referenced twice. At each node the build weighs both:
//!
//! - the object split of the binned SAH (`build/mod.rs`), by the triangles' boxes' centroids;
//! - if the node holds at least [`MIN_SPATIAL_REFS`] references (an eighth of the triangles
//!   in small scenes), the object split's two boxes overlap by more than `α = 10⁻⁵` of the
//!   root's area (Stich et al.'s test: elsewhere a spatial split rarely wins) and the node's
//!   budget allows,
//!   the best plane among `bins` equal slabs of the node's box on each axis. Each triangle's
//!   reference is chopped at the slab planes it crosses into the box of its part in each slab
//!   (the part of its box on that side of the plane, shrunk to the triangle there), and counted
//!   where it enters and where it leaves; a plane between slabs `k − 1` and `k` then has
//!   `N_L` = the references entering at slabs below `k` and `N_R` = those leaving at `k` or above,
//!   and costs `C_trav + (A_L·⌈N_L/8⌉ + A_R·⌈N_R/8⌉)/A` like an object split.
//!
//! The cheaper of the two (or a leaf) is taken. The extra references a node may make (its
//! budget) start as [`BuildSettings::spatial_splits`] times the triangles at the root, and what
//! a node leaves is shared among its children by their references, so the total stays within it
//! and the tree does not depend on the order of work (built in parallel, the same tree).
//!
//! A leaf never holds one triangle twice: a reference cut in two goes to different subtrees.
//! The collapse of least cost may join such subtrees into one leaf, and writes each triangle
//! once (`collapse::push_leaf`).
//!
//! The parts' boxes are conservative: the points where a triangle's edges cross a plane are
//! computed in double precision and rounded outward to `f32` with a margin, and every part's box
//! stays inside its reference's. So every point of a triangle is in the box of one of its
//! leaves, and the traversal finds its hits exactly as without splits.

use glam::{Vec3, Vec3A};

use super::{
    Aabb, BinaryBvh, BinaryNode, BuildSettings, Builder, MAX_SAH_DEPTH, PrimRef, RECORD_TRIANGLES,
    hittable, in_parallel, records, unit_shift,
};

/// Spatial splits are tried where the object split's children overlap by more than this
/// fraction of the root's area (Stich et al.'s `α`).
const MIN_OVERLAP: f32 = 1e-5;

/// Nodes of fewer references than this (or than an eighth of the triangles, in small scenes)
/// are split by objects only: below it, spatial splits took most of the build's time and made
/// no better trees (BENCHMARKS.md, "Spatial splits").
const MIN_SPATIAL_REFS: usize = 512;

/// The most slabs per axis a spatial split is chosen among.
const MAX_SPATIAL_BINS: usize = 32;

/// Builds over the triangles that can be hit, as [`build_triangles`](super::build_triangles),
/// with spatial splits of up to `settings.spatial_splits` extra references per triangle.
pub(super) fn build_triangles_spatial(
    triangles: &[[Vec3; 3]],
    settings: &BuildSettings,
) -> BinaryBvh {
    let refs: Vec<PrimRef> = (0u32..)
        .zip(triangles)
        .filter(|&(_, &t)| hittable(t))
        .map(|(id, &[a, b, c])| {
            let (a, b, c) = (Vec3A::from(a), Vec3A::from(b), Vec3A::from(c));
            PrimRef::new(Aabb { min: a.min(b).min(c), max: a.max(b).max(c) }, id)
        })
        .collect();
    let prims = refs.len();
    let mut tree = Subtree::default();
    if !refs.is_empty() {
        let base = Builder { settings };
        let (bounds, centroid_bounds) = base.bounds_of(&refs);
        let budget = (settings.spatial_splits as f64 * prims as f64) as usize;
        let builder = SpatialBuilder {
            base,
            triangles,
            min_overlap: MIN_OVERLAP * bounds.half_area(),
            min_refs: MIN_SPATIAL_REFS.min(prims / 8),
            bins: settings.bins.clamp(2, MAX_SPATIAL_BINS),
        };
        builder.build_node(refs, bounds, centroid_bounds, budget, 0, &mut tree);
    }
    BinaryBvh { nodes: tree.nodes, order: tree.order, prims }
}

/// A subtree's nodes (depth first, the root first) and its leaves' triangles in order.
#[derive(Default)]
struct Subtree {
    nodes: Vec<BinaryNode>,
    order: Vec<u32>,
}

impl Subtree {
    /// Appends `other`, built on its own (its node and order indices from 0).
    fn append(&mut self, other: Subtree) {
        let (node_offset, order_offset) = (self.nodes.len() as u32, self.order.len() as u32);
        self.nodes.extend(other.nodes.into_iter().map(|mut node| {
            node.first_or_right += if node.is_leaf() { order_offset } else { node_offset };
            node
        }));
        self.order.extend(other.order);
    }
}

struct SpatialBuilder<'a> {
    base: Builder<'a>,
    triangles: &'a [[Vec3; 3]],
    /// Object splits whose children overlap by less than this area are taken without trying a
    /// spatial split.
    min_overlap: f32,
    /// Nodes of fewer references are split by objects only.
    min_refs: usize,
    /// Slabs per axis.
    bins: usize,
}

/// One slab of a spatial split's binning, on one axis.
#[derive(Clone, Copy, Default)]
struct SpatialBin {
    /// The parts of the references in the slab.
    bounds: Aabb,
    /// References whose box starts in the slab.
    enter: u32,
    /// References whose box ends in the slab.
    exit: u32,
}

/// The best spatial split of a node.
struct SpatialSplit {
    axis: usize,
    plane: f32,
    cost: f32,
}

impl SpatialBuilder<'_> {
    fn build_node(
        &self,
        mut refs: Vec<PrimRef>,
        bounds: Aabb,
        centroid_bounds: Aabb,
        budget: usize,
        depth: usize,
        out: &mut Subtree,
    ) {
        let settings = self.base.settings;
        let n = refs.len();
        let max_leaf = settings.max_leaf_size;
        let leaf = |refs: &[PrimRef], out: &mut Subtree| {
            let first = out.order.len() as u32;
            out.nodes.push(BinaryNode {
                bounds: bounds.bounds(),
                first_or_right: first,
                count: n as u32,
            });
            out.order.extend(refs.iter().map(PrimRef::id));
        };
        if n <= 1
            || (n <= RECORD_TRIANGLES.min(max_leaf)
                && settings.traversal_cost >= settings.record_cost)
        {
            return leaf(&refs, out);
        }
        let object = if depth < MAX_SAH_DEPTH {
            self.base.best_split(&refs, &bounds, &centroid_bounds)
        } else {
            None
        };
        let spatial = match &object {
            Some(split)
                if budget > 0
                    && n >= self.min_refs
                    && split.left.overlap_half_area(&split.right) > self.min_overlap =>
            {
                self.best_spatial(&refs, &bounds, budget)
            }
            _ => None,
        };
        let leaf_cost = records(n as u32, unit_shift(max_leaf)) * settings.record_cost;
        let best_cost = match (&object, &spatial) {
            (Some(o), Some(s)) => o.cost.min(s.cost),
            (Some(o), None) => o.cost,
            _ => f32::INFINITY,
        };
        if n <= max_leaf && leaf_cost <= best_cost {
            return leaf(&refs, out);
        }
        let parted = match (&object, &spatial) {
            (Some(o), Some(s)) if s.cost < o.cost => self.partition_spatial(&refs, s),
            _ => None,
        };
        let (left, right, budget) = match parted {
            Some((left, right, made)) => (left, right, budget.saturating_sub(made)),
            None => match &object {
                Some(split) => {
                    let (mid, _, _) = self.base.partition(&mut refs, split, &centroid_bounds);
                    let right = refs.split_off(mid);
                    (refs, right, budget)
                }
                None => {
                    // All centroids coincide (or the depth limit is reached): cut in half.
                    if n <= max_leaf {
                        return leaf(&refs, out);
                    }
                    let right = refs.split_off(n / 2);
                    (refs, right, budget)
                }
            },
        };
        // The budget left is shared by the references each side holds.
        let left_budget =
            (budget as u128 * left.len() as u128 / (left.len() + right.len()) as u128) as usize;
        let right_budget = budget - left_budget;
        let (left_bounds, left_centroids) = self.base.bounds_of(&left);
        let (right_bounds, right_centroids) = self.base.bounds_of(&right);

        let node_index = out.nodes.len();
        out.nodes.push(BinaryNode { bounds: bounds.bounds(), first_or_right: 0, count: 0 });
        if in_parallel(n) {
            let (mut l, mut r) = (Subtree::default(), Subtree::default());
            rayon::join(
                || {
                    let (b, c) = (left_bounds, left_centroids);
                    self.build_node(left, b, c, left_budget, depth + 1, &mut l)
                },
                || {
                    let (b, c) = (right_bounds, right_centroids);
                    self.build_node(right, b, c, right_budget, depth + 1, &mut r)
                },
            );
            out.append(l);
            out.nodes[node_index].first_or_right = out.nodes.len() as u32;
            out.append(r);
        } else {
            let (b, c) = (left_bounds, left_centroids);
            self.build_node(left, b, c, left_budget, depth + 1, out);
            out.nodes[node_index].first_or_right = out.nodes.len() as u32;
            let (b, c) = (right_bounds, right_centroids);
            self.build_node(right, b, c, right_budget, depth + 1, out);
        }
    }

    /// The cheapest spatial split of a node whose references are `refs` and box `bounds` that
    /// makes at most `budget` extra references, if any separates them.
    fn best_spatial(&self, refs: &[PrimRef], bounds: &Aabb, budget: usize) -> Option<SpatialSplit> {
        let bins = self.bins;
        let geometry = SlabGeometry::new(bounds, bins);
        let mut on_stack = [[SpatialBin::default(); 3]; MAX_SPATIAL_BINS];
        let heap: Vec<[SpatialBin; 3]>;
        let binned: &[[SpatialBin; 3]] = if in_parallel(refs.len()) {
            use rayon::prelude::*;
            let empty = || vec![[SpatialBin::default(); 3]; bins];
            heap = refs
                .par_chunks(4096)
                .map(|chunk| {
                    let mut acc = empty();
                    for r in chunk {
                        self.bin_reference(&geometry, r, &mut acc);
                    }
                    acc
                })
                .reduce(empty, |mut a, b| {
                    for (x, y) in a.iter_mut().zip(&b) {
                        for axis in 0..3 {
                            x[axis].bounds = x[axis].bounds.union(y[axis].bounds);
                            x[axis].enter += y[axis].enter;
                            x[axis].exit += y[axis].exit;
                        }
                    }
                    a
                });
            &heap
        } else {
            for r in refs {
                self.bin_reference(&geometry, r, &mut on_stack[..bins]);
            }
            &on_stack[..bins]
        };

        let n = refs.len() as u32;
        let unit = unit_shift(self.base.settings.max_leaf_size);
        let mut best: Option<(usize, usize, f32)> = None;
        for axis in (0..3).filter(|&axis| geometry.extent[axis] > 0.0) {
            // From the right: the box and count of slabs `k..`.
            let mut right_area = [0.0f32; MAX_SPATIAL_BINS];
            let mut right_count = [0u32; MAX_SPATIAL_BINS];
            let (mut right, mut count) = (Aabb::EMPTY, 0u32);
            for k in (1..bins).rev() {
                right = right.union(binned[k][axis].bounds);
                count += binned[k][axis].exit;
                right_count[k] = count;
                right_area[k] = right.half_area();
            }
            let (mut left, mut left_count) = (Aabb::EMPTY, 0u32);
            for k in 1..bins {
                left = left.union(binned[k - 1][axis].bounds);
                left_count += binned[k - 1][axis].enter;
                let right_count = right_count[k];
                if left_count == 0 || right_count == 0 {
                    continue;
                }
                let made = (left_count + right_count).saturating_sub(n);
                if made as usize > budget {
                    continue;
                }
                let cost = left.half_area() * records(left_count, unit)
                    + right_area[k] * records(right_count, unit);
                if best.is_none_or(|(_, _, c)| cost < c) {
                    best = Some((axis, k, cost));
                }
            }
        }
        let (axis, k, term) = best?;
        let settings = self.base.settings;
        let parent_area = bounds.half_area().max(f32::MIN_POSITIVE);
        Some(SpatialSplit {
            axis,
            plane: geometry.plane(axis, k),
            cost: settings.traversal_cost + term * settings.record_cost / parent_area,
        })
    }

    /// Adds reference `r` to the slabs it crosses on each axis: its part in each slab, and where
    /// it enters and leaves.
    fn bin_reference(&self, geometry: &SlabGeometry, r: &PrimRef, bins: &mut [[SpatialBin; 3]]) {
        let triangle = self.triangles[r.id() as usize];
        let b = r.bounds();
        for axis in (0..3).filter(|&axis| geometry.extent[axis] > 0.0) {
            let first = geometry.slab(axis, b.min[axis]);
            let last = geometry.slab(axis, b.max[axis]);
            bins[first][axis].enter += 1;
            bins[last][axis].exit += 1;
            let mut rest = b;
            for (k, bin) in bins[first..last].iter_mut().enumerate() {
                let plane = geometry.plane(axis, first + k + 1);
                let (part, beyond) = split_estimate(&triangle, &rest, axis, plane);
                if let Some(part) = part {
                    bin[axis].bounds = bin[axis].bounds.union(part);
                }
                match beyond {
                    Some(beyond) => rest = beyond,
                    None => {
                        rest = Aabb::EMPTY;
                        break;
                    }
                }
            }
            bins[last][axis].bounds = bins[last][axis].bounds.union(rest);
        }
    }

    /// The references of a node split at `split`'s plane: those wholly on one side go there,
    /// those across are cut in two. `None` if a side would be empty; else the two sides and how
    /// many references were added.
    fn partition_spatial(
        &self,
        refs: &[PrimRef],
        split: &SpatialSplit,
    ) -> Option<(Vec<PrimRef>, Vec<PrimRef>, usize)> {
        let (axis, plane) = (split.axis, split.plane);
        let (mut left, mut right) =
            (Vec::with_capacity(refs.len()), Vec::with_capacity(refs.len()));
        let mut made = 0;
        for r in refs {
            let b = r.bounds();
            if b.max[axis] <= plane {
                left.push(*r);
            } else if b.min[axis] >= plane {
                right.push(*r);
            } else {
                let triangle = self.triangles[r.id() as usize];
                match split_reference(triangle, &b, axis, plane) {
                    (Some(l), Some(h)) => {
                        left.push(PrimRef::new(l, r.id()));
                        right.push(PrimRef::new(h, r.id()));
                        made += 1;
                    }
                    (Some(l), None) => left.push(PrimRef::new(l, r.id())),
                    (None, Some(h)) => right.push(PrimRef::new(h, r.id())),
                    // Not reachable for a box that holds part of its triangle; kept whole.
                    (None, None) => left.push(*r),
                }
            }
        }
        (!left.is_empty() && !right.is_empty()).then_some((left, right, made))
    }
}

/// The slabs of a node's box along each axis.
struct SlabGeometry {
    min: Vec3A,
    extent: Vec3A,
    /// Slabs per unit length, slightly fewer than `bins / extent` so that the maximum lands in
    /// the last slab; zero on an axis without extent.
    scale: Vec3A,
    bins: usize,
}

impl SlabGeometry {
    fn new(bounds: &Aabb, bins: usize) -> SlabGeometry {
        let extent = bounds.max - bounds.min;
        let per_extent = bins as f32 * (1.0 - 1e-6);
        let scale = Vec3A::select(extent.cmpgt(Vec3A::ZERO), per_extent / extent, Vec3A::ZERO);
        SlabGeometry { min: bounds.min, extent, scale, bins }
    }

    /// The slab of coordinate `x` on `axis`.
    fn slab(&self, axis: usize, x: f32) -> usize {
        let position = ((x - self.min[axis]) * self.scale[axis]).max(0.0);
        (position as usize).min(self.bins - 1)
    }

    /// The plane between slabs `k − 1` and `k` on `axis`.
    fn plane(&self, axis: usize, k: usize) -> f32 {
        self.min[axis] + self.extent[axis] * (k as f32 / self.bins as f32)
    }
}

/// The boxes of the parts of `triangle` inside box `b` below and above `plane` on `axis`
/// (`None` for a side with no part), each inside `b` and conservative: every point of the
/// triangle in `b` on a side is in that side's box.
///
/// The points where the triangle's edges cross the plane are computed in `f64` and rounded
/// outward to `f32` with a margin far above `f64`'s rounding, so that each part's box holds the
/// exact crossing points.
pub(super) fn split_reference(
    triangle: [Vec3; 3],
    b: &Aabb,
    axis: usize,
    plane: f32,
) -> (Option<Aabb>, Option<Aabb>) {
    let (mut below, mut above) = (Aabb::EMPTY, Aabb::EMPTY);
    for i in 0..3 {
        let (v, w) = (triangle[i], triangle[(i + 1) % 3]);
        let (va, wa) = (v[axis], w[axis]);
        if va <= plane {
            below = below.grow(v.into());
        }
        if va >= plane {
            above = above.grow(v.into());
        }
        if (va < plane && wa > plane) || (va > plane && wa < plane) {
            let (low, high) = crossing(v, w, axis, plane);
            below = below.grow(low).grow(high);
            above = above.grow(low).grow(high);
        }
    }
    let mut below = below.intersect(b);
    below.max[axis] = below.max[axis].min(plane);
    let mut above = above.intersect(b);
    above.min[axis] = above.min[axis].max(plane);
    (below.is_valid().then_some(below), above.is_valid().then_some(above))
}

/// [`split_reference`] for the binning, which only weighs the planes: the crossing points in
/// `f32`, as they round.
#[inline]
fn split_estimate(
    triangle: &[Vec3; 3],
    b: &Aabb,
    axis: usize,
    plane: f32,
) -> (Option<Aabb>, Option<Aabb>) {
    let (mut below, mut above) = (Aabb::EMPTY, Aabb::EMPTY);
    let corners = triangle.map(Vec3A::from);
    for i in 0..3 {
        let (v, w) = (corners[i], corners[(i + 1) % 3]);
        let (va, wa) = (v[axis], w[axis]);
        if va <= plane {
            below = below.grow(v);
        }
        if va >= plane {
            above = above.grow(v);
        }
        if (va < plane && wa > plane) || (va > plane && wa < plane) {
            let p = v + (w - v) * ((plane - va) / (wa - va));
            below = below.grow(p);
            above = above.grow(p);
        }
    }
    let mut below = below.intersect(b);
    below.max[axis] = below.max[axis].min(plane);
    let mut above = above.intersect(b);
    above.min[axis] = above.min[axis].max(plane);
    (below.is_valid().then_some(below), above.is_valid().then_some(above))
}

/// The point where edge `v w` crosses `plane` on `axis`, as two corners of a box that holds it
/// exactly (on `axis`, both are the plane).
fn crossing(v: Vec3, w: Vec3, axis: usize, plane: f32) -> (Vec3A, Vec3A) {
    let t = (plane as f64 - v[axis] as f64) / (w[axis] as f64 - v[axis] as f64);
    let (mut low, mut high) = (Vec3A::ZERO, Vec3A::ZERO);
    for k in 0..3 {
        if k == axis {
            low[k] = plane;
            high[k] = plane;
            continue;
        }
        let (a, c) = (v[k] as f64, w[k] as f64);
        let p = a + (c - a) * t;
        // `f64`'s error here is below 2⁻⁵⁰ of the magnitudes; the margin is far wider, and each
        // bound then steps one `f32` outward from its rounding.
        let margin = (a.abs() + c.abs()) * 1e-12;
        low[k] = ((p - margin) as f32).next_down();
        high[k] = ((p + margin) as f32).next_up();
    }
    (low, high)
}

#[cfg(test)]
mod tests {
    use glam::{DVec3, Vec3};

    use super::*;
    use crate::bvh::build::{BuildSettings, build_triangles};
    use crate::bvh::tests::Lcg;

    /// Whether `p` is in box `b` (compared in `f64`, where `p` is exact enough).
    fn holds(b: &Aabb, p: DVec3) -> bool {
        (0..3).all(|k| b.min[k] as f64 <= p[k] && p[k] <= b.max[k] as f64)
    }

    /// Points of a triangle in `f64`: random inside, on its edges and its corners.
    fn points(triangle: [Vec3; 3], rng: &mut Lcg, count: usize) -> Vec<DVec3> {
        let [a, b, c] = triangle.map(|v| v.as_dvec3());
        let mut points = vec![a, b, c];
        for k in 0..count {
            let (mut u, mut v) = (rng.next() as f64, rng.next() as f64);
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            match k % 4 {
                0 => v = 0.0,
                1 => u = 1.0 - v,
                _ => {}
            }
            points.push(a + (b - a) * u + (c - a) * v);
        }
        points
    }

    /// A triangle for the tests: often long and thin, sometimes far from the origin (where
    /// `f32` is coarse), sometimes with corners on a grid.
    fn triangle(rng: &mut Lcg, case: usize) -> [Vec3; 3] {
        let offset = if case.is_multiple_of(5) { rng.vec() * 1e4 } else { rng.vec() };
        let a = offset + rng.vec() - 0.5;
        let long = (rng.vec() - 0.5) * [1.0, 10.0, 1000.0][case % 3];
        let thin = (rng.vec() - 0.5) * [1.0, 1e-2, 1e-4][case / 3 % 3];
        let t = [a, a + long, a + long * 0.5 + thin];
        if case.is_multiple_of(7) { t.map(|v| (v * 4.0).round() / 4.0) } else { t }
    }

    /// A part's box holds every point of its triangle inside the reference's box on its side of
    /// the plane, and stays inside that box and on its side: random, long thin and far-off
    /// triangles, boxes that cut them, planes at random and through corners.
    #[test]
    fn parts_hold_every_point_of_their_side() {
        let mut rng = Lcg(17);
        let (mut both, mut checked) = (0, 0);
        for case in 0..20_000 {
            let t = triangle(&mut rng, case);
            if !hittable(t) {
                continue;
            }
            let whole = {
                let [a, b, c] = t.map(Vec3A::from);
                Aabb { min: a.min(b).min(c), max: a.max(b).max(c) }
            };
            // Half the references are already cut: their box a random part of the triangle's.
            let b = if case % 2 == 0 {
                whole
            } else {
                let (p, q) = (rng.vec(), rng.vec());
                let at = |f: Vec3| whole.min + (whole.max - whole.min) * Vec3A::from(f);
                let (p, q) = (at(p), at(q));
                Aabb { min: p.min(q), max: p.max(q) }
            };
            let axis = case % 3;
            let plane = match case % 4 {
                0 => t[case % 3][axis],
                _ => b.min[axis] + (b.max[axis] - b.min[axis]) * rng.next(),
            };
            let (below, above) = split_reference(t, &b, axis, plane);
            for part in [below, above].iter().flatten() {
                assert!(
                    part.is_valid() && b.min.cmple(part.min).all() && part.max.cmple(b.max).all()
                );
            }
            if let Some(p) = below {
                assert!(p.max[axis] <= plane);
            }
            if let Some(p) = above {
                assert!(p.min[axis] >= plane);
            }
            both += (below.is_some() && above.is_some()) as usize;
            // Where the edges cross the plane (the parts' extreme points), and points all over.
            let mut points = points(t, &mut rng, 64);
            for i in 0..3 {
                let (v, w) = (t[i].as_dvec3(), t[(i + 1) % 3].as_dvec3());
                let (va, wa, p) = (v[axis], w[axis], plane as f64);
                if (va - p) * (wa - p) < 0.0 {
                    let mut x = v + (w - v) * ((p - va) / (wa - va));
                    x[axis] = p;
                    points.push(x);
                }
            }
            for p in points.into_iter().filter(|&p| holds(&b, p)) {
                checked += 1;
                if p[axis] <= plane as f64 {
                    assert!(below.is_some_and(|part| holds(&part, p)), "case {case}: {p} below");
                }
                if p[axis] >= plane as f64 {
                    assert!(above.is_some_and(|part| holds(&part, p)), "case {case}: {p} above");
                }
            }
        }
        assert!(both > 5_000 && checked > 200_000, "{both} cut, {checked} points");
    }

    /// Long thin triangles across a scene (strips, fans and slivers) and small ones among them.
    pub(in crate::bvh) fn slivers(count: usize, seed: u64) -> Vec<[Vec3; 3]> {
        let mut rng = Lcg(seed);
        (0..count)
            .map(|case| {
                let t = triangle(&mut rng, case);
                // Most in a unit scene, so that the long ones cross it.
                if case.is_multiple_of(5) { t.map(|v| v * 1e-4) } else { t }
            })
            .collect()
    }

    /// The spatial build's binary tree: splits were made (within the budget); no leaf holds a
    /// triangle twice; every box holds its children's; and every point of every triangle is in
    /// the box of a leaf that holds it.
    #[test]
    fn spatial_trees_cover_every_triangle_once_per_leaf() {
        for (count, budget) in [(600, 1.0), (3000, 0.2)] {
            let triangles = slivers(count, count as u64);
            let settings =
                BuildSettings { spatial_splits: budget, max_leaf_size: 4, ..BuildSettings::HIGH };
            let bvh = build_triangles(&triangles, &settings);
            let prims = triangles.iter().filter(|&&t| hittable(t)).count();
            assert_eq!(bvh.prims, prims);
            let made = bvh.order.len() - prims;
            assert!(made > 0 && made as f32 <= budget * prims as f32, "{made} extra references");
            let contains = |outer: &crate::bvh::Bounds, inner: &crate::bvh::Bounds| {
                outer.min.cmple(inner.min).all() && inner.max.cmple(outer.max).all()
            };
            let mut leaves_of = vec![Vec::new(); triangles.len()];
            for (index, node) in bvh.nodes.iter().enumerate() {
                if node.is_leaf() {
                    let range =
                        node.first_or_right as usize..(node.first_or_right + node.count) as usize;
                    let ids = &bvh.order[range];
                    for (k, &id) in ids.iter().enumerate() {
                        assert!(!ids[..k].contains(&id), "triangle {id} twice in leaf {index}");
                        leaves_of[id as usize].push(node.bounds);
                    }
                } else {
                    let (l, r) = (&bvh.nodes[index + 1], &bvh.nodes[node.first_or_right as usize]);
                    assert!(contains(&node.bounds, &l.bounds) && contains(&node.bounds, &r.bounds));
                }
            }
            let mut rng = Lcg(5);
            let in_box = |b: &crate::bvh::Bounds, p: DVec3| {
                (0..3).all(|k| b.min[k] as f64 <= p[k] && p[k] <= b.max[k] as f64)
            };
            for (id, &t) in triangles.iter().enumerate().filter(|&(_, &t)| hittable(t)) {
                for p in points(t, &mut rng, 16) {
                    assert!(
                        leaves_of[id].iter().any(|b| in_box(b, p)),
                        "triangle {id}'s point {p} is in none of its leaves"
                    );
                }
            }
        }
    }

    /// The 8-wide trees read off a spatial build (both collapses; the collapse of least cost
    /// joins subtrees that hold parts of one triangle into one leaf): each leaf holds a triangle
    /// once, every triangle is in a leaf, and `references` counts the leaves' triangles.
    #[test]
    fn wide_leaves_hold_each_triangle_once() {
        use crate::bvh::Bvh;
        use crate::bvh::build::Collapse;
        use crate::bvh::node::{Child, decode};
        let (mut joined, mut cut) = (0, 0);
        let collapses = [Collapse::Greedy, Collapse::Optimal { binary_leaf_size: 1 }];
        // Small scenes try spatial splits on small nodes too, which the collapse may join.
        for (triangles, collapse) in [24, 40, 64, 2000]
            .into_iter()
            .flat_map(|n| collapses.map(|c| (slivers(n, n as u64), c)))
        {
            let settings = BuildSettings { spatial_splits: 1.0, collapse, ..BuildSettings::HIGH };
            let bvh = Bvh::build(&triangles, &settings);
            let mut seen = vec![0usize; triangles.len()];
            let mut references = 0;
            for node in &bvh.wide.nodes {
                for &child in &node.children {
                    let Child::Leaf(offset) = decode(child) else { continue };
                    let ids: Vec<u32> =
                        bvh.wide.leaves.leaf_triangles(offset).map(|(id, _)| id).collect();
                    for (k, id) in ids.iter().enumerate() {
                        assert!(
                            !ids[..k].contains(id),
                            "{collapse:?}: triangle {id} twice in a leaf"
                        );
                        seen[*id as usize] += 1;
                    }
                    references += ids.len();
                }
            }
            let stats = bvh.stats();
            assert_eq!(references, stats.references);
            cut += stats.references - stats.indexed_triangles;
            for (id, &t) in triangles.iter().enumerate() {
                assert_eq!(seen[id] > 0, hittable(t), "{collapse:?}: triangle {id}");
            }
            // Parts of one triangle that the collapse joined, written once: the binary tree
            // the BVH was read off (as `Bvh::build` builds it) has more references.
            let binary_leaf = match collapse {
                Collapse::Optimal { binary_leaf_size } => binary_leaf_size,
                Collapse::Greedy => settings.max_leaf_size,
            };
            let binary = build_triangles(
                &triangles,
                &BuildSettings { max_leaf_size: binary_leaf, ..settings },
            );
            joined += binary.order.len() - stats.references;
        }
        assert!(cut > 0, "no triangle was cut");
        assert!(joined > 0, "no leaf joined parts of a triangle: the test would see no duplicate");
    }

    /// The budget is shared the same way whatever the threads: the same tree on a pool of one
    /// thread and of two (nodes above `PARALLEL_MIN` references are built in parallel).
    #[test]
    fn spatial_trees_are_the_same_on_any_number_of_threads() {
        let triangles = slivers(40_000, 3);
        let settings = BuildSettings { spatial_splits: 0.3, ..BuildSettings::HIGH };
        let on = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| build_triangles(&triangles, &settings))
        };
        let (one, two) = (on(1), on(2));
        assert!(one.order.len() > one.prims, "spatial splits were made");
        assert_eq!(one.order, two.order);
        let key = |n: &BinaryNode| {
            (n.bounds.min.to_array(), n.bounds.max.to_array(), n.first_or_right, n.count)
        };
        assert!(one.nodes.iter().map(key).eq(two.nodes.iter().map(key)));
    }
}
