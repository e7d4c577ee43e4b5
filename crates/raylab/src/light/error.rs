//! Why a light cannot be made ([`LightError`]).

/// A light that cannot be made: which, and why.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{light}: {problem}")]
pub struct LightError {
    /// The light (an environment map's file).
    pub light: String,
    /// What is wrong.
    pub problem: String,
}
