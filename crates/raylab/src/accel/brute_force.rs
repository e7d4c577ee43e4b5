//! Every ray against every triangle: the reference answer.

use glam::Vec3;

use super::{Accelerator, Hit};
use crate::ray::Ray;
use crate::triangle::{Triangle, WatertightRay};

/// Tests every triangle, in order. Exact and simple; linear in the triangle count.
#[derive(Clone, Debug, Default)]
pub struct BruteForce {
    vertices: Vec<[Vec3; 3]>,
}

impl BruteForce {
    /// Keeps a compact copy of the triangles' vertices.
    pub fn new(triangles: &[Triangle]) -> Self {
        BruteForce { vertices: triangles.iter().map(|t| [t.v0, t.v1, t.v2]).collect() }
    }
}

impl Accelerator for BruteForce {
    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        let setup = WatertightRay::new(ray);
        let mut closest: Option<Hit> = None;
        let mut t_max = ray.t_max;
        for (index, [v0, v1, v2]) in self.vertices.iter().enumerate() {
            // Only strictly nearer hits replace the current one: ties keep the lowest index.
            if let Some(h) = setup.intersect(*v0, *v1, *v2, t_max) {
                t_max = h.t;
                closest = Some(Hit { t: h.t, triangle: index as u32, b1: h.b1, b2: h.b2 });
            }
        }
        closest
    }

    fn occluded(&self, ray: &Ray) -> bool {
        let setup = WatertightRay::new(ray);
        self.vertices.iter().any(|[v0, v1, v2]| setup.intersect(*v0, *v1, *v2, ray.t_max).is_some())
    }
}
