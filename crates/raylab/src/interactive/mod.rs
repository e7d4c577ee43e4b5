//! The pieces of `raylab view` that need no window: the camera and light [`Controller`] (key
//! presses and their durations in, a [`Pose`] out) and the [`FrameRenderer`] (a [`View`] in, a
//! progressively refined picture out). The window loop only connects them.
//!
//! ```
//! use std::time::Duration;
//! use raylab::interactive::{Controller, Motion, Pose};
//! use glam::Vec3;
//!
//! let home = Pose { position: Vec3::new(0.0, 0.0, -3.0), yaw: 0.0, pitch: 0.0, light: Vec3::ZERO };
//! let mut controller = Controller::new(home, 1.0);
//! controller.press(Motion::Forward, Duration::from_millis(100));
//! controller.release(Motion::Forward, Duration::from_millis(600));
//! assert!((controller.pose().position.z - -2.5).abs() < 1e-6);
//! ```

mod controller;
mod frame;
mod script;

pub use controller::{Controller, MAX_PITCH, Motion, Pose, SPEED_STEP, TURN_RATE};
#[cfg(feature = "io")]
pub use frame::rgb8_from_0rgb;
pub use frame::{FrameInfo, FrameRenderer, MAX_SCALE, View, ViewMode, next_scale};
pub use script::{HEADLESS_FPS, scripted_motions};
