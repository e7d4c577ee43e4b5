"""Agreement with Embree (embreex, the binding trimesh uses) on random and grazing rays."""

import os

import numpy as np
import pytest

from conftest import random_rays

if os.environ.get("RAYLAB_REQUIRE_EMBREEX"):
    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh
else:
    rtcore_scene = pytest.importorskip("embreex.rtcore_scene")
    TriangleMesh = pytest.importorskip("embreex.mesh_construction").TriangleMesh


def embree_hits(mesh, origins, directions):
    scene = rtcore_scene.EmbreeScene()
    TriangleMesh(scene, mesh.vertices[mesh.faces.astype(np.int64)])
    result = scene.run(origins, directions, output=1)
    return result["tfar"], result["primID"]


def grazing_rays(mesh, n, seed):
    """Rays that meet a random face at a point inside it at 0.5° to 5° from its plane."""
    rng = np.random.default_rng(seed)
    v = mesh.vertices.astype(np.float64)
    f = mesh.faces[rng.integers(0, len(mesh), n)]
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    w = rng.dirichlet([1, 1, 1], n)
    point = w[:, :1] * a + w[:, 1:2] * b + w[:, 2:] * c
    normal = np.cross(b - a, c - a)
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    along = (b - a) / np.linalg.norm(b - a, axis=1)[:, None]
    angle = np.radians(rng.uniform(0.5, 5.0, n))
    direction = np.cos(angle)[:, None] * along - np.sin(angle)[:, None] * normal
    length = np.linalg.norm(v.max(0) - v.min(0))
    origin = point - direction * length
    return origin.astype(np.float32), direction.astype(np.float32)


@pytest.mark.parametrize("kind", ["random", "grazing"])
def test_the_same_answers_as_embree(bunny, kind):
    n = 200_000
    rays = random_rays(bunny, n, seed=11) if kind == "random" else grazing_rays(bunny, n, 12)
    hits = bunny.intersect(*rays)
    t, primitive = embree_hits(bunny, *rays)
    ours, theirs = hits.triangle >= 0, primitive >= 0
    same = ours == theirs
    assert same.mean() >= 0.9999, f"{(~same).sum()} of {n} rays disagree on hit or miss"
    both = ours & theirs
    relative = np.abs(hits.t[both] - t[both]) / np.maximum(t[both], 1e-30)
    close = relative <= 1e-5
    assert close.mean() >= 0.9999, f"{(~close).sum()} of {both.sum()} hits differ in t"
