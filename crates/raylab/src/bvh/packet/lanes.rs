//! The packet leaf kernel of the x86 instruction sets: a leaf's triangles against the packet's
//! rays, `L` rays per instruction ([`packet_leaf_lanes`]). Its scalar twin is
//! [`packet_leaf_scalar`](super::leaf::packet_leaf_scalar); the kernel types that call it are in
//! `packet/leaf.rs`, and the packet's node test (`FrustumBroadcast`) is with the node kernels.

use super::bundle::{LeafSize, LineBundle};
use super::rays::{PACKET, PacketRays};
use crate::bvh::bounds::{Bounds, FAR_SCALE, SLAB_PAD};
use crate::bvh::leaf::RECORD_VERTICES;
use crate::bvh::node::WideBvh;
use crate::bvh::simd::{LaneMask, Lanes, RayLanes, ShearedLanes, shear_point, watertight_sheared};

/// The lanes of a packet row from `base` on.
///
/// # Safety
/// The CPU must support `V`'s instruction set, and `base` plus the register's lanes must
/// not pass `PACKET`.
#[inline(always)]
unsafe fn lanes<V: Lanes>(row: &[f32; PACKET], base: usize) -> V {
    debug_assert!(base < PACKET);
    // SAFETY: the caller's guarantee.
    unsafe { V::loadu(row.as_ptr().add(base)) }
}

#[cfg(test)]
thread_local! {
    /// How many leaves this thread's packets tested without their box test (for the tests).
    pub(super) static COVERING: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

/// The triangles of the leaf at `offset` that some line of `bundle` may cross
/// ([`LineBundle::may_cross_record`]): bit `k` for its `k`-th triangle.
#[inline(always)]
fn crossable(bundle: &LineBundle, bvh: &WideBvh, offset: u32) -> u64 {
    let (mut live, mut first) = (0u64, 0);
    for record in bvh.leaves.leaf(offset) {
        live |= (bundle.may_cross_record(&record) as u64) << first;
        first += record.triangles();
    }
    live
}

/// [`PacketKernel::packet_leaf`](super::leaf::PacketKernel::packet_leaf) with `L` rays per
/// register `V`: the slab test of the leaf's box and the watertight test of each of its
/// triangles, for `L` rays at a time, by the same operations as the single-ray tests
/// ([`RayBoxTest::enter`](crate::bvh::RayBoxTest::enter), [`watertight_sheared`]).
///
/// Where the rays' lines meet in one point and the leaf is far larger than the packet's
/// footprint ([`LeafSize::Covering`]), the slab test is left out and every open ray is tested
/// against the triangles the bundle may cross. That changes no answer: the slab test is
/// conservative (a ray that hits a triangle enters the box of its
/// leaf, or the single-ray traversal would miss the hit that brute force finds), so it only
/// ever spares triangle tests, and a ray tested against more triangles than its own traversal
/// tests still gets the nearest hit below its limit, ties to the lowest index.
///
/// # Safety
/// The CPU must support `V`'s instruction set, which holds `L` (4, 8 or 16) floats.
#[inline(always)]
pub(crate) unsafe fn packet_leaf_lanes<V: Lanes, const L: usize>(
    rays: &mut PacketRays,
    open: &mut u64,
    occlusion: bool,
    bvh: &WideBvh,
    bounds: &Bounds,
    offset: u32,
) {
    let negative = rays.negative;
    // Per axis, not `[0, 1, 2].map(..)` (see `plane_rows`).
    let (lo, hi) = (bounds.min, bounds.max);
    let near_planes = [
        if negative[0] { hi.x } else { lo.x },
        if negative[1] { hi.y } else { lo.y },
        if negative[2] { hi.z } else { lo.z },
    ];
    let far_planes = [
        if negative[0] { lo.x } else { hi.x },
        if negative[1] { lo.y } else { hi.y },
        if negative[2] { lo.z } else { hi.z },
    ];
    let [kx, ky, kz] = rays.k;
    // For the whole function: every load reads `L` lanes from `base`, and `base + L <= PACKET`
    // because `PACKET` is a multiple of `L`; the table's rows are read only where `shared`,
    // after rows `0..nv` were written, and corners index below `nv`.
    // SAFETY: the caller's guarantee of the instruction set, and the bounds above.
    unsafe {
        // Bit `k` of `active[g]` for ray `L·g + k`, where that ray is tested against the leaf's
        // triangles; bit `k` of `live` for the leaf's `k`-th triangle (at most 64), where some
        // ray is tested against it.
        let mut active = [0u32; PACKET / 4];
        let groups = rays.len.div_ceil(L);
        // The leaf's size beside the packet's footprint, where the rays' lines meet in a point.
        let (bundle, size) = match &rays.bundle {
            Some(bundle) => (Some(bundle), bundle.size_of(bounds)),
            None => (None, LeafSize::Small),
        };
        let covering = if size == LeafSize::Covering { bundle } else { None };
        let live = if let Some(bundle) = covering {
            // A leaf that covers the packet (a wall of a small scene before a tile): the
            // triangles no line of the packet crosses culled once, the rest tested against
            // every open ray, without the slab test that would only keep most of them.
            let live = crossable(bundle, bvh, offset);
            if live == 0 {
                return;
            }
            #[cfg(test)]
            COVERING.set(COVERING.get() + 1);
            for (g, active) in active.iter_mut().enumerate().take(groups) {
                *active = (*open >> (g * L)) as u32 & ((1 << L) - 1);
            }
            live
        } else {
            // The slab test of every group of `L` rays, as `RayBoxTest::enter` per lane (no
            // operand is NaN: packet rays have finite origins and `1/d`, and a leaf's box is
            // finite).
            let mut any = 0;
            for (g, active) in active.iter_mut().enumerate().take(groups) {
                let base = g * L;
                let open = (*open >> base) as u32 & ((1 << L) - 1);
                if open == 0 {
                    continue;
                }
                let mut near = lanes::<V>(&rays.box_t_min, base);
                let mut far = lanes::<V>(&rays.box_limit, base);
                let mut reach = V::splat(0.0);
                for axis in 0..3 {
                    let o = lanes::<V>(&rays.origin[axis], base);
                    let inv = lanes::<V>(&rays.inv_direction[axis], base);
                    let t_near = V::splat(near_planes[axis]).sub(o).mul(inv);
                    let t_far = V::splat(far_planes[axis]).sub(o).mul(inv);
                    near = t_near.max(near);
                    far = t_far.mul(V::splat(FAR_SCALE)).min(far);
                    if axis == kz {
                        reach = t_near.abs().max(t_far.abs());
                    }
                }
                let pad = reach.mul(V::splat(SLAB_PAD));
                *active = open & near.sub(pad).le_mask(far.add(pad));
                any |= *active;
            }
            if any == 0 {
                return;
            }
            // Culled only now that some ray enters the leaf's box (in large meshes most leaves
            // the packet's frustum reaches are entered by none of its rays), and only where
            // the leaf is large beside the packet.
            match bundle {
                Some(bundle) if size == LeafSize::Large => crossable(bundle, bvh, offset),
                _ => u64::MAX,
            }
        };

        // Record by record: its corners decoded and its vertices read once, then for each
        // group its vertices in the rays' frames (once per vertex) and its triangles tested.
        let mut table = [std::mem::MaybeUninit::<[V; 3]>::uninit(); RECORD_VERTICES];
        let mut first = 0;
        for record in bvh.leaves.leaf(offset) {
            let (nv, nt) = (record.vertices(), record.triangles());
            let todo = (live >> first) as u32 & ((1 << nt) - 1);
            first += nt;
            if todo == 0 {
                continue;
            }
            let corner_rows = record.corner_rows();
            let rows = record.rows();
            let (x, y, z) = (rows[kx], rows[ky], rows[kz]);
            for (g, active) in active.iter_mut().enumerate().take(groups) {
                if *active == 0 {
                    continue;
                }
                let base = g * L;
                let shear = [
                    lanes::<V>(&rays.shear[0], base),
                    lanes::<V>(&rays.shear[1], base),
                    lanes::<V>(&rays.shear[2], base),
                ];
                let origin = [
                    lanes::<V>(&rays.origin[kx], base),
                    lanes::<V>(&rays.origin[ky], base),
                    lanes::<V>(&rays.origin[kz], base),
                ];
                let abs_shear = [shear[0].abs(), shear[1].abs()];
                let t_min = lanes::<V>(&rays.triangle_t_min, base);
                // Each vertex into the rays' frames once (rows `0..nv` of the table, which
                // corners index), where that is less work than each corner of the triangles to
                // test (about 13 against 21 instructions: where they share vertices, as in a
                // mesh; the small scenes' leaves of separate quads do not). The same values
                // either way.
                let shared = 13 * nv < 21 * todo.count_ones() as usize;
                if shared {
                    for (v, row) in table.iter_mut().enumerate().take(nv) {
                        let p = [V::splat(x[v]), V::splat(y[v]), V::splat(z[v])];
                        row.write(shear_point(origin, shear, p));
                    }
                }
                let mut todo = todo;
                while todo != 0 {
                    let t = todo.trailing_zeros() as usize;
                    todo &= todo - 1;
                    let [a, b, c] = corner_rows.map(|row| row[t] as usize);
                    // Not `.map(..)` on vectors: a closure would not inherit the target
                    // features.
                    let (a, b, c) = if shared {
                        (table[a].assume_init(), table[b].assume_init(), table[c].assume_init())
                    } else {
                        let vertex = |v: usize| [x[v], y[v], z[v]];
                        let [a, b, c] = [vertex(a), vertex(b), vertex(c)];
                        (
                            shear_point(
                                origin,
                                shear,
                                [V::splat(a[0]), V::splat(a[1]), V::splat(a[2])],
                            ),
                            shear_point(
                                origin,
                                shear,
                                [V::splat(b[0]), V::splat(b[1]), V::splat(b[2])],
                            ),
                            shear_point(
                                origin,
                                shear,
                                [V::splat(c[0]), V::splat(c[1]), V::splat(c[2])],
                            ),
                        )
                    };
                    let sheared = ShearedLanes {
                        x: [a[0], b[0], c[0]],
                        y: [a[1], b[1], c[1]],
                        z: [a[2], b[2], c[2]],
                    };
                    let ray_lanes = RayLanes {
                        shear_z: shear[2],
                        abs_shear,
                        t_min,
                        t_max: lanes::<V>(&rays.triangle_limit, base),
                    };
                    let decided = watertight_sheared::<V, true>(&sheared, &ray_lanes, *active);
                    let mut hits = decided.hits;
                    let (mut t_hit, mut b1, mut b2) = ([0.0f32; L], [0.0f32; L], [0.0f32; L]);
                    if hits != 0 {
                        decided.t.store(t_hit.as_mut_ptr());
                        decided.b1.store(b1.as_mut_ptr());
                        decided.b2.store(b2.as_mut_ptr());
                    }
                    let mut undecided = decided.undecided;
                    if undecided != 0 {
                        let [v0, v1, v2] = record.triangle(t);
                        while undecided != 0 {
                            let j = undecided.trailing_zeros() as usize;
                            undecided &= undecided - 1;
                            let i = base + j;
                            let limit = rays.triangle_limit[i];
                            if let Some(h) = rays.triangle_ray(i).intersect(v0, v1, v2, limit) {
                                hits |= 1 << j;
                                (t_hit[j], b1[j], b2[j]) = (h.t, h.b1, h.b2);
                            }
                        }
                    }
                    if hits == 0 {
                        continue;
                    }
                    if occlusion {
                        *open &= !((hits as u64) << base);
                        *active &= !hits;
                        if *active == 0 {
                            break;
                        }
                    } else {
                        let id = record.id(t);
                        // The decided hits nearer than their ray's best a register at a time;
                        // the rest (as near as the best, or decided by the scalar test) one by
                        // one.
                        let best = lanes::<V>(&rays.best_t, base);
                        let nearer = decided.t.lt(best).bits() & decided.hits;
                        if nearer != 0 {
                            let found = [decided.t, decided.b1, decided.b2];
                            rays.take_nearer::<V>(base, nearer, id, found);
                            hits &= !nearer;
                        }
                        while hits != 0 {
                            let j = hits.trailing_zeros() as usize;
                            hits &= hits - 1;
                            rays.offer(base + j, t_hit[j], id, b1[j], b2[j]);
                        }
                    }
                }
            }
            if occlusion && *open == 0 {
                return;
            }
        }
    }
}
