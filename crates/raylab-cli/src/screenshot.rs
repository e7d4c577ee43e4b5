//! Screenshots of `raylab view`: the window's words to an image file.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use raylab::image_io;
use raylab::interactive::rgb8_from_0rgb;

/// Writes a window buffer of `0x00RRGGBB` words to an image file (whole, or not at all).
pub fn save_screenshot(path: &Path, words: &[u32], width: u32, height: u32) -> Result<()> {
    image_io::save_rgb8(path, &rgb8_from_0rgb(words, width, height))
        .with_context(|| format!("cannot write the screenshot {}", path.display()))
}

/// The first `raylab-view-N.png` in the current folder that does not exist yet.
pub fn next_screenshot_path() -> Result<PathBuf> {
    for n in 1..100_000 {
        let path = PathBuf::from(format!("raylab-view-{n}.png"));
        if !path.try_exists().unwrap_or(true) {
            return Ok(path);
        }
    }
    bail!("cannot find a free screenshot name: raylab-view-1.png to raylab-view-99999.png exist")
}
