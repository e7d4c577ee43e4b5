//! The render's progress bar.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, RwLock};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use raylab::session::Event;

/// Renders longer than this get a progress bar (on a terminal).
const PROGRESS_AFTER: Duration = Duration::from_millis(500);

/// A progress bar that appears only on a terminal and only once a render has taken a while.
/// It counts rows rendered, or, with a time limit, milliseconds of it; either way it shows the
/// samples per second and the time left.
pub struct Progress {
    bar: ProgressBar,
    start: Instant,
    on_terminal: bool,
    shown: AtomicBool,
    rows_done: Arc<AtomicU64>,
    deadline: Option<Duration>,
}

impl Progress {
    /// A bar over `rows` rows of `width` pixels (rows of every pass), or over the time limit.
    pub fn new(rows: u64, width: u64, deadline: Option<Duration>) -> Self {
        let length = deadline.map_or(rows, |limit| limit.as_millis().max(1) as u64);
        let bar = ProgressBar::with_draw_target(Some(length), ProgressDrawTarget::hidden());
        let rows_done = Arc::new(AtomicU64::new(0));
        let start = Instant::now();
        let counted = Arc::clone(&rows_done);
        let style = ProgressStyle::with_template(
            "{bar:40} {percent}%, {samples_per_second} samples/s, {elapsed} elapsed, ~{eta} left",
        )
        .expect("the template is valid")
        .with_key(
            "samples_per_second",
            move |_: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
                let samples = counted.load(Ordering::Relaxed) as f64 * width as f64;
                let rate = samples / start.elapsed().as_secs_f64().max(1e-9);
                let _ = if rate >= 1e6 {
                    write!(w, "{:.2} M", rate / 1e6)
                } else {
                    write!(w, "{:.0} k", rate / 1e3)
                };
            },
        );
        bar.set_style(style);
        Progress {
            bar,
            start,
            on_terminal: std::io::stderr().is_terminal(),
            shown: AtomicBool::new(false),
            rows_done,
            deadline,
        }
    }

    pub fn advance(&self, rows: u32) {
        self.rows_done.fetch_add(rows as u64, Ordering::Relaxed);
        match self.deadline {
            Some(_) => self.bar.set_position(self.start.elapsed().as_millis() as u64),
            None => self.bar.inc(rows as u64),
        }
        if self.on_terminal
            && self.start.elapsed() > PROGRESS_AFTER
            && !self.shown.swap(true, Ordering::Relaxed)
        {
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
        }
    }

    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// A render job's events on the console: a progress bar per frame, and its notes (resumed,
/// already rendered, a checkpoint not written) on standard error.
#[derive(Default)]
pub struct FrameProgress {
    bar: RwLock<Option<Progress>>,
}

impl FrameProgress {
    /// Shows `event`.
    pub fn on(&self, event: Event) {
        match event {
            Event::Started { rows, row_pixels, time_limit } => {
                *self.bar.write().expect("no panic holds it") =
                    Some(Progress::new(rows, row_pixels, time_limit));
            }
            Event::Rows(rows) => {
                if let Some(bar) = &*self.bar.read().expect("no panic holds it") {
                    bar.advance(rows);
                }
            }
            Event::Finished => {
                if let Some(bar) = self.bar.write().expect("no panic holds it").take() {
                    bar.finish();
                }
            }
            Event::AlreadyRendered(output) => {
                eprintln!("raylab: {} is already rendered", output.display());
            }
            Event::Resumed { checkpoint, samples } => eprintln!(
                "raylab: going on from {} at {samples} samples per pixel",
                checkpoint.display()
            ),
            Event::CheckpointNotWritten(error) => {
                eprintln!("raylab: warning: no checkpoint written: {error}");
            }
        }
    }
}
