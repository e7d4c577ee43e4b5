//! Decoding texture files: PNG (8 and 16 bits, grey or colour, with or without alpha) and JPEG,
//! through the `image` crate, with the size checked from the header before any texel is
//! allocated.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use super::image::TextureImage;
use crate::color::srgb_to_linear;
use crate::file_bytes::ReadError;

/// The longest side a texture may have, in texels.
pub const MAX_TEXTURE_SIDE: u32 = 16_384;

/// The most texels a texture may have (8192², 256 MiB at 8 bits; a 16-bit image is held as
/// floats, four times that).
pub const MAX_TEXTURE_TEXELS: u64 = 1 << 26;

/// Decodes an image file's bytes; `srgb` says whether its colour is sRGB-encoded (colour
/// textures) or linear (normal maps, roughness). `name` is for messages. Errors are one line,
/// without the name (the caller says where the texture comes from).
pub fn decode_texture(name: &str, bytes: &[u8], srgb: bool) -> Result<TextureImage, TextureError> {
    let reader = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| TextureError::Decode(format!("cannot read it: {e}")))?;
    if reader.format().is_none() {
        return Err(TextureError::Format);
    }
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_TEXTURE_SIDE);
    limits.max_image_height = Some(MAX_TEXTURE_SIDE);
    // The decoded image at 16 bits per channel, RGBA, and the decoder's own buffers.
    limits.max_alloc = Some(MAX_TEXTURE_TEXELS * 8 + (64 << 20));
    let mut reader = reader;
    reader.limits(limits);
    let decoder = reader.into_decoder().map_err(|e| TextureError::Decode(describe(&e)))?;
    let (width, height) = image::ImageDecoder::dimensions(&decoder);
    check_size(width, height)?;
    let decoded = image::DynamicImage::from_decoder(decoder)
        .map_err(|e| TextureError::Decode(describe(&e)))?;
    use image::DynamicImage as D;
    Ok(match decoded {
        D::ImageLuma8(_) | D::ImageLumaA8(_) | D::ImageRgb8(_) | D::ImageRgba8(_) => {
            let rgba = decoded.into_rgba8();
            let texels = rgba.as_raw().chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
            TextureImage::from_rgba8(name, width, height, texels, srgb)
        }
        D::ImageRgb32F(_) | D::ImageRgba32F(_) => {
            let rgba = decoded.into_rgba32f();
            let texels = rgba.as_raw().chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
            TextureImage::from_rgba_f32(name, width, height, texels)
        }
        // 16 bits (and whatever comes next): decoded to linear floats.
        _ => {
            let rgba = decoded.into_rgba16();
            let colour = |v: u16| {
                let v = f32::from(v) / 65535.0;
                if srgb { srgb_to_linear(v) } else { v }
            };
            let texels = rgba
                .as_raw()
                .chunks_exact(4)
                .map(|c| [colour(c[0]), colour(c[1]), colour(c[2]), f32::from(c[3]) / 65535.0])
                .collect();
            TextureImage::from_rgba_f32(name, width, height, texels)
        }
    })
}

/// The largest texture file [`load_texture`] reads.
pub const MAX_TEXTURE_FILE_BYTES: u64 = 1 << 30;

/// Reads and decodes an image file (see [`decode_texture`]); errors name the file.
pub fn load_texture(path: &Path, srgb: bool) -> Result<TextureImage, TextureError> {
    // At most 1 GiB (or half the memory available): more than any image within the size
    // limits takes, compressed; a bigger file is refused before it is read.
    let limit = crate::file_bytes::read_limit_bytes().min(MAX_TEXTURE_FILE_BYTES);
    let bytes = crate::file_bytes::read_bytes(path, false, limit).map_err(|e| match e {
        ReadError::Read { path, error } => TextureError::Unreadable { path, error },
        other => TextureError::File(other),
    })?;
    let name =
        path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into());
    decode_texture(&name, &bytes, srgb)
        .map_err(|e| TextureError::InFile { path: path.to_path_buf(), source: Box::new(e) })
}

/// Refuses sizes beyond [`MAX_TEXTURE_SIDE`] and [`MAX_TEXTURE_TEXELS`], and empty images.
pub fn check_size(width: u32, height: u32) -> Result<(), TextureError> {
    let texels = u64::from(width) * u64::from(height);
    if width == 0 || height == 0 {
        return Err(TextureError::Empty { width, height });
    }
    if width > MAX_TEXTURE_SIDE || height > MAX_TEXTURE_SIDE || texels > MAX_TEXTURE_TEXELS {
        return Err(TextureError::TooLarge { width, height });
    }
    Ok(())
}

/// Why an image cannot be a texture. Decoding errors name no file (the caller says where the
/// bytes come from); [`load_texture`]'s name it.
#[derive(Debug, thiserror::Error)]
pub enum TextureError {
    /// The file does not exist or cannot be read.
    #[error("{}: cannot read it: {error}", .path.display())]
    Unreadable {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        error: std::io::Error,
    },
    /// The file is larger than a texture may be.
    #[error(transparent)]
    File(ReadError),
    /// Not an image format raylab reads.
    #[error("not a PNG or JPEG image")]
    Format,
    /// A damaged image, or one over the decoder's limits.
    #[error("{0}")]
    Decode(String),
    /// An image without texels.
    #[error("an empty {width}×{height} image")]
    Empty {
        /// Its width.
        width: u32,
        /// Its height.
        height: u32,
    },
    /// More texels than a texture may have.
    #[error(
        "{width}×{height} texels is over the texture size limit ({MAX_TEXTURE_SIDE} a side, \
         {MAX_TEXTURE_TEXELS} texels in all)"
    )]
    TooLarge {
        /// Its width.
        width: u32,
        /// Its height.
        height: u32,
    },
    /// A file's image could not be decoded.
    #[error("{}: {source}", .path.display())]
    InFile {
        /// The file.
        path: PathBuf,
        /// Why.
        source: Box<TextureError>,
    },
}

/// One line from an `image` error.
fn describe(error: &image::ImageError) -> String {
    match error {
        image::ImageError::Limits(_) => format!(
            "over the texture size limit ({MAX_TEXTURE_SIDE} a side, {MAX_TEXTURE_TEXELS} texels \
             in all)"
        ),
        other => {
            let text = other.to_string();
            format!("a damaged image: {}", text.lines().next().unwrap_or("cannot decode it"))
        }
    }
}
