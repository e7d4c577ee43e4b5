//! What `raylab render` and `raylab view` share: the scene, the camera, the light, the stage and
//! the threads, parsed and checked the same way.

use anyhow::{Context, Result, bail};
use clap::Args;
use glam::Vec3;
use raylab::camera::tidy;
use raylab::scene::CameraSettings;
use raylab::{Camera, Scene, Stage};

use crate::args::{self, Size};
use crate::system;

/// The most threads `--threads` accepts.
const MAX_THREADS: usize = 1024;

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

    /// Draw every copy of a mesh the model uses in several places (glTF nodes sharing a mesh)
    /// as triangles of its own, in one BVH, instead of storing the mesh once under a two-level
    /// BVH: more memory, the same picture; for comparisons.
    #[arg(long)]
    pub flatten: bool,

    /// Point-light position [default: the lab's (0, -0.5, -0.7); for a model, above it, to the
    /// right and in front].
    #[arg(long, value_name = "X,Y,Z", value_parser = args::vec3, allow_hyphen_values = true)]
    pub light: Option<Vec3>,

    /// Point-light power P per channel [default: the lab's 14; for a model, enough for an
    /// irradiance of 1 at its centre].
    #[arg(long, value_name = "WATTS", value_parser = args::non_negative_f32)]
    pub light_power: Option<f32>,

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

/// A checked scene, its camera and the thread count.
pub struct Setup {
    pub scene: Scene,
    pub camera: Camera,
    pub threads: usize,
    /// Whether the scene is a model file (framed by the camera unless told otherwise).
    pub is_model: bool,
    /// How long reading (or making) the scene took.
    pub load: std::time::Duration,
}

impl SceneArgs {
    /// Loads and checks everything before any rendering, so that no work is lost to a bad value.
    pub fn setup(&self) -> Result<Setup> {
        let start = std::time::Instant::now();
        let (mut scene, is_model) = load_scene(&self.scene, self.flatten)?;
        let load = start.elapsed();
        let scene_camera = scene.camera;
        if let Some(position) = self.light {
            scene.point_light_mut().position = position;
        }
        if let Some(power) = self.light_power {
            scene.point_light_mut().power = Vec3::splat(power);
        }
        scene.validate()?;

        let Size { width, height } = self.size.unwrap_or(match scene.settings.size {
            Some((width, height)) => Size { width, height },
            None => Size { width: 500, height: 500 },
        });
        // The scene file's camera; an animation's first keyframe without one.
        let settings = scene_camera.or(scene.keyframes.first().map(|k| k.camera));
        let camera = self.camera(settings, &scene, is_model, width, height)?;
        let threads = match self.threads {
            None | Some(0) => system::cores(),
            Some(n) if n > MAX_THREADS => bail!("--threads {n} is more than {MAX_THREADS}"),
            Some(n) => n,
        };
        Ok(Setup { scene, camera, threads, is_model, load })
    }
}

impl SceneArgs {
    /// The camera of a `width×height` picture of `scene`: `settings` (a scene file's camera, or
    /// an animation's at some frame; `None`: the lab's, or one framing a model), with the
    /// command line's options overriding its parts.
    pub fn camera(
        &self,
        settings: Option<CameraSettings>,
        scene: &Scene,
        is_model: bool,
        width: u32,
        height: u32,
    ) -> Result<Camera> {
        let base = match settings {
            Some(settings) => settings.camera(width, height),
            None => Camera::lab(width, height),
        };
        let focal_length_px = match (self.focal, self.fov) {
            (Some(focal), _) => focal,
            (None, Some(fov)) => Camera::focal_length_for_fov(width, fov),
            (None, None) => base.focal_length_px,
        };
        if !focal_length_px.is_finite() {
            bail!(
                "--fov {} is too small: the focal length would be infinite",
                self.fov.unwrap_or(0.0)
            );
        }
        let default_position = match scene.bounds() {
            Some((lo, hi)) if is_model => Camera::framing(lo, hi, width, height).position,
            _ => base.position,
        };
        let mut camera = Camera {
            position: self.camera.unwrap_or(default_position),
            yaw: self.yaw.map_or(base.yaw, f32::to_radians),
            pitch: self.pitch.map_or(base.pitch, f32::to_radians),
            roll: base.roll,
            focal_length_px,
            width,
            height,
            aperture_radius: self.aperture.unwrap_or(base.aperture_radius),
            focus_distance: self.focus_distance.unwrap_or(base.focus_distance),
        };
        if camera.has_lens() && self.focus_distance.is_none() && settings.is_none() {
            // Focus on what the image's centre sees.
            let centre = camera.ray(width as f32 / 2.0, height as f32 / 2.0);
            let bvh = system::build_bvh(&scene.name, &scene.geometry)?;
            if let Some(hit) = raylab::Accelerator::closest_hit(&bvh, &centre) {
                camera.focus_distance = (hit.t * centre.direction.dot(camera.forward())).max(1e-6);
            }
        }
        Ok(camera)
    }
}

impl Setup {
    /// The render threads.
    pub fn thread_pool(&self) -> Result<rayon::ThreadPool> {
        rayon::ThreadPoolBuilder::new()
            .num_threads(self.threads)
            .build()
            .context("cannot start the render threads")
    }
}

/// A built-in scene by name, or a model file (anything that looks like a path), its instances
/// placed as copies if `flatten`. The flag says whether it is a model.
fn load_scene(name: &str, flatten: bool) -> Result<(Scene, bool)> {
    let path = std::path::Path::new(name);
    let looks_like_a_file = path.exists() || name.contains('/') || name.contains('.');
    match Scene::built_in(name) {
        Ok(scene) => return Ok((scene, false)),
        // Neither a built-in name nor a file: say what the built-in scenes are.
        Err(unknown) if !looks_like_a_file => return Err(unknown.into()),
        Err(_) => {}
    }
    let lower = name.to_ascii_lowercase();
    if lower.ends_with(".toml") {
        let scene = raylab::scene::load_scene_file(path)?;
        for warning in &scene.warnings {
            eprintln!("raylab: warning: {warning}");
        }
        return Ok((scene, false));
    }
    let mut loaded = raylab::scene::load_mesh(path)?;
    if flatten {
        loaded.mesh = loaded.flattened();
        loaded.instanced.clear();
    }
    for warning in &loaded.warnings {
        eprintln!("raylab: warning: {warning}");
    }
    // A file with its own camera (glTF) is seen through it; other models are framed.
    Ok((Scene::from_loaded(&loaded), loaded.camera.is_none()))
}

/// A vector as `(x, y, z)` with [`tidy`] numbers.
pub fn tidy_vec3(v: Vec3) -> String {
    format!("({}, {}, {})", tidy(v.x), tidy(v.y), tidy(v.z))
}
