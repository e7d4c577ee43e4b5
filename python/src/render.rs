//! `raylab._raylab.render`: a scene rendered into numpy arrays by the library's render session
//! ([`RenderJob::render_film`]): the same pixels as `raylab render` writes for the same scene,
//! settings and seed.
//!
//! The render runs on a thread of its own while the calling thread waits without the GIL,
//! waking every 50 ms to report progress (the callback is called there, with the GIL, never from
//! the render's threads) and to let Python handle its signals: Ctrl-C (`KeyboardInterrupt`)
//! sets the job's stop flag, the pass in flight finishes, and the picture so far comes back
//! with its sample count. An exception in the callback stops the render the same way and is
//! raised once it has stopped.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Duration;

use numpy::{IntoPyArray, PyArray3, PyArrayMethods};
use pyo3::exceptions::{PyKeyboardInterrupt, PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;

use std::collections::BTreeMap;

use numpy::PyReadonlyArray2;
use raylab::LoadedMesh;
use raylab::mesh::CornerAttribute;
use raylab::scene::{LoadOptions, OpenError, OpenedScene, parse_scene_with_meshes};
use raylab::session::{CameraOptions, Event, FilmOutcome, RenderJob, RenderOptions};
use raylab::session::{ResolvedSettings, SessionError};
use raylab::settings::{AovKind, IntegratorKind, MaxDepth};
use raylab::{Film, Region, SamplerKind, Scene};

/// A film as a `float32` array of shape `(height, width, 3)`.
fn image<'py>(py: Python<'py>, film: &Film) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let flat: Vec<f32> = film.pixels().iter().flat_map(|p| p.to_array()).collect();
    flat.into_pyarray(py).reshape([film.height() as usize, film.width() as usize, 3])
}

fn value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

fn open_error(e: OpenError) -> PyErr {
    match &e {
        OpenError::Model(raylab::LoadError::File(_) | raylab::LoadError::Folder { .. }) => {
            PyOSError::new_err(e.to_string())
        }
        // The scene file itself could not be read (the library says so in its message).
        OpenError::SceneFile(file) if file.message.starts_with("cannot read") => {
            PyOSError::new_err(e.to_string())
        }
        _ => value_error(e),
    }
}

/// Sets its flag when dropped: when the render thread ends, by returning or by a panic.
struct SetOnDrop<'a>(&'a AtomicBool);

impl Drop for SetOnDrop<'_> {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Release);
    }
}

/// A `raylab.Scene` mesh as the Python layer passes it: name, vertices, faces, and optional
/// per-vertex normals and texture coordinates.
type ArrayMesh<'py> = (
    String,
    PyReadonlyArray2<'py, f32>,
    PyReadonlyArray2<'py, u32>,
    Option<PyReadonlyArray2<'py, f32>>,
    Option<PyReadonlyArray2<'py, f32>>,
);

/// A `raylab.Scene`'s meshes, by the names its text gives them. Normals and texture
/// coordinates are per vertex, so their corners are the faces' (as a PLY file's).
fn in_memory(meshes: &[ArrayMesh<'_>]) -> PyResult<BTreeMap<String, LoadedMesh>> {
    let mut out = BTreeMap::new();
    for (name, vertices, faces, normals, uvs) in meshes {
        let (vertices, faces) = (vertices.as_array(), faces.as_array());
        if vertices.ncols() != 3 || faces.ncols() != 3 {
            return Err(PyValueError::new_err(format!(
                "{name}: vertices and faces need 3 columns"
            )));
        }
        let positions: Vec<glam::Vec3> =
            vertices.rows().into_iter().map(|r| glam::Vec3::new(r[0], r[1], r[2])).collect();
        let triangles: Vec<[u32; 3]> =
            faces.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect();
        if let Some(i) =
            triangles.iter().position(|t| t.iter().any(|&v| v as usize >= positions.len()))
        {
            return Err(PyValueError::new_err(format!(
                "{name}: faces[{i}] indexes past the vertices"
            )));
        }
        let normals = per_vertex::<3>(name, normals, "normals", positions.len())?.map(|rows| {
            CornerAttribute::per_vertex(
                rows.into_iter().map(glam::Vec3::from).collect(),
                &triangles,
            )
        });
        let uvs = per_vertex::<2>(name, uvs, "uvs", positions.len())?.map(|rows| {
            CornerAttribute::per_vertex(
                rows.into_iter().map(glam::Vec2::from).collect(),
                &triangles,
            )
        });
        let mesh = raylab::Mesh {
            name: name.clone(),
            positions,
            triangles,
            normals,
            uvs,
            ..Default::default()
        };
        out.insert(name.clone(), LoadedMesh { mesh, ..Default::default() });
    }
    Ok(out)
}

/// Per-vertex values of mesh `name` (`what`: "normals", "uvs"), checked: one row of `N`
/// finite numbers per vertex.
fn per_vertex<const N: usize>(
    name: &str,
    values: &Option<PyReadonlyArray2<'_, f32>>,
    what: &str,
    vertices: usize,
) -> PyResult<Option<Vec<[f32; N]>>> {
    let Some(values) = values else { return Ok(None) };
    let values = values.as_array();
    if values.ncols() != N || values.nrows() != vertices {
        return Err(PyValueError::new_err(format!(
            "{name}: {what} must have shape ({vertices}, {N}), not {:?}",
            values.shape()
        )));
    }
    let rows: Vec<[f32; N]> =
        values.rows().into_iter().map(|r| std::array::from_fn(|k| r[k])).collect();
    if let Some(i) = rows.iter().position(|r| !r.iter().all(|x| x.is_finite())) {
        return Err(PyValueError::new_err(format!("{name}: {what}[{i}] is not finite")));
    }
    Ok(Some(rows))
}

/// What [`render`] returns to the Python layer: the picture, the AOV layers by name, the
/// samples per pixel reached, whether it was stopped, its region `(x0, y0, x1, y1)`, the
/// scene's warnings and the samples that were not finite.
type Rendered<'py> = (
    Bound<'py, PyArray3<f32>>,
    Vec<(&'static str, Bound<'py, PyArray3<f32>>)>,
    u32,
    bool,
    (u32, u32, u32, u32),
    Vec<String>,
    u64,
);

/// Renders `scene` (a built-in name or a file) as `raylab render` would with these options.
#[pyfunction]
#[pyo3(signature = (
    scene, size=None, spp=None, integrator=None, seed=None, max_depth=None, sampler=None,
    region=None, aovs=Vec::new(), threads=None, progress=None, scene_text=None,
    meshes=Vec::new()
))]
#[allow(clippy::too_many_arguments)]
pub fn render<'py>(
    py: Python<'py>,
    scene: String,
    size: Option<(u32, u32)>,
    spp: Option<u32>,
    integrator: Option<String>,
    seed: Option<u64>,
    max_depth: Option<u32>,
    sampler: Option<String>,
    region: Option<(u32, u32, u32, u32)>,
    aovs: Vec<String>,
    threads: Option<usize>,
    progress: Option<Bound<'py, PyAny>>,
    scene_text: Option<String>,
    meshes: Vec<ArrayMesh<'py>>,
) -> PyResult<Rendered<'py>> {
    let options = RenderOptions {
        integrator: integrator
            .map(|s| s.parse::<IntegratorKind>())
            .transpose()
            .map_err(value_error)?,
        spp,
        max_depth: max_depth.map(MaxDepth::Segments),
        seed,
        sampler: sampler.map(|s| s.parse::<SamplerKind>()).transpose().map_err(value_error)?,
        ..RenderOptions::default()
    };
    let aovs = aovs.iter().map(|a| a.parse::<AovKind>()).collect::<Result<Vec<_>, _>>();
    let aovs = aovs.map_err(value_error)?;
    let OpenedScene { scene, is_model } = match scene_text {
        None => py.detach(|| Scene::open(&scene, &LoadOptions::default())).map_err(open_error)?,
        Some(text) => {
            let meshes = in_memory(&meshes)?;
            // Files the scene names (textures, meshes) are found from the working folder.
            let path = std::path::Path::new(".").join(&scene);
            let options = LoadOptions::default();
            let scene = py
                .detach(|| parse_scene_with_meshes(&text, &path, &options, &meshes))
                .map_err(value_error)?;
            OpenedScene { scene, is_model: false }
        }
    };
    scene.validate().map_err(value_error)?;
    let settings = ResolvedSettings::resolve(&scene, &options);
    let cameras = CameraOptions { size, ..CameraOptions::default() };

    let stop = AtomicBool::new(false);
    let done = AtomicBool::new(false);
    let (rows_total, rows_done) = (AtomicU64::new(0), AtomicU64::new(0));
    let events = |event: Event| match event {
        Event::Started { rows, .. } => rows_total.store(rows, Ordering::Relaxed),
        Event::Rows(rows) => {
            rows_done.fetch_add(u64::from(rows), Ordering::Relaxed);
        }
        _ => {}
    };
    let mut raised: Option<PyErr> = None;
    let mut interrupted_by_user = false;
    let outcome = std::thread::scope(|s| {
        let render = s.spawn(|| {
            // `done` is set however the thread ends, a panic included, so the loop below ends.
            let _done = SetOnDrop(&done);
            (|| -> Result<FilmOutcome, SessionError> {
                let mut job = RenderJob::new(&scene, settings, threads.unwrap_or(0))?;
                job.aovs = aovs.clone();
                job.stop_when(&stop);
                let (width, height) = cameras.size(&scene);
                if let Some((x0, y0, x1, y1)) = region {
                    job.region = Some(Region::new([x0, y0, x1, y1], width, height)?);
                }
                let first = scene.camera.or(scene.keyframes.first().map(|k| k.camera));
                let camera = cameras.camera(first, &scene, is_model, job.accel()?)?;
                job.render_film(&camera, &events)
            })()
        });
        while !done.load(Ordering::Acquire) {
            py.detach(|| {
                for _ in 0..10 {
                    if done.load(Ordering::Acquire) {
                        break;
                    }
                    std::thread::sleep(Duration::from_millis(5));
                }
            });
            if done.load(Ordering::Acquire) {
                break;
            }
            if let Err(error) = py.check_signals() {
                interrupted_by_user |= error.is_instance_of::<PyKeyboardInterrupt>(py);
                if !interrupted_by_user {
                    raised.get_or_insert(error);
                }
                stop.store(true, Ordering::Relaxed);
            }
            if let Some(callback) = &progress
                && raised.is_none()
            {
                let total = rows_total.load(Ordering::Relaxed);
                let fraction = if total == 0 {
                    0.0
                } else {
                    rows_done.load(Ordering::Relaxed) as f64 / total as f64
                };
                if let Err(error) = callback.call1((fraction.min(1.0),)) {
                    // Ctrl-C while the callback ran is Ctrl-C: the picture so far is kept.
                    if error.is_instance_of::<PyKeyboardInterrupt>(py) {
                        interrupted_by_user = true;
                    } else {
                        raised = Some(error);
                    }
                    stop.store(true, Ordering::Relaxed);
                }
            }
        }
        render.join()
    });
    if let Some(error) = raised {
        return Err(error);
    }
    let outcome = match outcome {
        Err(_) => return Err(PyRuntimeError::new_err("the render failed unexpectedly (a panic)")),
        // Stopped before the first pass was done: there is no picture to return.
        Ok(Err(SessionError::NothingRendered)) if interrupted_by_user => {
            return Err(PyKeyboardInterrupt::new_err(
                "the render was interrupted before its first pass",
            ));
        }
        Ok(result) => result.map_err(value_error)?,
    };
    if let Some(callback) = &progress
        && !outcome.interrupted
    {
        callback.call1((1.0f64,))?;
    }
    let layers = aovs
        .iter()
        .zip(&outcome.layers)
        .map(|(kind, film)| Ok((kind.name(), image(py, film)?)))
        .collect::<PyResult<Vec<_>>>()?;
    let r = outcome.region;
    Ok((
        image(py, &outcome.film)?,
        layers,
        outcome.samples,
        outcome.interrupted,
        (r.x0, r.y0, r.x1, r.y1),
        scene.warnings.clone(),
        outcome.discarded,
    ))
}

/// Writes a `float32` image of shape `(height, width, 3)` to `path`, in the format its
/// extension names: linear values for `.exr` and `.pfm`; for `.png` and `.ppm`, brightened by
/// `2^exposure`, tone-mapped (`clamp`, `reinhard` or `aces`) and sRGB-encoded if `srgb`.
/// Atomic: a file that cannot be written is left as it was.
#[pyfunction]
#[pyo3(signature = (path, image, exposure=0.0, tone_map="clamp", srgb=true))]
pub fn write_image(
    py: Python<'_>,
    path: std::path::PathBuf,
    image: numpy::PyReadonlyArray3<'_, f32>,
    exposure: f32,
    tone_map: &str,
    srgb: bool,
) -> PyResult<()> {
    use numpy::PyUntypedArrayMethods;
    let shape = image.shape();
    if shape[2] != 3 || shape[0] == 0 || shape[1] == 0 {
        return Err(PyValueError::new_err(format!(
            "image must have shape (height, width, 3) with some pixels, not {shape:?}"
        )));
    }
    let (height, width) = (u32::try_from(shape[0]), u32::try_from(shape[1]));
    let (Ok(height), Ok(width)) = (height, width) else {
        return Err(PyValueError::new_err(format!("image of {shape:?} pixels is too large")));
    };
    let flat = image.as_slice().map_err(|_| PyValueError::new_err("image must be C-contiguous"))?;
    let pixels = flat.as_chunks::<3>().0.iter().map(|&p| glam::Vec3::from(p)).collect();
    let film = Film::from_pixels(width, height, pixels);
    let display =
        raylab::film::Display { exposure, tone_map: tone_map.parse().map_err(value_error)?, srgb };
    py.detach(|| raylab::image_io::save_film(&path, &film, &display)).map_err(|e| {
        let message = e.to_string();
        match e {
            raylab::image_io::ImageIoError::Io { .. }
            | raylab::image_io::ImageIoError::IsAFolder { .. }
            | raylab::image_io::ImageIoError::NoSuchFolder { .. } => PyOSError::new_err(message),
            _ => PyValueError::new_err(message),
        }
    })
}
