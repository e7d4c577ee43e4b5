//! Textures in scene files: any colour or roughness input can be a table instead of a value.
//!
//! ```toml
//! [materials.floor]
//! type = "diffuse"
//! reflectance = { texture = "marble", scale = 4, colors = [[0.9, 0.88, 0.85], [0.25, 0.22, 0.2]] }
//!
//! [materials.brushed]
//! type = "roughconductor"
//! material = "Al"
//! alpha = { texture = "clouds", scale = 8, range = [0.05, 0.4] }
//!
//! [materials.photo]
//! type = "diffuse"
//! reflectance = { texture = "wall.png", wrap = "mirror", scale = 2 }
//! ```
//!
//! `texture` names a pattern (`perlin`, `fbm`, `clouds`, `marble`, `wood`: see
//! `raylab::texture`) or an image file (`.png`, `.jpg`, beside the scene file). Patterns take
//! `scale` (noise cells per unit of length, 1), `octaves` (6, at most 16), `turbulence` (1),
//! `seed` (0) and the two ends of their blend: `colors` for colours (black to white), `range`
//! for roughness (0 to 1). Images take `scale` (repeats per unit of texture coordinates, 1),
//! `wrap` (`repeat`, `clamp` or `mirror`) and `srgb` (true for colours, false for roughness);
//! their `v` runs up from the bottom row, as OBJ's and Mitsuba's.

use std::ops::Range;
use std::sync::Arc;

use glam::{Affine2, Vec2, Vec3};
use serde::Deserialize;

use super::builder::{Builder, Result, SceneFileError};
use crate::texture::{ImageTexture, NoiseTexture, Pattern, Perlin, Texture, Wrap, load_texture};

/// A colour: three numbers or a texture.
#[derive(Deserialize)]
#[serde(untagged)]
pub(super) enum ColourDoc {
    Constant([f32; 3]),
    Texture(TextureDoc),
}

/// A number (a roughness): one number or a texture.
#[derive(Deserialize)]
#[serde(untagged)]
pub(super) enum ScalarDoc {
    Constant(f32),
    Texture(TextureDoc),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TextureDoc {
    texture: String,
    scale: Option<f32>,
    octaves: Option<u32>,
    turbulence: Option<f32>,
    seed: Option<u64>,
    colors: Option<[[f32; 3]; 2]>,
    range: Option<[f32; 2]>,
    wrap: Option<String>,
    srgb: Option<bool>,
}

impl<F: Fn(Option<Range<usize>>, String) -> SceneFileError> Builder<'_, F> {
    /// A colour input: its constant (white where a texture gives the colour) and the texture.
    pub(super) fn colour(
        &self,
        doc: &ColourDoc,
        span: &Range<usize>,
    ) -> Result<(Vec3, Option<Texture>)> {
        match doc {
            ColourDoc::Constant(c) => Ok((Vec3::from_array(*c), None)),
            ColourDoc::Texture(t) => Ok((Vec3::ONE, Some(self.texture(t, false, span)?))),
        }
    }

    /// A roughness input: its constant (or `default` where a texture gives it) and the texture.
    pub(super) fn scalar(
        &self,
        doc: &ScalarDoc,
        default: f32,
        span: &Range<usize>,
    ) -> Result<(f32, Option<Texture>)> {
        match doc {
            ScalarDoc::Constant(v) => Ok((*v, None)),
            ScalarDoc::Texture(t) => Ok((default, Some(self.texture(t, true, span)?))),
        }
    }

    fn texture(&self, doc: &TextureDoc, scalar: bool, span: &Range<usize>) -> Result<Texture> {
        let scale = doc.scale.unwrap_or(1.0);
        if !(scale.is_finite() && scale > 0.0) {
            return self.error(span.clone(), format!("texture scale {scale} must be above 0"));
        }
        if let Some(pattern) = Pattern::from_name(&doc.texture) {
            let octaves = doc.octaves.unwrap_or(6);
            if !(1..=16).contains(&octaves) {
                return self.error(span.clone(), format!("octaves {octaves}: from 1 to 16"));
            }
            let colors = match (doc.colors, doc.range, scalar) {
                (Some(c), None, false) => c.map(Vec3::from_array),
                (None, Some([a, b]), true) => [Vec3::splat(a), Vec3::splat(b)],
                (None, None, _) => [Vec3::ZERO, Vec3::ONE],
                _ if scalar => {
                    return self.error(span.clone(), "a roughness texture takes `range`");
                }
                _ => return self.error(span.clone(), "a colour texture takes `colors`"),
            };
            let turbulence = doc.turbulence.unwrap_or(1.0);
            if !colors.iter().all(|c| c.is_finite()) || !turbulence.is_finite() {
                return self.error(span.clone(), "texture colors and turbulence must be finite");
            }
            let noise = Perlin::new(doc.seed.unwrap_or(0));
            return Ok(Texture::Noise(NoiseTexture {
                pattern,
                noise,
                scale,
                octaves,
                turbulence,
                colors,
            }));
        }
        let lower = doc.texture.to_ascii_lowercase();
        if ![".png", ".jpg", ".jpeg"].iter().any(|e| lower.ends_with(e)) {
            return self.error(
                span.clone(),
                format!(
                    "unknown texture '{}': expected one of {} or an image file (.png, .jpg)",
                    doc.texture,
                    Pattern::NAMES.join(", ")
                ),
            );
        }
        let wrap = match doc.wrap.as_deref().unwrap_or("repeat") {
            "repeat" => Wrap::Repeat,
            "clamp" => Wrap::Clamp,
            "mirror" => Wrap::Mirror,
            other => {
                return self.error(
                    span.clone(),
                    format!("unknown wrap '{other}': expected repeat, clamp or mirror"),
                );
            }
        };
        let image = load_texture(&self.folder.join(&doc.texture), doc.srgb.unwrap_or(!scalar))
            .or_else(|error| self.error(span.clone(), error.to_string()))?;
        let mut texture = ImageTexture::obj(Arc::new(image));
        texture.wrap = [wrap; 2];
        texture.transform *= Affine2::from_scale(Vec2::splat(scale));
        Ok(Texture::Image(texture))
    }
}
