//! Every crossing of a ray with the surface, not only the closest: what inside/outside tests
//! count (a point is inside a closed mesh when a ray from it crosses the surface an odd number
//! of times).
//!
//! [`Bvh::crossings`] visits every box the ray enters (the single-ray box test, its limit the
//! ray's end) and tests each triangle with [`WatertightRay::crossing`]: the watertight test
//! with half-open edges, so that a ray through an edge or a vertex that triangles share counts
//! once where the surface goes on across it. Plain [`intersect`](WatertightRay::intersect)
//! counts such a ray on every triangle that touches the point, which is right for the closest
//! hit (no ray slips through) but would count a crossing twice.
//!
//! Tests: `bvh::tests::crossings_*` (brute force over the same test, rays through shared
//! edges and vertices of closed meshes, points inside and outside).

use super::Bvh;
use super::bounds::{FAR_SCALE, RayBoxTest};
use super::node::{Child, EMPTY, WIDTH, decode};
use super::traverse::{Stack, can_hit};
use crate::accel::Hit;
use crate::ray::Ray;
use crate::triangle::WatertightRay;

impl Bvh {
    /// Calls `each` with every crossing of `ray` with the triangles (`t_min <= t < t_max` and
    /// `t` conservatively above zero, as for the closest hit), in no particular order. A ray
    /// through an edge or a vertex that triangles share crosses one of them where the surface
    /// goes on across the point (see [`WatertightRay::crossing`]).
    pub fn crossings(&self, ray: &Ray, mut each: impl FnMut(Hit)) {
        let wide = &self.wide;
        if !can_hit(ray) || wide.nodes.is_empty() {
            return;
        }
        let box_ray = RayBoxTest::new(ray);
        let margin = box_ray.margin(&wide.root);
        let triangle_ray = WatertightRay::new(ray);
        let limit = ray.t_max * FAR_SCALE;
        // The single-ray traversals' stack, on the call stack: no allocation per ray.
        let mut stack = Stack::<u32>::new();
        stack.push(0);
        while let Some(child) = stack.pop() {
            match decode(child) {
                Child::Node(index) => {
                    let node = &wide.nodes[index as usize];
                    for k in 0..WIDTH {
                        let entered = node.children[k] != EMPTY
                            && box_ray.enter_with_margin(&node.bounds(k), limit, margin).is_some();
                        if entered {
                            stack.push(node.children[k]);
                        }
                    }
                }
                Child::Leaf(offset) => {
                    for (triangle, [a, b, c]) in wide.leaves.leaf_triangles(offset) {
                        if let Some(h) = triangle_ray.crossing(a, b, c, ray.t_max) {
                            each(Hit { t: h.t, triangle, b1: h.b1, b2: h.b2 });
                        }
                    }
                }
                Child::Empty => {}
            }
        }
    }

    /// The number of [`crossings`](Self::crossings) of `ray`.
    pub fn count_crossings(&self, ray: &Ray) -> u32 {
        let mut count = 0;
        self.crossings(ray, |_| count += 1);
        count
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use crate::Bvh;
    use crate::ray::Ray;
    use crate::triangle::WatertightRay;

    /// A closed sphere of `rings × segments` quads (two triangles each, the poles' fans),
    /// wound counter-clockwise seen from outside.
    fn sphere(rings: usize, segments: usize) -> Vec<[Vec3; 3]> {
        let point = |i: usize, j: usize| {
            let theta = std::f32::consts::PI * i as f32 / rings as f32;
            let phi = std::f32::consts::TAU * (j % segments) as f32 / segments as f32;
            Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin())
        };
        let mut triangles = Vec::new();
        for i in 0..rings {
            for j in 0..segments {
                let (a, b, c, d) =
                    (point(i, j), point(i + 1, j), point(i + 1, j + 1), point(i, j + 1));
                if i > 0 {
                    triangles.push([a, d, c]);
                }
                if i + 1 < rings {
                    triangles.push([a, c, b]);
                }
            }
        }
        triangles
    }

    /// The unit cube's twelve triangles, wound counter-clockwise seen from outside.
    fn cube() -> Vec<[Vec3; 3]> {
        let v = |x: u8, y: u8, z: u8| Vec3::new(f32::from(x), f32::from(y), f32::from(z));
        let quads = [
            [v(0, 0, 0), v(0, 1, 0), v(1, 1, 0), v(1, 0, 0)],
            [v(0, 0, 1), v(1, 0, 1), v(1, 1, 1), v(0, 1, 1)],
            [v(0, 0, 0), v(1, 0, 0), v(1, 0, 1), v(0, 0, 1)],
            [v(0, 1, 0), v(0, 1, 1), v(1, 1, 1), v(1, 1, 0)],
            [v(0, 0, 0), v(0, 0, 1), v(0, 1, 1), v(0, 1, 0)],
            [v(1, 0, 0), v(1, 1, 0), v(1, 1, 1), v(1, 0, 1)],
        ];
        quads.iter().flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]]).collect()
    }

    fn brute_force(triangles: &[[Vec3; 3]], ray: &Ray) -> Vec<u32> {
        let w = WatertightRay::new(ray);
        (0..triangles.len() as u32)
            .filter(|&i| {
                let [a, b, c] = triangles[i as usize];
                w.crossing(a, b, c, ray.t_max).is_some()
            })
            .collect()
    }

    fn crossed(bvh: &Bvh, ray: &Ray) -> Vec<u32> {
        let mut ids = Vec::new();
        bvh.crossings(ray, |h| ids.push(h.triangle));
        ids.sort_unstable();
        ids
    }

    /// A deterministic stream of numbers in [0, 1).
    fn numbers(seed: u64) -> impl FnMut() -> f32 {
        let mut pcg = crate::sampling::Pcg32::new(seed, 0);
        move || pcg.next_f32()
    }

    #[test]
    fn crossings_are_brute_forces() {
        let triangles = sphere(24, 48);
        let bvh = Bvh::new(&triangles);
        let mut next = numbers(3);
        for _ in 0..2000 {
            let origin = Vec3::new(next(), next(), next()) * 4.0 - 2.0;
            let direction = Vec3::new(next(), next(), next()) - 0.5;
            let ray = Ray::new(origin, direction);
            assert_eq!(crossed(&bvh, &ray), brute_force(&triangles, &ray), "{ray:?}");
        }
    }

    #[test]
    fn crossings_through_shared_edges_and_vertices_count_once() {
        let bvh = Bvh::new(&cube());
        let centre = Vec3::splat(0.5);
        // From the centre through every corner, every edge's midpoint and every face's
        // diagonal (a shared edge of its two triangles): one crossing each.
        let mut targets = Vec::new();
        for x in [0.0, 0.5, 1.0] {
            for y in [0.0, 0.5, 1.0] {
                for z in [0.0, 0.5, 1.0] {
                    targets.push(Vec3::new(x, y, z));
                }
            }
        }
        targets.extend([Vec3::new(0.25, 0.25, 0.0), Vec3::new(1.0, 0.75, 0.75)]);
        for target in targets.into_iter().filter(|&t| t != centre) {
            let ray = Ray::new(centre, target - centre);
            assert_eq!(bvh.count_crossings(&ray), 1, "towards {target}");
            // The same line from outside, through the point and on through the cube: two.
            let outside = Ray::new(centre + (target - centre) * 3.0, centre - target);
            assert_eq!(bvh.count_crossings(&outside), 2, "from beyond {target}");
        }
    }

    #[test]
    fn a_ray_through_a_ridge_crosses_once_and_one_along_it_touches() {
        // Two triangles folded along the edge x = 0, z = 0: a roof, both sides facing up.
        let roof = [
            [Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0), Vec3::new(-1.0, 0.0, -1.0)],
            [Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, -1.0)],
        ];
        let bvh = Bvh::new(&roof);
        for y in [0.25f32, 0.5, 0.75] {
            // Down onto the ridge: the slopes lie on either side of it, one crossing.
            let ray = Ray::new(Vec3::new(0.0, y, 1.0), -Vec3::Z);
            assert_eq!(bvh.count_crossings(&ray), 1, "down at y = {y}");
            // Level across the ridge: both slopes lie below it as the ray sees them, so it
            // touches the roof without crossing: none or two.
            for dx in [1.0f32, -1.0] {
                let ray = Ray::new(Vec3::new(-2.0 * dx, y, 0.0), Vec3::new(dx, 0.0, 0.0));
                assert_eq!(bvh.count_crossings(&ray) % 2, 0, "level at y = {y}");
            }
        }
    }

    #[test]
    fn crossings_tell_inside_from_outside() {
        let triangles = sphere(16, 32);
        let bvh = Bvh::new(&triangles);
        let mut next = numbers(9);
        let directions = [Vec3::new(0.3, 0.8, -0.52), Vec3::X, Vec3::new(-0.1, -0.2, 0.97)];
        for _ in 0..3000 {
            let p = Vec3::new(next(), next(), next()) * 2.4 - 1.2;
            // The polyhedron is inside the unit sphere and holds the sphere of radius cos(π/16).
            let r = p.length();
            if (0.97..=1.0).contains(&r) {
                continue;
            }
            for d in directions {
                let inside = bvh.count_crossings(&Ray::new(p, d)) % 2 == 1;
                assert_eq!(inside, r < 0.97, "{p} along {d}");
            }
        }
        // Points on a grid, whose rays along the axes run through the sphere's vertices and
        // edges in its symmetry planes.
        for i in -6..=6 {
            for j in -6..=6 {
                let p = Vec3::new(i as f32 / 8.0, j as f32 / 8.0, 0.0);
                if p.length() >= 0.97 {
                    continue;
                }
                for d in [Vec3::X, Vec3::Y, -Vec3::Z, Vec3::new(1.0, 1.0, 0.0)] {
                    assert_eq!(bvh.count_crossings(&Ray::new(p, d)) % 2, 1, "{p} along {d}");
                }
            }
        }
    }
}
