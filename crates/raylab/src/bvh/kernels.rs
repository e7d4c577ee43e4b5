//! Ray/box tests of one ray against the eight children of a [`WideNode`].
//!
//! Each kernel computes, for every child, the same values as [`RayBoxTest::enter`] (the scalar
//! twin) in the same order of operations: per axis `tn = (near plane − o)·(1/d)` folded into
//! `near = max(tn, near)`, and `tf = ((far plane − o)·(1/d))·(1 + 2γ₃)` into `far = min(tf, far)`,
//! then, both moved out by `SLAB_PAD` times the box's reach on the ray's dominant axis,
//! `near <= far`. x86's `maxps`/`minps` return their second operand when the first is NaN,
//! which is how the scalar `f32::max`/`min` treat a NaN `tn`/`tf` (a ray inside a box's face
//! plane): the tests in `bvh/tests.rs` check that all kernels agree bit for bit.

use super::bounds::{FAR_SCALE, RayBoxTest, SLAB_PAD};
use super::build::BLOCK;
use super::wide::{WIDTH, WideNode};
use crate::triangle::{TriangleBlock, WatertightRay};

/// Which children a ray enters, and where.
pub(crate) trait NodeKernel {
    /// The ray, prepared for this kernel once per ray.
    type Ray: Copy;

    /// Prepares a ray.
    ///
    /// # Safety
    /// As for [`enter`](Self::enter).
    unsafe fn prepare(ray: &RayBoxTest) -> Self::Ray;

    /// The mask of children entered within `[t_min, t_limit]` (bit `k` for child `k`), and each
    /// child's entry distance (meaningful only where the bit is set).
    ///
    /// # Safety
    /// The CPU must support the kernel's instruction set (checked once when a BVH picks it).
    unsafe fn enter(node: &WideNode, ray: &Self::Ray, t_limit: f32) -> (u32, [f32; WIDTH]);

    /// The hits of a ray on the triangles of `block` below `t_max`, as
    /// [`WatertightRay::intersect`] decides them. The blocks must hold no zero-area triangles
    /// (the BVH leaves them out). The scalar twin is [`block_hits_scalar`].
    ///
    /// # Safety
    /// As for [`enter`](Self::enter).
    #[inline(always)]
    unsafe fn block_hits(
        ray: &WatertightRay,
        block: &TriangleBlock<BLOCK>,
        t_max: f32,
    ) -> BlockHits {
        block_hits_scalar(ray, block, t_max)
    }
}

/// What a block test decides for each of its four lanes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct BlockHits {
    /// Lanes hit, with their `t` and barycentrics below, exactly as `intersect` computes them.
    pub hits: u32,
    /// Lanes that only [`WatertightRay::intersect`] can decide (an edge function rounded to zero
    /// and must be recomputed in double precision).
    pub undecided: u32,
    /// Ray parameter per lane (meaningful where `hits` has the bit).
    pub t: [f32; BLOCK],
    /// Barycentric weight of `v1` per lane.
    pub b1: [f32; BLOCK],
    /// Barycentric weight of `v2` per lane.
    pub b2: [f32; BLOCK],
}

/// The scalar twin of the block kernels: the batched pre-test, then the full scalar test on each
/// candidate. Decides every lane.
#[inline(always)]
pub(crate) fn block_hits_scalar(
    ray: &WatertightRay,
    block: &TriangleBlock<BLOCK>,
    t_max: f32,
) -> BlockHits {
    let mut out = BlockHits::default();
    let mut candidates = ray.block_candidates(block, t_max);
    while candidates != 0 {
        let lane = candidates.trailing_zeros() as usize;
        candidates &= candidates - 1;
        let [v0, v1, v2] = block.triangle(lane);
        if let Some(h) = ray.intersect(v0, v1, v2, t_max) {
            out.hits |= 1 << lane;
            out.t[lane] = h.t;
            out.b1[lane] = h.b1;
            out.b2[lane] = h.b2;
        }
    }
    out
}

/// Plane rows of the near and far planes per axis: the box's min for a positive direction.
#[inline(always)]
fn plane_rows(ray: &RayBoxTest) -> ([usize; 3], [usize; 3]) {
    let near = [0, 1, 2].map(|axis| if ray.negative[axis] { 3 + axis } else { axis });
    let far = [0, 1, 2].map(|axis| if ray.negative[axis] { axis } else { 3 + axis });
    (near, far)
}

/// The scalar twin: [`RayBoxTest::enter`] per child.
pub(crate) struct Scalar;

impl NodeKernel for Scalar {
    type Ray = RayBoxTest;

    #[inline(always)]
    unsafe fn prepare(ray: &RayBoxTest) -> RayBoxTest {
        *ray
    }

    #[inline(always)]
    unsafe fn enter(node: &WideNode, ray: &RayBoxTest, t_limit: f32) -> (u32, [f32; WIDTH]) {
        let mut mask = 0;
        let mut near = [0.0; WIDTH];
        for (k, slot) in near.iter_mut().enumerate() {
            if let Some(t) = ray.enter(&node.bounds(k), t_limit) {
                mask |= 1 << k;
                *slot = t;
            }
        }
        (mask, near)
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
pub(crate) use x86::block_hits_sse;
#[cfg(target_arch = "x86_64")]
pub(crate) use x86::{Avx2, Sse};

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    use super::*;

    /// Eight children with two 4-wide SSE halves: every x86-64 CPU has SSE2.
    pub(crate) struct Sse;

    /// A ray broadcast into vector registers.
    #[derive(Clone, Copy)]
    pub(crate) struct Broadcast<V> {
        origin: [V; 3],
        inv: [V; 3],
        t_min: V,
        near_rows: [usize; 3],
        far_rows: [usize; 3],
        dominant_axis: usize,
    }

    impl NodeKernel for Sse {
        type Ray = Broadcast<__m128>;

        #[inline(always)]
        unsafe fn block_hits(
            ray: &WatertightRay,
            block: &TriangleBlock<BLOCK>,
            t_max: f32,
        ) -> BlockHits {
            block_hits_sse(ray, block, t_max)
        }

        #[inline(always)]
        unsafe fn prepare(ray: &RayBoxTest) -> Self::Ray {
            let (near_rows, far_rows) = plane_rows(ray);
            // SAFETY: SSE2 is part of x86-64.
            unsafe {
                Broadcast {
                    origin: [0, 1, 2].map(|a| _mm_set1_ps(ray.origin[a])),
                    inv: [0, 1, 2].map(|a| _mm_set1_ps(ray.inv_direction[a])),
                    t_min: _mm_set1_ps(ray.t_min),
                    near_rows,
                    far_rows,
                    dominant_axis: ray.dominant_axis,
                }
            }
        }

        #[inline(always)]
        unsafe fn enter(node: &WideNode, ray: &Self::Ray, t_limit: f32) -> (u32, [f32; WIDTH]) {
            // SAFETY: SSE2 is part of x86-64; every load reads 4 floats inside a row of 8 of
            // `node`, which is 32-byte aligned, so offsets 0 and 4 are 16-byte aligned.
            unsafe {
                let scale = _mm_set1_ps(FAR_SCALE);
                let limit = _mm_set1_ps(t_limit);
                let mut out = [0.0f32; WIDTH];
                let mut mask = 0u32;
                let pad_scale = _mm_set1_ps(SLAB_PAD);
                let abs = |v: __m128| _mm_andnot_ps(_mm_set1_ps(-0.0), v);
                let kz = ray.dominant_axis;
                for half in 0..2 {
                    let mut near = ray.t_min;
                    let mut far = limit;
                    let mut reach = _mm_setzero_ps();
                    for axis in 0..3 {
                        let np = _mm_load_ps(node.planes[ray.near_rows[axis]][4 * half..].as_ptr());
                        let fp = _mm_load_ps(node.planes[ray.far_rows[axis]][4 * half..].as_ptr());
                        let tn = _mm_mul_ps(_mm_sub_ps(np, ray.origin[axis]), ray.inv[axis]);
                        let tf = _mm_mul_ps(_mm_sub_ps(fp, ray.origin[axis]), ray.inv[axis]);
                        near = _mm_max_ps(tn, near);
                        far = _mm_min_ps(_mm_mul_ps(tf, scale), far);
                        if axis == kz {
                            reach = _mm_max_ps(abs(tn), abs(tf));
                        }
                    }
                    let pad = _mm_mul_ps(reach, pad_scale);
                    let near = _mm_sub_ps(near, pad);
                    let far = _mm_add_ps(far, pad);
                    let hit = _mm_cmple_ps(near, far);
                    mask |= (_mm_movemask_ps(hit) as u32) << (4 * half);
                    _mm_storeu_ps(out[4 * half..].as_mut_ptr(), near);
                }
                (mask, out)
            }
        }
    }

    /// [`block_hits_scalar`] for four triangles with SSE2. Every value is computed by the same
    /// operations in the same order as [`WatertightRay::block_candidates`] and
    /// [`WatertightRay::intersect`] (no fused multiply-add), so every decision, `t` and
    /// barycentric is the same bit for bit; lanes whose edge functions round to exactly zero are
    /// left `undecided` for the scalar test's double-precision path.
    #[inline(always)]
    pub(crate) fn block_hits_sse(
        ray: &WatertightRay,
        block: &TriangleBlock<BLOCK>,
        t_max: f32,
    ) -> BlockHits {
        use crate::float::gamma;
        let (kx, ky, kz) = (ray.kx, ray.ky, ray.kz);
        let [p0, p1, p2] = &block.vertices;
        // SAFETY: SSE2 is part of x86-64; each load reads one row of 4 floats of the block,
        // which is 16-byte aligned (`repr(align(16))`); stores go to arrays of 4 floats.
        unsafe {
            let splat = _mm_set1_ps;
            let (ox, oy, oz) =
                (splat(ray.origin[kx]), splat(ray.origin[ky]), splat(ray.origin[kz]));
            let (sx, sy, sz) = (splat(ray.shear_x), splat(ray.shear_y), splat(ray.shear_z));
            let load = |row: &[f32; BLOCK]| _mm_load_ps(row.as_ptr());
            let a_kx = _mm_sub_ps(load(&p0[kx]), ox);
            let a_ky = _mm_sub_ps(load(&p0[ky]), oy);
            let a_kz = _mm_sub_ps(load(&p0[kz]), oz);
            let b_kx = _mm_sub_ps(load(&p1[kx]), ox);
            let b_ky = _mm_sub_ps(load(&p1[ky]), oy);
            let b_kz = _mm_sub_ps(load(&p1[kz]), oz);
            let c_kx = _mm_sub_ps(load(&p2[kx]), ox);
            let c_ky = _mm_sub_ps(load(&p2[ky]), oy);
            let c_kz = _mm_sub_ps(load(&p2[kz]), oz);
            let ax = _mm_sub_ps(a_kx, _mm_mul_ps(sx, a_kz));
            let ay = _mm_sub_ps(a_ky, _mm_mul_ps(sy, a_kz));
            let bx = _mm_sub_ps(b_kx, _mm_mul_ps(sx, b_kz));
            let by = _mm_sub_ps(b_ky, _mm_mul_ps(sy, b_kz));
            let cx = _mm_sub_ps(c_kx, _mm_mul_ps(sx, c_kz));
            let cy = _mm_sub_ps(c_ky, _mm_mul_ps(sy, c_kz));
            let e0 = _mm_sub_ps(_mm_mul_ps(bx, cy), _mm_mul_ps(by, cx));
            let e1 = _mm_sub_ps(_mm_mul_ps(cx, ay), _mm_mul_ps(cy, ax));
            let e2 = _mm_sub_ps(_mm_mul_ps(ax, by), _mm_mul_ps(ay, bx));
            let zero = _mm_setzero_ps();
            let any_zero = _mm_or_ps(
                _mm_or_ps(_mm_cmpeq_ps(e0, zero), _mm_cmpeq_ps(e1, zero)),
                _mm_cmpeq_ps(e2, zero),
            );
            let all_ge = _mm_and_ps(
                _mm_and_ps(_mm_cmpge_ps(e0, zero), _mm_cmpge_ps(e1, zero)),
                _mm_cmpge_ps(e2, zero),
            );
            let all_le = _mm_and_ps(
                _mm_and_ps(_mm_cmple_ps(e0, zero), _mm_cmple_ps(e1, zero)),
                _mm_cmple_ps(e2, zero),
            );
            let inside = _mm_or_ps(all_ge, all_le);
            let det = _mm_add_ps(_mm_add_ps(e0, e1), e2);
            let az = _mm_mul_ps(sz, a_kz);
            let bz = _mm_mul_ps(sz, b_kz);
            let cz = _mm_mul_ps(sz, c_kz);
            let t_scaled =
                _mm_add_ps(_mm_add_ps(_mm_mul_ps(e0, az), _mm_mul_ps(e1, bz)), _mm_mul_ps(e2, cz));
            let t_limit =
                _mm_mul_ps(_mm_mul_ps(splat(t_max), det), splat(crate::triangle::T_LIMIT_SLACK));
            let front = _mm_and_ps(
                _mm_and_ps(_mm_cmpgt_ps(det, zero), _mm_cmpgt_ps(t_scaled, zero)),
                _mm_cmplt_ps(t_scaled, t_limit),
            );
            let back = _mm_and_ps(
                _mm_and_ps(_mm_cmplt_ps(det, zero), _mm_cmplt_ps(t_scaled, zero)),
                _mm_cmpgt_ps(t_scaled, t_limit),
            );
            let candidate = _mm_or_ps(any_zero, _mm_and_ps(inside, _mm_or_ps(front, back)));
            let candidates = _mm_movemask_ps(candidate) as u32;
            let undecided = candidates & _mm_movemask_ps(any_zero) as u32;
            let decidable = candidates & !undecided;
            if decidable == 0 {
                return BlockHits { undecided, ..BlockHits::default() };
            }

            // The rest of `intersect`, lane by lane, for the lanes without a zero edge function.
            let inv_det = _mm_div_ps(splat(1.0), det);
            let t = _mm_mul_ps(t_scaled, inv_det);
            // `t.is_nan() || t >= t_max` rejects: accept `t < t_max` (false for NaN).
            let mut accept = _mm_cmplt_ps(t, splat(t_max));
            if ray.t_min > 0.0 {
                // `t < t_min` rejects.
                accept = _mm_and_ps(accept, _mm_cmpnlt_ps(t, splat(ray.t_min)));
            } else {
                // `t <= delta_t` rejects; the same expression as `conservative_delta_t`.
                let abs = |v: __m128| _mm_andnot_ps(splat(-0.0), v);
                let max3 = |a: __m128, b: __m128, c: __m128| {
                    _mm_max_ps(_mm_max_ps(abs(a), abs(b)), abs(c))
                };
                let max_zt = max3(az, bz, cz);
                let delta_z = _mm_mul_ps(splat(gamma(3)), max_zt);
                let max_xt = max3(ax, bx, cx);
                let max_yt = max3(ay, by, cy);
                let max_unsheared_z = max3(a_kz, b_kz, c_kz);
                let delta_x = _mm_mul_ps(
                    splat(gamma(5)),
                    _mm_add_ps(max_xt, _mm_mul_ps(splat(ray.shear_x.abs()), max_unsheared_z)),
                );
                let delta_y = _mm_mul_ps(
                    splat(gamma(5)),
                    _mm_add_ps(max_yt, _mm_mul_ps(splat(ray.shear_y.abs()), max_unsheared_z)),
                );
                let delta_e = _mm_mul_ps(
                    splat(2.0),
                    _mm_add_ps(
                        _mm_add_ps(
                            _mm_mul_ps(_mm_mul_ps(splat(gamma(2)), max_xt), max_yt),
                            _mm_mul_ps(delta_y, max_xt),
                        ),
                        _mm_mul_ps(delta_x, max_yt),
                    ),
                );
                let max_e = max3(e0, e1, e2);
                let sum = _mm_add_ps(
                    _mm_add_ps(
                        _mm_mul_ps(_mm_mul_ps(splat(gamma(3)), max_e), max_zt),
                        _mm_mul_ps(delta_e, max_zt),
                    ),
                    _mm_mul_ps(delta_z, max_e),
                );
                let delta_t = _mm_mul_ps(_mm_mul_ps(splat(3.0), sum), abs(inv_det));
                accept = _mm_and_ps(accept, _mm_cmpnle_ps(t, delta_t));
            }
            let hits = decidable & _mm_movemask_ps(accept) as u32;
            let mut out = BlockHits { hits, undecided, ..BlockHits::default() };
            _mm_storeu_ps(out.t.as_mut_ptr(), t);
            _mm_storeu_ps(out.b1.as_mut_ptr(), _mm_mul_ps(e1, inv_det));
            _mm_storeu_ps(out.b2.as_mut_ptr(), _mm_mul_ps(e2, inv_det));
            out
        }
    }

    /// All eight children in one AVX2 register.
    pub(crate) struct Avx2;

    impl NodeKernel for Avx2 {
        type Ray = Broadcast<__m256>;

        #[inline(always)]
        unsafe fn block_hits(
            ray: &WatertightRay,
            block: &TriangleBlock<BLOCK>,
            t_max: f32,
        ) -> BlockHits {
            block_hits_sse(ray, block, t_max)
        }

        #[inline(always)]
        unsafe fn prepare(ray: &RayBoxTest) -> Self::Ray {
            let (near_rows, far_rows) = plane_rows(ray);
            // SAFETY: the caller checked AVX2 support (this function's contract).
            unsafe {
                Broadcast {
                    origin: [0, 1, 2].map(|a| _mm256_set1_ps(ray.origin[a])),
                    inv: [0, 1, 2].map(|a| _mm256_set1_ps(ray.inv_direction[a])),
                    t_min: _mm256_set1_ps(ray.t_min),
                    near_rows,
                    far_rows,
                    dominant_axis: ray.dominant_axis,
                }
            }
        }

        #[inline(always)]
        unsafe fn enter(node: &WideNode, ray: &Self::Ray, t_limit: f32) -> (u32, [f32; WIDTH]) {
            // SAFETY: the caller checked AVX2 support; every load reads one 32-byte aligned row
            // of 8 floats of `node`.
            unsafe {
                let scale = _mm256_set1_ps(FAR_SCALE);
                let mut near = ray.t_min;
                let mut far = _mm256_set1_ps(t_limit);
                let mut reach = _mm256_setzero_ps();
                let abs = |v: __m256| _mm256_andnot_ps(_mm256_set1_ps(-0.0), v);
                for axis in 0..3 {
                    let np = _mm256_load_ps(node.planes[ray.near_rows[axis]].as_ptr());
                    let fp = _mm256_load_ps(node.planes[ray.far_rows[axis]].as_ptr());
                    let tn = _mm256_mul_ps(_mm256_sub_ps(np, ray.origin[axis]), ray.inv[axis]);
                    let tf = _mm256_mul_ps(_mm256_sub_ps(fp, ray.origin[axis]), ray.inv[axis]);
                    near = _mm256_max_ps(tn, near);
                    far = _mm256_min_ps(_mm256_mul_ps(tf, scale), far);
                    if axis == ray.dominant_axis {
                        reach = _mm256_max_ps(abs(tn), abs(tf));
                    }
                }
                let pad = _mm256_mul_ps(reach, _mm256_set1_ps(SLAB_PAD));
                let near = _mm256_sub_ps(near, pad);
                let far = _mm256_add_ps(far, pad);
                let hit = _mm256_cmp_ps::<_CMP_LE_OQ>(near, far);
                let mut out = [0.0f32; WIDTH];
                _mm256_storeu_ps(out.as_mut_ptr(), near);
                (_mm256_movemask_ps(hit) as u32, out)
            }
        }
    }
}
