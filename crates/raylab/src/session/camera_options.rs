//! Where the camera stands: a scene's camera with a caller's overrides.

use glam::Vec3;

use super::SessionError;
use crate::accel::Accelerator;
use crate::camera::Camera;
use crate::scene::{CameraSettings, Scene};

/// Overrides of a scene's camera, each `None` keeping the scene's (or the default's) value.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CameraOptions {
    /// Image size in pixels [default: the scene file's, else 500×500].
    pub size: Option<(u32, u32)>,
    /// Position (lab axes: x right, y down, z forward).
    pub position: Option<Vec3>,
    /// Yaw in degrees (the lab's `R(y)`).
    pub yaw_deg: Option<f32>,
    /// Pitch in degrees, positive looking up.
    pub pitch_deg: Option<f32>,
    /// Focal length in pixels.
    pub focal_length_px: Option<f32>,
    /// Horizontal field of view in degrees, where no focal length is given.
    pub fov_deg: Option<f32>,
    /// Thin-lens radius in scene units.
    pub aperture_radius: Option<f32>,
    /// Distance the lens keeps sharp [default: the scene file's, else what the image's centre
    /// sees].
    pub focus_distance: Option<f32>,
}

impl CameraOptions {
    /// The image size: the option's, else the scene file's, else 500×500.
    pub fn size(&self, scene: &Scene) -> (u32, u32) {
        self.size.or(scene.settings.size).unwrap_or((500, 500))
    }

    /// The camera of a picture of `scene`: `settings` (a scene file's camera, or an
    /// animation's at some frame; `None`: the lab's, or one framing the bounding box where
    /// `is_model`), with these overrides. A lens with no focus distance from anywhere focuses
    /// on what the image's centre sees in `accel`.
    pub fn camera(
        &self,
        settings: Option<CameraSettings>,
        scene: &Scene,
        is_model: bool,
        accel: &(impl Accelerator + ?Sized),
    ) -> Result<Camera, SessionError> {
        let (width, height) = self.size(scene);
        let base = match settings {
            Some(settings) => settings.camera(width, height),
            None => Camera::lab(width, height),
        };
        let focal_length_px = match (self.focal_length_px, self.fov_deg) {
            (Some(focal), _) => focal,
            (None, Some(fov)) => Camera::focal_length_for_fov(width, fov),
            (None, None) => base.focal_length_px,
        };
        if !focal_length_px.is_finite() {
            return Err(SessionError::Invalid(format!(
                "a field of view of {}° is too small: the focal length would be infinite",
                self.fov_deg.unwrap_or(0.0)
            )));
        }
        let default_position = match scene.bounds() {
            Some((lo, hi)) if is_model => Camera::framing(lo, hi, width, height).position,
            _ => base.position,
        };
        let mut camera = Camera {
            position: self.position.unwrap_or(default_position),
            yaw: self.yaw_deg.map_or(base.yaw, f32::to_radians),
            pitch: self.pitch_deg.map_or(base.pitch, f32::to_radians),
            roll: base.roll,
            focal_length_px,
            width,
            height,
            aperture_radius: self.aperture_radius.unwrap_or(base.aperture_radius),
            focus_distance: self.focus_distance.unwrap_or(base.focus_distance),
        };
        if camera.has_lens() && self.focus_distance.is_none() && settings.is_none() {
            // Focus on what the image's centre sees.
            let centre = camera.ray(width as f32 / 2.0, height as f32 / 2.0);
            if let Some(hit) = accel.closest_hit(&centre) {
                camera.focus_distance = (hit.t * centre.direction.dot(camera.forward())).max(1e-6);
            }
        }
        Ok(camera)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::BruteForce;

    #[test]
    fn overrides_replace_parts_of_the_camera_and_a_lens_focuses_on_the_centre() {
        let scene = Scene::built_in("cornell").unwrap();
        let accel = BruteForce::new(&scene.vertices());
        let lab = CameraOptions::default().camera(None, &scene, false, &accel).unwrap();
        assert_eq!(lab, Camera::lab(500, 500));
        let options = CameraOptions {
            size: Some((64, 32)),
            position: Some(Vec3::new(0.0, -0.5, 0.0)),
            yaw_deg: Some(90.0),
            fov_deg: Some(90.0),
            aperture_radius: Some(0.1),
            ..CameraOptions::default()
        };
        let camera = options.camera(None, &scene, false, &accel).unwrap();
        assert_eq!((camera.width, camera.height), (64, 32));
        assert!((camera.yaw - std::f32::consts::FRAC_PI_2).abs() < 1e-6);
        assert!((camera.focal_length_px - 32.0).abs() < 1e-4, "{}", camera.focal_length_px);
        // Looking along +x from the middle of the room, above the boxes: the centre ray meets
        // the side wall at x = 1 (the lab's room spans −1..1), one unit away.
        assert!((camera.focus_distance - 1.0).abs() < 1e-3, "{}", camera.focus_distance);
        let tiny = CameraOptions { fov_deg: Some(1e-40), ..CameraOptions::default() };
        let error = tiny.camera(None, &scene, false, &accel).unwrap_err().to_string();
        assert!(error.contains("is too small"), "{error}");
    }
}
