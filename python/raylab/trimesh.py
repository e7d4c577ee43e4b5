"""A drop-in ray intersector for trimesh, with raylab's watertight queries.

    import trimesh, raylab.trimesh
    mesh = trimesh.load("bunny.ply")
    mesh.ray = raylab.trimesh.RayMeshIntersector(mesh)

Then `mesh.ray.intersects_first`, `intersects_any`, `intersects_id`, `intersects_location` and
`mesh.contains` answer with raylab, with trimesh's arguments, return types and shapes (those of
trimesh's embreex intersector, `trimesh.ray.ray_pyembree`). trimesh itself is needed only to
have a mesh: this module imports nothing from it.

Where the answers differ from trimesh's intersectors, on purpose:

- Watertight: a ray through an edge or a vertex that faces share always hits (Embree's default
  mode, which trimesh uses, can let it through between them).
- Multiple hits (`intersects_id(multiple_hits=True)`, `intersects_location`) are every crossing
  of the ray with the surface, found in one traversal, rather than rays re-cast from just past
  each hit: a ray through a shared edge or vertex crosses once (trimesh may report both faces,
  or skip a face that lies closer than its offset). They are sorted by ray, then distance.
- `contains_points` counts crossings along one ray per point with the same rule, so points
  whose rays pass through edges or vertices are answered exactly too. As in trimesh, points on
  the surface may answer either way, and the mesh must be closed.
- Hit locations are where the ray meets the face's plane, in float64, as trimesh computes
  them (the face's point at the hit's barycentrics where the ray runs nearly in that plane).
"""

import numpy as np

import raylab

__all__ = ["RayMeshIntersector"]


class RayMeshIntersector:
    """Ray queries on a `trimesh.Trimesh` (anything with `vertices` and `faces`).

    The BVH is built on first use and again whenever the mesh's content changes (trimesh's
    hash of it). The vertices are moved by the mesh's lowest corner, in float64, before they
    are rounded to float32, as the embreex intersector does, so a mesh far from the origin
    keeps its precision.
    """

    def __init__(self, geometry, *, threads=None):
        self.mesh = geometry
        self.threads = threads
        self._built = None  # (the mesh's hash, origin, raylab.Mesh)

    def _scene(self):
        key = hash(self.mesh)
        if self._built is None or self._built[0] != key:
            vertices = np.asarray(self.mesh.vertices, dtype=np.float64)
            origin = vertices.min(axis=0) if len(vertices) else np.zeros(3)
            mesh = raylab.Mesh(vertices - origin, np.asarray(self.mesh.faces))
            self._built = (key, origin, mesh)
        return self._built[1], self._built[2]

    def _rays(self, ray_origins, ray_directions):
        origins = np.asarray(ray_origins, dtype=np.float64)
        directions = np.asarray(ray_directions, dtype=np.float64)
        if origins.shape != directions.shape:
            raise ValueError("Ray origin and direction don't match!")
        if origins.ndim != 2 or origins.shape[1] != 3:
            raise ValueError(f"rays must have shape (n, 3), not {origins.shape}")
        with np.errstate(invalid="ignore", over="ignore"):
            length = np.linalg.norm(directions, axis=1)
            unit = directions / np.where(length > 0, length, 1.0)[:, None]
        origin, mesh = self._scene()
        shifted = origins - origin
        # As trimesh's intersectors answer them: a ray with a zero or non-finite direction or
        # origin hits nothing (raylab.Mesh would refuse it).
        bad = ~(np.isfinite(shifted).all(axis=1) & np.isfinite(unit).all(axis=1) & (length > 0))
        t_max = np.where(bad, -1.0, np.inf).astype(np.float32)
        if bad.any():
            unit, shifted = unit.copy(), shifted.copy()
            unit[bad], shifted[bad] = (0.0, 0.0, 1.0), 0.0
        return origins, unit, shifted, mesh, t_max

    def intersects_first(self, ray_origins, ray_directions):
        """The index of the first face each ray hits, -1 for none: int64 (n,)."""
        _, unit, shifted, mesh, t_max = self._rays(ray_origins, ray_directions)
        return mesh.intersect(shifted, unit, t_max=t_max, threads=self.threads).triangle

    def intersects_any(self, ray_origins, ray_directions):
        """Whether each ray hits the surface: bool (n,)."""
        _, unit, shifted, mesh, t_max = self._rays(ray_origins, ray_directions)
        return mesh.occluded(shifted, unit, t_max=t_max, threads=self.threads)

    def intersects_id(
        self,
        ray_origins,
        ray_directions,
        multiple_hits=True,
        max_hits=100,
        return_locations=False,
    ):
        """The faces the rays hit: `(index_tri, index_ray)`, and the hit points as a third
        array (m, 3) if `return_locations`. With `multiple_hits`, every crossing of each ray
        (at most `max_hits`), else its first hit only."""
        origins, unit, shifted, mesh, t_max = self._rays(ray_origins, ray_directions)
        if multiple_hits:
            found = mesh.intersect_all(
                shifted, unit, t_max=t_max, max_hits=max_hits, threads=self.threads
            )
            index_ray, index_tri = found.ray, found.triangle
            u, v = found.u, found.v
        else:
            hits = mesh.intersect(shifted, unit, t_max=t_max, threads=self.threads)
            index_ray = np.flatnonzero(hits.triangle >= 0)
            index_tri = hits.triangle[index_ray]
            u, v = hits.u[index_ray], hits.v[index_ray]
        if not return_locations:
            return index_tri, index_ray
        corners = np.asarray(self.mesh.vertices, dtype=np.float64)[
            np.asarray(self.mesh.faces)[index_tri]
        ].reshape(-1, 3, 3)
        # The ray's point on the face's plane, in float64 (as trimesh computes it); where the
        # ray runs nearly in that plane, the face's point at the hit's barycentrics.
        a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
        normal = np.cross(b - a, c - a)
        o, d = origins[index_ray], unit[index_ray]
        across = np.einsum("ij,ij->i", normal, d)
        scale = np.linalg.norm(normal, axis=1) * np.linalg.norm(d, axis=1)
        steep = np.abs(across) > 1e-6 * scale
        t = np.einsum("ij,ij->i", normal, a - o) / np.where(steep, across, 1.0)
        u = u.astype(np.float64)[:, None]
        v = v.astype(np.float64)[:, None]
        on_face = (1 - u - v) * a + u * b + v * c
        locations = np.where(steep[:, None], o + d * t[:, None], on_face)
        return index_tri, index_ray, locations.reshape(-1, 3)

    def intersects_location(self, ray_origins, ray_directions, multiple_hits=True):
        """Where the rays hit: `(locations, index_ray, index_tri)`."""
        index_tri, index_ray, locations = self.intersects_id(
            ray_origins, ray_directions, multiple_hits=multiple_hits, return_locations=True
        )
        return locations, index_ray, index_tri

    def contains_points(self, points):
        """Whether each point is inside the (closed) mesh: bool (n,)."""
        origin, mesh = self._scene()
        points = np.asarray(points, dtype=np.float64)
        if points.ndim != 2 or points.shape[1] != 3:
            raise ValueError(f"points must have shape (n, 3), not {points.shape}")
        return mesh.contains(points - origin, threads=self.threads)
