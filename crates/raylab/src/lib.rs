//! # raylab
//!
//! A fast, correct CPU ray tracer that starts as the classic Cornell-box ray-tracing lab
//! (KTH DH2323 Lab 2, Bristol COMS30115) and does it right: watertight ray/triangle intersection,
//! the closest hit, shadow rays without acne at any scale, and the true field of view.
//!
//! ## Ray queries
//!
//! Build a [`Bvh`] over a mesh's triangles and ask it the two questions of every ray tracer
//! ([`Accelerator`]): what does this ray hit first ([`closest_hit`](Accelerator::closest_hit)),
//! and is anything in the way ([`occluded`](Accelerator::occluded)), for one ray or a batch. The
//! test is watertight (no ray slips between two triangles that share an edge), and the answers
//! are exactly those of testing every triangle ([`BruteForce`]), ties at equal `t` going to the
//! lowest triangle index.
//!
//! ```
//! use glam::Vec3;
//! use raylab::{Accelerator, Bvh, Ray};
//!
//! let file = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/meshes/bunny_lowres.obj");
//! let mesh = raylab::scene::load_mesh(std::path::Path::new(file))?.flattened();
//! let triangles: Vec<[Vec3; 3]> = mesh.triangle_vertices().collect();
//! let bvh = Bvh::new(&triangles);
//!
//! // One ray, from far in front of the bunny toward the middle of its bounding box.
//! let (lo, hi) = triangles.iter().flatten().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), &v| {
//!     (lo.min(v), hi.max(v))
//! });
//! let centre = (lo + hi) / 2.0;
//! let origin = centre - Vec3::Z * 10.0 * (hi - lo).length();
//! let ray = Ray::new(origin, centre - origin);
//! let hit = bvh.closest_hit(&ray).expect("the bunny");
//! let [v0, v1, v2] = triangles[hit.triangle as usize];
//! let point = hit.b0() * v0 + hit.b1 * v1 + hit.b2 * v2; // the barycentric weights of the hit
//! assert!((point - ray.at(hit.t)).length() < 1e-3 * (hi - lo).length());
//!
//! // A shadow ray is a segment: is anything between the hit and the origin?
//! let back = Ray::segment(origin, point - origin, 0.999);
//! assert!(!bvh.occluded(&back));
//!
//! // A batch: a tile of rays answered together (coherent rays go as packets), with exactly
//! // the single-ray answers.
//! let rays: Vec<Ray> = (0..64)
//!     .map(|i| {
//!         let offset = Vec3::new((i % 8) as f32 - 3.5, (i / 8) as f32 - 3.5, 0.0) * 0.01;
//!         Ray::new(origin, centre + offset * (hi - lo).length() - origin)
//!     })
//!     .collect();
//! let mut hits = vec![None; rays.len()];
//! bvh.closest_hits(&rays, &mut hits);
//! let mut blocked = vec![false; rays.len()];
//! bvh.occluded_each(&rays, &mut blocked);
//! for (ray, (hit, blocked)) in rays.iter().zip(hits.iter().zip(&blocked)) {
//!     assert_eq!(*hit, bvh.closest_hit(ray));
//!     assert_eq!(*blocked, hit.is_some());
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## Rendering
//!
//! The renderer is one flow: **scene → accelerator → integrator → film → image**. Its
//! integrators are the lab's light model ([`Lab`]) and a physically based path tracer
//! ([`Path`]) that converges to Mitsuba 3's images.
//!
//! ```
//! use raylab::{render, Accelerator, BruteForce, Camera, Lab, Scene, Stage};
//!
//! let scene = Scene::built_in("cornell")?;
//! let accel = BruteForce::new(&scene.vertices());
//! let camera = Camera::lab(64, 64);
//! let film = render(&camera, &Lab::new(&scene, &accel, Stage::Ambient), &|_rows| {})?;
//! let image = film.to_rgb8_clamped()?;
//! assert_eq!(image.dimensions(), (64, 64));
//!
//! // Ray queries work on their own too.
//! let hit = accel.closest_hit(&camera.pixel_ray(32, 32)).expect("the back wall");
//! assert!(hit.t > 3.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Beyond the lab, the `path` integrator path-traces any scene, here a scene file's text, with
//! an [`Accumulator`] adding samples per pixel (see `docs/scene-format.md` for the format):
//!
//! ```
//! use raylab::{Accumulator, Bvh, Path, PathSettings};
//!
//! let scene = raylab::scene::parse_scene(
//!     r#"
//!     [camera]
//!     position = [0, 0, 3]
//!     target = [0, 0, 0]
//!
//!     [materials.gold]
//!     type = "roughconductor"
//!     material = "Au"
//!     alpha = 0.2
//!
//!     [[shapes]]
//!     type = "sphere"
//!     material = "gold"
//!
//!     [[lights]]
//!     type = "environment"
//!     radiance = [1, 1, 1]
//!     "#,
//!     std::path::Path::new("example.toml"),
//! )?;
//! let bvh = Bvh::new(&scene.vertices());
//! let path = Path::new(&scene, &bvh, PathSettings::default());
//! let camera = scene.camera.expect("the file has one").camera(32, 32);
//! let mut picture = Accumulator::new(32, 32)?;
//! for _ in 0..4 {
//!     picture.add_sample(&camera, &path);
//! }
//! let film = picture.mean()?;
//! // Gold reflects more red than blue, and no more light than the sky sends.
//! let centre = film.pixel(16, 16);
//! assert!(centre.x > centre.z && centre.max_element() <= 1.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

//! ## A render session
//!
//! [`session`] is what the `raylab` command renders through: open any scene by name
//! ([`Scene::open`]), resolve its settings with your overrides by one rule, and let a
//! [`RenderJob`](session::RenderJob) build the BVH, render on its threads and write the image
//! (or an OpenEXR part, with checkpoints, AOV layers and a progress callback):
//!
//! ```
//! use raylab::Scene;
//! use raylab::session::{CameraOptions, RenderJob, RenderOptions, ResolvedSettings};
//!
//! let opened = Scene::open("cornell", &Default::default())?;
//! let settings = ResolvedSettings::resolve(&opened.scene, &RenderOptions::default());
//! let mut job = RenderJob::new(&opened.scene, settings, 0)?; // 0: a thread per core
//! let cameras = CameraOptions { size: Some((64, 48)), ..CameraOptions::default() };
//! let camera = cameras.camera(opened.scene.camera, &opened.scene, opened.is_model, job.accel()?)?;
//! let output = std::env::temp_dir().join("raylab-doc-example.png");
//! let outcome = job.render_frame(&camera, &output, None, &|_event| {})?;
//! assert_eq!((outcome.samples, outcome.interrupted), (1, false)); // the lab's one ray a pixel
//! # std::fs::remove_file(&output)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! More in `examples/`: rays against an OBJ mesh, a scene built in code, a TOML scene file.

#![warn(missing_docs)]

pub mod accel;
pub mod bvh;
pub mod camera;
pub mod color;
pub mod cpu;
#[cfg(feature = "io")]
pub mod file_bytes;
pub mod film;
pub mod filter;
pub mod float;
#[cfg(feature = "support")]
#[doc(hidden)]
pub mod fuzzing;
pub mod geometry;
#[cfg(feature = "support")]
#[doc(hidden)]
pub mod image_compare;
#[cfg(feature = "io")]
pub mod image_io;
pub mod integrator;
pub mod interaction;
pub mod interactive;
pub mod light;
pub mod material;
pub mod memory;
pub mod mesh;
#[cfg(feature = "io")]
pub mod parts;
#[cfg(feature = "io")]
mod quiet_panic;
pub mod ray;
#[cfg(feature = "bench")]
#[doc(hidden)]
pub mod ray_sets;
pub mod region;
pub mod render;
pub mod sampling;
pub mod scene;
#[cfg(feature = "io")]
pub mod session;
pub mod settings;
pub mod texture;
pub mod triangle;
pub mod unknown_name;

pub use accel::{Accelerator, BruteForce, Hit};
pub use bvh::{BuildSettings, Bvh, SceneBvh};
pub use camera::{Camera, RayGenerator};
pub use film::{Film, FilmError};
pub use filter::Filter;
pub use geometry::Geometry;
pub use integrator::{
    Aov, AovKind, Integrator, Lab, LightSet, Path, PathScalar, PathSettings, Stage,
    TriangleSampling,
};
pub use interaction::SurfaceInteraction;
pub use light::{Light, PointLight};
pub use material::{Bsdf, Material, MaterialError};
pub use mesh::{Mesh, MeshMaterial};
pub use ray::{Ray, SurfacePoint};
pub use region::Region;
pub use render::{Accumulator, SampleSettings, render, render_samples};
pub use sampling::{Sampler, SamplerKind, sample_offset};
#[cfg(feature = "io")]
pub use scene::{LoadError, LoadedMesh, load_mesh};
pub use scene::{Scene, SceneError};
pub use triangle::Triangle;
pub use unknown_name::UnknownName;
