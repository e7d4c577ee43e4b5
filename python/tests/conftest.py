"""Shared fixtures: the test meshes (RAYLAB_TEST_MESHES, set by tests/python_suite.rs; the
repository's crates/raylab/tests/data/meshes otherwise)."""

import os
import pathlib

import pytest

import raylab

MESHES = pathlib.Path(
    os.environ.get(
        "RAYLAB_TEST_MESHES",
        pathlib.Path(__file__).resolve().parents[2] / "crates/raylab/tests/data/meshes",
    )
)


@pytest.fixture(scope="session")
def bunny():
    """The 75k-triangle bunny (closed), as a raylab.Mesh."""
    return raylab.load_mesh(MESHES / "bunny.obj.gz")


def random_rays(mesh, n, seed):
    """`n` rays from a sphere around `mesh` toward random points in its box (about 60 % hit)."""
    import numpy as np

    rng = np.random.default_rng(seed)
    v = mesh.vertices
    lo, hi = v.min(0), v.max(0)
    centre, radius = (lo + hi) / 2, np.linalg.norm(hi - lo)
    outward = rng.normal(size=(n, 3))
    outward /= np.linalg.norm(outward, axis=1)[:, None]
    origins = (centre + outward * radius).astype(np.float32)
    targets = (lo + rng.random((n, 3)) * (hi - lo)).astype(np.float32)
    return origins, (targets - origins).astype(np.float32)
