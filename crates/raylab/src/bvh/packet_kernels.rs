//! The packet kernels of the x86 instruction sets: a packet's frustum against a node's eight
//! boxes ([`FrustumBroadcast`]) and a leaf's triangles against the packet's rays, `L` rays per
//! instruction ([`packet_leaf_lanes`]). Their scalar twins are [`Frustum::enter`] and
//! [`packet_leaf_scalar`](super::packet::packet_leaf_scalar); the node kernels that call them
//! are in `kernels`.

use super::bounds::{Bounds, FAR_SCALE, Frustum, SLAB_PAD};
use super::kernels::plane_rows;
use super::lanes::Lanes;
use super::leaf::RECORD_VERTICES;
use super::packet_rays::{PACKET, PacketRays};
use super::watertight_lanes::{RayLanes, ShearedLanes, shear_point, watertight_sheared};
use super::wide::{WideBvh, WideNode};

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

/// [`NodeKernel::packet_leaf`] with `L` rays per register `V`: the slab test of the leaf's box
/// and the watertight test of each of its triangles, for `L` rays at a time, by the same
/// operations as the single-ray tests ([`RayBoxTest::enter`], [`watertight_sheared`]).
///
/// # Safety
/// The CPU must support `V`'s instruction set, which holds `L` (4, 8 or 16) floats.
#[inline(always)]
pub(super) unsafe fn packet_leaf_lanes<V: Lanes, const L: usize>(
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
        // The slab test of every group of `L` rays first, as `RayBoxTest::enter` per lane (no
        // operand is NaN: packet rays have finite origins and `1/d`, and a leaf's box is
        // finite): bit `k` of `active[g]` for ray `L·g + k`.
        let mut active = [0u32; PACKET / 4];
        let groups = rays.len.div_ceil(L);
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
        // The leaf's triangles some line of the packet may cross (bit `k` for its `k`-th
        // triangle, at most 64): where the rays' lines meet in one point, the others are culled
        // once for the whole packet (only now that some ray enters the leaf's box: in large
        // meshes most leaves the packet's frustum reaches are entered by none of its rays), and
        // only where the leaf is large beside the packet (`LineBundle::worth_culling`).
        let live = match &rays.bundle {
            Some(bundle) if bundle.worth_culling(bounds) => {
                let (mut live, mut first) = (0u64, 0);
                for record in bvh.leaves.leaf(offset) {
                    live |= (bundle.may_cross_record(&record) as u64) << first;
                    first += record.triangles();
                }
                live
            }
            _ => u64::MAX,
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

/// A vector in three registers of equal lanes.
///
/// # Safety
/// The CPU must support `V`'s instruction set.
#[inline(always)]
unsafe fn splat3<V: Lanes>(v: glam::Vec3) -> [V; 3] {
    // SAFETY: the caller's guarantee.
    unsafe { [V::splat(v.x), V::splat(v.y), V::splat(v.z)] }
}

/// The least and greatest products of two intervals, as `bounds::interval_product`.
///
/// # Safety
/// The CPU must support `V`'s instruction set.
#[inline(always)]
unsafe fn interval_product<V: Lanes>(a_lo: V, a_hi: V, i_lo: V, i_hi: V) -> (V, V) {
    // SAFETY: the caller's guarantee.
    unsafe {
        let (p0, p1) = (a_lo.mul(i_lo), a_lo.mul(i_hi));
        let (p2, p3) = (a_hi.mul(i_lo), a_hi.mul(i_hi));
        (p0.min(p1).min(p2.min(p3)), p0.max(p1).max(p2.max(p3)))
    }
}

/// A packet's bound broadcast into vector registers.
#[derive(Clone, Copy)]
pub(crate) struct FrustumBroadcast<V> {
    origin_lo: [V; 3],
    origin_hi: [V; 3],
    inv_lo: [V; 3],
    inv_hi: [V; 3],
    t_min: V,
    near_rows: [usize; 3],
    far_rows: [usize; 3],
    pad_axes: [bool; 3],
}

impl<V: Lanes> FrustumBroadcast<V> {
    /// # Safety
    /// The CPU must support `V`'s instruction set.
    #[inline(always)]
    pub(super) unsafe fn new(f: &Frustum) -> Self {
        let (near_rows, far_rows) = plane_rows(f.negative);
        // SAFETY: the caller's guarantee.
        unsafe {
            FrustumBroadcast {
                origin_lo: splat3(f.origin_lo),
                origin_hi: splat3(f.origin_hi),
                inv_lo: splat3(f.inv_lo),
                inv_hi: splat3(f.inv_hi),
                t_min: V::splat(f.t_min),
                near_rows,
                far_rows,
                pad_axes: f.pad_axes,
            }
        }
    }

    /// [`Frustum::enter`] for the children from `first` on that `V` holds: their mask (bit 0 for child
    /// `first`), and their entries written to `out[first..]`.
    ///
    /// # Safety
    /// The CPU must support `V`'s instruction set; `first` is 0, or 4 for a 4-lane `V`.
    #[inline(always)]
    pub(super) unsafe fn enter(
        &self,
        node: &WideNode,
        t_limit: f32,
        first: usize,
        out: &mut [f32],
    ) -> u32 {
        // SAFETY: the caller's guarantee; loads read one register of a 32-byte aligned row
        // of 8 from `first`, which is aligned to the register size.
        unsafe {
            let scale = V::splat(FAR_SCALE);
            let mut near = self.t_min;
            let mut far = V::splat(t_limit);
            let mut reach = V::splat(0.0);
            for axis in 0..3 {
                let np = V::load(node.planes[self.near_rows[axis]][first..].as_ptr());
                let fp = V::load(node.planes[self.far_rows[axis]][first..].as_ptr());
                let (o_lo, o_hi) = (self.origin_lo[axis], self.origin_hi[axis]);
                let (i_lo, i_hi) = (self.inv_lo[axis], self.inv_hi[axis]);
                let (tn_lo, tn_hi) = interval_product(np.sub(o_hi), np.sub(o_lo), i_lo, i_hi);
                let (tf_lo, tf_hi) = interval_product(fp.sub(o_hi), fp.sub(o_lo), i_lo, i_hi);
                near = tn_lo.max(near);
                far = tf_hi.mul(scale).min(far);
                if self.pad_axes[axis] {
                    let axis_reach = tn_lo.abs().max(tn_hi.abs()).max(tf_lo.abs().max(tf_hi.abs()));
                    reach = reach.max(axis_reach);
                }
            }
            let pad = reach.mul(V::splat(SLAB_PAD));
            let near = near.sub(pad);
            let far = far.add(pad);
            near.store(out[first..].as_mut_ptr());
            near.le_mask(far) << first
        }
    }
}
