//! The instruction set chosen once: a BVH holds a table of its query functions, each compiled
//! for one instruction set, as Embree's dispatch does.
//!
//! The traversals (`traverse`, `packet`, `traverse/flat.rs`) are generic over the kernel types
//! of `isa.rs`. `queries!` instantiates every query for one of them inside a function compiled
//! with that set's target features, so the kernels inline into a traversal built for the
//! instructions they use. [`Queries::for_isa`] hands out a table only for a set this CPU
//! supports, which is the safety argument of every call through a table.

use super::isa::{Isa, Scalar};
use super::node::WideBvh;
use super::packet;
use super::traverse::{self, TreeRaysKernel, flat::Flat, flat_kernel::FlatKernel};
use crate::accel::{Hit, HitRows, RayRows};
use crate::ray::Ray;

/// A BVH's queries, compiled for one instruction set.
///
/// Calling a function of a table is sound only for a table that [`Queries::for_isa`] handed
/// out (it checks the CPU): the module is private to `bvh`, and `Bvh` keeps its table private.
#[derive(Clone, Copy)]
pub(crate) struct Queries {
    /// The set the functions are compiled for.
    pub isa: Isa,
    /// The closest hit of one ray, through the tree.
    pub closest_hit: unsafe fn(&WideBvh, &Ray) -> Option<Hit>,
    /// Whether one ray is occluded, through the tree.
    pub occluded: unsafe fn(&WideBvh, &Ray) -> bool,
    /// Closest hits of rays in packets.
    pub closest_hits: unsafe fn(&WideBvh, &[Ray], &mut [Option<Hit>]),
    /// Occlusion of rays in packets.
    pub occluded_each: unsafe fn(&WideBvh, &[Ray], &mut [bool]),
    /// Closest hits of a tile of rays in packets, answered in rows.
    pub closest_hits_rows: unsafe fn(&WideBvh, &[Ray], &mut HitRows),
    /// Occlusion of a tile of rays in rows, in packets, as a mask.
    pub occluded_rows: unsafe fn(&WideBvh, &RayRows) -> u64,
    /// Closest hits of incoherent rays, through the tree in lanes where the set has them.
    pub closest_hits_incoherent: unsafe fn(&WideBvh, &[Ray], &mut [Option<Hit>]),
    /// Occlusion of incoherent rays, through the tree in lanes where the set has them.
    pub occluded_incoherent: unsafe fn(&WideBvh, &[Ray], &mut [bool]),
    /// The closest hit of one ray in a small scene's flat list.
    pub flat_closest_hit: unsafe fn(&Flat, &Ray) -> Option<Hit>,
    /// Whether one ray is occluded, in a small scene's flat list.
    pub flat_occluded: unsafe fn(&Flat, &Ray) -> bool,
    /// Closest hits of incoherent rays, in lanes, in a small scene's flat list.
    pub flat_closest_hits: unsafe fn(&Flat, &[Ray], &mut [Option<Hit>]),
    /// Occlusion of incoherent rays, in lanes, in a small scene's flat list.
    pub flat_occluded_each: unsafe fn(&Flat, &[Ray], &mut [bool]),
}

impl std::fmt::Debug for Queries {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Queries").field("isa", &self.isa).finish_non_exhaustive()
    }
}

/// The table of kernel type `$kernel`, its functions compiled with `$features` enabled.
macro_rules! queries {
    ($isa:expr, $kernel:ty $(, $features:literal)?) => {{
        $(#[target_feature(enable = $features)])?
        unsafe fn closest_hit(bvh: &WideBvh, ray: &Ray) -> Option<Hit> {
            // SAFETY: the table is handed out only for a set this CPU supports (`for_isa`).
            unsafe { traverse::closest_hit::<$kernel>(bvh, ray) }
        }
        $(#[target_feature(enable = $features)])?
        unsafe fn occluded(bvh: &WideBvh, ray: &Ray) -> bool {
            // SAFETY: as above.
            unsafe { traverse::occluded::<$kernel>(bvh, ray) }
        }
        $(#[target_feature(enable = $features)])?
        unsafe fn closest_hits(bvh: &WideBvh, rays: &[Ray], out: &mut [Option<Hit>]) {
            // SAFETY: as above.
            unsafe { packet::closest_hits::<$kernel>(bvh, rays, out) }
        }
        $(#[target_feature(enable = $features)])?
        unsafe fn occluded_each(bvh: &WideBvh, rays: &[Ray], out: &mut [bool]) {
            // SAFETY: as above.
            unsafe { packet::occluded_each::<$kernel>(bvh, rays, out) }
        }
        $(#[target_feature(enable = $features)])?
        unsafe fn closest_hits_rows(bvh: &WideBvh, rays: &[Ray], out: &mut HitRows) {
            // SAFETY: as above.
            unsafe { packet::closest_hits_rows::<$kernel>(bvh, rays, out) }
        }
        $(#[target_feature(enable = $features)])?
        unsafe fn occluded_rows(bvh: &WideBvh, rays: &RayRows) -> u64 {
            // SAFETY: as above.
            unsafe { packet::occluded_rows::<$kernel>(bvh, rays) }
        }
        $(#[target_feature(enable = $features)])?
        unsafe fn closest_hits_incoherent(bvh: &WideBvh, rays: &[Ray], out: &mut [Option<Hit>]) {
            // SAFETY: as above.
            unsafe { <$kernel as TreeRaysKernel>::closest_hits(bvh, rays, out) }
        }
        $(#[target_feature(enable = $features)])?
        unsafe fn occluded_incoherent(bvh: &WideBvh, rays: &[Ray], out: &mut [bool]) {
            // SAFETY: as above.
            unsafe { <$kernel as TreeRaysKernel>::occluded_each(bvh, rays, out) }
        }
        $(#[target_feature(enable = $features)])?
        unsafe fn flat_closest_hit(flat: &Flat, ray: &Ray) -> Option<Hit> {
            // SAFETY: as above.
            unsafe { <$kernel as FlatKernel>::closest_hit(flat, ray) }
        }
        $(#[target_feature(enable = $features)])?
        unsafe fn flat_occluded(flat: &Flat, ray: &Ray) -> bool {
            // SAFETY: as above.
            unsafe { <$kernel as FlatKernel>::occluded(flat, ray) }
        }
        $(#[target_feature(enable = $features)])?
        unsafe fn flat_closest_hits(flat: &Flat, rays: &[Ray], out: &mut [Option<Hit>]) {
            // SAFETY: as above.
            unsafe { <$kernel as FlatKernel>::closest_hits(flat, rays, out) }
        }
        $(#[target_feature(enable = $features)])?
        unsafe fn flat_occluded_each(flat: &Flat, rays: &[Ray], out: &mut [bool]) {
            // SAFETY: as above.
            unsafe { <$kernel as FlatKernel>::occluded_each(flat, rays, out) }
        }
        Queries {
            isa: $isa,
            closest_hit,
            occluded,
            closest_hits,
            occluded_each,
            closest_hits_rows,
            occluded_rows,
            closest_hits_incoherent,
            occluded_incoherent,
            flat_closest_hit,
            flat_occluded,
            flat_closest_hits,
            flat_occluded_each,
        }
    }};
}

const SCALAR: Queries = queries!(Isa::Scalar, Scalar);

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::*;
    use crate::bvh::isa::{Avx2, Avx512, Sse};

    pub(super) const SSE2: Queries = queries!(Isa::Sse2, Sse, "sse2");
    pub(super) const AVX2: Queries = queries!(Isa::Avx2, Avx2, "avx2,fma,bmi1,bmi2,lzcnt,popcnt");
    pub(super) const AVX512: Queries =
        queries!(Isa::Avx512, Avx512, "avx2,fma,bmi1,bmi2,lzcnt,popcnt,avx512f,avx512vl");
}

impl Queries {
    /// The table of `isa`, or `None` if this CPU lacks it: the one place an instruction set is
    /// matched.
    pub(crate) fn for_isa(isa: Isa) -> Option<Queries> {
        if !isa.is_supported() {
            return None;
        }
        Some(match isa {
            #[cfg(target_arch = "x86_64")]
            Isa::Sse2 => x86::SSE2,
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => x86::AVX2,
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => x86::AVX512,
            _ => SCALAR,
        })
    }
}
