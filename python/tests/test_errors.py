"""Bad input is a ValueError or TypeError naming the argument, never a crash."""

import numpy as np
import pytest

import raylab

V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float32)
F = np.array([[0, 1, 2]])


@pytest.fixture(scope="module")
def mesh():
    return raylab.Mesh(V, F)


@pytest.mark.parametrize(
    "vertices, faces, error, words",
    [
        (V[:, :2], F, ValueError, "vertices must have shape (n, 3)"),
        (V.astype(complex), F, TypeError, "vertices must hold real numbers"),
        ([["a", "b", "c"]], F, TypeError, "vertices must hold real numbers"),
        (np.array([[0, 0, np.nan], [1, 0, 0], [0, 1, 0]]), F, ValueError, "vertices[0]"),
        (V, [[0, 1, 3]], ValueError, "faces[0] = [0, 1, 3] indexes past the 3 vertices"),
        (V, [[0, -1, 2]], ValueError, "faces[0] = [0, -1, 2] has a negative index"),
        (V, [[0.0, 1.0, 2.0]], TypeError, "faces must hold integers"),
        (V, [[0, 1]], ValueError, "faces must have shape (m, 3)"),
        (V, [[0, 1, 2], [0, 1]], TypeError, "faces must be an array of integers"),
    ],
)
def test_bad_meshes(vertices, faces, error, words):
    with pytest.raises(error) as raised:
        raylab.Mesh(vertices, faces)
    assert words in str(raised.value)


@pytest.mark.parametrize(
    "kwargs, error, words",
    [
        (dict(origins=[[0, 0, -1]], directions=[[0, 0, 0]]), ValueError, "directions[0]"),
        (dict(origins=[[0, 0, np.inf]], directions=[[0, 0, 1]]), ValueError, "origins[0]"),
        (dict(origins=[[0, 0, -1]], directions=[[0, np.nan, 1]]), ValueError, "directions[0]"),
        (dict(origins=[[0, 0, -1]] * 2, directions=[[0, 0, 1]]), ValueError, "same shape"),
        (dict(origins=[0, 0, -1], directions=[0, 0, 1]), ValueError, "origins must have shape"),
        (dict(origins=[[0, 0, -1]], directions=[[0, 0, 1]], t_max=np.nan), ValueError, "NaN"),
        (dict(origins=[[0, 0, -1]], directions=[[0, 0, 1]], t_min=[0, 1]), ValueError, "t_min"),
        (dict(origins=[[0, 0, -1]], directions=[[0, 0, 1]], t_max="far"), TypeError, "t_max"),
        (dict(origins=[[0, 0, -1]], directions=[[0, 0, 1]], threads=0), ValueError, "threads"),
        (dict(origins=[[0, 0, -1]], directions=[[0, 0, 1]], threads=1.5), TypeError, "threads"),
        (dict(origins=[[0, 0, -1]], directions=np.array([[True, False, True]])), TypeError, "directions"),
    ],
)
@pytest.mark.parametrize("query", ["intersect", "occluded"])
def test_bad_rays(mesh, query, kwargs, error, words):
    with pytest.raises(error) as raised:
        getattr(mesh, query)(**kwargs)
    assert words in str(raised.value)


def test_the_first_bad_ray_is_named(mesh):
    directions = np.tile(np.float32([0, 0, 1]), (100_000, 1))
    directions[71_234] = 0
    with pytest.raises(ValueError, match=r"directions\[71234\]"):
        mesh.intersect(np.zeros_like(directions), directions)


def test_refit_needs_as_many_vertices(mesh):
    with pytest.raises(ValueError, match="vertices has 2 rows, the mesh 3"):
        mesh.refit(V[:2])


def test_load_mesh_errors(tmp_path):
    with pytest.raises(OSError, match="missing.obj"):
        raylab.load_mesh(tmp_path / "missing.obj")
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    with pytest.raises(ValueError, match="bad.obj"):
        raylab.load_mesh(bad)
    with pytest.raises(ValueError, match="notes.txt"):
        (tmp_path / "notes.txt").write_text("hello")
        raylab.load_mesh(tmp_path / "notes.txt")
    with pytest.raises(OSError):
        raylab.load_mesh(tmp_path)


def test_empty_meshes_and_empty_ray_sets(mesh):
    empty = raylab.Mesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=int))
    assert len(empty) == 0
    assert empty.intersect([[0, 0, 0]], [[0, 0, 1]]).triangle.tolist() == [-1]
    hits = mesh.intersect(np.zeros((0, 3)), np.zeros((0, 3)))
    assert hits.t.shape == (0,)
