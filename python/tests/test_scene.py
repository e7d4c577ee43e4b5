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
