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
"""

from collections import namedtuple
import math
import os

import numpy as np

from . import _raylab

__version__ = _raylab.__version__
__all__ = ["AllHits", "Hits", "Mesh", "load_mesh"]

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
    if threads < 1:
        raise ValueError(f"threads must be at least 1, not {threads}")
    return int(threads)


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
        """The closest hit of each ray `origins[i] + t·directions[i]` with t_min < t < t_max.

        origins, directions: (n, 3) real numbers; directions need not be unit length (t is
            in units of their length) but must be finite and non-zero.
        t_min, t_max: a number or (n,) numbers for each ray.
        threads: how many threads (None: every core).

        Returns `Hits(t, triangle, u, v)`.
        """
        rays = _rays(origins, directions, t_min, t_max)
        return Hits(*self._mesh.intersect(*rays, threads=_threads(threads)))

    def occluded(self, origins, directions, t_min=0.0, t_max=math.inf, *, threads=None):
        """Whether each ray hits anything with t_min < t < t_max: a bool array (n,).

        The arguments are those of `intersect`; for a shadow ray toward a point, pass the
        direction to it and t_max=1 (or a little less, to not count the point's own surface).
        """
        rays = _rays(origins, directions, t_min, t_max)
        return self._mesh.occluded(*rays, threads=_threads(threads))

    def count_hits(self, origins, directions, t_min=0.0, t_max=math.inf, *, threads=None):
        """How many times each ray crosses the surface with t_min < t < t_max: an int64
        array (n,).

        Every hit counts, not only the closest. A ray through an edge or a vertex that faces
        share counts once where the surface goes on across the point (and twice or not at all
        where it folds back, as at a silhouette), so on a closed mesh the count's parity
        tells inside from outside. The arguments are those of `intersect`.
        """
        rays = _rays(origins, directions, t_min, t_max)
        return self._mesh.count_hits(*rays, threads=_threads(threads))

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
        found = self._mesh.all_hits(*rays, int(max_hits), threads=_threads(threads))
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
