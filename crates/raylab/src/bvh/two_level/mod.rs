//! A two-level accelerator: a top level over instances, a bottom level per stored mesh.
//!
//! A [`Geometry`] with instances (see [`crate::geometry::instance`]) stores a mesh drawn in
//! several places once. [`TwoLevel`] builds one bottom-level accelerator per stored mesh, over
//! its triangles in their own space, and one over every triangle stored in world space (the
//! meshes drawn once), and a small binary tree over the instances' world boxes on top. Where
//! the instances are few (up to 64), single rays test all their boxes at once instead, sixteen
//! per instruction (`rows.rs`); packets of rays walk the tree (`lanes.rs`).
//!
//! A ray that reaches an instance's box is carried into the instance's space by its inverse
//! placement, `o' = M⁻¹·o` and `d' = M⁻¹·d` (not renormalized, so `t` keeps its meaning and hits
//! of different instances compare by `t` directly), and traced through the mesh's bottom level.
//! The transformed ray is the same for every triangle of the instance, so the watertight test
//! leaves no crack between them: the crack test holds through instances as it does on flat
//! meshes. Hits at equal `t` still go to the lowest scene triangle index: within an instance
//! the bottom level decides it (its local order is the scene order), across instances the
//! top level lets a later instance's hit at exactly the best `t` through and keeps the first.
//!
//! The answers are those of the same bottom-level test made instance by instance, whatever the
//! bottom accelerator: a [`TwoLevel<BruteForce>`](crate::BruteForce) and a
//! [`TwoLevel<Bvh>`](crate::Bvh) agree exactly (`tests/instancing.rs`).

use std::cell::Cell;
use std::collections::HashMap;

use glam::Vec3;

mod build;
mod lanes;
mod rows;
mod top;

use crate::accel::{Accelerator, Hit, HitRows, ROWS, RayRows};
use crate::bvh::{Bounds, Frustum, RayBoxTest};
use crate::geometry::Geometry;
use crate::geometry::instance::max_row_sum;
use crate::ray::Ray;
use build::{build_top, padded, transformed};
use lanes::BoxLanes;
use rows::{Entries, TopRows};
use top::{Margin, Node, PACKET, Placed, RAY_ERROR};

/// Instances over per-mesh accelerators `A` (see the module documentation).
pub struct TwoLevel<A> {
    bottoms: Vec<Bottom<A>>,
    placed: Vec<Placed>,
    /// The top level, depth first: an inner node's left child follows it.
    nodes: Vec<Node>,
    /// The same boxes as rows, for single rays, where the instances are few (`rows.rs`).
    rows: Option<TopRows>,
}

/// One bottom-level accelerator and how its hits' indices become scene triangles.
struct Bottom<A> {
    accel: A,
    /// Its triangle count.
    triangles: usize,
    /// For the bottom over world-space triangles: the scene index of each of its triangles.
    /// Empty for a stored mesh (its instances add their first scene index).
    scene_ids: Vec<u32>,
}

impl<A: Accelerator> TwoLevel<A> {
    /// Builds over `geometry`'s instances, making each bottom level with `build` from triangles'
    /// corners (in the mesh's own space for an instanced mesh).
    pub fn build<E>(
        geometry: &Geometry,
        mut build: impl FnMut(&[[Vec3; 3]]) -> Result<A, E>,
    ) -> Result<TwoLevel<A>, E> {
        let mut bottoms = Vec::new();
        let mut placed = Vec::new();
        // Every triangle stored in world space goes into one bottom level.
        let mut world = Vec::new();
        let mut scene_ids = Vec::new();
        for instance in geometry.instances().iter().filter(|x| x.placement.is_none()) {
            for k in 0..instance.count {
                world.push(geometry.stored_triangle((instance.stored_first + k) as usize));
                scene_ids.push(instance.first + k);
            }
        }
        if !world.is_empty() {
            let bounds = world.iter().fold(Bounds::EMPTY, |b, &t| b.union(Bounds::of_triangle(t)));
            placed.push(Placed {
                bottom: 0,
                first: 0,
                placement: None,
                bounds: padded(bounds, 0.0),
                margin: Margin::default(),
            });
            bottoms.push(Bottom { accel: build(&world)?, triangles: world.len(), scene_ids });
        }
        drop(world);
        // One bottom level per stored mesh, shared by its instances.
        let mut by_stored: HashMap<(u32, u32), (u32, Bounds)> = HashMap::new();
        for instance in geometry.instances() {
            let Some(placement) = &instance.placement else { continue };
            let key = (instance.stored_first, instance.count);
            let (bottom, local) = match by_stored.get(&key) {
                Some(&entry) => entry,
                None => {
                    let triangles: Vec<[Vec3; 3]> = (0..instance.count)
                        .map(|k| geometry.stored_triangle((instance.stored_first + k) as usize))
                        .collect();
                    let bounds = triangles
                        .iter()
                        .fold(Bounds::EMPTY, |b, &t| b.union(Bounds::of_triangle(t)));
                    let accel = build(&triangles)?;
                    let entry = (bottoms.len() as u32, bounds);
                    bottoms.push(Bottom { accel, triangles: triangles.len(), scene_ids: vec![] });
                    by_stored.insert(key, entry);
                    entry
                }
            };
            let (m, translation) = (&placement.to_world, placement.to_world.translation);
            // The corners `M·p` round by about ε (|A|·|p| + |T|).
            let size = max_row_sum(&m.matrix3) * local.min.abs().max(local.max.abs()).max_element()
                + translation.abs().max_element();
            let bounds = padded(transformed(&local, m), size);
            let margin = Margin {
                scale: RAY_ERROR
                    * f32::EPSILON
                    * max_row_sum(&m.matrix3)
                    * max_row_sum(&placement.to_object.matrix3),
                reach: bounds.min.abs().max(bounds.max.abs()).max_element()
                    + translation.abs().max_element(),
            };
            placed.push(Placed {
                bottom,
                first: instance.first,
                placement: Some(*placement),
                bounds,
                margin,
            });
        }
        placed.retain(|p| !p.bounds.is_empty());
        let mut nodes = Vec::new();
        if !placed.is_empty() {
            let n = placed.len();
            build_top(&mut placed, (0, n), 0, &mut nodes);
        }
        let rows = TopRows::new(&placed, crate::cpu::Isa::detect());
        Ok(TwoLevel { bottoms, placed, nodes, rows })
    }

    /// The same accelerator with its single rays walking the top level's tree even where the
    /// instances are few enough for rows (`rows.rs`), or its rows tested with `isa`'s
    /// instructions (which this CPU must have): for the tests that compare them, with the
    /// `support` feature.
    #[cfg(feature = "support")]
    pub fn with_top_rows(mut self, isa: Option<crate::cpu::Isa>) -> Self {
        assert!(isa.is_none_or(|isa| isa.is_supported()), "{isa:?} is not supported here");
        self.rows = isa.and_then(|isa| TopRows::new(&self.placed, isa));
        self
    }

    /// Whether single rays test the top level's boxes as rows (at most 64 instances) rather
    /// than walk its tree.
    #[doc(hidden)]
    pub fn has_top_rows(&self) -> bool {
        self.rows.is_some()
    }

    /// The triangles the bottom levels hold: each stored mesh's once, however many instances
    /// draw it.
    pub fn bottom_triangles(&self) -> usize {
        self.bottoms.iter().map(|b| b.triangles).sum()
    }

    /// The number of bottom-level accelerators.
    pub fn bottom_count(&self) -> usize {
        self.bottoms.len()
    }

    /// The number of instances the top level holds.
    pub fn instance_count(&self) -> usize {
        self.placed.len()
    }

    /// The bottom-level accelerators.
    pub fn bottoms(&self) -> impl Iterator<Item = &A> {
        self.bottoms.iter().map(|b| &b.accel)
    }

    /// The bytes of the top level and the bottoms' index tables (not the bottom accelerators).
    pub fn top_bytes(&self) -> usize {
        std::mem::size_of_val(self.nodes.as_slice())
            + std::mem::size_of_val(self.placed.as_slice())
            + self.bottoms.iter().map(|b| 4 * b.scene_ids.len()).sum::<usize>()
    }

    /// The ray in `placed`'s space, limited to `t < t_max`.
    #[inline]
    fn local_ray(placed: &Placed, ray: &Ray, t_max: f32) -> Ray {
        match &placed.placement {
            None => Ray { t_max, ..*ray },
            Some(p) => Ray {
                origin: p.to_object.transform_point3(ray.origin),
                direction: p.to_object.transform_vector3(ray.direction),
                t_min: ray.t_min,
                t_max,
            },
        }
    }

    /// The rays of `mask` that `t_max` keeps (giving each its `t_max`), carried into
    /// `placed`'s space: into `local`, their packet indices into `which`.
    #[inline]
    fn gather(
        placed: &Placed,
        rays: &[Ray],
        mask: u64,
        t_max: impl Fn(usize) -> Option<f32>,
        local: &mut Vec<Ray>,
        which: &mut Vec<usize>,
    ) {
        local.clear();
        which.clear();
        let mut rest = mask;
        while rest != 0 {
            let i = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            if let Some(t_max) = t_max(i) {
                local.push(Self::local_ray(placed, &rays[i], t_max));
                which.push(i);
            }
        }
    }

    /// A bottom level's hit as a hit on a scene triangle.
    #[inline]
    fn scene_hit(&self, placed: &Placed, hit: Hit) -> Hit {
        let bottom = &self.bottoms[placed.bottom as usize];
        if let Some(&id) = bottom.scene_ids.get(hit.triangle as usize) {
            return Hit { triangle: id, ..hit };
        }
        let triangle = placed.first + hit.triangle;
        match &placed.placement {
            Some(p) => p.world_hit(hit, triangle),
            None => Hit { triangle, ..hit },
        }
    }

    /// Visits the top level's leaves that the ray may reach within the current `t_max` (which
    /// `visit` may lower), nearest box first; `visit` returns `true` to stop.
    #[inline]
    fn walk(&self, ray: &Ray, mut visit: impl FnMut(&Placed) -> Option<f32>) {
        if self.nodes.is_empty() || !ray.origin.is_finite() || !ray.direction.is_finite() {
            return;
        }
        let test = RayBoxTest::new(ray);
        let size = ray.origin.abs().max_element();
        let mut t_max = ray.t_max;
        if let Some(rows) = &self.rows {
            // Every box at once, then the instances entered, nearest entry first.
            let mut entries = Entries::new();
            let mut left = rows.enter(&test, size, t_max, &mut entries);
            while left != 0 {
                let mut k = left.trailing_zeros() as usize;
                let mut rest = left & (left - 1);
                while rest != 0 {
                    let j = rest.trailing_zeros() as usize;
                    rest &= rest - 1;
                    if entries.near[j] < entries.near[k] {
                        k = j;
                    }
                }
                left &= !(1 << k);
                if entries.enters(k, t_max) {
                    match visit(&self.placed[k]) {
                        Some(t) => t_max = t_max.min(t),
                        None => return,
                    }
                }
            }
            return;
        }
        let grow = |b: &Bounds, margin: &Margin| grown(b, margin.pad(size));
        let mut stack = [(0u32, 0f32); STACK];
        let mut len = 0;
        let root = &self.nodes[0];
        if let Some(t) = test.enter(&grow(&root.bounds, &root.margin), t_max) {
            stack[0] = (0, t);
            len = 1;
        }
        while len > 0 {
            len -= 1;
            let (index, entry) = stack[len];
            if entry > t_max {
                continue;
            }
            let node = &self.nodes[index as usize];
            if node.count > 0 {
                let range = node.index as usize..(node.index + node.count) as usize;
                for placed in &self.placed[range] {
                    if test.enter(&grow(&placed.bounds, &placed.margin), t_max).is_some() {
                        match visit(placed) {
                            Some(t) => t_max = t_max.min(t),
                            None => return,
                        }
                    }
                }
                continue;
            }
            let (left, right) = (index + 1, node.index);
            let (left_node, right_node) = (&self.nodes[left as usize], &self.nodes[right as usize]);
            let near = test.enter(&grow(&left_node.bounds, &left_node.margin), t_max);
            let far = test.enter(&grow(&right_node.bounds, &right_node.margin), t_max);
            let mut push = |entry: (u32, f32)| {
                stack[len] = entry;
                len += 1;
            };
            match (near, far) {
                (Some(a), Some(b)) if a <= b => {
                    push((right, b));
                    push((left, a));
                }
                (Some(a), Some(b)) => {
                    push((left, a));
                    push((right, b));
                }
                (Some(a), None) => push((left, a)),
                (None, Some(b)) => push((right, b)),
                (None, None) => {}
            }
        }
    }
}

impl<A: Accelerator> TwoLevel<A> {
    /// Visits, for up to [`PACKET`] rays together, each top-level leaf with the mask of the rays
    /// that may reach it (their boxes tested against `t_max(i)` at the time); `visit` gets the
    /// instance and the mask.
    fn walk_packet(
        &self,
        rays: &[Ray],
        t_max: impl Fn(usize) -> f32,
        mut visit: impl FnMut(&Placed, u64),
    ) {
        debug_assert!(rays.len() <= PACKET);
        if self.nodes.is_empty() {
            return;
        }
        let mut tests = [None; PACKET];
        let mut live = 0u64;
        for (i, ray) in rays.iter().enumerate() {
            if ray.origin.is_finite() && ray.direction.is_finite() {
                tests[i] = Some(RayBoxTest::new(ray));
                live |= 1 << i;
            }
        }
        let lead =
            rays.iter().find(|r| r.direction.is_finite()).map_or(Vec3::ZERO, |r| r.direction);
        // A bound on the whole packet where the rays share their directions' signs: a box it
        // misses is missed by every ray, at the cost of one test.
        let frustum = Frustum::of(tests[..rays.len()].iter().flatten().copied());
        let packet_t_max = (0..rays.len())
            .map(&t_max)
            .fold(f32::NEG_INFINITY, |a, t| if t.is_nan() { f32::INFINITY } else { a.max(t) });
        // The rays lane by lane, their `t_max` brought up to date after every visit.
        let mut lanes = BoxLanes::new(&tests[..rays.len()]);
        let packet_size = lanes.largest_size();
        let refresh = |lanes: &mut BoxLanes| {
            for (i, t) in lanes.t_max[..rays.len()].iter_mut().enumerate() {
                *t = t_max(i);
            }
        };
        refresh(&mut lanes);
        let reaching = |lanes: &BoxLanes, bounds: &Bounds, margin: &Margin, mask: u64| {
            if let Some(frustum) = &frustum
                && frustum.enter(&grown(bounds, margin.pad(packet_size)), packet_t_max).is_none()
            {
                return 0;
            }
            lanes.reaching(bounds, margin, mask)
        };
        let mut stack = [(0u32, 0u64); STACK];
        let mut len = 0;
        let root = reaching(&lanes, &self.nodes[0].bounds, &self.nodes[0].margin, live);
        if root != 0 {
            stack[0] = (0, root);
            len = 1;
        }
        while len > 0 {
            len -= 1;
            let (index, mask) = stack[len];
            let node = &self.nodes[index as usize];
            if node.count > 0 {
                let range = node.index as usize..(node.index + node.count) as usize;
                for placed in &self.placed[range] {
                    let mask = reaching(&lanes, &placed.bounds, &placed.margin, mask);
                    if mask != 0 {
                        visit(placed, mask);
                        refresh(&mut lanes);
                    }
                }
                continue;
            }
            // The packet's nearer child last, to be visited first (by its first ray's
            // direction): its hits then cull the farther child's instances.
            let (left, right) = (index + 1, node.index);
            let between = self.nodes[right as usize].bounds.centroid()
                - self.nodes[left as usize].bounds.centroid();
            let order = if between.dot(lead) < 0.0 { [left, right] } else { [right, left] };
            for child in order {
                let child_node = &self.nodes[child as usize];
                let mask = reaching(&lanes, &child_node.bounds, &child_node.margin, mask);
                if mask != 0 {
                    stack[len] = (child, mask);
                    len += 1;
                }
            }
        }
    }
}

impl<A: Accelerator> Accelerator for TwoLevel<A> {
    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        self.walk(ray, |placed| {
            // A hit at exactly the best `t` may still win on its lower index: let it through.
            let t_max = best.map_or(ray.t_max, |b| b.t.next_up());
            let local = Self::local_ray(placed, ray, t_max);
            if let Some(hit) = self.bottoms[placed.bottom as usize].accel.closest_hit(&local) {
                self.scene_hit(placed, hit).keep_first(&mut best);
            }
            Some(best.map_or(ray.t_max, |b| b.t.next_up()))
        });
        best
    }

    fn occluded(&self, ray: &Ray) -> bool {
        let mut occluded = false;
        self.walk(ray, |placed| {
            let local = Self::local_ray(placed, ray, ray.t_max);
            occluded = self.bottoms[placed.bottom as usize].accel.occluded(&local);
            if occluded { None } else { Some(ray.t_max) }
        });
        occluded
    }

    /// Traces up to 64 rays at a time through the top level together, and the rays that reach
    /// an instance through its bottom level together (its packets, for a BVH). The answers are
    /// exactly those of [`closest_hit`](Self::closest_hit).
    fn closest_hits(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), hits.len(), "one answer per ray");
        let mut local = Vec::with_capacity(PACKET);
        let mut local_hits = Vec::with_capacity(PACKET);
        let mut which = Vec::with_capacity(PACKET);
        for (rays, hits) in rays.chunks(PACKET).zip(hits.chunks_mut(PACKET)) {
            hits.fill(None);
            let best: [Cell<Option<Hit>>; PACKET] = std::array::from_fn(|_| Cell::new(None));
            // A hit at exactly the best `t` may still win on its lower index: let it through.
            let t_max = |i: usize| best[i].get().map_or(rays[i].t_max, |b| b.t.next_up());
            self.walk_packet(rays, t_max, |placed, mask| {
                Self::gather(placed, rays, mask, |i| Some(t_max(i)), &mut local, &mut which);
                local_hits.clear();
                local_hits.resize(local.len(), None);
                self.bottoms[placed.bottom as usize].accel.closest_hits(&local, &mut local_hits);
                for (&i, hit) in which.iter().zip(&local_hits) {
                    if let Some(hit) = hit {
                        let mut b = best[i].get();
                        self.scene_hit(placed, *hit).keep_first(&mut b);
                        best[i].set(b);
                    }
                }
            });
            for (hit, best) in hits.iter_mut().zip(&best) {
                *hit = best.get();
            }
        }
    }

    /// Occlusion for up to 64 rays at a time, as [`closest_hits`](Self::closest_hits); the
    /// answers are exactly those of [`occluded`](Self::occluded).
    fn occluded_each(&self, rays: &[Ray], occluded: &mut [bool]) {
        assert_eq!(rays.len(), occluded.len(), "one answer per ray");
        let mut local = Vec::with_capacity(PACKET);
        let mut local_occluded = Vec::with_capacity(PACKET);
        let mut which = Vec::with_capacity(PACKET);
        for (rays, occluded) in rays.chunks(PACKET).zip(occluded.chunks_mut(PACKET)) {
            let done: [Cell<bool>; PACKET] = std::array::from_fn(|_| Cell::new(false));
            // An occluded ray has nothing left to find: an empty range drops it.
            let t_max = |i: usize| if done[i].get() { f32::NEG_INFINITY } else { rays[i].t_max };
            self.walk_packet(rays, t_max, |placed, mask| {
                let open = |i: usize| (!done[i].get()).then_some(rays[i].t_max);
                Self::gather(placed, rays, mask, open, &mut local, &mut which);
                local_occluded.clear();
                local_occluded.resize(local.len(), false);
                let bottom = &self.bottoms[placed.bottom as usize].accel;
                bottom.occluded_each(&local, &mut local_occluded);
                for (&i, &o) in which.iter().zip(&local_occluded) {
                    if o {
                        done[i].set(true);
                    }
                }
            });
            for (o, done) in occluded.iter_mut().zip(done) {
                *o = done.get();
            }
        }
    }

    /// Through [`closest_hits`](Self::closest_hits)' packets, copied into rows.
    fn closest_hits_rows(&self, rays: &[Ray], hits: &mut HitRows) {
        assert!(rays.len() <= ROWS, "at most {ROWS} rays in rows");
        let mut answers = [None; ROWS];
        let answers = &mut answers[..rays.len()];
        self.closest_hits(rays, answers);
        for (i, &hit) in answers.iter().enumerate() {
            hits.set(i, hit);
        }
    }

    /// Through [`occluded_each`](Self::occluded_each)'s packets, as a mask.
    fn occluded_rows(&self, rays: &RayRows) -> u64 {
        assert!(rays.len <= ROWS, "at most {ROWS} rays in rows");
        let list: [Ray; ROWS] = std::array::from_fn(|i| rays.ray(i));
        let mut occluded = [false; ROWS];
        self.occluded_each(&list[..rays.len], &mut occluded[..rays.len]);
        (0..rays.len).filter(|&i| occluded[i]).fold(0, |mask, i| mask | 1 << i)
    }
}

/// `bounds` grown by `pad` on every side.
#[inline]
fn grown(bounds: &Bounds, pad: f32) -> Bounds {
    Bounds { min: bounds.min - Vec3::splat(pad), max: bounds.max + Vec3::splat(pad) }
}

/// Entries of a traversal stack: at most one per level of the tree, plus one.
const STACK: usize = build::SAH_DEPTH as usize + 34;

/// A small deterministic generator for the top level's tests: SplitMix64's step, its top 24 bits
/// as a number in `[0, 1)`.
#[cfg(test)]
fn tests_uniform(state: &mut u64) -> f32 {
    *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    (crate::sampling::mix64(*state) >> 40) as f32 / (1u64 << 24) as f32
}
