"""raylab.trimesh.RayMeshIntersector as trimesh's own ray tests use an intersector.

These are ports of the tests in trimesh 5.2.0's `tests/test_ray.py` (they are not in its wheel
or source distribution, with the models they load), each with the same checks on meshes that
trimesh makes itself, and with raylab's intersector in place of Embree's. Not ported:
- `test_rays`: it needs trimesh's `ray_data.json` and its models; `test_embreex.py` compares
  with Embree on the bunny instead.
- `test_on_edge`: it needs the model `7_8ths_cube.stl`; edges and corners are tested below on
  boxes.
- `test_embree_duplicate_hits` expects a ray that starts exactly on a face to hit that face
  (at t = 0): raylab's hits are at t conservatively above zero, so such a ray crosses the far
  face only. `test_hits_from_on_and_off_the_surface` checks that, and the two hits of a ray
  started just outside, at the same scales.
"""

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")

import raylab.trimesh  # noqa: E402
from conftest import MESHES  # noqa: E402


def with_raylab(mesh):
    mesh.ray = raylab.trimesh.RayMeshIntersector(mesh)
    return mesh


def test_rps():
    sphere = with_raylab(trimesh.creation.icosphere(subdivisions=5))
    rng = np.random.default_rng(1)
    origins = rng.random((10_000, 3))
    origins[:, 2] = -5
    directions = np.tile([0, 0, 1.0], (10_000, 1))
    a = sphere.ray.intersects_id(origins, directions)
    b = sphere.ray.intersects_location(origins, directions)
    assert all(isinstance(i, np.ndarray) for i in a + b)
    # Every ray within the unit disc (less the polyhedron's flats) goes in and out again.
    radius = np.hypot(origins[:, 0], origins[:, 1])
    counts = np.bincount(a[1], minlength=10_000)
    assert (counts[radius < 0.99] == 2).all()
    assert (counts[radius > 1.0] == 0).all()
    # trimesh's own (numpy) intersector agrees on which rays hit.
    reference = trimesh.ray.ray_triangle.RayMeshIntersector(sphere)
    ours = sphere.ray.intersects_any(origins, directions)
    theirs = reference.intersects_any(origins, directions)
    assert (ours == theirs).mean() > 0.999


def test_empty():
    sphere = with_raylab(trimesh.creation.icosphere())
    origins = np.random.default_rng(2).random((100, 3))
    origins[:, 2] = -5
    directions = np.tile([0, 1.0, 0], (100, 1))
    index_tri, index_ray = sphere.ray.intersects_id(origins, directions)
    assert index_tri.shape == (0,) and index_ray.shape == (0,)
    locations, index_ray, index_tri = sphere.ray.intersects_location(origins, directions)
    assert locations.shape == (0, 3) and index_ray.shape == (0,) and index_tri.shape == (0,)
    assert sphere.ray.intersects_first(origins, directions).tolist() == [-1] * 100


def test_contains():
    scale = 1.5
    mesh = with_raylab(trimesh.creation.box())
    assert mesh.ray.contains_points(mesh.vertices / scale).all()
    assert not mesh.ray.contains_points(mesh.vertices * scale).any()
    way_out = np.random.default_rng(3).random((30, 3)) * 100 + 1 + mesh.bounds[1]
    assert not mesh.ray.contains_points(way_out).any()
    assert mesh.ray.contains_points([mesh.center_mass]).all()
    # trimesh's own `contains` goes through the intersector.
    assert mesh.contains([[0, 0, 0], [2, 0, 0]]).tolist() == [True, False]


def test_contains_cavity():
    # A box with a box-shaped cavity (its faces turned inward), as trimesh's boolean makes it.
    outer = trimesh.creation.box(extents=[1, 1, 1])
    inner = trimesh.creation.box(extents=[0.1, 0.1, 0.1])
    inner.invert()
    mesh = with_raylab(trimesh.util.concatenate([outer, inner]))
    assert mesh.contains([[0, 0, 0], [0.3, 0.3, 0.3], [0.0, 0.0, 0.06]]).tolist() == [
        False,
        True,
        True,
    ]


def test_on_vertex():
    m = with_raylab(trimesh.creation.box())
    origins = np.zeros_like(m.vertices)
    vectors = m.vertices.copy()
    assert m.ray.intersects_any(ray_origins=origins, ray_directions=vectors).all()
    _, index_ray, _ = m.ray.intersects_location(ray_origins=origins, ray_directions=vectors)
    assert (np.bincount(index_ray, minlength=len(origins)) == 1).all()


def test_multiple_hits():
    f = 1000.0
    h, w = 256, 256
    directions = trimesh.util.grid_arange([[-h / 2, -w / 2], [h / 2, w / 2]], step=2.0)
    directions = np.column_stack((directions, np.ones(len(directions)) * f))
    origins = np.tile([0, 0, -15.0], (len(directions), 1))
    cube = with_raylab(trimesh.creation.box(extents=[2, 2, 2]))
    first, _ = cube.ray.intersects_id(origins, directions, multiple_hits=False)
    assert len(np.unique(first)) == 2
    every, _ = cube.ray.intersects_id(origins, directions, multiple_hits=True)
    assert len(np.unique(every)) > 2


def test_contain_single():
    # Not watertight: the answers mean little, but every point gets one and nothing fails.
    mesh = with_raylab(trimesh.load(MESHES / "teapot.obj", force="mesh"))
    points = mesh.bounding_box.sample_grid(step=2.0)
    assert len(mesh.ray.contains_points(points)) == len(points)
    for point in mesh.bounding_box.vertices:
        mesh.ray.contains_points([point])


def test_box():
    mesh = with_raylab(trimesh.creation.box())
    origins = trimesh.util.grid_linspace(
        mesh.bounds[:, :2] + np.reshape([-0.02, 0.02], (-1, 1)), 100
    )
    origins = np.column_stack((origins, np.ones(len(origins)) * -100))
    vectors = np.ones((len(origins), 3)) * [0, 0, 1.0]
    positions, ray, _ = mesh.ray.intersects_location(origins, vectors)
    assert len(positions) > 0
    for p, r in zip(positions, ray):
        assert np.allclose(p[:2], origins[r][:2])
        assert np.isclose(p[2], mesh.bounds[:, 2]).any()


@pytest.mark.parametrize("scale", [1e-4, 0.1, 1.0, 10, 1e4, 1e8])
def test_hits_from_on_and_off_the_surface(scale):
    mesh = trimesh.creation.box().subdivide().subdivide()
    mesh.apply_scale(scale)
    with_raylab(mesh)
    down = np.array([[0.0, 0.0, -1.0]])
    # From exactly on the top face: the face at t = 0 does not count, the bottom does.
    index_tri, _ = mesh.ray.intersects_id(np.array([[0.0, 0.0, scale / 2]]), down)
    assert len(index_tri) == 1, (scale, index_tri)
    # From just above it: both faces, in order.
    locations, _, index_tri = mesh.ray.intersects_location(
        np.array([[0.0, 0.0, scale / 2 * 1.01]]), down
    )
    assert len(index_tri) == 2, (scale, index_tri)
    assert np.allclose(locations[:, 2], [scale / 2, -scale / 2])


def test_the_answers_are_the_meshs_own():
    # The intersector answers for the mesh as it is now: a moved mesh is traced again.
    mesh = with_raylab(trimesh.creation.box())
    ray = (np.array([[0.0, 0.0, -5.0]]), np.array([[0.0, 0.0, 1.0]]))
    before = mesh.ray.intersects_location(*ray)[0]
    mesh.apply_translation([0, 0, 1])
    after = mesh.ray.intersects_location(*ray)[0]
    assert np.allclose(after[:, 2], before[:, 2] + 1)


def test_rays_without_a_direction_hit_nothing():
    # As trimesh's intersectors answer them, where raylab.Mesh refuses them.
    mesh = with_raylab(trimesh.creation.box())
    origins = np.array([[0, 0, -5.0], [0, 0, -5.0], [np.nan, 0, -5.0], [0, 0, -5.0]])
    directions = np.array([[0, 0, 1.0], [0, 0, 0.0], [0, 0, 1.0], [np.inf, 0, 1.0]])
    assert mesh.ray.intersects_first(origins, directions).tolist() == [mesh.ray.intersects_first(
        origins[:1], directions[:1])[0], -1, -1, -1]
    assert mesh.ray.intersects_any(origins, directions).tolist() == [True, False, False, False]
    _, index_ray = mesh.ray.intersects_id(origins, directions)
    assert set(index_ray.tolist()) == {0}
