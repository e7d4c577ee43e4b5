//! How a BVH is built: the binned SAH's bins, leaf sizes and costs, and the flat list of small
//! scenes. The presets trade build time for tracing speed; none changes the answers.

use crate::bvh::node::MAX_LEAF_TRIANGLES;

/// How a BVH is built: a trade of build time for tracing speed. Never changes the answers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildSettings {
    /// Bins per axis for the SAH sweep (2 to 256): more bins find better splits, slower.
    pub bins: usize,
    /// The most triangles in a leaf (1 to 64). A leaf's records of up to eight triangles are
    /// tested one pass each.
    pub max_leaf_size: usize,
    /// Cost of entering a node, relative to `record_cost`.
    pub traversal_cost: f32,
    /// Cost of testing one leaf record (up to eight triangles over up to sixteen vertices).
    pub record_cost: f32,
    /// Scenes of at most this many triangles (of non-zero area) also keep them in a flat list,
    /// and single rays test them all, sixteen per instruction, instead of walking the tree
    /// (`flat`): faster for a few dozen triangles. `0` always walks the tree; at most
    /// [`MAX_FLAT_LIMIT`](Self::MAX_FLAT_LIMIT) (larger limits are clamped to it).
    pub flat_limit: usize,
    /// How the binary tree becomes the 8-wide one.
    pub collapse: Collapse,
}

/// How the binary tree becomes the 8-wide one. Never changes the answers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Collapse {
    /// Open the child of largest area until a node has eight (`build/collapse.rs`); the binary
    /// build's leaves are the wide tree's.
    #[default]
    Greedy,
    /// The cut of the binary tree into wide nodes and leaves of least surface-area cost, by
    /// dynamic programming (`build/optimal.rs`). The binary tree is built with leaves of at most
    /// `binary_leaf_size` triangles (1 to [`max_leaf_size`](BuildSettings::max_leaf_size)), which
    /// the collapse may merge into leaves of up to `max_leaf_size`: smaller binary leaves leave
    /// it more choice and take longer to build.
    Optimal {
        /// The most triangles in a leaf of the binary tree.
        binary_leaf_size: usize,
    },
}

impl BuildSettings {
    /// Quickest to build: 8 bins.
    pub const FAST: BuildSettings = BuildSettings {
        bins: 8,
        max_leaf_size: 8,
        traversal_cost: 1.0,
        record_cost: 1.0,
        flat_limit: Self::FLAT_LIMIT,
        collapse: Collapse::Greedy,
    };
    /// The default: 16 bins, leaves of up to 8 triangles.
    pub const MEDIUM: BuildSettings = BuildSettings {
        bins: 16,
        max_leaf_size: 8,
        traversal_cost: 1.0,
        record_cost: 1.0,
        flat_limit: Self::FLAT_LIMIT,
        collapse: Collapse::Greedy,
    };
    /// Best trees: 32 bins, and the collapse of least cost over binary leaves of up to four.
    pub const HIGH: BuildSettings = BuildSettings {
        bins: 32,
        max_leaf_size: 8,
        traversal_cost: 1.0,
        record_cost: 1.0,
        flat_limit: Self::FLAT_LIMIT,
        collapse: Collapse::Optimal { binary_leaf_size: 4 },
    };
    /// Every preset with its name.
    pub const PRESETS: [(&'static str, BuildSettings); 3] =
        [("fast", Self::FAST), ("medium", Self::MEDIUM), ("high", Self::HIGH)];

    /// The presets' [`flat_limit`](Self::flat_limit): three blocks of sixteen. On the
    /// 32-triangle Cornell box the flat list traces every kind of ray faster than the tree; from
    /// about 50 triangles the tree wins on primary rays, and from about 100 on all
    /// (`raylab bench --flat-limit N` compares them).
    pub const FLAT_LIMIT: usize = 48;

    /// The largest [`flat_limit`](Self::flat_limit): the rays in lanes put every distinct corner
    /// of the list in their frames at once (`flat_rays.rs`, 256 bytes a corner with AVX-512),
    /// which stays a few megabytes at 4,096 triangles, and a list that long is already many
    /// times slower than the tree.
    pub const MAX_FLAT_LIMIT: usize = 4096;

    /// Scenes below this many triangles get leaves of at most four triangles (see
    /// [`for_triangles`](Self::for_triangles)).
    pub const SMALL_SCENE: usize = 4096;

    /// What [`Bvh::new`](crate::bvh::Bvh::new) builds with: [`MEDIUM`](Self::MEDIUM), with leaves of at most four
    /// triangles for scenes of fewer than [`SMALL_SCENE`](Self::SMALL_SCENE).
    ///
    /// A small scene's tree stays in cache whatever its size, so smaller leaves cost no memory
    /// traffic and save triangle tests, above all for packets of camera rays. On large meshes,
    /// leaves of up to eight were faster and smaller (measured before leaf records, with
    /// blocks of four triangles).
    pub fn for_triangles(triangles: usize) -> BuildSettings {
        if triangles < Self::SMALL_SCENE {
            BuildSettings { max_leaf_size: 4, ..Self::MEDIUM }
        } else {
            Self::MEDIUM
        }
    }

    /// The settings with every field clamped to its valid range.
    pub(crate) fn clamped(&self) -> BuildSettings {
        let max_leaf_size = self.max_leaf_size.clamp(1, MAX_LEAF_TRIANGLES);
        BuildSettings {
            bins: self.bins.clamp(2, super::bins::MAX_BINS),
            max_leaf_size,
            traversal_cost: if self.traversal_cost.is_finite() {
                self.traversal_cost.max(0.0)
            } else {
                1.0
            },
            record_cost: if self.record_cost > 0.0 && self.record_cost.is_finite() {
                self.record_cost
            } else {
                1.0
            },
            flat_limit: self.flat_limit.min(Self::MAX_FLAT_LIMIT),
            collapse: match self.collapse {
                Collapse::Greedy => Collapse::Greedy,
                Collapse::Optimal { binary_leaf_size } => {
                    Collapse::Optimal { binary_leaf_size: binary_leaf_size.clamp(1, max_leaf_size) }
                }
            },
        }
    }
}

impl Default for BuildSettings {
    fn default() -> Self {
        Self::MEDIUM
    }
}
