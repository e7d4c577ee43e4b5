//! The render's progress bar.

use std::io::IsTerminal;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

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
