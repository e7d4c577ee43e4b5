//! A bounding volume hierarchy: ray queries in logarithmic time.
//!
//! [`Bvh::build`] makes a binary tree with the binned surface area heuristic (`build`), in
//! parallel on the current rayon pool, then collapses it into an 8-wide tree (`wide`) whose
//! nodes test a ray against eight boxes at once with SIMD (`kernels`), and whose leaves are
//! records of up to eight triangles over a table of the vertices they share (`leaf`), tested in
//! one pass (`leaf_kernels`). Traversal (`traverse`) visits the nearest child first for the closest
//! hit and stops at the first hit for occlusion. Scenes of a few dozen triangles (the Cornell
//! boxes) answer single rays without the tree: every triangle is tested, sixteen per instruction
//! (`flat`, up to [`BuildSettings::flat_limit`] triangles). Moving geometry keeps its tree:
//! [`Bvh::refit`] takes the triangles' new vertices and recomputes the boxes bottom-up (`refit`).
//!
//! The instruction set is picked once, at build time, from what the CPU supports: AVX-512 or AVX2
//! where present, SSE2 on every other x86-64, portable scalar code elsewhere
//! ([`Isa::detect`]). Every kernel has a scalar twin, and the tests check that all of them give
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

mod bounds;
mod build;
mod bundle;
mod flat;
mod kernels;
#[cfg(target_arch = "x86_64")]
mod lanes;
mod leaf;
#[cfg(target_arch = "x86_64")]
mod leaf_kernels;
mod packet;
#[cfg(target_arch = "x86_64")]
mod packet_kernels;
mod packet_rays;
mod packet_setup;
mod refit;
mod scene;
mod sweep;
mod traverse;
mod two_level;
#[cfg(target_arch = "x86_64")]
mod watertight_lanes;
mod wide;

use glam::Vec3;

pub use bounds::{Bounds, Frustum, RayBoxTest};
pub(crate) use bounds::{FAR_SCALE, SLAB_PAD};
pub use refit::RefitError;
pub use scene::SceneBvh;
pub use traverse::TraversalStats;
pub use two_level::TwoLevel;

use crate::accel::{Accelerator, Hit};
use crate::ray::Ray;
use wide::WideBvh;

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
    /// (`flat`): faster for a few dozen triangles. `0` always walks the tree.
    pub flat_limit: usize,
}

impl BuildSettings {
    /// Quickest to build: 8 bins.
    pub const FAST: BuildSettings = BuildSettings {
        bins: 8,
        max_leaf_size: 8,
        traversal_cost: 1.0,
        record_cost: 1.0,
        flat_limit: Self::FLAT_LIMIT,
    };
    /// The default: 16 bins, leaves of up to 8 triangles.
    pub const MEDIUM: BuildSettings = BuildSettings {
        bins: 16,
        max_leaf_size: 8,
        traversal_cost: 1.0,
        record_cost: 1.0,
        flat_limit: Self::FLAT_LIMIT,
    };
    /// Best trees: 32 bins.
    pub const HIGH: BuildSettings = BuildSettings {
        bins: 32,
        max_leaf_size: 8,
        traversal_cost: 1.0,
        record_cost: 1.0,
        flat_limit: Self::FLAT_LIMIT,
    };
    /// Every preset with its name.
    pub const PRESETS: [(&'static str, BuildSettings); 3] =
        [("fast", Self::FAST), ("medium", Self::MEDIUM), ("high", Self::HIGH)];

    /// The presets' [`flat_limit`](Self::flat_limit): three blocks of sixteen. Measured
    /// (`raylab bench --flat-limit`, one thread): on the 32-triangle Cornell box the flat list
    /// traces primary, shadow and diffuse rays 1.3, 1.6 and 1.6 times as fast as the tree; with
    /// 52 and 72 triangles it wins on shadow and diffuse rays but loses on primary ones; with 112
    /// the tree is 1.3 to 1.7 times as fast.
    pub const FLAT_LIMIT: usize = 48;

    /// Scenes below this many triangles get leaves of at most four triangles (see
    /// [`for_triangles`](Self::for_triangles)).
    pub const SMALL_SCENE: usize = 4096;

    /// What [`Bvh::new`] builds with: [`MEDIUM`](Self::MEDIUM), with leaves of at most four
    /// triangles for scenes of fewer than [`SMALL_SCENE`](Self::SMALL_SCENE).
    ///
    /// A small scene's tree stays in cache whatever its size, so smaller leaves cost no memory
    /// traffic and save triangle tests, above all for packets of camera rays (the lab frame
    /// renders in 22 rather than 28 ms on one thread). On large meshes, leaves of up to eight
    /// are faster and smaller (measured with the four-triangle blocks that leaf records replaced;
    /// the 871k-triangle dragon: 56 rather than 63 bytes per triangle then).
    pub fn for_triangles(triangles: usize) -> BuildSettings {
        if triangles < Self::SMALL_SCENE {
            BuildSettings { max_leaf_size: 4, ..Self::MEDIUM }
        } else {
            Self::MEDIUM
        }
    }

    /// The settings with every field clamped to its valid range.
    fn clamped(&self) -> BuildSettings {
        BuildSettings {
            bins: self.bins.clamp(2, build::MAX_BINS),
            max_leaf_size: self.max_leaf_size.clamp(1, wide::MAX_LEAF_TRIANGLES),
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
            flat_limit: self.flat_limit,
        }
    }
}

impl Default for BuildSettings {
    fn default() -> Self {
        Self::MEDIUM
    }
}

/// The instruction set of the node kernels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Isa {
    /// Portable code, one box at a time: the reference.
    Scalar,
    /// SSE2: two groups of four boxes (every x86-64 CPU).
    Sse2,
    /// AVX2: eight boxes at once.
    Avx2,
    /// AVX-512 (F and VL): the AVX2 node kernel, with the rest of traversal compiled for AVX-512.
    Avx512,
}

impl Isa {
    /// The best instruction set this CPU supports.
    pub fn detect() -> Isa {
        Isa::ALL.into_iter().rev().find(|isa| isa.is_supported()).unwrap_or(Isa::Scalar)
    }

    /// Every instruction set, from the most portable.
    pub const ALL: [Isa; 4] = [Isa::Scalar, Isa::Sse2, Isa::Avx2, Isa::Avx512];

    /// Whether this CPU can run it.
    pub fn is_supported(self) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            match self {
                Isa::Scalar | Isa::Sse2 => true,
                Isa::Avx2 => std::arch::is_x86_feature_detected!("avx2"),
                Isa::Avx512 => {
                    std::arch::is_x86_feature_detected!("avx2")
                        && std::arch::is_x86_feature_detected!("avx512f")
                        && std::arch::is_x86_feature_detected!("avx512vl")
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            self == Isa::Scalar
        }
    }

    /// A short name: `scalar`, `sse2`, `avx2`, `avx512`.
    pub fn name(self) -> &'static str {
        match self {
            Isa::Scalar => "scalar",
            Isa::Sse2 => "sse2",
            Isa::Avx2 => "avx2",
            Isa::Avx512 => "avx512",
        }
    }
}

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
    /// caller's index per triangle (see `bvh/leaf.rs`).
    pub leaf_bytes: usize,
    /// Bytes of the flat list of a small scene's triangles (see
    /// [`BuildSettings::flat_limit`]), `0` for none.
    pub flat_bytes: usize,
}

impl BvhStats {
    /// Bytes of the BVH: nodes, the leaves' records, and a small scene's flat list.
    pub fn bytes(&self) -> usize {
        self.nodes * size_of::<wide::WideNode>() + self.leaf_bytes + self.flat_bytes
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
    flat: Option<flat::Flat>,
    isa: Isa,
    stats: BvhStats,
}

impl std::fmt::Debug for Bvh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Bvh").field("isa", &self.isa).field("stats", &self.stats).finish()
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

    /// About how many bytes building over `triangles` triangles takes at its peak (the
    /// primitives' boxes and build records, the binary tree and the wide tree with its copies of
    /// the triangles): for a caller to check against the memory it has before it builds.
    pub fn build_bytes_estimate(triangles: usize) -> u64 {
        // At its peak the build holds about 90 bytes per triangle: the build records (32) with
        // the binary tree (about 25), then the wide tree (about 56, see `BvhStats::bytes`) while
        // the binary tree is collapsed. 160 leaves a margin.
        triangles as u64 * 160
    }

    fn build_checked(triangles: &[[Vec3; 3]], settings: &BuildSettings) -> Bvh {
        let settings = settings.clamped();
        let binary = build::build_triangles(triangles, &settings);
        let indexed_triangles = binary.order.len();
        let flat = (indexed_triangles <= settings.flat_limit).then(|| {
            let mut indices = binary.order.clone();
            indices.sort_unstable();
            flat::Flat::new(triangles, &indices)
        });
        let wide = wide::collapse(&binary, |i| triangles[i as usize], |i| i);
        let stats = BvhStats {
            triangles: triangles.len(),
            indexed_triangles,
            nodes: wide.nodes.len(),
            leaf_bytes: wide.leaves.bytes(),
            flat_bytes: flat.as_ref().map_or(0, flat::Flat::bytes),
        };
        Bvh { wide, flat, isa: Isa::detect(), stats }
    }

    /// The same tree traversed with another instruction set, or `None` if this CPU lacks it.
    pub fn with_isa(mut self, isa: Isa) -> Option<Bvh> {
        isa.is_supported().then(|| {
            self.isa = isa;
            self
        })
    }

    /// The instruction set in use.
    pub fn isa(&self) -> Isa {
        self.isa
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
        unsafe { traverse::closest_hit_counted::<kernels::Scalar, _>(&self.wide, ray, stats) }
    }

    /// Whether the ray is occluded, exactly as [`occluded`](Accelerator::occluded) answers it,
    /// counting as [`closest_hit_counted`](Self::closest_hit_counted) does.
    pub fn occluded_counted(&self, ray: &Ray, stats: &mut TraversalStats) -> bool {
        stats.rays += 1;
        // SAFETY: the scalar kernel needs no special instructions.
        unsafe { traverse::occluded_counted::<kernels::Scalar, _>(&self.wide, ray, stats) }
    }
}

#[cfg(target_arch = "x86_64")]
mod entry {
    //! One copy of each traversal per instruction set, compiled with that set enabled.
    use super::kernels::{Avx2, Avx512, Sse};
    use super::wide::WideBvh;
    use super::{packet, traverse};
    use crate::accel::Hit;
    use crate::ray::Ray;

    pub(super) fn closest_hit_sse2(bvh: &WideBvh, ray: &Ray) -> Option<Hit> {
        // SAFETY: SSE2 is part of x86-64.
        unsafe { traverse::closest_hit::<Sse>(bvh, ray) }
    }

    pub(super) fn occluded_sse2(bvh: &WideBvh, ray: &Ray) -> bool {
        // SAFETY: SSE2 is part of x86-64.
        unsafe { traverse::occluded::<Sse>(bvh, ray) }
    }

    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn closest_hit_avx2(bvh: &WideBvh, ray: &Ray) -> Option<Hit> {
        // SAFETY: this function's caller checked AVX2 support.
        unsafe { traverse::closest_hit::<Avx2>(bvh, ray) }
    }

    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn occluded_avx2(bvh: &WideBvh, ray: &Ray) -> bool {
        // SAFETY: this function's caller checked AVX2 support.
        unsafe { traverse::occluded::<Avx2>(bvh, ray) }
    }

    #[target_feature(enable = "avx2,avx512f,avx512vl")]
    pub(super) unsafe fn closest_hit_avx512(bvh: &WideBvh, ray: &Ray) -> Option<Hit> {
        // SAFETY: this function's caller checked AVX2 and AVX-512 F/VL support.
        unsafe { traverse::closest_hit::<Avx512>(bvh, ray) }
    }

    pub(super) fn closest_hits_sse2(bvh: &WideBvh, rays: &[Ray], out: &mut [Option<Hit>]) {
        // SAFETY: SSE2 is part of x86-64.
        unsafe { packet::closest_hits::<Sse>(bvh, rays, out) }
    }

    pub(super) fn occluded_each_sse2(bvh: &WideBvh, rays: &[Ray], out: &mut [bool]) {
        // SAFETY: SSE2 is part of x86-64.
        unsafe { packet::occluded_each::<Sse>(bvh, rays, out) }
    }

    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn closest_hits_avx2(bvh: &WideBvh, rays: &[Ray], out: &mut [Option<Hit>]) {
        // SAFETY: this function's caller checked AVX2 support.
        unsafe { packet::closest_hits::<Avx2>(bvh, rays, out) }
    }

    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn occluded_each_avx2(bvh: &WideBvh, rays: &[Ray], out: &mut [bool]) {
        // SAFETY: this function's caller checked AVX2 support.
        unsafe { packet::occluded_each::<Avx2>(bvh, rays, out) }
    }

    #[target_feature(enable = "avx2,avx512f,avx512vl")]
    pub(super) unsafe fn closest_hits_avx512(bvh: &WideBvh, rays: &[Ray], out: &mut [Option<Hit>]) {
        // SAFETY: this function's caller checked AVX2 and AVX-512 F/VL support.
        unsafe { packet::closest_hits::<Avx512>(bvh, rays, out) }
    }

    #[target_feature(enable = "avx2,avx512f,avx512vl")]
    pub(super) unsafe fn occluded_each_avx512(bvh: &WideBvh, rays: &[Ray], out: &mut [bool]) {
        // SAFETY: this function's caller checked AVX2 and AVX-512 F/VL support.
        unsafe { packet::occluded_each::<Avx512>(bvh, rays, out) }
    }

    #[target_feature(enable = "avx2,avx512f,avx512vl")]
    pub(super) unsafe fn occluded_avx512(bvh: &WideBvh, ray: &Ray) -> bool {
        // SAFETY: this function's caller checked AVX2 and AVX-512 F/VL support.
        unsafe { traverse::occluded::<Avx512>(bvh, ray) }
    }
}

impl Accelerator for Bvh {
    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        if let Some(flat) = &self.flat {
            return match self.isa {
                // SAFETY: (all arms) `with_isa` and `build` only set an ISA the CPU supports.
                #[cfg(target_arch = "x86_64")]
                Isa::Avx512 => unsafe { flat::closest_hit_avx512(flat, ray) },
                // SAFETY: the ISA was checked when it was set (as above).
                #[cfg(target_arch = "x86_64")]
                Isa::Avx2 => unsafe { flat::closest_hit_avx2(flat, ray) },
                #[cfg(target_arch = "x86_64")]
                Isa::Sse2 => flat::closest_hit_sse2(flat, ray),
                _ => flat::closest_hit_scalar(flat, ray),
            };
        }
        match self.isa {
            // SAFETY: (all arms) `with_isa` and `build` only set an ISA the CPU supports.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => unsafe { entry::closest_hit_avx512(&self.wide, ray) },
            // SAFETY: the ISA was checked when it was set (as above).
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => unsafe { entry::closest_hit_avx2(&self.wide, ray) },
            #[cfg(target_arch = "x86_64")]
            Isa::Sse2 => entry::closest_hit_sse2(&self.wide, ray),
            // SAFETY: the scalar kernel needs no special instructions.
            _ => unsafe { traverse::closest_hit::<kernels::Scalar>(&self.wide, ray) },
        }
    }

    fn occluded(&self, ray: &Ray) -> bool {
        if let Some(flat) = &self.flat {
            return match self.isa {
                // SAFETY: (all arms) `with_isa` and `build` only set an ISA the CPU supports.
                #[cfg(target_arch = "x86_64")]
                Isa::Avx512 => unsafe { flat::occluded_avx512(flat, ray) },
                // SAFETY: the ISA was checked when it was set (as above).
                #[cfg(target_arch = "x86_64")]
                Isa::Avx2 => unsafe { flat::occluded_avx2(flat, ray) },
                #[cfg(target_arch = "x86_64")]
                Isa::Sse2 => flat::occluded_sse2(flat, ray),
                _ => flat::occluded_scalar(flat, ray),
            };
        }
        match self.isa {
            // SAFETY: (all arms) `with_isa` and `build` only set an ISA the CPU supports.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => unsafe { entry::occluded_avx512(&self.wide, ray) },
            // SAFETY: the ISA was checked when it was set (as above).
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => unsafe { entry::occluded_avx2(&self.wide, ray) },
            #[cfg(target_arch = "x86_64")]
            Isa::Sse2 => entry::occluded_sse2(&self.wide, ray),
            // SAFETY: the scalar kernel needs no special instructions.
            _ => unsafe { traverse::occluded::<kernels::Scalar>(&self.wide, ray) },
        }
    }

    /// Traces the rays in packets of up to 64 (see [`Frustum`]): best for coherent rays, such
    /// as an 8×8 tile of camera rays or of shadow rays toward one light. The answers are exactly
    /// those of [`closest_hit`](Self::closest_hit).
    fn closest_hits(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        match self.isa {
            // SAFETY: (all arms) `with_isa` and `build` only set an ISA the CPU supports.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => unsafe { entry::closest_hits_avx512(&self.wide, rays, hits) },
            // SAFETY: the ISA was checked when it was set (as above).
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => unsafe { entry::closest_hits_avx2(&self.wide, rays, hits) },
            #[cfg(target_arch = "x86_64")]
            Isa::Sse2 => entry::closest_hits_sse2(&self.wide, rays, hits),
            // SAFETY: the scalar kernel needs no special instructions.
            _ => unsafe { packet::closest_hits::<kernels::Scalar>(&self.wide, rays, hits) },
        }
    }

    /// Occlusion in packets of up to 64, as [`closest_hits`](Self::closest_hits); the answers
    /// are exactly those of [`occluded`](Self::occluded).
    fn occluded_each(&self, rays: &[Ray], occluded: &mut [bool]) {
        match self.isa {
            // SAFETY: (all arms) `with_isa` and `build` only set an ISA the CPU supports.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => unsafe { entry::occluded_each_avx512(&self.wide, rays, occluded) },
            // SAFETY: the ISA was checked when it was set (as above).
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => unsafe { entry::occluded_each_avx2(&self.wide, rays, occluded) },
            #[cfg(target_arch = "x86_64")]
            Isa::Sse2 => entry::occluded_each_sse2(&self.wide, rays, occluded),
            // SAFETY: the scalar kernel needs no special instructions.
            _ => unsafe { packet::occluded_each::<kernels::Scalar>(&self.wide, rays, occluded) },
        }
    }
}

#[cfg(test)]
mod tests;
