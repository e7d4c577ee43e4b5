"""Known answers, and the Rust library's answers, for Mesh.intersect / occluded / refit."""

import os
import pathlib

import numpy as np
import pytest

import raylab
from conftest import MESHES, random_rays

TRIANGLE = ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])


def test_a_ray_and_the_unit_triangle():
    mesh = raylab.Mesh(*TRIANGLE)
    hits = mesh.intersect(
        [[0.25, 0.25, -1], [0.25, 0.5, 2], [2, 2, -1], [0.5, 0.25, -1]],
        [[0, 0, 1], [0, 0, -1], [0, 0, 1], [0, 0, 4]],
    )
    assert hits.t.dtype == np.float32 and hits.triangle.dtype == np.int64
    # t in units of the direction's length: the last direction is 4 long.
    assert hits.t.tolist() == [1.0, 2.0, np.inf, 0.25]
    assert hits.triangle.tolist() == [0, 0, -1, 0]
    # u, v: the weights of the second and third vertex.
    assert hits.u.tolist() == [0.25, 0.25, 0.0, 0.5]
    assert hits.v.tolist() == [0.25, 0.5, 0.0, 0.25]


def test_the_limits_of_a_ray():
    mesh = raylab.Mesh(*TRIANGLE)
    o, d = [[0.25, 0.25, -1]] * 4, [[0, 0, 1]] * 4
    t_max = np.array([0.5, 1.5, np.inf, 2.0])
    t_min = np.array([0.0, 0.0, 1.5, 0.5])
    assert mesh.intersect(o, d, t_min=t_min, t_max=t_max).t.tolist() == [np.inf, 1, np.inf, 1]
    assert mesh.occluded(o, d, t_min=t_min, t_max=t_max).tolist() == [False, True, False, True]
    # A scalar limit holds for every ray.
    assert mesh.occluded(o, d, t_max=0.999).tolist() == [False] * 4


def square_fan():
    """A unit square cut into eight triangles around its centre (the shared vertex)."""
    rim = [(0, 0), (0.5, 0), (1, 0), (1, 0.5), (1, 1), (0.5, 1), (0, 1), (0, 0.5)]
    vertices = [[0.5, 0.5, 0.0]] + [[x, y, 0.0] for x, y in rim]
    faces = [[0, 1 + i, 1 + (i + 1) % len(rim)] for i in range(len(rim))]
    return np.array(vertices), np.array(faces)


def test_rays_through_a_shared_edge_or_vertex_always_hit():
    # Two triangles sharing the diagonal x = y: rays through exactly that edge.
    square = raylab.Mesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]])
    s = (np.arange(1, 512) / 512).astype(np.float32)
    for dz in (1.0, -1.0):
        for tilt in (0.0, 0.3, -0.7):
            origins = np.stack([s - tilt, s + tilt * 0.5, np.full_like(s, -dz)], axis=1)
            directions = np.tile(np.float32([tilt, -tilt * 0.5, dz]), (len(s), 1))
            hits = square.intersect(origins, directions)
            assert (hits.triangle >= 0).all(), "a ray slipped through the shared edge"
            assert square.occluded(origins, directions).all()
    # Eight triangles around a shared vertex: rays through exactly that vertex, at any angle.
    fan = raylab.Mesh(*square_fan())
    rng = np.random.default_rng(5)
    directions = rng.normal(size=(4096, 3)).astype(np.float32)
    directions[:, 2] = np.abs(directions[:, 2]) + 0.05
    origins = (np.float32([0.5, 0.5, 0.0]) - directions).astype(np.float32)
    hits = fan.intersect(origins, directions)
    assert (hits.triangle >= 0).all(), "a ray slipped through the shared vertex"


def test_occluded_agrees_with_intersect(bunny):
    origins, directions = random_rays(bunny, 20_000, seed=1)
    hits = bunny.intersect(origins, directions)
    assert 0.3 < (hits.triangle >= 0).mean() < 0.9
    np.testing.assert_array_equal(bunny.occluded(origins, directions), hits.triangle >= 0)
    # Segments that end before the hit are not blocked; t == inf for the misses gives inf.
    assert not bunny.occluded(origins, directions, t_max=np.minimum(hits.t * 0.5, 1e30)).any()


def test_any_thread_count_gives_the_same_answers(bunny):
    origins, directions = random_rays(bunny, 50_000, seed=2)
    one = bunny.intersect(origins, directions, threads=1)
    for threads in (2, 3, None):
        other = bunny.intersect(origins, directions, threads=threads)
        for a, b in zip(one, other):
            np.testing.assert_array_equal(a, b)


def test_float64_input_is_rounded_to_float32(bunny):
    origins, directions = random_rays(bunny, 1000, seed=3)
    a = bunny.intersect(origins, directions)
    b = bunny.intersect(origins.astype(np.float64), directions.astype(np.float64))
    np.testing.assert_array_equal(a.t, b.t)


def read(directory, name, dtype, shape=(-1,)):
    return np.fromfile(directory / name, dtype=np.dtype(dtype).newbyteorder("<")).reshape(shape)


@pytest.mark.skipif(
    "RAYLAB_RUST_ANSWERS" not in os.environ,
    reason="the Rust library's answers are written by `cargo test -p raylab-python`",
)
def test_the_rust_librarys_answers_bit_for_bit(bunny):
    directory = pathlib.Path(os.environ["RAYLAB_RUST_ANSWERS"])
    origins = read(directory, "origins.f32", np.float32, (-1, 3))
    directions = read(directory, "directions.f32", np.float32, (-1, 3))
    hits = bunny.intersect(origins, directions)
    # Bit for bit: the floats compared as their bit patterns.
    for name, got in (("t", hits.t), ("u", hits.u), ("v", hits.v)):
        want = read(directory, f"{name}.f32", np.float32)
        np.testing.assert_array_equal(got.view(np.uint32), want.view(np.uint32), err_msg=name)
    np.testing.assert_array_equal(hits.triangle, read(directory, "triangle.i64", np.int64))
    assert 0.2 < (hits.triangle >= 0).mean() < 0.9
    # Shadow segments to half the hit (odd rays: twice), or of length 1 for a miss.
    scale = np.where(np.arange(len(hits.t)) % 2 == 0, 0.5, 2.0).astype(np.float32)
    t_max = np.where(hits.triangle >= 0, hits.t * scale, np.float32(1.0)).astype(np.float32)
    want = read(directory, "occluded.u8", np.uint8).astype(bool)
    np.testing.assert_array_equal(bunny.occluded(origins, directions, t_max=t_max), want)


def test_refit_gives_a_new_meshs_answers(bunny):
    vertices, faces = bunny.vertices, bunny.faces
    moved = (vertices * np.float32(1.5) + np.float32([0.1, -0.2, 0.05])).astype(np.float32)
    refitted = raylab.load_mesh(MESHES / "bunny.obj.gz")
    refitted.refit(moved)
    fresh = raylab.Mesh(moved, faces)
    origins, directions = random_rays(fresh, 20_000, seed=4)
    a, b = refitted.intersect(origins, directions), fresh.intersect(origins, directions)
    np.testing.assert_array_equal(a.triangle, b.triangle)
    np.testing.assert_array_equal(a.t, b.t)
    np.testing.assert_array_equal(refitted.vertices, moved)


def test_load_mesh_reads_the_formats():
    assert len(raylab.load_mesh(MESHES / "bunny.obj.gz")) == 75_408
    assert len(raylab.load_mesh(MESHES / "bunny_lowres.obj")) == 3_674
    # A glTF's instanced meshes are copied into their places.
    assert len(raylab.load_mesh(MESHES / "2CylinderEngine/2CylinderEngine.glb")) == 121_496


def cube():
    vertices = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    index = {tuple(v): i for i, v in enumerate(vertices.astype(int).tolist())}
    quads = [
        [(0, 0, 0), (0, 1, 0), (1, 1, 0), (1, 0, 0)],
        [(0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)],
        [(0, 0, 0), (1, 0, 0), (1, 0, 1), (0, 0, 1)],
        [(0, 1, 0), (0, 1, 1), (1, 1, 1), (1, 1, 0)],
        [(0, 0, 0), (0, 0, 1), (0, 1, 1), (0, 1, 0)],
        [(1, 0, 0), (1, 1, 0), (1, 1, 1), (1, 0, 1)],
    ]
    faces = []
    for a, b, c, d in quads:
        faces += [[index[a], index[b], index[c]], [index[a], index[c], index[d]]]
    return raylab.Mesh(vertices, faces)


def test_count_hits_through_shared_edges_and_corners():
    mesh = cube()
    centre = np.full((27, 3), 0.5)
    grid = np.array([[x, y, z] for x in (0, 0.5, 1) for y in (0, 0.5, 1) for z in (0, 0.5, 1)])
    keep = ~(grid == 0.5).all(axis=1)
    # From the centre through every corner, edge midpoint and face centre: one crossing.
    assert mesh.count_hits(centre[keep], grid[keep] - 0.5).tolist() == [1] * 26
    # From beyond, back through the point and the cube: two.
    assert mesh.count_hits(grid[keep] * 3 - 1, 0.5 - grid[keep]).tolist() == [2] * 26
    # The closest hit still counts every touching triangle as hit: none slips through.
    assert (mesh.intersect(centre[keep], grid[keep] - 0.5).triangle >= 0).all()


def test_contains_a_closed_cube_and_the_bunny(bunny):
    mesh = cube()
    rng = np.random.default_rng(8)
    points = rng.uniform(-0.5, 1.5, (20_000, 3))
    inside = ((points > 0) & (points < 1)).all(axis=1)
    np.testing.assert_array_equal(mesh.contains(points), inside)
    # Points on a grid, in the cube's face planes' neighbourhood (on none of them).
    g = np.arange(-2, 11) / 8
    grid = np.stack(np.meshgrid(g, g, g), axis=-1).reshape(-1, 3)
    grid = grid[~((grid == 0) | (grid == 1)).any(axis=1)]
    np.testing.assert_array_equal(mesh.contains(grid), ((grid > 0) & (grid < 1)).all(axis=1))
    # The bunny: every point agrees along three directions.
    lo, hi = bunny.vertices.min(0), bunny.vertices.max(0)
    points = lo + rng.random((5000, 3)) * (hi - lo)
    parity = [bunny.count_hits(points, np.tile(d, (5000, 1))) % 2 for d in np.eye(3)]
    np.testing.assert_array_equal(parity[0], parity[1])
    np.testing.assert_array_equal(parity[0], parity[2])
    np.testing.assert_array_equal(bunny.contains(points), parity[0] == 1)
    assert 0.05 < bunny.contains(points).mean() < 0.95


def bumpy_sphere(n):
    """A closed sphere of `2·n·(n − 1)` triangles with bumps: a tree of several megabytes."""
    theta = np.linspace(0, np.pi, n + 1)[1:-1]
    phi = np.linspace(0, 2 * np.pi, n, endpoint=False)
    th, ph = np.meshgrid(theta, phi, indexing="ij")
    r = 1 + 0.05 * np.sin(7 * th) * np.cos(11 * ph)
    ring = np.stack([r * np.sin(th) * np.cos(ph), r * np.sin(th) * np.sin(ph), r * np.cos(th)], -1)
    vertices = np.concatenate([[[0, 0, 1]], ring.reshape(-1, 3), [[0, 0, -1]]])
    rows, cols = n - 1, n
    at = lambda i, j: 1 + i * cols + j % cols  # noqa: E731
    faces = [[0, at(0, j), at(0, j + 1)] for j in range(cols)]
    faces += [[len(vertices) - 1, at(rows - 1, j + 1), at(rows - 1, j)] for j in range(cols)]
    for i in range(rows - 1):
        for j in range(cols):
            faces += [[at(i, j), at(i + 1, j), at(i + 1, j + 1)], [at(i, j), at(i + 1, j + 1), at(i, j + 1)]]
    return raylab.Mesh(vertices, faces)


def test_a_large_batch_in_the_trees_order_gives_every_rays_own_answer():
    """A large batch on a large tree is traced sorted by where its rays run through the tree
    (`raylab::bvh::order`); small batches are traced as given, and those are the Rust library's
    answers (the test above). Both must give every ray the same answer, bit for bit."""
    from raylab import _raylab

    mesh = bumpy_sphere(300)
    assert mesh.bvh_bytes >= _raylab.ORDER_MIN_TREE_BYTES, "the tree must be large enough"
    n = 3 * _raylab.ORDER_MIN_RAYS
    origins, directions = random_rays(mesh, n, seed=9)
    # Some rays start inside the sphere, some are segments that end early.
    origins[::7] *= np.float32(0.01)
    t_max = np.where(np.arange(n) % 5 == 0, np.float32(0.8), np.float32(np.inf)).astype(np.float32)
    small = _raylab.ORDER_MIN_RAYS // 2

    def in_small_batches(query):
        parts = [query(origins[s : s + small], directions[s : s + small], t_max=t_max[s : s + small])
                 for s in range(0, n, small)]
        return [np.concatenate(p) for p in zip(*parts)] if isinstance(parts[0], tuple) else np.concatenate(parts)

    for threads in (1, 2):
        whole = mesh.intersect(origins, directions, t_max=t_max, threads=threads)
        given = in_small_batches(lambda o, d, t_max: mesh.intersect(o, d, t_max=t_max, threads=threads))
        for name, a, b in zip(("t", "triangle", "u", "v"), whole, given):
            np.testing.assert_array_equal(a.view(np.uint32) if a.dtype == np.float32 else a,
                                          b.view(np.uint32) if b.dtype == np.float32 else b, err_msg=name)
        assert 0.3 < (whole.triangle >= 0).mean() < 0.95
        for query in (mesh.occluded, mesh.count_hits):
            whole = query(origins, directions, t_max=t_max, threads=threads)
            given = in_small_batches(lambda o, d, t_max: query(o, d, t_max=t_max, threads=threads))
            np.testing.assert_array_equal(whole, given)
    # Inside or outside, for points inside the sphere and beyond it.
    points = np.random.default_rng(10).uniform(-1.2, 1.2, (n, 3))
    inside = np.linalg.norm(points, axis=1) < 0.9
    outside = np.linalg.norm(points, axis=1) > 1.1
    contained = mesh.contains(points)
    assert contained[inside].all() and not contained[outside].any()
    # A bad ray in such a batch is named as in any other: the first one. The first here has a
    # NaN t_min (its key is its segment's); a later one a NaN direction, whose key is 0, so
    # the trace meets the later one first, also on one thread.
    t_min = np.zeros(n, np.float32)
    t_min[small + 3] = np.nan
    directions[2 * small + 1] = np.nan
    for query in (mesh.intersect, mesh.occluded, mesh.count_hits):
        for threads in (1, 2):
            with pytest.raises(ValueError, match=rf"ray {small + 3}: t_min = NaN"):
                query(origins, directions, t_min=t_min, threads=threads)
