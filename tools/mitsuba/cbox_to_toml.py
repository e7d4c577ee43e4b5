#!/usr/bin/env python3
"""Writes scenes/cornell-mitsuba.toml from the Mitsuba 3 Cornell box export (cbox.json):
every shape with its exact `to_world` matrix, reflectance and emitter, the camera and the
integrator's settings.

    python3 tools/mitsuba/cbox_to_toml.py ../shared/scenes/mitsuba-cbox/cbox.json > scenes/cornell-mitsuba.toml
"""
import json
import sys

d = json.load(open(sys.argv[1]))


def number(x):
    return repr(float(x)).rstrip("0").rstrip(".") if float(x) != int(x) else str(int(x))


def vec(v):
    return "[" + ", ".join(number(x) for x in v) + "]"


cam = d["camera"]
out = [
    "# Mitsuba 3's Cornell box (mi.cornell_box(), Mitsuba 3.9.1), exactly: every shape with its",
    "# to_world matrix, one-sided diffuse materials, the one-sided area light, the camera and the",
    "# path integrator's settings. Written by tools/mitsuba/cbox_to_toml.py from cbox.json.",
    "# Render: raylab render scenes/cornell-mitsuba.toml -o cbox.exr",
    "",
    "[render]",
    f"size = {vec(d['film'].get('size', [512, 512]))}" if isinstance(d.get("film"), dict) and "size" in d["film"] else "size = [512, 512]",
    "spp = 64",
    f"max_depth = {d['integrator']['max_depth']}",
    'integrator = "path"',
    'filter = "box"',
    "",
    "[camera]",
    f"position = {vec(cam['origin'])}",
    f"target = {vec(cam['target'])}",
    f"up = {vec(cam['up'])}",
    f"fov = {cam['fov_deg']}",
    f"fov_axis = \"{cam['fov_axis']}\"",
    "",
]
materials = {}
for shape in d["shapes"]:
    reflectance = tuple(shape["bsdf"]["reflectance"])
    name = {
        "green-wall": "green",
        "red-wall": "red",
    }.get(shape["name"], "white")
    materials.setdefault(name, reflectance)
for name, reflectance in materials.items():
    out += [f"[materials.{name}]", 'type = "diffuse"', f"reflectance = {vec(reflectance)}", ""]
for shape in d["shapes"]:
    name = {"green-wall": "green", "red-wall": "red"}.get(shape["name"], "white")
    assert tuple(shape["bsdf"]["reflectance"]) == materials[name]
    out += [f"[[shapes]]  # {shape['name']}", f"type = \"{shape['mitsuba_type']}\"", f'material = "{name}"']
    if shape.get("emitter"):
        out.append(f"emission = {vec(shape['emitter']['radiance'])}")
    rows = ", ".join(vec(r) for r in shape["mitsuba_to_world"])
    out += [f"to_world = [{rows}]", ""]
print("\n".join(out).rstrip() + "\n", end="")
