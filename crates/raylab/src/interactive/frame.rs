//! The frame function: one frame of `raylab view`, with or without a window.
//!
//! A frame renders one sample per pixel. While the view changes from frame to frame (the camera
//! or the light moves) each frame starts afresh, at a reduced resolution if the full one would
//! miss the frame-time budget; while it stands still, frames add samples to the same picture
//! (progressive anti-aliasing) up to a limit.

use std::time::{Duration, Instant};

#[cfg(feature = "io")]
use image::RgbImage;

use glam::Vec3;

use super::Pose;
use crate::accel::Accelerator;
use crate::camera::Camera;
use crate::film::{Display, FilmError};
use crate::integrator::LightSet;
use crate::integrator::{AovKind, Choice, Chosen, Integrator, PathSettings, Stage};
use crate::ray::Ray;
use crate::render::{Accumulator, SampleSettings};
use crate::sampling::{Sampler, SamplerKind};
use crate::scene::Scene;
use crate::settings::IntegratorKind;

/// What a frame computes: an integrator, and for the lab's its stage. The integrator is
/// built by the one chooser renders use ([`Chosen`]); a view shows normals as `(n + 1)/2` and
/// depth relative to the scene's size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ViewMode {
    integrator: IntegratorKind,
    /// The lab's stage; the last for the others, which do not read it.
    stage: Stage,
}

impl ViewMode {
    /// Path tracing (the wavefront).
    pub const PATH: ViewMode = ViewMode::of(IntegratorKind::Path, Stage::Ambient);
    /// The first surface's albedo.
    pub const ALBEDO: ViewMode = ViewMode::of(IntegratorKind::Aov(AovKind::Albedo), Stage::Ambient);
    /// The first surface's shading normal, shown as `(n + 1)/2`.
    pub const NORMALS: ViewMode =
        ViewMode::of(IntegratorKind::Aov(AovKind::Normals), Stage::Ambient);
    /// The distance to the first surface, shown relative to the scene's size.
    pub const DEPTH: ViewMode = ViewMode::of(IntegratorKind::Aov(AovKind::Depth), Stage::Ambient);

    /// The mode that shows what `integrator` computes; the lab shows `stage` (the others are
    /// given the last stage, which they do not read, so that modes compare equal exactly when
    /// they show the same).
    pub const fn of(integrator: IntegratorKind, stage: Stage) -> ViewMode {
        let stage = match integrator {
            IntegratorKind::Lab => stage,
            _ => Stage::Ambient,
        };
        ViewMode { integrator, stage }
    }

    /// The lab's model at `stage`.
    pub const fn lab(stage: Stage) -> ViewMode {
        ViewMode { integrator: IntegratorKind::Lab, stage }
    }

    /// Which integrator it runs.
    pub fn integrator(self) -> IntegratorKind {
        self.integrator
    }

    /// The lab's stage it shows (the last for the other integrators).
    pub fn stage(self) -> Stage {
        self.stage
    }

    /// How its radiance is shown: the lab's linear clamp for the lab, normals and depth, sRGB
    /// for the physically based modes.
    pub fn display(self) -> Display {
        match self.integrator {
            IntegratorKind::Lab
            | IntegratorKind::Aov(AovKind::Normals)
            | IntegratorKind::Aov(AovKind::Depth) => Display::LAB,
            IntegratorKind::Path
            | IntegratorKind::PathScalar
            | IntegratorKind::Aov(AovKind::Albedo) => Display::SRGB,
        }
    }
}

impl std::fmt::Display for ViewMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.integrator {
            IntegratorKind::Lab => write!(f, "stage {}", self.stage),
            IntegratorKind::Path => f.write_str("path tracing"),
            IntegratorKind::PathScalar => f.write_str("path tracing (scalar)"),
            IntegratorKind::Aov(kind) => f.write_str(kind.name()),
        }
    }
}

/// Everything a frame shows: the pose, what to compute and the window's size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// The camera's position and direction, and the light's position.
    pub pose: Pose,
    /// What to compute.
    pub mode: ViewMode,
    /// Window width in pixels, at least 1.
    pub width: u32,
    /// Window height in pixels, at least 1.
    pub height: u32,
    /// The focal length in pixels for an image `focal_width` pixels wide: the lab's `f = W` is
    /// `(W, W)`. Other widths scale it, so the field of view stays when the window is resized;
    /// at `focal_width` itself it is exact, so a still view is the render of the same camera.
    pub focal: (u32, f32),
    /// The thin lens: radius and focus distance (a radius of 0 is a pinhole).
    pub lens: (f32, f32),
    /// The camera's roll about its view direction (a scene file's camera may have one; the
    /// controller keeps it).
    pub roll: f32,
}

impl View {
    /// The camera for this view, rendering at `1/scale` of the window's resolution (at least one
    /// pixel) with the same field of view.
    pub fn camera(&self, scale: u32) -> Camera {
        let scale = scale.max(1);
        let width = self.width.div_ceil(scale).max(1);
        let height = self.height.div_ceil(scale).max(1);
        Camera {
            position: self.pose.position,
            yaw: self.pose.yaw,
            pitch: self.pose.pitch,
            roll: self.roll,
            focal_length_px: self.focal_length_px(width),
            width,
            height,
            aperture_radius: self.lens.0,
            focus_distance: self.lens.1,
        }
    }

    /// The focal length in pixels for an image `width` pixels wide.
    pub fn focal_length_px(&self, width: u32) -> f32 {
        let (base_width, focal) = self.focal;
        if width == base_width { focal } else { focal / base_width.max(1) as f32 * width as f32 }
    }
}

/// What a frame did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameInfo {
    /// The view changed since the previous frame, so this frame started a new picture.
    pub moving: bool,
    /// Samples per pixel in the picture now.
    pub samples: u32,
    /// The picture's resolution is `1/scale` of the window's.
    pub scale: u32,
    /// Time spent on the frame: rendering it and writing the window's pixels.
    pub render_time: Duration,
}

/// Frames that fit their budget while moving: the resolution divides by this much at most.
pub const MAX_SCALE: u32 = 8;

/// The resolution scale for the next moving frame, given that this one, at `scale`, took
/// `elapsed` against a `budget`: coarser when over budget, at once by as much as the time says
/// (it grows with the pixel count, the square of the scale's inverse); finer by one step when
/// the finer resolution's estimated time fits in ¾ of the budget.
pub fn next_scale(scale: u32, elapsed: Duration, budget: Duration) -> u32 {
    if elapsed > budget {
        let ratio = elapsed.as_secs_f64() / budget.as_secs_f64().max(1e-9);
        // (Less a hair, so that exactly 3× the pixel time asks for 3, not 4.)
        let needed = (scale as f64 * ratio.sqrt() - 1e-9).ceil().min(MAX_SCALE as f64) as u32;
        return needed.max(scale + 1).min(MAX_SCALE);
    }
    if scale > 1 {
        let growth = (scale as f64 / (scale - 1) as f64).powi(2);
        if elapsed.as_secs_f64() * growth < budget.as_secs_f64() * 0.75 {
            return scale - 1;
        }
    }
    scale
}

/// Renders the frames of a view that changes or stands still.
#[derive(Debug)]
pub struct FrameRenderer {
    picture: Option<(View, u32, Accumulator)>,
    scale: u32,
    /// The path tracer's lights, for the point light's position they were made with.
    lights: Option<(Vec3, LightSet)>,
    /// A moving frame should take at most this long; `None` renders every frame at full
    /// resolution (for benchmarks).
    pub budget: Option<Duration>,
    /// A still picture stops refining at this many samples per pixel.
    pub max_samples: u32,
    /// The path tracer's settings (the scene file's max depth).
    pub path_settings: PathSettings,
    /// How pictures draw their samples (the scene file's seed, sampler and filter).
    pub sample_settings: SampleSettings,
}

impl FrameRenderer {
    /// A renderer with a moving-frame budget (`None`: always full resolution) that refines a
    /// still picture up to `max_samples` samples per pixel.
    pub fn new(budget: Option<Duration>, max_samples: u32) -> FrameRenderer {
        FrameRenderer {
            picture: None,
            scale: 1,
            lights: None,
            budget,
            max_samples: max_samples.max(1),
            path_settings: PathSettings::default(),
            sample_settings: SampleSettings::default(),
        }
    }

    /// Whether `view` is already shown with every sample it will get: no frame is needed.
    pub fn is_done(&self, view: &View) -> bool {
        matches!(&self.picture, Some((shown, 1, picture))
            if shown == view && picture.samples() >= self.max_samples)
    }

    /// Renders one frame of `view` of `scene`, whose triangles `accel` holds, on the current
    /// rayon pool: a new picture if the view changed, else one more sample of the same one. The
    /// picture is then written into `window`, resized to the view's `width×height` words of
    /// `0x00RRGGBB` (see [`write_0rgb`](Self::write_0rgb)).
    pub fn frame<A: Accelerator + ?Sized>(
        &mut self,
        scene: &Scene,
        accel: &A,
        view: &View,
        window: &mut Vec<u32>,
    ) -> Result<FrameInfo, FilmError> {
        let start = Instant::now();
        let refining = matches!(&self.picture, Some((shown, 1, _)) if shown == view);
        let moving = !refining && self.picture.as_ref().is_some_and(|(shown, ..)| shown != view);
        let scale = if moving && self.budget.is_some() { self.scale } else { 1 };
        let camera = view.camera(scale);
        // The old picture's memory is used again for a new one of the same size: its sums are
        // zeroed by the frame's pass itself, band by band (`restart_with_sample`).
        let mut restart = false;
        if !refining {
            match &mut self.picture {
                Some((shown, shown_scale, picture))
                    if (picture.width(), picture.height()) == (camera.width, camera.height) =>
                {
                    restart = true;
                    (*shown, *shown_scale) = (*view, scale);
                }
                _ => {
                    self.picture = None;
                    let mut picture = Accumulator::new(camera.width, camera.height)?;
                    picture.settings = self.sample_settings;
                    self.picture = Some((*view, scale, picture));
                }
            }
        }
        let (_, _, picture) = self.picture.as_mut().expect("a picture was just made");
        let lights = match view.mode.integrator {
            IntegratorKind::Path | IntegratorKind::PathScalar => {
                let light = view.pose.light;
                if self.lights.as_ref().is_none_or(|(at, _)| *at != light) {
                    // The scene's point light, where the controller moved it.
                    let mut moved = LightSet::new(scene);
                    moved.move_first_point_light(light);
                    self.lights = Some((light, moved));
                }
                self.lights.as_ref().map(|(_, lights)| lights)
            }
            _ => None,
        };
        let choice = Choice {
            kind: view.mode.integrator,
            stage: view.mode.stage,
            path: self.path_settings,
            lights,
        };
        let mut integrator = Chosen::new(&choice, scene, accel, &camera);
        integrator.move_lab_light(view.pose.light);
        match view.mode.integrator {
            IntegratorKind::Aov(AovKind::Normals) => {
                add(picture, restart, &camera, &ShownNormals(&integrator))
            }
            IntegratorKind::Aov(AovKind::Depth) => {
                let size = scene
                    .bounds()
                    .map_or(1.0, |(lo, hi)| (hi - lo).length())
                    .max(f32::MIN_POSITIVE);
                add(picture, restart, &camera, &ShownDepth(&integrator, size))
            }
            _ => add(picture, restart, &camera, &integrator),
        }
        let words = view.width as usize * view.height as usize;
        if window.len() != words {
            // Only when the size changes: every word is written below.
            window.clear();
            window.try_reserve_exact(words).map_err(|_| FilmError::OutOfMemory {
                width: view.width,
                height: view.height,
                bytes: words as u64 * 4,
            })?;
            window.resize(words, 0);
        }
        picture.write_0rgb_shown(window, view.width, view.height, &view.mode.display());
        let render_time = start.elapsed();
        if moving && let Some(budget) = self.budget {
            self.scale = next_scale(scale, render_time, budget);
        }
        Ok(FrameInfo { moving, samples: picture.samples(), scale, render_time })
    }

    /// Writes the picture into a `width×height` window buffer of `0x00RRGGBB` words, scaled to
    /// fill it; black before the first frame.
    ///
    /// # Panics
    /// If `out` does not hold `width×height` words.
    pub fn write_0rgb(&self, out: &mut [u32], width: u32, height: u32) {
        match &self.picture {
            Some((view, _, picture)) => {
                picture.write_0rgb_shown(out, width, height, &view.mode.display())
            }
            None => out.fill(0),
        }
    }
}

/// Adds the next sample of `integrator` to `picture`, or makes it the first where `restart`
/// says the picture starts again ([`Accumulator::restart_with_sample`]).
fn add(
    picture: &mut Accumulator,
    restart: bool,
    camera: &Camera,
    integrator: &(impl Integrator + ?Sized),
) {
    if restart {
        picture.restart_with_sample(camera, integrator);
    } else {
        picture.add_sample(camera, integrator);
    }
}

/// Normals as colours: `(n + 1)/2`.
struct ShownNormals<'a, I: ?Sized>(&'a I);

impl<I: Integrator + ?Sized> Integrator for ShownNormals<'_, I> {
    fn radiance(&self, ray: &Ray, sampler: &mut Sampler) -> Vec3 {
        let n = self.0.radiance(ray, sampler);
        if n == Vec3::ZERO { n } else { (n + Vec3::ONE) * 0.5 }
    }
    fn sampler_kind(&self) -> SamplerKind {
        SamplerKind::Lab
    }
}

/// Depth as grey: near is bright, a scene's diagonal away is black.
struct ShownDepth<'a, I: ?Sized>(&'a I, f32);

impl<I: Integrator + ?Sized> Integrator for ShownDepth<'_, I> {
    fn radiance(&self, ray: &Ray, sampler: &mut Sampler) -> Vec3 {
        let depth = self.0.radiance(ray, sampler).x;
        if depth == 0.0 { Vec3::ZERO } else { Vec3::splat((1.0 - depth / self.1).max(0.0)) }
    }
    fn sampler_kind(&self) -> SamplerKind {
        SamplerKind::Lab
    }
}

#[cfg(feature = "io")]
/// An RGB image of a window buffer of `0x00RRGGBB` words, `width×height` of them.
///
/// # Panics
/// If `words` does not hold `width×height` words.
pub fn rgb8_from_0rgb(words: &[u32], width: u32, height: u32) -> RgbImage {
    assert_eq!(words.len(), width as usize * height as usize, "a word per pixel");
    let bytes = words.iter().flat_map(|w| [(w >> 16) as u8, (w >> 8) as u8, *w as u8]).collect();
    RgbImage::from_raw(width, height, bytes).expect("three bytes per pixel")
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::integrator::{Lab, PathScalar};
    use crate::{BruteForce, render_samples};

    fn lab_view(width: u32, height: u32) -> View {
        View {
            pose: Pose {
                position: Vec3::new(0.0, 0.0, -3.0),
                yaw: 0.0,
                pitch: 0.0,
                light: Vec3::new(0.0, -0.5, -0.7),
            },
            mode: ViewMode::lab(Stage::Ambient),
            width,
            height,
            focal: (width, width as f32),
            lens: (0.0, 1.0),
            roll: 0.0,
        }
    }

    #[test]
    fn scales_follow_the_budget() {
        let ms = Duration::from_millis;
        assert_eq!(next_scale(1, ms(40), ms(33)), 2);
        assert_eq!(next_scale(1, ms(20), ms(33)), 1);
        assert_eq!(next_scale(MAX_SCALE, ms(400), ms(33)), MAX_SCALE);
        // Nine times over budget: a third of the resolution at once.
        assert_eq!(next_scale(1, ms(270), ms(30)), 3);
        assert_eq!(next_scale(2, ms(1000), ms(10)), MAX_SCALE);
        // At scale 2 a frame of 5 ms would take about 20 ms at full resolution: fits.
        assert_eq!(next_scale(2, ms(5), ms(33)), 1);
        // 8 ms would be about 32 ms: too close to the budget, stay.
        assert_eq!(next_scale(2, ms(8), ms(33)), 2);
        assert_eq!(next_scale(1, ms(1), Duration::ZERO), MAX_SCALE);
    }

    #[test]
    fn views_keep_their_field_of_view_at_any_scale() {
        let view = lab_view(500, 300);
        assert_eq!(view.camera(1), Camera { width: 500, height: 300, ..Camera::lab(500, 300) });
        let coarse = view.camera(3);
        assert_eq!((coarse.width, coarse.height), (167, 100));
        assert!((coarse.fov_x_deg() - view.camera(1).fov_x_deg()).abs() < 1e-4);
        assert_eq!(lab_view(1, 1).camera(8).width, 1);
    }

    fn rgb(words: &[u32], view: &View) -> RgbImage {
        rgb8_from_0rgb(words, view.width, view.height)
    }

    #[test]
    fn still_frames_refine_moving_frames_restart() {
        let scene = Scene::built_in("cornell").unwrap();
        let accel = BruteForce::new(&scene.vertices());
        let view = lab_view(24, 16);
        let mut renderer = FrameRenderer::new(None, 3);
        let mut words = Vec::new();
        for n in 1..=3 {
            assert!(!renderer.is_done(&view));
            let info = renderer.frame(&scene, &accel, &view, &mut words).unwrap();
            assert_eq!((info.moving, info.samples, info.scale), (false, n, 1));
        }
        assert!(renderer.is_done(&view));
        // The picture after three still frames is the three-sample render, bit for bit.
        let camera = view.camera(1);
        let lab = Lab::new(&scene, &accel, Stage::Ambient);
        let expected = render_samples(&camera, &lab, 3, &|_| {}).unwrap();
        assert!(rgb(&words, &view) == expected.to_rgb8_clamped().unwrap());

        // The light moves: a new picture, showing the moved light.
        let mut moved = view;
        moved.pose.light.x += 0.3;
        let info = renderer.frame(&scene, &accel, &moved, &mut words).unwrap();
        assert_eq!((info.moving, info.samples), (true, 1));
        let mut scene_moved = scene.clone();
        scene_moved.point_light_mut().position = moved.pose.light;
        let lab_moved = Lab::new(&scene_moved, &accel, Stage::Ambient);
        let expected = crate::render(&camera, &lab_moved, &|_| {}).unwrap();
        assert!(rgb(&words, &view) == expected.to_rgb8_clamped().unwrap());
        // Standing still again refines the moved picture.
        assert_eq!(renderer.frame(&scene, &accel, &moved, &mut words).unwrap().samples, 2);
    }

    #[test]
    fn moving_frames_drop_resolution_when_over_budget_and_recover_when_still() {
        let scene = Scene::built_in("cornell").unwrap();
        let accel = BruteForce::new(&scene.vertices());
        let mut view = lab_view(64, 48);
        // A zero budget: every moving frame is over it.
        let mut renderer = FrameRenderer::new(Some(Duration::ZERO), 16);
        let mut words = Vec::new();
        renderer.frame(&scene, &accel, &view, &mut words).unwrap();
        let mut scales = Vec::new();
        for _ in 0..4 {
            view.pose.yaw += 0.01;
            scales.push(renderer.frame(&scene, &accel, &view, &mut words).unwrap().scale);
        }
        // The first moving frame is at full resolution; the next at the coarsest, at once.
        assert_eq!(scales, [1, MAX_SCALE, MAX_SCALE, MAX_SCALE]);
        // The window shows the coarse render scaled up: each of its pixels fills a block.
        let scale = scales[3];
        let coarse = view.camera(scale);
        let lab = Lab::new(&scene, &accel, Stage::Ambient);
        let coarse = crate::render(&coarse, &lab, &|_| {}).unwrap().to_rgb8_clamped().unwrap();
        let shown = rgb(&words, &view);
        for (x, y, pixel) in shown.enumerate_pixels() {
            let source = coarse
                .get_pixel(x * coarse.width() / view.width, y * coarse.height() / view.height);
            assert_eq!(pixel, source, "window pixel ({x}, {y}) at scale {scale}");
        }
        // Still: full resolution again, from the first sample.
        let info = renderer.frame(&scene, &accel, &view, &mut words).unwrap();
        assert_eq!((info.moving, info.samples, info.scale), (false, 1, 1));
        // A resize is a change of view.
        view.width = 50;
        let info = renderer.frame(&scene, &accel, &view, &mut words).unwrap();
        assert!(info.moving && info.samples == 1 && words.len() == 50 * 48);
    }

    #[test]
    fn still_path_tracing_refines_to_the_render_and_shows_srgb() {
        let scene = Scene::built_in("cornell").unwrap();
        let accel = BruteForce::new(&scene.vertices());
        let view = View { mode: ViewMode::PATH, ..lab_view(24, 16) };
        let mut renderer = FrameRenderer::new(None, 8);
        let mut words = Vec::new();
        for _ in 0..3 {
            renderer.frame(&scene, &accel, &view, &mut words).unwrap();
        }
        // Three still frames are `render_samples` of three samples with the same path tracer.
        let path = PathScalar::new(&scene, &accel, PathSettings::default());
        let film = render_samples(&view.camera(1), &path, 3, &|_| {}).unwrap();
        let expected = film.to_rgb8(&Display::SRGB).unwrap();
        assert_eq!(rgb(&words, &view), expected);
        // The lab's point light moved by the controller moves in the path tracer too.
        let mut moved = view;
        moved.pose.light = Vec3::new(0.5, 0.5, 0.5);
        renderer.frame(&scene, &accel, &moved, &mut words).unwrap();
        let mut scene_moved = scene.clone();
        scene_moved.point_light_mut().position = moved.pose.light;
        let path = PathScalar::new(&scene_moved, &accel, PathSettings::default());
        let film = render_samples(&moved.camera(1), &path, 1, &|_| {}).unwrap();
        assert_eq!(rgb(&words, &moved), film.to_rgb8(&Display::SRGB).unwrap());
        // Every mode renders, and switching modes starts a new picture.
        for mode in
            [ViewMode::ALBEDO, ViewMode::NORMALS, ViewMode::DEPTH, ViewMode::lab(Stage::Flat)]
        {
            let info = renderer.frame(&scene, &accel, &View { mode, ..view }, &mut words).unwrap();
            assert_eq!(info.samples, 1, "{mode}");
            assert!(words.iter().any(|&w| w != 0), "{mode} shows something");
        }
        assert_eq!(ViewMode::of(IntegratorKind::Path, Stage::Flat), ViewMode::PATH);
        assert_eq!(ViewMode::of(IntegratorKind::Lab, Stage::Flat), ViewMode::lab(Stage::Flat));
        assert_eq!(ViewMode::lab(Stage::Shadows).to_string(), "stage shadows");
    }

    #[test]
    fn window_words_round_trip_to_rgb() {
        let image = rgb8_from_0rgb(&[0x00ff_8001, 0x0000_00ff], 2, 1);
        assert_eq!(image.get_pixel(0, 0).0, [255, 128, 1]);
        assert_eq!(image.get_pixel(1, 0).0, [0, 0, 255]);
    }
}
