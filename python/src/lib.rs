//! `raylab._raylab`: the extension module under the Python package `raylab` (`python/raylab`).
//!
//! The Python layer (`raylab/__init__.py`) checks the arguments' kinds and shapes, names them
//! in its errors and converts them to the layouts this module takes: C-contiguous `float32`
//! arrays of shape `(n, 3)` for points and directions, `uint32` of shape `(m, 3)` for faces,
//! `float32` of shape `(n,)` for ray limits. This module checks them again (a wrong layout is
//! a `ValueError`, never a crash), checks the values (non-finite points, zero directions,
//! faces out of range; a ray's values as it is traced), and answers with the library's own
//! single-ray queries ([`Accelerator::closest_hit`], [`Accelerator::occluded`],
//! [`Bvh::count_crossings`], [`Bvh::crossings`]), chunk by chunk on rayon's threads, the GIL
//! released. A large batch on a large tree is traced in the order of [`raylab::bvh::order`]
//! (rays through the same part of the tree one after the other, for the cache) and its answers
//! put back in the rays' order (all but `all_hits`, which traces as given). The answers are the library's, bit for
//! bit, in any order (`tests/test_queries.py` checks them against answers written by the Rust
//! library in `tests/python_suite.rs`).

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use glam::Vec3;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use numpy::{PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use rayon::prelude::*;

use raylab::bvh::{Batch, RaySource};
use raylab::{Bvh, Hit, Ray};

mod render;

/// Rays per task: the library's batch chunks.
const CHUNK: usize = Batch::CHUNK;

/// A triangle mesh and its BVH, built once.
#[pyclass(module = "raylab._raylab", name = "Mesh")]
struct Mesh {
    vertices: Vec<Vec3>,
    faces: Vec<[u32; 3]>,
    bvh: Bvh,
}

/// The rows of a C-contiguous `(n, 3)` array as points, or a `ValueError` naming `name`.
fn rows<'a>(array: &'a PyReadonlyArray2<'_, f32>, name: &str) -> PyResult<&'a [[f32; 3]]> {
    let shape = array.shape();
    if shape.len() != 2 || shape[1] != 3 {
        return Err(PyValueError::new_err(format!("{name} must have shape (n, 3)")));
    }
    let flat = array
        .as_slice()
        .map_err(|_| PyValueError::new_err(format!("{name} must be C-contiguous")))?;
    let (rows, rest) = flat.as_chunks::<3>();
    debug_assert!(rest.is_empty());
    Ok(rows)
}

/// A C-contiguous `(n,)` array as a slice, or a `ValueError` naming `name`.
fn column<'a>(array: &'a PyReadonlyArray1<'_, f32>, name: &str) -> PyResult<&'a [f32]> {
    array.as_slice().map_err(|_| PyValueError::new_err(format!("{name} must be C-contiguous")))
}

/// The faces as index triples, each checked against the vertex count.
fn faces_of(faces: &PyReadonlyArray2<'_, u32>, vertices: usize) -> PyResult<Vec<[u32; 3]>> {
    let shape = faces.shape();
    if shape.len() != 2 || shape[1] != 3 {
        return Err(PyValueError::new_err("faces must have shape (m, 3)"));
    }
    let flat = faces.as_slice().map_err(|_| PyValueError::new_err("faces must be C-contiguous"))?;
    let (faces, _) = flat.as_chunks::<3>();
    if let Some((i, face)) =
        faces.iter().enumerate().find(|(_, f)| f.iter().any(|&v| v as usize >= vertices))
    {
        return Err(PyValueError::new_err(format!(
            "faces[{i}] = {face:?} indexes past the {vertices} vertices"
        )));
    }
    Ok(faces.to_vec())
}

/// The points as vectors, each checked to be finite.
fn points_of(points: &[[f32; 3]], name: &str) -> PyResult<Vec<Vec3>> {
    if let Some(i) = points.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        return Err(PyValueError::new_err(format!("{name}[{i}] = {:?} is not finite", points[i])));
    }
    Ok(points.iter().map(|&p| Vec3::from(p)).collect())
}

fn triangles(vertices: &[Vec3], faces: &[[u32; 3]]) -> Vec<[Vec3; 3]> {
    faces.iter().map(|f| f.map(|v| vertices[v as usize])).collect()
}

/// A ray limit: one for every ray, or one per ray.
#[derive(FromPyObject)]
enum Limit<'py> {
    One(f32),
    Each(PyReadonlyArray1<'py, f32>),
}

/// [`Limit`]'s values: one, or a slice of one per ray.
#[derive(Clone, Copy)]
enum Limits<'a> {
    One(f32),
    Each(&'a [f32]),
}

impl Limits<'_> {
    #[inline(always)]
    fn get(&self, i: usize) -> f32 {
        match self {
            Limits::One(x) => *x,
            Limits::Each(xs) => xs[i],
        }
    }
}

/// A query's rays as the Python layer passes them: one tuple `(origins, directions, t_min,
/// t_max)`, the arrays C-contiguous `float32`.
#[derive(FromPyObject)]
struct RayArgs<'py>(PyReadonlyArray2<'py, f32>, PyReadonlyArray2<'py, f32>, Limit<'py>, Limit<'py>);

/// The rays of a query, their layouts checked; each ray's values (finite origin, finite
/// non-zero direction, limits that are not NaN) are checked as it is traced ([`get`](Self::get)).
struct Rays<'a> {
    origins: &'a [[f32; 3]],
    directions: &'a [[f32; 3]],
    t_min: Limits<'a>,
    t_max: Limits<'a>,
}

impl<'a> Rays<'a> {
    fn new(RayArgs(origins, directions, t_min, t_max): &'a RayArgs<'_>) -> PyResult<Rays<'a>> {
        let origins = rows(origins, "origins")?;
        let n = origins.len();
        let limits = |limit: &'a Limit<'_>, name: &str| -> PyResult<Limits<'a>> {
            Ok(match limit {
                Limit::One(x) => Limits::One(*x),
                Limit::Each(array) => {
                    let xs = column(array, name)?;
                    if xs.len() != n {
                        return Err(PyValueError::new_err(format!(
                            "{name} has {} values for {n} rays",
                            xs.len()
                        )));
                    }
                    Limits::Each(xs)
                }
            })
        };
        let rays = Rays {
            origins,
            directions: rows(directions, "directions")?,
            t_min: limits(t_min, "t_min")?,
            t_max: limits(t_max, "t_max")?,
        };
        if rays.directions.len() != n {
            return Err(PyValueError::new_err(format!(
                "origins has {n} rows but directions has {}",
                rays.directions.len()
            )));
        }
        Ok(rays)
    }

    /// The ray from these parts, or what is wrong with it (`i` its index, for the message).
    #[inline(always)]
    fn ray(i: usize, o: [f32; 3], d: [f32; 3], t_min: f32, t_max: f32) -> Result<Ray, String> {
        let finite = |v: [f32; 3]| v[0].is_finite() & v[1].is_finite() & v[2].is_finite();
        let good = finite(o) & finite(d) & (d != [0.0; 3]) & !t_min.is_nan() & !t_max.is_nan();
        if !good {
            return Err(Rays::fault(i, o, d, t_min, t_max));
        }
        Ok(Ray { origin: Vec3::from(o), direction: Vec3::from(d), t_min: t_min.max(0.0), t_max })
    }

    /// What is wrong with a bad ray (out of the traces' loops).
    #[cold]
    #[inline(never)]
    fn fault(i: usize, o: [f32; 3], d: [f32; 3], t_min: f32, t_max: f32) -> String {
        let finite = |v: [f32; 3]| v.iter().all(|x| x.is_finite());
        if !finite(o) {
            format!("origins[{i}] = {o:?} is not finite")
        } else if !finite(d) || d == [0.0; 3] {
            format!("directions[{i}] = {d:?} is not a finite, non-zero direction")
        } else {
            format!("ray {i}: t_min = {t_min}, t_max = {t_max}: NaN")
        }
    }

    /// Ray `i`, or what is wrong with it.
    #[inline(always)]
    fn get(&self, i: usize) -> Result<Ray, String> {
        Rays::ray(i, self.origins[i], self.directions[i], self.t_min.get(i), self.t_max.get(i))
    }

    /// Ray `i` as it is, unchecked (NaN and all).
    #[inline(always)]
    fn unchecked(&self, i: usize) -> Ray {
        let (origin, direction) = (Vec3::from(self.origins[i]), Vec3::from(self.directions[i]));
        Ray { origin, direction, t_min: self.t_min.get(i), t_max: self.t_max.get(i) }
    }

    /// The message for the first bad ray (after a parallel pass found one, maybe a later one).
    fn first_error(&self) -> String {
        (0..self.len()).find_map(|i| self.get(i).err()).unwrap_or_else(|| {
            "a ray was bad while it was traced but is not now: were the arrays changed by \
             another thread during the query?"
                .into()
        })
    }

    /// Runs `answer` on every ray and its index in parallel, in chunks, for `out`'s chunk
    /// (`CHUNK` slots of each output per chunk); the first bad ray's message if there is one
    /// (the outputs are then partly written).
    fn each<O: Send>(
        &self,
        out: O,
        split: impl Fn(O) -> Vec<O> + Sync,
        answer: impl Fn(&mut O, usize, &Ray) + Sync,
    ) -> Result<(), String> {
        let chunk = |(c, mut out): (usize, O)| {
            let start = c * CHUNK;
            let end = (start + CHUNK).min(self.len());
            let parts = self.origins[start..end].iter().zip(&self.directions[start..end]);
            for (k, (&o, &d)) in parts.enumerate() {
                let (t0, t1) = (self.t_min.get(start + k), self.t_max.get(start + k));
                answer(&mut out, k, &Rays::ray(start + k, o, d, t0, t1)?);
            }
            Ok(())
        };
        let parts = split(out);
        // One chunk on the calling thread: no pool's thread to wake (see `run`).
        let found = if parts.len() <= 1 {
            parts.into_iter().enumerate().try_for_each(chunk)
        } else {
            parts.into_par_iter().enumerate().try_for_each(chunk)
        };
        // The threads may have met a later bad ray first: name the first one.
        found.map_err(|_: String| self.first_error())
    }
}

/// The library's batch engine reads the rays from the arrays, checking each as it is traced.
impl RaySource for Rays<'_> {
    type Error = String;

    fn len(&self) -> usize {
        self.origins.len()
    }

    #[inline(always)]
    fn ray(&self, i: usize) -> Result<Ray, String> {
        self.get(i)
    }

    #[inline(always)]
    fn ray_unchecked(&self, i: usize) -> Ray {
        self.unchecked(i)
    }

    /// Asks the cache for ray `i`'s origin and direction (and limits, if they are arrays).
    #[inline(always)]
    fn prefetch(&self, i: usize) {
        use raylab::bvh::batch::prefetch;
        prefetch(self.origins.as_ptr().wrapping_add(i).cast());
        prefetch(self.directions.as_ptr().wrapping_add(i).cast());
        for limits in [self.t_min, self.t_max] {
            if let Limits::Each(xs) = limits {
                prefetch(xs.as_ptr().wrapping_add(i).cast());
            }
        }
    }
}

/// A closest hit as `intersect`'s columns: `(t, triangle, u, v)`, `(inf, -1, 0, 0)` for a miss.
#[inline(always)]
fn hit_row(hit: Option<Hit>) -> (f32, i64, f32, f32) {
    match hit {
        Some(h) => (h.t, i64::from(h.triangle), h.b1, h.b2),
        None => (f32::INFINITY, -1, 0.0, 0.0),
    }
}

/// Thread pools by size, made once each.
fn pool(threads: usize) -> PyResult<Arc<rayon::ThreadPool>> {
    static POOLS: Mutex<Option<HashMap<usize, Arc<rayon::ThreadPool>>>> = Mutex::new(None);
    let mut pools = POOLS.lock().map_err(|_| PyRuntimeError::new_err("thread pools poisoned"))?;
    let pools = pools.get_or_insert_with(HashMap::new);
    if let Some(pool) = pools.get(&threads) {
        return Ok(pool.clone());
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start {threads} threads: {e}")))?;
    let pool = Arc::new(pool);
    pools.insert(threads, pool.clone());
    Ok(pool)
}

/// Runs `work` on `threads` threads (rayon's global pool for `None`), the GIL released; a
/// query of `rays` rays that fit one chunk runs on the calling thread instead (waking a pool's
/// thread costs more than such a query: 10–90 µs against about 3 µs for Embree's call).
fn run<T: Send>(
    py: Python<'_>,
    threads: Option<usize>,
    rays: usize,
    work: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    let pool = match threads {
        Some(0) => return Err(PyValueError::new_err("threads must be at least 1")),
        _ if rays <= CHUNK => None,
        None => None,
        Some(n) => Some(pool(n)?),
    };
    Ok(py.detach(|| match pool {
        Some(pool) => pool.install(work),
        None => work(),
    }))
}

#[pymethods]
impl Mesh {
    #[new]
    fn new(
        py: Python<'_>,
        vertices: PyReadonlyArray2<'_, f32>,
        faces: PyReadonlyArray2<'_, u32>,
    ) -> PyResult<Mesh> {
        let vertices = points_of(rows(&vertices, "vertices")?, "vertices")?;
        let faces = faces_of(&faces, vertices.len())?;
        Mesh::build(py, vertices, faces)
    }

    /// The vertices, a `float32` array of shape `(n, 3)` (a copy).
    #[getter]
    fn vertices<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let flat: Vec<f32> = self.vertices.iter().flat_map(|v| v.to_array()).collect();
        flat.into_pyarray(py).reshape([self.vertices.len(), 3])
    }

    /// The faces, a `uint32` array of shape `(m, 3)` (a copy).
    #[getter]
    fn faces<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<u32>>> {
        let flat: Vec<u32> = self.faces.iter().flatten().copied().collect();
        flat.into_pyarray(py).reshape([self.faces.len(), 3])
    }

    /// Bytes of the BVH (nodes and leaf records).
    #[getter]
    fn bvh_bytes(&self) -> usize {
        self.bvh.stats().bytes()
    }

    /// The closest hits: `(t, triangle, u, v)`, `t = inf` and `triangle = -1` for a miss.
    #[pyo3(signature = (rays, threads=None))]
    #[allow(clippy::type_complexity)]
    fn intersect<'py>(
        &self,
        py: Python<'py>,
        rays: RayArgs<'py>,
        threads: Option<usize>,
    ) -> PyResult<(
        Bound<'py, PyArray1<f32>>,
        Bound<'py, PyArray1<i64>>,
        Bound<'py, PyArray1<f32>>,
        Bound<'py, PyArray1<f32>>,
    )> {
        let rays = Rays::new(&rays)?;
        let bvh = &self.bvh;
        let n = rays.len();
        let (mut t, mut triangle) = (vec![0.0f32; n], vec![0i64; n]);
        let (mut u, mut v) = (vec![0.0f32; n], vec![0.0f32; n]);
        // The columns filled with the GIL released too.
        run(py, threads, n, || -> Result<(), String> {
            let hits = Batch::new(bvh).closest_hits(&rays)?;
            for (i, hit) in hits.into_iter().enumerate() {
                (t[i], triangle[i], u[i], v[i]) = hit_row(hit);
            }
            Ok(())
        })?
        .map_err(PyValueError::new_err)?;
        Ok((t.into_pyarray(py), triangle.into_pyarray(py), u.into_pyarray(py), v.into_pyarray(py)))
    }

    /// Whether anything is hit between `t_min` and `t_max`, per ray.
    #[pyo3(signature = (rays, threads=None))]
    fn occluded<'py>(
        &self,
        py: Python<'py>,
        rays: RayArgs<'py>,
        threads: Option<usize>,
    ) -> PyResult<Bound<'py, PyArray1<bool>>> {
        let rays = Rays::new(&rays)?;
        let bvh = &self.bvh;
        let blocked = run(py, threads, rays.len(), || Batch::new(bvh).occluded(&rays))?
            .map_err(PyValueError::new_err)?;
        Ok(blocked.into_pyarray(py))
    }

    /// How often each ray crosses the surface between `t_min` and `t_max` (every hit, not
    /// only the closest, a shared edge or vertex counted once where the surface goes on
    /// across it: `Bvh::crossings`).
    #[pyo3(signature = (rays, threads=None))]
    fn count_hits<'py>(
        &self,
        py: Python<'py>,
        rays: RayArgs<'py>,
        threads: Option<usize>,
    ) -> PyResult<Bound<'py, PyArray1<i64>>> {
        let rays = Rays::new(&rays)?;
        let bvh = &self.bvh;
        let batch = Batch::new(bvh);
        let counts = run(py, threads, rays.len(), || {
            batch.answers(&rays, |ray| i64::from(bvh.count_crossings(ray)))
        })?
        .map_err(PyValueError::new_err)?;
        Ok(counts.into_pyarray(py))
    }

    /// Every crossing of every ray (as [`count_hits`](Self::count_hits) counts them), at most
    /// `max_hits` per ray (its nearest): `(ray, triangle, t, u, v)`, sorted by ray, then `t`,
    /// then triangle.
    #[pyo3(signature = (rays, max_hits, threads=None))]
    #[allow(clippy::type_complexity, clippy::too_many_arguments)]
    fn all_hits<'py>(
        &self,
        py: Python<'py>,
        rays: RayArgs<'py>,
        max_hits: usize,
        threads: Option<usize>,
    ) -> PyResult<(
        Bound<'py, PyArray1<i64>>,
        Bound<'py, PyArray1<i64>>,
        Bound<'py, PyArray1<f32>>,
        Bound<'py, PyArray1<f32>>,
        Bound<'py, PyArray1<f32>>,
    )> {
        let rays = Rays::new(&rays)?;
        let bvh = &self.bvh;
        // Each chunk's hits, in ray order; the chunks then joined in order.
        let chunks = rays.len().div_ceil(CHUNK);
        let mut found: Vec<Vec<(u32, Hit)>> = vec![Vec::new(); chunks];
        run(py, threads, rays.len(), || {
            rays.each(
                &mut found[..],
                |f| f.chunks_mut(1).collect(),
                |f, k, ray| {
                    let hits = &mut f[0];
                    let start = hits.len();
                    bvh.crossings(ray, |h| hits.push((k as u32, h)));
                    let mine = &mut hits[start..];
                    mine.sort_unstable_by(|a, b| {
                        a.1.t.total_cmp(&b.1.t).then(a.1.triangle.cmp(&b.1.triangle))
                    });
                    hits.truncate(start + max_hits.min(hits.len() - start));
                },
            )
        })?
        .map_err(PyValueError::new_err)?;
        let all = found.iter().enumerate().flat_map(|(c, hits)| {
            hits.iter().map(move |&(k, h)| ((c * CHUNK) as i64 + i64::from(k), h))
        });
        let (mut ray, mut triangle) = (Vec::new(), Vec::new());
        let (mut t, mut u, mut v) = (Vec::new(), Vec::new(), Vec::new());
        for (r, h) in all {
            ray.push(r);
            triangle.push(i64::from(h.triangle));
            t.push(h.t);
            u.push(h.b1);
            v.push(h.b2);
        }
        Ok((
            ray.into_pyarray(py),
            triangle.into_pyarray(py),
            t.into_pyarray(py),
            u.into_pyarray(py),
            v.into_pyarray(py),
        ))
    }

    /// Moves the vertices (the same count, the faces unchanged) and refits the BVH; rebuilds
    /// it where a refit cannot keep the tree (a face that had no area has one now).
    fn refit(&mut self, py: Python<'_>, vertices: PyReadonlyArray2<'_, f32>) -> PyResult<()> {
        let vertices = points_of(rows(&vertices, "vertices")?, "vertices")?;
        if vertices.len() != self.vertices.len() {
            return Err(PyValueError::new_err(format!(
                "vertices has {} rows, the mesh {}: make a new Mesh for other vertices",
                vertices.len(),
                self.vertices.len()
            )));
        }
        let triangles = triangles(&vertices, &self.faces);
        let bvh = &mut self.bvh;
        let refitted = py.detach(|| bvh.refit(&triangles).is_ok());
        if !refitted {
            self.bvh = py
                .detach(|| Bvh::try_new(&triangles))
                .map_err(|e| PyValueError::new_err(e.to_string()))?;
        }
        self.vertices = vertices;
        Ok(())
    }

    fn __len__(&self) -> usize {
        self.faces.len()
    }
}

impl Mesh {
    fn build(py: Python<'_>, vertices: Vec<Vec3>, faces: Vec<[u32; 3]>) -> PyResult<Mesh> {
        let triangles = triangles(&vertices, &faces);
        let bvh = py
            .detach(|| Bvh::try_new(&triangles))
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(Mesh { vertices, faces, bvh })
    }
}

/// Loads an OBJ, PLY or glTF file (`.obj.gz` and `.ply.gz` too) as one mesh: a glTF's
/// instanced meshes are copied into their places.
#[pyfunction]
fn load_mesh(py: Python<'_>, path: PathBuf) -> PyResult<Mesh> {
    let loaded = py.detach(|| raylab::load_mesh(&path)).map_err(|e| match &e {
        raylab::LoadError::File(_) | raylab::LoadError::Folder { .. } => {
            PyOSError::new_err(e.to_string())
        }
        _ => PyValueError::new_err(e.to_string()),
    })?;
    let mesh = loaded.flattened();
    Mesh::build(py, mesh.positions, mesh.triangles)
}

/// The Rust side of the `raylab` package.
#[pymodule]
fn _raylab(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // A wrong `RAYLAB_ISA` stops the import with its reason, rather than being ignored.
    raylab::cpu::Isa::from_env()
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(format!("RAYLAB_ISA: {e}")))?;
    m.add_class::<Mesh>()?;
    m.add_function(wrap_pyfunction!(load_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(render::render, m)?)?;
    m.add_function(wrap_pyfunction!(render::write_image, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("ISA", raylab::cpu::Isa::detect().name())?;
    m.add("ORDER_MIN_RAYS", Batch::ORDER_MIN_RAYS)?;
    m.add("ORDER_MIN_TREE_BYTES", Batch::ORDER_MIN_TREE_BYTES)?;
    Ok(())
}
