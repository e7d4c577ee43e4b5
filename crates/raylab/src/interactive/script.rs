//! The scripted camera path of `raylab view --headless`: which keys are held at each frame, so
//! that a benchmark of the window's frames shows a new view (and new shadows) every frame, the
//! same on every machine.

use super::controller::Motion;

/// Simulated frames per second of the headless path.
pub const HEADLESS_FPS: u32 = 60;

/// The keys the headless path holds from frame `frame` to the next (at 60 frames per second): the
/// camera swings its yaw ±20° while moving forward and back, and the light sweeps left and
/// right, so that every frame shows a new view (and new shadows).
pub fn scripted_motions(frame: u32) -> [(Motion, bool); 6] {
    // 60°/s: right for ⅓ s (0 → 20°), left for ⅔ s (→ −20°), right for ⅓ s (→ 0), over again.
    let swing = frame % 80;
    let turn_right = !(20..60).contains(&swing);
    let forward = frame % 120 < 60;
    let light_right = forward;
    [
        (Motion::TurnRight, turn_right),
        (Motion::TurnLeft, !turn_right),
        (Motion::Forward, forward),
        (Motion::Back, !forward),
        (Motion::LightRight, light_right),
        (Motion::LightLeft, !light_right),
    ]
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use super::*;
    use crate::interactive::{Controller, Pose};

    #[test]
    fn the_scripted_path_swings_and_returns() {
        let mut c = Controller::new(
            Pose { position: glam::Vec3::ZERO, yaw: 0.0, pitch: 0.0, light: glam::Vec3::ZERO },
            1.0,
        );
        let mut max_yaw = 0.0f32;
        for frame in 0..=240 {
            let at = Duration::from_secs(frame as u64) / HEADLESS_FPS;
            for (motion, held) in scripted_motions(frame) {
                if held { c.press(motion, at) } else { c.release(motion, at) }
            }
            c.advance(at);
            max_yaw = max_yaw.max(c.pose().yaw.abs());
        }
        // Four seconds: three whole swings, two forward-and-back and light sweeps.
        assert!((max_yaw - 20f32.to_radians()).abs() < 0.02, "{}", max_yaw.to_degrees());
        assert!(c.pose().yaw.abs() < 0.02, "{}", c.pose().yaw);
        assert!(
            c.pose().position.length() < 0.05 && c.pose().light.length() < 0.05,
            "{:?}",
            c.pose()
        );
    }
}
