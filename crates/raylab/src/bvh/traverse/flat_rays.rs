//! A small scene's flat list against many incoherent rays at once: the rays in lanes, one
//! triangle per step.
//!
//! `flat.rs` answers one ray at a time with sixteen triangles per instruction. Each ray then
//! pays for its own set-up (the dominant axis, the shear, one division), for broadcasting it
//! into registers, and for the reduction that picks its nearest lane at the end: on Mitsuba's
//! 36-triangle box, three blocks of real work carry about as much again in overhead, and a path
//! tracer's wavefront asks for hundreds of such rays at a time. Here the roles swap, as in a
//! ray stream: `W` rays sit in the lanes of a register (sixteen on AVX-512, eight on AVX2, four
//! on SSE2), and each triangle of the list is broadcast to all of them. A lane keeps its own
//! nearest hit in registers, so nothing is reduced across lanes, and a triangle that no lane can
//! hit skips the division and the error bound
//! ([`watertight_sheared_scaled`]'s early out).
//!
//! Occlusion runs in lanes too, although a group runs until its last ray is blocked or has seen
//! every triangle where a ray alone stops at its first blocker: in a closed box most shadow
//! rays are unblocked, so a lone ray seldom stops early anyway, and with the corners shared
//! (below) the lanes are the faster (`cargo bench -p raylab --bench flat_rays`).
//!
//! ## Corners shared
//! A closed mesh's corner belongs to about six triangles; Mitsuba's 36-triangle box has 108
//! triangle corners but only 36 distinct ones (`SharedCorners`, made with the list). A group
//! of rays puts each distinct corner in its lanes' ray frames once (the permutation below and
//! the shear, sixteen operations a corner, and `kz` scaled by `shear_z`), then tests each
//! triangle from three loads per coordinate. Corners are distinct by their bits, so a
//! triangle's frame coordinates are those it would compute itself, bit for bit.
//!
//! ## The permutation, lane by lane
//! The watertight test looks at a triangle along the ray's dominant axis `kz`, with `kx`, `ky`
//! the other two ([`WatertightRay`]). Rays in lanes have different axes, so each lane picks its
//! own coordinates of the broadcast corners: `kx = 0, 1, 2` selects `x`, `y` or `z` with two
//! selects per coordinate, six per corner (once per distinct corner and group, below), masks
//! made once per group of rays. Sorting the rays by axis instead would leave up to six
//! part-filled groups in every batch.
//!
//! ## The answers are the single-ray query's
//! Each lane runs [`watertight_sheared_scaled`], the same operations in the same order as
//! [`WatertightRay::intersect`]; lanes whose edge functions round to zero are decided by
//! `intersect` itself in double precision. Triangles come in index order and a lane takes a hit
//! only if it is strictly nearer, so at equal `t` the lowest index wins, and the rare hits are
//! merged as [`Hit::keep_first`] orders them: `t`, triangle and barycentrics are bit for bit
//! [`flat.rs`](super::flat)'s, the tree's and [`BruteForce`](crate::BruteForce)'s. The scalar twin is the
//! single-ray query, ray by ray (the default of `FlatKernel`, in `flat_kernel.rs`).

use glam::Vec3;

use super::can_hit;
use super::flat::{Flat, SharedCorners};
use crate::accel::Hit;
use crate::bvh::simd::{
    LaneMask, Lanes, RayLanes, ShearedLanes, shear_point, watertight_sheared_scaled,
};
use crate::ray::Ray;
use crate::triangle::WatertightRay;

/// The most lanes a register holds (AVX-512's sixteen).
const MAX_LANES: usize = 16;

/// Up to [`MAX_LANES`] rays, row by row (lane `k` of each row is ray `k`).
///
/// Lanes without a ray, or whose ray can hit nothing ([`can_hit`]), hold a harmless ray along
/// `+z` with a NaN `t_max`, which admits no hit, and have no bit in `live`.
pub(super) struct RayRows {
    pub(super) origin: [[f32; MAX_LANES]; 3],
    pub(super) direction: [[f32; MAX_LANES]; 3],
    pub(super) t_min: [f32; MAX_LANES],
    t_max: [f32; MAX_LANES],
    /// Bit `k` set where lane `k` has a ray that can hit.
    pub(super) live: u32,
}

impl RayRows {
    /// The rows of `rays` (at most [`MAX_LANES`]).
    #[inline(always)]
    pub(super) fn new(rays: &[Ray]) -> RayRows {
        debug_assert!(rays.len() <= MAX_LANES);
        let mut rows = RayRows {
            origin: [[0.0; MAX_LANES]; 3],
            direction: [[0.0; MAX_LANES], [0.0; MAX_LANES], [1.0; MAX_LANES]],
            t_min: [0.0; MAX_LANES],
            t_max: [f32::NAN; MAX_LANES],
            live: 0,
        };
        for (lane, ray) in rays.iter().enumerate() {
            if !can_hit(ray) {
                continue;
            }
            for axis in 0..3 {
                rows.origin[axis][lane] = ray.origin[axis];
                rows.direction[axis][lane] = ray.direction[axis];
            }
            rows.t_min[lane] = ray.t_min;
            rows.t_max[lane] = ray.t_max;
            rows.live |= 1 << lane;
        }
        rows
    }
}

/// The rays' watertight set-up in registers of `V` ([`WatertightRay`] lane by lane), and the
/// masks that pick each lane's permuted coordinates.
pub(super) struct RayRegisters<V: Lanes> {
    /// The origin's `kx`, `ky`, `kz` coordinates.
    origin: [V; 3],
    /// `shear_x`, `shear_y`, `shear_z`.
    shear: [V; 3],
    pub(super) ray: RayLanes<V>,
    /// Per axis `kx`, `ky`, `kz`: the lanes where it is `x`, and those where it is `y`.
    picks: [[V::Mask; 2]; 3],
}

impl<V: Lanes> RayRegisters<V> {
    /// [`WatertightRay::new`] of every lane, by the same comparisons and operations: the
    /// dominant axis `kz` (ties to the lower axis), `kx` and `ky` after it, swapped where the
    /// ray points along `−kz`, `shear_z = 1/d[kz]`, `shear_x = d[kx]·shear_z`,
    /// `shear_y = d[ky]·shear_z`, and a NaN `t_min` made infinite. Selects instead of the scalar
    /// set-up's branches, which incoherent rays mispredict.
    ///
    /// # Safety
    /// The CPU must support `V`'s instruction set, which holds at most [`MAX_LANES`] floats.
    #[inline(always)]
    pub(super) unsafe fn new(rows: &RayRows) -> Self {
        // No closures: they would not inherit the caller's target features.
        // SAFETY: the caller's guarantee; every row holds `MAX_LANES` floats.
        unsafe {
            let o = [load::<V>(&rows.origin[0]), load(&rows.origin[1]), load(&rows.origin[2])];
            let d =
                [load::<V>(&rows.direction[0]), load(&rows.direction[1]), load(&rows.direction[2])];
            let [ax, ay, az] = [d[0].abs(), d[1].abs(), d[2].abs()];
            // `>=` as "not less than": the same for the live lanes, whose directions have no
            // NaN (`can_hit`).
            let z_is_x = ax.nlt(ay).and(ax.nlt(az));
            let z_is_y = ay.nlt(az).andnot_of(z_is_x);
            let all = ax.eq(ax).or(ax.nlt(ax));
            let z_is_z = all.andnot_of(z_is_x.or(z_is_y));
            let d_z = pick([z_is_x, z_is_y], d);
            let shear_z = V::splat(1.0).div(d_z);
            // kz = x: (kx, ky) = (y, z), y: (z, x), z: (x, y); swapped along −kz.
            let neg = d_z.lt(V::splat(0.0));
            let x_picks = [either::<V>(neg, z_is_z, z_is_y), either::<V>(neg, z_is_x, z_is_z)];
            let y_picks = [either::<V>(neg, z_is_y, z_is_z), either::<V>(neg, z_is_z, z_is_x)];
            let z_picks = [z_is_x, z_is_y];
            let shear_x = pick(x_picks, d).mul(shear_z);
            let shear_y = pick(y_picks, d).mul(shear_z);
            let t_min = load::<V>(&rows.t_min);
            RayRegisters {
                origin: [pick(x_picks, o), pick(y_picks, o), pick(z_picks, o)],
                shear: [shear_x, shear_y, shear_z],
                ray: RayLanes {
                    shear_z,
                    abs_shear: [shear_x.abs(), shear_y.abs()],
                    // A NaN range start admits no hit.
                    t_min: V::select(t_min.eq(t_min), t_min, V::splat(f32::INFINITY)),
                    t_max: load(&rows.t_max),
                },
                picks: [x_picks, y_picks, z_picks],
            }
        }
    }

    /// A corner in each lane's ray frame ([`shear_point`] of its permuted coordinates).
    ///
    /// # Safety
    /// The CPU must support `V`'s instruction set.
    #[inline(always)]
    pub(super) unsafe fn corner(&self, p: Vec3) -> [V; 3] {
        // SAFETY: the caller's guarantee.
        unsafe {
            let xyz = [V::splat(p.x), V::splat(p.y), V::splat(p.z)];
            let permuted =
                [pick(self.picks[0], xyz), pick(self.picks[1], xyz), pick(self.picks[2], xyz)];
            shear_point(self.origin, self.shear, permuted)
        }
    }
}

impl<V: Lanes> RayRegisters<V> {
    /// Each of `corners` in every lane's ray frame: [`corner`](Self::corner)'s coordinates,
    /// then the `kz` one scaled by `shear_z`.
    ///
    /// # Safety
    /// The CPU must support `V`'s instruction set.
    #[inline(always)]
    unsafe fn frame(&self, corners: &[Vec3], frame: &mut [[V; 4]]) {
        for (slot, &p) in frame.iter_mut().zip(corners) {
            // SAFETY: the caller's guarantee.
            unsafe {
                let [x, y, z] = self.corner(p);
                *slot = [x, y, z, self.ray.shear_z.mul(z)];
            }
        }
    }
}

/// A row's lanes in a register.
///
/// # Safety
/// The CPU must support `V`'s instruction set, which holds at most [`MAX_LANES`] floats.
#[inline(always)]
unsafe fn load<V: Lanes>(row: &[f32; MAX_LANES]) -> V {
    // SAFETY: the caller's guarantee.
    unsafe { V::loadu(row.as_ptr()) }
}

/// `swapped` in the lanes of `neg`, `plain` in the others.
///
/// # Safety
/// The CPU must support `V`'s instruction set.
#[inline(always)]
unsafe fn either<V: Lanes>(neg: V::Mask, plain: V::Mask, swapped: V::Mask) -> V::Mask {
    // SAFETY: the caller's guarantee.
    unsafe { plain.andnot_of(neg).or(swapped.and(neg)) }
}

/// Each lane's coordinate of `[x, y, z]` along its axis (`x` where `is_x`, else `y` where
/// `is_y`, else `z`).
///
/// # Safety
/// The CPU must support `V`'s instruction set.
#[inline(always)]
unsafe fn pick<V: Lanes>([is_x, is_y]: [V::Mask; 2], [x, y, z]: [V; 3]) -> V {
    // SAFETY: the caller's guarantee.
    unsafe { V::select(is_x, x, V::select(is_y, y, z)) }
}

/// The closest hit of each ray, `W` rays to a register `V`: exactly
/// [`closest_hit`](super::flat::closest_hit_scalar)'s answers.
///
/// # Safety
/// The CPU must support `V`'s instruction set, and `V` must hold `W` floats (`W <= 16`).
#[inline(always)]
pub(crate) unsafe fn closest_hits<V: Lanes, const W: usize>(
    flat: &Flat,
    rays: &[Ray],
    hits: &mut [Option<Hit>],
) {
    assert_eq!(rays.len(), hits.len(), "one answer per ray");
    debug_assert!(W <= MAX_LANES);
    let shared = flat.shared();
    let mut frame = frame_for::<V>(shared);
    for (rays, hits) in rays.chunks(W).zip(hits.chunks_mut(W)) {
        let rows = RayRows::new(rays);
        // SAFETY: (the whole block) the caller's guarantee; stores write `W` floats into rows
        // of 16; `corners_of` reads `frame` at indices below its length (one slot per corner
        // of `SharedCorners`, whose triangles index only the corners it holds).
        unsafe {
            let registers = RayRegisters::<V>::new(&rows);
            // Each lane's nearest decided hit so far: its `t` is also the lane's limit, so
            // that a triangle no nearer is rejected before the division.
            let mut best_t = registers.ray.t_max;
            let mut best_b1 = V::splat(0.0);
            let mut best_b2 = V::splat(0.0);
            // Triangle indices ride along as float bits: only ever selected, never computed.
            let mut best_id = V::splat(0.0);
            // The lanes with a decided hit.
            let mut found = 0;
            // Hits only the double-precision test could decide, per lane.
            let mut rare = [None; MAX_LANES];
            if rows.live != 0 {
                // Each distinct corner in every lane's ray frame, once: a closed mesh's corner
                // belongs to about six triangles.
                registers.frame(&shared.corners, &mut frame);
                for &(corners, id) in &shared.triangles {
                    let (sheared, scaled) = corners_of(&frame, corners);
                    let ray = RayLanes { t_max: best_t, ..registers.ray };
                    let decided =
                        watertight_sheared_scaled::<V, true>(&sheared, scaled, &ray, rows.live);
                    if decided.hits != 0 {
                        // Hits are strictly nearer than the lane's best (`t < t_max`), so the
                        // earlier triangle keeps a tie; padding lanes are never hit (their
                        // `t_max` is NaN).
                        let nearer = decided.hit_mask;
                        best_t = V::select(nearer, decided.t, best_t);
                        best_b1 = V::select(nearer, decided.b1, best_b1);
                        best_b2 = V::select(nearer, decided.b2, best_b2);
                        best_id = V::select(nearer, V::splat(f32::from_bits(id)), best_id);
                        found |= decided.hits;
                    }
                    let mut undecided = decided.undecided;
                    while undecided != 0 {
                        let lane = undecided.trailing_zeros() as usize;
                        undecided &= undecided - 1;
                        let triangle = shared.triangle(corners);
                        decide_rarely(rays, lane, triangle, id, &mut rare[lane]);
                    }
                }
            }
            let mut t = [0.0f32; MAX_LANES];
            let (mut ids, mut b1, mut b2) =
                ([0.0f32; MAX_LANES], [0.0; MAX_LANES], [0.0; MAX_LANES]);
            best_t.store(t.as_mut_ptr());
            best_id.store(ids.as_mut_ptr());
            best_b1.store(b1.as_mut_ptr());
            best_b2.store(b2.as_mut_ptr());
            for (lane, hit) in hits.iter_mut().enumerate() {
                let mut best = (found & (1 << lane) != 0).then(|| Hit {
                    t: t[lane],
                    triangle: ids[lane].to_bits(),
                    b1: b1[lane],
                    b2: b2[lane],
                });
                if let Some(h) = rare[lane] {
                    Hit::keep_first(h, &mut best);
                }
                *hit = best;
            }
        }
    }
}

/// Whether each ray is blocked, `W` rays to a register `V`: exactly
/// [`occluded`](super::flat::occluded_scalar)'s answers. A group stops once every live lane is
/// blocked.
///
/// # Safety
/// The CPU must support `V`'s instruction set, and `V` must hold `W` floats (`W <= 16`).
#[inline(always)]
pub(crate) unsafe fn occluded<V: Lanes, const W: usize>(
    flat: &Flat,
    rays: &[Ray],
    occluded: &mut [bool],
) {
    assert_eq!(rays.len(), occluded.len(), "one answer per ray");
    debug_assert!(W <= MAX_LANES);
    let shared = flat.shared();
    let mut frame = frame_for::<V>(shared);
    for (rays, occluded) in rays.chunks(W).zip(occluded.chunks_mut(W)) {
        let rows = RayRows::new(rays);
        // The lanes found blocked.
        let mut blocked = 0;
        // SAFETY: (the whole block) the caller's guarantee; `corners_of` reads `frame` at
        // indices below its length (one slot per corner of `SharedCorners`, whose triangles
        // index only the corners it holds).
        unsafe {
            let registers = RayRegisters::<V>::new(&rows);
            if rows.live != 0 {
                registers.frame(&shared.corners, &mut frame);
                for &(corners, _) in &shared.triangles {
                    let open = rows.live & !blocked;
                    if open == 0 {
                        break;
                    }
                    let (sheared, scaled) = corners_of(&frame, corners);
                    let decided = watertight_sheared_scaled::<V, true>(
                        &sheared,
                        scaled,
                        &registers.ray,
                        open,
                    );
                    blocked |= decided.hits;
                    let mut undecided = decided.undecided;
                    while undecided != 0 {
                        let lane = undecided.trailing_zeros() as usize;
                        undecided &= undecided - 1;
                        if blocked_rarely(&rays[lane], shared.triangle(corners)) {
                            blocked |= 1 << lane;
                        }
                    }
                }
            }
        }
        for (lane, occluded) in occluded.iter_mut().enumerate() {
            *occluded = blocked & (1 << lane) != 0;
        }
    }
}

/// A slot per distinct corner of `shared`, for [`RayRegisters::frame`] to fill.
fn frame_for<V: Lanes>(shared: &SharedCorners) -> Vec<[V; 4]> {
    // SAFETY: any bits are a valid register of floats.
    let frame = vec![[unsafe { std::mem::zeroed::<V>() }; 4]; shared.corners.len()];
    // `corners_of` reads the frame at the triangles' corner indices: all below its length.
    debug_assert!(
        shared.triangles.iter().flat_map(|(c, _)| c).all(|&k| (k as usize) < frame.len())
    );
    frame
}

/// A triangle's corners in the lanes' ray frames, as [`watertight_sheared_scaled`] takes them,
/// from the frames of the flat list's distinct corners.
///
/// # Safety
/// Every index of `corners` must be below `frame.len()`.
#[inline(always)]
pub(super) unsafe fn corners_of<V: Lanes>(
    frame: &[[V; 4]],
    corners: [u32; 3],
) -> (ShearedLanes<V>, [V; 3]) {
    // SAFETY: every index is below `frame.len()` (the caller's guarantee).
    let [a, b, c] = corners.map(|k| unsafe { *frame.get_unchecked(k as usize) });
    let sheared =
        ShearedLanes { x: [a[0], b[0], c[0]], y: [a[1], b[1], c[1]], z: [a[2], b[2], c[2]] };
    (sheared, [a[3], b[3], c[3]])
}

/// Whether `ray` hits `triangle` by the double-precision test (an edge function rounded to
/// zero).
#[cold]
#[inline(never)]
pub(super) fn blocked_rarely(ray: &Ray, [v0, v1, v2]: [Vec3; 3]) -> bool {
    WatertightRay::new(ray).intersect(v0, v1, v2, ray.t_max).is_some()
}

/// Lane `lane`'s test of `triangle` in double precision (an edge function rounded to zero),
/// its hit kept in `best` as [`Hit::keep_first`] orders hits.
#[cold]
#[inline(never)]
fn decide_rarely(
    rays: &[Ray],
    lane: usize,
    [v0, v1, v2]: [Vec3; 3],
    id: u32,
    best: &mut Option<Hit>,
) {
    let ray = &rays[lane];
    if let Some(h) = WatertightRay::new(ray).intersect(v0, v1, v2, ray.t_max) {
        Hit { t: h.t, triangle: id, b1: h.b1, b2: h.b2 }.keep_first(best);
    }
}
