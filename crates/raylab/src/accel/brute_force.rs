//! Every ray against every triangle: the reference answer.

use glam::Vec3;

use super::{Accelerator, Hit};
use crate::ray::Ray;
use crate::triangle::{LANES, Triangle, TriangleBlock, WatertightRay};

/// Tests every triangle, in order. Exact and simple; linear in the triangle count.
///
/// Triangles are kept in blocks of [`LANES`]: a vectorized pre-test picks the few triangles of a
/// block that a ray may hit, and the scalar watertight test decides those.
#[derive(Clone, Debug, Default)]
pub struct BruteForce {
    blocks: Vec<TriangleBlock>,
}

impl BruteForce {
    /// Keeps a compact copy of the triangles' vertices.
    pub fn new(triangles: &[Triangle]) -> Self {
        BruteForce { blocks: TriangleBlock::pack(triangles.iter().map(|t| [t.v0, t.v1, t.v2])) }
    }

    /// The triangles' vertices, in order: for reference loops in tests.
    pub fn triangles(&self) -> impl Iterator<Item = [Vec3; 3]> + '_ {
        self.blocks
            .iter()
            .flat_map(|block| (0..LANES).map(move |lane| block.triangle(lane)))
            .filter(|t| !t[0].is_nan())
    }
}

/// Calls `visit(index, hit)` for each triangle that `t_max()` still admits, in index order.
#[inline]
fn for_each_hit(
    blocks: &[TriangleBlock],
    ray: &WatertightRay,
    mut t_max: impl FnMut() -> f32,
    mut visit: impl FnMut(u32, crate::triangle::TriangleHit) -> bool,
) {
    for (b, block) in blocks.iter().enumerate() {
        let mut candidates = ray.block_candidates(block, t_max());
        while candidates != 0 {
            let lane = candidates.trailing_zeros() as usize;
            candidates &= candidates - 1;
            let [v0, v1, v2] = block.triangle(lane);
            if let Some(hit) = ray.intersect(v0, v1, v2, t_max()) {
                if visit((b * LANES + lane) as u32, hit) {
                    return;
                }
            }
        }
    }
}

impl Accelerator for BruteForce {
    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        let setup = WatertightRay::new(ray);
        let closest = std::cell::Cell::new(None::<Hit>);
        let t_max = || closest.get().map_or(ray.t_max, |h| h.t);
        // Only strictly nearer hits replace the current one: ties keep the lowest index.
        for_each_hit(&self.blocks, &setup, t_max, |triangle, h| {
            closest.set(Some(Hit { t: h.t, triangle, b1: h.b1, b2: h.b2 }));
            false
        });
        closest.get()
    }

    fn occluded(&self, ray: &Ray) -> bool {
        let setup = WatertightRay::new(ray);
        let mut occluded = false;
        for_each_hit(
            &self.blocks,
            &setup,
            || ray.t_max,
            |_, _| {
                occluded = true;
                true
            },
        );
        occluded
    }
}
