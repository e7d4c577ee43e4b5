//! A camera as a scene describes it, independent of the image size ([`CameraSettings`]), and the
//! image axis its field of view spans ([`FovAxis`]).

use glam::Vec3;

use crate::camera::Camera;

/// A camera as a scene describes it, independent of the image size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraSettings {
    /// Position, in the lab's frame.
    pub position: Vec3,
    /// Yaw in radians (the lab's `R(y)`).
    pub yaw: f32,
    /// Pitch in radians, positive looking up.
    pub pitch: f32,
    /// Roll in radians about the view direction (see [`Camera::roll`](crate::Camera::roll)).
    pub roll: f32,
    /// The field of view in degrees, and the axis it spans.
    pub fov_deg: f32,
    /// Which image axis the field of view spans.
    pub fov_axis: FovAxis,
    /// Thin-lens radius (0: pinhole).
    pub aperture_radius: f32,
    /// Focus distance along the view direction.
    pub focus_distance: f32,
}

/// The image axis a field of view spans (Mitsuba's `fov_axis`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum FovAxis {
    /// The width.
    #[default]
    X,
    /// The height.
    Y,
    /// The shorter side.
    Smaller,
    /// The longer side.
    Larger,
}

impl CameraSettings {
    /// The camera for a `width×height` image.
    pub fn camera(&self, width: u32, height: u32) -> Camera {
        let span = match self.fov_axis {
            FovAxis::X => width,
            FovAxis::Y => height,
            FovAxis::Smaller => width.min(height),
            FovAxis::Larger => width.max(height),
        };
        Camera {
            position: self.position,
            yaw: self.yaw,
            pitch: self.pitch,
            roll: self.roll,
            focal_length_px: Camera::focal_length_for_fov(span, self.fov_deg),
            width,
            height,
            aperture_radius: self.aperture_radius,
            focus_distance: self.focus_distance,
        }
    }
}
