#!/usr/bin/env python3
"""Mitsuba 3 reference renders of a raylab scene file (TOML), translated as raylab reads it.

Made for crates/raylab/tests/data/mitsuba-materials/materials.toml (five spheres of sphere.obj:
gold, glass, frosted glass, blue plastic and brushed aluminium, on a grey floor under a
rectangular light, in a constant environment), for
crates/raylab/tests/data/mitsuba-gltf/boxes.toml (a textured glTF box drawn eighteen times by its
nodes) and for crates/raylab/tests/data/mitsuba-envmap/envmap.toml (spheres on a floor under an
HDR sky with a small bright sun, and a spot light), but it translates the scene format generically
(docs/scene-format.md), as far as Mitsuba has the same thing:

  [render]   size -> hdrfilm width/height (pixel_format rgb, float32); filter box -> rfilter box,
             gaussian -> gaussian (stddev 0.5, Mitsuba's radius 4 stddev = 2 px); max_depth ->
             path max_depth (rr_depth 5, Mitsuba's and raylab's default); integrator must be
             `path`; the sampler is --sampler (Mitsuba's default `independent`; `multijitter`,
             its best for the Cornell box; raylab's sobol/lab samplers only change the noise, not
             the expectation). spp and seed come from the command line; --warmup renders once
             first, so that the timing is of compiled kernels.
  [camera]   position + target (up [0, 1, 0]), or position + yaw/pitch: perspective with
             to_world = look_at(position, target, up), fov, fov_axis; aperture_radius > 0 ->
             thinlens (aperture_radius, focus_distance).
  materials  diffuse (its reflectance a colour, or an image texture { texture = "file.png",
             wrap, scale } as Mitsuba's bitmap: sRGB decoded, bilinear, wrap_mode, to_uv scale),
             conductor, roughconductor (RGB eta/k; a named metal is raylab's RGB table,
             not Mitsuba's spectral data), dielectric, roughdielectric, plastic, twosided. Named
             IORs become raylab's numbers (the same table as Mitsuba's). Rough materials always get
             distribution ggx (Mitsuba's default would be beckmann) and sample_visible true.
             Anisotropic ones (alpha_u != alpha_v) use Mitsuba's shading frame (dp_du: on a mesh
             without UVs, the triangle's first edge), which raylab uses too; --duff-frames wraps
             them in `raylab_frame`, a Python BSDF that evaluates the nested Mitsuba BSDF in the
             Duff basis of the shading normal instead (raylab's frame before).
  shapes     rectangle, cube (Mitsuba's plugins), sphere (raylab's 48 x 96 UV sphere with vertex
             normals, written to a temporary PLY), mesh (.obj / .ply through Mitsuba's plugins, with
             face_normals false and flip_normals false, and a named material; a .gltf / .glb
             file's default scene through gltf_mesh.py: each mesh once, written to a temporary
             OBJ with its normals and texture coordinates, in a shapegroup, and an instance of it
             for each node that draws it, at the node's world matrix). Transform: scale,
             then rotate (right-handed, degrees), then translate, then to_world:
             to_world = M . T . R . S. `emission` -> an `area` emitter on the shape (its BSDF is
             the named material, or black diffuse without one).
  lights     environment -> constant; point -> point (intensity, or power / 4 pi); envmap ->
             envmap (filename beside the scene file, scale, to_world = the rotate and to_world
             keys as for shapes); directional -> directional (direction or to_world,
             irradiance); spot -> spot (intensity, cutoff_angle, beam_width; to_world, or
             position + target as look_at with an up across the axis). A `sun` has no Mitsuba
             counterpart (its sunsky is another model): an error.

Not translated (an error): the `cornell` shape, meshes without `material` (MTL materials),
.gz meshes, integrators other than path.

Output: linear float32 RGB, row 0 = top. By the suffix of --out: .pfm (little-endian,
'PF\\nW H\\n-1.0\\n', rows bottom to top), .exr (mi.Bitmap) or .npy (H, W, 3); --also-npy,
--also-exr, --also-pfm write the same image in the other formats next to it, and --png writes a
tone-mapped sRGB preview (exposure --exposure, then clipped to [0, 1]).

--passes N renders N passes of --spp samples with seeds seed, seed+1, ..., seed+N-1 and averages
them (with the box filter every pixel gets exactly spp samples per pass, so this equals one
render of N * spp samples).

Requirements: pip install mitsuba (3.9.1 used); for llvm_* variants a libLLVM (Debian:
libllvm19) and DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so (set here if unset
and that file exists).

Example (the committed reference):
  nice -n 10 python3 tools/mitsuba/materials_reference.py \\
      crates/raylab/tests/data/mitsuba-materials/materials.toml \\
      --spp 2048 --passes 8 --seed 0 \\
      --out crates/raylab/tests/data/mitsuba-materials/reference.pfm
"""

import time

T_PROCESS0 = time.perf_counter()

import argparse
import math
import os
import sys
import tempfile
import tomllib

import numpy as np

# raylab's tables (crates/raylab/src/scene/scene_file/materials.rs, material/conductor.rs).
NAMED_IORS = {
    "vacuum": 1.0, "helium": 1.000036, "hydrogen": 1.000132, "air": 1.000277,
    "carbon dioxide": 1.00045, "water": 1.333, "acetone": 1.36, "ethanol": 1.361,
    "carbon tetrachloride": 1.461, "glycerol": 1.4729, "benzene": 1.501,
    "silicone oil": 1.52045, "bromine": 1.661, "water ice": 1.31, "fused quartz": 1.458,
    "pyrex": 1.47, "acrylic glass": 1.49, "polypropylene": 1.49, "bk7": 1.5046,
    "sodium chloride": 1.544, "amber": 1.55, "pet": 1.575, "diamond": 2.419,
}
METALS = {
    "Au": ([0.183, 0.421, 1.373], [3.424, 2.346, 1.770]),
    "Ag": ([0.159, 0.145, 0.135], [3.929, 3.190, 2.381]),
    "Cu": ([0.271, 0.677, 1.316], [3.609, 2.625, 2.292]),
    "Al": ([1.657, 0.880, 0.521], [9.224, 6.270, 4.837]),
    "none": ([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]),
}


class SceneError(Exception):
    pass


def rgb(v, what="colour"):
    if isinstance(v, (int, float)):
        v = [v, v, v]
    if len(v) != 3:
        raise SceneError(f"{what}: expected [r, g, b], got {v!r}")
    return {"type": "rgb", "value": [float(x) for x in v]}


sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mitsuba_run import Render, load_mitsuba  # noqa: E402
from pfm import write_pfm  # noqa: E402
import gltf_mesh  # noqa: E402


# ---------------------------------------------------------------------------------------------
# Transforms (numpy 4x4, y-up file frame = Mitsuba's world frame).

def rotation(axis, angle_deg):
    a = np.asarray(axis, dtype=np.float64)
    n = np.linalg.norm(a)
    if n == 0 or not math.isfinite(angle_deg):
        raise SceneError("rotate needs a non-zero axis and a finite angle")
    x, y, z = a / n
    t = math.radians(angle_deg)
    c, s, C = math.cos(t), math.sin(t), 1 - math.cos(t)
    m = np.eye(4)
    m[:3, :3] = [[c + x * x * C, x * y * C - z * s, x * z * C + y * s],
                 [y * x * C + z * s, c + y * y * C, y * z * C - x * s],
                 [z * x * C - y * s, z * y * C + x * s, c + z * z * C]]
    return m


def shape_matrix(doc):
    """scale, then rotate, then translate, then to_world: M . T . R . S."""
    m = np.eye(4)
    if "scale" in doc:
        s = doc["scale"]
        f = [float(s)] * 3 if isinstance(s, (int, float)) else [float(x) for x in s]
        if len(f) != 3 or any(x == 0 for x in f):
            raise SceneError(f"scale {s!r}")
        m = np.diag(f + [1.0]) @ m
    if "rotate" in doc:
        m = rotation(doc["rotate"]["axis"], float(doc["rotate"]["angle"])) @ m
    if "translate" in doc:
        t = np.eye(4)
        t[:3, 3] = [float(x) for x in doc["translate"]]
        m = t @ m
    if "to_world" in doc:
        w = np.array(doc["to_world"], dtype=np.float64)
        if w.shape != (4, 4) or not np.allclose(w[3], [0, 0, 0, 1]):
            raise SceneError("to_world must be 4x4 with last row 0 0 0 1")
        m = w @ m
    return m


# ---------------------------------------------------------------------------------------------
# raylab's tangent frame for anisotropic materials.
#
# raylab's shading frame at every hit is Duff et al.'s orthonormal basis of the shading normal
# (integrator/path.rs: Frame::new(shading_normal); it is computed in the lab's y-down frame, but
# that half turn about x commutes with the basis exactly). Mitsuba 3.9.1's mesh without UVs
# instead takes dp_du = the triangle's first edge (the barycentric parametrisation) and
# Gram-Schmidts it against the shading normal, so an anisotropic BSDF's alpha_u direction jumps
# from triangle to triangle (a checkered, faceted brushed metal). Isotropic BSDFs do not care.
# The wrapper below re-expresses wi/wo in mi.Frame3f(sh_frame.n) -- Mitsuba's coordinate_system,
# the same Duff basis -- around the unchanged nested Mitsuba BSDF. Only with --duff-frames.

def register_raylab_frame(mi):
    class RaylabFrame(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.nested = props["nested"]
            self.m_flags = self.nested.flags()
            self.m_components = [self.nested.flags(i)
                                 for i in range(self.nested.component_count())]

        def _reframe(self, si):
            frame = mi.Frame3f(si.sh_frame.n)
            si2 = mi.SurfaceInteraction3f(si)
            si2.sh_frame = frame
            si2.wi = frame.to_local(si.sh_frame.to_world(si.wi))
            return si2, frame

        def sample(self, ctx, si, sample1, sample2, active=True):
            si2, frame = self._reframe(si)
            bs, weight = self.nested.sample(ctx, si2, sample1, sample2, active)
            bs.wo = si.sh_frame.to_local(frame.to_world(bs.wo))
            return bs, weight

        def eval(self, ctx, si, wo, active=True):
            si2, frame = self._reframe(si)
            return self.nested.eval(ctx, si2, frame.to_local(si.sh_frame.to_world(wo)), active)

        def pdf(self, ctx, si, wo, active=True):
            si2, frame = self._reframe(si)
            return self.nested.pdf(ctx, si2, frame.to_local(si.sh_frame.to_world(wo)), active)

        def eval_pdf(self, ctx, si, wo, active=True):
            si2, frame = self._reframe(si)
            return self.nested.eval_pdf(ctx, si2, frame.to_local(si.sh_frame.to_world(wo)),
                                        active)

        def traverse(self, callback):
            self.nested.traverse(callback)

        def to_string(self):
            return f"RaylabFrame[nested={self.nested}]"

    mi.register_bsdf("raylab_frame", lambda props: RaylabFrame(props))


# ---------------------------------------------------------------------------------------------
# Materials.

def ior(value, default):
    if value is None:
        return default
    if isinstance(value, str):
        if value not in NAMED_IORS:
            raise SceneError(f"unknown index of refraction '{value}'")
        return NAMED_IORS[value]
    return float(value)


def metal(doc):
    name, eta, k = doc.get("material"), doc.get("eta"), doc.get("k")
    if name is not None and eta is None and k is None:
        if name not in METALS:
            raise SceneError(f"unknown metal '{name}'")
        eta, k = METALS[name]
    elif name is None and eta is not None and k is not None:
        pass
    elif name is None and eta is None and k is None:
        eta, k = METALS["none"]
    else:
        raise SceneError("a conductor takes `material` or both `eta` and `k`")
    return {
        "eta": rgb(eta, "eta"),
        "k": rgb(k, "k"),
        "specular_reflectance": rgb(doc.get("specular_reflectance", [1.0, 1.0, 1.0])),
    }


def roughness(doc):
    d = doc.get("distribution", "ggx")
    if d != "ggx":
        raise SceneError(f"distribution '{d}': only ggx")
    a, u, v = doc.get("alpha"), doc.get("alpha_u"), doc.get("alpha_v")
    out = {"distribution": "ggx", "sample_visible": True}
    if a is not None and u is None and v is None:
        out["alpha"] = float(a)
    elif a is None and u is not None and v is not None:
        out["alpha_u"], out["alpha_v"] = float(u), float(v)
    elif a is None and u is None and v is None:
        out["alpha"] = 0.1
    else:
        raise SceneError("give `alpha`, or both `alpha_u` and `alpha_v`")
    return out


def anisotropic(d):
    return d.get("alpha_u", 0.0) != d.get("alpha_v", 0.0)


def material(doc, raylab_frames=True):
    """The Mitsuba BSDF dict; anisotropic rough materials wrapped in raylab_frame."""
    d = plain_material(doc, raylab_frames)
    if raylab_frames and anisotropic(d):
        return {"type": "raylab_frame", "nested": d}
    return d


def colour(value, what="colour"):
    """A colour, or an image texture table ({ texture = "file.png", wrap, scale }) as Mitsuba's
    bitmap: sRGB-decoded to linear, then bilinear (raylab's path tracer reads level 0 of its
    mip-map bilinearly, in linear light, texel centres at (x + 1/2)/w as Mitsuba's)."""
    if not isinstance(value, dict):
        return rgb(value, what)
    name = value.get("texture", "")
    if os.path.splitext(name)[1].lower() not in (".png", ".jpg", ".jpeg"):
        raise SceneError(f"{what}: only image textures are translated, not {name!r}")
    if value.get("srgb", True) is not True or "colors" in value:
        raise SceneError(f"{what}: an image texture with srgb or colors is not translated")
    wrap = value.get("wrap", "repeat")
    if wrap not in ("repeat", "clamp", "mirror"):
        raise SceneError(f"{what}: wrap {wrap!r}")
    # raylab reads an image at (s u, 1 - s v) from its top-left corner (the OBJ convention, v
    # up, then the scale); Mitsuba at to_uv(u, 1 - v), its OBJ loader having flipped v: so
    # to_uv = translate(0, 1 - s) . scale(s).
    s = float(value.get("scale", 1.0))
    to_uv = mi_module().ScalarTransform4f().translate([0.0, 1.0 - s, 0.0]) @ \
        mi_module().ScalarTransform4f().scale([s, s, 1.0])
    return {"type": "bitmap", "filename": os.path.join(TEXTURE_FOLDER[0], name),
            "filter_type": "bilinear", "wrap_mode": wrap, "raw": False, "to_uv": to_uv}


# The scene file's folder (textures are read beside it) and the Mitsuba module, set by main.
TEXTURE_FOLDER = [""]
_MI = []


def mi_module():
    return _MI[0]


def plain_material(doc, raylab_frames):
    kind = doc.get("type")
    if kind == "diffuse":
        return {"type": "diffuse", "reflectance": colour(doc["reflectance"], "reflectance")}
    if kind == "conductor":
        return {"type": "conductor", **metal(doc)}
    if kind == "roughconductor":
        return {"type": "roughconductor", **metal(doc), **roughness(doc)}
    if kind in ("dielectric", "roughdielectric"):
        d = {"type": kind, "int_ior": ior(doc.get("int_ior"), 1.5046),
             "ext_ior": ior(doc.get("ext_ior"), 1.000277)}
        if kind == "roughdielectric":
            d.update(roughness(doc))
        return d
    if kind == "plastic":
        return {
            "type": "plastic",
            "diffuse_reflectance": rgb(doc.get("diffuse_reflectance", [0.5, 0.5, 0.5])),
            "specular_reflectance": rgb(doc.get("specular_reflectance", [1.0, 1.0, 1.0])),
            "int_ior": ior(doc.get("int_ior"), 1.49),
            "ext_ior": ior(doc.get("ext_ior"), 1.000277),
            "nonlinear": bool(doc.get("nonlinear", False)),
        }
    if kind == "twosided":
        return {"type": "twosided", "bsdf": material(doc["bsdf"], raylab_frames)}
    raise SceneError(f"unknown material type {kind!r}")


# ---------------------------------------------------------------------------------------------
# Shapes.

def raylab_sphere_ply(path, centre, radius):
    """Writes raylab's built-in sphere (scene_file/shapes.rs) as a binary PLY: 48 rings x 96
    segments (9,024 triangles), facing out, vertex normals = the unit positions."""
    rings, segments = 48, 96
    theta = np.pi * np.arange(rings + 1, dtype=np.float64) / rings
    phi = 2 * np.pi * np.arange(segments, dtype=np.float64) / segments
    th, ph = np.meshgrid(theta, phi, indexing="ij")
    unit = np.stack([np.sin(th) * np.cos(ph), np.cos(th), -np.sin(th) * np.sin(ph)],
                    axis=-1).reshape(-1, 3)
    idx = lambda r, s: r * segments + s % segments
    tris = []
    for r in range(rings):
        for s in range(segments):
            a, b, c, d = idx(r, s), idx(r, s + 1), idx(r + 1, s), idx(r + 1, s + 1)
            if r > 0:
                tris.append((a, c, b))
            if r + 1 < rings:
                tris.append((b, c, d))
    pos = np.asarray(centre, dtype=np.float64) + radius * unit
    vert = np.hstack([pos, unit]).astype("<f4")
    faces = np.zeros(len(tris), dtype=[("n", "u1"), ("i", "<u4", 3)])
    faces["n"] = 3
    faces["i"] = np.array(tris, dtype=np.uint32)
    with open(path, "wb") as f:
        f.write(("ply\nformat binary_little_endian 1.0\n"
                 f"element vertex {len(vert)}\n"
                 "property float x\nproperty float y\nproperty float z\n"
                 "property float nx\nproperty float ny\nproperty float nz\n"
                 f"element face {len(tris)}\n"
                 "property list uchar uint vertex_indices\nend_header\n").encode())
        f.write(vert.tobytes())
        f.write(faces.tobytes())


def shape_dicts(mi, doc, folder, materials, sphere_dir, raylab_frames):
    out = {}
    for i, s in enumerate(doc.get("shapes", [])):
        kind = s.get("type")
        key = f"shape_{i:03d}_{kind}"
        m = shape_matrix(s)
        name = s.get("material")
        if name is not None:
            if name not in materials:
                raise SceneError(f"no material named '{name}'")
            bsdf = material(materials[name], raylab_frames)
        elif "emission" in s:
            bsdf = {"type": "diffuse", "reflectance": rgb([0.0, 0.0, 0.0])}
        else:
            raise SceneError(f"shape {i} ({kind}): needs a material (MTL materials are not "
                             "translated)")
        if kind in ("rectangle", "cube"):
            d = {"type": kind, "to_world": mi.ScalarTransform4f(m.tolist())}
        elif kind == "mesh" and os.path.splitext(s["file"])[1].lower() in (".gltf", ".glb"):
            # Each glTF mesh once (a shapegroup), placed by its nodes (instances).
            path = os.path.join(folder, s["file"])
            if "emission" in s:
                raise SceneError(f"mesh {path}: a glTF mesh with `emission` is not translated")
            os.makedirs(sphere_dir, exist_ok=True)
            for j, (triangles, worlds) in enumerate(gltf_mesh.read(path)):
                obj = os.path.join(sphere_dir, f"{key}_{j}.obj")
                gltf_mesh.write_obj(obj, triangles)
                group = f"{key}_{j}_group"
                out[group] = {"type": "shapegroup",
                              "mesh": {"type": "obj", "filename": obj, "face_normals": False,
                                       "flip_normals": False, "bsdf": bsdf}}
                for k, world in enumerate(worlds):
                    out[f"{key}_{j}_instance_{k:03d}"] = {
                        "type": "instance", "shapegroup": {"type": "ref", "id": group},
                        "to_world": mi.ScalarTransform4f((m @ world).tolist())}
            continue
        elif kind == "mesh":
            path = os.path.join(folder, s["file"])
            ext = os.path.splitext(path)[1].lower()
            if ext not in (".obj", ".ply"):
                raise SceneError(f"mesh {path}: only .obj, .ply, .gltf and .glb are translated")
            d = {"type": ext[1:], "filename": path, "face_normals": False,
                 "flip_normals": False, "to_world": mi.ScalarTransform4f(m.tolist())}
        elif kind == "sphere":
            centre = [float(x) for x in s.get("center", [0, 0, 0])]
            radius = float(s.get("radius", 1.0))
            if not radius > 0:
                raise SceneError("a sphere needs a radius above 0")
            os.makedirs(sphere_dir, exist_ok=True)
            path = os.path.join(sphere_dir, f"{key}.ply")
            raylab_sphere_ply(path, centre, radius)
            d = {"type": "ply", "filename": path, "face_normals": False,
                 "flip_normals": False, "to_world": mi.ScalarTransform4f(m.tolist())}
        else:
            raise SceneError(f"shape type {kind!r} is not translated")
        emitter = None
        if "emission" in s:
            emitter = {"type": "area", "radiance": rgb(s["emission"], "emission")}
        d["bsdf"] = bsdf
        if emitter is not None:
            d["emitter"] = emitter
        out[key] = d
    return out


# ---------------------------------------------------------------------------------------------
# Camera, lights, the scene.

def camera_dict(mi, cam, width, height, spp, filt, sampler="independent"):
    pos = [float(x) for x in cam["position"]]
    up = [float(x) for x in cam.get("up", [0, 1, 0])]
    if np.linalg.norm(np.array(up) / np.linalg.norm(up) - [0, 1, 0]) > 1e-4:
        raise SceneError("camera: only up = [0, 1, 0] (as raylab)")
    if "target" in cam:
        if "yaw" in cam or "pitch" in cam:
            raise SceneError("camera: target or yaw/pitch, not both")
        target = [float(x) for x in cam["target"]]
    else:
        yaw = math.radians(float(cam.get("yaw", 0.0)))
        pitch = math.radians(float(cam.get("pitch", 0.0)))
        fwd = [math.sin(yaw) * math.cos(pitch), math.sin(pitch),
               -math.cos(yaw) * math.cos(pitch)]
        target = [p + f for p, f in zip(pos, fwd)]
    d = {
        "type": "perspective",
        "to_world": mi.ScalarTransform4f().look_at(origin=pos, target=target, up=up),
        "fov": float(cam.get("fov", 53.1301)),
        "fov_axis": cam.get("fov_axis", "x"),
        "film": {"type": "hdrfilm", "width": width, "height": height,
                 "rfilter": filt, "pixel_format": "rgb", "component_format": "float32"},
        "sampler": {"type": sampler, "sample_count": spp},
    }
    aperture = float(cam.get("aperture_radius", 0.0))
    if aperture > 0:
        d["type"] = "thinlens"
        d["aperture_radius"] = aperture
        d["focus_distance"] = float(cam.get("focus_distance", 1.0))
    return d


def build_scene_dict(mi, doc, folder, width, height, spp, max_depth, rr_depth, sphere_dir,
                     raylab_frames=True, sampler="independent"):
    """The Mitsuba scene dict; built-in spheres are written as PLY files into sphere_dir."""
    render = doc.get("render", {})
    integrator = render.get("integrator", "path")
    if integrator != "path":
        raise SceneError(f"integrator {integrator!r}: only path is translated")
    filt = render.get("filter", "box")
    filt = {"box": {"type": "box"},
            "gaussian": {"type": "gaussian", "stddev": 0.5}}.get(filt)
    if filt is None:
        raise SceneError("filter: box or gaussian")
    if "camera" not in doc:
        raise SceneError("the scene needs a [camera] (the lab's default camera is not translated)")
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": int(max_depth), "rr_depth": int(rr_depth)},
        "sensor": camera_dict(mi, doc["camera"], width, height, spp, filt, sampler),
    }
    scene.update(shape_dicts(mi, doc, folder, doc.get("materials", {}), sphere_dir,
                             raylab_frames))
    for i, light in enumerate(doc.get("lights", [])):
        kind = light.get("type")
        if kind == "environment":
            scene[f"light_{i:03d}_constant"] = {"type": "constant",
                                                "radiance": rgb(light["radiance"])}
        elif kind == "point":
            if ("intensity" in light) == ("power" in light):
                raise SceneError("a point light needs one of intensity or power")
            intensity = (light["intensity"] if "intensity" in light
                         else [float(p) / (4 * math.pi) for p in light["power"]])
            scene[f"light_{i:03d}_point"] = {"type": "point",
                                             "position": [float(x) for x in light["position"]],
                                             "intensity": rgb(intensity)}
        elif kind == "envmap":
            m = shape_matrix({k: light[k] for k in ("rotate", "to_world") if k in light})
            scene[f"light_{i:03d}_envmap"] = {
                "type": "envmap",
                "filename": os.path.join(folder, light["filename"]),
                "scale": float(light.get("scale", 1.0)),
                "to_world": mi.ScalarTransform4f(m.tolist())}
        elif kind == "directional":
            d = {"type": "directional", "irradiance": rgb(light.get("irradiance", 1.0))}
            if ("direction" in light) == ("to_world" in light):
                raise SceneError("a directional light needs direction or to_world")
            if "direction" in light:
                d["direction"] = [float(x) for x in light["direction"]]
            else:
                d["to_world"] = mi.ScalarTransform4f(light["to_world"])
            scene[f"light_{i:03d}_directional"] = d
        elif kind == "spot":
            d = {"type": "spot", "intensity": rgb(light.get("intensity", 1.0))}
            for key in ("cutoff_angle", "beam_width"):
                if key in light:
                    d[key] = float(light[key])
            if "to_world" in light:
                d["to_world"] = mi.ScalarTransform4f(light["to_world"])
            else:
                origin = np.array(light["position"], dtype=np.float64)
                target = np.array(light["target"], dtype=np.float64)
                axis = (target - origin) / np.linalg.norm(target - origin)
                # Any up not along the axis: the spot is round.
                up = [0.0, 1.0, 0.0] if abs(axis[1]) < 0.9 else [1.0, 0.0, 0.0]
                d["to_world"] = mi.ScalarTransform4f().look_at(
                    origin=origin.tolist(), target=target.tolist(), up=up)
            scene[f"light_{i:03d}_spot"] = d
        else:
            raise SceneError(f"light type {kind!r}")
    return scene


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene", help="raylab scene file (.toml)")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--size", type=int, nargs=2, metavar=("W", "H"),
                    help="film size (default: the file's [render] size)")
    ap.add_argument("--spp", type=int, default=64, help="samples per pixel per pass")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--passes", type=int, default=1,
                    help="independent passes (seeds seed..seed+passes-1), averaged")
    ap.add_argument("--max-depth", type=int, help="default: the file's max_depth (else -1)")
    ap.add_argument("--rr-depth", type=int, default=5)
    ap.add_argument("--sampler", default="independent",
                    choices=["independent", "multijitter", "orthogonal", "stratified", "ldsampler"])
    ap.add_argument("--warmup", action="store_true",
                    help="render once first (another seed), so the timing is of compiled kernels")
    ap.add_argument("--threads", type=int, default=0,
                    help="Dr.Jit worker threads (0 = Dr.Jit default = all cores)")
    ap.add_argument("--out", required=True, help="output: .pfm, .exr or .npy")
    ap.add_argument("--also-npy", action="store_true")
    ap.add_argument("--also-exr", action="store_true")
    ap.add_argument("--also-pfm", action="store_true")
    ap.add_argument("--png", help="also write a tone-mapped sRGB preview here")
    ap.add_argument("--exposure", type=float, default=1.0, help="for --png")
    ap.add_argument("--duff-frames", action="store_true",
                    help="anisotropic materials in the Duff basis of the shading normal (see "
                         "raylab_frame; raylab's frame before it took Mitsuba's dp_du) instead of "
                         "Mitsuba's own mesh tangent frame, which raylab now uses too")
    ap.add_argument("--print-scene", action="store_true", help="print the Mitsuba scene dict")
    args = ap.parse_args()

    dr, mi = load_mitsuba(args.variant, args.threads)
    register_raylab_frame(mi)

    with open(args.scene, "rb") as f:
        doc = tomllib.load(f)
    folder = os.path.dirname(os.path.abspath(args.scene))
    TEXTURE_FOLDER[0] = folder
    _MI.append(mi)
    render = doc.get("render", {})
    width, height = args.size if args.size else render.get("size", [500, 500])
    max_depth = args.max_depth if args.max_depth is not None else render.get("max_depth", -1)

    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="raylab_spheres_") as sphere_dir:
        scene_dict = build_scene_dict(mi, doc, folder, width, height, args.spp, max_depth,
                                      args.rr_depth, sphere_dir, args.duff_frames, args.sampler)
        if args.print_scene:
            print(scene_dict)
        scene = mi.load_dict(scene_dict)
    t_load = time.perf_counter() - t0

    if args.warmup:
        dr.eval(mi.render(scene, spp=args.spp, seed=args.seed + 1000))
        dr.sync_thread()
    render = Render(dr, mi, scene, args.spp, args.seed, args.passes)
    img = render.image
    assert img.shape == (height, width, 3), img.shape

    os.makedirs(os.path.dirname(os.path.abspath(args.out)) or ".", exist_ok=True)
    stem, ext = os.path.splitext(args.out)
    writers = {
        ".pfm": lambda p: write_pfm(p, img),
        ".exr": lambda p: mi.Bitmap(img, pixel_format=mi.Bitmap.PixelFormat.RGB).write(p),
        ".npy": lambda p: np.save(p, img),
    }
    if ext.lower() not in writers:
        raise SystemExit(f"--out: .pfm, .exr or .npy, not {ext!r}")
    writers[ext.lower()](args.out)
    written = [args.out]
    for flag, e in ((args.also_npy, ".npy"), (args.also_exr, ".exr"), (args.also_pfm, ".pfm")):
        if flag and e != ext.lower():
            writers[e](stem + e)
            written.append(stem + e)
    if args.png:
        x = np.clip(img.astype(np.float64) * args.exposure, 0.0, 1.0)
        x = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
        png = np.ascontiguousarray(np.round(x * 255.0).astype(np.uint8))
        mi.Bitmap(png, pixel_format=mi.Bitmap.PixelFormat.RGB).write(args.png)
        written.append(args.png)

    total_spp = args.spp * args.passes
    print(f"mitsuba {mi.__version__} drjit {dr.__version__} variant {args.variant} "
          f"sampler {args.sampler}")
    print(f"scene {args.scene}")
    print("anisotropic frames: " + ("the Duff basis of the shading normal" if args.duff_frames
                                     else "Mitsuba's dp_du (mesh: first triangle edge), as raylab's"))
    print(f"size {width}x{height} spp {total_spp} ({args.passes} pass(es) x {args.spp}) "
          f"seed {args.seed} max_depth {max_depth} rr_depth {args.rr_depth}")
    render.report(t_load, T_PROCESS0)
    for p in written:
        print(f"wrote {p}")


if __name__ == "__main__":
    try:
        sys.exit(main())
    except SceneError as e:
        sys.exit(f"materials_reference.py: {e}")
