//! The render thread of `raylab view`: renders the latest view whenever it is not done and
//! hands finished frames to the event loop one at a time, through the state both threads share.

use std::sync::{Condvar, Mutex, MutexGuard};
use std::time::Duration;

use raylab::interactive::{FrameInfo, FrameRenderer, View};
use winit::event_loop::EventLoopProxy;

use crate::view_session::Session;

/// A moving frame should take at most this long: 30 frames per second with room to spare.
const MOVING_BUDGET: Duration = Duration::from_millis(25);

/// A finished frame, in window words `0x00RRGGBB`.
pub(super) struct Frame {
    pub(super) words: Vec<u32>,
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) info: FrameInfo,
}

/// What the two threads share.
pub(super) struct Shared {
    pub(super) state: Mutex<State>,
    /// Wakes the render thread: a new view, a free frame slot, or quitting.
    pub(super) changed: Condvar,
}

pub(super) struct State {
    pub(super) view: View,
    /// The finished frame the event loop has not taken yet.
    pub(super) ready: Option<Frame>,
    /// A buffer to reuse for the next frame.
    pub(super) spare: Vec<u32>,
    pub(super) quit: bool,
    pub(super) error: Option<String>,
}

impl Shared {
    pub(super) fn lock(&self) -> MutexGuard<'_, State> {
        // A panic on the other thread must not turn into a second one here.
        self.state.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn wait<'a>(&self, guard: MutexGuard<'a, State>) -> MutexGuard<'a, State> {
        self.changed.wait(guard).unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Tells the render thread to stop.
    pub(super) fn quit(&self) {
        self.lock().quit = true;
        self.changed.notify_all();
    }
}

/// The event the render thread sends: a frame is ready (or the renderer failed).
#[derive(Debug)]
pub(super) struct FrameReady;

/// Tells the render thread to stop when dropped.
pub(super) struct QuitOnDrop<'a>(pub(super) &'a Shared);

impl Drop for QuitOnDrop<'_> {
    fn drop(&mut self) {
        self.0.quit();
    }
}

/// The render thread: [`render_loop`], with a panic reported to the window as an error rather
/// than leaving it waiting for frames.
pub(super) fn render_thread(session: &Session, shared: &Shared, proxy: EventLoopProxy<FrameReady>) {
    let rendered = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        render_loop(session, shared, &proxy)
    }));
    if let Err(panic) = rendered {
        let message = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        shared.lock().error = Some(format!("the render thread failed: {message}"));
        let _ = proxy.send_event(FrameReady);
    }
}

/// Renders the latest view whenever it is not done, and hands over frames one at a time.
fn render_loop(session: &Session, shared: &Shared, proxy: &EventLoopProxy<FrameReady>) {
    let mut renderer = FrameRenderer::new(Some(MOVING_BUDGET), session.max_spp);
    renderer.path_settings = session.path_settings;
    renderer.sample_settings = session.sample_settings;
    loop {
        let (view, mut words) = {
            let mut state = shared.lock();
            while !state.quit && renderer.is_done(&state.view) {
                state = shared.wait(state);
            }
            if state.quit {
                return;
            }
            (state.view, std::mem::take(&mut state.spare))
        };
        let rendered = session
            .pool
            .install(|| renderer.frame(session.scene, session.accel, &view, &mut words));
        let info = match rendered {
            Ok(info) => info,
            Err(error) => {
                shared.lock().error = Some(format!("cannot render a frame: {error}"));
                let _ = proxy.send_event(FrameReady);
                return;
            }
        };
        let frame = Frame { words, width: view.width, height: view.height, info };
        {
            let mut state = shared.lock();
            while !state.quit && state.ready.is_some() {
                state = shared.wait(state);
            }
            if state.quit {
                return;
            }
            state.ready = Some(frame);
        }
        if proxy.send_event(FrameReady).is_err() {
            return; // The event loop is gone.
        }
    }
}
