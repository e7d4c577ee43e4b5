//! What every part of a scene file's reader shares: the error that names the file, line and
//! column ([`SceneFileError`]), and the [`Builder`] that the materials, textures, lights and
//! shapes are built by, with its placement of things in the file's y-up frame.

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::{Affine3A, Mat4, Vec3};
use serde::Deserialize;
use toml::Spanned;

use crate::scene::{LoadOptions, LoadedMesh};

/// A scene file that cannot be used: the file, where in it, and what is wrong.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("{}:{line}:{column}: {message}", .path.display())]
pub struct SceneFileError {
    /// The scene file.
    pub path: PathBuf,
    /// Line, from 1.
    pub line: usize,
    /// Column, from 1.
    pub column: usize,
    /// What is wrong.
    pub message: String,
}

pub(super) struct Builder<'a, F> {
    pub(super) at: &'a F,
    pub(super) folder: &'a Path,
    /// How the meshes are loaded.
    pub(super) options: &'a LoadOptions,
    /// The meshes' loaders' warnings, for [`Scene::warnings`](crate::scene::Scene::warnings).
    pub(super) warnings: std::cell::RefCell<Vec<String>>,
    /// The mesh files that several shapes place (five spheres of one `sphere.obj`), by their
    /// paths as the scene names them: the uses still to come, and the mesh once read. Such a
    /// file is read and parsed once and kept until its last use; a file used once is not kept.
    pub(super) shared_meshes: std::cell::RefCell<BTreeMap<PathBuf, (usize, Option<LoadedMesh>)>>,
    /// Meshes given in memory, by the name a shape's `file` gives
    /// ([`parse_scene_with_meshes`](super::parse_scene_with_meshes)).
    pub(super) in_memory: &'a BTreeMap<String, LoadedMesh>,
}

pub(super) type Result<T> = std::result::Result<T, SceneFileError>;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RotateDoc {
    pub(super) axis: [f32; 3],
    pub(super) angle: f32,
}

impl<F: Fn(Option<Range<usize>>, String) -> SceneFileError> Builder<'_, F> {
    /// Fails at `span` of the file with `message`.
    pub(super) fn error<T>(&self, span: Range<usize>, message: impl Into<String>) -> Result<T> {
        Err((self.at)(Some(span), message.into()))
    }

    /// `scale`, then `rotate`, then `translate`, then `to_world`, those given: in the file's
    /// y-up frame.
    pub(super) fn placement(
        &self,
        scale: Option<&Spanned<toml::Value>>,
        rotate: Option<&RotateDoc>,
        translate: Option<[f32; 3]>,
        to_world: Option<[[f32; 4]; 4]>,
    ) -> Result<Affine3A> {
        let mut transform = Affine3A::IDENTITY;
        if let Some(scale) = scale {
            let factors = match scale.get_ref() {
                toml::Value::Float(f) => Vec3::splat(*f as f32),
                toml::Value::Integer(i) => Vec3::splat(*i as f32),
                toml::Value::Array(a) if a.len() == 3 => {
                    let mut v = [0.0f32; 3];
                    for (slot, x) in v.iter_mut().zip(a) {
                        *slot = match x {
                            toml::Value::Float(f) => *f as f32,
                            toml::Value::Integer(i) => *i as f32,
                            _ => return self.error(scale.span(), "scale: expected numbers"),
                        };
                    }
                    Vec3::from_array(v)
                }
                _ => return self.error(scale.span(), "scale: expected a number or [x, y, z]"),
            };
            if !factors.is_finite() || factors.cmpeq(Vec3::ZERO).any() {
                return self
                    .error(scale.span(), format!("scale {factors} must be finite and not zero"));
            }
            transform = Affine3A::from_scale(factors);
        }
        if let Some(rotate) = rotate {
            let axis = Vec3::from_array(rotate.axis).normalize_or_zero();
            if axis == Vec3::ZERO || !rotate.angle.is_finite() {
                return (Err((self.at)(
                    None,
                    "rotate needs a non-zero axis and a finite angle (degrees)".into(),
                )))?;
            }
            transform = Affine3A::from_axis_angle(axis, rotate.angle.to_radians()) * transform;
        }
        if let Some(t) = translate {
            transform = Affine3A::from_translation(Vec3::from_array(t)) * transform;
        }
        if let Some(m) = to_world {
            // Rows as written; glam is column-major.
            let matrix = Mat4::from_cols_array_2d(&m).transpose();
            let last = matrix.row(3);
            if !matrix.is_finite() || last != glam::Vec4::W || matrix.determinant() == 0.0 {
                return Err((self.at)(
                    None,
                    "to_world must be a finite, invertible affine matrix (last row 0 0 0 1)".into(),
                ));
            }
            transform = Affine3A::from_mat4(matrix) * transform;
        }
        Ok(transform)
    }
}
