//! Catching a panic inside a dependency (a decoder, a ported C algorithm) that a hostile input
//! set off, without printing it: the caller turns it into a one-line error or a warning.

use std::cell::Cell;
use std::sync::Once;

thread_local! {
    /// Whether a panic on this thread is expected and caught, so not to be printed.
    static QUIET_PANICS: Cell<bool> = const { Cell::new(false) };
}

/// Runs `f`, returning `None` if it panicked. The panic is not printed (only on this thread: `f`
/// must not hand its work to other threads).
pub(crate) fn catch_quietly<T>(f: impl FnOnce() -> T) -> Option<T> {
    quiet_panic_hook();
    let was = QUIET_PANICS.with(|quiet| quiet.replace(true));
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    QUIET_PANICS.with(|quiet| quiet.set(was));
    result.ok()
}

/// Installs, once, a panic hook that stays silent while [`QUIET_PANICS`] is set on the
/// panicking thread and otherwise hands the panic to the hook that was there before.
fn quiet_panic_hook() {
    static INSTALL: Once = Once::new();
    INSTALL.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !QUIET_PANICS.with(Cell::get) {
                previous(info);
            }
        }));
    });
}
