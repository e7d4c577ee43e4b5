//! Kernel twins and tree invariants; brute-force agreement is in `tests/bvh.rs`.

use glam::Vec3;

use super::isa::Scalar;
use super::node::kernel::{BoxRay, NodeKernel, NodeRay};
use super::node::{Child, WideNode, decode};
use super::*;

/// A small deterministic generator (PCG-style LCG) for test data, shared by the BVH's tests.
pub(in crate::bvh) struct Lcg(pub(in crate::bvh) u64);

impl Lcg {
    /// A number in `[0, 1)`.
    pub(in crate::bvh) fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
    /// A point in the unit cube.
    pub(in crate::bvh) fn vec(&mut self) -> Vec3 {
        Vec3::new(self.next(), self.next(), self.next())
    }
}

/// A xorshift64 stream of raw bits from `seed` (non-zero), for tests that want every bit
/// pattern of a float (NaN payloads, subnormals, infinities).
pub(in crate::bvh) fn xorshift(mut state: u64) -> impl FnMut() -> u64 {
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    }
}

/// Nodes with random boxes, including flat ones, boxes that share the ray's origin planes, and
/// unused slots; rays with ±0 and tiny direction components.
pub(in crate::bvh) fn hostile_cases() -> Vec<(WideNode, Ray, f32)> {
    let mut rng = Lcg(7);
    let mut cases = Vec::new();
    for i in 0..4000 {
        let mut node = WideNode {
            planes: [
                [f32::INFINITY; 8],
                [f32::INFINITY; 8],
                [f32::INFINITY; 8],
                [f32::NEG_INFINITY; 8],
                [f32::NEG_INFINITY; 8],
                [f32::NEG_INFINITY; 8],
            ],
            children: [node::EMPTY; 8],
        };
        let origin = (rng.vec() * 4.0 - 2.0).round() * 0.5; // On a grid: shares planes with boxes.
        for slot in 0..8 {
            if rng.next() < 0.1 {
                continue; // unused slot
            }
            let a = (rng.vec() * 4.0 - 2.0).round() * 0.5;
            let mut b = a + (rng.vec() * 2.0).round() * 0.5; // zero extent on some axes
            if i % 3 == 0 {
                b = a + rng.vec();
            }
            for axis in 0..3 {
                node.planes[axis][slot] = a[axis];
                node.planes[3 + axis][slot] = b[axis];
            }
            node.children[slot] = slot as u32;
        }
        let mut d = rng.vec() * 2.0 - 1.0;
        for axis in 0..3 {
            match (i / 3 + axis) % 5 {
                0 => d[axis] = 0.0,
                1 => d[axis] = -0.0,
                2 => d[axis] *= 1e-30,
                _ => {}
            }
        }
        if d == Vec3::ZERO {
            d.z = 1.0;
        }
        let t_limit = if i % 2 == 0 { f32::INFINITY } else { rng.next() * 3.0 };
        // Every seventh scene far from the world's origin: `o·(1/d)` far larger than the
        // distances (the fused test's own margin).
        let origin = if i % 7 == 6 {
            let offset = Vec3::new(1000.0, -3.0e4, 250.5);
            for slot in 0..8 {
                if node.children[slot] != node::EMPTY {
                    for axis in 0..3 {
                        node.planes[axis][slot] += offset[axis];
                        node.planes[3 + axis][slot] += offset[axis];
                    }
                }
            }
            origin + offset
        } else {
            origin
        };
        let mut ray = Ray::new(origin, d);
        ray.t_min = if i % 4 == 1 { 0.25 } else { 0.0 };
        cases.push((node, ray, t_limit));
    }
    cases
}

/// The box around a node's children: the root that single rays' margins are taken over.
pub(in crate::bvh) fn node_root(node: &WideNode) -> Bounds {
    (0..8).fold(Bounds::EMPTY, |b, k| b.union(node.bounds(k)))
}

/// The hostile cases, and rays from their origins at each used child's centre, every third
/// with a finite limit (most of these have a fused form and enter boxes); the scenes moved far
/// from the world's origin give rays that the fused form leaves to the plain one.
fn aimed_cases() -> Vec<(WideNode, Ray, f32)> {
    let mut cases = hostile_cases();
    for (i, (node, ray, _)) in hostile_cases().into_iter().enumerate() {
        for k in (0..8).filter(|&k| node.children[k] != node::EMPTY) {
            let aim = node.bounds(k).centroid() + Vec3::new(1e-3, -2e-3, 3e-3) * k as f32;
            if aim != ray.origin {
                let limit = if (i + k) % 3 == 0 { 0.5 + (k as f32) * 0.25 } else { f32::INFINITY };
                cases.push((node, Ray::new(ray.origin, aim - ray.origin), limit));
            }
        }
    }
    cases
}

/// What the AVX2 and AVX-512 node kernels compute: the fused test where the ray has one, the
/// plain one otherwise.
fn fused_twin(node: &WideNode, ray: &RayBoxTest, margin: f32, t_limit: f32) -> (u32, [f32; 8]) {
    let Some(fused) = ray.fused(margin) else {
        // SAFETY: the scalar kernel needs nothing.
        return unsafe { (*ray, margin).enter(node, t_limit) };
    };
    let (mut mask, mut near) = (0, [0.0; 8]);
    for (k, slot) in near.iter_mut().enumerate() {
        if let Some(t) = fused.enter(&node.bounds(k), t_limit) {
            mask |= 1 << k;
            *slot = t;
        }
    }
    (mask, near)
}

/// What the SSE2 kernel computes: the plain test.
fn plain_twin(node: &WideNode, ray: &RayBoxTest, margin: f32, t_limit: f32) -> (u32, [f32; 8]) {
    // SAFETY: the scalar kernel needs nothing.
    unsafe { (*ray, margin).enter(node, t_limit) }
}

type Twin = fn(&WideNode, &RayBoxTest, f32, f32) -> (u32, [f32; 8]);

/// A prepared ray's test, in whichever form it was prepared.
///
/// # Safety
/// The CPU must support the instruction set of the kernel that prepared it.
#[inline(always)]
unsafe fn enter_either<F: BoxRay, P: BoxRay>(
    node: &WideNode,
    ray: &NodeRay<F, P>,
    t: f32,
) -> (u32, [f32; 8]) {
    match ray {
        // SAFETY: the caller's guarantee.
        NodeRay::Fused(f) => unsafe { f.enter(node, t) },
        // SAFETY: as above.
        NodeRay::Plain(p) => unsafe { p.enter(node, t) },
    }
}

/// Checks a kernel against its twin on every aimed case; returns how many rays had a fused form.
fn check_kernel<K: NodeKernel>(
    twin: Twin,
    run: impl Fn(&WideNode, &NodeRay<K::Fused, K::Plain>, f32) -> (u32, [f32; 8]),
) -> usize {
    let mut fused = 0;
    for (node, ray, t_limit) in aimed_cases() {
        let box_ray = RayBoxTest::new(&ray);
        let margin = box_ray.margin(&node_root(&node));
        fused += usize::from(box_ray.fused(margin).is_some());
        let (mask, near) = twin(&node, &box_ray, margin, t_limit);
        // SAFETY: `check_kernel` runs only kernels this CPU supports.
        let (simd_mask, simd_near) = run(&node, &unsafe { K::prepare(&box_ray, margin) }, t_limit);
        assert_eq!(mask, simd_mask, "{ray:?} limit {t_limit}\n{node:?}");
        for k in 0..8 {
            if mask & (1 << k) != 0 {
                // Equal as numbers: only the sign of a zero distance may differ.
                assert_eq!(near[k], simd_near[k], "child {k} of {node:?}, {ray:?}");
            }
        }
    }
    fused
}

/// The fused test (`FusedSlabs`, the AVX2 and AVX-512 kernels' form) enters every box that
/// the per-box test enters, no later, also in scenes far from the world's origin; most rays
/// have a fused form (the others, with a zero or tiny direction component, are tested plainly).
#[test]
fn the_fused_test_enters_every_box_the_per_box_test_enters() {
    let (mut fused_rays, mut plain_rays, mut both, mut only_fused) = (0, 0, 0, 0);
    for (node, ray, t_limit) in aimed_cases() {
        let box_ray = RayBoxTest::new(&ray);
        let margin = box_ray.margin(&node_root(&node));
        let Some(fused) = box_ray.fused(margin) else {
            plain_rays += 1;
            continue;
        };
        fused_rays += 1;
        for k in 0..8 {
            let bounds = node.bounds(k);
            match (box_ray.enter(&bounds, t_limit), fused.enter(&bounds, t_limit)) {
                (Some(near), Some(fused_near)) => {
                    assert!(fused_near <= near, "{ray:?} {bounds:?}: {fused_near} > {near}");
                    both += 1;
                }
                (Some(_), None) => panic!("{ray:?} limit {t_limit} misses {bounds:?}"),
                (None, Some(_)) => only_fused += 1,
                (None, None) => {}
            }
            if node.children[k] == node::EMPTY {
                assert!(fused.enter(&bounds, t_limit).is_none(), "an unused slot is entered");
            }
        }
    }
    assert!(fused_rays > 20000 && plain_rays > 1000, "{fused_rays} fused, {plain_rays} plain");
    assert!(both > 20000, "{both} boxes entered");
    // Boxes that the rays only graze, on the grid of shared planes, within the margins.
    assert!(only_fused * 50 < both, "{only_fused} more boxes than {both}");
}

#[test]
fn scalar_kernel_agrees_with_the_box_test() {
    for (node, ray, t_limit) in hostile_cases() {
        let box_ray = RayBoxTest::new(&ray);
        let margin = box_ray.margin(&node_root(&node));
        // SAFETY: the scalar kernel needs nothing.
        let (mask, _) = unsafe { (box_ray, margin).enter(&node, t_limit) };
        for k in 0..8 {
            let expected = box_ray.enter_with_margin(&node.bounds(k), t_limit, margin).is_some();
            assert_eq!(mask & (1 << k) != 0, expected);
            // Unused slots are never entered.
            if node.children[k] == node::EMPTY {
                assert!(!expected);
            }
        }
    }
}

/// The single-ray test with the ray's one margin enters every box that the per-box test
/// (`enter`, each box's own rounding and triangle margins) enters, no later, and few others.
#[test]
fn the_margin_test_enters_every_box_the_per_box_test_enters() {
    let (mut both, mut only_margin) = (0, 0);
    for (node, ray, t_limit) in hostile_cases() {
        let box_ray = RayBoxTest::new(&ray);
        let margin = box_ray.margin(&node_root(&node));
        for k in 0..8 {
            let bounds = node.bounds(k);
            let lean = box_ray.enter_with_margin(&bounds, t_limit, margin);
            match (box_ray.enter(&bounds, t_limit), lean) {
                (Some(near), Some(lean_near)) => {
                    assert!(lean_near <= near, "{ray:?} {bounds:?}: {lean_near} > {near}");
                    both += 1;
                }
                (Some(_), None) => panic!("{ray:?} limit {t_limit} misses {bounds:?}"),
                (None, Some(_)) => only_margin += 1,
                (None, None) => {}
            }
        }
    }
    assert!(both > 1000, "{both} boxes entered");
    assert!(only_margin * 100 < both, "{only_margin} more boxes than {both}");
}

#[cfg(target_arch = "x86_64")]
#[test]
fn sse2_kernel_agrees_with_its_scalar_twin() {
    use super::isa::Sse;
    // SAFETY: SSE2 is part of x86-64.
    check_kernel::<Sse>(plain_twin, |node, ray, t| unsafe { enter_either(node, ray, t) });
}

#[cfg(target_arch = "x86_64")]
#[test]
fn avx2_kernel_agrees_with_its_scalar_twin() {
    use super::isa::Avx2;
    if !Isa::Avx2.is_supported() {
        eprintln!("skipped: this CPU has no AVX2");
        return;
    }
    #[target_feature(enable = "avx2,fma")]
    fn run(
        node: &WideNode,
        ray: &NodeRay<<Avx2 as NodeKernel>::Fused, <Avx2 as NodeKernel>::Plain>,
        t: f32,
    ) -> (u32, [f32; 8]) {
        // SAFETY: compiled with AVX2 and FMA, called only after detection.
        unsafe { enter_either(node, ray, t) }
    }
    // SAFETY: AVX2 support was checked above.
    let fused = check_kernel::<Avx2>(fused_twin, |node, ray, t| unsafe { run(node, ray, t) });
    assert!(fused > 20000, "only {fused} rays took the fused form");
}

/// Packets of rays around each hostile case's ray: from nearby origins (some on the box grid)
/// with directions of the same signs.
fn frustum_cases() -> Vec<(WideNode, Vec<RayBoxTest>, f32)> {
    let mut rng = Lcg(11);
    let mut cases = Vec::new();
    for (node, ray, t_limit) in hostile_cases() {
        let mut rays = Vec::new();
        for k in 0..1 + (rng.next() * 12.0) as usize {
            let spread = if k % 2 == 0 { 0.0 } else { rng.next() * 0.5 };
            let origin = (ray.origin + (rng.vec() - 0.5) * spread).round() * 0.5;
            // Zero components (which cannot join a packet) become small ones of the same sign.
            let d = ray.direction.abs().max(Vec3::splat(1e-3)) * (0.5 + rng.vec());
            let negative = glam::BVec3::new(
                ray.direction.x.is_sign_negative(),
                ray.direction.y.is_sign_negative(),
                ray.direction.z.is_sign_negative(),
            );
            let d = Vec3::select(negative, -d, d);
            let mut member = Ray::new(origin, d);
            member.t_min = ray.t_min * rng.next();
            rays.push(RayBoxTest::new(&member));
        }
        if rays.iter().all(Frustum::can_join) {
            cases.push((node, rays, t_limit));
        }
    }
    assert!(cases.len() > 1000, "only {} packets", cases.len());
    cases
}

/// The packet test never prunes a box that one of its rays enters.
#[test]
fn the_frustum_test_contains_every_member_ray_test() {
    let mut entered = 0;
    for (node, rays, t_limit) in frustum_cases() {
        let frustum = Frustum::of(rays.iter().copied()).expect("one octant");
        for k in 0..8 {
            let bounds = node.bounds(k);
            let packet = frustum.enter(&bounds, t_limit);
            for ray in &rays {
                if let Some(t) = ray.enter(&bounds, t_limit) {
                    entered += 1;
                    let near = packet.unwrap_or_else(|| panic!("{ray:?} enters {bounds:?}"));
                    assert!(near <= t, "packet entry {near} after the ray's {t}");
                }
            }
        }
    }
    assert!(entered > 1000, "only {entered} boxes entered");
}

fn check_frustum_kernel<K: NodeKernel>(
    run: impl Fn(&WideNode, &K::Frustum, f32) -> (u32, [f32; 8]),
) {
    for (node, rays, t_limit) in frustum_cases() {
        let frustum = Frustum::of(rays.iter().copied()).expect("one octant");
        // SAFETY: the scalar kernel needs nothing.
        let (mask, near) = unsafe { Scalar::enter_frustum(&node, &frustum, t_limit) };
        // SAFETY: `check_frustum_kernel` runs only kernels this CPU supports.
        let (simd_mask, simd_near) = run(&node, &unsafe { K::prepare_frustum(&frustum) }, t_limit);
        assert_eq!(mask, simd_mask, "{frustum:?} limit {t_limit}\n{node:?}");
        for k in 0..8 {
            if mask & (1 << k) != 0 {
                assert_eq!(near[k], simd_near[k], "child {k} of {node:?}, {frustum:?}");
            }
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[test]
fn sse2_frustum_kernel_agrees_with_its_scalar_twin() {
    use super::isa::Sse;
    // SAFETY: SSE2 is part of x86-64.
    check_frustum_kernel::<Sse>(|node, f, t| unsafe { Sse::enter_frustum(node, f, t) });
}

#[cfg(target_arch = "x86_64")]
#[test]
fn avx2_frustum_kernel_agrees_with_its_scalar_twin() {
    use super::isa::Avx2;
    if !Isa::Avx2.is_supported() {
        eprintln!("skipped: this CPU has no AVX2");
        return;
    }
    #[target_feature(enable = "avx2")]
    fn run(node: &WideNode, f: &<Avx2 as NodeKernel>::Frustum, t: f32) -> (u32, [f32; 8]) {
        // SAFETY: compiled with AVX2, called only after detection.
        unsafe { Avx2::enter_frustum(node, f, t) }
    }
    // SAFETY: AVX2 support was checked above.
    check_frustum_kernel::<Avx2>(|node, f, t| unsafe { run(node, f, t) });
}

/// Walks the tree: every child box contains its subtree's triangles, every triangle with area
/// appears exactly once.
/// The build bins large nodes and builds their children in parallel: the tree must not depend
/// on how many threads there are. 40,000 triangles (clustered, so that the SAH has real choices)
/// take the parallel paths at the top levels (`PARALLEL_MIN` is 16,384).
#[test]
fn the_tree_is_the_same_for_every_thread_count() {
    let mut rng = Lcg(5);
    let triangles: Vec<[Vec3; 3]> = (0..40_000)
        .map(|i| {
            let cluster = Vec3::new((i % 7) as f32 * 9.0, (i % 5) as f32 * 4.0, (i % 3) as f32);
            let p = cluster + rng.vec() * 3.0;
            [p, p + rng.vec() * 0.2, p + rng.vec() * 0.2]
        })
        .collect();
    let bits = |bvh: &Bvh| {
        let mut words = Vec::new();
        for node in &bvh.wide.nodes {
            words.extend(node.planes.iter().flatten().map(|x| x.to_bits()));
            words.extend(node.children);
        }
        words.extend(bvh.wide.leaves.words());
        words
    };
    for (name, settings) in BuildSettings::PRESETS {
        let build = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| Bvh::build(&triangles, &settings))
        };
        let one = bits(&build(1));
        assert!(one.len() > 100_000, "{name}");
        for threads in [2, 3] {
            assert!(bits(&build(threads)) == one, "{name}: another tree on {threads} threads");
        }
    }
}

/// The collapse of least cost keeps its limits where costs overflow: boxes whose half area is
/// infinite (coordinates near `f32::MAX`) or NaN (an infinite extent beside a zero one), many
/// alike, with a node cost of zero too. Every leaf fits the leaf limit, every triangle is in one
/// leaf, and rays get the brute-force answers.
#[test]
fn the_collapse_of_least_cost_keeps_its_limits_on_huge_boxes() {
    use crate::accel::{Accelerator, BruteForce};
    let huge = [Vec3::splat(-3e38), Vec3::new(3e38, -3e38, 0.0), Vec3::splat(3e38)];
    let flat = [Vec3::new(-3e38, 0.0, 0.0), Vec3::new(3e38, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
    let mut rng = Lcg(5);
    let mut triangles = vec![huge; 100];
    triangles.extend(vec![flat; 100]);
    triangles.extend((0..200).map(|_| {
        let p = rng.vec() * 10.0;
        [p, p + rng.vec(), p + rng.vec()]
    }));
    for (traversal_cost, binary_leaf_size) in [(1.0, 4), (0.0, 1), (0.0, 4)] {
        let collapse = Collapse::Optimal { binary_leaf_size };
        let settings =
            BuildSettings { traversal_cost, collapse, flat_limit: 0, ..BuildSettings::HIGH };
        let bvh = Bvh::build(&triangles, &settings);
        let mut seen = vec![0u32; triangles.len()];
        let mut stack = vec![0u32];
        while let Some(index) = stack.pop() {
            let node = &bvh.wide.nodes[index as usize];
            for k in 0..8 {
                match decode(node.children[k]) {
                    Child::Empty => {}
                    Child::Node(child) => stack.push(child),
                    Child::Leaf(offset) => {
                        let leaf: Vec<_> = bvh.wide.leaves.leaf_triangles(offset).collect();
                        assert!(leaf.len() <= settings.max_leaf_size, "{}", leaf.len());
                        for (id, _) in leaf {
                            seen[id as usize] += 1;
                        }
                    }
                }
            }
        }
        assert!(seen.iter().all(|&s| s == 1), "{traversal_cost} {binary_leaf_size}");
        let brute = BruteForce::new(&triangles);
        for i in 0..200 {
            let from = rng.vec() * 20.0 - 5.0;
            let ray = Ray::new(from, rng.vec() * 2.0 - Vec3::ONE);
            assert_eq!(bvh.closest_hit(&ray), brute.closest_hit(&ray), "ray {i}");
            assert_eq!(bvh.occluded(&ray), brute.occluded(&ray), "ray {i}");
        }
    }
}

#[test]
fn wide_trees_cover_every_triangle_once() {
    let mut rng = Lcg(3);
    let mut triangles: Vec<[Vec3; 3]> = (0..3000)
        .map(|_| {
            let p = rng.vec() * 20.0;
            [p, p + rng.vec(), p + rng.vec()]
        })
        .collect();
    triangles[10] = [Vec3::ONE; 3]; // zero area
    triangles[11][1] = Vec3::NAN;
    for (_, settings) in BuildSettings::PRESETS {
        let bvh = Bvh::build(&triangles, &settings);
        let mut seen = vec![0u32; triangles.len()];
        fn visit(bvh: &Bvh, node: u32, within: Bounds, seen: &mut [u32], triangles: &[[Vec3; 3]]) {
            let node: &WideNode = &bvh.wide.nodes[node as usize];
            for k in 0..8 {
                let b = node.bounds(k);
                match decode(node.children[k]) {
                    Child::Empty => assert!(b.is_empty()),
                    Child::Node(child) => {
                        assert!(within.min.cmple(b.min).all() && within.max.cmpge(b.max).all());
                        visit(bvh, child, b, seen, triangles);
                    }
                    Child::Leaf(offset) => {
                        for (id, t) in bvh.wide.leaves.leaf_triangles(offset) {
                            seen[id as usize] += 1;
                            assert_eq!(t, triangles[id as usize]);
                            let tb = Bounds::of_triangle(t);
                            assert!(b.min.cmple(tb.min).all() && b.max.cmpge(tb.max).all());
                        }
                    }
                }
            }
        }
        let all = Bounds { min: Vec3::NEG_INFINITY, max: Vec3::INFINITY };
        visit(&bvh, 0, all, &mut seen, &triangles);
        for (i, &count) in seen.iter().enumerate() {
            assert_eq!(count, if i == 10 || i == 11 { 0 } else { 1 }, "triangle {i}");
        }
        assert_eq!(bvh.stats().indexed_triangles, 2998);
    }
}

#[test]
fn empty_and_single_triangle_trees_answer() {
    let bvh = Bvh::build(&[], &BuildSettings::default());
    assert_eq!(bvh.closest_hit(&Ray::new(Vec3::ZERO, Vec3::Z)), None);
    assert!(!bvh.occluded(&Ray::new(Vec3::ZERO, Vec3::Z)));
    let bvh = Bvh::build(&[[Vec3::ZERO, Vec3::X, Vec3::Y]], &BuildSettings::default());
    let hit = bvh.closest_hit(&Ray::new(Vec3::new(0.2, 0.2, -1.0), Vec3::Z)).unwrap();
    assert_eq!((hit.t, hit.triangle), (1.0, 0));
    assert!(bvh.occluded(&Ray::new(Vec3::new(0.2, 0.2, -1.0), Vec3::Z)));
}

/// Two clusters of eight triangles 100 apart: the root has a leaf of one record per cluster, so
/// what a ray visits is known exactly.
#[test]
fn traversal_counts_are_the_nodes_leaves_and_records_visited() {
    // A strip of four quads (eight triangles over ten vertices: one record).
    let strip = |x: f32| {
        let p = move |u: f32, v: f32| Vec3::new(x + u, v, 0.0);
        (0..4).flat_map(move |k| {
            let v = k as f32 * 0.5;
            [[p(0.0, v), p(1.0, v), p(0.0, v + 0.5)], [p(1.0, v), p(1.0, v + 0.5), p(0.0, v + 0.5)]]
        })
    };
    let triangles: Vec<[Vec3; 3]> = strip(0.0).chain(strip(100.0)).collect();
    let bvh = Bvh::build(&triangles, &BuildSettings { flat_limit: 0, ..BuildSettings::MEDIUM });
    let stats = |rays: u64, nodes: u64, leaves: u64, records: u64| TraversalStats {
        rays,
        nodes,
        leaves,
        records,
    };
    let cases = [
        // Into the first cluster: the root, then its leaf.
        (Ray::new(Vec3::new(0.2, 0.2, -5.0), Vec3::Z), true, stats(1, 1, 1, 1)),
        (Ray::new(Vec3::new(100.7, 1.5, 5.0), -Vec3::Z), true, stats(1, 1, 1, 1)),
        // Between the clusters: the root's boxes only.
        (Ray::new(Vec3::new(50.0, 0.5, -5.0), Vec3::Z), false, stats(1, 1, 0, 0)),
        // A ray that can hit nothing is not traversed.
        (Ray::new(Vec3::new(0.2, 0.2, -5.0), Vec3::NAN), false, stats(1, 0, 0, 0)),
    ];
    for (ray, hits, expected) in cases {
        let (mut closest, mut occluded) = (TraversalStats::default(), TraversalStats::default());
        let hit = bvh.closest_hit_counted(&ray, &mut closest);
        assert_eq!(hit, bvh.closest_hit(&ray), "{ray:?}");
        assert_eq!(hit.is_some(), hits, "{ray:?}");
        assert_eq!(bvh.occluded_counted(&ray, &mut occluded), hits, "{ray:?}");
        assert_eq!((closest, occluded), (expected, expected), "{ray:?}");
    }
    // Counts add up over rays.
    let mut total = TraversalStats::default();
    for (ray, _, _) in cases {
        bvh.closest_hit_counted(&ray, &mut total);
    }
    assert_eq!(total, stats(4, 3, 2, 2));
    assert_eq!(total + stats(1, 2, 3, 4), stats(5, 5, 5, 6));
    assert_eq!(total.per_ray(), [0.75, 0.5, 0.5]);
}

/// Rays from `origin` that a batch of queries must answer as single rays do: directions with
/// NaN or zero parts, an infinite origin, an empty or NaN range.
fn hostile_rays(origin: Vec3) -> [Ray; 7] {
    [
        Ray::new(origin, Vec3::new(f32::NAN, 1.0, 0.0)),
        Ray::new(origin, Vec3::ZERO),
        Ray::new(Vec3::new(f32::INFINITY, 0.0, 0.0), Vec3::X),
        Ray { t_min: 2.0, t_max: 1.0, ..Ray::new(origin, Vec3::Y) },
        Ray { t_max: f32::NAN, ..Ray::new(origin, -Vec3::Y) },
        Ray { t_min: f32::NAN, ..Ray::new(origin, Vec3::Z) },
        Ray::new(origin, Vec3::new(0.0, -0.0, 1.0)),
    ]
}

/// Every flat kernel (SSE2, AVX2, AVX-512, as this CPU allows) gives exactly its scalar twin's
/// answers, which are brute force's: scenes on a coarse grid (edge functions exactly zero, so
/// the double-precision path decides), with duplicated triangles (ties at equal `t`, which go to
/// the lower index), rays starting just off a surface (the self-intersection bound), explicit
/// `t_min`, short segments, meshes whose corners are shared (as the lanes share them), and 1 to
/// 40 triangles (full, partial and several blocks). The rays of a case are also traced together,
/// for closest hits and for occlusion, in lanes (`flat_rays.rs`), with rays that can hit
/// nothing among them (NaN, zero or infinite parts, an empty range), in batches of every length
/// up to 47, so that groups are full, partial, and padded.
#[test]
fn flat_kernels_agree_with_their_scalar_twin_and_brute_force() {
    use crate::accel::BruteForce;
    let mut rng = Lcg(29);
    let mut tested = [0usize; 4];
    let (mut hits, mut ties, mut edge_hits) = (0, 0, 0);
    for case in 0..1500 {
        let snap = |v: Vec3| if case % 2 == 0 { (v * 4.0).round() / 4.0 } else { v };
        let count = 1 + case % 40;
        // Two cases in four a mesh: corners drawn from a few points, each shared by several
        // triangles, as the lanes share them (`SharedCorners`); every other one on the grid.
        let pool: Vec<Vec3> = (0..2 + count / 2).map(|_| snap(rng.vec() * 4.0 - 2.0)).collect();
        let corner = |rng: &mut Lcg| pool[(rng.next() * pool.len() as f32) as usize % pool.len()];
        let mut triangles: Vec<[Vec3; 3]> = (0..count)
            .map(|_| {
                if case % 4 == 1 || case % 4 == 2 {
                    return [corner(&mut rng), corner(&mut rng), corner(&mut rng)];
                }
                let p = snap(rng.vec() * 4.0 - 2.0);
                [p, snap(p + rng.vec() * 2.0 - 1.0), snap(p + rng.vec() * 2.0 - 1.0)]
            })
            .collect();
        if case % 3 == 0 {
            // A later copy of an earlier triangle: hits tie, the lower index wins.
            let copy = triangles[case % count];
            triangles.push(copy);
        }
        let settings = BuildSettings { flat_limit: usize::MAX, ..BuildSettings::MEDIUM };
        let bvh = Bvh::build(&triangles, &settings);
        let flat = bvh.flat.as_ref().expect("a flat list below the limit");
        let brute = BruteForce::new(&triangles);
        let mut batch = Vec::new();
        for r in 0..40 {
            let [a, b, c] = triangles[(case + r) % triangles.len()];
            let target = match r % 3 {
                0 => a,
                1 => a.lerp(b, rng.next()),
                _ => a.lerp(b, rng.next()).lerp(c, rng.next()),
            };
            let origin = match r % 4 {
                3 => target + (rng.vec() * 2.0 - 1.0) * [1e-5, 1e-6, 1e-7][r % 3],
                _ => snap(rng.vec() * 8.0 - 4.0),
            };
            if origin == target {
                continue;
            }
            let mut ray = Ray::new(origin, target - origin);
            ray.t_min = if r % 5 == 0 { 0.5 * rng.next() } else { 0.0 };
            ray.t_max = [f32::INFINITY, 1.0, 0.5 + rng.next()][r % 3];
            batch.push(ray);
            let closest = traverse::flat::closest_hit_scalar(flat, &ray);
            let occluded = traverse::flat::occluded_scalar(flat, &ray);
            assert_eq!(closest, brute.closest_hit(&ray), "scalar twin, case {case}: {ray:?}");
            assert_eq!(occluded, brute.occluded(&ray), "scalar twin, case {case}: {ray:?}");
            if let Some(h) = closest {
                hits += 1;
                edge_hits += (h.b0() == 0.0 || h.b1 == 0.0 || h.b2 == 0.0) as usize;
                ties += (case % 3 == 0 && h.triangle as usize == case % count) as usize;
            }
            for (k, isa) in Isa::ALL.into_iter().enumerate() {
                let Some(simd) = Bvh::build(&triangles, &settings).with_isa(isa) else {
                    continue;
                };
                tested[k] += 1;
                assert_eq!(simd.closest_hit(&ray), closest, "{}, case {case}: {ray:?}", isa.name());
                assert_eq!(simd.occluded(&ray), occluded, "{}, case {case}: {ray:?}", isa.name());
            }
        }
        let hostile = hostile_rays(batch.first().map_or(Vec3::ZERO, |r| r.origin));
        let at = case % (batch.len() + 1);
        batch.splice(at..at, hostile.into_iter().cycle().skip(case).take(1 + case % 7));
        let batch = &batch[..=(case % batch.len())];
        let expected: Vec<_> =
            batch.iter().map(|r| traverse::flat::closest_hit_scalar(flat, r)).collect();
        let expected_occluded: Vec<_> =
            batch.iter().map(|r| traverse::flat::occluded_scalar(flat, r)).collect();
        for (k, isa) in Isa::ALL.into_iter().enumerate() {
            let Some(simd) = Bvh::build(&triangles, &settings).with_isa(isa) else {
                continue;
            };
            tested[k] += 1;
            let mut hits = vec![Some(Hit { t: -1.0, triangle: 7, b1: 0.0, b2: 0.0 }); batch.len()];
            simd.closest_hits_incoherent(batch, &mut hits);
            assert_eq!(hits, expected, "{} in lanes, case {case}: {batch:?}", isa.name());
            let mut occluded: Vec<bool> = (0..batch.len()).map(|i| i % 2 == 0).collect();
            simd.occluded_incoherent(batch, &mut occluded);
            assert_eq!(
                occluded,
                expected_occluded,
                "{} occlusion in lanes, case {case}",
                isa.name()
            );
        }
    }
    for (k, isa) in Isa::ALL.into_iter().enumerate() {
        if tested[k] == 0 {
            eprintln!("note: this CPU lacks {}: its flat kernel is not tested here", isa.name());
        }
    }
    assert!(tested[0] > 0 && tested[1] > 0, "the scalar and SSE2 kernels always run");
    assert!(hits > 20_000 && edge_hits > 1000 && ties > 100, "{hits} {edge_hits} {ties}");
}

/// Incoherent rays through the tree in lanes (`tree_rays.rs`, AVX2 and AVX-512 as this CPU
/// allows) get exactly the single-ray answers, which the scalar traversal gives: trees of 1 to
/// about 3,000 triangles without a flat list, leaves of one to thirty-two triangles (several
/// records to a leaf), meshes on a coarse grid (edge functions exactly zero: the
/// double-precision path) with shared corners and duplicated triangles (ties at equal `t`),
/// and rays in groups of sixteen from one origin (a pixel's samples: many lanes open, so the
/// lanes' node and leaf tests run) or each from its own (few lanes open: the single-ray
/// fallbacks), from just off a surface, with `t_min`, short ranges and rays that can hit
/// nothing, in batches whose length is no multiple of a register's lanes.
#[test]
fn tree_rays_in_lanes_give_the_single_ray_answers() {
    let mut rng = Lcg(41);
    let mut tested = [0usize; 4];
    let (mut hits, mut blocked, mut ties, mut edge_hits) = (0, 0, 0, 0);
    for case in 0..60 {
        let snap = |v: Vec3| if case % 2 == 0 { (v * 8.0).round() / 8.0 } else { v };
        let count = [1, 7, 40, 300, 3000][case % 5] + case;
        let pool: Vec<Vec3> = (0..count / 2 + 3).map(|_| snap(rng.vec() * 6.0 - 3.0)).collect();
        let mut triangles: Vec<[Vec3; 3]> = (0..count)
            .map(|_| {
                if case % 3 == 0 {
                    let k = |rng: &mut Lcg| {
                        pool[(rng.next() * pool.len() as f32) as usize % pool.len()]
                    };
                    return [k(&mut rng), k(&mut rng), k(&mut rng)];
                }
                let p = snap(rng.vec() * 6.0 - 3.0);
                [p, snap(p + rng.vec() * 0.8 - 0.4), snap(p + rng.vec() * 0.8 - 0.4)]
            })
            .collect();
        // Later copies of earlier triangles: hits on them tie, the lower index wins.
        let copied: std::collections::BTreeSet<usize> =
            (0..count / 10).map(|k| k * 7 % count).collect();
        for &k in &copied {
            triangles.push(triangles[k]);
        }
        let max_leaf_size = [1, 4, 8, 16, 32][case / 5 % 5];
        // Every other pair of cases (grid-snapped and not) the collapse of least cost, over
        // binary leaves of 1 to 4.
        let collapse = match case / 2 % 2 {
            0 => Collapse::Greedy,
            _ => Collapse::Optimal { binary_leaf_size: 1 + case / 4 % 4 },
        };
        let settings =
            BuildSettings { flat_limit: 0, max_leaf_size, collapse, ..BuildSettings::MEDIUM };
        let scalar = Bvh::build(&triangles, &settings).with_isa(Isa::Scalar).expect("scalar");
        let mut batch = Vec::new();
        while batch.len() < 400 {
            let group = batch.len() / 16 % 2 == 0;
            let origin = snap(rng.vec() * 8.0 - 4.0);
            for r in 0..16 {
                let [a, b, c] =
                    triangles[(rng.next() * triangles.len() as f32) as usize % triangles.len()];
                let target = match r % 3 {
                    0 => a,
                    1 => a.lerp(b, rng.next()),
                    _ => a.lerp(b, rng.next()).lerp(c, rng.next()),
                };
                let from = match (group, r % 5) {
                    (_, 4) => target + (rng.vec() * 2.0 - 1.0) * 1e-5,
                    (true, _) => origin,
                    (false, _) => snap(rng.vec() * 8.0 - 4.0),
                };
                if from == target {
                    continue;
                }
                let mut ray = Ray::new(from, target - from);
                ray.t_min = if r % 7 == 0 { 0.3 * rng.next() } else { 0.0 };
                ray.t_max = [f32::INFINITY, 1.0, 0.5 + rng.next(), 10.0][r % 4];
                batch.push(ray);
            }
        }
        let hostile = hostile_rays(batch[0].origin);
        let at = case * 37 % batch.len();
        batch.splice(at..at, hostile.into_iter().cycle().skip(case).take(1 + case % 7));
        let batch = &batch[..batch.len() - case % 16];
        let expected: Vec<_> = batch.iter().map(|r| scalar.closest_hit(r)).collect();
        let expected_occluded: Vec<_> = batch.iter().map(|r| scalar.occluded(r)).collect();
        for h in expected.iter().flatten() {
            hits += 1;
            edge_hits += (h.b0() == 0.0 || h.b1 == 0.0 || h.b2 == 0.0) as usize;
            ties += copied.contains(&(h.triangle as usize)) as usize;
        }
        blocked += expected_occluded.iter().filter(|&&o| o).count();
        for (k, isa) in Isa::ALL.into_iter().enumerate() {
            let Some(simd) = Bvh::build(&triangles, &settings).with_isa(isa) else {
                continue;
            };
            tested[k] += 1;
            let mut hits = vec![Some(Hit { t: -1.0, triangle: 7, b1: 0.0, b2: 0.0 }); batch.len()];
            simd.closest_hits_incoherent(batch, &mut hits);
            for (i, (got, want)) in hits.iter().zip(&expected).enumerate() {
                let bits = |h: &Option<Hit>| {
                    h.map(|h| (h.t.to_bits(), h.triangle, h.b1.to_bits(), h.b2.to_bits()))
                };
                assert_eq!(
                    bits(got),
                    bits(want),
                    "{} closest, case {case}, ray {i}: {:?}",
                    isa.name(),
                    batch[i]
                );
            }
            let mut occluded: Vec<bool> = (0..batch.len()).map(|i| i % 2 == 0).collect();
            simd.occluded_incoherent(batch, &mut occluded);
            for (i, (got, want)) in occluded.iter().zip(&expected_occluded).enumerate() {
                assert_eq!(
                    got,
                    want,
                    "{} occluded, case {case}, ray {i}: {:?}",
                    isa.name(),
                    batch[i]
                );
            }
        }
    }
    for (k, isa) in Isa::ALL.into_iter().enumerate() {
        if tested[k] == 0 {
            eprintln!("note: this CPU lacks {}: its tree rays are not tested here", isa.name());
        }
    }
    assert!(tested[0] > 0 && tested[1] > 0, "the scalar and SSE2 kernels always run");
    assert!(
        hits > 10_000 && blocked > 5_000 && edge_hits > 200 && ties > 50,
        "{hits} {blocked} {edge_hits} {ties}"
    );
}

#[test]
fn more_triangles_than_a_bvh_holds_are_an_error_not_a_panic() {
    assert_eq!(check_triangle_count(MAX_TRIANGLES), Ok(()));
    let error = check_triangle_count(MAX_TRIANGLES + 1).unwrap_err();
    assert_eq!(error, BuildError::TooManyTriangles(MAX_TRIANGLES + 1));
    assert_eq!(error.to_string(), "134217727 triangles: a BVH holds at most 134217726");
    assert!(Bvh::try_new(&[[Vec3::ZERO, Vec3::X, Vec3::Y]]).is_ok());
    // The memory estimate covers what the build keeps: at least the finished tree.
    let triangles: Vec<[Vec3; 3]> = (0..5000)
        .map(|i| {
            let p = Vec3::new(i as f32, (i % 7) as f32, (i % 13) as f32);
            [p, p + Vec3::X, p + Vec3::Y]
        })
        .collect();
    for settings in [BuildSettings::for_triangles(5000), BuildSettings::HIGH] {
        let bvh = Bvh::build(&triangles, &settings);
        assert!(Bvh::build_bytes_estimate(5000, &settings) >= 2 * bvh.stats().bytes() as u64);
    }
    // Finer binary leaves take more.
    let optimal = |binary_leaf_size| BuildSettings {
        collapse: Collapse::Optimal { binary_leaf_size },
        ..BuildSettings::HIGH
    };
    assert!(
        Bvh::build_bytes_estimate(5000, &optimal(1)) > Bvh::build_bytes_estimate(5000, &optimal(4))
    );
}

/// Mitsuba's box shares its corners as its shapes do: each of its six rectangles (five walls
/// and the light) has four corners, two of them in both its triangles, and each of its two
/// boxes eight, each in the triangles of three faces. Four of the walls' corners come out of
/// two walls' matrices with the same bits and are shared too. So 36 triangles, 108 triangle
/// corners, 6 × 4 − 4 + 2 × 8 = 36 distinct corners; each triangle's corners are its own.
#[test]
fn the_flat_list_shares_the_corners_of_mitsubas_box() {
    use crate::scene::{LoadOptions, Scene};
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let file = root.join("cornell-mitsuba.toml").display().to_string();
    let scene = Scene::open(&file, &LoadOptions::default()).expect("the scene file").scene;
    let triangles = scene.geometry.vertices();
    let bvh = Bvh::build(&triangles, &BuildSettings::MEDIUM);
    let shared = bvh.flat.as_ref().expect("a small scene's flat list").shared();
    assert_eq!((triangles.len(), shared.triangles.len(), shared.corners.len()), (36, 36, 36));
    let bits: std::collections::HashSet<_> =
        shared.corners.iter().map(|c| c.to_array().map(f32::to_bits)).collect();
    assert_eq!(bits.len(), shared.corners.len(), "distinct corners");
    for (k, &(corners, id)) in shared.triangles.iter().enumerate() {
        assert_eq!(id as usize, k, "in index order");
        assert_eq!(shared.triangle(corners), triangles[k], "triangle {id}");
    }
}

/// A flat list longer than [`BuildSettings::MAX_FLAT_LIMIT`] is never made, whatever the
/// settings ask: its lanes' frames would grow with it.
#[test]
fn the_flat_limit_is_clamped() {
    let triangles: Vec<[Vec3; 3]> = (0..=BuildSettings::MAX_FLAT_LIMIT)
        .map(|i| {
            let p = Vec3::new(i as f32, 0.0, 0.0);
            [p, p + Vec3::X, p + Vec3::Y]
        })
        .collect();
    let settings = BuildSettings { flat_limit: usize::MAX, ..BuildSettings::FAST };
    assert!(Bvh::build(&triangles, &settings).flat.is_none());
    assert!(Bvh::build(&triangles[1..], &settings).flat.is_some());
}
