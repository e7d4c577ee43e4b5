//! `raylab`: render, view and benchmark scenes from the command line. A thin shell over the
//! `raylab` library: parse the arguments, call the library, report.

mod args;
mod bench_cmd;
mod embree_columns;
mod merge_cmd;
mod progress;
mod render_cmd;
mod render_state;
mod scene_args;
mod stats;
mod system;
mod view_cmd;
mod view_window;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// A fast, correct CPU ray tracer: the classic Cornell-box lab, done right.
#[derive(Parser, Debug)]
#[command(name = "raylab", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a scene to an image file (the lab's Cornell box by default).
    Render(render_cmd::RenderArgs),
    /// Assemble the parts of a render (`raylab render --tile I/N` or `--region`, .exr) into the
    /// whole image, exactly as a single render would have made it.
    Merge(merge_cmd::MergeArgs),
    /// Open the lab's interactive window: move the camera with the arrow keys and the light with
    /// W/S/A/D/Q/E while the picture follows in real time; still, it refines.
    View(view_cmd::ViewArgs),
    /// Measure ray-query speed on the standard ray sets (primary, shadow, diffuse), as Embree is
    /// measured (shared/bench/BENCHMARK.md).
    Bench(bench_cmd::BenchArgs),
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(error) => {
            use clap::error::ErrorKind;
            if matches!(error.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion)
                || error.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
            {
                error.exit();
            }
            // One line, like every other error: clap's first line names the problem.
            let rendered = error.to_string();
            let first = rendered.lines().next().unwrap_or("invalid arguments");
            let first = first.strip_prefix("error: ").unwrap_or(first);
            eprintln!("raylab: error: {first} (see raylab --help)");
            return ExitCode::from(2);
        }
    };
    let result = match cli.command {
        Command::Render(args) => render_cmd::run(&args),
        Command::Merge(args) => merge_cmd::run(&args),
        Command::View(args) => view_cmd::run(&args),
        Command::Bench(args) => bench_cmd::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) if error.is::<render_state::Interrupted>() => {
            eprintln!("raylab: {error}");
            ExitCode::from(render_state::INTERRUPTED_STATUS)
        }
        Err(error) => {
            // One line: the context chain joined by ": ".
            eprintln!("raylab: error: {error:#}");
            ExitCode::FAILURE
        }
    }
}
