//! Every ray against every triangle: the reference answer.

use glam::Vec3;

use super::{Accelerator, Hit};
use crate::ray::Ray;
use crate::triangle::{LANES, TriangleBlock, WatertightRay};

/// Tests every triangle, in order. Exact and simple; linear in the triangle count.
///
/// Triangles are kept in blocks of [`LANES`]: a vectorized pre-test picks the few triangles of a
/// block that a ray may hit, and the scalar watertight test decides those.
#[derive(Clone, Debug, Default)]
pub struct BruteForce {
    blocks: Vec<TriangleBlock>,
}

impl BruteForce {
    /// Keeps a compact copy of the triangles' vertices (for a scene, `Scene::vertices`).
    pub fn new(triangles: &[[Vec3; 3]]) -> Self {
        BruteForce { blocks: TriangleBlock::pack(triangles.iter().copied()) }
    }

    /// The triangles' vertices, in order: for reference loops in tests.
    pub fn triangles(&self) -> impl Iterator<Item = [Vec3; 3]> + '_ {
        self.blocks
            .iter()
            .flat_map(|block| (0..LANES).map(move |lane| block.triangle(lane)))
            .filter(|t| !t[0].is_nan())
    }
}

impl Accelerator for BruteForce {
    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        let setup = WatertightRay::new(ray);
        let mut closest: Option<Hit> = None;
        let mut t_max = ray.t_max;
        for (b, block) in self.blocks.iter().enumerate() {
            let mut candidates = setup.block_candidates(block, t_max);
            while candidates != 0 {
                let lane = candidates.trailing_zeros() as usize;
                candidates &= candidates - 1;
                let [v0, v1, v2] = block.triangle(lane);
                // Only strictly nearer hits pass `t < t_max`: ties keep the lowest index.
                if let Some(h) = setup.intersect(v0, v1, v2, t_max) {
                    t_max = h.t;
                    let triangle = (b * LANES + lane) as u32;
                    closest = Some(Hit { t: h.t, triangle, b1: h.b1, b2: h.b2 });
                }
            }
        }
        closest
    }

    fn occluded(&self, ray: &Ray) -> bool {
        let setup = WatertightRay::new(ray);
        self.blocks.iter().any(|block| {
            let mut candidates = setup.block_candidates(block, ray.t_max);
            while candidates != 0 {
                let lane = candidates.trailing_zeros() as usize;
                candidates &= candidates - 1;
                let [v0, v1, v2] = block.triangle(lane);
                if setup.intersect(v0, v1, v2, ray.t_max).is_some() {
                    return true;
                }
            }
            false
        })
    }
}
