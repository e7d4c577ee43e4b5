//! The top level of a scene with few instances as rows: one ray against every instance's box in
//! one straight loop, sixteen boxes per instruction on AVX-512.
//!
//! The binary top level ([`TwoLevel::walk`](super::TwoLevel)) tests a ray's boxes one at a time,
//! two per inner node, each test a chain of scalar slab arithmetic and branches on its outcome.
//! On a scene of 19 instances (the 18 glTF boxes of `tests/data/mitsuba-gltf`, and its floor and
//! light as the world's) a bounce ray made about ten such tests to reach 1.5 instances, and the walk was a quarter of the path
//! tracer's time (`perf record`). Where the instances are few ([`ROWS_LIMIT`]), [`TopRows`]
//! keeps their boxes as arrays (one per coordinate, their margins beside them) and tests the ray
//! against all of them at once; the instances it enters are then visited nearest entry first,
//! each checked against the best hit found so far, exactly as the tree checks its leaves.
//!
//! The arithmetic is [`RayBoxTest::enter`]'s on the grown box (`grown(bounds, margin.pad(|o|∞))`),
//! operation for operation, so an instance is entered exactly when the tree's leaf test enters
//! it (`tests` compares them on every instruction set, bit for bit). The far distance is kept
//! before the ray's limit shrinks: `min` is exact and `+ pad` rounds monotonically, so
//! `(far ∧ t) + pad = (far + pad) ∧ (t + pad)` and the check at visit time is the tree's test
//! at that time. Which instances are visited, and in which order, changes no answer: every
//! instance that may hold a hit up to the best one is visited either way, and ties at equal `t`
//! go to the lowest triangle index as always (`tests/instancing.rs`).

use super::top::{Margin, Placed};
use crate::bvh::{FAR_SCALE, RayBoxTest, SLAB_PAD};
use crate::cpu::Isa;

/// The most instances kept as rows (one bit each in a mask); a scene with more walks the tree.
/// Sixty-four boxes are four AVX-512 steps; the tree tested about ten boxes, one at a time, to
/// find a ray's instances among eighteen.
pub(super) const ROWS_LIMIT: usize = 64;

/// Lanes per step of the loop: one AVX-512 register of `f32`.
const LANES: usize = 16;

/// The instances' boxes and margins as rows, in the order of [`TwoLevel`](super::TwoLevel)'s
/// `placed`, padded to whole steps with boxes that no ray enters.
pub(super) struct TopRows {
    /// Per axis, the boxes' low and high planes.
    low: [Vec<[f32; LANES]>; 3],
    high: [Vec<[f32; LANES]>; 3],
    /// The margins' `scale` and `reach` ([`Margin::pad`]).
    scale: Vec<[f32; LANES]>,
    reach: Vec<[f32; LANES]>,
    /// How many are real.
    count: usize,
    isa: Isa,
}

/// What one ray's test gives each row: where it enters the grown box (less the slab pad), its
/// far distance within the ray's own limit (before the pad) and the pad.
pub(super) struct Entries {
    pub near: [f32; ROWS_LIMIT],
    pub far: [f32; ROWS_LIMIT],
    pub pad: [f32; ROWS_LIMIT],
}

impl Entries {
    pub fn new() -> Entries {
        Entries { near: [0.0; ROWS_LIMIT], far: [0.0; ROWS_LIMIT], pad: [0.0; ROWS_LIMIT] }
    }

    /// Whether row `k` is entered while the ray's limit is `t_max` (at most the limit the rows
    /// were tested with): [`RayBoxTest::enter`]'s `near − pad ≤ min(far, t_max) + pad`.
    #[inline(always)]
    pub fn enters(&self, k: usize, t_max: f32) -> bool {
        self.near[k] <= self.far[k].min(t_max) + self.pad[k]
    }
}

impl TopRows {
    /// The rows of `placed`, tested with `isa`'s instructions; `None` for more than
    /// [`ROWS_LIMIT`] instances.
    pub fn new(placed: &[Placed], isa: Isa) -> Option<TopRows> {
        if placed.len() > ROWS_LIMIT {
            return None;
        }
        let steps = placed.len().div_ceil(LANES);
        // No ray enters an empty box: its near plane is at +∞ or its pad is ∞ − ∞ = NaN.
        let empty = [f32::INFINITY; LANES];
        let mut rows = TopRows {
            low: std::array::from_fn(|_| vec![empty; steps]),
            high: std::array::from_fn(|_| vec![[f32::NEG_INFINITY; LANES]; steps]),
            scale: vec![[0.0; LANES]; steps],
            reach: vec![[0.0; LANES]; steps],
            count: placed.len(),
            isa,
        };
        for (k, p) in placed.iter().enumerate() {
            let (step, lane) = (k / LANES, k % LANES);
            for axis in 0..3 {
                rows.low[axis][step][lane] = p.bounds.min[axis];
                rows.high[axis][step][lane] = p.bounds.max[axis];
            }
            rows.scale[step][lane] = p.margin.scale;
            rows.reach[step][lane] = p.margin.reach;
        }
        Some(rows)
    }

    /// The mask of the real rows: padding lanes never enter (their boxes are empty), but the
    /// kernels' masks are kept to the rows there are.
    #[inline(always)]
    fn real(&self) -> u64 {
        u64::MAX >> (ROWS_LIMIT - self.count.max(1))
    }

    /// Tests the ray of `test` (`size` = its `|o|∞`) against every row within `t_max`: fills
    /// `entries` and returns the mask of the rows it enters.
    #[inline]
    pub fn enter(&self, test: &RayBoxTest, size: f32, t_max: f32, entries: &mut Entries) -> u64 {
        match self.isa {
            // SAFETY: `Isa::detect` picks a set only where the CPU has it (the tests pick the
            // sets this CPU supports).
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => unsafe { enter_avx512(self, test, size, t_max, entries) },
            // SAFETY: as above.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => unsafe { enter_avx2(self, test, size, t_max, entries) },
            _ => enter_rows(self, test, size, t_max, entries),
        }
    }
}

/// The rows' test: a plain loop over the lanes that the compiler turns into vector code where
/// it is compiled with vector instructions (the wrappers below); its portable compilation is
/// the twin. Per lane, [`RayBoxTest::enter`] on `grown(bounds, margin.pad(size))`.
#[inline(always)]
fn enter_rows(
    rows: &TopRows,
    test: &RayBoxTest,
    size: f32,
    t_max: f32,
    entries: &mut Entries,
) -> u64 {
    let mut mask = 0u64;
    for step in 0..rows.scale.len() {
        let (scale, reach) = (&rows.scale[step], &rows.reach[step]);
        // The margin grows each box by `pad`; the near plane is the low one moved down (`-pad`)
        // or, for a negative direction, the high one moved up (`+pad`): `± pad` exactly.
        let mut grow = [0.0f32; LANES];
        for k in 0..LANES {
            grow[k] = Margin { scale: scale[k], reach: reach[k] }.pad(size);
        }
        let mut t_near = [[0.0f32; LANES]; 3];
        let mut t_far = [[0.0f32; LANES]; 3];
        for axis in 0..3 {
            let (low, high) = (&rows.low[axis][step], &rows.high[axis][step]);
            let (o, inv) = (test.origin[axis], test.inv_direction[axis]);
            let (near_rows, far_rows, sign) =
                if test.negative[axis] { (high, low, 1.0) } else { (low, high, -1.0) };
            for k in 0..LANES {
                let pad = sign * grow[k];
                t_near[axis][k] = (near_rows[k] + pad - o) * inv;
                t_far[axis][k] = (far_rows[k] - pad - o) * inv;
            }
        }
        let dominant = test.dominant_axis;
        let base = step * LANES;
        let near = &mut entries.near[base..base + LANES];
        let far = &mut entries.far[base..base + LANES];
        let pads = &mut entries.pad[base..base + LANES];
        for k in 0..LANES {
            // `f32::max`/`min` return the other operand when one is NaN, as in `enter`.
            let mut n = test.t_min;
            let mut f = t_max;
            for axis in 0..3 {
                n = t_near[axis][k].max(n);
                f = (t_far[axis][k] * FAR_SCALE).min(f);
            }
            let pad = t_near[dominant][k].abs().max(t_far[dominant][k].abs()) * SLAB_PAD;
            near[k] = n - pad;
            far[k] = f;
            pads[k] = pad;
        }
        let mut entered = 0u16;
        for k in 0..LANES {
            entered |= u16::from(near[k] <= far[k] + pads[k]) << k;
        }
        mask |= u64::from(entered) << base;
    }
    mask & rows.real()
}

/// [`enter_rows`] in AVX-512 instructions, sixteen rows a step: the same operations in the same
/// order. `_mm512_max_ps`/`min_ps` return their second operand where either is NaN, so the
/// operands are placed (and a blend added where the second may be NaN) to give `f32::max`'s and
/// `min`'s NaN-ignoring answers; a zero's sign may differ, which no comparison sees.
///
/// # Safety
/// The CPU must support AVX2 and AVX-512 F and VL ([`Isa::Avx512`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f,avx512vl")]
unsafe fn enter_avx512(
    rows: &TopRows,
    test: &RayBoxTest,
    size: f32,
    t_max: f32,
    entries: &mut Entries,
) -> u64 {
    use std::arch::x86_64::*;
    let nan = |x: __m512| _mm512_cmp_ps_mask::<_CMP_UNORD_Q>(x, x);
    // `f32::max(a, b)`/`min(a, b)` where `b` may be NaN.
    let max = |a: __m512, b: __m512| _mm512_mask_blend_ps(nan(b), _mm512_max_ps(a, b), a);
    let min = |a: __m512, b: __m512| _mm512_mask_blend_ps(nan(b), _mm512_min_ps(a, b), a);
    let abs = |x: __m512| _mm512_abs_ps(x);
    let size = _mm512_set1_ps(size);
    let far_scale = _mm512_set1_ps(FAR_SCALE);
    let slab_pad = _mm512_set1_ps(SLAB_PAD);
    let mut mask = 0u64;
    for step in 0..rows.scale.len() {
        let load = |row: &[f32; LANES]| {
            // SAFETY: sixteen `f32` of a `[f32; 16]`.
            unsafe { _mm512_loadu_ps(row.as_ptr()) }
        };
        let grow =
            _mm512_mul_ps(load(&rows.scale[step]), _mm512_add_ps(size, load(&rows.reach[step])));
        let mut near = _mm512_set1_ps(test.t_min);
        let mut far = _mm512_set1_ps(t_max);
        let mut extent = _mm512_setzero_ps();
        for axis in 0..3 {
            let (low, high) = (load(&rows.low[axis][step]), load(&rows.high[axis][step]));
            let (o, inv) =
                (_mm512_set1_ps(test.origin[axis]), _mm512_set1_ps(test.inv_direction[axis]));
            let (near_rows, far_rows, sign) =
                if test.negative[axis] { (high, low, 1.0) } else { (low, high, -1.0) };
            let pad = _mm512_mul_ps(_mm512_set1_ps(sign), grow);
            let t_near = _mm512_mul_ps(_mm512_sub_ps(_mm512_add_ps(near_rows, pad), o), inv);
            let t_far = _mm512_mul_ps(_mm512_sub_ps(_mm512_sub_ps(far_rows, pad), o), inv);
            // `near` is never NaN (it starts at `t_min ≥ 0`): `max_ps(t_near, near)` keeps it
            // where `t_near` is.
            near = _mm512_max_ps(t_near, near);
            far = min(_mm512_mul_ps(t_far, far_scale), far);
            if axis == test.dominant_axis {
                extent = max(abs(t_near), abs(t_far));
            }
        }
        let pad = _mm512_mul_ps(extent, slab_pad);
        let near = _mm512_sub_ps(near, pad);
        let base = step * LANES;
        // SAFETY: the sixteen entries from `step · 16`, below `ROWS_LIMIT` because
        // `step < scale.len() ≤ ROWS_LIMIT / 16`.
        unsafe {
            _mm512_storeu_ps(entries.near.as_mut_ptr().add(base), near);
            _mm512_storeu_ps(entries.far.as_mut_ptr().add(base), far);
            _mm512_storeu_ps(entries.pad.as_mut_ptr().add(base), pad);
        }
        let entered = _mm512_cmp_ps_mask::<_CMP_LE_OQ>(near, _mm512_add_ps(far, pad));
        mask |= u64::from(entered) << base;
    }
    mask & rows.real()
}

/// [`enter_rows`] compiled for AVX2.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn enter_avx2(
    rows: &TopRows,
    test: &RayBoxTest,
    size: f32,
    t_max: f32,
    entries: &mut Entries,
) -> u64 {
    enter_rows(rows, test, size, t_max, entries)
}

#[cfg(test)]
mod tests {
    use super::super::tests_uniform as uniform;
    use glam::Vec3;

    use super::*;
    use crate::bvh::Bounds;
    use crate::ray::Ray;

    /// The tree's leaf test of `placed` for the ray of `test` within `t_max`.
    fn tree_enters(test: &RayBoxTest, placed: &Placed, t_max: f32) -> bool {
        let pad = placed.margin.pad(test.origin.abs().max_element());
        let grown = Bounds {
            min: placed.bounds.min - Vec3::splat(pad),
            max: placed.bounds.max + Vec3::splat(pad),
        };
        test.enter(&grown, t_max).is_some()
    }

    /// On every instruction set this CPU has (none is skipped here: `Isa::ALL` filtered by
    /// `is_supported`, which on this machine is all four), the rows' mask is the tree's leaf test
    /// of each box, and `Entries::enters` at a smaller limit is the tree's test at that limit:
    /// over hostile rays (axis-parallel directions with signed zeros, origins on the boxes'
    /// planes, rays aimed just past corners, empty, reversed and NaN ranges) and boxes with and
    /// without margins, from one row to sixty-four.
    #[test]
    fn the_rows_enter_where_the_tree_enters() {
        let isas: Vec<Isa> = Isa::ALL.into_iter().filter(|isa| isa.is_supported()).collect();
        let mut state = 3u64;
        let mut agreed = (0u32, 0u32);
        for round in 0..300 {
            let mut r = || uniform(&mut state);
            let count = 1 + (r() * ROWS_LIMIT as f32) as usize % ROWS_LIMIT;
            let placed: Vec<Placed> = (0..count)
                .map(|k| {
                    let min = Vec3::new(r() * 4.0 - 3.0, r() * 4.0 - 3.0, r() * 4.0 - 3.0);
                    let size = if k % 9 == 4 {
                        Vec3::new(r(), 0.0, r()) // flat
                    } else {
                        Vec3::new(r(), r(), r()) * 1.5
                    };
                    let margin = if (round + k) % 3 == 0 {
                        Margin::default()
                    } else {
                        Margin { scale: 1e-3 * r(), reach: 10.0 * r() }
                    };
                    let bounds = Bounds { min, max: min + size * 2.0 };
                    Placed { bottom: 0, first: 0, placement: None, bounds, margin }
                })
                .collect();
            // On a plane, a box without margin (its grown plane is its own): 0 · ∞ is NaN.
            let on_plane = round % 5 == 0;
            let target = match (0..count).find(|k| (round + k) % 3 == 0) {
                Some(k) if on_plane => k,
                _ => (r() * count as f32) as usize % count,
            };
            let target = &placed[target].bounds;
            let mut origin = Vec3::new(r() * 8.0 - 4.0, r() * 8.0 - 4.0, r() * 8.0 - 4.0);
            if on_plane {
                origin.y = target.max.y;
            }
            let centre = target.centroid();
            let aim = match round % 4 {
                0 => target.max + (target.max - centre) * 2e-6,
                3 => origin + Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5),
                _ => target.min + (target.max - target.min) * Vec3::new(r(), r(), r()),
            };
            let mut direction = aim - origin;
            match round % 7 {
                0 => direction.x = 0.0,
                1 => direction = Vec3::new(-0.0, direction.y, 0.0),
                2 => direction.z = -0.0,
                _ => {}
            }
            if on_plane && round % 3 != 2 {
                // Along the plane: the slab's distances are (0 · ±∞) = NaN.
                direction.y = if round % 2 == 0 { 0.0 } else { -0.0 };
            }
            if direction == Vec3::ZERO {
                direction = Vec3::X;
            }
            let mut ray = Ray::new(origin, direction);
            ray.t_min = if round % 4 == 1 { r() * 2.0 } else { 0.0 };
            let t_max = match round % 6 {
                0 => f32::INFINITY,
                1 => 0.0,
                2 => f32::NAN,
                3 => f32::NEG_INFINITY,
                _ => r() * 8.0,
            };
            let test = RayBoxTest::new(&ray);
            let size = ray.origin.abs().max_element();
            // Later limits, as the walk lowers them: at most `t_max` (any, for a NaN `t_max`).
            let later = [t_max, 0.5 * r() * 8.0, 0.0, f32::NAN, f32::INFINITY]
                .map(|t| if t_max.is_nan() || t <= t_max { t } else { t_max });
            for &isa in &isas {
                let rows = TopRows::new(&placed, isa).expect("at most 64 rows");
                let mut entries = Entries::new();
                let mask = rows.enter(&test, size, t_max, &mut entries);
                assert_eq!(mask >> count.min(63) >> (count / 64), 0, "no bit beyond the rows");
                for (k, p) in placed.iter().enumerate() {
                    let expected = tree_enters(&test, p, t_max);
                    assert_eq!(mask >> k & 1 == 1, expected, "{isa:?} round {round} row {k}");
                    agreed.0 += u32::from(expected);
                    agreed.1 += 1;
                    if expected {
                        for &t in &later {
                            assert_eq!(
                                entries.enters(k, t),
                                tree_enters(&test, p, t),
                                "{isa:?} round {round} row {k} at {t}"
                            );
                        }
                    }
                }
            }
        }
        // Both answers occur often.
        assert!(agreed.0 > agreed.1 / 20 && agreed.0 < agreed.1 * 9 / 10, "{agreed:?}");
    }
}
