//! The 8-wide BVH: the binary tree collapsed so that one node test covers eight boxes.
//!
//! # Node layout
//! A [`WideNode`] is 224 bytes, 32-byte aligned: six rows of eight floats, the boxes' planes stored
//! plane by plane (`min x` of all eight children, then `min y`, `min z`, `max x`, `max y`,
//! `max z`), then eight child references. One AVX load fetches a plane of all eight children.
//!
//! A child reference is a `u32`:
//! - `EMPTY` (`u32::MAX`): an unused slot; its box is empty (`min = +∞`, `max = −∞`), so it is
//!   never hit and needs no special case in the kernels;
//! - top bit clear: the index of an interior [`WideNode`];
//! - top bit set: a leaf; bits 0..=30 hold the word offset of its first record in the leaf arena
//!   ([`Leaves`], which describes the records), below `2³¹ − 1` so that no leaf encodes as
//!   `EMPTY`.
//!
//! For example `0x8000_0011` is a leaf whose first record starts at word 17 of the arena.
//!
//! # Collapsing
//! Each wide node takes a binary node's two children and repeatedly opens the interior child of
//! largest surface area until it has eight children or only leaves are left, so that the boxes a
//! ray is most likely to enter are tested together (Wald et al., "Getting Rid of Packets", 2008;
//! Embree's BVH8 builder does the same). Nodes are laid out depth first, each subtree contiguous.

use glam::Vec3;

use super::bounds::Bounds;
use super::build::BinaryBvh;
use super::leaf::Leaves;

/// Children per node.
pub(crate) const WIDTH: usize = 8;

/// Eight child boxes and references.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub(crate) struct WideNode {
    /// `planes[p][child]`, `p` = min x, min y, min z, max x, max y, max z.
    pub planes: [[f32; WIDTH]; 6],
    pub children: [u32; WIDTH],
}

pub(crate) const EMPTY: u32 = u32::MAX;
const LEAF_BIT: u32 = 1 << 31;
const OFFSET_MASK: u32 = LEAF_BIT - 1;
/// The most triangles one leaf may hold (packets cull a leaf's triangles in one `u64` mask).
pub(crate) const MAX_LEAF_TRIANGLES: usize = 64;

/// A decoded child reference.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Child {
    Empty,
    Node(u32),
    /// The word offset of the leaf's first record in [`WideBvh::leaves`].
    Leaf(u32),
}

#[inline]
pub(crate) fn decode(child: u32) -> Child {
    if child == EMPTY {
        Child::Empty
    } else if child & LEAF_BIT == 0 {
        Child::Node(child)
    } else {
        Child::Leaf(child & OFFSET_MASK)
    }
}

pub(crate) fn encode_leaf(offset: u32) -> u32 {
    // `offset = OFFSET_MASK` would encode as `EMPTY`.
    assert!(offset < OFFSET_MASK, "leaf arena beyond 2^31 words: too many triangles for one BVH");
    LEAF_BIT | offset
}

impl WideNode {
    const UNUSED: WideNode = WideNode {
        planes: [
            [f32::INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
        ],
        children: [EMPTY; WIDTH],
    };

    /// The box of child `slot`.
    pub fn bounds(&self, slot: usize) -> Bounds {
        let p = &self.planes;
        Bounds {
            min: Vec3::new(p[0][slot], p[1][slot], p[2][slot]),
            max: Vec3::new(p[3][slot], p[4][slot], p[5][slot]),
        }
    }

    pub(crate) fn set_bounds(&mut self, slot: usize, b: Bounds) {
        for axis in 0..3 {
            self.planes[axis][slot] = b.min[axis];
            self.planes[3 + axis][slot] = b.max[axis];
        }
    }
}

/// The flattened wide tree and its leaf triangles.
pub(crate) struct WideBvh {
    /// Depth first; the root is node 0 (a tree always has a root node, possibly all empty).
    pub nodes: Vec<WideNode>,
    /// The leaves' records: their triangles and the caller's indices of them.
    pub leaves: Leaves,
    /// The box around everything (the root's children): single rays' box margins are bounded
    /// inside it ([`RayBoxTest::margin`](super::RayBoxTest::margin)).
    pub root: Bounds,
}

impl WideBvh {
    /// The union of the root's child boxes.
    pub(crate) fn root_bounds(&self) -> Bounds {
        (0..WIDTH).fold(Bounds::EMPTY, |b, k| b.union(self.nodes[0].bounds(k)))
    }
}

/// Collapses `binary` (built over `prim_ids`' triangles) into a wide BVH.
///
/// `triangle(i)` gives the vertices of build primitive `i`, and `prim_ids[i]` its caller's index.
pub(crate) fn collapse(
    binary: &BinaryBvh,
    triangle: impl Fn(u32) -> [Vec3; 3],
    prim_ids: impl Fn(u32) -> u32,
) -> WideBvh {
    let mut wide = WideBvh {
        nodes: Vec::with_capacity(binary.nodes.len() / 4 + 1),
        leaves: Leaves::with_capacity(binary.order.len()),
        root: Bounds::EMPTY,
    };
    wide.nodes.push(WideNode::UNUSED);
    if binary.nodes.is_empty() {
        return wide;
    }
    let collapser = Collapser { binary, triangle: &triangle, prim_ids: &prim_ids };
    if binary.nodes[0].is_leaf() {
        // A single leaf: a root with one child.
        let child = collapser.emit_leaf(0, &mut wide);
        wide.nodes[0].children[0] = child;
        wide.nodes[0].set_bounds(0, binary.nodes[0].bounds);
    } else {
        collapser.emit_node(0, 0, &mut wide);
    }
    wide.root = wide.root_bounds();
    wide
}

struct Collapser<'a, T, I> {
    binary: &'a BinaryBvh,
    triangle: &'a T,
    prim_ids: &'a I,
}

impl<T: Fn(u32) -> [Vec3; 3], I: Fn(u32) -> u32> Collapser<'_, T, I> {
    /// Fills wide node `slot` from binary interior node `node`.
    fn emit_node(&self, node: usize, slot: usize, wide: &mut WideBvh) {
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
        // Keep the depth-first order of the binary tree among siblings.
        children.sort_unstable();
        for (k, &child) in children.iter().enumerate() {
            let reference = if nodes[child].is_leaf() {
                self.emit_leaf(child, wide)
            } else {
                let index = wide.nodes.len();
                wide.nodes.push(WideNode::UNUSED);
                self.emit_node(child, index, wide);
                index as u32
            };
            wide.nodes[slot].children[k] = reference;
            wide.nodes[slot].set_bounds(k, nodes[child].bounds);
        }
    }

    /// Writes binary leaf `node`'s triangles as records; returns its reference.
    fn emit_leaf(&self, node: usize, wide: &mut WideBvh) -> u32 {
        let leaf = self.binary.nodes[node];
        let first = leaf.first_or_right as usize;
        let prims = &self.binary.order[first..first + leaf.count as usize];
        let triangles: Vec<(u32, [Vec3; 3])> =
            prims.iter().map(|&prim| ((self.prim_ids)(prim), (self.triangle)(prim))).collect();
        encode_leaf(wide.leaves.push_leaf(&triangles))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn references_round_trip() {
        assert_eq!(decode(encode_leaf(17)), Child::Leaf(17));
        assert_eq!(encode_leaf(17), 0x8000_0011);
        assert_eq!(decode(encode_leaf(OFFSET_MASK - 1)), Child::Leaf(OFFSET_MASK - 1));
        assert_eq!(decode(7), Child::Node(7));
        assert_eq!(decode(EMPTY), Child::Empty);
    }

    #[test]
    fn unused_slots_have_empty_boxes() {
        assert!(WideNode::UNUSED.bounds(3).is_empty());
        assert_eq!(std::mem::size_of::<WideNode>(), 224);
    }
}
