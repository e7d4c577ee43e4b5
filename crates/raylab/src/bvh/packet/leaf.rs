//! The packet leaves' kernels: the rays of a packet against the triangles of a leaf, several
//! rays per instruction (`packet/lanes.rs`), deciding as the single-ray tests do; the scalar
//! twin, [`packet_leaf_scalar`], runs them ray by ray.

use super::rays::PacketRays;
use super::rows::RestRows;
use crate::bvh::bounds::Bounds;
use crate::bvh::isa::Scalar;
use crate::bvh::leaf::kernel::prepare_triangle_ray;
use crate::bvh::node::WideBvh;
use crate::bvh::traverse::{Closest, Kernel, leaf_occluded};
use crate::ray::Ray;

/// The packet leaf test, per instruction set: by default [`packet_leaf_scalar`].
pub(crate) trait PacketKernel: Kernel {
    /// Tests the rays of a packet in `open` that enter `bounds` against the triangles of the
    /// leaf inside it: for the closest hit (`occlusion` false: each ray's best hit is offered
    /// every hit), or for occlusion (rays hit are taken out of `open`). Decides exactly as the
    /// single-ray tests do; the scalar twin is [`packet_leaf_scalar`]. (The lane kernels test
    /// every open ray, without the box test, against a leaf far larger than the packet's
    /// footprint: the same answers, `packet/lanes.rs` says why.)
    ///
    /// # Safety
    /// The CPU must support the kernel's instruction set (checked once when a BVH picks it).
    #[inline(always)]
    unsafe fn packet_leaf(
        rays: &mut PacketRays,
        open: &mut u64,
        occlusion: bool,
        bvh: &WideBvh,
        bounds: &Bounds,
        offset: u32,
    ) {
        // SAFETY: the caller's guarantee.
        unsafe { packet_leaf_scalar::<Self>(rays, open, occlusion, bvh, bounds, offset) }
    }

    /// Copies `rays` (at most [`PACKET`](super::rays::PACKET)) into rows for
    /// [`fill`](super::setup::fill): by default one ray at a time
    /// ([`rows_portable`](super::rows::rows_portable)).
    ///
    /// # Safety
    /// The CPU must support the kernel's instruction set.
    #[inline(always)]
    unsafe fn rows_of_rays(
        rays: &[Ray],
        origin: &mut [[f32; super::rays::PACKET]; 3],
        rest: &mut RestRows,
    ) {
        super::rows::rows_portable(rays, origin, rest)
    }
}

impl PacketKernel for Scalar {}

/// The scalar twin of [`PacketKernel::packet_leaf`]: ray by ray, the single-ray tests.
///
/// # Safety
/// The CPU must support `K`'s instruction set.
#[inline(always)]
pub(crate) unsafe fn packet_leaf_scalar<K: Kernel>(
    rays: &mut PacketRays,
    open: &mut u64,
    occlusion: bool,
    bvh: &WideBvh,
    bounds: &Bounds,
    offset: u32,
) {
    let mut rest = *open;
    while rest != 0 {
        let i = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        if rays.box_ray(i).enter(bounds, rays.box_limit[i]).is_none() {
            continue;
        }
        // SAFETY: the caller guarantees `K`'s instruction set.
        let triangle_ray = &unsafe { prepare_triangle_ray::<K>(&rays.triangle_ray(i)) };
        if occlusion {
            let t_max = rays.triangle_limit[i];
            // SAFETY: the caller guarantees `K`'s instruction set.
            if unsafe { leaf_occluded::<K>(bvh, offset, triangle_ray, t_max) } {
                *open &= !(1 << i);
            }
        } else {
            let mut closest = Closest {
                best: rays.best(i),
                triangle_limit: rays.triangle_limit[i],
                box_limit: rays.box_limit[i],
            };
            // SAFETY: the caller guarantees `K`'s instruction set.
            unsafe { closest.leaf::<K>(bvh, offset, triangle_ray) };
            if let Some(h) = closest.best {
                rays.offer(i, h.t, h.triangle, h.b1, h.b2);
            }
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    use super::*;
    use crate::bvh::isa::{Avx2, Avx512, Sse};
    use crate::bvh::packet::lanes::packet_leaf_lanes;

    /// The packet leaf `$lanes` rays per register `$register`: SSE2's four, AVX2's eight and
    /// AVX-512's sixteen.
    macro_rules! packet_kernel {
        ($isa:ty, $register:ty, $lanes:literal, $transpose:literal) => {
            impl PacketKernel for $isa {
                #[inline(always)]
                unsafe fn packet_leaf(
                    rays: &mut PacketRays,
                    open: &mut u64,
                    occlusion: bool,
                    bvh: &WideBvh,
                    bounds: &Bounds,
                    offset: u32,
                ) {
                    // SAFETY: the caller's guarantee of the instruction set; the register
                    // holds `$lanes` floats.
                    unsafe {
                        packet_leaf_lanes::<$register, $lanes>(
                            rays, open, occlusion, bvh, bounds, offset,
                        )
                    }
                }

                /// SSE2 copies the rays one by one; AVX2 and AVX-512 by an AVX transposition.
                #[inline(always)]
                unsafe fn rows_of_rays(
                    rays: &[Ray],
                    origin: &mut [[f32; crate::bvh::packet::rays::PACKET]; 3],
                    rest: &mut RestRows,
                ) {
                    if $transpose {
                        // SAFETY: the caller's guarantee of the instruction set, which has AVX.
                        unsafe { crate::bvh::packet::rows::rows_avx(rays, origin, rest) }
                    } else {
                        crate::bvh::packet::rows::rows_portable(rays, origin, rest)
                    }
                }
            }
        };
    }
    packet_kernel!(Sse, __m128, 4, false);
    packet_kernel!(Avx2, __m256, 8, true);
    packet_kernel!(Avx512, __m512, 16, true);
}
