//! The 8-wide tree's layout: nodes of eight boxes and eight child references, tested by one
//! kernel call each (`node/kernel.rs`); the build makes them by collapsing a binary tree
//! (`build/collapse.rs`, greedy, or `build/optimal.rs`, at the least SAH cost).
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

use glam::Vec3;

pub(crate) mod kernel;

use crate::bvh::bounds::Bounds;
use crate::bvh::leaf::Leaves;

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
    pub(crate) const UNUSED: WideNode = WideNode {
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
