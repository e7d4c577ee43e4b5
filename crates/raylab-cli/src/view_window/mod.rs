//! The window of `raylab view`: winit for events, softbuffer for pixels, no GPU.
//!
//! Two threads. The event loop (this thread) turns input into the controller's pose and shows
//! finished frames; a render thread renders the latest view with the library's frame function
//! and hands each frame over. Input never waits for a frame: the event loop only copies pixels.

use std::collections::VecDeque;
use std::num::NonZeroU32;
use std::rc::Rc;
use std::sync::{Condvar, Mutex};
use std::time::{Duration, Instant};

use anyhow::{Result, anyhow, bail};
use raylab::Stage;
use raylab::interactive::ViewMode;
use raylab::interactive::{Controller, Motion, View};
use winit::application::ApplicationHandler;
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

mod render_thread;

use render_thread::{Frame, FrameReady, QuitOnDrop, Shared, State, render_thread};

use crate::screenshot::{next_screenshot_path, save_screenshot};
use crate::view_session::{KEYS_HELP, Session};

/// Touchpad scrolling changes the speed by a step per this many pixels.
const WHEEL_STEP_PIXELS: f64 = 60.0;

/// While keys are held, the pose is brought up to date at least this often.
const TICK: Duration = Duration::from_millis(4);

/// Fails with advice when there is no display to open a window on.
pub fn check_display() -> Result<()> {
    let set = |name: &str| std::env::var_os(name).is_some_and(|value| !value.is_empty());
    if !set("DISPLAY") && !set("WAYLAND_DISPLAY") && !set("WAYLAND_SOCKET") {
        bail!(
            "cannot open a window: there is no display (neither DISPLAY nor WAYLAND_DISPLAY is \
             set); use `raylab view --headless` to render without a window"
        );
    }
    Ok(())
}

/// Opens the window and runs until it is closed.
pub fn run(session: Session) -> Result<()> {
    check_display()?;
    let event_loop = EventLoop::<FrameReady>::with_user_event().build().map_err(|error| {
        let display = std::env::var("WAYLAND_DISPLAY")
            .or_else(|_| std::env::var("DISPLAY"))
            .unwrap_or_default();
        // winit says "os error at FILE:LINE: MESSAGE"; users need the message.
        let error = error.to_string();
        let error = error
            .strip_prefix("os error at ")
            .and_then(|rest| rest.split_once(": "))
            .map_or(error.as_str(), |(_, message)| message);
        anyhow!(
            "cannot open a window on display '{display}': {error}; use `raylab view --headless` \
             to render without a window"
        )
    })?;
    let shared = Shared {
        state: Mutex::new(State {
            view: session.view,
            ready: None,
            spare: Vec::new(),
            quit: false,
            error: None,
        }),
        changed: Condvar::new(),
    };
    let proxy = event_loop.create_proxy();
    let mut app = App::new(&session, &shared);
    let result = std::thread::scope(|scope| {
        let renderer = scope.spawn(|| render_thread(&session, &shared, proxy));
        // However the event loop ends, even by a panic, the render thread is told to stop
        // before the scope waits for it.
        let _quit = QuitOnDrop(&shared);
        let result = event_loop.run_app(&mut app);
        // Close the window now rather than after the frame in flight.
        app.screen = None;
        shared.quit();
        if renderer.join().is_err() {
            shared.lock().error.get_or_insert_with(|| "the render thread failed".into());
        }
        result
    });
    if let Some(error) = app.error.take() {
        return Err(error);
    }
    if let Some(error) = shared.lock().error.take() {
        bail!("{error}");
    }
    result.map_err(|error| anyhow!("the window's event loop failed: {error}"))?;
    // --screenshot without --exit-after-frames: the picture shown when the window closed.
    if let Some(path) = session.screenshot
        && !app.screenshot_written
    {
        app.screenshot_to(path)?;
    }
    Ok(())
}

/// The window and what is shown in it.
struct Screen {
    window: Rc<Window>,
    surface: softbuffer::Surface<Rc<Window>, Rc<Window>>,
}

struct App<'a> {
    session: &'a Session<'a>,
    shared: &'a Shared,
    controller: Controller,
    screen: Option<Screen>,
    start: Instant,
    /// The view as the event loop last sent it.
    view: View,
    /// The frame on screen, or about to be: see `unpresented`.
    shown: Option<Frame>,
    /// `shown` is waiting for the window to be redrawn (winit's `RedrawRequested`, which paces
    /// frames to the compositor on Wayland).
    unpresented: bool,
    frames_shown: u32,
    screenshot_written: bool,
    /// Wheel motion in pixels (touchpads) not yet turned into speed steps.
    wheel_pixels: f64,
    /// When recent frames were shown, for frames per second.
    recent: VecDeque<Instant>,
    cursor: Option<PhysicalPosition<f64>>,
    dragging: bool,
    error: Option<anyhow::Error>,
}

impl<'a> App<'a> {
    fn new(session: &'a Session<'a>, shared: &'a Shared) -> Self {
        App {
            session,
            shared,
            controller: session.controller.clone(),
            screen: None,
            start: Instant::now(),
            view: session.view,
            shown: None,
            unpresented: false,
            frames_shown: 0,
            screenshot_written: false,
            wheel_pixels: 0.0,
            recent: VecDeque::new(),
            cursor: None,
            dragging: false,
            error: None,
        }
    }

    /// Time since the window opened: the controller's clock.
    fn now(&self) -> Duration {
        self.start.elapsed()
    }

    /// Sends the view to the render thread.
    fn publish_view(&self) {
        self.shared.lock().view = self.view;
        self.shared.changed.notify_all();
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, error: anyhow::Error) {
        self.error.get_or_insert(error);
        event_loop.exit();
    }

    fn create_screen(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let attributes = Window::default_attributes()
            .with_title("raylab")
            .with_inner_size(PhysicalSize::new(self.view.width, self.view.height));
        let window = Rc::new(
            event_loop
                .create_window(attributes)
                .map_err(|error| anyhow!("cannot open a window: {error}"))?,
        );
        let context = softbuffer::Context::new(window.clone())
            .map_err(|error| anyhow!("cannot draw in the window: {error}"))?;
        let surface = softbuffer::Surface::new(&context, window.clone())
            .map_err(|error| anyhow!("cannot draw in the window: {error}"))?;
        self.screen = Some(Screen { window, surface });
        Ok(())
    }

    /// Copies the frame on screen into the window.
    fn present(&mut self) -> Result<()> {
        let (Some(screen), Some(frame)) = (&mut self.screen, &self.shown) else {
            return Ok(());
        };
        let (Some(width), Some(height)) =
            (NonZeroU32::new(frame.width), NonZeroU32::new(frame.height))
        else {
            return Ok(());
        };
        let draw_error =
            |error: softbuffer::SoftBufferError| anyhow!("cannot draw in the window: {error}");
        screen.surface.resize(width, height).map_err(draw_error)?;
        let mut buffer = screen.surface.buffer_mut().map_err(draw_error)?;
        buffer.copy_from_slice(&frame.words);
        screen.window.pre_present_notify();
        buffer.present().map_err(draw_error)
    }

    /// Takes the render thread's finished frame, if the one before it has been presented, and
    /// asks for a redraw to present it. A frame of a size the window no longer has is dropped.
    fn take_ready_frame(&mut self, event_loop: &ActiveEventLoop) {
        if event_loop.exiting() || self.unpresented {
            // Frames can still arrive after `exit`: the last one shown must stay the last.
            return;
        }
        let frame = {
            let mut state = self.shared.lock();
            if let Some(error) = state.error.take() {
                drop(state);
                self.fail(event_loop, anyhow!(error));
                return;
            }
            let Some(frame) = state.ready.take() else {
                return;
            };
            if (frame.width, frame.height) != (self.view.width, self.view.height) {
                state.spare = frame.words;
                drop(state);
                self.shared.changed.notify_all();
                return;
            }
            // The previous frame's memory goes back for reuse.
            if let Some(old) = self.shown.take() {
                state.spare = old.words;
            }
            frame
        };
        self.shared.changed.notify_all();
        self.shown = Some(frame);
        self.unpresented = true;
        if let Some(screen) = &self.screen {
            screen.window.request_redraw();
        }
    }

    /// Presents the frame taken last, then handles --exit-after-frames (or a finished picture
    /// that will get no more frames) and takes the next frame if one is ready.
    fn redraw(&mut self, event_loop: &ActiveEventLoop) {
        if let Err(error) = self.present() {
            return self.fail(event_loop, error);
        }
        if !std::mem::take(&mut self.unpresented) {
            return; // Shown again after being uncovered: not a new frame.
        }
        self.frames_shown += 1;
        let now = Instant::now();
        self.recent.push_back(now);
        while self.recent.front().is_some_and(|&t| now - t > Duration::from_secs(1)) {
            self.recent.pop_front();
        }
        self.update_title();
        if let Some(limit) = self.session.exit_after_frames {
            let info = &self.shown.as_ref().expect("a frame was presented").info;
            // A finished picture gets no more frames: it is the last one.
            let finished = !info.moving && info.samples >= self.session.max_spp;
            if self.frames_shown >= limit || finished {
                if let Some(path) = self.session.screenshot
                    && let Err(error) = self.screenshot_to(path)
                {
                    return self.fail(event_loop, error);
                }
                return event_loop.exit();
            }
        }
        self.take_ready_frame(event_loop);
    }

    fn update_title(&self) {
        let (Some(screen), Some(frame)) = (&self.screen, &self.shown) else {
            return;
        };
        let info = &frame.info;
        let fps = self.recent.len().saturating_sub(1) as f64
            / self
                .recent
                .back()
                .zip(self.recent.front())
                .map_or(0.0, |(last, first)| (*last - *first).as_secs_f64())
                .max(1e-9);
        let resolution =
            if info.scale > 1 { format!(" at 1/{}", info.scale) } else { String::new() };
        let state = if info.samples >= self.session.max_spp { " (done)" } else { "" };
        screen.window.set_title(&format!(
            "raylab — {} — {:.0} fps, {:.1} ms/frame, {} spp{resolution}{state} — {} — \
             arrows move/turn, PgUp/PgDn up/down, WASDQE light, drag look, +/- speed, 1-5 stage, \
             6-9 path/albedo/normals/depth, \
             P screenshot, R reset, H keys, Esc quit",
            self.session.scene.name,
            if self.recent.len() > 1 { fps } else { 0.0 },
            info.render_time.as_secs_f64() * 1e3,
            info.samples,
            self.view.mode,
        ));
    }

    /// Writes the frame on screen to `path`.
    fn screenshot_to(&mut self, path: &std::path::Path) -> Result<()> {
        let Some(frame) = &self.shown else {
            bail!("cannot write the screenshot {}: no frame was shown", path.display());
        };
        save_screenshot(path, &frame.words, frame.width, frame.height)?;
        if Some(path) == self.session.screenshot {
            self.screenshot_written = true;
        }
        println!(
            "screenshot: {} ({}×{}, {} samples per pixel)",
            path.display(),
            frame.width,
            frame.height,
            frame.info.samples
        );
        Ok(())
    }

    fn key(&mut self, event_loop: &ActiveEventLoop, code: KeyCode, pressed: bool, repeat: bool) {
        let now = self.now();
        if let Some(motion) = motion_for(code) {
            if pressed {
                self.controller.press(motion, now);
            } else {
                self.controller.release(motion, now);
            }
            return;
        }
        if !pressed
            || repeat
                && !matches!(
                    code,
                    KeyCode::Equal | KeyCode::Minus | KeyCode::NumpadAdd | KeyCode::NumpadSubtract
                )
        {
            return;
        }
        match code {
            KeyCode::Escape => event_loop.exit(),
            KeyCode::KeyR => self.controller.reset(now),
            KeyCode::Equal | KeyCode::NumpadAdd => self.controller.faster(now),
            KeyCode::Minus | KeyCode::NumpadSubtract => self.controller.slower(now),
            KeyCode::KeyH | KeyCode::F1 => println!("{KEYS_HELP}"),
            KeyCode::KeyP | KeyCode::F12 => {
                let result = next_screenshot_path().and_then(|path| self.screenshot_to(&path));
                if let Err(error) = result {
                    // Not worth closing the window for: say so and go on.
                    eprintln!("raylab: error: {error:#}");
                }
            }
            _ => {
                if let Some(mode) = mode_for(code) {
                    self.view.mode = mode;
                    self.publish_view();
                }
            }
        }
    }
}

/// The held motion a key drives, as in the lab: arrows for the camera, W/S/A/D/Q/E for the light.
fn motion_for(code: KeyCode) -> Option<Motion> {
    Some(match code {
        KeyCode::ArrowUp => Motion::Forward,
        KeyCode::ArrowDown => Motion::Back,
        KeyCode::ArrowLeft => Motion::TurnLeft,
        KeyCode::ArrowRight => Motion::TurnRight,
        KeyCode::PageUp => Motion::Up,
        KeyCode::PageDown => Motion::Down,
        KeyCode::KeyW => Motion::LightForward,
        KeyCode::KeyS => Motion::LightBack,
        KeyCode::KeyA => Motion::LightLeft,
        KeyCode::KeyD => Motion::LightRight,
        KeyCode::KeyQ => Motion::LightUp,
        KeyCode::KeyE => Motion::LightDown,
        _ => return None,
    })
}

/// What a number key shows: 1–5 the lab's stages, 6 path tracing, 7–9 albedo, normals, depth.
fn mode_for(code: KeyCode) -> Option<ViewMode> {
    let index = match code {
        KeyCode::Digit1 | KeyCode::Numpad1 => 0,
        KeyCode::Digit2 | KeyCode::Numpad2 => 1,
        KeyCode::Digit3 | KeyCode::Numpad3 => 2,
        KeyCode::Digit4 | KeyCode::Numpad4 => 3,
        KeyCode::Digit5 | KeyCode::Numpad5 => 4,
        KeyCode::Digit6 | KeyCode::Numpad6 => return Some(ViewMode::PATH),
        KeyCode::Digit7 | KeyCode::Numpad7 => return Some(ViewMode::ALBEDO),
        KeyCode::Digit8 | KeyCode::Numpad8 => return Some(ViewMode::NORMALS),
        KeyCode::Digit9 | KeyCode::Numpad9 => return Some(ViewMode::DEPTH),
        _ => return None,
    };
    Some(ViewMode::lab(Stage::ALL[index]))
}

impl ApplicationHandler<FrameReady> for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.screen.is_none()
            && let Err(error) = self.create_screen(event_loop)
        {
            self.fail(event_loop, error);
        }
    }

    fn user_event(&mut self, event_loop: &ActiveEventLoop, _: FrameReady) {
        self.take_ready_frame(event_loop);
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::RedrawRequested => self.redraw(event_loop),
            WindowEvent::Resized(size) if size.width > 0 && size.height > 0 => {
                self.view.width = size.width;
                self.view.height = size.height;
                self.publish_view();
            }
            WindowEvent::Focused(false) => {
                self.controller.release_all(self.now());
                self.dragging = false;
            }
            WindowEvent::KeyboardInput { event, .. } => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    self.key(event_loop, code, event.state == ElementState::Pressed, event.repeat);
                }
            }
            WindowEvent::MouseInput { button: MouseButton::Left, state, .. } => {
                self.dragging = state == ElementState::Pressed;
            }
            WindowEvent::CursorMoved { position, .. } => {
                if self.dragging
                    && let Some(last) = self.cursor
                {
                    let focal = self.view.focal_length_px(self.view.width);
                    let now = self.now();
                    self.controller.drag(
                        (position.x - last.x) as f32,
                        (position.y - last.y) as f32,
                        focal,
                        now,
                    );
                }
                self.cursor = Some(position);
            }
            WindowEvent::CursorLeft { .. } => self.cursor = None,
            WindowEvent::MouseWheel { delta, .. } => {
                // A notch of a wheel is a step; a touchpad's pixels count by WHEEL_STEP_PIXELS.
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y.signum() as i32 * (y != 0.0) as i32,
                    MouseScrollDelta::PixelDelta(position) => {
                        self.wheel_pixels += position.y;
                        let steps = (self.wheel_pixels / WHEEL_STEP_PIXELS).trunc();
                        self.wheel_pixels -= steps * WHEEL_STEP_PIXELS;
                        steps as i32
                    }
                };
                let now = self.now();
                for _ in 0..steps.unsigned_abs() {
                    if steps > 0 {
                        self.controller.faster(now)
                    } else {
                        self.controller.slower(now)
                    }
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let now = self.now();
        self.controller.advance(now);
        let pose = self.controller.pose();
        if pose != self.view.pose {
            self.view.pose = pose;
            self.publish_view();
        }
        // While something moves, wake up to move it on even without events.
        event_loop.set_control_flow(if self.controller.is_moving() {
            ControlFlow::WaitUntil(Instant::now() + TICK)
        } else {
            ControlFlow::Wait
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_follow_the_lab() {
        let table = [
            (KeyCode::ArrowUp, Motion::Forward),
            (KeyCode::ArrowDown, Motion::Back),
            (KeyCode::ArrowLeft, Motion::TurnLeft),
            (KeyCode::ArrowRight, Motion::TurnRight),
            (KeyCode::PageUp, Motion::Up),
            (KeyCode::PageDown, Motion::Down),
            (KeyCode::KeyW, Motion::LightForward),
            (KeyCode::KeyS, Motion::LightBack),
            (KeyCode::KeyA, Motion::LightLeft),
            (KeyCode::KeyD, Motion::LightRight),
            (KeyCode::KeyQ, Motion::LightUp),
            (KeyCode::KeyE, Motion::LightDown),
        ];
        for (code, motion) in table {
            assert_eq!(motion_for(code), Some(motion), "{code:?}");
        }
        // Every motion has its key, and no other key moves anything.
        assert!(Motion::ALL.iter().all(|m| table.iter().any(|(_, t)| t == m)));
        for code in [KeyCode::KeyR, KeyCode::KeyP, KeyCode::Escape, KeyCode::Digit1, KeyCode::Space]
        {
            assert_eq!(motion_for(code), None, "{code:?}");
        }
        let stages =
            [KeyCode::Digit1, KeyCode::Digit2, KeyCode::Digit3, KeyCode::Digit4, KeyCode::Digit5];
        for (code, stage) in stages.into_iter().zip(Stage::ALL) {
            assert_eq!(mode_for(code), Some(ViewMode::lab(stage)));
        }
        assert_eq!(mode_for(KeyCode::Numpad5), Some(ViewMode::lab(Stage::Ambient)));
        assert_eq!(mode_for(KeyCode::Digit6), Some(ViewMode::PATH));
        assert_eq!(mode_for(KeyCode::Numpad9), Some(ViewMode::DEPTH));
        assert_eq!(mode_for(KeyCode::Digit0), None);
    }
}
