//! Moving geometry without a rebuild: the same tree, its boxes recomputed bottom-up.
//!
//! An animated or skinned mesh keeps its triangles and only moves its vertices. [`Bvh::refit`]
//! writes the new vertices into the leaves' records anew (and the flat list of a small scene), then
//! recomputes every child box from the leaves up. Nodes are stored depth first, every child after
//! its parent, so one pass over the nodes from last to first sees each child before its parent.
//! The answers stay exactly brute force's for the new positions (the box test only needs boxes
//! that contain their triangles); only the tree's quality can suffer if the triangles move far
//! from where they were built, which a rebuild restores.
//!
//! A triangle that loses its area or gets a non-finite vertex is parked: it gets NaN
//! vertices, which no ray hits (as brute force never hits it). A triangle that was left out of
//! the build for those reasons and now has area has no place in the tree: refit refuses, and the
//! caller rebuilds.

use glam::Vec3;

use super::Bvh;
use super::bounds::Bounds;
use super::build::hittable;
use super::leaf::Leaves;
use super::node::{Child, EMPTY, WIDTH, decode, encode_leaf};
use super::traverse::flat::Flat;

/// Why [`Bvh::refit`] could not move the triangles.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RefitError {
    /// The tree was built over another number of triangles.
    TriangleCount {
        /// Triangles at build.
        built: usize,
        /// Triangles given to refit.
        given: usize,
    },
    /// A triangle the build left out (zero area or a non-finite vertex) now has area: rebuild.
    NewTriangle(u32),
}

impl std::fmt::Display for RefitError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RefitError::TriangleCount { built, given } => {
                write!(f, "the BVH holds {built} triangles, not {given}: rebuild it")
            }
            RefitError::NewTriangle(i) => write!(
                f,
                "triangle {i} had no area when the BVH was built and has now: rebuild the BVH"
            ),
        }
    }
}

impl std::error::Error for RefitError {}

impl Bvh {
    /// Moves the triangles to `triangles` (the same ones, in the same order, with new vertices)
    /// and recomputes the boxes, keeping the tree (see the module documentation). Runs in time
    /// linear in the tree's size, a fraction of a build.
    ///
    /// # Errors
    /// If `triangles` has another length than at build, or a triangle the build left out now has
    /// area ([`RefitError`]); the BVH is then unchanged.
    pub fn refit(&mut self, triangles: &[[Vec3; 3]]) -> Result<(), RefitError> {
        if triangles.len() != self.stats.triangles {
            return Err(RefitError::TriangleCount {
                built: self.stats.triangles,
                given: triangles.len(),
            });
        }
        let leaf_refs: Vec<(usize, usize, u32)> = (self.wide.nodes.iter().enumerate())
            .flat_map(|(index, node)| {
                node.children.iter().enumerate().filter_map(move |(k, &child)| {
                    match decode(child) {
                        Child::Leaf(offset) => Some((index, k, offset)),
                        _ => None,
                    }
                })
            })
            .collect();
        let mut in_tree = vec![false; triangles.len()];
        for &(_, _, offset) in &leaf_refs {
            for (id, _) in self.wide.leaves.leaf_triangles(offset) {
                in_tree[id as usize] = true;
            }
        }
        if let Some(i) = (0..triangles.len()).find(|&i| !in_tree[i] && hittable(triangles[i])) {
            return Err(RefitError::NewTriangle(i as u32));
        }
        // The leaves written anew (which vertices are shared may change): hittable triangles as
        // given, the rest parked on NaN.
        let parked = [Vec3::NAN; 3];
        let mut indexed = 0;
        let mut leaves = Leaves::with_capacity(triangles.len());
        let mut child_bounds = vec![[Bounds::EMPTY; WIDTH]; self.wide.nodes.len()];
        let mut leaf = Vec::new();
        for &(index, k, offset) in &leaf_refs {
            leaf.clear();
            let mut bounds = Bounds::EMPTY;
            for (id, _) in self.wide.leaves.leaf_triangles(offset) {
                let triangle = triangles[id as usize];
                if hittable(triangle) {
                    indexed += 1;
                    bounds = bounds.union(Bounds::of_triangle(triangle));
                    leaf.push((id, triangle));
                } else {
                    leaf.push((id, parked));
                }
            }
            self.wide.nodes[index].children[k] = encode_leaf(leaves.push_leaf(&leaf));
            child_bounds[index][k] = bounds;
        }
        self.wide.leaves = leaves;
        if let Some(flat) = &mut self.flat {
            flat.refit(triangles);
        }
        // Boxes, children before parents.
        let mut node_bounds = vec![Bounds::EMPTY; self.wide.nodes.len()];
        for index in (0..self.wide.nodes.len()).rev() {
            let node = &self.wide.nodes[index];
            let mut union = Bounds::EMPTY;
            for (k, &child) in node.children.iter().enumerate() {
                if let Child::Node(child) = decode(child) {
                    child_bounds[index][k] = node_bounds[child as usize];
                }
                union = union.union(child_bounds[index][k]);
            }
            node_bounds[index] = union;
        }
        for (node, bounds) in self.wide.nodes.iter_mut().zip(&child_bounds) {
            for (k, &b) in bounds.iter().enumerate() {
                if node.children[k] != EMPTY {
                    node.set_bounds(k, b);
                }
            }
        }
        self.wide.root = self.wide.root_bounds();
        self.stats.indexed_triangles = indexed;
        self.stats.leaf_bytes = self.wide.leaves.bytes();
        // Moved corners may be shared differently.
        self.stats.flat_bytes = self.flat.as_ref().map_or(0, Flat::bytes);
        Ok(())
    }
}

impl Flat {
    /// The flat list's part of [`Bvh::refit`]: every lane's triangle as given, or parked on NaN.
    pub(super) fn refit(&mut self, triangles: &[[Vec3; 3]]) {
        self.move_triangles(|id| {
            let triangle = triangles[id as usize];
            if hittable(triangle) { triangle } else { [Vec3::NAN; 3] }
        });
    }
}
