//! The binary tree collapsed into the 8-wide one, so that one node test covers eight boxes.
//!
//! Each wide node takes a binary node's two children and repeatedly opens the interior child of
//! largest surface area until it has eight children or only leaves are left, so that the boxes a
//! ray is most likely to enter are tested together (Wald et al., "Getting Rid of Packets", 2008;
//! Embree's BVH8 builder does the same). Nodes are laid out depth first, each subtree contiguous.

use glam::Vec3;

use super::BinaryBvh;
use crate::bvh::bounds::Bounds;
use crate::bvh::leaf::Leaves;
use crate::bvh::node::{WIDTH, WideBvh, WideNode, encode_leaf};

/// Collapses `binary` (built over `prim_ids`' triangles) into a wide BVH.
///
/// `triangle(i)` gives the vertices of build primitive `i`, and `prim_ids[i]` its caller's index.
pub(crate) fn collapse(
    binary: &BinaryBvh,
    triangle: impl Fn(u32) -> [Vec3; 3],
    prim_ids: impl Fn(u32) -> u32,
) -> WideBvh {
    Collapser { binary, triangle: &triangle, prim_ids: &prim_ids }.read()
}

struct Collapser<'a, T, I> {
    binary: &'a BinaryBvh,
    triangle: &'a T,
    prim_ids: &'a I,
}

impl<T: Fn(u32) -> [Vec3; 3], I: Fn(u32) -> u32> Reading for Collapser<'_, T, I> {
    fn binary(&self) -> &BinaryBvh {
        self.binary
    }

    /// Opens the interior child of largest area until there are eight.
    fn children(&self, node: usize) -> Vec<usize> {
        let nodes = &self.binary.nodes;
        let mut children = vec![node + 1, nodes[node].first_or_right as usize];
        while children.len() < WIDTH {
            // Open the interior child of largest area.
            let widest = children
                .iter()
                .enumerate()
                .filter(|(_, c)| !nodes[**c].is_leaf())
                .max_by(|a, b| {
                    nodes[*a.1].bounds.half_area().total_cmp(&nodes[*b.1].bounds.half_area())
                })
                .map(|(k, _)| k);
            let Some(k) = widest else { break };
            let opened = children.swap_remove(k);
            children.push(opened + 1);
            children.push(nodes[opened].first_or_right as usize);
        }
        children
    }

    fn is_leaf(&self, child: usize) -> bool {
        self.binary.nodes[child].is_leaf()
    }

    /// Writes binary leaf `node`'s triangles as records.
    fn emit_leaf(&self, node: usize, wide: &mut WideBvh) -> u32 {
        let leaf = self.binary.nodes[node];
        let first = leaf.first_or_right as usize;
        let prims = &self.binary.order[first..first + leaf.count as usize];
        push_leaf(wide, prims, self.triangle, self.prim_ids)
    }
}

/// How a wide tree is read off a binary one (the greedy collapse and the one of least cost):
/// which binary nodes become a wide node's children, and which of those are leaves.
pub(super) trait Reading {
    /// The binary tree read.
    fn binary(&self) -> &BinaryBvh;

    /// The binary nodes under interior node `node` that become its wide node's children (at
    /// most eight).
    fn children(&self, node: usize) -> Vec<usize>;

    /// Whether binary node `child` becomes a leaf.
    fn is_leaf(&self, child: usize) -> bool;

    /// Writes binary node `child`'s triangles as one leaf; returns its reference.
    fn emit_leaf(&self, child: usize, wide: &mut WideBvh) -> u32;

    /// The whole wide tree: a root (node 0) filled from the binary root, a root with one leaf
    /// if that is a leaf, and an empty root for an empty tree.
    fn read(&self) -> WideBvh {
        let binary = self.binary();
        let mut wide = WideBvh {
            nodes: Vec::with_capacity(binary.nodes.len() / 4 + 1),
            leaves: Leaves::with_capacity(binary.order.len()),
            root: Bounds::EMPTY,
        };
        wide.nodes.push(WideNode::UNUSED);
        if binary.nodes.is_empty() {
            return wide;
        }
        if self.is_leaf(0) {
            // A single leaf: a root with one child.
            let child = self.emit_leaf(0, &mut wide);
            wide.nodes[0].children[0] = child;
            wide.nodes[0].set_bounds(0, binary.nodes[0].bounds);
        } else {
            self.emit_node(0, 0, &mut wide);
        }
        wide.root = wide.root_bounds();
        wide
    }

    /// Fills wide node `slot` from binary interior node `node`, and the subtrees under it.
    fn emit_node(&self, node: usize, slot: usize, wide: &mut WideBvh) {
        let mut children = self.children(node);
        debug_assert!(children.len() <= WIDTH);
        // Keep the depth-first order of the binary tree among siblings.
        children.sort_unstable();
        for (k, &child) in children.iter().enumerate() {
            let reference = if self.is_leaf(child) {
                self.emit_leaf(child, wide)
            } else {
                let index = wide.nodes.len();
                wide.nodes.push(WideNode::UNUSED);
                self.emit_node(child, index, wide);
                index as u32
            };
            wide.nodes[slot].children[k] = reference;
            wide.nodes[slot].set_bounds(k, self.binary().nodes[child].bounds);
        }
    }
}

/// Writes build primitives `prims` (`triangle(i)` the vertices of primitive `i`, `prim_ids(i)`
/// its caller's index) as one leaf's records; returns the leaf's reference.
pub(super) fn push_leaf(
    wide: &mut WideBvh,
    prims: &[u32],
    triangle: &impl Fn(u32) -> [Vec3; 3],
    prim_ids: &impl Fn(u32) -> u32,
) -> u32 {
    let triangles: Vec<(u32, [Vec3; 3])> =
        prims.iter().map(|&prim| (prim_ids(prim), triangle(prim))).collect();
    encode_leaf(wide.leaves.push_leaf(&triangles))
}
