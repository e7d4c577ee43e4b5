//! The accelerator of a whole scene: one BVH over its triangles, or two levels where it draws
//! a mesh in several places.

use super::TwoLevel;
use super::{BuildError, Bvh};
use crate::accel::{Accelerator, Hit, HitRows, RayRows};
use crate::geometry::Geometry;
use crate::ray::Ray;

/// A scene's BVH: [`Flat`](Self::Flat) when every mesh is drawn once (the triangles in world
/// space, one tree, packets), [`Instanced`](Self::Instanced) when some mesh is drawn in several
/// places (a tree per stored mesh under a tree of instances, see [`TwoLevel`]).
pub enum SceneBvh {
    /// One BVH over every triangle.
    Flat(Bvh),
    /// A BVH per stored mesh, under the instances.
    Instanced(TwoLevel<Bvh>),
}

impl SceneBvh {
    /// Builds over `geometry` on the current rayon pool, or says why not (a mesh of more
    /// triangles than a BVH holds).
    pub fn build(geometry: &Geometry) -> Result<SceneBvh, BuildError> {
        if geometry.is_instanced() {
            TwoLevel::build(geometry, Bvh::try_new).map(SceneBvh::Instanced)
        } else {
            Bvh::try_new(&geometry.vertices()).map(SceneBvh::Flat)
        }
    }

    /// The bytes of its trees (nodes, leaf records and the instances' table).
    pub fn bytes(&self) -> usize {
        match self {
            SceneBvh::Flat(bvh) => bvh.stats().bytes(),
            SceneBvh::Instanced(two) => {
                two.top_bytes() + two.bottoms().map(|b| b.stats().bytes()).sum::<usize>()
            }
        }
    }

    /// The triangles its trees hold: a mesh drawn in several places counts once.
    pub fn triangles(&self) -> usize {
        match self {
            SceneBvh::Flat(bvh) => bvh.stats().triangles,
            SceneBvh::Instanced(two) => two.bottom_triangles(),
        }
    }
}

impl std::fmt::Debug for SceneBvh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SceneBvh::Flat(bvh) => f.debug_tuple("Flat").field(bvh).finish(),
            SceneBvh::Instanced(two) => f
                .debug_struct("Instanced")
                .field("instances", &two.instance_count())
                .field("bottoms", &two.bottom_count())
                .finish(),
        }
    }
}

impl Accelerator for SceneBvh {
    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        match self {
            SceneBvh::Flat(bvh) => bvh.closest_hit(ray),
            SceneBvh::Instanced(two) => two.closest_hit(ray),
        }
    }

    fn occluded(&self, ray: &Ray) -> bool {
        match self {
            SceneBvh::Flat(bvh) => bvh.occluded(ray),
            SceneBvh::Instanced(two) => two.occluded(ray),
        }
    }

    fn closest_hits(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        match self {
            SceneBvh::Flat(bvh) => bvh.closest_hits(rays, hits),
            SceneBvh::Instanced(two) => two.closest_hits(rays, hits),
        }
    }

    fn occluded_each(&self, rays: &[Ray], occluded: &mut [bool]) {
        match self {
            SceneBvh::Flat(bvh) => bvh.occluded_each(rays, occluded),
            SceneBvh::Instanced(two) => two.occluded_each(rays, occluded),
        }
    }

    fn closest_hits_rows(&self, rays: &[Ray], hits: &mut HitRows) {
        match self {
            SceneBvh::Flat(bvh) => bvh.closest_hits_rows(rays, hits),
            SceneBvh::Instanced(two) => two.closest_hits_rows(rays, hits),
        }
    }

    fn occluded_rows(&self, rays: &RayRows) -> u64 {
        match self {
            SceneBvh::Flat(bvh) => bvh.occluded_rows(rays),
            SceneBvh::Instanced(two) => two.occluded_rows(rays),
        }
    }

    fn occluded_incoherent(&self, rays: &[Ray], occluded: &mut [bool]) {
        match self {
            SceneBvh::Flat(bvh) => bvh.occluded_incoherent(rays, occluded),
            SceneBvh::Instanced(two) => two.occluded_incoherent(rays, occluded),
        }
    }

    fn closest_hits_incoherent(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        match self {
            SceneBvh::Flat(bvh) => bvh.closest_hits_incoherent(rays, hits),
            SceneBvh::Instanced(two) => two.closest_hits_incoherent(rays, hits),
        }
    }
}
