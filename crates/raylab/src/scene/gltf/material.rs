//! glTF materials: the metallic-roughness material and its textures, read into
//! [`MeshMaterial`]s, and the file's images, each decoded once per colour space.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use glam::{Affine2, Vec2, Vec3};

use super::super::mesh_file::quoted;
use crate::material::{AlphaMask, MaterialTextures, NormalMap};
use crate::mesh::{MeshMaterial, PbrParameters};
use crate::texture::{ImageTexture, Texture, TextureImage, Wrap, decode_texture, load_texture};

/// The materials of `document` (found at `path`), their textures read from `images`. A texture
/// that cannot be used (a missing or broken image, a second set of texture coordinates) is left
/// out with a warning naming the material: the model still loads.
pub(super) fn read_materials(
    images: &mut Images,
    document: &gltf::Document,
    path: &Path,
    warnings: &mut Vec<String>,
) -> Vec<MeshMaterial> {
    document
        .materials()
        .map(|m| {
            let pbr = m.pbr_metallic_roughness();
            let [r, g, b, a] = pbr.base_color_factor();
            let strength = m.emissive_strength().unwrap_or(1.0);
            let name = m
                .name()
                .map_or_else(|| format!("material {}", m.index().unwrap_or(0)), str::to_string);
            let mut textures = MaterialTextures::default();
            let mut read = |info: Option<gltf::texture::Info>, what: &str, srgb: bool| {
                let info = info?;
                let transform = info.texture_transform().map(UvTransform::from_info);
                match images.texture(&info.texture(), info.tex_coord(), transform, srgb) {
                    Ok(texture) => Some(texture),
                    Err(error) => {
                        warnings.push(format!(
                            "{}: material {}: its {what} texture is ignored: {error}",
                            path.display(),
                            quoted(&name)
                        ));
                        None
                    }
                }
            };
            textures.base_color = read(pbr.base_color_texture(), "base colour", true);
            textures.metallic_roughness =
                read(pbr.metallic_roughness_texture(), "metallic-roughness", false);
            // Only read where something emits: the texture multiplies emissiveFactor.
            if m.emissive_factor().iter().any(|&e| e > 0.0) {
                textures.emission = read(m.emissive_texture(), "emissive", true);
            }
            match m.alpha_mode() {
                gltf::material::AlphaMode::Opaque => {}
                gltf::material::AlphaMode::Mask => {
                    let cutoff = m.alpha_cutoff().unwrap_or(0.5);
                    textures.alpha_mask = Some(AlphaMask { cutoff, factor: a });
                }
                gltf::material::AlphaMode::Blend => warnings.push(format!(
                    "{}: material {}: alphaMode BLEND is rendered opaque (MASK cuts out)",
                    path.display(),
                    quoted(&name)
                )),
            }
            if let Some(normal) = m.normal_texture() {
                // The `gltf` crate reads KHR_texture_transform only on a `textureInfo`; a
                // normal texture's is read from its JSON.
                let texture = normal
                    .extension_value("KHR_texture_transform")
                    .map(UvTransform::from_json)
                    .transpose()
                    .and_then(|transform| {
                        images.texture(&normal.texture(), normal.tex_coord(), transform, false)
                    });
                match texture {
                    Ok(texture) => {
                        textures.normal = Some(NormalMap { texture, scale: normal.scale() })
                    }
                    Err(error) => warnings.push(format!(
                        "{}: material {}: its normal texture is ignored: {error}",
                        path.display(),
                        quoted(&name)
                    )),
                }
            }
            // KHR_materials_ior allows 0 (an old exporter's "not set") and asks for at least 1
            // otherwise: a glass needs a finite index of at least 1.
            let ior = match m.ior() {
                None => 1.5,
                Some(ior) if ior.is_finite() && ior >= 1.0 => ior,
                Some(ior) => {
                    warnings.push(format!(
                        "{}: material {}: ior {ior} is not a refractive index; 1.5 is used",
                        path.display(),
                        quoted(&name)
                    ));
                    1.5
                }
            };
            MeshMaterial {
                diffuse: Vec3::new(r, g, b),
                emission: Vec3::from_array(m.emissive_factor()) * strength,
                textures,
                pbr: Some(PbrParameters {
                    metallic: pbr.metallic_factor(),
                    roughness: pbr.roughness_factor(),
                    transmission: m.transmission().map_or(0.0, |t| t.transmission_factor()),
                    ior,
                }),
                name,
            }
        })
        .collect()
}

/// The file's images, decoded as materials ask for them, each once per colour space.
pub(super) struct Images<'a> {
    /// Where relative URIs point.
    folder: &'a Path,
    buffers: &'a [gltf::buffer::Data],
    decoded: HashMap<(usize, bool), Arc<TextureImage>>,
    /// Images found broken before the `gltf` crate reads them, with the reason.
    broken: HashMap<usize, String>,
}

impl<'a> Images<'a> {
    /// The images of a file whose buffers are `buffers`, relative URIs found in `folder`;
    /// `broken` names the images found broken before the `gltf` crate reads them.
    pub(super) fn new(
        folder: &'a Path,
        buffers: &'a [gltf::buffer::Data],
        broken: HashMap<usize, String>,
    ) -> Self {
        Images { folder, buffers, decoded: HashMap::new(), broken }
    }

    /// A material's texture: its image (sRGB colour or linear data), sampler and transform.
    fn texture(
        &mut self,
        texture: &gltf::Texture,
        tex_coord: u32,
        transform: Option<UvTransform>,
        srgb: bool,
    ) -> Result<Texture, String> {
        let tex_coord = transform.and_then(|t| t.tex_coord).unwrap_or(tex_coord);
        if tex_coord != 0 {
            return Err(format!("it reads TEXCOORD_{tex_coord}, and only TEXCOORD_0 is read"));
        }
        let source = texture.source();
        let key = (source.index(), srgb);
        let image = match self.decoded.get(&key) {
            Some(image) => image.clone(),
            None => {
                let image = Arc::new(self.decode(&source, srgb)?);
                self.decoded.insert(key, image.clone());
                image
            }
        };
        let sampler = texture.sampler();
        let wrap = |mode| match mode {
            gltf::texture::WrappingMode::ClampToEdge => Wrap::Clamp,
            gltf::texture::WrappingMode::MirroredRepeat => Wrap::Mirror,
            gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
        };
        let mut texture = ImageTexture::new(image);
        texture.wrap = [wrap(sampler.wrap_s()), wrap(sampler.wrap_t())];
        if let Some(t) = transform {
            texture.transform = t.matrix();
            if !texture.transform.is_finite() {
                return Err("its KHR_texture_transform is not finite".into());
            }
        }
        Ok(Texture::Image(texture))
    }

    /// Decodes image `source` from its buffer view, data URI or file.
    fn decode(&self, source: &gltf::Image, srgb: bool) -> Result<TextureImage, String> {
        if let Some(problem) = self.broken.get(&source.index()) {
            return Err(problem.clone());
        }
        let name =
            source.name().map_or_else(|| format!("image {}", source.index()), str::to_string);
        match source.source() {
            gltf::image::Source::View { view, .. } => {
                let buffer = self.buffers.get(view.buffer().index()).ok_or("no buffer")?;
                let bytes = buffer
                    .0
                    .get(view.offset()..view.offset().saturating_add(view.length()))
                    .ok_or_else(|| format!("{name}: its buffer view lies outside its buffer"))?;
                decode_texture(&name, bytes, srgb).map_err(|e| format!("{name}: {e}"))
            }
            gltf::image::Source::Uri { uri, .. } => {
                if let Some(data) = uri.strip_prefix("data:") {
                    let (_, encoded) = data
                        .split_once(";base64,")
                        .ok_or_else(|| format!("{name}: a data URI that is not base64"))?;
                    let bytes = base64::decode(encoded)
                        .map_err(|e| format!("{name}: its base64 data is broken: {e}"))?;
                    return decode_texture(&name, &bytes, srgb).map_err(|e| format!("{name}: {e}"));
                }
                let relative = urlencoding::decode(uri).map_err(|e| format!("{uri}: {e}"))?;
                load_texture(&self.folder.join(relative.as_ref()), srgb).map_err(|e| e.to_string())
            }
        }
    }
}

/// `KHR_texture_transform` on a texture reference: an offset, a rotation (radians) and a
/// scale, and the set of texture coordinates it reads instead of the reference's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct UvTransform {
    offset: [f32; 2],
    rotation: f32,
    scale: [f32; 2],
    tex_coord: Option<u32>,
}

impl UvTransform {
    /// As the `gltf` crate reads it on a `textureInfo`.
    fn from_info(t: gltf::texture::TextureTransform) -> Self {
        UvTransform {
            offset: t.offset(),
            rotation: t.rotation(),
            scale: t.scale(),
            tex_coord: t.tex_coord(),
        }
    }

    /// From the extension's JSON object, with the specification's defaults (no offset, no
    /// rotation, unit scale) for what it leaves out.
    fn from_json(value: &gltf::json::Value) -> Result<Self, String> {
        let bad = |what: &str| format!("its KHR_texture_transform's {what}");
        let object = value.as_object().ok_or_else(|| bad("value is not an object"))?;
        let pair = |key: &str, default: [f32; 2]| match object.get(key) {
            None => Ok(default),
            Some(value) => match value.as_array().map(Vec::as_slice) {
                Some([x, y]) => match (x.as_f64(), y.as_f64()) {
                    (Some(x), Some(y)) => Ok([x as f32, y as f32]),
                    _ => Err(bad(&format!("{key} is not two numbers"))),
                },
                _ => Err(bad(&format!("{key} is not two numbers"))),
            },
        };
        let rotation = match object.get("rotation") {
            None => 0.0,
            Some(value) => value.as_f64().ok_or_else(|| bad("rotation is not a number"))? as f32,
        };
        let tex_coord = match object.get("texCoord") {
            None => None,
            Some(value) => Some(
                value
                    .as_u64()
                    .and_then(|set| u32::try_from(set).ok())
                    .ok_or_else(|| bad("texCoord is not a set number"))?,
            ),
        };
        Ok(UvTransform {
            offset: pair("offset", [0.0, 0.0])?,
            rotation,
            scale: pair("scale", [1.0, 1.0])?,
            tex_coord,
        })
    }

    /// The matrix, translation × rotation × scale, with its rotation turning counter-clockwise
    /// in texture space (the extension's `[cos sin; −sin cos]`).
    fn matrix(&self) -> Affine2 {
        let (sin, cos) = self.rotation.sin_cos();
        Affine2::from_cols(
            Vec2::new(cos, -sin) * self.scale[0],
            Vec2::new(sin, cos) * self.scale[1],
            Vec2::from_array(self.offset),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_transform_reads_from_json_with_the_specification_s_defaults() {
        let json =
            |text: &str| gltf::json::deserialize::from_str::<gltf::json::Value>(text).unwrap();
        let full = UvTransform::from_json(&json(
            r#"{"offset": [0.5, -1], "rotation": 1.5, "scale": [2, 3], "texCoord": 1}"#,
        ));
        let expected = UvTransform {
            offset: [0.5, -1.0],
            rotation: 1.5,
            scale: [2.0, 3.0],
            tex_coord: Some(1),
        };
        assert_eq!(full, Ok(expected));
        let empty = UvTransform::from_json(&json("{}")).unwrap();
        assert_eq!(empty.matrix(), Affine2::IDENTITY);
        assert_eq!(empty.tex_coord, None);
        for (text, complaint) in [
            ("[1, 2]", "value is not an object"),
            (r#"{"offset": [1]}"#, "offset is not two numbers"),
            (r#"{"scale": ["a", 1]}"#, "scale is not two numbers"),
            (r#"{"rotation": null}"#, "rotation is not a number"),
            (r#"{"texCoord": -1}"#, "texCoord is not a set number"),
        ] {
            let error = UvTransform::from_json(&json(text)).unwrap_err();
            assert!(error.ends_with(complaint), "{text}: {error}");
        }
    }

    /// A quarter turn with scale (2, 1) and offset (1, 0): u = (1, 0) goes to (1, 0) + 2·(0, −1).
    #[test]
    fn the_matrix_is_translation_rotation_scale() {
        let t = UvTransform {
            offset: [1.0, 0.0],
            rotation: std::f32::consts::FRAC_PI_2,
            scale: [2.0, 1.0],
            tex_coord: None,
        };
        let moved = t.matrix().transform_point2(Vec2::X);
        assert!(moved.abs_diff_eq(Vec2::new(1.0, -2.0), 1e-6), "{moved}");
    }
}
