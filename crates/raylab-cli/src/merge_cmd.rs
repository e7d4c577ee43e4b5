//! `raylab merge`: the parts of a render assembled into the whole image.

use std::io::Write;
use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::Args;
use raylab::film::{Display, ToneMap};
use raylab::image_io::{self, ImageFormat};
use raylab::parts;

use crate::args;

#[derive(Args, Debug)]
pub struct MergeArgs {
    /// The parts: .exr files written by `raylab render --tile I/N` or `--region` with the same
    /// scene and settings, together covering every pixel once.
    #[arg(required = true, value_name = "PART")]
    parts: Vec<PathBuf>,

    /// The whole image: .exr (every channel of the parts, and their header), .pfm, or
    /// .png/.ppm (through the display transform).
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,

    /// Brightness of .png/.ppm output in stops: radiance is multiplied by 2^EV.
    #[arg(long, value_name = "EV", default_value = "0", value_parser = args::finite_f32)]
    exposure: f32,

    /// Tone mapping of .png/.ppm output: clamp, reinhard or aces.
    #[arg(long, value_name = "NAME", default_value = "clamp")]
    tonemap: ToneMap,
}

pub fn run(args: &MergeArgs) -> Result<()> {
    let format = image_io::check_writable(&args.output)?;
    // By identity, not by name: `./a.exr` and `a.exr`, or a link, are the same file.
    if let Ok(output) = std::fs::canonicalize(&args.output)
        && args.parts.iter().any(|p| std::fs::canonicalize(p).is_ok_and(|p| p == output))
    {
        bail!("{}: the output would overwrite one of the parts", args.output.display());
    }
    let parts = args.parts.iter().map(|p| parts::read_part(p)).collect::<Result<Vec<_>, _>>()?;
    let count = parts.len();
    let (header, channels) = parts::merge(parts)?;
    let (width, height) = header.image;
    if format == ImageFormat::Exr {
        parts::write_exr(&args.output, header.image, header.region, channels, Some(&header))?;
    } else {
        let film = parts::beauty(&channels, width, height).context("parts have R, G and B")?;
        drop(channels);
        // The lab's integrator shows linear values, the others sRGB-encoded.
        let srgb = !header.settings.contains("integrator=lab;");
        let display = Display { exposure: args.exposure, tone_map: args.tonemap, srgb };
        image_io::save_film(&args.output, &film, &display)?;
    }
    let report = format!(
        "{}: {width}×{height} from {} parts, {} samples per pixel\n",
        args.output.display(),
        count,
        header.samples
    );
    match std::io::stdout().lock().write_all(report.as_bytes()) {
        Err(error) if error.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(error).context("cannot print the report to standard output")
        }
        _ => Ok(()),
    }
}
