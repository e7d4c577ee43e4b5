//! Instancing: a mesh drawn in several places is stored once, under a two-level BVH, and rays
//! find through it what they find on the flattened scene — no cracks, the brute-force answers,
//! and the same picture.

use std::path::{Path, PathBuf};

use glam::{Affine3A, Quat, Vec3};
use raylab::accel::{HitRows, ROWS, RayRows};
use raylab::bvh::TwoLevel;
use raylab::scene::load_mesh;
use raylab::{Accelerator, BruteForce, Geometry, Hit, Mesh, Ray, Scene, SceneBvh};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes").join(name)
}

/// A small deterministic generator (SplitMix64), for reproducible rays.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }

    fn in_box(&mut self, lo: Vec3, hi: Vec3) -> Vec3 {
        lo + (hi - lo) * Vec3::new(self.next(), self.next(), self.next())
    }
}

/// A closed cube `[−1, 1]³` of `n × n` quads a face, its vertices shared along the edges
/// (welded), wound counter-clockwise seen from outside.
fn closed_cube(n: u32) -> Mesh {
    let mut positions = Vec::new();
    let mut index = std::collections::HashMap::new();
    let mut vertex = |p: Vec3| {
        let key = p.to_array().map(f32::to_bits);
        *index.entry(key).or_insert_with(|| {
            positions.push(p);
            positions.len() as u32 - 1
        })
    };
    let mut triangles = Vec::new();
    for axis in 0..3 {
        for side in [-1.0f32, 1.0] {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let at = |i: u32, j: u32| {
                let mut p = Vec3::ZERO;
                p[axis] = side;
                p[u] = -1.0 + 2.0 * i as f32 / n as f32;
                p[v] = -1.0 + 2.0 * j as f32 / n as f32;
                p
            };
            for j in 0..n {
                for i in 0..n {
                    let q =
                        [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)].map(&mut vertex);
                    // (u × v) is +axis: counter-clockwise from outside on the + side.
                    if side > 0.0 {
                        triangles.extend([[q[0], q[1], q[2]], [q[0], q[2], q[3]]]);
                    } else {
                        triangles.extend([[q[0], q[2], q[1]], [q[0], q[3], q[2]]]);
                    }
                }
            }
        }
    }
    Mesh { name: "cube".into(), positions, triangles, ..Mesh::default() }
}

/// Placements that make rounding hard: a turn with unequal scales far from the origin, a mirror,
/// a tiny copy and a large one.
fn awkward_transforms() -> Vec<Affine3A> {
    vec![
        Affine3A::from_scale_rotation_translation(
            Vec3::new(0.7, 1.9, 0.31),
            Quat::from_euler(glam::EulerRot::YXZ, 0.4, -1.1, 0.27),
            Vec3::new(13.1, -4.7, 8.3),
        ),
        Affine3A::from_scale_rotation_translation(
            Vec3::new(-1.0, 1.0, 1.3),
            Quat::from_rotation_y(2.3),
            Vec3::new(-6.0, 1.5, 3.0),
        ),
        Affine3A::from_scale_rotation_translation(
            Vec3::splat(1.0 / 64.0),
            Quat::from_rotation_z(0.9),
            Vec3::new(0.25, 0.5, -2.0),
        ),
        Affine3A::from_scale_rotation_translation(
            Vec3::splat(40.0),
            Quat::from_rotation_x(-0.35),
            Vec3::new(0.0, 0.0, 150.0),
        ),
    ]
}

/// The reference for a scene with instances: every instance, its ray carried into its space by
/// the inverse placement, tested triangle by triangle; the first hit by `t`, then by scene index.
fn reference_hit(geometry: &Geometry, ray: &Ray) -> Option<Hit> {
    let mut best = None;
    for instance in geometry.instances() {
        let stored = (instance.stored_first..instance.stored_first + instance.count)
            .map(|s| geometry.stored_triangle(s as usize))
            .collect::<Vec<_>>();
        let local = match &instance.placement {
            None => *ray,
            Some(p) => Ray {
                origin: p.to_object.transform_point3(ray.origin),
                direction: p.to_object.transform_vector3(ray.direction),
                ..*ray
            },
        };
        if let Some(hit) = BruteForce::new(&stored).closest_hit(&local) {
            let scene = instance.first + hit.triangle;
            let hit = match &instance.placement {
                Some(p) => p.world_hit(hit, scene),
                None => Hit { triangle: scene, ..hit },
            };
            hit.keep_first(&mut best);
        }
    }
    best
}

/// The cube drawn in every awkward place, and once more as a mesh of its own in world space.
fn instanced_cubes() -> (Geometry, Mesh) {
    let cube = closed_cube(6);
    let mut geometry = Geometry::new();
    let plain = Affine3A::from_translation(Vec3::new(3.0, 3.0, 3.0));
    geometry.add_mesh(&cube, &plain, |_| 0);
    geometry.add_instanced_mesh(&cube, &awkward_transforms(), |i| i as u32 % 3);
    (geometry, cube)
}

/// Rays at the scene's vertices and edge midpoints (where ties and cracks are) and at random
/// points, from random origins around it.
fn hostile_rays(geometry: &Geometry, count: usize, seed: u64) -> Vec<Ray> {
    let (lo, hi) = geometry.bounds().unwrap();
    let (lo, hi) = (lo - (hi - lo) * 0.2, hi + (hi - lo) * 0.2);
    let mut rng = Rng(seed);
    (0..count)
        .map(|k| {
            let origin = rng.in_box(lo, hi);
            let i = (rng.next() * geometry.len() as f32) as usize % geometry.len();
            let [a, b, c] = geometry.triangle(i);
            let target = match k % 4 {
                0 => a,
                1 => (a + b) / 2.0,
                2 => (a + b + c) / 3.0,
                _ => rng.in_box(lo, hi),
            };
            let mut ray = Ray::new(origin, target - origin);
            if k % 7 == 0 {
                ray.t_max = 0.5 + rng.next();
            }
            ray
        })
        .collect()
}

#[test]
fn hits_through_instances_are_the_brute_force_answers() {
    let (geometry, cube) = instanced_cubes();
    assert!(geometry.is_instanced());
    let drawn = cube.triangles.len() * 5;
    assert_eq!((geometry.len(), geometry.stored_len()), (drawn, 2 * cube.triangles.len()));
    let bvh = SceneBvh::build(&geometry).unwrap();
    assert!(matches!(bvh, SceneBvh::Instanced(_)), "{bvh:?}");
    assert_eq!(bvh.triangles(), 2 * cube.triangles.len(), "the instanced cube is built once");
    let brute = TwoLevel::build(&geometry, |t| Ok::<_, ()>(BruteForce::new(t))).unwrap();
    let rays = hostile_rays(&geometry, 6000, 7);
    let mut hits = 0;
    for ray in &rays {
        let expected = reference_hit(&geometry, ray);
        assert_eq!(bvh.closest_hit(ray), expected, "{ray:?}");
        assert_eq!(brute.closest_hit(ray), expected, "{ray:?}");
        assert_eq!(bvh.occluded(ray), expected.is_some(), "{ray:?}");
        assert_eq!(brute.occluded(ray), expected.is_some(), "{ray:?}");
        hits += expected.is_some() as usize;
    }
    assert!(hits > rays.len() / 2, "only {hits} of {} rays hit", rays.len());
    // The batched entry points answer the same, also for rays that never hit (a NaN, a zero
    // direction, an empty range) among the others, and for tiles of coherent rays.
    let mut rays = rays;
    let o = Vec3::new(0.0, 0.0, -50.0);
    rays.extend([
        Ray::new(Vec3::NAN, Vec3::Z),
        Ray::new(o, Vec3::ZERO),
        Ray::segment(o, Vec3::Z, f32::NAN),
        Ray::segment(o, Vec3::Z, -1.0),
    ]);
    let (lo, hi) = geometry.bounds().unwrap();
    for copy in [lo, hi, (lo + hi) / 2.0] {
        for k in 0..64 {
            let target = copy + Vec3::new((k % 8) as f32, (k / 8) as f32, 0.0) * 0.05;
            rays.push(Ray::new(o, target - o));
        }
    }
    for accel in [&bvh as &dyn Accelerator, &brute] {
        let mut batch = vec![None; rays.len()];
        accel.closest_hits(&rays, &mut batch);
        let single: Vec<Option<Hit>> = rays.iter().map(|r| accel.closest_hit(r)).collect();
        assert_eq!(batch, single);
        let mut batch = vec![false; rays.len()];
        accel.occluded_each(&rays, &mut batch);
        let single: Vec<bool> = rays.iter().map(|r| accel.occluded(r)).collect();
        assert_eq!(batch, single);
        // In rows, a tile at a time.
        for (tile, single) in rays.chunks(ROWS).zip(single.chunks(ROWS)) {
            let mut hits = HitRows::default();
            accel.closest_hits_rows(tile, &mut hits);
            let blocked = accel.occluded_rows(&RayRows::from_rays(tile));
            for (i, (ray, &occluded)) in tile.iter().zip(single).enumerate() {
                assert_eq!(hits.hit(i), accel.closest_hit(ray), "{ray:?}");
                assert_eq!(blocked >> i & 1 != 0, occluded, "{ray:?}");
            }
        }
    }
}

/// The instanced scene and its flattening (every copy's triangles moved into world space) are
/// the same surfaces: rays hit the same triangle at the same `t` up to the rounding of the
/// transforms, and the points agree.
#[test]
fn instances_hit_where_their_flattened_triangles_are() {
    let (geometry, _) = instanced_cubes();
    let flat = BruteForce::new(&geometry.vertices());
    let bvh = SceneBvh::build(&geometry).unwrap();
    let rays = hostile_rays(&geometry, 4000, 11);
    let (mut same, mut both) = (0, 0);
    for ray in &rays {
        let (Some(a), Some(b)) = (bvh.closest_hit(ray), flat.closest_hit(ray)) else { continue };
        both += 1;
        let scale = ray.direction.length() * a.t.max(1.0);
        assert!((a.t - b.t).abs() * ray.direction.length() < 1e-4 * scale, "{a:?} {b:?}");
        let (pa, pb) = (geometry.surface_point(&a).p, geometry.surface_point(&b).p);
        assert!((pa - pb).length() < 1e-3 * scale, "{pa} {pb}");
        same += (a.triangle == b.triangle) as usize;
    }
    assert!(both > 1500, "{both}");
    // Rays aimed at shared vertices and edges may pick either neighbour; most must agree.
    assert!(same as f64 > 0.85 * both as f64, "{same} of {both}");
}

/// The crack test through instances: rays from inside each placed cube toward its vertices and
/// edge midpoints, and in random directions, always hit it; rays from outside aimed at those
/// points never pass through.
#[test]
fn no_ray_slips_through_an_instanced_closed_mesh() {
    let (geometry, cube) = instanced_cubes();
    let bvh = SceneBvh::build(&geometry).unwrap();
    let brute = TwoLevel::build(&geometry, |t| Ok::<_, ()>(BruteForce::new(t))).unwrap();
    let per_copy = cube.triangles.len();
    let mut rng = Rng(3);
    let mut rays = 0;
    for copy in 0..5 {
        let triangles: Vec<[Vec3; 3]> =
            (copy * per_copy..(copy + 1) * per_copy).map(|i| geometry.triangle(i)).collect();
        let centre = triangles.iter().flatten().sum::<Vec3>() / (3 * per_copy) as f32;
        let targets = triangles.iter().flat_map(|&[a, b, c]| [a, (a + b) / 2.0, (b + c) / 2.0]);
        for (k, target) in targets.enumerate() {
            // From slightly off the centre, so that the rays are not symmetric.
            let inside = centre + (target - centre) * 0.01 * rng.next();
            let outward = Ray::new(inside, target - inside);
            let outside = inside + 200.0 * (target - inside);
            let far = Ray::new(outside, inside - outside);
            let random = Ray::new(inside, Vec3::new(rng.next(), rng.next(), rng.next()) - 0.5);
            for ray in [outward, random] {
                rays += 1;
                for (name, accel) in [("bvh", &bvh as &dyn Accelerator), ("brute", &brute)] {
                    let hit = accel.closest_hit(&ray);
                    assert!(hit.is_some(), "{name}: copy {copy} target {k}: escaped {ray:?}");
                    assert!(accel.occluded(&ray), "{name}: copy {copy}: {ray:?}");
                }
            }
            // From outside, back through the target (met at t = 199/200, where the ray from
            // inside left the convex cube): hit there or sooner, never beyond.
            let hit = bvh.closest_hit(&far).expect("hits from outside");
            assert!(hit.t <= 0.995 * (1.0 + 1e-4), "copy {copy} target {k}: {hit:?}");
        }
    }
    assert!(rays > 5000, "{rays}");
}

/// A mirrored instance keeps its front side outside, as a flattening loader's turned
/// triangles do: its normals point away from its centre and its hits' barycentrics name the
/// corners `triangle(i)` gives.
#[test]
fn mirrored_instances_keep_their_front_side_outside() {
    let (geometry, cube) = instanced_cubes();
    let per_copy = cube.triangles.len();
    let mirror = &geometry.instances()[2];
    assert!(mirror.placement.unwrap().mirrored);
    let centre: Vec3 = mirror.placement.unwrap().to_world.translation.into();
    for i in mirror.first as usize..mirror.first as usize + per_copy {
        let [a, b, c] = geometry.triangle(i);
        let outward = (a + b + c) / 3.0 - centre;
        assert!(geometry.normal(i).dot(outward) > 0.0, "triangle {i}");
    }
    let bvh = SceneBvh::build(&geometry).unwrap();
    let mut rng = Rng(5);
    for _ in 0..200 {
        let target = centre + (Vec3::new(rng.next(), rng.next(), rng.next()) - 0.5) * 0.2;
        let origin = centre + Vec3::new(0.3, 5.0, -7.0);
        let ray = Ray::new(origin, target - origin);
        let hit = bvh.closest_hit(&ray).unwrap();
        let point = geometry.surface_point(&hit);
        assert!((point.p - ray.at(hit.t)).length() < 1e-4, "{} {}", point.p, ray.at(hit.t));
        assert!(point.normal.dot(ray.direction) < 0.0, "seen from outside: the front");
    }
}

/// The engine's known figures: 121,496 triangles drawn, 75,730 stored (14 of its 29 meshes
/// drawn 52 times in all), the bounding box of its flattened OBJ, and a BVH that holds each
/// distinct mesh once.
#[test]
fn the_engine_stores_each_distinct_mesh_once() {
    let loaded = load_mesh(&data("2CylinderEngine/2CylinderEngine.glb")).unwrap();
    assert_eq!(loaded.triangle_count(), 121_496);
    assert_eq!(loaded.stored_triangle_count(), 75_730);
    assert_eq!(loaded.instanced.len(), 14);
    assert_eq!(loaded.instanced.iter().map(|m| m.transforms.len()).sum::<usize>(), 52);
    let obj = load_mesh(&data("2CylinderEngine/2CylinderEngine.obj.gz")).unwrap();
    let (lo, hi) = loaded.bounds().unwrap();
    let (obj_lo, obj_hi) = obj.mesh.bounds().unwrap();
    assert!(lo.abs_diff_eq(obj_lo, 2e-3) && hi.abs_diff_eq(obj_hi, 2e-3), "{lo} {hi}");

    let scene = Scene::from_loaded(&loaded);
    assert_eq!((scene.geometry.len(), scene.geometry.stored_len()), (121_496, 75_730));
    let bvh = SceneBvh::build(&scene.geometry).unwrap();
    assert_eq!(bvh.triangles(), 75_730);
    let flattened = Scene::from_mesh(&loaded.flattened());
    assert_eq!(flattened.geometry.len(), 121_496);
    let flat_bvh = SceneBvh::build(&flattened.geometry).unwrap();
    assert_eq!(flat_bvh.triangles(), 121_496);
    // Memory follows the stored triangles.
    assert!(scene.geometry.bytes() * 4 < flattened.geometry.bytes() * 3);
    assert!(bvh.bytes() * 4 < flat_bvh.bytes() * 3, "{} {}", bvh.bytes(), flat_bvh.bytes());
}

/// The instanced engine and its flattened OBJ, seen through the glTF's camera with the lab's
/// light model (shadow rays included), give the same picture: at most a few pixels along
/// silhouettes differ, where rounding picks a neighbouring triangle.
#[test]
fn the_instanced_engine_renders_as_its_flattened_obj() {
    use raylab::image_compare::{compare_rgb8, save_failure_images};
    use raylab::{Lab, Stage, render};
    let loaded = load_mesh(&data("2CylinderEngine/2CylinderEngine.glb")).unwrap();
    let instanced = Scene::from_loaded(&loaded);
    let flattened =
        Scene::from_mesh(&load_mesh(&data("2CylinderEngine/2CylinderEngine.obj.gz")).unwrap().mesh);
    // An odd size: rows end in tiles shorter than the lab's.
    let camera = loaded.camera.unwrap().camera(157, 118);
    let picture = |scene: &Scene| {
        let bvh = SceneBvh::build(&scene.geometry).unwrap();
        let lab = Lab::new(scene, &bvh, Stage::Ambient);
        render(&camera, &lab, &|_| {}).unwrap().to_rgb8_clamped().unwrap()
    };
    let (a, b) = (picture(&instanced), picture(&flattened));
    let covered = b.pixels().filter(|p| p.0 != [0, 0, 0]).count();
    assert!(covered > 157 * 118 / 4, "the engine covers only {covered} pixels");
    let difference = compare_rgb8(&a, &b, 2).unwrap();
    if difference.fraction_over_tolerance() > 0.002 || difference.mean_abs_diff > 0.05 {
        let saved = save_failure_images("instanced_engine", &a, &b);
        panic!("{difference:?}; images: {saved:?}");
    }
}

/// The path tracer sees the same engine instanced and flattened (the glTF's own materials and
/// normals in both): the same samples give the same pixels but where rounding sends a path to a
/// neighbouring triangle.
#[test]
fn the_path_tracer_sees_instances_as_their_copies() {
    use raylab::image_compare::{compare_rgb8, save_failure_images};
    use raylab::{PathScalar as PathTracer, PathSettings, render_samples};
    let loaded = load_mesh(&data("2CylinderEngine/2CylinderEngine.glb")).unwrap();
    let instanced = Scene::from_loaded(&loaded);
    let flat = raylab::LoadedMesh { mesh: loaded.flattened(), instanced: vec![], ..loaded.clone() };
    let flattened = Scene::from_loaded(&flat);
    assert!(instanced.geometry.is_instanced() && !flattened.geometry.is_instanced());
    let camera = loaded.camera.unwrap().camera(96, 72);
    let picture = |scene: &Scene| {
        let bvh = SceneBvh::build(&scene.geometry).unwrap();
        let path = PathTracer::new(scene, &bvh, PathSettings::default());
        let film = render_samples(&camera, &path, 4, &|_| {}).unwrap();
        film.to_rgb8(&raylab::film::Display::SRGB).unwrap()
    };
    let (a, b) = (picture(&instanced), picture(&flattened));
    let lit = b.pixels().filter(|p| p.0.iter().any(|&c| c > 16)).count();
    assert!(lit > 96 * 72 / 4, "only {lit} pixels are lit");
    let difference = compare_rgb8(&a, &b, 8).unwrap();
    if difference.fraction_over_tolerance() > 0.005 || difference.mean_abs_diff > 0.2 {
        let saved = save_failure_images("instanced_engine_path", &a, &b);
        panic!("{difference:?}; images: {saved:?}");
    }
}

/// Instances laid out to make the surface area heuristic split one off at a time (a row of
/// boxes, each twice as far and a little larger than the last): the top level stays shallow
/// enough for its fixed traversal stacks, and answers stay exact.
#[test]
fn a_degenerate_row_of_instances_is_traced_exactly() {
    let cube = closed_cube(1);
    let transforms: Vec<Affine3A> = (0..400)
        .map(|k| {
            let s = 1.02f32.powi(k);
            Affine3A::from_scale_rotation_translation(
                Vec3::splat(s),
                Quat::from_rotation_z(k as f32 * 0.1),
                Vec3::new(3.0 * s * k as f32, 0.0, 0.0),
            )
        })
        .collect();
    let mut geometry = Geometry::new();
    geometry.add_instanced_mesh(&cube, &transforms, |_| 0);
    let bvh = SceneBvh::build(&geometry).unwrap();
    let mut rays = hostile_rays(&geometry, 3000, 17);
    // Along the row, through every instance.
    rays.push(Ray::new(Vec3::new(-10.0, 0.01, 0.02), Vec3::X));
    rays.push(Ray::new(Vec3::new(1e5, 0.01, 0.02), -Vec3::X));
    for ray in &rays {
        assert_eq!(bvh.closest_hit(ray), reference_hit(&geometry, ray), "{ray:?}");
    }
    let mut batch = vec![None; rays.len()];
    bvh.closest_hits(&rays, &mut batch);
    let single: Vec<Option<Hit>> = rays.iter().map(|r| bvh.closest_hit(r)).collect();
    assert_eq!(batch, single);
}

/// Placements that take a mesh stored far from the origin (a CAD part modelled in place) back
/// near it, apart: a translation, the same after a turn, and a mirror with a stretch.
fn placed_back(offset: Vec3) -> Vec<Affine3A> {
    let back = Affine3A::from_translation(-offset);
    vec![
        back,
        Affine3A::from_rotation_translation(
            Quat::from_euler(glam::EulerRot::XYZ, 0.3, 0.7, 1.1),
            Vec3::new(4.0, 0.0, 0.0),
        ) * back,
        Affine3A::from_scale_rotation_translation(
            Vec3::new(-1.5, 0.5, 1.0),
            Quat::IDENTITY,
            Vec3::new(0.0, 0.0, 6.0),
        ) * back,
    ]
}

/// The cube stored around `offset` and drawn back near the origin by each of `placed_back`'s
/// placements.
fn far_stored_cubes(offset: Vec3) -> Geometry {
    let mut cube = closed_cube(4);
    for p in &mut cube.positions {
        *p = *p * Vec3::new(1.0, 0.7, 1.3) + offset;
    }
    let mut geometry = Geometry::new();
    geometry.add_instanced_mesh(&cube, &placed_back(offset), |_| 0);
    geometry
}

/// Rays that graze the instances' world boxes: along each axis, just inside and just outside
/// each face, where the rounding of the ray's way into object space (an ulp of the stored
/// coordinates, far larger than one of the world's) decides hit or miss.
fn grazing_rays(geometry: &Geometry) -> Vec<Ray> {
    let mut rays = Vec::new();
    let mut rng = Rng(23);
    for i in 0..geometry.len() {
        let [a, b, _] = geometry.triangle(i);
        for step in -8..=8 {
            let point = a + (b - a) * rng.next() + Vec3::splat(step as f32 * 3e-5);
            for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
                rays.push(Ray::new(point - 5.0 * axis, axis));
                rays.push(Ray::new(point + 5.0 * axis, -axis));
            }
        }
    }
    rays
}

/// A mesh stored 5000 units away and placed back: the top level's boxes and margins still let
/// every ray reach the instance the reference finds it in (grazing rays included), single and
/// batched.
#[test]
fn far_stored_instances_are_traced_exactly() {
    let geometry = far_stored_cubes(Vec3::new(5000.0, 3000.0, -2000.0));
    let bvh = SceneBvh::build(&geometry).unwrap();
    assert!(matches!(bvh, SceneBvh::Instanced(_)));
    let mut rays = hostile_rays(&geometry, 2000, 29);
    rays.extend(grazing_rays(&geometry));
    let mut hits = 0;
    for ray in &rays {
        let expected = reference_hit(&geometry, ray);
        hits += expected.is_some() as usize;
        assert_eq!(bvh.closest_hit(ray), expected, "{ray:?}");
        assert_eq!(bvh.occluded(ray), expected.is_some(), "{ray:?}");
    }
    assert!(hits > rays.len() / 4, "only {hits} of {} rays hit", rays.len());
    let mut batch = vec![None; rays.len()];
    bvh.closest_hits(&rays, &mut batch);
    let single: Vec<Option<Hit>> = rays.iter().map(|r| bvh.closest_hit(r)).collect();
    assert_eq!(batch, single);
}

/// Rays leaving a surface point of a far-stored instance, back the way they came or toward a
/// point above it, never find the surface they leave: the point's error bound covers the
/// rounding of the placement and of the ray's way back into object space, where an ulp of
/// the stored coordinates is thousands of the world's.
#[test]
fn rays_leaving_far_stored_instances_do_not_hit_their_own_surface() {
    for offset in [Vec3::new(5000.0, 3000.0, -2000.0), Vec3::new(-7e4, 2e4, 9e4)] {
        let geometry = far_stored_cubes(offset);
        let bvh = SceneBvh::build(&geometry).unwrap();
        let mut rng = Rng(31);
        let (mut tested, mut self_hits, mut shadowed) = (0, 0, 0);
        for i in 0..geometry.len() {
            let [a, b, c] = geometry.triangle(i);
            let normal = (b - a).cross(c - a).normalize();
            for _ in 0..40 {
                let (u, v) = (rng.next(), rng.next());
                let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
                let target = a + u * (b - a) + v * (c - a);
                // From outside the closed cube, in front of the face.
                let origin = target + 0.5 * normal + 0.1 * rng.in_box(-Vec3::ONE, Vec3::ONE);
                let Some(hit) = bvh.closest_hit(&Ray::new(origin, target - origin)) else {
                    continue;
                };
                if hit.triangle as usize != i {
                    continue;
                }
                tested += 1;
                let point = geometry.surface_point(&hit);
                // Out on the side the ray came from (cosine-ish spread about the normal).
                let side = if point.normal.dot(origin - point.p) > 0.0 { 1.0 } else { -1.0 };
                let mut direction = side * point.normal + 0.9 * rng.in_box(-Vec3::ONE, Vec3::ONE);
                if direction.dot(point.normal) * side <= 0.0 {
                    direction = side * point.normal;
                }
                self_hits +=
                    bvh.closest_hit(&point.spawn_ray(direction))
                        .is_some_and(|h| h.triangle == hit.triangle) as u32;
                shadowed += bvh.occluded(&point.spawn_ray_to(point.p + side * point.normal)) as u32;
            }
        }
        assert!(tested > geometry.len() * 20, "{offset}: only {tested} points");
        assert_eq!((self_hits, shadowed), (0, 0), "{offset}: of {tested} points");
    }
}

/// A light stored far away and placed back: light sampling from a floor beneath it finds it
/// unoccluded (the shadow ray stops short of the light's own surface by its error bound).
#[test]
fn a_far_stored_instanced_light_is_not_occluded_by_itself() {
    let offset = Vec3::new(6e4, -4e4, 3e4);
    let quad = Mesh {
        name: "light".into(),
        positions: [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .map(|(x, z)| Vec3::new(x, -1.0, z) + offset)
            .to_vec(),
        // Facing +y, down onto the floor (the lab's y points down).
        triangles: vec![[0, 2, 1], [0, 3, 2]],
        ..Mesh::default()
    };
    let mut geometry = Geometry::new();
    let turn = Affine3A::from_rotation_y(0.4);
    let placements = [
        turn * Affine3A::from_translation(-offset),
        Affine3A::from_translation(-offset + 3.0 * Vec3::X),
    ];
    geometry.add_instanced_mesh(&quad, &placements, |_| 1);
    let emitter =
        raylab::Material { emission: Vec3::ONE, ..raylab::Material::diffuse("light", Vec3::ZERO) };
    let scene = Scene {
        name: "far light".into(),
        geometry,
        materials: vec![raylab::Material::diffuse("floor", Vec3::splat(0.5)), emitter],
        ..Scene::default()
    };
    let bvh = SceneBvh::build(&scene.geometry).unwrap();
    let lights = raylab::LightSet::new(&scene);
    let mut rng = Rng(37);
    let (mut samples, mut occluded) = (0, 0);
    for _ in 0..4000 {
        let p = Vec3::new(4.0 * rng.next() - 1.0, 0.5 + rng.next(), 4.0 * rng.next() - 2.0);
        let point = raylab::SurfacePoint { p, error: Vec3::splat(1e-6), normal: -Vec3::Y };
        let u = glam::Vec2::new(rng.next(), rng.next());
        if let Some(sample) = lights.sample(&point, u) {
            samples += 1;
            occluded += bvh.occluded(&sample.shadow_ray) as u32;
        }
    }
    assert!(samples > 3000, "only {samples} samples");
    assert_eq!(occluded, 0, "of {samples} samples");
}

/// The top level walked as rows (every instance's box in one loop, on each instruction set this
/// CPU has) and as its binary tree: both give the reference's answers, on the awkward
/// placements, on far-stored instances with their margins (grazing rays) and on the engine's 52
/// placements. Which instances are visited, and in which order, changes no answer.
#[test]
fn the_top_level_as_rows_answers_as_its_tree() {
    use raylab::Bvh;
    use raylab::bvh::Isa;
    let loaded = load_mesh(&data("2CylinderEngine/2CylinderEngine.glb")).unwrap();
    let engine = Scene::from_loaded(&loaded).geometry;
    let far = far_stored_cubes(Vec3::new(5000.0, 3000.0, -2000.0));
    let scenes = [(instanced_cubes().0, 3000), (far.clone(), 1000), (engine, 400)];
    let isas: Vec<Option<Isa>> =
        Isa::ALL.into_iter().filter(|isa| isa.is_supported()).map(Some).collect();
    for (geometry, count) in &scenes {
        let mut rays = hostile_rays(geometry, *count, 31);
        if geometry.len() < 1000 {
            rays.extend(grazing_rays(geometry));
        }
        let expected: Vec<Option<Hit>> = rays.iter().map(|r| reference_hit(geometry, r)).collect();
        let hits = expected.iter().flatten().count();
        assert!(hits > rays.len() / 4, "only {hits} of {} rays hit", rays.len());
        for isa in isas.iter().copied().chain([None]) {
            let two = TwoLevel::build(geometry, Bvh::try_new).unwrap().with_top_rows(isa);
            // Every scene here has at most 64 instances: rows where asked for, else the tree.
            assert_eq!(two.has_top_rows(), isa.is_some(), "{isa:?}");
            for (ray, expected) in rays.iter().zip(&expected) {
                assert_eq!(two.closest_hit(ray), *expected, "{isa:?} {ray:?}");
                assert_eq!(two.occluded(ray), expected.is_some(), "{isa:?} {ray:?}");
            }
        }
    }
}
