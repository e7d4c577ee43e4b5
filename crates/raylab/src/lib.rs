//! # raylab
//!
//! A fast, correct CPU ray tracer that starts as the classic Cornell-box ray-tracing lab
//! (KTH DH2323 Lab 2, Bristol COMS30115) and does it right: watertight ray/triangle intersection,
//! the closest hit, shadow rays without acne at any scale, and the true field of view.
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

#![warn(missing_docs)]

pub mod accel;
pub mod bvh;
pub mod camera;
pub mod film;
pub mod float;
pub mod geometry;
pub mod image_compare;
pub mod image_io;
pub mod integrator;
pub mod interactive;
pub mod light;
pub mod material;
pub mod mesh;
pub mod ray;
pub mod ray_sets;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod triangle;

pub use accel::{Accelerator, BruteForce, Hit};
pub use bvh::{BuildSettings, Bvh};
pub use camera::{Camera, RayGenerator};
pub use film::{Film, FilmError};
pub use geometry::{Geometry, SurfaceInteraction};
pub use integrator::{Aov, AovKind, Integrator, Lab, Path, PathSettings, Stage};
pub use light::{Light, LightSet, PointLight, TriangleSampling};
pub use material::{Bsdf, Material};
pub use mesh::{Mesh, MeshMaterial};
pub use ray::{Ray, SurfacePoint};
pub use render::{Accumulator, Filter, SampleSettings, render, render_samples};
pub use sampling::{Sampler, SamplerKind, sample_offset};
pub use scene::{LoadError, LoadedMesh, load_mesh};
pub use scene::{Scene, SceneError};
pub use triangle::Triangle;
