//! The lab's pinhole camera.
//!
//! Axes as in the lab: x right, y **down**, z forward. A camera has a position, a yaw (rotation
//! about the vertical axis), a pitch (beyond the lab: looking up or down) and a focal length in
//! pixels. Pixel `(x, y)` of a `W×H` image casts the ray with direction
//! `R(yaw)·P(pitch)·(x + ½ − W/2, y + ½ − H/2, f)`, where
//! `R(y) = [[cos y, 0, sin y], [0, 1, 0], [−sin y, 0, cos y]]` (lab §"Moving the camera") and
//! `P(p) = [[1, 0, 0], [0, cos p, −sin p], [0, sin p, cos p]]` tilts the view up for `p > 0`
//! (y is down). With the lab's pitch of 0, `P` is the identity.
//!
//! The field of view follows from the focal length by `2·atan(W / 2f)`: with the lab's `f = W`
//! that is 53.13°, not the 90° that `tan` arithmetic suggests.

use std::fmt;

use glam::{Mat3, Vec2, Vec3};

use crate::ray::Ray;

/// A pinhole camera with the lab's conventions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Position of the pinhole.
    pub position: Vec3,
    /// Rotation about the vertical (y) axis, in radians; positive turns toward +x.
    pub yaw: f32,
    /// Rotation about the camera's horizontal axis, in radians; positive looks up (toward −y).
    /// The lab's camera has none.
    pub pitch: f32,
    /// Rotation about the view direction, in radians; positive turns the picture's up toward
    /// its right (the camera rolls left). The lab's camera has none.
    pub roll: f32,
    /// Focal length in pixels: the distance from the pinhole to the image plane.
    pub focal_length_px: f32,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Radius of the thin lens in scene units: 0 is a pinhole, everything sharp (the lab's).
    pub aperture_radius: f32,
    /// Distance along the view direction at which the thin lens focuses, in scene units.
    pub focus_distance: f32,
}

impl Camera {
    /// The lab's camera for a `width×height` image: at (0, 0, −3), yaw 0, and `f = width` (500 px
    /// for the lab's 500×500), which frames the Cornell box.
    pub fn lab(width: u32, height: u32) -> Self {
        Camera {
            position: Vec3::new(0.0, 0.0, -3.0),
            yaw: 0.0,
            pitch: 0.0,
            roll: 0.0,
            focal_length_px: width as f32,
            width,
            height,
            aperture_radius: 0.0,
            focus_distance: 1.0,
        }
    }

    /// The angle one pixel at the centre of the image subtends, in radians: a camera ray's
    /// cone spreads by it (texture filtering, in the `texture` module).
    #[inline]
    pub fn pixel_spread(&self) -> f32 {
        (1.0 / self.focal_length_px).atan()
    }

    /// Whether the camera has a lens of some size (depth of field), rather than a pinhole.
    #[inline]
    pub fn has_lens(&self) -> bool {
        self.aperture_radius > 0.0
    }

    /// The focal length in pixels that gives a horizontal field of view of `fov_deg` for an image
    /// `width` pixels wide: `f = W / (2·tan(fov/2))`.
    pub fn focal_length_for_fov(width: u32, fov_deg: f32) -> f32 {
        width as f32 / (2.0 * (fov_deg.to_radians() / 2.0).tan())
    }

    /// Horizontal field of view in degrees: `2·atan(W / 2f)`.
    pub fn fov_x_deg(&self) -> f32 {
        2.0 * (self.width as f32 / (2.0 * self.focal_length_px)).atan().to_degrees()
    }

    /// Vertical field of view in degrees: `2·atan(H / 2f)`.
    pub fn fov_y_deg(&self) -> f32 {
        2.0 * (self.height as f32 / (2.0 * self.focal_length_px)).atan().to_degrees()
    }

    /// `R(yaw)·P(pitch)·Z(roll)`, mapping camera space to world space: the lab's `R(yaw)` when
    /// the pitch and roll are 0.
    pub fn rotation(&self) -> Mat3 {
        let turned = self.yaw_pitch();
        if self.roll == 0.0 {
            return turned;
        }
        let (sin, cos) = self.roll.sin_cos();
        // Columns of [[cos, −sin, 0], [sin, cos, 0], [0, 0, 1]].
        turned * Mat3::from_cols(Vec3::new(cos, sin, 0.0), Vec3::new(-sin, cos, 0.0), Vec3::Z)
    }

    /// `R(yaw)·P(pitch)`.
    fn yaw_pitch(&self) -> Mat3 {
        let (sin, cos) = self.yaw.sin_cos();
        // Columns of [[cos, 0, sin], [0, 1, 0], [−sin, 0, cos]].
        let yaw = Mat3::from_cols(Vec3::new(cos, 0.0, -sin), Vec3::Y, Vec3::new(sin, 0.0, cos));
        if self.pitch == 0.0 {
            // Exactly the lab's matrix, without a product with the identity's rounding.
            return yaw;
        }
        let (sin, cos) = self.pitch.sin_cos();
        // Columns of [[1, 0, 0], [0, cos, −sin], [0, sin, cos]].
        let pitch = Mat3::from_cols(Vec3::X, Vec3::new(0.0, cos, sin), Vec3::new(0.0, -sin, cos));
        yaw * pitch
    }

    /// The unit vector the camera looks along.
    pub fn forward(&self) -> Vec3 {
        self.rotation() * Vec3::Z
    }

    /// The unit vector to the camera's right in the image.
    pub fn right(&self) -> Vec3 {
        self.rotation() * Vec3::X
    }

    /// The ray through the film position `(x, y)` in pixels, where `(0, 0)` is the top-left
    /// corner of the image and `(W, H)` the bottom-right one. The direction has unit length.
    ///
    /// For many rays, make a [`RayGenerator`] once with [`rays`](Self::rays).
    #[inline]
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        self.rays().ray(x, y)
    }

    /// The ray through the centre of pixel `(x, y)`.
    #[inline]
    pub fn pixel_ray(&self, x: u32, y: u32) -> Ray {
        self.rays().pixel_ray(x, y)
    }

    /// Generates this camera's rays with the rotation computed once.
    #[inline]
    pub fn rays(&self) -> RayGenerator {
        RayGenerator {
            position: self.position,
            rotation: self.rotation(),
            half_width: self.width as f32 / 2.0,
            half_height: self.height as f32 / 2.0,
            focal_length_px: self.focal_length_px,
            // Film coordinates are scaled by the largest of the image's half-sizes and the focal
            // length before normalizing, so that huge focal lengths do not overflow |d|².
            scale: 1.0
                / (self.width as f32 / 2.0)
                    .max(self.height as f32 / 2.0)
                    .max(self.focal_length_px.abs())
                    .max(f32::MIN_POSITIVE),
            aperture_radius: self.aperture_radius,
            focus_distance: self.focus_distance,
        }
    }

    /// Where `point` appears on the film, in pixels (the inverse of [`ray`](Self::ray)), or `None`
    /// if it is not in front of the camera.
    pub fn project(&self, point: Vec3) -> Option<Vec2> {
        let local = self.rotation().transpose() * (point - self.position);
        if local.z <= 0.0 {
            return None;
        }
        let scale = self.focal_length_px / local.z;
        Some(Vec2::new(
            local.x * scale + self.width as f32 / 2.0,
            local.y * scale + self.height as f32 / 2.0,
        ))
    }
}

impl fmt::Display for Camera {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let p = self.position;
        write!(
            f,
            "camera at ({}, {}, {}), yaw {}°",
            tidy(p.x),
            tidy(p.y),
            tidy(p.z),
            tidy(self.yaw.to_degrees())
        )?;
        if self.pitch != 0.0 {
            write!(f, ", pitch {}°", tidy(self.pitch.to_degrees()))?;
        }
        if self.roll != 0.0 {
            write!(f, ", roll {}°", tidy(self.roll.to_degrees()))?;
        }
        write!(
            f,
            ", focal length {} px: field of view {:.2}° × {:.2}°",
            tidy(self.focal_length_px),
            self.fov_x_deg(),
            self.fov_y_deg()
        )
    }
}

/// Rays made together by [`RayGenerator::rays_through`].
const RAY_LANES: usize = 32;

/// A [`Camera`]'s rays, with the rotation `R(yaw)` computed once.
#[derive(Clone, Copy, Debug)]
pub struct RayGenerator {
    position: Vec3,
    rotation: Mat3,
    half_width: f32,
    half_height: f32,
    focal_length_px: f32,
    scale: f32,
    aperture_radius: f32,
    focus_distance: f32,
}

impl RayGenerator {
    /// The ray through the film position `(x, y)` in pixels (see [`Camera::ray`]).
    #[inline]
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        // d = R(yaw)·(x − W/2, y − H/2, f), normalized.
        let local = Vec3::new(x - self.half_width, y - self.half_height, self.focal_length_px);
        Ray::new(self.position, (self.rotation * (local * self.scale)).normalize())
    }

    /// The ray through the centre of pixel `(x, y)`.
    #[inline]
    pub fn pixel_ray(&self, x: u32, y: u32) -> Ray {
        self.ray(x as f32 + 0.5, y as f32 + 0.5)
    }

    /// The rays through the film positions `films` (pixels), `out[i]` for `films[i]`: what
    /// [`ray`](Self::ray) gives each, bit for bit: the same operations in the same order
    /// (`R·(local·s)` column by column, then `d · (1/√(d·d))`), in lanes (the square root and
    /// the division of eight rays in one AVX instruction each).
    ///
    /// # Panics
    /// If the slices differ in length.
    #[inline(always)]
    pub fn rays_through(&self, films: &[Vec2], out: &mut [Ray]) {
        assert_eq!(films.len(), out.len(), "one ray per film position");
        let (films, rest) = films.as_chunks::<RAY_LANES>();
        let (out, out_rest) = out.as_chunks_mut::<RAY_LANES>();
        for (films, out) in films.iter().zip(out) {
            self.lanes_of_rays(films, out);
        }
        for (film, out) in rest.iter().zip(out_rest) {
            *out = self.ray(film.x, film.y);
        }
    }

    /// [`rays_through`](Self::rays_through) for [`RAY_LANES`] rays: each step over all the
    /// lanes before the next, in arrays, a form the compiler vectorizes. (Eight lanes with the
    /// directions stored straight into the rays were left scalar: the arrays must be long
    /// enough to stay in memory.)
    #[inline(always)]
    fn lanes_of_rays(&self, films: &[Vec2; RAY_LANES], out: &mut [Ray; RAY_LANES]) {
        let [c0, c1, c2] = [self.rotation.x_axis, self.rotation.y_axis, self.rotation.z_axis];
        let z = self.focal_length_px * self.scale;
        let (mut x, mut y) = ([0.0f32; RAY_LANES], [0.0f32; RAY_LANES]);
        for k in 0..RAY_LANES {
            x[k] = (films[k].x - self.half_width) * self.scale;
            y[k] = (films[k].y - self.half_height) * self.scale;
        }
        let mut d = [[0.0f32; RAY_LANES]; 3];
        for (axis, d) in d.iter_mut().enumerate() {
            for k in 0..RAY_LANES {
                d[k] = c0[axis] * x[k] + c1[axis] * y[k] + c2[axis] * z;
            }
        }
        let mut inverse_length = [0.0f32; RAY_LANES];
        for (k, inverse) in inverse_length.iter_mut().enumerate() {
            let squared = d[0][k] * d[0][k] + d[1][k] * d[1][k] + d[2][k] * d[2][k];
            *inverse = 1.0 / squared.sqrt();
        }
        for (k, ray) in out.iter_mut().enumerate() {
            let direction = Vec3::new(
                d[0][k] * inverse_length[k],
                d[1][k] * inverse_length[k],
                d[2][k] * inverse_length[k],
            );
            *ray = Ray::new(self.position, direction);
        }
    }

    /// The ray through the film position `film` (pixels) and the point of the thin lens that the
    /// uniform numbers `u_lens` pick (concentric disk): it passes through the point that the
    /// pinhole ray meets at the focus distance, so that plane stays sharp (PBR 4th ed. §5.2.3).
    #[inline]
    pub fn lens_ray(&self, film: Vec2, u_lens: Vec2) -> Ray {
        let local =
            Vec3::new(film.x - self.half_width, film.y - self.half_height, self.focal_length_px);
        let focus = local * (self.focus_distance / self.focal_length_px);
        let disk =
            crate::sampling::square_to_uniform_disk_concentric(u_lens) * self.aperture_radius;
        let lens = Vec3::new(disk.x, disk.y, 0.0);
        Ray::new(self.position + self.rotation * lens, (self.rotation * (focus - lens)).normalize())
    }
}

/// A number for people, as the camera and the command line's reports print them: at most four
/// decimals, no trailing zeros (`30.000002` → `30`), and no `-0`.
pub fn tidy(value: f32) -> String {
    let text = format!("{value:.4}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    if text == "-0" { "0".to_string() } else { text.to_string() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_is_tidy() {
        let camera = Camera { yaw: 30f32.to_radians(), ..Camera::lab(500, 500) };
        assert_eq!(
            camera.to_string(),
            "camera at (0, 0, -3), yaw 30°, focal length 500 px: field of view 53.13° × 53.13°"
        );
    }

    /// The rays of a batch are `ray`'s bit for bit, compiled for the baseline and for AVX2
    /// (as the scheduler's AVX2 bands inline it), for turned cameras, huge and tiny focal
    /// lengths, film positions off the image, and batches shorter than 32 or not a multiple of it.
    #[test]
    fn rays_through_are_ray_bit_for_bit() {
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        fn through_avx2(rays: &RayGenerator, films: &[Vec2], out: &mut [Ray]) {
            rays.rays_through(films, out);
        }
        let mut state = 0x2545_F491_4F6C_DD1Du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let cameras = [
            Camera::lab(500, 500),
            Camera { yaw: 0.7, pitch: -0.3, roll: 0.2, ..Camera::lab(640, 360) },
            Camera { focal_length_px: 1e30, ..Camera::lab(33, 17) },
            Camera { focal_length_px: 0.01, yaw: -2.0, ..Camera::lab(8, 800) },
        ];
        let bits = |r: &Ray| {
            let [o, d] = [r.origin, r.direction].map(|v| v.to_array().map(f32::to_bits));
            (o, d, r.t_min.to_bits(), r.t_max.to_bits())
        };
        for camera in cameras {
            let rays = camera.rays();
            for n in [1, 7, 8, 9, 64, 203] {
                let films: Vec<Vec2> = (0..n)
                    .map(|_| {
                        let (w, h) = (camera.width as f32, camera.height as f32);
                        Vec2::new((next() * 1.2 - 0.1) * w, (next() * 1.2 - 0.1) * h)
                    })
                    .collect();
                let mut out = vec![Ray::new(Vec3::ZERO, Vec3::X); n];
                rays.rays_through(&films, &mut out);
                for (film, ray) in films.iter().zip(&out) {
                    assert_eq!(bits(ray), bits(&rays.ray(film.x, film.y)), "{camera}, {film}");
                }
                #[cfg(target_arch = "x86_64")]
                if std::arch::is_x86_feature_detected!("avx2") {
                    let mut wide = vec![Ray::new(Vec3::ZERO, Vec3::X); n];
                    // SAFETY: AVX2 was detected just above.
                    unsafe { through_avx2(&rays, &films, &mut wide) };
                    for (film, ray) in films.iter().zip(&wide) {
                        assert_eq!(bits(ray), bits(&rays.ray(film.x, film.y)), "{camera}, {film}");
                    }
                }
            }
        }
    }

    #[test]
    fn huge_focal_lengths_still_give_unit_directions() {
        let camera = Camera { focal_length_px: 1e30, ..Camera::lab(500, 500) };
        let d = camera.pixel_ray(0, 0).direction;
        assert!((d.length() - 1.0).abs() < 1e-6 && d.z > 0.999, "{d}");
    }

    #[test]
    fn the_lab_camera_has_a_53_degree_field_of_view() {
        let camera = Camera::lab(500, 500);
        assert!((camera.fov_x_deg() - 53.130_1).abs() < 1e-3, "{}", camera.fov_x_deg());
        assert_eq!(camera.fov_x_deg(), camera.fov_y_deg());
        let ninety = Camera { focal_length_px: 250.0, ..camera };
        assert!((ninety.fov_x_deg() - 90.0).abs() < 1e-4);
    }

    #[test]
    fn fov_and_focal_length_round_trip() {
        for fov in [10.0f32, 39.3, 53.13, 90.0, 120.0] {
            let f = Camera::focal_length_for_fov(640, fov);
            let camera = Camera { focal_length_px: f, ..Camera::lab(640, 480) };
            assert!((camera.fov_x_deg() - fov).abs() < 1e-3, "{fov}");
        }
    }

    #[test]
    fn pixel_rays_follow_the_lab_formula() {
        let camera = Camera { yaw: 0.3, ..Camera::lab(500, 500) };
        let (x, y) = (17u32, 401u32);
        let d = Vec3::new(x as f32 + 0.5 - 250.0, y as f32 + 0.5 - 250.0, 500.0);
        let (s, c) = 0.3f32.sin_cos();
        // R(y)·d written out row by row.
        let expected = Vec3::new(c * d.x + s * d.z, d.y, -s * d.x + c * d.z).normalize();
        let ray = camera.pixel_ray(x, y);
        assert!((ray.direction - expected).length() < 1e-6);
        assert_eq!(ray.origin, Vec3::new(0.0, 0.0, -3.0));
    }

    #[test]
    fn the_centre_pixel_ray_looks_forward_and_yaw_turns_toward_x() {
        let camera = Camera::lab(2, 2);
        assert_eq!(camera.ray(1.0, 1.0).direction, Vec3::Z);
        let turned = Camera { yaw: std::f32::consts::FRAC_PI_2, ..camera };
        assert!((turned.forward() - Vec3::X).length() < 1e-6);
        assert!((turned.right() + Vec3::Z).length() < 1e-6);
    }

    #[test]
    fn pitch_looks_up_and_keeps_the_horizon_level() {
        let camera = Camera { pitch: 30f32.to_radians(), ..Camera::lab(2, 2) };
        let forward = camera.forward();
        // Up is −y in the lab's axes.
        assert!((forward - Vec3::new(0.0, -0.5, 3f32.sqrt() / 2.0)).length() < 1e-6, "{forward}");
        // Pitch tilts about the camera's right axis, which stays horizontal.
        let turned = Camera { yaw: 1.0, ..camera };
        assert!(turned.right().y.abs() < 1e-7);
        assert!((turned.forward().length() - 1.0).abs() < 1e-6);
        assert!(turned.to_string().contains("yaw 57.2958°, pitch 30°"), "{turned}");
        let level = Camera { pitch: 0.0, ..turned };
        assert!(!level.to_string().contains("pitch"));
    }

    #[test]
    fn lens_rays_meet_at_the_focus_distance() {
        let camera =
            Camera { aperture_radius: 0.1, focus_distance: 4.0, yaw: 0.4, ..Camera::lab(64, 48) };
        let rays = camera.rays();
        let film = Vec2::new(20.25, 31.5);
        let pinhole = rays.ray(film.x, film.y);
        // The pinhole ray reaches the focus plane (4 along the view axis) here:
        let t = 4.0 / pinhole.direction.dot(camera.forward());
        let focus = pinhole.at(t);
        for u in [Vec2::ZERO, Vec2::new(0.9, 0.2), Vec2::splat(0.5), Vec2::new(0.3, 0.99)] {
            let ray = rays.lens_ray(film, u);
            assert!((ray.origin - camera.position).length() <= 0.1 + 1e-6);
            let offset = ray.origin - camera.position;
            assert!(offset.dot(camera.forward()).abs() < 1e-6, "the lens is in the film's plane");
            let s = (focus - ray.origin).dot(ray.direction);
            assert!((ray.at(s) - focus).length() < 1e-5, "{u}: misses the focus point");
        }
        // At the lens centre the ray is the pinhole's.
        let centre = rays.lens_ray(film, Vec2::splat(0.5));
        assert!((centre.direction - pinhole.direction).length() < 1e-6);
        assert!(!Camera::lab(8, 8).has_lens() && camera.has_lens());
    }

    #[test]
    fn roll_turns_the_picture_about_the_view_direction() {
        let camera = Camera { roll: 90f32.to_radians(), yaw: 0.3, ..Camera::lab(8, 8) };
        let level = Camera { roll: 0.0, ..camera };
        // The view direction stays; the picture's up (−y in camera space) turns to its right.
        assert!((camera.forward() - level.forward()).length() < 1e-6);
        let up = camera.rotation() * Vec3::NEG_Y;
        assert!((up - level.right()).length() < 1e-6, "{up}");
        assert!(camera.to_string().contains("roll 90°"));
        let film = camera.project(camera.ray(1.25, 6.5).at(2.0)).unwrap();
        assert!((film - Vec2::new(1.25, 6.5)).length() < 1e-4);
    }

    #[test]
    fn project_inverts_ray() {
        let camera = Camera {
            yaw: -0.7,
            pitch: 0.2,
            position: Vec3::new(0.3, -0.2, -2.0),
            ..Camera::lab(320, 200)
        };
        let ray = camera.ray(123.25, 77.5);
        let film = camera.project(ray.at(3.0)).unwrap();
        assert!((film - Vec2::new(123.25, 77.5)).length() < 1e-3, "{film}");
        assert!(camera.project(camera.position - camera.forward()).is_none());
    }
}
