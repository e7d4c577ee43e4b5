"""raylab for Python: watertight ray queries on numpy arrays.

    >>> import numpy as np, raylab
    >>> mesh = raylab.Mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
    >>> hits = mesh.intersect([[0.25, 0.25, -1]], [[0, 0, 1]])
    >>> float(hits.t[0]), int(hits.triangle[0])
    (1.0, 0)

Every query answers exactly as raylab's Rust BVH does, bit for bit: the ray/triangle test is
watertight (a ray through an edge or a vertex that two triangles share hits one of them; none
slips between), and the closest hit at equal distances is the lowest triangle index. Points
are ``float32`` inside: ``float64`` input is rounded to the nearest ``float32``.

The queries release the GIL and run on every core unless ``threads=`` says how many.
``raylab.ISA`` names the instruction set their kernels use: the best this CPU has, or the one
the environment variable ``RAYLAB_ISA`` names (``scalar``, ``sse2``, ``avx2``, ``avx512``) when
it is set before the import, to measure as on a CPU without AVX-512.
"""

from collections import namedtuple
import math
import os
import warnings

import numpy as np

from . import _raylab

__version__ = _raylab.__version__
ISA = _raylab.ISA
__all__ = [
    "AllHits", "Hits", "Mesh", "Render", "Scene", "load_mesh", "render", "write_image"
]

# `Mesh.contains`' ray direction: no axis, diagonal or simple ratio, so that rays from points
# on a grid do not run along a mesh's axis-aligned faces and edges.
_CONTAINS_DIRECTION = np.array([0.5773502, 0.6188021, -0.5327641], dtype=np.float32)

Hits = namedtuple("Hits", ["t", "triangle", "u", "v"])
Hits.__doc__ = """The closest hit of each ray.

t: float32 (n,), the distance along the ray in units of its direction's length; inf on a miss.
triangle: int64 (n,), the index of the face hit; -1 on a miss.
u, v: float32 (n,), the barycentric weights of the face's second and third vertex (the
    point is (1 - u - v)·a + u·b + v·c); 0 on a miss.
"""


AllHits = namedtuple("AllHits", ["ray", "triangle", "t", "u", "v"])
AllHits.__doc__ = """Every crossing of a set of rays, one entry per crossing.

ray: int64 (m,), the index of the ray; triangle: int64 (m,), the face crossed; t, u, v:
float32 (m,), as in `Hits`. Sorted by ray, then t, then triangle.
"""


def _positive_int(value, name):
    """`value` as an int, checked to be a positive integer (None passes)."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} must be a positive integer, not {value!r}")
    if value < 1:
        raise ValueError(f"{name} must be at least 1, not {value}")
    return int(value)


def _real_array(value, name, ndim_shape, dtype):
    """`value` as a C-contiguous array of `dtype`, checked to be real numbers of the shape
    described by `ndim_shape` (a tuple whose None entries are free)."""
    try:
        array = np.asarray(value)
    except Exception as error:  # ragged lists and the like
        raise TypeError(f"{name} must be an array of numbers: {error}") from None
    if array.dtype == np.bool_ or not (
        np.issubdtype(array.dtype, np.floating) or np.issubdtype(array.dtype, np.integer)
    ):
        raise TypeError(f"{name} must hold real numbers, not {array.dtype}")
    if array.ndim != len(ndim_shape) or any(
        want is not None and got != want for got, want in zip(array.shape, ndim_shape)
    ):
        shape = "(" + ", ".join("n" if s is None else str(s) for s in ndim_shape) + ")"
        raise ValueError(f"{name} must have shape {shape}, not {array.shape}")
    return np.ascontiguousarray(array, dtype=dtype)


def _points(value, name):
    return _real_array(value, name, (None, 3), np.float32)


def _faces(value):
    try:
        array = np.asarray(value)
    except Exception as error:
        raise TypeError(f"faces must be an array of integers: {error}") from None
    if array.size == 0 and array.ndim in (1, 2):
        array = array.reshape(0, 3).astype(np.int64)
    if array.dtype == np.bool_ or not np.issubdtype(array.dtype, np.integer):
        raise TypeError(f"faces must hold integers, not {array.dtype}")
    if array.ndim != 2 or array.shape[1] != 3:
        raise ValueError(f"faces must have shape (m, 3), not {array.shape}")
    if array.size and array.min() < 0:
        row = int(np.argwhere(array < 0)[0][0])
        raise ValueError(f"faces[{row}] = {array[row].tolist()} has a negative index")
    if array.size and array.max() > np.iinfo(np.uint32).max:
        row = int(np.argwhere(array > np.iinfo(np.uint32).max)[0][0])
        raise ValueError(f"faces[{row}] = {array[row].tolist()} indexes past 2**32 - 1")
    return np.ascontiguousarray(array, dtype=np.uint32)


def _limits(value, name, n):
    array = np.asarray(value)
    if array.dtype == np.bool_ or not (
        np.issubdtype(array.dtype, np.floating) or np.issubdtype(array.dtype, np.integer)
    ):
        raise TypeError(f"{name} must be a real number or an array of them, not {array.dtype}")
    if array.ndim == 0:
        return float(np.float32(array))
    if array.shape != (n,):
        raise ValueError(f"{name} must be a number or have shape ({n},), not {array.shape}")
    return np.ascontiguousarray(array, dtype=np.float32)


def _threads(threads):
    if threads is None:
        return None
    if isinstance(threads, bool) or not isinstance(threads, (int, np.integer)):
        raise TypeError(f"threads must be a positive integer or None, not {threads!r}")
    return _positive_int(threads, "threads")


def _rays(origins, directions, t_min, t_max):
    origins = _points(origins, "origins")
    directions = _points(directions, "directions")
    if origins.shape != directions.shape:
        raise ValueError(
            f"origins and directions must have the same shape, not {origins.shape} "
            f"and {directions.shape}"
        )
    n = origins.shape[0]
    return origins, directions, _limits(t_min, "t_min", n), _limits(t_max, "t_max", n)


class Mesh:
    """A triangle mesh and its BVH, built once.

    vertices: (n, 3) real numbers (float32 inside); every vertex must be finite.
    faces: (m, 3) integers, each in [0, n).

    Faces of zero area stay in `faces` but are never hit.
    """

    __slots__ = ("_mesh",)

    def __init__(self, vertices, faces):
        if isinstance(vertices, _raylab.Mesh):  # from load_mesh
            self._mesh = vertices
            return
        self._mesh = _raylab.Mesh(_points(vertices, "vertices"), _faces(faces))

    @property
    def vertices(self):
        """The vertices, float32 (n, 3) (a copy)."""
        return self._mesh.vertices

    @property
    def faces(self):
        """The faces, uint32 (m, 3) (a copy)."""
        return self._mesh.faces

    @property
    def bvh_bytes(self):
        """The BVH's size in bytes."""
        return self._mesh.bvh_bytes

    def __len__(self):
        return len(self._mesh)

    def __repr__(self):
        return f"raylab.Mesh({len(self)} faces)"

    def intersect(self, origins, directions, t_min=0.0, t_max=math.inf, *, threads=None):
        """The closest hit of each ray `origins[i] + t·directions[i]` with t_min <= t < t_max
        (and t above zero: a negative t_min counts as 0, and with t_min = 0 a hit must be
        conservatively past the origin, so a ray does not hit the surface it starts on).

        origins, directions: (n, 3) real numbers; directions need not be unit length (t is
            in units of their length) but must be finite and non-zero.
        t_min, t_max: a number or (n,) numbers for each ray.
        threads: how many threads (None: every core).

        Returns `Hits(t, triangle, u, v)`.
        """
        rays = _rays(origins, directions, t_min, t_max)
        return Hits(*self._mesh.intersect(rays, threads=_threads(threads)))

    def occluded(self, origins, directions, t_min=0.0, t_max=math.inf, *, threads=None):
        """Whether each ray hits anything with t_min <= t < t_max: a bool array (n,).

        The arguments are those of `intersect`. For a shadow ray toward a point on a surface,
        pass the direction to it and t_max a little below 1 (0.999), so that the point's own
        surface does not block it.
        """
        rays = _rays(origins, directions, t_min, t_max)
        return self._mesh.occluded(rays, threads=_threads(threads))

    def count_hits(self, origins, directions, t_min=0.0, t_max=math.inf, *, threads=None):
        """How many times each ray crosses the surface with t_min <= t < t_max: an int64
        array (n,).

        Every hit counts, not only the closest. A ray through an edge or a vertex that faces
        share counts once where the surface goes on across the point (and twice or not at all
        where it folds back, as at a silhouette), so on a closed mesh the count's parity
        tells inside from outside. The arguments are those of `intersect`.
        """
        rays = _rays(origins, directions, t_min, t_max)
        return self._mesh.count_hits(rays, threads=_threads(threads))

    def intersect_all(
        self, origins, directions, t_min=0.0, t_max=math.inf, *, max_hits=None, threads=None
    ):
        """Every crossing of every ray with the surface (those `count_hits` counts), at most
        `max_hits` per ray (its nearest; None: all).

        Returns `AllHits(ray, triangle, t, u, v)`, one entry per crossing, sorted by ray,
        then t, then triangle. The arguments are those of `intersect`.
        """
        rays = _rays(origins, directions, t_min, t_max)
        if max_hits is None:
            max_hits = 2**63 - 1
        elif isinstance(max_hits, bool) or not isinstance(max_hits, (int, np.integer)):
            raise TypeError(f"max_hits must be a non-negative integer or None, not {max_hits!r}")
        elif max_hits < 0:
            raise ValueError(f"max_hits must be at least 0, not {max_hits}")
        found = self._mesh.all_hits(rays, int(max_hits), threads=_threads(threads))
        return AllHits(*found)

    def contains(self, points, *, threads=None):
        """Whether each point is inside the mesh, which must be closed: a bool array (n,).

        A ray from each point crosses the surface an odd number of times exactly when the
        point is inside (`count_hits`, along one fixed direction). Points on the surface
        itself may answer either way.
        """
        points = _points(points, "points")
        directions = np.broadcast_to(_CONTAINS_DIRECTION, points.shape)
        counts = self.count_hits(points, directions, threads=threads)
        return counts % 2 == 1

    def refit(self, vertices):
        """Moves the vertices (same count, faces unchanged) and refits the BVH in place,
        faster than a new Mesh; the answers stay exact."""
        self._mesh.refit(_points(vertices, "vertices"))


def load_mesh(path):
    """Loads an OBJ, PLY or glTF (.gltf, .glb) file, or a gzip-compressed .obj.gz or .ply.gz,
    as one Mesh (a glTF's instanced meshes copied into their places).

    Raises OSError when the file cannot be read, ValueError when its content is malformed.
    """
    return Mesh(_raylab.load_mesh(os.fspath(path)), None)


Render = namedtuple("Render", ["image", "aovs", "samples", "interrupted", "region"])
Render.__doc__ = """A rendered picture.

image: float32 (height, width, 3), linear radiance (the region's pixels for a region).
aovs: {name: float32 (height, width, 3)} for the AOVs asked for ("albedo", "normals",
    "depth"; depth is the same in all three channels).
samples: the samples per pixel reached (fewer than asked if interrupted).
interrupted: whether Ctrl-C or the progress callback stopped it.
region: (x0, y0, x1, y1), the part of the image rendered.
"""


def _name(value, name):
    if value is None or isinstance(value, str):
        return value
    raise TypeError(f"{name} must be a name (str), not {value!r}")


def render(
    scene="cornell",
    *,
    size=None,
    spp=None,
    integrator=None,
    seed=None,
    max_depth=None,
    sampler=None,
    region=None,
    aovs=(),
    threads=None,
    progress=None,
):
    """Renders a scene into numpy arrays, exactly as `raylab render` renders it to a file
    (the same pixels for the same scene, settings and seed).

    scene: a built-in scene ("cornell", "terrain"), or a file: a TOML scene, or a model
        (.obj, .ply, .gltf, .glb) that the camera frames; or a `raylab.Scene`.
    size: (width, height) in pixels [the scene file's, else 500×500].
    spp: samples per pixel [the scene file's; 16 for path tracing, 1 for the lab].
    integrator: "path", "path-scalar", "lab", "albedo", "normals" or "depth" [the scene
        file's; "path" where a surface emits or a light is not a point light, else "lab"].
    seed: the seed of every random number [0]. max_depth: the longest path, as Mitsuba counts
        it [unlimited]. sampler: "sobol", "multijitter", "stratified" or "independent".
    region: (x0, y0, x1, y1), the part of the image to render (x1, y1 excluded).
    aovs: names of extra layers from the same samples: "albedo", "normals", "depth".
    threads: how many threads [every core].
    progress: called as progress(fraction) about twenty times a second from the calling
        thread, and with 1.0 at the end; an exception in it stops the render and is raised.

    Ctrl-C stops the render at the end of the pass in flight: the picture so far is returned,
    with `samples` telling how many it has and `interrupted` set.

    Returns a `Render`. Raises OSError for a file that cannot be read, ValueError for a
    malformed scene or a setting out of range.
    """
    text, meshes = None, []
    if isinstance(scene, Scene):
        text, meshes, scene = scene.to_toml(), scene._arrays(), "<python scene>"
    if isinstance(scene, os.PathLike):
        scene = os.fspath(scene)
    if not isinstance(scene, str):
        raise TypeError(f"scene must be a name, a path or a raylab.Scene, not {scene!r}")
    if size is not None:
        if len(size) != 2:
            raise ValueError(f"size must be (width, height), not {size!r}")
        size = (_positive_int(size[0], "size's width"), _positive_int(size[1], "size's height"))
    if region is not None:
        region = tuple(region)
        if len(region) != 4 or any(
            isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0 for v in region
        ):
            raise ValueError(f"region must be (x0, y0, x1, y1), non-negative integers: {region!r}")
        region = tuple(int(v) for v in region)
    if isinstance(aovs, str):
        aovs = [aovs]
    aovs = [_name(a, "each AOV") for a in aovs]
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer))
                             or seed < 0):
        raise ValueError(f"seed must be a non-negative integer, not {seed!r}")
    if max_depth is not None and (
        isinstance(max_depth, bool) or not isinstance(max_depth, (int, np.integer)) or max_depth < 0
    ):
        raise ValueError(f"max_depth must be a non-negative integer, not {max_depth!r}")
    if progress is not None and not callable(progress):
        raise TypeError(f"progress must be callable, not {progress!r}")
    image, layers, samples, interrupted, region, notes, _ = _raylab.render(
        scene,
        size=size,
        spp=_positive_int(spp, "spp"),
        integrator=_name(integrator, "integrator"),
        seed=None if seed is None else int(seed),
        max_depth=None if max_depth is None else int(max_depth),
        sampler=_name(sampler, "sampler"),
        region=region,
        aovs=aovs,
        threads=_threads(threads),
        progress=progress,
        scene_text=text,
        meshes=meshes,
    )
    for note in notes:
        warnings.warn(note, stacklevel=2)
    return Render(image, dict(layers), samples, interrupted, region)


def write_image(path, image, *, exposure=0.0, tone_map="clamp", srgb=True):
    """Writes an image, float (height, width, 3) or (height, width), in the format the file
    name's extension says: .exr and .pfm keep linear float values; .png (and .ppm) are
    8-bit, brightened by 2**exposure, tone-mapped ("clamp", "reinhard" or "aces") and
    sRGB-encoded unless srgb=False. The file is replaced whole or not at all.
    """
    array = _real_array(image, "image", (None, None, None)[: np.ndim(image)], np.float32)
    if array.ndim == 2:
        array = np.repeat(array[:, :, None], 3, axis=2)
    if array.ndim != 3 or array.shape[2] != 3:
        raise ValueError(f"image must have shape (height, width, 3) or (height, width), "
                         f"not {array.shape}")
    _raylab.write_image(os.fspath(path), np.ascontiguousarray(array), exposure=float(exposure),
                        tone_map=_name(tone_map, "tone_map"), srgb=bool(srgb))


from .scene import Scene  # noqa: E402  (it uses the checks above)
