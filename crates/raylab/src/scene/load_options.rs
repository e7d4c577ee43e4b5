//! How a model's meshes are loaded ([`LoadOptions`]): what becomes of a mesh a model draws in
//! several places ([`Instancing`]).

use crate::unknown_name::UnknownName;

/// How [`Scene::open`](super::Scene::open) loads a model or a scene file's meshes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// What becomes of a mesh that a model draws in several places (glTF nodes sharing a mesh).
    pub instancing: Instancing,
}

/// What becomes of a mesh that a model draws in several places: stored once and drawn through
/// each copy's transform (a two-level BVH: `bvh::TwoLevel`), or copied into world space as
/// triangles of its own (one BVH over them all). The picture is the same
/// either way (`tests/instancing.rs` and `tests/mitsuba.rs` compare); what differs is memory
/// and time:
///
/// - two levels store each mesh once, but every ray that reaches a copy's box walks that copy's
///   tree too, with its ray set-up in the mesh's space: the copies' boxes overlap where a flat
///   tree's nodes would not, so paths through instances take longer (BENCHMARKS.md has the
///   figures for 2CylinderEngine and the glTF boxes);
/// - flat copies cost memory: about 100 bytes per copied triangle for the geometry and its
///   tree.
///
/// So [`Auto`](Self::Auto), the default, copies the meshes that cost least to copy and keeps the
/// rest instanced: what a forest of a million trees needs, without making a model of a few
/// copies slow.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Instancing {
    /// Copy a model's instanced meshes, the fewest extra triangles first, while the copies
    /// beyond each mesh's first add at most [`AUTO_FLATTEN_TRIANGLES`] triangles to the model;
    /// keep the rest instanced. The budget is a model file's: each mesh file that a scene file
    /// names has its own.
    #[default]
    Auto,
    /// Keep every mesh drawn in several places stored once: the least memory.
    Keep,
    /// Copy every instance: the fastest to trace, the most memory.
    Flatten,
}

impl std::str::FromStr for Instancing {
    type Err = UnknownName;

    fn from_str(name: &str) -> Result<Instancing, UnknownName> {
        match name {
            "auto" => Ok(Instancing::Auto),
            "keep" => Ok(Instancing::Keep),
            "flatten" => Ok(Instancing::Flatten),
            _ => Err(UnknownName::new("instancing", name, "auto, keep or flatten")),
        }
    }
}

/// The most triangles that [`Instancing::Auto`] adds to a model (a mesh file) by copying its
/// instanced meshes (each mesh's copies beyond its first): 2¹⁸, some 25 MiB of geometry and
/// tree.
pub const AUTO_FLATTEN_TRIANGLES: usize = 1 << 18;

impl Instancing {
    /// Applies this choice to a loaded model: copies its instanced meshes into
    /// [`LoadedMesh::mesh`](super::LoadedMesh::mesh) as it says. Returns how many meshes it copied.
    pub fn apply(self, loaded: &mut super::mesh_file::LoadedMesh) -> usize {
        match self {
            Instancing::Auto => loaded.flatten_within(AUTO_FLATTEN_TRIANGLES),
            Instancing::Keep => 0,
            Instancing::Flatten => loaded.flatten_within(usize::MAX),
        }
    }
}
