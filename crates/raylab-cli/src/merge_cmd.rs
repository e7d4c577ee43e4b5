//! `raylab merge`: the parts of a render assembled into the whole image.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use raylab::film::ToneMap;
use raylab::session;

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
    let merged = session::merge_parts(&args.parts, &args.output, args.exposure, args.tonemap)?;
    let (width, height) = merged.size;
    let report = format!(
        "{}: {width}×{height} from {} parts, {} samples per pixel\n",
        args.output.display(),
        merged.parts,
        merged.samples
    );
    crate::print_report(&report)
}
