//! One ray against a leaf record's triangles (see `bvh/leaf`), by the x86 instruction sets.
//!
//! Every kernel first takes the record's distinct vertices into the ray's frame, once each
//! ([`shear_point`]), then lays the triangles' corners out one triangle per lane from that
//! table, and runs the watertight test on all the triangles at once ([`watertight_sheared`]):
//! - AVX2: the table is one register of 8 per coordinate (two for records of more than 8
//!   vertices), and one `vpermps` per corner and coordinate picks each lane's vertex (from both
//!   halves, blended by the index's bit 3, for more than 8); the whole record (up to 8 triangles)
//!   in one pass;
//! - AVX-512: the same in AVX registers, with the two-table permute `vpermt2ps` of AVX-512 VL
//!   for records of more than 8 vertices (the 16-lane form, a whole 16-triangle record per pass,
//!   was slower on the AVX-512 CPU measured: its 512-bit instructions take a vector port from
//!   the 8-wide node kernel);
//! - SSE2: the table is transformed four vertices at a time into arrays, and each pass of four
//!   triangles reads its corners from them.
//!
//! The scalar twin is [`record_hits_scalar`](super::record_hits_scalar): each value is
//! computed by the same operations in the same order, so the kernels agree with it bit for bit
//! (the tests below check every kernel this machine supports).

use std::arch::x86_64::*;

use super::{RECORD_TRIANGLES, RECORD_VERTICES, Record, RecordHits, TriangleRay};
use crate::bvh::simd::{
    LaneHits, Lanes, RayBroadcast, ShearedLanes, shear_point, watertight_sheared,
};

/// The bits of the first `n` lanes (`n <= 8`).
#[inline(always)]
fn first_lanes(n: usize) -> u32 {
    debug_assert!(n <= 8);
    (1u32 << n) - 1
}

/// Lanes `first..first + 8` of a coordinate row, zero past `nv`.
///
/// # Safety
/// The CPU must support AVX2; `row` points to the record's `nv` floats, `first < nv`.
#[inline(always)]
unsafe fn row_avx2(row: *const f32, first: usize, nv: usize) -> __m256 {
    // SAFETY: the caller's guarantee; the masked load reads only lanes below `nv - first`.
    unsafe {
        let lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
        let mask = _mm256_cmpgt_epi32(_mm256_set1_epi32((nv - first) as i32), lanes);
        _mm256_maskload_ps(row.add(first), mask)
    }
}

/// Corner `c`'s byte indices of the record's (up to 8) triangles, widened to lanes.
///
/// # Safety
/// The CPU must support AVX2.
#[inline(always)]
unsafe fn corners_avx2(record: &Record, c: usize) -> __m256i {
    // SAFETY: the caller's guarantee; `Record::corner_indices` has 16 readable bytes.
    unsafe { _mm256_cvtepu8_epi32(_mm_loadl_epi64(record.corner_indices(c).cast())) }
}

/// Entry `index[k]` (below 16) of a table in two halves, for each lane `k`.
///
/// # Safety
/// The CPU must support AVX2.
#[inline(always)]
unsafe fn pick16_avx2(low: __m256, high: __m256, index: __m256i) -> __m256 {
    // SAFETY: the caller's guarantee.
    unsafe {
        let from_low = _mm256_permutevar8x32_ps(low, index);
        let from_high = _mm256_permutevar8x32_ps(high, index);
        // Bit 3 of the index, moved to the sign bit, picks the high half.
        let high_half = _mm256_castsi256_ps(_mm256_slli_epi32::<28>(index));
        _mm256_blendv_ps(from_low, from_high, high_half)
    }
}

/// Entry `index[k]` (below 16) of a table in two halves, for each lane `k`: one AVX-512 VL
/// two-table permute (`vpermt2ps`).
///
/// # Safety
/// The CPU must support AVX-512 F and VL.
#[inline(always)]
unsafe fn pick16_avx512(low: __m256, high: __m256, index: __m256i) -> __m256 {
    // SAFETY: the caller's guarantee.
    unsafe { _mm256_permutex2var_ps(low, index, high) }
}

/// The record's hits with AVX2, all its triangles in one pass; `TWO_TABLE` picks the corners
/// of records of more than 8 vertices with AVX-512 VL's two-table permute.
///
/// Written without closures, as every kernel here: a closure does not inherit the target
/// features of the function it is inlined into, and one left out of line passes its vectors
/// through memory and calls every intrinsic, at half the speed.
///
/// # Safety
/// The CPU must support AVX2, and AVX-512 F and VL if `TWO_TABLE`.
#[inline(always)]
pub(crate) unsafe fn record_hits_avx2<const TWO_TABLE: bool>(
    ray: &TriangleRay<RayBroadcast<__m256>>,
    record: &Record,
    t_max: f32,
) -> RecordHits {
    let r = &ray.lanes;
    let [kx, ky, kz] = r.k;
    let (nv, nt) = (record.vertices(), record.triangles());
    // SAFETY: the caller guarantees the instruction sets; the loads as `row_avx2` and
    // `corners_avx2` require (`8 < nv` where the second halves are loaded); the stores write
    // the 8 lanes of arrays of 8.
    unsafe {
        let (px, py, pz) = (record.coordinates(kx), record.coordinates(ky), record.coordinates(kz));
        let low = [row_avx2(px, 0, nv), row_avx2(py, 0, nv), row_avx2(pz, 0, nv)];
        let [lx, ly, lz] = shear_point(r.origin, r.shear, low);
        let a = corners_avx2(record, 0);
        let b = corners_avx2(record, 1);
        let c = corners_avx2(record, 2);
        let sheared = if nv <= 8 {
            // Most records (a leaf of four to eight triangles of a mesh has six to ten
            // vertices): one permute per corner and coordinate.
            ShearedLanes {
                x: [
                    _mm256_permutevar8x32_ps(lx, a),
                    _mm256_permutevar8x32_ps(lx, b),
                    _mm256_permutevar8x32_ps(lx, c),
                ],
                y: [
                    _mm256_permutevar8x32_ps(ly, a),
                    _mm256_permutevar8x32_ps(ly, b),
                    _mm256_permutevar8x32_ps(ly, c),
                ],
                z: [
                    _mm256_permutevar8x32_ps(lz, a),
                    _mm256_permutevar8x32_ps(lz, b),
                    _mm256_permutevar8x32_ps(lz, c),
                ],
            }
        } else {
            let high = [row_avx2(px, 8, nv), row_avx2(py, 8, nv), row_avx2(pz, 8, nv)];
            let [hx, hy, hz] = shear_point(r.origin, r.shear, high);
            if TWO_TABLE {
                ShearedLanes {
                    x: [
                        pick16_avx512(lx, hx, a),
                        pick16_avx512(lx, hx, b),
                        pick16_avx512(lx, hx, c),
                    ],
                    y: [
                        pick16_avx512(ly, hy, a),
                        pick16_avx512(ly, hy, b),
                        pick16_avx512(ly, hy, c),
                    ],
                    z: [
                        pick16_avx512(lz, hz, a),
                        pick16_avx512(lz, hz, b),
                        pick16_avx512(lz, hz, c),
                    ],
                }
            } else {
                ShearedLanes {
                    x: [pick16_avx2(lx, hx, a), pick16_avx2(lx, hx, b), pick16_avx2(lx, hx, c)],
                    y: [pick16_avx2(ly, hy, a), pick16_avx2(ly, hy, b), pick16_avx2(ly, hy, c)],
                    z: [pick16_avx2(lz, hz, a), pick16_avx2(lz, hz, b), pick16_avx2(lz, hz, c)],
                }
            }
        };
        let decided =
            watertight_sheared::<__m256, true>(&sheared, &r.lanes(t_max), first_lanes(nt));
        let mut out = RecordHits::default();
        merge(&mut out, &decided, 0);
        out
    }
}

/// Adds a pass's decisions for triangles `first..` (as many as `V` has lanes) to `out`.
///
/// # Safety
/// The CPU must support `V`'s instruction set; `first` plus `V`'s lanes must not pass
/// [`RECORD_TRIANGLES`].
#[inline(always)]
unsafe fn merge<V: Lanes>(out: &mut RecordHits, decided: &LaneHits<V>, first: usize) {
    out.hits |= decided.hits << first;
    out.undecided |= decided.undecided << first;
    if decided.hits != 0 {
        // SAFETY: the caller's guarantee: each store writes within the arrays of 8.
        unsafe {
            decided.t.store(out.t.as_mut_ptr().add(first));
            decided.b1.store(out.b1.as_mut_ptr().add(first));
            decided.b2.store(out.b2.as_mut_ptr().add(first));
        }
    }
}

/// Four lanes of a row of the table, at the indices `bytes[0..4]` (taken modulo 16).
///
/// # Safety
/// Four bytes must be readable from `bytes`.
#[inline(always)]
unsafe fn pick4_sse(row: &[f32; RECORD_VERTICES], bytes: *const u8) -> __m128 {
    // SAFETY: the caller's guarantee; SSE2 is part of x86-64.
    unsafe {
        let at = |k: usize| row[*bytes.add(k) as usize % RECORD_VERTICES];
        _mm_setr_ps(at(0), at(1), at(2), at(3))
    }
}

/// The record's hits with SSE2 (every x86-64): four triangles per pass.
#[inline(always)]
pub(crate) fn record_hits_sse(
    ray: &TriangleRay<RayBroadcast<__m128>>,
    record: &Record,
    t_max: f32,
) -> RecordHits {
    let r = &ray.lanes;
    let [kx, ky, kz] = r.k;
    let (nv, nt) = (record.vertices(), record.triangles());
    let mut out = RecordHits::default();
    // The table, zero past `nv`, then in the ray's frame.
    let mut table = [[0.0f32; RECORD_VERTICES]; 3];
    for (row, axis) in table.iter_mut().zip([kx, ky, kz]) {
        // SAFETY: `coordinates` points to the record's `nv` floats of the axis.
        let coordinates = unsafe { std::slice::from_raw_parts(record.coordinates(axis), nv) };
        row[..nv].copy_from_slice(coordinates);
    }
    // SAFETY: SSE2 is part of x86-64; loads and stores stay inside the arrays of 16 floats
    // (`first + 4 <= 16`) and of 8 (`first + 4 <= 8`); the index reads stay within the 16
    // bytes `Record::corner_indices` guarantees readable.
    unsafe {
        let mut first = 0;
        while first < nv {
            let x = __m128::loadu(table[0].as_ptr().add(first));
            let y = __m128::loadu(table[1].as_ptr().add(first));
            let z = __m128::loadu(table[2].as_ptr().add(first));
            let [x, y, z] = shear_point(r.origin, r.shear, [x, y, z]);
            x.store(table[0].as_mut_ptr().add(first));
            y.store(table[1].as_mut_ptr().add(first));
            z.store(table[2].as_mut_ptr().add(first));
            first += 4;
        }
        let ray_lanes = r.lanes(t_max);
        let mut first = 0;
        while first < nt {
            let a = record.corner_indices(0).add(first);
            let b = record.corner_indices(1).add(first);
            let c = record.corner_indices(2).add(first);
            let [tx, ty, tz] = &table;
            let sheared = ShearedLanes {
                x: [pick4_sse(tx, a), pick4_sse(tx, b), pick4_sse(tx, c)],
                y: [pick4_sse(ty, a), pick4_sse(ty, b), pick4_sse(ty, c)],
                z: [pick4_sse(tz, a), pick4_sse(tz, b), pick4_sse(tz, c)],
            };
            let lanes = first_lanes((nt - first).min(4));
            let decided = watertight_sheared::<__m128, true>(&sheared, &ray_lanes, lanes);
            merge(&mut out, &decided, first);
            first += 4;
        }
    }
    out
}

const _: () = assert!(RECORD_TRIANGLES == 8 && RECORD_VERTICES == 16);

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::bvh::Isa;
    use crate::bvh::leaf::{Leaves, record_hits_scalar};
    use crate::ray::Ray;
    use crate::triangle::WatertightRay;

    fn sse(ray: &WatertightRay, record: &Record, t_max: f32) -> RecordHits {
        // SAFETY: SSE2 is part of x86-64.
        let lanes = unsafe { RayBroadcast::<__m128>::new(ray) };
        record_hits_sse(&TriangleRay { ray: *ray, lanes }, record, t_max)
    }

    #[target_feature(enable = "avx2")]
    fn avx2(ray: &WatertightRay, record: &Record, t_max: f32) -> RecordHits {
        // SAFETY: compiled with AVX2, called only after detection.
        let lanes = unsafe { RayBroadcast::<__m256>::new(ray) };
        // SAFETY: as above.
        unsafe { record_hits_avx2::<false>(&TriangleRay { ray: *ray, lanes }, record, t_max) }
    }

    #[target_feature(enable = "avx2,avx512f,avx512vl")]
    fn avx512(ray: &WatertightRay, record: &Record, t_max: f32) -> RecordHits {
        // SAFETY: compiled with AVX-512 F and VL, called only after detection.
        let lanes = unsafe { RayBroadcast::<__m256>::new(ray) };
        // SAFETY: as above.
        unsafe { record_hits_avx2::<true>(&TriangleRay { ray: *ray, lanes }, record, t_max) }
    }

    /// Every record kernel this CPU supports decides every triangle as the scalar test does,
    /// with the same `t` and barycentrics bit for bit; the triangles it leaves undecided are
    /// those the scalar test must recompute in double precision. Records of 1 to 8 triangles
    /// over 3 to 16 shared vertices, half of them on a coarse grid (edge functions exactly
    /// zero), rays at vertices, edges and interiors, from near the surface and with `t_min`.
    #[test]
    fn record_kernels_agree_with_their_scalar_twin() {
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let vec = |next: &mut dyn FnMut() -> f32| Vec3::new(next(), next(), next()) * 4.0 - 2.0;
        type Kernel = fn(&WatertightRay, &Record, f32) -> RecordHits;
        let kernels: [(&str, Isa, Kernel); 3] = [
            ("sse2", Isa::Sse2, sse),
            // SAFETY: (both) called only where `is_supported` said so.
            ("avx2", Isa::Avx2, |r, c, t| unsafe { avx2(r, c, t) }),
            // SAFETY: as above.
            ("avx512", Isa::Avx512, |r, c, t| unsafe { avx512(r, c, t) }),
        ];
        for (name, isa, _) in &kernels {
            if !isa.is_supported() {
                eprintln!("note: this CPU lacks {name}: its record kernel is not tested here");
            }
        }
        let (mut decided_hits, mut undecided) = ([0usize; 3], [0usize; 3]);
        for case in 0..6000 {
            let grid = case % 2 == 0;
            let vertices = 3 + case % 14;
            let pool: Vec<Vec3> = (0..vertices)
                .map(|_| if grid { (vec(&mut next) * 2.0).round() / 2.0 } else { vec(&mut next) })
                .collect();
            let count = 1 + (case * 7) % 8;
            let triangles: Vec<(u32, [Vec3; 3])> = (0..count * 4)
                .map(|k| {
                    let pick = |j: usize| pool[(k * 5 + j * (1 + k % 3) + case) % vertices];
                    [pick(0), pick(1), pick(2)]
                })
                .filter(|&t| !crate::triangle::is_degenerate(t))
                .take(count)
                .enumerate()
                .map(|(i, t)| (i as u32, t))
                .collect();
            if triangles.is_empty() {
                continue;
            }
            let mut leaves = Leaves::default();
            let offset = leaves.push_leaf(&triangles);
            let record = leaves.record(offset);
            assert!(record.next().is_none(), "at most 16 vertices fit in one record");
            let [a, b, c] = triangles[case % triangles.len()].1;
            let (u, v) = (next(), next());
            let target = match case % 3 {
                0 => a,
                1 => a.lerp(b, u),
                _ => a.lerp(b, u).lerp(c, v),
            };
            let origin = match case % 4 {
                3 => target + (vec(&mut next) * 0.5) * [1e-5, 1e-6, 1e-7][case % 3],
                _ => vec(&mut next) * 2.0,
            };
            if origin == target {
                continue;
            }
            let mut ray = Ray::new(origin, target - origin);
            ray.t_min = if case % 5 == 0 { 0.5 * next() } else { 0.0 };
            let ray = WatertightRay::new(&ray);
            for t_max in [f32::INFINITY, 1.0, 0.5 + next()] {
                let scalar = record_hits_scalar(&ray, &record, t_max);
                for (k, (name, isa, kernel)) in kernels.iter().enumerate() {
                    if !isa.is_supported() {
                        continue;
                    }
                    let simd = kernel(&ray, &record, t_max);
                    assert_eq!(simd.hits & simd.undecided, 0);
                    let mut resolved = simd.hits;
                    for t in 0..record.triangles() {
                        let bit = 1 << t;
                        if simd.undecided & bit != 0 {
                            undecided[k] += 1;
                            let [v0, v1, v2] = record.triangle(t);
                            if ray.intersect(v0, v1, v2, t_max).is_some() {
                                resolved |= bit;
                            }
                        }
                        if simd.hits & bit != 0 {
                            decided_hits[k] += 1;
                            let same = |x: f32, y: f32| x.to_bits() == y.to_bits();
                            assert!(
                                same(simd.t[t], scalar.t[t])
                                    && same(simd.b1[t], scalar.b1[t])
                                    && same(simd.b2[t], scalar.b2[t]),
                                "{name}, case {case}: {simd:?} vs {scalar:?}"
                            );
                        }
                    }
                    assert_eq!(resolved, scalar.hits, "{name}, case {case}, t_max {t_max}");
                }
            }
        }
        for (k, (name, isa, _)) in kernels.iter().enumerate() {
            if isa.is_supported() {
                assert!(
                    decided_hits[k] > 5000 && undecided[k] > 500,
                    "{name}: {} hits, {} undecided",
                    decided_hits[k],
                    undecided[k]
                );
            }
        }
    }
}
