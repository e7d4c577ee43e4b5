//! The instruction sets the BVH's kernels are compiled for: [`Isa`], what a caller chooses, and
//! one type per set that the kernels are implemented for ([`Scalar`], `Sse`, `Avx2`,
//! `Avx512`).
//!
//! A kernel is a trait implemented for these types: the node test (`node/kernel.rs`), the leaf
//! records' test (`leaf/kernel.rs`) and the packet leaves' test (`packet/leaf.rs`). The
//! traversals are generic over them and compiled once per set into a table of functions
//! (`bvh/queries.rs`), which a BVH picks once, when it is built.

pub use crate::cpu::Isa;

/// The portable kernels, one box and one triangle at a time: every vector kernel's twin.
pub(crate) struct Scalar;

#[cfg(target_arch = "x86_64")]
/// SSE2 (every x86-64 CPU): a node's eight boxes in two 4-wide halves.
pub(crate) struct Sse;

#[cfg(target_arch = "x86_64")]
/// AVX2: a node's eight boxes in one register.
pub(crate) struct Avx2;

#[cfg(target_arch = "x86_64")]
/// AVX-512 F and VL: AVX2's node kernel, leaf records with the two-table permute, packet leaves
/// sixteen rays per instruction.
pub(crate) struct Avx512;
