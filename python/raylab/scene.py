"""`raylab.Scene`: a scene made in Python with the scene files' names (docs/scene-format.md in
the repository): `[render]` settings, `[materials.NAME]`, `[[shapes]]`, `[[lights]]`,
`[camera]`. Meshes may be numpy arrays.

    scene = raylab.Scene(size=(256, 256), spp=16, integrator="path")
    scene.material("white", type="diffuse", reflectance=[0.8, 0.8, 0.8])
    scene.mesh(vertices, faces, material="white", translate=[0, -1, 0])
    scene.shape(type="sphere", material="white", radius=0.5)
    scene.light(type="point", position=[0, 3, 3], intensity=[20, 20, 20])
    scene.camera(position=[0, 1, 5], target=[0, 0, 0], fov=40)
    result = raylab.render(scene)

The scene becomes a scene file's text (`to_toml()`) that raylab's own reader reads, with the
arrays handed over in memory, so every name, default and error message is the scene files'.
"""

import math
import os

import numpy as np


def _toml_value(value, where):
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        if not math.isfinite(value):
            raise ValueError(f"{where} = {value} is not a finite number")
        return repr(float(value))
    if isinstance(value, str):
        escaped = value.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")
        return f'"{escaped}"'
    if isinstance(value, os.PathLike):
        return _toml_value(os.fspath(value), where)
    if isinstance(value, dict):
        items = ", ".join(f"{_key(k)} = {_toml_value(v, f'{where}.{k}')}" for k, v in value.items())
        return "{ " + items + " }"
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v, f"{where}[{i}]") for i, v in enumerate(value)) + "]"
    raise TypeError(f"{where}: {value!r} is not a number, string, list or table")


def _key(name):
    if not isinstance(name, str) or not name:
        raise TypeError(f"a key must be a non-empty string, not {name!r}")
    if all(c.isalnum() or c in "_-" for c in name):
        return name
    return _toml_value(name, "key")


def _table(header, entries, where):
    lines = [header]
    lines += [f"{_key(k)} = {_toml_value(v, f'{where}.{k}')}" for k, v in entries.items()
              if v is not None]
    return "\n".join(lines)


class Scene:
    """A scene made in Python (see the module documentation). Keyword arguments are the
    `[render]` settings: size (width, height), spp, max_depth, integrator, sampler, filter,
    seed and the others the scene format has."""

    def __init__(self, **render):
        self._render = dict(render)
        self._camera = None
        self._materials = {}
        self._shapes = []
        self._lights = []
        self._meshes = {}

    def material(self, name, **parameters):
        """Adds material `name` (`type` and its parameters, as `[materials.NAME]`); returns
        the name."""
        if not isinstance(name, str) or not name:
            raise TypeError(f"a material's name must be a non-empty string, not {name!r}")
        self._materials[name] = parameters
        return name

    def shape(self, **parameters):
        """Adds a shape, as a `[[shapes]]` entry: `type` ("rectangle", "cube", "sphere",
        "mesh" with `file`, "cornell"), `material`, `emission`, and its placement."""
        self._shapes.append(parameters)

    def mesh(self, vertices, faces, normals=None, uvs=None, **parameters):
        """Adds a triangle mesh from arrays (as `raylab.Mesh` takes them), with a shape's
        other keys (`material`, `emission`, `scale`, `rotate`, `translate`, ...).

        normals: optional (n, 3) shading normals, one per vertex (interpolated across each
            face, as a PLY file's `nx ny nz`; a zero normal means none).
        uvs: optional (n, 2) texture coordinates, one per vertex (`v` up from an image's
            bottom row, as in OBJ and Mitsuba), for image textures."""
        from . import _faces, _points, _real_array  # the checks of raylab.Mesh

        name = f"<python mesh {len(self._meshes)}>"
        vertices, faces = _points(vertices, "vertices"), _faces(faces)
        if len(faces) and int(faces.max()) >= len(vertices):
            row = int(np.argwhere(faces >= len(vertices))[0][0])
            raise ValueError(f"faces[{row}] = {faces[row].tolist()} indexes past the "
                             f"{len(vertices)} vertices")
        arrays = {"vertices": vertices}
        if normals is not None:
            arrays["normals"] = _real_array(normals, "normals", (len(vertices), 3), np.float32)
        if uvs is not None:
            arrays["uvs"] = _real_array(uvs, "uvs", (len(vertices), 2), np.float32)
        for what, array in arrays.items():
            if not np.isfinite(array).all():
                row = int(np.argwhere(~np.isfinite(array).all(axis=1))[0][0])
                raise ValueError(f"{what}[{row}] = {array[row].tolist()} is not finite")
        self._meshes[name] = (vertices, faces, arrays.get("normals"), arrays.get("uvs"))
        self._shapes.append(dict(type="mesh", file=name, **parameters))

    def light(self, **parameters):
        """Adds a light, as a `[[lights]]` entry (`type` "point" or "environment", ...)."""
        self._lights.append(parameters)

    def camera(self, **parameters):
        """Sets the camera, as `[camera]` (position, target, up, fov, ...)."""
        self._camera = parameters

    def to_toml(self):
        """The scene as a scene file's text (its meshes from arrays named
        `<python mesh N>`)."""
        parts = []
        if self._render:
            parts.append(_table("[render]", self._render, "render"))
        if self._camera is not None:
            parts.append(_table("[camera]", self._camera, "camera"))
        for name, parameters in self._materials.items():
            parts.append(_table(f"[materials.{_key(name)}]", parameters, f"materials.{name}"))
        for i, shape in enumerate(self._shapes):
            parts.append(_table("[[shapes]]", shape, f"shapes[{i}]"))
        for i, light in enumerate(self._lights):
            parts.append(_table("[[lights]]", light, f"lights[{i}]"))
        return "\n\n".join(parts) + "\n"

    def _arrays(self):
        return [(name, *arrays) for name, arrays in self._meshes.items()]

    def __repr__(self):
        return (f"raylab.Scene({len(self._materials)} materials, {len(self._shapes)} shapes, "
                f"{len(self._lights)} lights)")
