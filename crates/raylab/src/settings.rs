//! The render settings a scene file gives ([`RenderSettings`], its `[render]` table), and the
//! choices scene files, the command line, `raylab view` and the render session name alike:
//! what a render computes ([`IntegratorKind`], [`AovKind`]) and how long its paths may be
//! ([`MaxDepth`]). (The settings of one part live with it: the path tracer's
//! `PathSettings`, the sampling's `SampleSettings`, the BVH's `BuildSettings`; a render
//! session resolves all of a render's into `ResolvedSettings`.)
//!
//! | name | [`IntegratorKind`] | computes |
//! |---|---|---|
//! | `lab` | `Lab` | the lab's light model (point light, shadows, ambient term) |
//! | `path` | `Path` | path tracing (area lights, indirect light, glossy and specular materials) |
//! | `path-scalar` | `PathScalar` | the same path tracer one path at a time (the same pixels) |
//! | `albedo`, `normals`, `depth` | `Aov(AovKind)` | what the camera sees first (arbitrary output variables) |
//!
//! When nothing names one, a scene that the lab's model cannot light whole is path-traced (some
//! surface emits, or some light is not a point light: an environment, a sun, a spot or a
//! directional light), and any other scene gets the lab's model
//! ([`IntegratorKind::default_for`], given `Scene::needs_path_tracing`).

use std::fmt;
use std::str::FromStr;

use crate::filter::Filter;
use crate::sampling::SamplerKind;
use crate::unknown_name::UnknownName;

/// Render settings a scene file may give (each `None` leaves the renderer's default).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct RenderSettings {
    /// Image size in pixels.
    pub size: Option<(u32, u32)>,
    /// Samples per pixel.
    pub spp: Option<u32>,
    /// The longest path.
    pub max_depth: Option<MaxDepth>,
    /// The seed.
    pub seed: Option<u64>,
    /// The integrator.
    pub integrator: Option<IntegratorKind>,
    /// The sampler.
    pub sampler: Option<SamplerKind>,
    /// The pixel filter.
    pub filter: Option<Filter>,
}

/// How long the path tracer's paths may be: Mitsuba's `max_depth`, which counts segments, the
/// camera's included (1 shows only the emitters seen directly, 2 adds direct light), or no
/// limit (Mitsuba's `-1`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MaxDepth {
    /// At most this many segments.
    Segments(u32),
    /// No limit.
    Unlimited,
}

impl MaxDepth {
    /// The limit in segments, `None` for none (as `PathSettings::max_depth` takes it).
    pub fn segments(self) -> Option<u32> {
        match self {
            MaxDepth::Segments(n) => Some(n),
            MaxDepth::Unlimited => None,
        }
    }
}

/// Which first-hit quantity an AOV (arbitrary output variable) shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "io", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "io", serde(rename_all = "lowercase"))]
pub enum AovKind {
    /// The surface's albedo.
    Albedo,
    /// The shading normal facing the camera.
    Normals,
    /// The distance to the surface.
    Depth,
}

impl AovKind {
    /// Every kind, in the order of the command line's help.
    pub const ALL: [AovKind; 3] = [AovKind::Albedo, AovKind::Normals, AovKind::Depth];

    /// Its name: `albedo`, `normals` or `depth` (also its layer's name in an OpenEXR file).
    pub fn name(self) -> &'static str {
        match self {
            AovKind::Albedo => "albedo",
            AovKind::Normals => "normals",
            AovKind::Depth => "depth",
        }
    }
}

impl fmt::Display for AovKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for AovKind {
    type Err = UnknownName;

    fn from_str(name: &str) -> Result<AovKind, UnknownName> {
        AovKind::ALL
            .into_iter()
            .find(|kind| kind.name() == name)
            .ok_or_else(|| UnknownName::new("AOV", name, "albedo, normals or depth"))
    }
}

/// Which integrator computes a picture.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "io", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "io", serde(rename_all = "lowercase"))]
pub enum IntegratorKind {
    /// The lab's light model, at the stage the render settings give.
    Lab,
    /// The path tracer: the wavefront, whose vertices run sixteen to an instruction
    /// (`Path`).
    Path,
    /// The path tracer one path at a time (`PathScalar`): the reference twin of `path`, with the
    /// same samples to the bit.
    #[cfg_attr(feature = "io", serde(rename = "path-scalar"))]
    PathScalar,
    /// A first-hit image.
    Aov(AovKind),
}

impl IntegratorKind {
    /// The integrator of a scene that names none: `path` where the lab's model would miss some
    /// of its light (emitting surfaces, environments, spot, directional and sun lights:
    /// `Scene::needs_path_tracing`), else `lab`.
    pub fn default_for(needs_path_tracing: bool) -> IntegratorKind {
        if needs_path_tracing { IntegratorKind::Path } else { IntegratorKind::Lab }
    }

    /// What it estimates, for a render's identity: `path-scalar` is `path` (the same samples
    /// to the bit, so the parts of one merge with and resume the other's).
    pub fn estimator(self) -> IntegratorKind {
        match self {
            IntegratorKind::PathScalar => IntegratorKind::Path,
            other => other,
        }
    }

    /// Its name, as scene files and the command line write it.
    pub fn name(self) -> &'static str {
        match self {
            IntegratorKind::Lab => "lab",
            IntegratorKind::Path => "path",
            IntegratorKind::PathScalar => "path-scalar",
            IntegratorKind::Aov(kind) => kind.name(),
        }
    }

    /// Whether its pictures are shown as the lab shows them (linear values clamped, no sRGB
    /// encoding) rather than as physically based renders are (sRGB).
    pub fn shows_linear(self) -> bool {
        self == IntegratorKind::Lab
    }
}

impl fmt::Display for IntegratorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for IntegratorKind {
    type Err = UnknownName;

    fn from_str(name: &str) -> Result<IntegratorKind, UnknownName> {
        match name {
            "lab" => Ok(IntegratorKind::Lab),
            "path" => Ok(IntegratorKind::Path),
            "path-scalar" => Ok(IntegratorKind::PathScalar),
            other => other.parse().map(IntegratorKind::Aov).map_err(|_| {
                UnknownName::new(
                    "integrator",
                    name,
                    "lab, path, path-scalar, albedo, normals or depth",
                )
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_read_back_and_unknown_names_say_what_is_known() {
        for kind in [IntegratorKind::Lab, IntegratorKind::Path, IntegratorKind::PathScalar]
            .into_iter()
            .chain(AovKind::ALL.map(IntegratorKind::Aov))
        {
            assert_eq!(kind.name().parse::<IntegratorKind>(), Ok(kind));
        }
        let error = "whitted".parse::<IntegratorKind>().unwrap_err();
        assert_eq!(
            error.to_string(),
            "unknown integrator 'whitted': expected lab, path, path-scalar, albedo, normals or depth"
        );
        assert!(
            "lab".parse::<AovKind>().unwrap_err().to_string().contains("albedo, normals or depth")
        );
        assert_eq!(IntegratorKind::default_for(true), IntegratorKind::Path);
        assert_eq!(IntegratorKind::default_for(false), IntegratorKind::Lab);
    }
}
