//! Building the top level: the instances' boxes, grown for the rounding of their transforms,
//! and a binary tree over them by the surface area heuristic.

use glam::{Affine3A, Vec3};

use super::top::{Margin, Node, Placed};
use crate::bvh::Bounds;

/// The most instances in a top-level leaf.
const LEAF_SIZE: usize = 1;

/// A box grown by a small margin: the instance's transform and the ray's are both rounded, so
/// an object-space hit at the very edge of the mesh must still find its world box. `size`
/// bounds the terms its corners were computed from (`|A|·|p| + |T|`, 0 for corners as
/// stored): where a far-off mesh is placed back near the origin, they dwarf the result.
pub(super) fn padded(bounds: Bounds, size: f32) -> Bounds {
    if bounds.is_empty() {
        return bounds;
    }
    let scale = (bounds.max - bounds.min).max_element()
        + bounds.min.abs().max(bounds.max.abs()).max_element()
        + size;
    let pad = Vec3::splat(scale * 1e-5);
    Bounds { min: bounds.min - pad, max: bounds.max + pad }
}

/// The box around `bounds` moved by `m`: its eight corners' box.
pub(super) fn transformed(bounds: &Bounds, m: &Affine3A) -> Bounds {
    if bounds.is_empty() {
        return *bounds;
    }
    (0..8).fold(Bounds::EMPTY, |b, corner| {
        let pick = |axis: usize| {
            if corner >> axis & 1 == 0 { bounds.min[axis] } else { bounds.max[axis] }
        };
        b.grow(m.transform_point3(Vec3::new(pick(0), pick(1), pick(2))))
    })
}

/// How deep the top level splits by the surface area heuristic; below, it halves the instances
/// (median splits), so that no tree is deeper than `SAH_DEPTH + 32` and the traversal stacks
/// (`STACK`) cannot overflow, however the instances lie (a row of growing boxes would make the
/// heuristic split off one at a time).
pub(super) const SAH_DEPTH: u32 = 32;

/// Builds the top level over `placed[start..end]`, splitting where the surface area heuristic
/// is least (a full sweep over the boxes sorted by centre on each axis: instances are few), or
/// in the middle below [`SAH_DEPTH`], down to one instance a leaf; returns the node's index.
pub(super) fn build_top(
    placed: &mut [Placed],
    (start, end): (usize, usize),
    depth: u32,
    nodes: &mut Vec<Node>,
) -> u32 {
    let bounds = placed[start..end].iter().fold(Bounds::EMPTY, |b, p| b.union(p.bounds));
    let margin = placed[start..end].iter().fold(Margin::default(), |m, p| m.max(p.margin));
    let index = nodes.len() as u32;
    nodes.push(Node { bounds, margin, index: start as u32, count: (end - start) as u32 });
    if end - start <= LEAF_SIZE {
        return index;
    }
    // The split (axis, first index of the right side) of least cost; by default the middle
    // along the axis where the centres spread most.
    let centres = placed[start..end].iter().fold(Bounds::EMPTY, |b, p| b.grow(p.bounds.centroid()));
    let mut best = (f32::INFINITY, centres.longest_axis(), start + (end - start) / 2);
    let mut right_areas = vec![0.0f32; end - start];
    for axis in (0..3).filter(|_| depth < SAH_DEPTH) {
        let range = &mut placed[start..end];
        range.sort_unstable_by(|a, b| {
            a.bounds.centroid()[axis].total_cmp(&b.bounds.centroid()[axis])
        });
        let mut grown = Bounds::EMPTY;
        for k in (1..range.len()).rev() {
            grown = grown.union(range[k].bounds);
            right_areas[k] = grown.half_area();
        }
        let mut grown = Bounds::EMPTY;
        for k in 1..range.len() {
            grown = grown.union(range[k - 1].bounds);
            let cost = grown.half_area() * k as f32 + right_areas[k] * (range.len() - k) as f32;
            if cost < best.0 {
                best = (cost, axis, start + k);
            }
        }
    }
    let (_, axis, middle) = best;
    placed[start..end]
        .sort_unstable_by(|a, b| a.bounds.centroid()[axis].total_cmp(&b.bounds.centroid()[axis]));
    build_top(placed, (start, middle), depth + 1, nodes);
    let right = build_top(placed, (middle, end), depth + 1, nodes);
    nodes[index as usize].index = right;
    nodes[index as usize].count = 0;
    index
}
