//! MTL material libraries (beside OBJ files): `newmtl`, the diffuse colour `Kd`, the emission
//! `Ke`, and the diffuse texture `map_Kd` with its `-s` (scale), `-o` (offset) and `-clamp`
//! options. Everything else is ignored.
//!
//! Texture paths are relative to the library's folder. Files written on Windows use `\` as
//! the separator (`map_Kd .\SpiderTex.jpg`): a path not found as written is tried with `/`.
//! A texture that is missing or cannot be decoded is a warning, and the material keeps its
//! `Kd`: the model still loads.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Affine2, Vec2, Vec3};

use super::mesh_file::{quoted, read_bytes};
use crate::material::MaterialTextures;
use crate::mesh::MeshMaterial;
use crate::texture::{ImageTexture, Texture, TextureImage, Wrap, decode_texture};

/// The largest texture file read (a 8192² PNG compresses to far less).
const TEXTURE_FILE_LIMIT_BYTES: u64 = 1 << 30;

/// A `map_Kd` line: the file and how the texture is placed.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct TextureLine {
    /// Its line in the library.
    pub line: u64,
    /// The file name as written.
    pub file: String,
    /// `-s u v`: the texture coordinates are multiplied by this…
    pub scale: Vec2,
    /// …then `-o u v` added.
    pub offset: Vec2,
    /// `-clamp on`: no tiling.
    pub clamp: bool,
}

/// A library's materials, in file order, each with its `map_Kd` line if it has one. An error is
/// the line number and what was wrong.
pub(crate) type Library = Vec<(MeshMaterial, Option<TextureLine>)>;

/// Reads an MTL file's materials (see the module documentation), and the `map_Kd` lines it
/// could not read (each with its line number and what was wrong): those materials are drawn
/// untextured.
#[allow(clippy::type_complexity)]
pub(crate) fn parse_mtl(text: &[u8]) -> Result<(Library, Vec<(u64, String)>), (u64, String)> {
    let mut materials: Library = Vec::new();
    let mut ignored = Vec::new();
    for (index, raw) in text.split(|&b| b == b'\n').enumerate() {
        let number = index as u64 + 1;
        let line = String::from_utf8_lossy(raw);
        let mut words = line.split_whitespace();
        let keyword = words.next();
        if keyword == Some("newmtl") {
            let name = line.trim().get("newmtl".len()..).unwrap_or("").trim();
            if name.is_empty() {
                return Err((number, "expected a material name after `newmtl`".into()));
            }
            let material = MeshMaterial {
                name: name.into(),
                diffuse: MeshMaterial::DEFAULT_DIFFUSE,
                emission: Vec3::ZERO,
                textures: MaterialTextures::default(),
                pbr: None,
            };
            materials.push((material, None));
            continue;
        }
        let Some(keyword @ ("Kd" | "Ke" | "map_Kd")) = keyword else { continue };
        let Some((material, texture)) = materials.last_mut() else {
            return Err((number, format!("`{keyword}` before any `newmtl`")));
        };
        match keyword {
            "map_Kd" => match parse_map(number, words.collect()) {
                Ok(line) => *texture = Some(line),
                Err(message) => ignored.push((number, message)),
            },
            _ => {
                let colour = parse_colour(keyword, words).map_err(|message| (number, message))?;
                match keyword {
                    "Kd" => material.diffuse = colour,
                    _ => material.emission = colour,
                }
            }
        }
    }
    Ok((materials, ignored))
}

/// `map_Kd [options] file`: the options this loader uses (`-s`, `-o`, `-clamp`) and skips
/// (the rest of the MTL specification's), then the file name (which may hold spaces).
fn parse_map(line: u64, words: Vec<&str>) -> Result<TextureLine, String> {
    let mut texture = TextureLine {
        line,
        file: String::new(),
        scale: Vec2::ONE,
        offset: Vec2::ZERO,
        clamp: false,
    };
    let mut i = 0;
    // Up to three numbers after -s, -o, -t (u, v and an unused w).
    let numbers = |i: &mut usize| -> Vec<f32> {
        let mut values = Vec::new();
        while values.len() < 3
            && let Some(v) = words.get(*i).and_then(|w| w.parse::<f32>().ok())
        {
            values.push(v);
            *i += 1;
        }
        values
    };
    while let Some(&word) = words.get(i) {
        if !word.starts_with('-') || word.len() == 1 {
            break;
        }
        i += 1;
        match word {
            "-s" | "-o" | "-t" => {
                let values = numbers(&mut i);
                let uv = match values.as_slice() {
                    [u] => Vec2::new(*u, 1.0),
                    [u, v, ..] => Vec2::new(*u, *v),
                    _ => return Err(format!("`map_Kd {word}` needs numbers")),
                };
                if !uv.is_finite() {
                    return Err(format!("`map_Kd {word}` {uv} is not finite"));
                }
                match word {
                    "-s" => texture.scale = uv,
                    "-o" => texture.offset = uv,
                    _ => {}
                }
            }
            // `on` or `off`; anything else is the file name, not the option's value.
            "-clamp" => match words.get(i) {
                Some(&"on") => (texture.clamp, i) = (true, i + 1),
                Some(&"off") => i += 1,
                _ => {}
            },
            "-mm" => i += 2,
            "-blendu" | "-blendv" | "-bm" | "-boost" | "-cc" | "-imfchan" | "-texres" => i += 1,
            other => return Err(format!("`map_Kd`: unknown option {}", quoted(other))),
        }
    }
    texture.file = words.get(i..).unwrap_or_default().join(" ");
    if texture.file.is_empty() {
        return Err("`map_Kd` names no file".into());
    }
    Ok(texture)
}

/// `r g b`, or `r` alone for grey, as finite numbers.
fn parse_colour<'a>(keyword: &str, words: impl Iterator<Item = &'a str>) -> Result<Vec3, String> {
    let words: Vec<&str> = words.collect();
    let numbers: Option<Vec<f32>> =
        words.iter().map(|w| w.parse::<f32>().ok().filter(|v| v.is_finite())).collect();
    match numbers.as_deref() {
        Some(&[grey]) => Ok(Vec3::splat(grey)),
        Some(&[r, g, b]) => Ok(Vec3::new(r, g, b)),
        _ => Err(format!(
            "expected `{keyword} r g b` (or `{keyword} r` for grey) with finite numbers, found {}",
            quoted(&words.join(" "))
        )),
    }
}

/// Texture images read so far, by path: a file that several materials use is decoded once.
#[derive(Default)]
pub(crate) struct TextureFiles {
    images: HashMap<PathBuf, Arc<TextureImage>>,
}

impl TextureFiles {
    /// The texture a `map_Kd` line of the library at `library` describes, its file read and
    /// decoded (sRGB colour); an error is one line naming the file.
    pub(crate) fn load(&mut self, library: &Path, line: &TextureLine) -> Result<Texture, String> {
        let folder = library.parent().unwrap_or(Path::new(""));
        let written = folder.join(&line.file);
        let path = if !written.exists() && line.file.contains('\\') {
            folder.join(line.file.replace('\\', "/"))
        } else {
            written
        };
        let image = match self.images.get(&path) {
            Some(image) => image.clone(),
            None => {
                let bytes = read_bytes(&path, false, TEXTURE_FILE_LIMIT_BYTES)
                    .map_err(|e| e.to_string())?;
                let name = line.file.rsplit(['/', '\\']).next().unwrap_or(&line.file);
                let image = decode_texture(name, &bytes, true)
                    .map_err(|e| format!("{}: {e}", path.display()))?;
                let image = Arc::new(image);
                self.images.insert(path, image.clone());
                image
            }
        };
        let mut texture = ImageTexture::obj(image);
        // -s and -o act on the file's (u, v), before the flip to the image's rows.
        texture.transform *= Affine2::from_scale_angle_translation(line.scale, 0.0, line.offset);
        if line.clamp {
            texture.wrap = [Wrap::Clamp; 2];
        }
        Ok(Texture::Image(texture))
    }
}
