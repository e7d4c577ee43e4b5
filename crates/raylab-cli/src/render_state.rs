//! What keeps a render's work: interrupts (SIGINT, SIGTERM) that end it cleanly, checkpoints
//! written as it goes, and resuming from one.
//!
//! - The first SIGINT or SIGTERM lets the passes in flight finish (a group of up to sixteen that
//!   takes about a quarter of a second; every pixel gets the same number of samples), then the
//!   image so far is written, atomically, with the samples per pixel it reached in its header,
//!   and `raylab` exits with status 130. A second signal exits at once; every file is written to
//!   a temporary name and renamed, so even then no file is left half written.
//! - `--checkpoint SECONDS` writes the sums of the samples beside the output
//!   (`NAME.checkpoint.exr`, see `raylab::parts`) at most every SECONDS, between passes, and on
//!   an interrupt. The same command run again finds it and goes on from it (a Slurm job requeued
//!   after pre-emption does just that); `raylab render --resume STATE` goes on from it with the
//!   command line recorded inside. Either way the image is the one an uninterrupted render gives,
//!   bit for bit. A finished render deletes its checkpoint.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use anyhow::{Context, Result, bail};
use raylab::parts::{self, Part, PartKind};
use serde::{Deserialize, Serialize};

/// The exit status of an interrupted render (128 + SIGINT, the shell's convention).
pub const INTERRUPTED_STATUS: u8 = 130;

/// A render that stopped at a signal, after writing what it had: `main` reports it and exits
/// with [`INTERRUPTED_STATUS`].
#[derive(Debug)]
pub struct Interrupted {
    /// What was written and how far it got, for the console.
    pub report: String,
}

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "interrupted: {}", self.report)
    }
}

impl std::error::Error for Interrupted {}

/// Set by the first SIGINT or SIGTERM; the second exits the process at once with status 130.
pub fn interrupt_flag() -> Result<Arc<AtomicBool>> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let flag = Arc::new(AtomicBool::new(false));
    for signal in [SIGINT, SIGTERM] {
        // Registered first, so that it sees the flag before the second handler sets it: on the
        // second signal it is already set, and the process exits.
        signal_hook::flag::register_conditional_shutdown(
            signal,
            INTERRUPTED_STATUS as i32,
            Arc::clone(&flag),
        )
        .context("cannot install the interrupt handler")?;
        signal_hook::flag::register(signal, Arc::clone(&flag))
            .context("cannot install the interrupt handler")?;
    }
    Ok(flag)
}

/// The command line a checkpoint records: the working directory and the arguments after
/// `render`, so that `--resume` can run the same render again.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Command {
    pub directory: PathBuf,
    pub arguments: Vec<String>,
}

impl Command {
    /// This process's command line (the arguments after the `render` subcommand).
    pub fn of_this_process() -> Result<Command> {
        let mut arguments = Vec::new();
        for argument in std::env::args_os().skip(1).skip_while(|a| a != "render").skip(1) {
            match argument.into_string() {
                Ok(a) => arguments.push(a),
                Err(a) => bail!(
                    "--checkpoint records the command line to resume, and the argument {a:?} \
                     is not UTF-8 text"
                ),
            }
        }
        let directory = std::env::current_dir()
            .context("--checkpoint records the working directory, which cannot be read")?;
        Ok(Command { directory, arguments })
    }

    /// As JSON, for a checkpoint's header.
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).expect("a command serializes")
    }

    /// From a checkpoint's header.
    pub fn from_json(state: &Path, json: &str) -> Result<Command> {
        serde_json::from_str(json).with_context(|| {
            format!("{}: its recorded command line cannot be read", state.display())
        })
    }
}

/// What checkpoint `state` records for resuming: the command line parsed again as `P` (the
/// arguments after `raylab render`), the command, and the checkpoint itself; the working
/// directory is the one the render started in.
pub fn recorded<P: clap::Parser>(state: &Path) -> Result<(P, Command, Part)> {
    let part = parts::read_part(state)?;
    if part.header.kind != PartKind::Checkpoint {
        bail!("{}: not a checkpoint (it is a finished image)", state.display());
    }
    let Some(json) = &part.header.command else {
        bail!("{}: the checkpoint records no command line to resume", state.display());
    };
    let command = Command::from_json(state, json)?;
    let recorded = P::try_parse_from(
        std::iter::once("raylab render".to_string()).chain(command.arguments.iter().cloned()),
    )
    .map_err(|e| {
        let text = e.to_string();
        anyhow::anyhow!(
            "{}: its recorded command line no longer parses: {}",
            state.display(),
            text.lines().next().unwrap_or("").trim_start_matches("error: ")
        )
    })?;
    std::env::set_current_dir(&command.directory).with_context(|| {
        format!(
            "{}: cannot go back to the directory the render started in, {}",
            state.display(),
            command.directory.display()
        )
    })?;
    Ok((recorded, command, part))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_read_back() {
        let command = Command {
            directory: "/tmp/x y".into(),
            arguments: vec!["scene.toml".into(), "--spp".into(), "8".into(), "é".into()],
        };
        assert_eq!(Command::from_json(Path::new("s"), &command.to_json()).unwrap(), command);
        let error = Command::from_json(Path::new("s.exr"), "{").unwrap_err();
        assert!(format!("{error:#}").starts_with("s.exr: its recorded command line"));
    }
}
