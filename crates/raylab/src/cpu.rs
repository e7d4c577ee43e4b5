//! The instruction sets raylab's SIMD code is compiled for, and which of them this CPU has:
//! detected once where a kernel is chosen (a BVH's query table, the sampler's lane loops).
//!
//! `RAYLAB_ISA` caps the choice for the whole process (what a caller asks for by name, as
//! `Bvh::with_isa` or `raylab bench --isa`, may still go above it): `RAYLAB_ISA=avx2` makes every kernel
//! that [`Isa::detect`] picks run its AVX2 form on a CPU with AVX-512, so that the path tracer,
//! `raylab view` and the Python package can be measured as on the CPUs most people own. It
//! names one of `scalar`, `sse2`, `avx2`, `avx512` ([`Isa::name`]); a set this CPU lacks, or
//! another name, is an error that [`Isa::from_env`] reports (the command line and the Python
//! package check it before they start) and that [`Isa::detect`] ignores.

/// An x86 instruction set level, or portable code: what a BVH's kernels and the sampler's
/// lane loops are compiled for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Isa {
    /// Portable code: the reference.
    Scalar,
    /// SSE2 (every x86-64 CPU).
    Sse2,
    /// AVX2.
    Avx2,
    /// AVX-512 F and VL (with AVX2).
    Avx512,
}

impl Isa {
    /// The best instruction set this CPU supports, or the one `RAYLAB_ISA` names if this CPU
    /// supports it (see the module documentation). Read once per process.
    pub fn detect() -> Isa {
        static CHOSEN: std::sync::OnceLock<Isa> = std::sync::OnceLock::new();
        *CHOSEN.get_or_init(|| match Isa::from_env() {
            Ok(Some(isa)) => isa,
            _ => Isa::best(),
        })
    }

    /// The best instruction set this CPU supports, whatever `RAYLAB_ISA` says.
    pub fn best() -> Isa {
        Isa::ALL.into_iter().rev().find(|isa| isa.is_supported()).unwrap_or(Isa::Scalar)
    }

    /// The set `RAYLAB_ISA` names: `None` when it is unset or empty, an error when it names no
    /// set or one this CPU lacks.
    pub fn from_env() -> Result<Option<Isa>, IsaError> {
        match std::env::var("RAYLAB_ISA") {
            Ok(name) if name.is_empty() => Ok(None),
            Ok(name) => Isa::supported_by_name(&name).map(Some),
            Err(std::env::VarError::NotPresent) => Ok(None),
            Err(std::env::VarError::NotUnicode(_)) => Err(IsaError::Unknown("(not UTF-8)".into())),
        }
    }

    /// The set called `name` ([`Isa::name`]), if this CPU supports it.
    pub fn supported_by_name(name: &str) -> Result<Isa, IsaError> {
        let isa = Isa::ALL
            .into_iter()
            .find(|isa| isa.name() == name)
            .ok_or_else(|| IsaError::Unknown(name.to_string()))?;
        if isa.is_supported() { Ok(isa) } else { Err(IsaError::Unsupported(isa)) }
    }

    /// Every instruction set, from the most portable.
    pub const ALL: [Isa; 4] = [Isa::Scalar, Isa::Sse2, Isa::Avx2, Isa::Avx512];

    /// Whether this CPU can run it.
    pub fn is_supported(self) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            match self {
                Isa::Scalar | Isa::Sse2 => true,
                Isa::Avx2 => avx2_level(),
                Isa::Avx512 => {
                    avx2_level()
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

    /// Whether this set includes `other` (later in [`Isa::ALL`], or the same).
    pub fn at_least(self, other: Isa) -> bool {
        let rank = |isa: Isa| Isa::ALL.iter().position(|&x| x == isa);
        rank(self) >= rank(other)
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

/// Why an instruction set cannot be used.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum IsaError {
    /// No set has this name.
    Unknown(String),
    /// This CPU lacks the set.
    Unsupported(Isa),
}

impl std::fmt::Display for IsaError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            IsaError::Unknown(name) => {
                write!(f, "unknown instruction set '{name}': use scalar, sse2, avx2 or avx512")
            }
            IsaError::Unsupported(isa) => write!(
                f,
                "this CPU cannot run {}: it supports up to {}",
                isa.name(),
                Isa::best().name()
            ),
        }
    }
}

impl std::error::Error for IsaError {}

/// AVX2 with what every AVX2 CPU has beside it (Haswell and Zen on): FMA, BMI1 and BMI2, LZCNT
/// and POPCNT. The kernels of the AVX2 level are compiled with all of them.
#[cfg(target_arch = "x86_64")]
fn avx2_level() -> bool {
    std::arch::is_x86_feature_detected!("avx2")
        && std::arch::is_x86_feature_detected!("fma")
        && std::arch::is_x86_feature_detected!("bmi1")
        && std::arch::is_x86_feature_detected!("bmi2")
        && std::arch::is_x86_feature_detected!("lzcnt")
        && std::arch::is_x86_feature_detected!("popcnt")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_find_their_sets_and_refuse_others() {
        for isa in Isa::ALL {
            match Isa::supported_by_name(isa.name()) {
                Ok(found) => assert_eq!(found, isa),
                Err(e) => {
                    assert_eq!(e, IsaError::Unsupported(isa));
                    assert!(!isa.is_supported());
                }
            }
        }
        assert_eq!(Isa::supported_by_name("avx3"), Err(IsaError::Unknown("avx3".into())));
        assert!(IsaError::Unknown("x".into()).to_string().contains("avx2 or avx512"));
        assert!(Isa::best().is_supported());
        assert!(Isa::Avx512.at_least(Isa::Avx2) && Isa::Avx2.at_least(Isa::Avx2));
        assert!(!Isa::Sse2.at_least(Isa::Avx2) && Isa::Sse2.at_least(Isa::Scalar));
        assert!(Isa::detect().is_supported());
    }
}
