//! What decides a render's pixels besides the scene: its identity, stored in every part and
//! checkpoint (the `raylab.settings` attribute, see [`crate::parts`]) as one line of JSON.
//!
//! Two parts merge, and a checkpoint resumes, only where their identities are equal (and
//! their scenes' content hashes). The identity is typed: reading it back gives the integrator,
//! the camera and the settings as values, never by searching text. Parts written before
//! identities were typed (raylab 0.1.0's first releases wrote `size=…; camera=…` text) are
//! refused with a message saying so: render them again.

use serde::{Deserialize, Serialize};

use crate::camera::Camera;
use crate::filter::Filter;
use crate::integrator::{Stage, TriangleSampling};
use crate::sampling::SamplerKind;
use crate::settings::{AovKind, IntegratorKind};

/// The version of the identity's layout; a change to it (a field added) is a new version.
const VERSION: u32 = 1;

/// The camera, as it decides the pixels.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CameraIdentity {
    /// Position, in the lab's frame.
    pub position: [f32; 3],
    /// Yaw, pitch and roll in radians.
    pub yaw: f32,
    /// Pitch in radians.
    pub pitch: f32,
    /// Roll in radians.
    pub roll: f32,
    /// Focal length in pixels.
    pub focal_length_px: f32,
    /// Thin-lens radius (0: a pinhole).
    pub aperture_radius: f32,
    /// Distance in focus.
    pub focus_distance: f32,
}

impl From<&Camera> for CameraIdentity {
    fn from(camera: &Camera) -> CameraIdentity {
        CameraIdentity {
            position: camera.position.to_array(),
            yaw: camera.yaw,
            pitch: camera.pitch,
            roll: camera.roll,
            focal_length_px: camera.focal_length_px,
            aperture_radius: camera.aperture_radius,
            focus_distance: camera.focus_distance,
        }
    }
}

/// Everything besides the scene that a render's pixels depend on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RenderIdentity {
    /// The layout's version.
    pub version: u32,
    /// The whole image's size in pixels.
    pub size: (u32, u32),
    /// The camera.
    pub camera: CameraIdentity,
    /// What was computed.
    pub integrator: IntegratorKind,
    /// The lab integrator's stage.
    pub stage: Stage,
    /// Samples per pixel of the finished render.
    pub spp: u32,
    /// The seed.
    pub seed: u64,
    /// The sampler (resolved: the integrator's own where none was asked for).
    pub sampler: SamplerKind,
    /// The pixel filter.
    pub filter: Filter,
    /// The longest path (`None`: unlimited).
    pub max_depth: Option<u32>,
    /// How points on area lights are sampled.
    pub light_sampling: TriangleSampling,
    /// The extra layers, in order.
    pub aovs: Vec<AovKind>,
}

/// Why a part's identity cannot be read.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum IdentityError {
    /// Written by a raylab from before typed identities.
    #[error(
        "{file}: written by an earlier version of raylab, whose parts and checkpoints this one \
         cannot check; render it again"
    )]
    Earlier {
        /// The part or checkpoint.
        file: String,
    },
    /// Not an identity this version reads.
    #[error("{file}: its render settings cannot be read: {problem}")]
    Malformed {
        /// The part or checkpoint.
        file: String,
        /// What the JSON reader said, or the version found.
        problem: String,
    },
}

impl RenderIdentity {
    /// An identity at the current version (the caller fills in the fields).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        camera: &Camera,
        integrator: IntegratorKind,
        stage: Stage,
        spp: u32,
        seed: u64,
        sampler: SamplerKind,
        filter: Filter,
        max_depth: Option<u32>,
        light_sampling: TriangleSampling,
        aovs: Vec<AovKind>,
    ) -> RenderIdentity {
        RenderIdentity {
            version: VERSION,
            size: (camera.width, camera.height),
            camera: camera.into(),
            integrator: integrator.estimator(),
            stage,
            spp,
            seed,
            sampler,
            filter,
            max_depth,
            light_sampling,
            aovs,
        }
    }

    /// As one line of ASCII JSON, for a part's header.
    pub fn to_text(&self) -> String {
        serde_json::to_string(self).expect("an identity serializes")
    }

    /// From a part's header text; `file` names it in errors.
    pub fn from_text(file: &str, text: &str) -> Result<RenderIdentity, IdentityError> {
        if text.starts_with("size=") {
            return Err(IdentityError::Earlier { file: file.to_owned() });
        }
        let malformed =
            |problem: String| IdentityError::Malformed { file: file.to_owned(), problem };
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| malformed(e.to_string()))?;
        match value.get("version").and_then(serde_json::Value::as_u64) {
            Some(v) if v == u64::from(VERSION) => {}
            Some(v) => return Err(malformed(format!("version {v}, this raylab reads {VERSION}"))),
            None => return Err(malformed("no version".to_owned())),
        }
        serde_json::from_value(value).map_err(|e| malformed(e.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn identity() -> RenderIdentity {
        let mut camera = Camera::lab(40, 27);
        camera.yaw = 0.1f32.to_radians();
        camera.focus_distance = 2.345_678_9;
        RenderIdentity::new(
            &camera,
            IntegratorKind::Path,
            Stage::Ambient,
            64,
            7,
            SamplerKind::Sobol,
            Filter::GAUSSIAN,
            Some(8),
            TriangleSampling::SolidAngle,
            vec![AovKind::Albedo, AovKind::Depth],
        )
    }

    #[test]
    fn identities_read_back_exactly() {
        let path = identity();
        let text = path.to_text();
        assert!(text.is_ascii() && !text.contains('\n'), "{text}");
        assert!(text.contains(r#""integrator":"path""#), "{text}");
        assert_eq!(RenderIdentity::from_text("a.exr", &text), Ok(path));
        let lab =
            RenderIdentity { integrator: IntegratorKind::Aov(AovKind::Normals), ..identity() };
        assert_eq!(RenderIdentity::from_text("b.exr", &lab.to_text()), Ok(lab));
    }

    /// `path-scalar` gives `path`'s pixels to the bit, so a render by one is the same render
    /// as by the other: parts of both merge, and either resumes the other's checkpoint.
    #[test]
    fn the_scalar_path_renders_under_the_paths_identity() {
        let camera = Camera::lab(40, 27);
        let with = |integrator| {
            RenderIdentity::new(
                &camera,
                integrator,
                Stage::Ambient,
                16,
                3,
                SamplerKind::Sobol,
                Filter::GAUSSIAN,
                Some(8),
                TriangleSampling::Area,
                Vec::new(),
            )
        };
        let scalar = with(IntegratorKind::PathScalar);
        assert_eq!(scalar, with(IntegratorKind::Path));
        assert_eq!(scalar.integrator, IntegratorKind::Path);
        assert_ne!(scalar, with(IntegratorKind::Lab));
    }

    #[test]
    fn earlier_and_malformed_identities_are_refused_by_name() {
        let old = "size=40x27; camera=Camera { .. }; integrator=lab; stage=ambient; spp=1";
        let error = RenderIdentity::from_text("t0.exr", old).unwrap_err().to_string();
        assert!(error.starts_with("t0.exr: written by an earlier version of raylab"), "{error}");
        let error = RenderIdentity::from_text("t1.exr", "{").unwrap_err().to_string();
        assert!(error.starts_with("t1.exr: its render settings cannot be read"), "{error}");
        let future = identity().to_text().replace(r#""version":1"#, r#""version":2"#);
        let error = RenderIdentity::from_text("t2.exr", &future).unwrap_err().to_string();
        assert!(error.contains("version 2, this raylab reads 1"), "{error}");
    }
}
