//! What `raylab render` and `raylab view` share: the scene, the camera, the light, the stage and
//! the threads, parsed and checked the same way.

use anyhow::Result;
use clap::Args;
use glam::Vec3;
use raylab::light::EnvironmentMap;
use raylab::scene::{CameraSettings, Instancing, LoadOptions, OpenedScene};
use raylab::session::CameraOptions;
use raylab::{Scene, Stage};

use crate::args::{self, Size};

#[derive(Args, Debug)]
pub struct SceneArgs {
    /// The scene: `cornell`, the lab's Cornell box (30 triangles, y down), a scene file (.toml,
    /// see docs/scene-format.md) or a model file (.obj with its .mtl, .ply, either optionally
    /// .gz; y up, framed by the camera unless --camera is given).
    #[arg(default_value = "cornell", value_name = "SCENE|MODEL")]
    pub scene: String,

    /// Image size in pixels [default: the scene file's, else 500x500].
    #[arg(long, value_name = "WxH", value_parser = args::size, allow_hyphen_values = true)]
    pub size: Option<Size>,

    /// Camera position (lab axes: x right, y down, z forward) [default: the lab's (0, 0, -3) for
    /// `cornell`; for a model, in front of it, framing its bounding box].
    #[arg(long, value_name = "X,Y,Z", value_parser = args::vec3, allow_hyphen_values = true)]
    pub camera: Option<Vec3>,

    /// Camera yaw in degrees: rotation about the vertical axis, positive toward +x (the lab's
    /// R(y)) [default: 0, or the scene file's camera].
    #[arg(long, value_name = "DEG", value_parser = args::finite_f32, allow_hyphen_values = true)]
    pub yaw: Option<f32>,

    /// Camera pitch in degrees, positive looking up, between -89 and 89 (the lab has none)
    /// [default: 0, or the scene file's camera].
    #[arg(long, value_name = "DEG", value_parser = args::pitch_deg, allow_hyphen_values = true)]
    pub pitch: Option<f32>,

    /// Focal length in pixels [default: the image width, as the lab's f = 500 for 500×500, which
    /// is a 53.13° horizontal field of view: fov = 2·atan(W / 2f), not 90°].
    #[arg(long, value_name = "PX", value_parser = args::positive_f32, conflicts_with = "fov")]
    pub focal: Option<f32>,

    /// Horizontal field of view in degrees, instead of --focal (sets f = W / (2·tan(fov/2))).
    #[arg(long, value_name = "DEG", value_parser = args::fov_deg)]
    pub fov: Option<f32>,

    /// Meshes that a model draws in several places (glTF nodes sharing a mesh): auto copies
    /// those whose copies add the fewest triangles (at most 262,144 per model file, some 25
    /// MiB) and stores the rest once, under a two-level BVH; keep stores every one once (the
    /// least memory); flatten copies every instance (the fastest to trace, the most memory).
    /// The picture is the same.
    #[arg(long, value_name = "HOW", default_value = "auto")]
    pub instancing: Instancing,

    /// The same as --instancing flatten.
    #[arg(long, hide = true, conflicts_with = "instancing")]
    pub flatten: bool,

    /// Point-light position [default: the lab's (0, -0.5, -0.7); for a model, above it, to the
    /// right and in front].
    #[arg(long, value_name = "X,Y,Z", value_parser = args::vec3, allow_hyphen_values = true)]
    pub light: Option<Vec3>,

    /// Point-light power P per channel [default: the lab's 14; for a model, enough for an
    /// irradiance of 1 at its centre].
    #[arg(long, value_name = "WATTS", value_parser = args::non_negative_f32)]
    pub light_power: Option<f32>,

    /// An equirectangular (latitude-longitude) HDR environment map, .hdr or .exr, lighting the
    /// scene from every direction, Mitsuba's envmap: the image's top row is up (+y of a y-up
    /// model), its left edge looks along -z. It replaces the scene's environments and, for a
    /// model without lights of its own, the default light; the path tracer sees it.
    #[arg(long, value_name = "FILE")]
    pub env: Option<std::path::PathBuf>,

    /// Turn the environment map about the vertical axis, in degrees (counter-clockwise seen
    /// from above) [default: 0].
    #[arg(
        long,
        value_name = "DEG",
        requires = "env",
        value_parser = args::finite_f32,
        allow_hyphen_values = true
    )]
    pub env_rotate: Option<f32>,

    /// Multiply the environment map's radiance by S [default: 1].
    #[arg(long, value_name = "S", requires = "env", value_parser = args::non_negative_f32)]
    pub env_scale: Option<f32>,

    /// Radius of the camera's thin lens in scene units, for depth of field [default: 0, a
    /// pinhole: everything sharp].
    #[arg(long, value_name = "R", value_parser = args::non_negative_f32)]
    pub aperture: Option<f32>,

    /// Distance along the view direction that the lens keeps sharp [default: the scene file's,
    /// else the distance to what the image's centre sees].
    #[arg(long, value_name = "D", value_parser = args::positive_f32)]
    pub focus_distance: Option<f32>,

    /// How much of the lab's light model to show (see below).
    #[arg(long, value_name = "STAGE", default_value = "ambient")]
    pub stage: Stage,

    /// Threads to render with [default: one per core].
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
}

pub const STAGES_HELP: &str = "\
Stages, the lab's steps in order (--stage NAME or 1-5):
  flat       flat triangle colour ρ, black where nothing is hit
  direct     the light's power per area D = P·max(r̂·n̂,0)/(4πr²) alone (lab eq. 27)
  reflected  ρ∗D, no shadows
  shadows    ρ∗D with shadow rays
  ambient    ρ∗(D+N) with shadows and constant ambient N = 0.5 (lab eq. 30; the default)

Every channel is clamped to [0,1] and shown without gamma, as in the lab.";

/// A scene opened and checked, with what the command line says of its camera.
pub struct Setup {
    pub scene: Scene,
    /// Whether the scene is a model file (framed by the camera unless told otherwise).
    pub is_model: bool,
    /// How long reading (or making) the scene took.
    pub load: std::time::Duration,
    /// What `--env` read, for the report: the map, its size and memory, and how long reading it
    /// and building its sampling density took.
    pub env_report: Option<String>,
}

impl SceneArgs {
    /// Opens and checks the scene, with the light's overrides, and prints its warnings.
    pub fn setup(&self) -> Result<Setup> {
        let start = std::time::Instant::now();
        let instancing = if self.flatten { Instancing::Flatten } else { self.instancing };
        let options = LoadOptions { instancing };
        let OpenedScene { mut scene, is_model } = Scene::open(&self.scene, &options)?;
        let load = start.elapsed();
        for warning in &scene.warnings {
            eprintln!("raylab: warning: {warning}");
        }
        let mut env_report = None;
        if let Some(path) = &self.env {
            let start = std::time::Instant::now();
            let image = raylab::image_io::load_film(path)?;
            let read = start.elapsed();
            let turn = glam::Mat3::from_rotation_y(self.env_rotate.unwrap_or(0.0).to_radians());
            let name = path.display().to_string();
            let map = EnvironmentMap::new(name, image, self.env_scale.unwrap_or(1.0), turn)?;
            let built = start.elapsed() - read;
            let (width, height) = map.size();
            env_report = Some(format!(
                "environment map {}: {width}×{height}, read in {:.1} ms, sampling built in {:.1} \
                 ms; memory {}",
                map.name(),
                read.as_secs_f64() * 1e3,
                built.as_secs_f64() * 1e3,
                raylab::film::format_bytes(map.memory_bytes() as u64),
            ));
            scene.light_with_environment_map(map, is_model);
        }
        if let Some(position) = self.light {
            scene.point_light_mut().position = position;
        }
        if let Some(power) = self.light_power {
            scene.point_light_mut().power = Vec3::splat(power);
        }
        scene.validate()?;
        Ok(Setup { scene, is_model, load, env_report })
    }

    /// The camera overrides.
    pub fn camera_options(&self) -> CameraOptions {
        CameraOptions {
            size: self.size.map(|Size { width, height }| (width, height)),
            position: self.camera,
            yaw_deg: self.yaw,
            pitch_deg: self.pitch,
            focal_length_px: self.focal,
            fov_deg: self.fov,
            aperture_radius: self.aperture,
            focus_distance: self.focus_distance,
        }
    }

    /// The render threads asked for (0: one per core).
    pub fn threads(&self) -> usize {
        self.threads.unwrap_or(0)
    }
}

impl Setup {
    /// The scene file's camera; an animation's first keyframe's without one.
    pub fn first_camera(&self) -> Option<CameraSettings> {
        self.scene.camera.or(self.scene.keyframes.first().map(|k| k.camera))
    }
}
