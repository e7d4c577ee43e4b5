//! The bugs students hit in the lab, as tests: holes along triangle diagonals, cracks between
//! triangles, the first hit instead of the closest, and −0.0 direction components. Every test runs
//! on every accelerator: brute force, and the BVH with every build preset and instruction set.

use glam::{Mat3, Vec3};
use proptest::prelude::*;
use raylab::bvh::{BuildSettings, Bvh, Isa};
use raylab::{Accelerator, BruteForce, Ray, Triangle};

/// Brute force, and the BVH with every build preset and every instruction set this CPU has.
fn accelerators(triangles: &[Triangle]) -> Vec<(String, Box<dyn Accelerator>)> {
    let vertices: Vec<[Vec3; 3]> = triangles.iter().map(|t| [t.v0, t.v1, t.v2]).collect();
    let mut all: Vec<(String, Box<dyn Accelerator>)> =
        vec![("brute force".into(), Box::new(BruteForce::new(&vertices)))];
    for (preset, settings) in BuildSettings::PRESETS {
        for isa in Isa::ALL {
            if let Some(bvh) = Bvh::build(&vertices, &settings).with_isa(isa) {
                all.push((format!("bvh {preset} {}", isa.name()), Box::new(bvh)));
            }
        }
    }
    all
}

fn triangle(v0: Vec3, v1: Vec3, v2: Vec3) -> Triangle {
    Triangle::new(v0, v1, v2, Vec3::ONE)
}

/// A rotation and translation that make every vertex coordinate an inexact float.
fn awkward_frame(p: Vec3) -> Vec3 {
    Mat3::from_euler(glam::EulerRot::YXZ, 0.3, -0.7, 0.11) * p + Vec3::new(0.1, -3.3, 7.7)
}

/// Appends an `n×n` grid of quads with corners `point(i, j)`, each split along a diagonal (the
/// same one everywhere, or alternating), to `triangles`, and its grid points to `vertices`.
fn grid(
    n: usize,
    point: impl Fn(usize, usize) -> Vec3,
    alternate_diagonals: bool,
    triangles: &mut Vec<Triangle>,
    vertices: &mut Vec<Vec3>,
) {
    vertices.extend((0..=n).flat_map(|j| (0..=n).map(move |i| (i, j))).map(|(i, j)| point(i, j)));
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (point(i, j), point(i + 1, j), point(i + 1, j + 1), point(i, j + 1));
            if alternate_diagonals && (i + j) % 2 == 1 {
                triangles.extend([triangle(a, b, d), triangle(b, c, d)]);
            } else {
                triangles.extend([triangle(a, b, c), triangle(a, c, d)]);
            }
        }
    }
}

/// An `n×n` grid of quads over `[0,1]²` in the plane z = 0, split along alternating diagonals,
/// then moved into the awkward frame. Returns triangles and vertices.
fn tessellated_quad(n: usize) -> (Vec<Triangle>, Vec<Vec3>) {
    let (mut triangles, mut vertices) = (Vec::new(), Vec::new());
    let point = |i: usize, j: usize| {
        awkward_frame(Vec3::new(i as f32 / n as f32, j as f32 / n as f32, 0.0))
    };
    grid(n, point, true, &mut triangles, &mut vertices);
    (triangles, vertices)
}

/// A closed, subdivided cube: 6 faces of `n×n` quads, all sharing edges and vertices exactly.
fn closed_cube(n: usize) -> (Vec<Triangle>, Vec<Vec3>) {
    let (mut triangles, mut vertices) = (Vec::new(), Vec::new());
    let axes =
        [(Vec3::X, Vec3::Y, Vec3::Z), (Vec3::Y, Vec3::Z, Vec3::X), (Vec3::Z, Vec3::X, Vec3::Y)];
    for (u, v, w) in axes {
        for side in [-1.0f32, 1.0] {
            // Grid points computed from integers so that shared edges get identical vertices.
            let s = |k: usize| 2.0 * k as f32 / n as f32 - 1.0;
            let point = |i: usize, j: usize| awkward_frame(u * s(i) + v * s(j) + w * side);
            grid(n, point, false, &mut triangles, &mut vertices);
        }
    }
    (triangles, vertices)
}

/// Quasi-random unit directions covering the sphere (a Fibonacci spiral).
fn sphere_directions(count: usize) -> impl Iterator<Item = Vec3> {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..count).map(move |i| {
        let z = 1.0 - 2.0 * (i as f32 + 0.5) / count as f32;
        let r = (1.0 - z * z).sqrt();
        let phi = golden * i as f32;
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    })
}

#[test]
fn a_ray_through_the_shared_diagonal_of_two_triangles_hits() {
    // The lab's back wall: two triangles sharing the diagonal from (−1,−1,1) to (1,1,1).
    let (a, b, c, d) = (
        Vec3::new(-1.0, -1.0, 1.0),
        Vec3::new(1.0, -1.0, 1.0),
        Vec3::new(1.0, 1.0, 1.0),
        Vec3::new(-1.0, 1.0, 1.0),
    );
    let camera = Vec3::new(0.0, 0.0, -3.0);
    for (name, accel) in accelerators(&[triangle(a, b, c), triangle(a, c, d)]) {
        let mut misses = Vec::new();
        for i in 1..10_000 {
            // Points on the diagonal (most not representable), seen from the camera and from a
            // few other origins. (Its ends are the quad's outer corners, which rays may miss.)
            let s = i as f32 / 10_000.0;
            let target = a.lerp(c, s);
            for origin in [camera, Vec3::new(0.37, -0.21, -1.3), Vec3::new(-2.0, 1.5, 0.2)] {
                if accel.closest_hit(&Ray::new(origin, target - origin)).is_none() {
                    misses.push((origin, target));
                }
            }
        }
        assert!(
            misses.is_empty(),
            "{name}: {} rays slipped through the diagonal, e.g. {:?}",
            misses.len(),
            misses[0]
        );
    }
}

#[test]
fn no_cracks_in_a_finely_tessellated_quad() {
    let (triangles, vertices) = tessellated_quad(24);
    let origins = [
        awkward_frame(Vec3::new(0.5, 0.5, -2.0)),
        awkward_frame(Vec3::new(-0.3, 1.2, 0.7)),
        awkward_frame(Vec3::new(0.45, 0.55, -1e-3)),
    ];
    // A dense grid of targets that do not line up with the tessellation...
    let grid = 300;
    let mut targets: Vec<Vec3> = (1..grid)
        .flat_map(|j| (1..grid).map(move |i| (i, j)))
        .map(|(i, j)| awkward_frame(Vec3::new(i as f32 / grid as f32, j as f32 / grid as f32, 0.0)))
        .collect();
    // ...and every vertex and edge midpoint inside the quad, where cracks open.
    let n = 25;
    targets.extend(
        vertices
            .iter()
            .enumerate()
            .filter(|(k, _)| {
                let (i, j) = (k % n, k / n);
                i > 0 && j > 0 && i < n - 1 && j < n - 1
            })
            .map(|(_, v)| *v),
    );
    for t in &triangles {
        targets.extend([(t.v0 + t.v1) / 2.0, (t.v1 + t.v2) / 2.0, (t.v2 + t.v0) / 2.0]);
    }
    let inside = |p: Vec3| {
        let local = Mat3::from_euler(glam::EulerRot::YXZ, 0.3, -0.7, 0.11).transpose()
            * (p - Vec3::new(0.1, -3.3, 7.7));
        local.x > 1e-3 && local.y > 1e-3 && local.x < 1.0 - 1e-3 && local.y < 1.0 - 1e-3
    };
    let targets: Vec<Vec3> = targets.into_iter().filter(|p| inside(*p)).collect();
    for (name, accel) in accelerators(&triangles) {
        let (mut rays, mut misses) = (0, 0);
        for origin in origins {
            for target in &targets {
                rays += 1;
                if accel.closest_hit(&Ray::new(origin, *target - origin)).is_none() {
                    misses += 1;
                }
                assert!(accel.occluded(&Ray::new(origin, *target - origin)), "{name}");
            }
        }
        assert!(rays > 200_000, "{rays}");
        assert_eq!(misses, 0, "{name}: {misses} of {rays} rays went through cracks");
    }
}

#[test]
fn no_ray_escapes_a_closed_mesh() {
    let (triangles, vertices) = closed_cube(12);
    for (name, accel) in accelerators(&triangles) {
        let mut escaped = 0;
        let mut rays = 0;
        for origin in [Vec3::ZERO, Vec3::new(0.3, -0.6, 0.2), Vec3::new(-0.99, 0.99, 0.5)] {
            let origin = awkward_frame(origin);
            let directions = sphere_directions(20_000).chain(vertices.iter().map(|v| *v - origin));
            for direction in directions {
                rays += 1;
                let ray = Ray::new(origin, direction);
                if accel.closest_hit(&ray).is_none() || !accel.occluded(&ray) {
                    escaped += 1;
                }
            }
        }
        assert_eq!(escaped, 0, "{name}: {escaped} of {rays} rays escaped the closed cube");
    }
}

#[test]
fn the_nearer_of_two_overlapping_triangles_wins_in_either_order() {
    let near =
        triangle(Vec3::new(-1.0, -1.0, 1.0), Vec3::new(1.0, -1.0, 1.0), Vec3::new(0.0, 1.0, 1.0));
    let far =
        triangle(Vec3::new(-1.0, -1.0, 2.0), Vec3::new(1.0, -1.0, 2.0), Vec3::new(0.0, 1.0, 2.0));
    // Crossing triangles: which is nearer depends on where the ray goes.
    // z = 1 + x on the tilted one: nearer than `near` for x < 0, farther for x > 0.
    let tilted =
        triangle(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 2.0), Vec3::new(0.0, 1.0, 1.0));
    let ray = Ray::new(Vec3::new(0.0, 0.0, -1.0), Vec3::Z);
    for (order, nearest) in [([near, far], 0), ([far, near], 1)] {
        for (name, accel) in accelerators(&order) {
            let hit = accel.closest_hit(&ray).unwrap();
            assert_eq!(hit.triangle, nearest, "{name}");
            assert!((hit.t - 2.0).abs() < 1e-6);
        }
    }
    for (origin_x, expect_tilted) in [(-0.5f32, true), (0.5, false)] {
        let ray = Ray::new(Vec3::new(origin_x, -0.5, -1.0), Vec3::Z);
        for scene in [[near, tilted], [tilted, near]] {
            for (name, accel) in accelerators(&scene) {
                let hit = accel.closest_hit(&ray).unwrap();
                let hit_tilted = scene[hit.triangle as usize] == tilted;
                assert_eq!(hit_tilted, expect_tilted, "{name}: ray at x = {origin_x}");
            }
        }
    }
}

#[test]
fn equal_distances_go_to_the_lowest_index() {
    let tri =
        triangle(Vec3::new(-1.0, -1.0, 1.0), Vec3::new(1.0, -1.0, 1.0), Vec3::new(0.0, 1.0, 1.0));
    // Many copies, so that the BVH spreads them over several leaves and nodes.
    for (name, accel) in accelerators(&[tri; 100]) {
        let hit = accel.closest_hit(&Ray::new(Vec3::new(0.0, 0.0, -1.0), Vec3::Z)).unwrap();
        assert_eq!(hit.triangle, 0, "{name}");
    }
}

#[test]
fn negative_zero_direction_components_hit() {
    let floor = [
        triangle(Vec3::new(-1.0, 1.0, -1.0), Vec3::new(1.0, 1.0, -1.0), Vec3::new(1.0, 1.0, 1.0)),
        triangle(Vec3::new(-1.0, 1.0, -1.0), Vec3::new(1.0, 1.0, 1.0), Vec3::new(-1.0, 1.0, 1.0)),
    ];
    for (name, accel) in accelerators(&floor) {
        for direction in
            [Vec3::new(-0.0, 1.0, -0.0), Vec3::new(0.0, 1.0, -0.0), Vec3::new(-0.0, 1.0, 0.0)]
        {
            // Also from the floor's edges and corner, where the ray runs in a box's face plane.
            for origin in [
                Vec3::new(0.25, 0.0, 0.25),
                Vec3::ZERO,
                Vec3::new(-0.5, -7.0, 0.5),
                Vec3::new(-1.0, 0.0, 0.3),
                Vec3::new(1.0, 0.0, 1.0),
            ] {
                let ray = Ray::new(origin, direction);
                let hit = accel.closest_hit(&ray);
                assert!(hit.is_some(), "{name}: {origin} {direction:?}");
                assert!(accel.occluded(&ray));
            }
        }
    }
}

#[test]
fn closest_hit_respects_t_max_and_occluded_agrees() {
    let wall =
        triangle(Vec3::new(-1.0, -1.0, 1.0), Vec3::new(1.0, -1.0, 1.0), Vec3::new(0.0, 1.0, 1.0));
    let origin = Vec3::new(0.0, 0.0, -1.0);
    for (name, accel) in accelerators(&[wall]) {
        assert!(accel.closest_hit(&Ray::segment(origin, Vec3::Z, 1.99)).is_none(), "{name}");
        assert!(!accel.occluded(&Ray::segment(origin, Vec3::Z, 1.99)));
        assert!(accel.closest_hit(&Ray::segment(origin, Vec3::Z, 2.01)).is_some());
        assert!(accel.occluded(&Ray::segment(origin, Vec3::Z, 2.01)));
        // t_min excludes nearer hits.
        let mut ray = Ray::new(origin, Vec3::Z);
        ray.t_min = 2.5;
        assert!(accel.closest_hit(&ray).is_none() && !accel.occluded(&ray), "{name}");
        ray.t_min = 1.5;
        assert_eq!(accel.closest_hit(&ray).map(|h| h.t), Some(2.0), "{name}");
    }
}

fn finite_vec3(range: f32) -> impl Strategy<Value = Vec3> {
    (-range..range, -range..range, -range..range).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// A ray aimed at a point well inside a triangle hits it, near that point.
    #[test]
    fn rays_at_interior_points_hit(
        v0 in finite_vec3(100.0), v1 in finite_vec3(100.0), v2 in finite_vec3(100.0),
        origin in finite_vec3(100.0), s in 0.0f32..1.0, r in 0.0f32..1.0,
    ) {
        let tri = triangle(v0, v1, v2);
        // Barycentrics at least 0.05 from every edge.
        let u = 0.05 + 0.85 * s;
        let v = 0.05 + (0.9 - u) * r;
        let target = (1.0 - u - v) * v0 + u * v1 + v * v2;
        let area = (v1 - v0).cross(v2 - v0).length();
        let to_target = target - origin;
        // Skip nearly degenerate and nearly edge-on configurations, where "well inside" is moot.
        prop_assume!(area > 1.0 && to_target.length() > 1.0);
        prop_assume!(tri.normal.dot(to_target.normalize()).abs() > 0.05);
        let hit = BruteForce::new(&[tri.corners()]).closest_hit(&Ray::new(origin, to_target));
        prop_assert!(hit.is_some());
        let hit = hit.unwrap();
        prop_assert!((hit.t - 1.0).abs() < 1e-3, "t = {}", hit.t);
        prop_assert!((hit.b1 - u).abs() < 1e-2 && (hit.b2 - v).abs() < 1e-2);
    }

    /// Two triangles sharing an edge: a ray at any point of that edge hits one of them.
    #[test]
    fn shared_edges_are_watertight(
        a in finite_vec3(10.0), b in finite_vec3(10.0), c in finite_vec3(10.0), d in finite_vec3(10.0),
        origin in finite_vec3(10.0), s in 0.0f32..=1.0,
    ) {
        // Triangles (a, b, c) and (b, a, d) share the edge a–b; d is put across the edge from c.
        let middle = (a + b) / 2.0;
        let d = middle + (middle - c) * 0.7 + d * 0.05;
        let target = a.lerp(b, s);
        let direction = target - origin;
        prop_assume!(direction.length() > 1e-3);
        let pair = [triangle(a, b, c), triangle(b, a, d)];
        let ray = Ray::new(origin, direction);
        // Does the ray see c and d on opposite sides of the edge? Then the pair covers the edge.
        let side = |p: Vec3| (b - a).cross(p - a).dot(-direction);
        prop_assume!(side(c) * side(d) < 0.0);
        prop_assume!((b - a).cross(c - a).length() > 1e-3 && (b - a).cross(d - a).length() > 1e-3);
        prop_assert!(BruteForce::new(&pair.map(|t| t.corners())).closest_hit(&ray).is_some());
    }
}

/// The plain scalar loop that [`BruteForce`] must agree with exactly.
fn scalar_closest_hit(triangles: &[Triangle], ray: &Ray) -> Option<raylab::Hit> {
    let setup = raylab::triangle::WatertightRay::new(ray);
    let mut closest = None;
    let mut t_max = ray.t_max;
    for (i, t) in triangles.iter().enumerate() {
        if let Some(h) = setup.intersect(t.v0, t.v1, t.v2, t_max) {
            t_max = h.t;
            closest = Some(raylab::Hit { t: h.t, triangle: i as u32, b1: h.b1, b2: h.b2 });
        }
    }
    closest
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1000))]

    /// The batched pre-test of [`BruteForce`] never drops a hit that the scalar test finds, and
    /// adds none: the answers are identical, bit for bit, also for rays aimed exactly at edges
    /// and vertices and for degenerate triangles.
    #[test]
    fn batched_and_scalar_tests_agree(
        vertices in proptest::collection::vec(finite_vec3(4.0), 3..60),
        origin in finite_vec3(8.0),
        aim in 0usize..1000, s in 0.0f32..=1.0, t_max in prop_oneof![Just(f32::INFINITY), 0.1f32..3.0],
    ) {
        let mut triangles: Vec<Triangle> = vertices.chunks_exact(3).map(|v| triangle(v[0], v[1], v[2])).collect();
        // A degenerate triangle among them.
        triangles.push(triangle(vertices[0], vertices[1], vertices[0]));
        let target_triangle = triangles[aim % triangles.len()];
        // Aim at a vertex, an edge or the inside, exactly.
        let target = match aim % 3 {
            0 => target_triangle.v0,
            1 => target_triangle.v0.lerp(target_triangle.v1, s),
            _ => target_triangle.v0.lerp(target_triangle.v1, s).lerp(target_triangle.v2, 0.5),
        };
        prop_assume!(target != origin);
        let ray = Ray::segment(origin, target - origin, t_max);
        let expected = scalar_closest_hit(&triangles, &ray);
        for (name, accel) in accelerators(&triangles) {
            prop_assert_eq!(accel.closest_hit(&ray), expected, "{}", name);
            prop_assert_eq!(accel.occluded(&ray), expected.is_some(), "{}", name);
        }
        prop_assert_eq!(BruteForce::new(&triangles.iter().map(Triangle::corners).collect::<Vec<_>>()).triangles().count(), triangles.len());
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1000))]

    /// The pre-test itself: every triangle that the scalar test hits within `t_max` has its bit
    /// set, for several `t_max` (so a wrongly dropped farther triangle cannot hide behind a
    /// nearer one).
    #[test]
    fn the_pre_test_keeps_every_triangle_the_scalar_test_hits(
        vertices in proptest::collection::vec(finite_vec3(4.0), 24..25),
        origin in finite_vec3(8.0),
        aim in 0usize..8, s in 0.0f32..=1.0,
    ) {
        let triangles: Vec<[Vec3; 3]> = vertices.chunks_exact(3).map(|v| [v[0], v[1], v[2]]).collect();
        let [v0, v1, _] = triangles[aim];
        let target = if aim % 2 == 0 { v0 } else { v0.lerp(v1, s) };
        prop_assume!(target != origin);
        let ray = raylab::triangle::WatertightRay::new(&Ray::new(origin, target - origin));
        let block = &raylab::triangle::TriangleBlock::<8>::pack(triangles.iter().copied())[0];
        for t_max in [f32::INFINITY, 2.0, 1.0, 0.5] {
            let mask = ray.block_candidates(block, t_max);
            for (lane, [a, b, c]) in triangles.iter().enumerate() {
                if ray.intersect(*a, *b, *c, t_max).is_some() {
                    prop_assert!(mask & (1 << lane) != 0, "lane {} dropped at t_max {}", lane, t_max);
                }
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// Whether a hit counts depends on its own `t` alone: with `t_max` just above, at, or just
    /// below the hit's `t`, the test accepts exactly when `t < t_max`. (Otherwise the closest hit
    /// would depend on which triangle tightened `t_max` first, and accelerators could disagree.)
    #[test]
    fn t_max_decides_on_t_alone(
        v0 in finite_vec3(300.0), v1 in finite_vec3(300.0), v2 in finite_vec3(300.0),
        origin in finite_vec3(300.0), s in 0.0f32..1.0, r in 0.0f32..1.0,
    ) {
        let target = v0.lerp(v1, s).lerp(v2, r);
        prop_assume!(target != origin);
        let ray = raylab::triangle::WatertightRay::new(&Ray::new(origin, target - origin));
        let Some(hit) = ray.intersect(v0, v1, v2, f32::INFINITY) else { return Ok(()) };
        let block = &raylab::triangle::TriangleBlock::<4>::pack([[v0, v1, v2]])[0];
        let up = raylab::float::next_float_up(hit.t);
        let down = raylab::float::next_float_down(hit.t);
        for t_max in [up, raylab::float::next_float_up(up), hit.t, down] {
            let accepted = ray.intersect(v0, v1, v2, t_max);
            prop_assert_eq!(accepted.is_some(), hit.t < t_max, "t {} t_max {}", hit.t, t_max);
            if let Some(h) = accepted {
                prop_assert_eq!(h, hit);
                prop_assert!(ray.block_candidates(block, t_max) & 1 == 1);
            }
        }
    }
}
