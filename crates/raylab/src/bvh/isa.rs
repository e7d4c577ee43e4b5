//! The instruction sets the BVH's kernels are compiled for: [`Isa`], what a caller chooses, and
//! one type per set that the kernels are implemented for ([`Scalar`], `Sse`, `Avx2`,
//! `Avx512`).
//!
//! A kernel is a trait implemented for these types: the node test (`node/kernel.rs`), the leaf
//! records' test (`leaf/kernel.rs`) and the packet leaves' test (`packet/leaf.rs`). The
//! traversals are generic over them and compiled once per set into a table of functions
//! (`bvh/queries.rs`), which a BVH picks once, when it is built.

/// The instruction set of a BVH's kernels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Isa {
    /// Portable code, one box at a time: the reference.
    Scalar,
    /// SSE2: two groups of four boxes (every x86-64 CPU).
    Sse2,
    /// AVX2: eight boxes at once.
    Avx2,
    /// AVX-512 (F and VL): the AVX2 node kernel, with the rest of traversal compiled for AVX-512.
    Avx512,
}

impl Isa {
    /// The best instruction set this CPU supports.
    pub fn detect() -> Isa {
        Isa::ALL.into_iter().rev().find(|isa| isa.is_supported()).unwrap_or(Isa::Scalar)
    }

    /// Every instruction set, from the most portable.
    pub const ALL: [Isa; 4] = [Isa::Scalar, Isa::Sse2, Isa::Avx2, Isa::Avx512];

    /// Whether this CPU can run it.
    pub fn is_supported(self) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            match self {
                Isa::Scalar | Isa::Sse2 => true,
                Isa::Avx2 => std::arch::is_x86_feature_detected!("avx2"),
                Isa::Avx512 => {
                    std::arch::is_x86_feature_detected!("avx2")
                        && std::arch::is_x86_feature_detected!("avx512f")
                        && std::arch::is_x86_feature_detected!("avx512vl")
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            self == Isa::Scalar
        }
    }

    /// A short name: `scalar`, `sse2`, `avx2`, `avx512`.
    pub fn name(self) -> &'static str {
        match self {
            Isa::Scalar => "scalar",
            Isa::Sse2 => "sse2",
            Isa::Avx2 => "avx2",
            Isa::Avx512 => "avx512",
        }
    }
}

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
