//! A bounding volume hierarchy: ray queries in logarithmic time.
//!
//! The files follow a ray's way through the structure, one concept each:
//!
//! | module | what it holds |
//! |---|---|
//! | `bounds` | boxes, the conservative slab test of one ray ([`RayBoxTest`]) and of a packet ([`Frustum`]) |
//! | `build` | [`BuildSettings`]; the binned SAH build of a binary tree, in parallel on the current rayon pool (`build/sweep.rs`: the split sweep); its collapse into the 8-wide tree: greedy (`build/collapse.rs`) or of least SAH cost by dynamic programming (`build/optimal.rs`, the `high` preset) |
//! | `node` | the wide node's layout (eight boxes plane by plane, eight child references, drawn in its doc); `node/kernel.rs`: one ray or a packet's bound against eight boxes |
//! | `leaf` | leaf records of up to eight triangles over a table of the vertices they share; `leaf/kernel.rs` and `leaf/lanes.rs`: a ray against a record in one pass |
//! | `traverse` | single rays: nearest child first for the closest hit, first hit for occlusion; `traverse/flat.rs`: scenes of a few dozen triangles (the Cornell boxes) answer single rays without the tree, every triangle tested sixteen per instruction (up to [`BuildSettings::flat_limit`] triangles); `traverse/flat_rays.rs`: many incoherent rays against that list, sixteen rays per instruction |
//! | `packet` | up to 64 coherent rays through the tree together: `rays` (their lanes), `setup`, `bundle` (a packet's bound in ray space), `leaf` and `lanes` (a leaf's triangles against several rays per instruction) |
//! | `batch` | large batches of independent queries on every thread, in the tree's order where it pays ([`Batch`]) |
//! | `order` | many rays sorted so that neighbours run through the same part of the tree ([`order::segment_key`], [`order::order_by_key`]): large batches of incoherent rays find more of a large tree in the cache |
//! | `refit` | moving geometry keeps its tree: [`Bvh::refit`] takes new vertices and recomputes the boxes bottom-up |
//! | `two_level` | [`TwoLevel`]: a tree over instances of bottom accelerators; `scene` ([`SceneBvh`]) picks one or two levels for a scene |
//! | `isa`, `simd`, `queries` | the instruction sets, the vector lanes most kernels are written in (one trait over SSE, AVX and AVX-512 registers), and the table of query functions a BVH picks once |
//!
//! The instruction set is picked once, when a BVH is built, from what the CPU supports: AVX-512
//! or AVX2 where present, SSE2 on every other x86-64, portable scalar code elsewhere
//! ([`Isa::detect`], [`Bvh::with_isa`]). The BVH then holds that set's table of query functions
//! (`queries.rs`, as Embree dispatches), each traversal compiled with the set's target features
//! around its kernels. Every kernel has a scalar twin, and the tests check that all of them give
//! the same answers, bit for bit.
//!
//! Answers never depend on the tree: the slab test is conservative (a box never loses a hit inside
//! it), the triangle test is the same watertight test as [`BruteForce`](crate::BruteForce), and
//! hits at exactly equal `t` go to the lowest triangle index. So every build setting and every
//! instruction set gives the same pixels, only at different speeds.
//!
//! ```
//! use raylab::bvh::{BuildSettings, Bvh};
//! use raylab::{Accelerator, Ray, Scene};
//! use glam::Vec3;
//!
//! let scene = Scene::built_in("cornell")?;
//! let bvh = Bvh::new(&scene.vertices());
//! let hit = bvh.closest_hit(&Ray::new(Vec3::new(0.0, 0.0, -3.0), Vec3::Z)).expect("a wall");
//! assert!(hit.t > 3.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod batch;
mod bounds;
mod build;
mod crossings;
mod isa;
mod leaf;
mod node;
pub mod order;
mod packet;
mod queries;
mod refit;
mod scene;
#[cfg(target_arch = "x86_64")]
pub(crate) mod simd;
mod traverse;
mod two_level;

use glam::Vec3;

pub use batch::{Batch, RaySource};
pub use bounds::{Bounds, Frustum, FusedSlabs, RayBoxTest};
pub(crate) use bounds::{FAR_SCALE, SLAB_PAD};
pub use build::{BuildSettings, Collapse};
pub use isa::Isa;
pub use refit::RefitError;
pub use scene::SceneBvh;
pub use traverse::TraversalStats;
pub use two_level::TwoLevel;

use crate::accel::{Accelerator, Hit, HitRows, RayRows};
use crate::ray::Ray;
use node::WideBvh;
use queries::Queries;
use traverse::flat::Flat;

/// Sizes of a built BVH.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BvhStats {
    /// Triangles given to the build.
    pub triangles: usize,
    /// Triangles in the tree: those with zero area or a non-finite vertex can never be hit and
    /// are left out.
    pub indexed_triangles: usize,
    /// Wide nodes.
    pub nodes: usize,
    /// Bytes of the leaves' records: each leaf's distinct vertices, three byte indices and the
    /// caller's index per triangle (see `bvh/leaf`).
    pub leaf_bytes: usize,
    /// Bytes of the flat list of a small scene's triangles (see
    /// [`BuildSettings::flat_limit`]), `0` for none.
    pub flat_bytes: usize,
}

impl BvhStats {
    /// Bytes of the BVH: nodes, the leaves' records, and a small scene's flat list.
    pub fn bytes(&self) -> usize {
        self.nodes * size_of::<node::WideNode>() + self.leaf_bytes + self.flat_bytes
    }
}

/// The most triangles one BVH holds: a triangle takes at most 12 words of leaf records (one
/// alone in its record), and leaf references address 2³¹ − 1 words.
pub const MAX_TRIANGLES: usize = (1 << 27) - 2;

/// Why a BVH could not be built.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum BuildError {
    /// More triangles than [`MAX_TRIANGLES`].
    TooManyTriangles(usize),
}

impl std::fmt::Display for BuildError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BuildError::TooManyTriangles(n) => {
                write!(f, "{n} triangles: a BVH holds at most {MAX_TRIANGLES}")
            }
        }
    }
}

impl std::error::Error for BuildError {}

fn check_triangle_count(triangles: usize) -> Result<(), BuildError> {
    if triangles > MAX_TRIANGLES {
        return Err(BuildError::TooManyTriangles(triangles));
    }
    Ok(())
}

/// An 8-wide BVH over triangles; an [`Accelerator`].
pub struct Bvh {
    wide: WideBvh,
    /// The triangles in a flat list, for scenes of at most `flat_limit` triangles.
    flat: Option<Flat>,
    /// The query functions of the instruction set in use, chosen once.
    queries: Queries,
    stats: BvhStats,
}

impl std::fmt::Debug for Bvh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Bvh").field("isa", &self.isa()).field("stats", &self.stats).finish()
    }
}

impl Bvh {
    /// Builds with the default settings over triangles given by their corners (for a scene,
    /// [`Scene::vertices`](crate::Scene::vertices)).
    pub fn new(triangles: &[[Vec3; 3]]) -> Bvh {
        Bvh::build(triangles, &BuildSettings::for_triangles(triangles.len()))
    }

    /// Builds over triangles given by their vertices; hits report indices into `triangles`.
    /// Runs on the current rayon pool.
    ///
    /// # Panics
    /// With more than [`MAX_TRIANGLES`] (about 134 million) triangles; [`try_build`](Self::try_build)
    /// says so instead.
    pub fn build(triangles: &[[Vec3; 3]], settings: &BuildSettings) -> Bvh {
        Bvh::try_build(triangles, settings).unwrap_or_else(|e| panic!("{e}"))
    }

    /// [`new`](Self::new), or an error for more triangles than a BVH holds.
    pub fn try_new(triangles: &[[Vec3; 3]]) -> Result<Bvh, BuildError> {
        Bvh::try_build(triangles, &BuildSettings::for_triangles(triangles.len()))
    }

    /// [`build`](Self::build), or an error for more triangles than a BVH holds.
    pub fn try_build(triangles: &[[Vec3; 3]], settings: &BuildSettings) -> Result<Bvh, BuildError> {
        check_triangle_count(triangles.len())?;
        Ok(Bvh::build_checked(triangles, settings))
    }

    /// About how many bytes building over `triangles` triangles with `settings` takes at its
    /// peak (the primitives' boxes and build records, the binary tree and the wide tree with its
    /// copies of the triangles): for a caller to check against the memory it has before it
    /// builds.
    pub fn build_bytes_estimate(triangles: usize, settings: &BuildSettings) -> u64 {
        let per_triangle = match settings.clamped().collapse {
            // About 90 bytes per triangle at the peak: the build records (32) with the binary
            // tree (about 25), then the wide tree (about 56, see `BvhStats::bytes`) while the
            // binary tree is collapsed. 160 leaves a margin.
            Collapse::Greedy => 160,
            // Up to 2/b binary nodes a triangle for binary leaves of up to b (32 bytes each) and
            // as many table rows (52 bytes), beside the wide tree: about 230 at b = 1.
            Collapse::Optimal { binary_leaf_size } => 100 + 2 * 84 / binary_leaf_size as u64,
        };
        triangles as u64 * per_triangle
    }

    fn build_checked(triangles: &[[Vec3; 3]], settings: &BuildSettings) -> Bvh {
        let settings = settings.clamped();
        let binary = match settings.collapse {
            Collapse::Greedy => build::build_triangles(triangles, &settings),
            Collapse::Optimal { binary_leaf_size } => build::build_triangles(
                triangles,
                &BuildSettings { max_leaf_size: binary_leaf_size, ..settings },
            ),
        };
        let indexed_triangles = binary.order.len();
        let flat = (indexed_triangles <= settings.flat_limit).then(|| {
            let mut indices = binary.order.clone();
            indices.sort_unstable();
            Flat::new(triangles, &indices)
        });
        let wide = match settings.collapse {
            Collapse::Greedy => build::collapse(&binary, |i| triangles[i as usize], |i| i),
            Collapse::Optimal { .. } => {
                let costs = build::Costs {
                    node: settings.traversal_cost,
                    record: settings.record_cost,
                    max_leaf: settings.max_leaf_size,
                };
                build::collapse_optimal(&binary, costs, |i| triangles[i as usize], |i| i)
            }
        };
        let stats = BvhStats {
            triangles: triangles.len(),
            indexed_triangles,
            nodes: wide.nodes.len(),
            leaf_bytes: wide.leaves.bytes(),
            flat_bytes: flat.as_ref().map_or(0, Flat::bytes),
        };
        let queries = Queries::for_isa(Isa::detect()).expect("the detected instruction set");
        Bvh { wide, flat, queries, stats }
    }

    /// The same tree traversed with another instruction set, or `None` if this CPU lacks it.
    pub fn with_isa(mut self, isa: Isa) -> Option<Bvh> {
        self.queries = Queries::for_isa(isa)?;
        Some(self)
    }

    /// The instruction set in use.
    pub fn isa(&self) -> Isa {
        self.queries.isa
    }

    /// The box around every triangle in the tree (empty for none).
    pub fn bounds(&self) -> Bounds {
        self.wide.root
    }

    /// Sizes of the tree.
    pub fn stats(&self) -> BvhStats {
        self.stats
    }

    /// The closest hit, exactly as [`closest_hit`](Accelerator::closest_hit) answers it, adding
    /// the nodes, leaves and leaf records the tree's traversal visits to `stats` (and one ray).
    ///
    /// It runs the portable node kernel, whose box tests decide as every vector kernel's do (the
    /// twin tests), so the counts are those of any instruction set; slower, for measurements. It
    /// always walks the tree, also for a small scene that answers single rays from its flat list.
    pub fn closest_hit_counted(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<Hit> {
        stats.rays += 1;
        // SAFETY: the scalar kernel needs no special instructions.
        unsafe { traverse::closest_hit_counted::<isa::Scalar, _>(&self.wide, ray, stats) }
    }

    /// Whether the ray is occluded, exactly as [`occluded`](Accelerator::occluded) answers it,
    /// counting as [`closest_hit_counted`](Self::closest_hit_counted) does.
    pub fn occluded_counted(&self, ray: &Ray, stats: &mut TraversalStats) -> bool {
        stats.rays += 1;
        // SAFETY: the scalar kernel needs no special instructions.
        unsafe { traverse::occluded_counted::<isa::Scalar, _>(&self.wide, ray, stats) }
    }
}

impl Accelerator for Bvh {
    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        // SAFETY: `queries` is the table of an instruction set this CPU supports
        // (`Queries::for_isa`).
        unsafe {
            match &self.flat {
                Some(flat) => (self.queries.flat_closest_hit)(flat, ray),
                None => (self.queries.closest_hit)(&self.wide, ray),
            }
        }
    }

    fn occluded(&self, ray: &Ray) -> bool {
        // SAFETY: as above.
        unsafe {
            match &self.flat {
                Some(flat) => (self.queries.flat_occluded)(flat, ray),
                None => (self.queries.occluded)(&self.wide, ray),
            }
        }
    }

    /// Traces the rays in packets of up to 64 (see [`Frustum`]): best for coherent rays, such
    /// as an 8×8 tile of camera rays or of shadow rays toward one light. The answers are exactly
    /// those of [`closest_hit`](Self::closest_hit).
    fn closest_hits(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        // SAFETY: as above.
        unsafe { (self.queries.closest_hits)(&self.wide, rays, hits) }
    }

    /// Occlusion in packets of up to 64, as [`closest_hits`](Self::closest_hits); the answers
    /// are exactly those of [`occluded`](Self::occluded).
    fn occluded_each(&self, rays: &[Ray], occluded: &mut [bool]) {
        // SAFETY: as above.
        unsafe { (self.queries.occluded_each)(&self.wide, rays, occluded) }
    }

    /// In packets, as [`closest_hits`](Self::closest_hits), the packet's hits copied out as
    /// the rows they are.
    fn closest_hits_rows(&self, rays: &[Ray], hits: &mut HitRows) {
        // SAFETY: as above.
        unsafe { (self.queries.closest_hits_rows)(&self.wide, rays, hits) }
    }

    /// In packets, as [`occluded_each`](Self::occluded_each), the packet's lanes filled from
    /// the rows as they are.
    fn occluded_rows(&self, rays: &RayRows) -> u64 {
        // SAFETY: as above.
        unsafe { (self.queries.occluded_rows)(&self.wide, rays) }
    }

    /// A small scene's flat list traces the rays in lanes, one triangle per step
    /// (`traverse/flat_rays.rs`); the tree traces them in lanes too with AVX2 and AVX-512
    /// (`traverse/tree_rays.rs`), one by one with SSE2 and the portable kernels.
    fn occluded_incoherent(&self, rays: &[Ray], occluded: &mut [bool]) {
        assert_eq!(rays.len(), occluded.len(), "one answer per ray");
        match &self.flat {
            // SAFETY: as above.
            Some(flat) => unsafe { (self.queries.flat_occluded_each)(flat, rays, occluded) },
            // SAFETY: as above.
            None => unsafe { (self.queries.occluded_incoherent)(&self.wide, rays, occluded) },
        }
    }

    /// A small scene's flat list traces the rays in lanes, one triangle per step
    /// (`traverse/flat_rays.rs`); the tree traces them in lanes too with AVX2 and AVX-512
    /// (`traverse/tree_rays.rs`), one by one with SSE2 and the portable kernels.
    fn closest_hits_incoherent(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), hits.len(), "one answer per ray");
        match &self.flat {
            // SAFETY: as above.
            Some(flat) => unsafe { (self.queries.flat_closest_hits)(flat, rays, hits) },
            // SAFETY: as above.
            None => unsafe { (self.queries.closest_hits_incoherent)(&self.wide, rays, hits) },
        }
    }
}

#[cfg(test)]
mod tests;
