//! `raylab`: render, view and benchmark scenes from the command line. A thin shell over the
//! `raylab` library: parse the arguments, call the library, report.

mod args;
mod bench_cmd;
mod embree_columns;
mod headless;
mod merge_cmd;
mod progress;
mod render_cmd;
mod render_state;
mod scene_args;
mod screenshot;
mod stats;
mod system;
mod view_cmd;
mod view_session;
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
    /// measured (docs/benchmarking.md in the repository).
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
            // One line, like every other error, with all that clap says of the problem.
            eprintln!(
                "raylab: error: {} (see raylab --help)",
                one_line_usage_error(&error.to_string())
            );
            return ExitCode::from(2);
        }
    };
    // `RAYLAB_ISA` caps the kernels' instruction set (raylab::cpu); a wrong one is refused
    // before any work, not ignored.
    if let Err(error) = raylab::cpu::Isa::from_env() {
        eprintln!("raylab: error: RAYLAB_ISA: {error}");
        return ExitCode::from(2);
    }
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
            eprintln!("raylab: error: {}", one_line_error(&error));
            ExitCode::FAILURE
        }
    }
}

/// Prints a command's report to standard output. The work is done by then: a closed or full
/// standard output is not worth a failure, but it must not be a panic either (`println!`
/// would panic).
fn print_report(report: &str) -> anyhow::Result<()> {
    use std::io::Write;
    match std::io::stdout().lock().write_all(report.as_bytes()) {
        Err(error) if error.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(anyhow::Error::new(error).context("cannot print the report to standard output"))
        }
        _ => Ok(()),
    }
}

/// An error and its causes on one line, joined by ": ", each cause said once: a message that
/// already quotes its cause (`cannot read 'x.exr': No such file or directory (os error 2)`)
/// is not followed by the cause again.
fn one_line_error(error: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in error.chain() {
        let text = cause.to_string();
        if line.contains(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
}

/// clap's message for bad arguments, whole, on one line: its `error: ` prefix dropped, the
/// lines up to its usage summary joined (a line that ends in `:` runs on into the next, as in
/// "the following required arguments were not provided: --output <FILE>").
fn one_line_usage_error(rendered: &str) -> String {
    let mut line = String::new();
    for part in rendered.lines().map(str::trim).take_while(|l| !l.starts_with("Usage:")) {
        let part = part.strip_prefix("error: ").unwrap_or(part);
        if part.is_empty() {
            continue;
        }
        if !line.is_empty() {
            line.push_str(if line.ends_with(':') { " " } else { "; " });
        }
        line.push_str(part);
    }
    if line.is_empty() { "invalid arguments".to_owned() } else { line }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An error that quotes its cause in its own message, as the library's errors do.
    #[derive(Debug)]
    struct Quoting(std::io::Error);

    impl std::fmt::Display for Quoting {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(f, "cannot read 'nothere.exr': {}", self.0)
        }
    }

    impl std::error::Error for Quoting {
        fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
            Some(&self.0)
        }
    }

    #[test]
    fn a_cause_the_message_already_quotes_is_said_once() {
        let os = std::io::Error::from(std::io::ErrorKind::NotFound);
        let cause = os.to_string();
        let error = anyhow::Error::new(Quoting(os)).context("merging 2 parts");
        assert_eq!(
            one_line_error(&error),
            format!("merging 2 parts: cannot read 'nothere.exr': {cause}")
        );
        // A cause the message does not quote is kept.
        let error = anyhow::anyhow!("disk full").context("writing out.exr");
        assert_eq!(one_line_error(&error), "writing out.exr: disk full");
    }

    #[test]
    fn clap_s_whole_message_fits_on_one_line() {
        let rendered = "error: the following required arguments were not provided:\n  \
                        --output <FILE>\n\nUsage: raylab merge --output <FILE> <PARTS>...\n\n\
                        For more information, try '--help'.\n";
        assert_eq!(
            one_line_usage_error(rendered),
            "the following required arguments were not provided: --output <FILE>"
        );
        let rendered = "error: unexpected argument '--bogus' found\n\n  tip: to pass '--bogus' \
                        as a value, use '-- --bogus'\n\nUsage: raylab render [OPTIONS]\n";
        assert_eq!(
            one_line_usage_error(rendered),
            "unexpected argument '--bogus' found; tip: to pass '--bogus' as a value, use '-- --bogus'"
        );
    }
}
