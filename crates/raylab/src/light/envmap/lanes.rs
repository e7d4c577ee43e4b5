//! An environment map's lookups for many rays at once, in vector code: what rays that leave the
//! scene see of it and with what density ([`EnvironmentMap::eval_pdf_each`]), one loop over
//! their directions compiled for AVX-512 (sixteen to an instruction, the texels gathered),
//! AVX2 (eight) and the baseline (the scalar twin). Each direction's numbers are
//! [`EnvironmentMap::eval_pdf`]'s to the bit: the loop runs the same function
//! (`eval_pdf_inline`), written without branches, calls or bounds checks for this.

use glam::Vec3;

use super::EnvironmentMap;
use crate::cpu::Isa;
use crate::light::Emission;

impl EnvironmentMap {
    /// [`eval_pdf`](Self::eval_pdf) for each of `directions`, to the bit, on the best
    /// instruction set this process uses ([`Isa::detect`]).
    ///
    /// # Panics
    /// If the slices differ in length.
    #[inline]
    pub fn eval_pdf_each(&self, directions: &[Vec3], out: &mut [Emission]) {
        self.eval_pdf_each_on(Isa::detect(), directions, out);
    }

    /// [`eval_pdf_each`](Self::eval_pdf_each) on the instruction set `isa`.
    ///
    /// # Panics
    /// If the slices differ in length, or this CPU does not support `isa`.
    pub fn eval_pdf_each_on(&self, isa: Isa, directions: &[Vec3], out: &mut [Emission]) {
        assert_eq!(directions.len(), out.len(), "an emission per direction");
        assert!(isa.is_supported(), "{} is not supported by this CPU", isa.name());
        match isa {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: the CPU supports AVX-512 (asserted above).
            Isa::Avx512 => unsafe { eval_pdf_avx512(self, directions, out) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: the CPU supports AVX2 (asserted above).
            Isa::Avx2 => unsafe { eval_pdf_avx2(self, directions, out) },
            _ => eval_pdf_baseline(self, directions, out),
        }
    }
}

/// The loop, inlined into each instruction set's build.
#[inline(always)]
fn eval_pdf_loop(map: &EnvironmentMap, directions: &[Vec3], out: &mut [Emission]) {
    for (direction, slot) in directions.iter().zip(out) {
        *slot = map.eval_pdf_inline(*direction);
    }
}

/// [`eval_pdf_loop`] compiled for AVX-512.
///
/// # Safety
/// The CPU must support AVX2 and AVX-512 F and VL ([`Isa::Avx512`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f,avx512vl")]
#[inline(never)]
unsafe fn eval_pdf_avx512(map: &EnvironmentMap, directions: &[Vec3], out: &mut [Emission]) {
    eval_pdf_loop(map, directions, out);
}

/// [`eval_pdf_loop`] compiled for AVX2.
///
/// # Safety
/// The CPU must support AVX2 ([`Isa::Avx2`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline(never)]
unsafe fn eval_pdf_avx2(map: &EnvironmentMap, directions: &[Vec3], out: &mut [Emission]) {
    eval_pdf_loop(map, directions, out);
}

/// [`eval_pdf_loop`] for the baseline instruction set: the scalar twin.
#[inline(never)]
fn eval_pdf_baseline(map: &EnvironmentMap, directions: &[Vec3], out: &mut [Emission]) {
    eval_pdf_loop(map, directions, out);
}
