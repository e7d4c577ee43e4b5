//! What a view runs on, window or not ([`Session`]: the scene, its BVH, the thread pool, the
//! controller and the settings), and its keys ([`KEYS_HELP`]).

use std::path::Path;

use raylab::interactive::{Controller, View};
use raylab::{PathSettings, SampleSettings, Scene, SceneBvh};

/// The key map, printed by `raylab view --help` and the H key.
pub const KEYS_HELP: &str = "\
Keys (motion is per second, not per frame):
  Up / Down          camera forward / back along its view direction
  Left / Right       camera yaw, the lab's R(y) (60°/s)
  Page Up / Down     camera up / down
  mouse drag         look around: grab the picture (yaw and pitch)
  W / S              light forward / back (horizontally, as the camera faces)
  A / D              light left / right
  Q / E              light up / down
  + / - , wheel      faster / slower (×√2 a step)
  1 2 3 4 5          lab stage: flat, direct, reflected, shadows, ambient
  6 7 8 9            path tracing, albedo, normals, depth
  P                  screenshot to raylab-view-N.png (the path is printed)
  R                  reset camera and light
  H                  print these keys
  Esc                quit
The title bar shows frames per second, milliseconds per frame and samples per pixel: a still
picture keeps refining (anti-aliasing) up to --max-spp samples.";

/// What the window needs to start.
pub struct Session<'a> {
    pub scene: &'a Scene,
    pub accel: &'a SceneBvh,
    pub pool: &'a rayon::ThreadPool,
    pub controller: Controller,
    pub view: View,
    pub max_spp: u32,
    /// The scene file's path-tracing and sampling settings.
    pub path_settings: PathSettings,
    pub sample_settings: SampleSettings,
    pub screenshot: Option<&'a Path>,
    pub exit_after_frames: Option<u32>,
}
