//! What the top level is made of: the instances as it sees them ([`Placed`]), its nodes
//! ([`Node`]), and the margin by which a box grows for a ray ([`Margin`]), shared by its build
//! (`build.rs`), its box rows (`rows.rs`) and its packets' box test (`lanes.rs`).

use crate::bvh::Bounds;
use crate::geometry::Placement;

/// How far, in units of `f32::EPSILON · cond(M) · (|o|∞ + reach)`, the world ray and the
/// placed image of its object-space copy may drift apart: the rounding of `M⁻¹` itself and of
/// `M⁻¹·o` (a few ulps each, times the condition number when mapped back), of `M⁻¹`'s
/// translation (`reach` includes `|T|∞`) and of `M⁻¹·d` over the ray's way to the instance
/// (`reach` includes the box's coordinates), with a wide margin.
pub(super) const RAY_ERROR: f32 = 64.0;

/// How much a top-level box grows for a ray from `o`: `scale · (|o|∞ + reach)`, enough that a
/// ray which hits a triangle in an instance's space always finds the instance's box in the
/// world, whatever the rounding of the transform (the bottom level decides on the
/// object-space ray, exactly as the reference does). An inner node's is the largest of its
/// subtree's, so it grows at least as much as any box below it.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Margin {
    /// `RAY_ERROR · ε · cond(M)`; 0 for triangles stored in the world.
    pub(super) scale: f32,
    /// The largest coordinate of the box or of `M`'s translation.
    pub(super) reach: f32,
}

impl Margin {
    #[inline(always)]
    pub(super) fn pad(&self, origin_size: f32) -> f32 {
        self.scale * (origin_size + self.reach)
    }

    pub(super) fn max(self, other: Margin) -> Margin {
        Margin { scale: self.scale.max(other.scale), reach: self.reach.max(other.reach) }
    }
}

/// An instance as the top level sees it.
pub(super) struct Placed {
    pub(super) bottom: u32,
    /// The scene index of the bottom's triangle 0 here.
    pub(super) first: u32,
    /// How the bottom's triangles are placed, or `None` for world-space triangles.
    pub(super) placement: Option<Placement>,
    pub(super) bounds: Bounds,
    pub(super) margin: Margin,
}

/// A node of the top level's binary tree, depth first: an inner node's left child follows it.
pub(super) struct Node {
    pub(super) bounds: Bounds,
    /// The largest margin below it.
    pub(super) margin: Margin,
    /// A leaf's first entry in `placed`, or an inner node's right child.
    pub(super) index: u32,
    /// A leaf's entry count; 0 for an inner node.
    pub(super) count: u32,
}

/// The most rays traced together through the top level: one bit each in a mask.
pub(super) const PACKET: usize = 64;
