//! The BVH gives exactly the brute-force answers: the same `t`, bit for bit, and the same triangle
//! (ties at equal `t` go to the lowest index in both), for every build preset, both collapses and
//! every instruction set, on random triangle soups and hostile inputs.

use glam::Vec3;
use proptest::prelude::*;
use raylab::accel::{HitRows, ROWS, RayRows};
use raylab::bvh::{BuildSettings, Bvh, Collapse, Isa};
use raylab::{Accelerator, BruteForce, Hit, Ray};

/// Every BVH variant over `triangles`: each preset's tree, small-scene leaves (one block), the
/// collapse of least cost over the finest binary trees, and
/// (up to 4,096 triangles) the flat list that small scenes answer single rays from.
fn bvhs(triangles: &[[Vec3; 3]]) -> Vec<(String, Bvh)> {
    let mut all = Vec::new();
    let small = ("small-scene", BuildSettings::for_triangles(0));
    // The collapse of least cost over binary leaves of one triangle, and on small-scene leaves.
    let optimal = |binary_leaf_size| Collapse::Optimal { binary_leaf_size };
    let finest = ("optimal-1", BuildSettings { collapse: optimal(1), ..BuildSettings::MEDIUM });
    let small_optimal = (
        "small-optimal",
        BuildSettings { collapse: optimal(2), ..BuildSettings::for_triangles(0) },
    );
    let tree = |settings: BuildSettings| BuildSettings { flat_limit: 0, ..settings };
    let mut variants: Vec<(&str, BuildSettings)> = BuildSettings::PRESETS
        .into_iter()
        .chain([small, finest, small_optimal])
        .map(|(n, s)| (n, tree(s)))
        .collect();
    if triangles.len() <= 4096 {
        variants.push(("flat", BuildSettings { flat_limit: usize::MAX, ..BuildSettings::MEDIUM }));
    }
    for (preset, settings) in variants {
        for isa in Isa::ALL {
            match Bvh::build(triangles, &settings).with_isa(isa) {
                Some(bvh) => all.push((format!("{preset} {}", isa.name()), bvh)),
                None => skipped_isa(isa),
            }
        }
    }
    all
}

/// Says once per test binary that this CPU cannot run an instruction set's kernels.
fn skipped_isa(isa: Isa) {
    static SAID: std::sync::Once = std::sync::Once::new();
    SAID.call_once(|| {
        eprintln!("note: this CPU lacks {}: its kernels are not tested here", isa.name())
    });
}

fn brute_force(triangles: &[[Vec3; 3]]) -> BruteForce {
    BruteForce::new(triangles)
}

/// Compares every BVH with brute force on `rays`, one at a time and as packets (the whole slice
/// at once, which the BVH cuts into packets of 64); returns how many rays hit something.
fn assert_agreement(triangles: &[[Vec3; 3]], rays: &[Ray]) -> Result<usize, TestCaseError> {
    let reference = brute_force(triangles);
    let expected: Vec<_> =
        rays.iter().map(|r| (reference.closest_hit(r), reference.occluded(r))).collect();
    for (name, bvh) in bvhs(triangles) {
        let mut stats = raylab::bvh::TraversalStats::default();
        for (ray, (closest, occluded)) in rays.iter().zip(&expected) {
            prop_assert_eq!(bvh.closest_hit(ray), *closest, "{}: {:?}", name, ray);
            prop_assert_eq!(bvh.occluded(ray), *occluded, "{}: {:?}", name, ray);
            // Counting changes nothing.
            prop_assert_eq!(bvh.closest_hit_counted(ray, &mut stats), *closest, "{}", name);
            prop_assert_eq!(bvh.occluded_counted(ray, &mut stats), *occluded, "{}", name);
        }
        let mut closest = vec![None; rays.len()];
        let mut occluded = vec![false; rays.len()];
        bvh.closest_hits(rays, &mut closest);
        bvh.occluded_each(rays, &mut occluded);
        for (i, (c, o)) in expected.iter().enumerate() {
            prop_assert_eq!(closest[i], *c, "{} packet: {:?}", name, rays[i]);
            prop_assert_eq!(occluded[i], *o, "{} packet: {:?}", name, rays[i]);
        }
        // In rows, a tile at a time: hits into rows that hold wrong answers first (those past
        // the tile must stay), occlusion from rays in rows.
        for (k, (tile, expected)) in rays.chunks(ROWS).zip(expected.chunks(ROWS)).enumerate() {
            let wrong = Some(Hit { t: -1.0, triangle: 7, b1: 0.5, b2: 0.5 });
            let mut hits = HitRows::default();
            (0..ROWS).for_each(|i| hits.set(i, wrong));
            bvh.closest_hits_rows(tile, &mut hits);
            let blocked = bvh.occluded_rows(&RayRows::from_rays(tile));
            for (i, (c, o)) in expected.iter().enumerate() {
                prop_assert_eq!(hits.hit(i), *c, "{} rows: {:?}", name, tile[i]);
                prop_assert_eq!(blocked >> i & 1 != 0, *o, "{} rows: {:?}", name, tile[i]);
            }
            prop_assert!((tile.len()..ROWS).all(|i| hits.hit(i) == wrong), "{} tile {}", name, k);
            let past = blocked.checked_shr(tile.len() as u32).unwrap_or(0);
            prop_assert_eq!(past, 0, "{}: no bit past the rays", name);
        }
    }
    Ok(expected.iter().filter(|(c, _)| c.is_some()).count())
}

/// A tile of `side`×`side` rays from `origin` through a small square of directions around
/// `centre` (spread `spread`), as a pinhole camera makes them; with `jitter`, every ray starts
/// at its own point near `origin` (as a lens or an area light would).
fn tile(origin: Vec3, centre: Vec3, spread: f32, side: usize, jitter: f32, t_max: f32) -> Vec<Ray> {
    let (u, v) = centre.normalize_or(Vec3::Z).any_orthonormal_pair();
    let mut rays = Vec::new();
    for y in 0..side {
        for x in 0..side {
            let (fx, fy) = (x as f32 / side as f32 - 0.5, y as f32 / side as f32 - 0.5);
            let d = centre + spread * (fx * u + fy * v);
            let o = origin + jitter * (fy * u - fx * v);
            rays.push(Ray::segment(o, d, t_max));
        }
    }
    rays
}

fn vec3(range: f32) -> impl Strategy<Value = Vec3> {
    (-range..range, -range..range, -range..range).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// Small triangles scattered in a box, some sharing vertices, some on a coarse grid (so that
/// boxes share planes with ray origins and with each other).
fn soup() -> impl Strategy<Value = Vec<[Vec3; 3]>> {
    proptest::collection::vec((vec3(10.0), vec3(1.5), vec3(1.5), any::<bool>()), 1..400).prop_map(
        |items| {
            items
                .into_iter()
                .map(|(p, a, b, snap)| {
                    let p = if snap { (p * 2.0).round() * 0.5 } else { p };
                    let (a, b) = if snap {
                        ((a * 2.0).round() * 0.5, (b * 2.0).round() * 0.5)
                    } else {
                        (a, b)
                    };
                    [p, p + a, p + b]
                })
                .collect()
        },
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn random_soups_agree_with_brute_force(
        triangles in soup(),
        origins in proptest::collection::vec(vec3(14.0), 8),
        targets in proptest::collection::vec((0usize..10_000, 0.0f32..=1.0, 0.0f32..=1.0), 24),
        t_max in prop_oneof![Just(f32::INFINITY), 1.0f32..30.0],
    ) {
        let mut rays = Vec::new();
        for (k, &(aim, s, r)) in targets.iter().enumerate() {
            let origin = origins[k % origins.len()];
            let [a, b, c] = triangles[aim % triangles.len()];
            // At a vertex, along an edge, or inside: exactly where ties and cracks happen.
            let target = match k % 3 {
                0 => a,
                1 => a.lerp(b, s),
                _ => a.lerp(b, s).lerp(c, r),
            };
            if target != origin {
                rays.push(Ray::segment(origin, target - origin, t_max));
                // And an axis-parallel ray with signed zeros through the same point.
                let axis = aim % 3;
                let mut d = Vec3::splat(if k % 2 == 0 { 0.0 } else { -0.0 });
                d[axis] = if origin[axis] < target[axis] { 1.0 } else { -1.0 };
                let mut o = target;
                o[axis] = origin[axis];
                if o != target {
                    rays.push(Ray::segment(o, d, t_max));
                }
            }
        }
        assert_agreement(&triangles, &rays)?;
    }

    /// Coherent packets: tiles of camera rays (and of rays from nearby origins) aimed at the
    /// soup, wide and narrow, some across a direction axis (so that packets split by octant),
    /// and a shadow-like tile of segments toward one point.
    #[test]
    fn coherent_tiles_agree_with_brute_force(
        triangles in soup(),
        origin in vec3(14.0),
        aim in 0usize..10_000,
        spread in prop_oneof![Just(0.0f32), 1e-3f32..0.1, 0.1f32..2.0],
        jitter in prop_oneof![Just(0.0f32), 1e-3f32..3.0],
        side in 2usize..12,
        t_max in prop_oneof![Just(f32::INFINITY), 1.0f32..30.0],
    ) {
        let [a, b, c] = triangles[aim % triangles.len()];
        let target = (a + b + c) / 3.0;
        prop_assume!(target != origin);
        let mut rays = tile(origin, target - origin, spread, side, jitter, t_max);
        // Segments from points of the tile's hits toward the origin, as shadow rays to a light.
        let reference = brute_force(&triangles);
        for ray in rays.clone() {
            if let Some(hit) = reference.closest_hit(&ray) {
                let p = ray.at(hit.t * 0.999);
                rays.push(Ray::segment(p, origin - p, 1.0));
            }
        }
        assert_agreement(&triangles, &rays)?;
    }
}

#[test]
fn coplanar_grids_and_duplicates_agree() {
    // A grid of quads where many rays hit shared edges and vertices at equal t, plus a duplicate
    // copy of the whole grid (every hit is a tie between two triangles).
    let n = 16;
    let mut triangles = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let p = |x: usize, y: usize| Vec3::new(x as f32 / n as f32, y as f32 / n as f32, 1.0);
            triangles.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
            triangles.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
        }
    }
    let copy = triangles.clone();
    triangles.extend(copy);
    let mut rays = Vec::new();
    for j in 0..=4 * n {
        for i in 0..=4 * n {
            let target = Vec3::new(i as f32 / (4 * n) as f32, j as f32 / (4 * n) as f32, 1.0);
            for origin in [Vec3::new(0.5, 0.5, -1.0), Vec3::new(-0.3, 1.7, 0.2)] {
                rays.push(Ray::new(origin, target - origin));
            }
            rays.push(Ray::new(Vec3::new(target.x, target.y, 0.0), Vec3::new(-0.0, 0.0, 1.0)));
        }
    }
    let hits = assert_agreement(&triangles, &rays).unwrap();
    assert!(hits > rays.len() / 2, "{hits} of {}", rays.len());
}

#[test]
fn hostile_inputs_do_not_panic_and_agree() {
    let big = 3e38f32;
    let cases: Vec<Vec<[Vec3; 3]>> = vec![
        // Huge coordinates: box extents overflow to infinity.
        vec![[Vec3::splat(-big), Vec3::new(big, -big, 0.0), Vec3::splat(big)]],
        // Tiny triangles near zero, subnormal sizes.
        (0..50)
            .map(|i| {
                let p = Vec3::splat(i as f32 * 1e-40);
                [p, p + Vec3::X * 1e-39, p + Vec3::Y * 1e-39]
            })
            .collect(),
        // All triangles identical.
        vec![[Vec3::ZERO, Vec3::X, Vec3::Y]; 300],
        // All centroids identical, different sizes.
        (1..200)
            .map(|i| {
                let s = i as f32;
                [Vec3::new(-s, -s, 0.0), Vec3::new(s, -s, 0.0), Vec3::new(0.0, 2.0 * s, 0.0)]
            })
            .collect(),
        // A flat layer (zero extent along z for every box).
        (0..300)
            .map(|i| {
                let p = Vec3::new((i % 20) as f32, (i / 20) as f32, 0.0);
                [p, p + Vec3::X, p + Vec3::Y]
            })
            .collect(),
    ];
    for triangles in cases {
        let mut rays = vec![
            Ray::new(Vec3::new(0.2, 0.2, -1.0), Vec3::Z),
            Ray::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z),
            Ray::new(Vec3::new(-5.0, 0.25, 0.0), Vec3::X),
            Ray::new(Vec3::new(0.0, 0.0, -1.0), Vec3::new(-0.0, -0.0, 1.0)),
            Ray::new(Vec3::new(1e-40, 1e-40, -1.0), Vec3::Z),
            Ray::new(Vec3::NAN, Vec3::Z),
            Ray::new(Vec3::ZERO, Vec3::ZERO),
            Ray::new(Vec3::new(0.3, 0.3, -1.0), Vec3::new(f32::INFINITY, 0.0, 1.0)),
        ];
        for i in 0..64 {
            let a = i as f32 * 0.1;
            rays.push(Ray::new(
                Vec3::new(a.sin(), a.cos(), -3.0),
                Vec3::new(-a.sin() * 0.3, 0.1, 1.0),
            ));
        }
        assert_agreement(&triangles, &rays).unwrap();
    }
}

#[test]
fn non_finite_and_zero_area_triangles_are_left_out_but_keep_their_indices() {
    let triangles = vec![
        [Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0)],
        [Vec3::NAN, Vec3::X, Vec3::Y],
        [Vec3::new(f32::INFINITY, 0.0, 0.0), Vec3::X, Vec3::Y],
        [Vec3::new(-1.0, -1.0, 2.0), Vec3::new(1.0, -1.0, 2.0), Vec3::new(0.0, 1.0, 2.0)],
    ];
    let bvh = Bvh::build(&triangles, &BuildSettings::default());
    assert_eq!(bvh.stats().triangles, 4);
    assert_eq!(bvh.stats().indexed_triangles, 1);
    let hit = bvh.closest_hit(&Ray::new(Vec3::ZERO, Vec3::Z)).unwrap();
    assert_eq!((hit.triangle, hit.t), (3, 2.0));
}

/// Rays from around a mesh's bounding box toward random points of random triangles (and a few
/// random directions), deterministic.
fn mesh_rays(triangles: &[[Vec3; 3]], count: usize) -> Vec<Ray> {
    let (lo, hi) = triangles
        .iter()
        .flatten()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    let centre = 0.5 * (lo + hi);
    let radius = 0.5 * (hi - lo).length();
    let mut state = 12345u64;
    let mut next = move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((state >> 40) as f32) / (1u64 << 24) as f32
    };
    (0..count)
        .map(|i| {
            let on_sphere =
                Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize_or(Vec3::X);
            let origin = if i % 4 == 0 { centre } else { centre + on_sphere * radius * 1.5 };
            let [a, b, c] = triangles[(next() * triangles.len() as f32) as usize % triangles.len()];
            let target = a.lerp(b, next()).lerp(c, next());
            let direction = if i % 7 == 0 { on_sphere } else { target - origin };
            Ray::new(origin, direction)
        })
        .collect()
}

fn mesh_agrees(path: &std::path::Path, rays: usize) {
    let mesh = raylab::scene::load_mesh(path).unwrap().mesh;
    let triangles: Vec<[Vec3; 3]> = mesh.triangle_vertices().collect();
    let mut rays = mesh_rays(&triangles, rays);
    // And two 8×8 tiles of camera rays, from in front and from a corner.
    let frame = raylab::ray_sets::Frame::of(&mesh).unwrap();
    let camera = raylab::ray_sets::primary_rays(&frame, 32, 32, 32.0);
    for (y, row) in camera.chunks(32).enumerate() {
        if (12..20).contains(&y) {
            rays.extend_from_slice(&row[12..20]);
        }
    }
    let (lo, hi) = mesh.bounds().unwrap();
    rays.extend(tile(hi + (hi - lo), 0.5 * (lo + hi) - hi - (hi - lo), 0.3, 8, 0.0, f32::INFINITY));
    let hits = assert_agreement(&triangles, &rays).unwrap();
    eprintln!(
        "{}: {} triangles, {hits} of {} rays hit",
        path.display(),
        triangles.len(),
        rays.len()
    );
    assert!(hits > rays.len() / 2);
}

#[test]
fn the_repository_meshes_agree_with_brute_force() {
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes");
    for (file, rays) in [
        ("teapot.obj", 2000),
        ("bunny_lowres.obj", 2000),
        ("cornell_box/cornell_box.obj", 2000),
        ("spider/spider.obj", 2000),
        ("bunny.obj.gz", 150),
    ] {
        mesh_agrees(&data.join(file), rays);
    }
}

/// The big meshes of `shared/data` beside the checkout (not in the repository):
/// `cargo test --release -p raylab --test bvh -- --ignored`.
#[test]
#[ignore = "needs ../shared/data and a release build"]
fn the_shared_meshes_agree_with_brute_force() {
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data");
    for file in ["dragon_res2.obj.gz", "2CylinderEngine/2CylinderEngine.obj.gz", "dragon.obj.gz"] {
        mesh_agrees(&data.join(file), 100);
    }
}

/// Build settings and instruction sets change speed, never pixels: a model rendered with the
/// lab's light model (shadow rays included) through every BVH variant gives the same film as
/// through brute force, value for value.
#[test]
fn every_bvh_variant_renders_the_same_pixels() {
    use raylab::{Camera, Lab, Scene, Stage, render};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/meshes/spider/spider.obj");
    let scene = Scene::from_mesh(&raylab::scene::load_mesh(&path).unwrap().mesh);
    let (lo, hi) = scene.bounds().unwrap();
    let camera = Camera::framing(lo, hi, 96, 64);
    let film_of = |accel: &dyn Accelerator| {
        let integrator = Lab::new(&scene, accel, Stage::Ambient);
        render(&camera, &integrator, &|_| {}).unwrap().to_rgb8_clamped().unwrap()
    };
    let reference = film_of(&BruteForce::new(&scene.vertices()));
    let covered = reference.pixels().filter(|p| p.0 != [0, 0, 0]).count();
    assert!(covered > 96 * 64 / 10, "the spider covers only {covered} pixels");
    let vertices: Vec<[Vec3; 3]> = scene.vertices();
    for (name, bvh) in bvhs(&vertices) {
        assert!(film_of(&bvh) == reference, "{name} changed pixels");
    }
}

/// A flat, axis-aligned triangle seen along another axis: the watertight test's `t` (0.99999917)
/// rounds below the triangle's box entry (1.0) by more than the slab test's own rounding. The
/// BVH must still find it, on a segment that ends in between and behind a nearer competitor
/// (the review's counterexample to an unpadded box test).
#[test]
fn hits_that_round_below_their_box_entry_are_not_pruned() {
    let o = Vec3::new(-0.9050156, -0.5129226, -1.2556036);
    let d = Vec3::new(-0.13466823, -0.27086824, 0.26947773);
    let flat = [
        Vec3::new(-1.052601, -1.2355757, -0.9861258),
        Vec3::new(-1.0098381, 0.25269437, -0.9861258),
        Vec3::new(-1.0920787, 0.3346547, -0.9861258),
    ];
    // A small triangle across the ray at t ≈ 0.9999994, and fillers so the two get leaves of
    // their own.
    let p = o + 0.9999994 * d;
    let u = d.any_orthonormal_vector() * 0.01;
    let w = d.normalize().cross(u);
    let mut triangles = vec![flat];
    let centre = (flat[0] + flat[1] + flat[2]) / 3.0;
    for k in 0..7 {
        let c = centre + Vec3::new(0.0, 0.002 * k as f32, 0.001);
        triangles.push([c, c + Vec3::X * 0.001, c + Vec3::Y * 0.001]);
    }
    triangles.push([p - u - w, p + u - w, p + 2.0 * w]);
    for k in 0..7 {
        let c = p + Vec3::new(0.0, 0.0, -0.3 - 0.002 * k as f32);
        triangles.push([c, c + Vec3::Y * 0.001, c + Vec3::X * 0.001]);
    }
    let rays = [Ray::new(o, d), Ray::segment(o, d, 0.9999995)];
    assert_agreement(&triangles, &rays).unwrap();
    assert_agreement(&triangles[..1], &rays).unwrap();
    assert!(brute_force(&triangles[..1]).occluded(&rays[1]), "the case still exercises the bug");
}

#[test]
fn rays_with_nan_or_empty_ranges_agree_on_every_kernel() {
    let triangles =
        [[Vec3::new(0.0, 0.0, 5.0), Vec3::new(1.0, 0.0, 5.0), Vec3::new(0.0, 1.0, 5.0)]];
    // Through the triangle's edge (an exactly zero edge function) and through its inside.
    let mut rays = Vec::new();
    for origin in [Vec3::new(0.5, 0.0, 0.0), Vec3::new(0.2, 0.2, 0.0)] {
        for (t_min, t_max) in [(0.0, f32::NAN), (f32::NAN, 10.0), (6.0, 4.0), (0.0, f32::INFINITY)]
        {
            let mut ray = Ray::segment(origin, Vec3::Z, t_max);
            ray.t_min = t_min;
            rays.push(ray);
        }
    }
    let hits = assert_agreement(&triangles, &rays).unwrap();
    assert_eq!(hits, 2, "only the two rays with a valid range hit");
}

/// Every variant, refitted to moved triangles, gives brute force's answers for the new
/// positions (single rays, packets, and batches in lanes): vertices jittered, a cluster moved far away, one triangle
/// flattened onto a line and one given a NaN vertex (both then never hit). Refitting to the
/// build's own positions changes nothing; a wrong count, or a triangle the build left out that
/// now has area, is refused and leaves the tree as it was.
#[test]
fn refitted_trees_agree_with_brute_force_on_moved_triangles() {
    let mut state = 99u64;
    let mut next = move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((state >> 40) as f32) / (1u64 << 24) as f32
    };
    let mut vec = move || Vec3::new(next(), next(), next());
    for count in [20usize, 400] {
        let mut triangles: Vec<[Vec3; 3]> = (0..count)
            .map(|_| {
                let p = vec() * 10.0;
                [p, p + vec(), p + vec()]
            })
            .collect();
        triangles[3] = [Vec3::ONE; 3]; // zero area at build: left out
        let mut moved: Vec<[Vec3; 3]> = triangles
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let shift = if i % 5 == 0 { Vec3::new(30.0, -5.0, 2.0) } else { Vec3::ZERO };
                t.map(|v| v + shift + (vec() - 0.5) * 0.3)
            })
            .collect();
        moved[3] = [Vec3::ONE; 3];
        // Flattened onto a line (exactly: zero area), in the middle of the others, where the
        // lane test's rounded edge functions could see area.
        let a = moved[7][0].round();
        moved[7] = [a, a + Vec3::new(1.0, 0.5, 0.25), a + Vec3::new(2.0, 1.0, 0.5)];
        moved[8][1] = Vec3::NAN;
        let rays = [mesh_rays(&triangles, 300), mesh_rays(&moved, 300)].concat();
        let brute = BruteForce::new(&moved);
        let expected: Vec<_> =
            rays.iter().map(|r| (brute.closest_hit(r), brute.occluded(r))).collect();
        assert!(expected.iter().filter(|e| e.0.is_some()).count() > 100);
        for (name, mut bvh) in bvhs(&triangles) {
            // The build's own positions: the same answers as the unrefitted tree.
            let before: Vec<_> = rays.iter().map(|r| bvh.closest_hit(r)).collect();
            bvh.refit(&triangles).unwrap();
            assert!(rays.iter().zip(&before).all(|(r, b)| bvh.closest_hit(r) == *b), "{name}");
            // Refused: the tree is left as it was.
            let mut revived = triangles.clone();
            revived[3] = [Vec3::ZERO, Vec3::X, Vec3::Y];
            assert_eq!(bvh.refit(&revived), Err(raylab::bvh::RefitError::NewTriangle(3)));
            assert!(matches!(
                bvh.refit(&triangles[1..]),
                Err(raylab::bvh::RefitError::TriangleCount { .. })
            ));
            assert!(rays.iter().zip(&before).all(|(r, b)| bvh.closest_hit(r) == *b), "{name}");
            bvh.refit(&moved).unwrap();
            assert_eq!(bvh.stats().indexed_triangles, count - 3, "{name}");
            for (ray, (closest, occluded)) in rays.iter().zip(&expected) {
                assert_eq!(bvh.closest_hit(ray), *closest, "{name}: {ray:?}");
                assert_eq!(bvh.occluded(ray), *occluded, "{name}: {ray:?}");
            }
            let mut closest = vec![None; rays.len()];
            let mut occluded = vec![false; rays.len()];
            bvh.closest_hits(&rays, &mut closest);
            bvh.occluded_each(&rays, &mut occluded);
            for (i, (c, o)) in expected.iter().enumerate() {
                assert_eq!((closest[i], occluded[i]), (*c, *o), "{name} packet: {:?}", rays[i]);
            }
            // Incoherent batches: in lanes against the flat list of a small scene, into buffers
            // that hold wrong answers first.
            closest.fill(Some(raylab::Hit { t: -1.0, triangle: 7, b1: 0.0, b2: 0.0 }));
            occluded.iter_mut().enumerate().for_each(|(i, o)| *o = i % 2 == 0);
            bvh.closest_hits_incoherent(&rays, &mut closest);
            bvh.occluded_incoherent(&rays, &mut occluded);
            for (i, (c, o)) in expected.iter().enumerate() {
                assert_eq!((closest[i], occluded[i]), (*c, *o), "{name} lanes: {:?}", rays[i]);
            }
        }
    }
}
