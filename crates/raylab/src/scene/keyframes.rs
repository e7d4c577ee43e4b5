//! Camera keyframes: an animation's camera at any frame.
//!
//! A scene file's `[[keyframes]]` give the camera at some frames; between two of them the
//! position, field of view, aperture and focus distance are interpolated linearly, and the
//! orientation along the shortest arc between the two rotations (quaternion slerp), so that a
//! turn through ±180° of yaw does not spin the long way round. Before the first keyframe the
//! camera is the first's, after the last the last's.
//!
//! For example keyframes at frame 0 (position (0, 0, 4), yaw 0°) and frame 10 (position
//! (2, 0, 4), yaw 90°) give at frame 5 the position (1, 0, 4) and yaw 45°; at frame 2.5 yaw
//! 22.5°.

use glam::{Mat3, Quat, Vec3};

use super::camera_settings::CameraSettings;
use crate::camera::Camera;

/// The camera at one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Keyframe {
    /// The frame number.
    pub frame: u32,
    /// The camera then.
    pub camera: CameraSettings,
}

/// The camera at `frame` between `keyframes` (sorted by frame, each frame once), or `None`
/// without keyframes.
pub fn camera_at(keyframes: &[Keyframe], frame: f32) -> Option<CameraSettings> {
    let first = keyframes.first()?;
    let last = keyframes.last()?;
    if frame <= first.frame as f32 {
        return Some(first.camera);
    }
    if frame >= last.frame as f32 {
        return Some(last.camera);
    }
    let next = keyframes.iter().position(|k| k.frame as f32 > frame)?;
    let (a, b) = (&keyframes[next - 1], &keyframes[next]);
    let t = (frame - a.frame as f32) / (b.frame - a.frame) as f32;
    let (ca, cb) = (&a.camera, &b.camera);
    let lerp = |x: f32, y: f32| x + (y - x) * t;
    let rotation = rotation_of(ca).slerp(rotation_of(cb), t);
    let (yaw, pitch, roll) = yaw_pitch_roll(Mat3::from_quat(rotation));
    Some(CameraSettings {
        position: ca.position.lerp(cb.position, t),
        yaw,
        pitch,
        roll,
        fov_deg: lerp(ca.fov_deg, cb.fov_deg),
        fov_axis: ca.fov_axis,
        aperture_radius: lerp(ca.aperture_radius, cb.aperture_radius),
        focus_distance: lerp(ca.focus_distance, cb.focus_distance),
    })
}

/// The camera's rotation as a quaternion.
fn rotation_of(camera: &CameraSettings) -> Quat {
    let c = Camera { yaw: camera.yaw, pitch: camera.pitch, roll: camera.roll, ..Camera::lab(1, 1) };
    Quat::from_mat3(&c.rotation()).normalize()
}

/// Yaw, pitch and roll of a camera rotation (`R(yaw)·P(pitch)·Z(roll)`, see
/// [`Camera::rotation`]): the view direction gives yaw and pitch, the picture's up the roll.
pub(crate) fn yaw_pitch_roll(rotation: Mat3) -> (f32, f32, f32) {
    let forward = (rotation * Vec3::Z).normalize();
    let yaw = forward.x.atan2(forward.z);
    let pitch = (-forward.y).clamp(-1.0, 1.0).asin();
    // The lab's y points down: the picture's up is −y in camera space.
    let up = rotation * Vec3::NEG_Y;
    let level = Camera { yaw, pitch, ..Camera::lab(1, 1) }.rotation() * Vec3::NEG_Y;
    let roll = forward.dot(level.cross(up)).atan2(level.dot(up));
    (yaw, pitch, roll)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::FovAxis;

    fn camera(position: Vec3, yaw_deg: f32, pitch_deg: f32, roll_deg: f32) -> CameraSettings {
        CameraSettings {
            position,
            yaw: yaw_deg.to_radians(),
            pitch: pitch_deg.to_radians(),
            roll: roll_deg.to_radians(),
            fov_deg: 40.0,
            fov_axis: FovAxis::X,
            aperture_radius: 0.0,
            focus_distance: 1.0,
        }
    }

    fn near(a: f32, b: f32) -> bool {
        (a - b).abs() < 1e-4
    }

    #[test]
    fn the_documented_example() {
        let keys = [
            Keyframe { frame: 0, camera: camera(Vec3::new(0.0, 0.0, 4.0), 0.0, 0.0, 0.0) },
            Keyframe { frame: 10, camera: camera(Vec3::new(2.0, 0.0, 4.0), 90.0, 0.0, 0.0) },
        ];
        let at5 = camera_at(&keys, 5.0).unwrap();
        assert!(at5.position.abs_diff_eq(Vec3::new(1.0, 0.0, 4.0), 1e-6));
        assert!(near(at5.yaw.to_degrees(), 45.0) && near(at5.pitch, 0.0) && near(at5.roll, 0.0));
        assert!(near(camera_at(&keys, 2.5).unwrap().yaw.to_degrees(), 22.5));
        // Outside the keys: the nearest key, exactly.
        assert_eq!(camera_at(&keys, -3.0), Some(keys[0].camera));
        assert_eq!(camera_at(&keys, 10.0), Some(keys[1].camera));
        assert_eq!(camera_at(&keys, 99.0), Some(keys[1].camera));
        assert_eq!(camera_at(&[], 1.0), None);
    }

    /// Angles read back from the rotation they make, for pitches short of straight up or down.
    #[test]
    fn yaw_pitch_roll_round_trips() {
        for yaw in [-170.0f32, -90.0, -20.0, 0.0, 35.0, 120.0, 179.0] {
            for pitch in [-80.0f32, -30.0, 0.0, 10.0, 60.0] {
                for roll in [-150.0f32, -45.0, 0.0, 5.0, 90.0] {
                    let c = camera(Vec3::ZERO, yaw, pitch, roll);
                    let (y, p, r) = yaw_pitch_roll(Mat3::from_quat(rotation_of(&c)));
                    let same = |a: f32, b: f32| {
                        let d = (a - b).rem_euclid(std::f32::consts::TAU);
                        !(1e-3..=std::f32::consts::TAU - 1e-3).contains(&d)
                    };
                    assert!(
                        same(y, c.yaw) && same(p, c.pitch) && same(r, c.roll),
                        "{yaw} {pitch} {roll}: {} {} {}",
                        y.to_degrees(),
                        p.to_degrees(),
                        r.to_degrees()
                    );
                }
            }
        }
    }

    /// From yaw 170° to −170° the camera turns 20° through 180°, not 340° the other way.
    #[test]
    fn turns_take_the_shortest_arc() {
        let keys = [
            Keyframe { frame: 0, camera: camera(Vec3::ZERO, 170.0, 0.0, 0.0) },
            Keyframe { frame: 2, camera: camera(Vec3::ZERO, -170.0, 0.0, 0.0) },
        ];
        let middle = camera_at(&keys, 1.0).unwrap();
        assert!(near(middle.yaw.abs().to_degrees(), 180.0), "{}", middle.yaw.to_degrees());
    }

    /// The view direction moves evenly: at every step the same angle.
    #[test]
    fn orientation_moves_at_a_constant_rate() {
        let keys = [
            Keyframe { frame: 0, camera: camera(Vec3::ZERO, -30.0, 20.0, 10.0) },
            Keyframe { frame: 8, camera: camera(Vec3::ZERO, 60.0, -10.0, -20.0) },
        ];
        let rotation = |f: f32| {
            let c = camera_at(&keys, f).unwrap();
            rotation_of(&c)
        };
        let steps: Vec<f32> =
            (0..8).map(|f| rotation(f as f32).angle_between(rotation(f as f32 + 1.0))).collect();
        for s in &steps {
            assert!((s - steps[0]).abs() < 1e-3, "{steps:?}");
        }
    }
}
