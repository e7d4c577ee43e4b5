"""raylab.Scene: a scene made in Python renders as the same scene file does."""

import numpy as np
import pytest

import raylab


def box_mesh():
    """A closed box, a unit cube's twelve triangles (no normals: flat, as the OBJ below)."""
    v = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=np.float32)
    f = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    return v, f


SETTINGS = dict(size=[40, 30], spp=4, integrator="path", max_depth=5, seed=2)


def made_in_python(vertices, faces):
    scene = raylab.Scene(**SETTINGS)
    scene.material("floor", type="diffuse", reflectance=[0.5, 0.5, 0.5])
    scene.material("red", type="diffuse", reflectance=[0.7, 0.2, 0.1])
    scene.shape(type="rectangle", material="floor", scale=5,
                rotate={"axis": [1, 0, 0], "angle": -90}, translate=[0, -1, 0])
    scene.mesh(vertices, faces, material="red", translate=[-0.5, -1, -0.5])
    scene.shape(type="rectangle", emission=[8, 8, 8], scale=0.5,
                rotate={"axis": [1, 0, 0], "angle": 90}, translate=[0, 2, 0])
    scene.light(type="environment", radiance=[0.1, 0.1, 0.15])
    scene.camera(position=[0, 1, 4], target=[0, 0, 0], fov=50)
    return scene


def test_a_python_scene_renders_as_its_scene_file(tmp_path):
    vertices, faces = box_mesh()
    scene = made_in_python(vertices, faces)
    # The same scene as a file, its mesh an OBJ beside it.
    with open(tmp_path / "box.obj", "w") as obj:
        obj.writelines(f"v {x!r} {y!r} {z!r}\n" for x, y, z in vertices.tolist())
        obj.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces.tolist())
    text = scene.to_toml().replace("<python mesh 0>", "box.obj")
    (tmp_path / "scene.toml").write_text(text)
    ours = raylab.render(scene)
    theirs = raylab.render(tmp_path / "scene.toml")
    assert ours.image.shape == (30, 40, 3) and ours.samples == 4
    np.testing.assert_array_equal(ours.image.view(np.uint32), theirs.image.view(np.uint32))
    assert ours.image.mean() > 0.01


def test_the_scene_files_errors_name_the_place():
    scene = raylab.Scene(size=[8, 8])
    scene.material("odd", type="velvet")
    scene.shape(type="sphere", material="odd")
    with pytest.raises(ValueError, match="velvet"):
        raylab.render(scene)
    scene = raylab.Scene()
    scene.shape(type="sphere", material="missing")
    with pytest.raises(ValueError, match="missing"):
        raylab.render(scene)
    scene = raylab.Scene(size=[8, 8])
    scene.camera(position=[0, 0, float("nan")])
    with pytest.raises(ValueError, match=r"camera.position\[2\] = nan is not a finite number"):
        raylab.render(scene)
    with pytest.raises(TypeError):
        raylab.Scene(size=object()).to_toml()


def test_bad_mesh_arrays():
    scene = raylab.Scene()
    with pytest.raises(ValueError, match="indexes past"):
        scene.mesh(np.zeros((3, 3)), [[0, 1, 3]])
    with pytest.raises(ValueError, match="not finite"):
        scene.mesh([[0, 0, 0], [1, 0, np.nan], [0, 1, 0]], [[0, 1, 2]])
    with pytest.raises(TypeError, match="faces must hold integers"):
        scene.mesh(np.zeros((3, 3)), [[0.0, 1.0, 2.0]])


def uv_sphere(n=12):
    """A coarse sphere: vertices, faces, unit normals and (longitude, latitude) coordinates."""
    rows = []
    for i in range(n + 1):
        theta = np.pi * i / n
        for j in range(2 * n + 1):
            phi = np.pi * j / n
            rows.append((np.sin(theta) * np.cos(phi), np.cos(theta), np.sin(theta) * np.sin(phi),
                         j / (2 * n), 1 - i / n))
    rows = np.array(rows, dtype=np.float32)
    at = lambda i, j: i * (2 * n + 1) + j  # noqa: E731
    faces = [f for i in range(n) for j in range(2 * n)
             for f in ([at(i, j), at(i + 1, j + 1), at(i + 1, j)], [at(i, j), at(i, j + 1), at(i + 1, j + 1)])]
    return rows[:, :3], np.array(faces), rows[:, :3].copy(), rows[:, 3:].copy()


def test_mesh_normals_and_uvs_render_as_a_ply_file(tmp_path):
    vertices, faces, normals, uvs = uv_sphere()
    # A texture of four coloured quadrants, read through the coordinates: red, green (top),
    # blue, violet (bottom).
    texture = np.zeros((8, 8, 3), np.float32)
    texture[:4, :4], texture[:4, 4:], texture[4:, :4], texture[4:, 4:] = (
        [0.8, 0.1, 0.1], [0.1, 0.8, 0.1], [0.1, 0.1, 0.8], [0.5, 0.1, 0.8])
    raylab.write_image(tmp_path / "quadrants.png", texture)

    def scene(**arrays):
        s = raylab.Scene(size=[48, 40], spp=4, integrator="path", max_depth=3, seed=5)
        s.material("painted", type="diffuse",
                   reflectance={"texture": str(tmp_path / "quadrants.png")})
        s.mesh(vertices, faces, material="painted", **arrays)
        s.light(type="point", position=[2, 3, -4], intensity=[40, 40, 40])
        s.light(type="environment", radiance=[0.05, 0.05, 0.05])
        s.camera(position=[0, 0.5, -3.5], target=[0, 0, 0], fov=40)
        return s

    ours = scene(normals=normals, uvs=uvs)
    # The same mesh as a PLY file with per-vertex normals and coordinates.
    with open(tmp_path / "sphere.ply", "w") as ply:
        ply.write(f"ply\nformat ascii 1.0\nelement vertex {len(vertices)}\n"
                  + "".join(f"property float {p}\n" for p in ("x", "y", "z", "nx", "ny", "nz", "u", "v"))
                  + f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
        for v, nrm, uv in zip(vertices.tolist(), normals.tolist(), uvs.tolist()):
            ply.write(" ".join(repr(x) for x in v + nrm + uv) + "\n")
        ply.writelines(f"3 {a} {b} {c}\n" for a, b, c in faces.tolist())
    (tmp_path / "scene.toml").write_text(ours.to_toml().replace("<python mesh 0>", "sphere.ply"))
    a, b = raylab.render(ours), raylab.render(tmp_path / "scene.toml")
    np.testing.assert_array_equal(a.image.view(np.uint32), b.image.view(np.uint32))
    # Both are used. Without the normals the facets show; without the coordinates the texture
    # is read elsewhere (at each face's barycentric coordinates, as Mitsuba does).
    flat, plain = raylab.render(scene(uvs=uvs)), raylab.render(scene(normals=normals))
    assert np.abs(flat.image - a.image).max() > 0.01
    assert np.abs(plain.image - a.image).max() > 0.01

    def dominant_channels(image):
        """Which channel is largest in each clearly coloured pixel (not the grey background)."""
        coloured = image.max(axis=2) > 1.5 * image.min(axis=2)
        return set(np.argmax(image[coloured], axis=1).tolist())

    # The coordinates as given: the camera sees longitudes u in (1/2, 1), so the upper
    # hemisphere (v > 1/2) is the green quadrant and the lower one the violet.
    assert dominant_channels(a.image[:13]) == {1}
    assert dominant_channels(a.image[-13:]) == {2}


@pytest.mark.parametrize(
    "arrays, words",
    [
        (dict(normals=np.zeros((5, 3))), r"normals must have shape \(8, 3\)"),
        (dict(uvs=np.zeros((8, 3))), r"uvs must have shape \(8, 2\)"),
        (dict(normals=np.full((8, 3), np.nan)), r"normals\[0\] .* is not finite"),
        (dict(uvs=[["a", "b"]] * 8), "uvs must hold real numbers"),
    ],
)
def test_bad_normals_and_uvs(arrays, words):
    vertices, faces = box_mesh()
    with pytest.raises((ValueError, TypeError), match=words):
        raylab.Scene().mesh(vertices, faces, **arrays)
