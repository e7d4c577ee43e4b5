"""glTF 2.0 meshes for the Mitsuba translator (materials_reference.py): what raylab's glTF loader
reads of a file's default scene, as numpy arrays.

Reads .gltf (external buffers or base64 data URIs) and .glb; the default scene (or scene 0), its
nodes' transforms (`matrix`, or translation x rotation x scale), composed down the hierarchy;
each mesh's triangle primitives: POSITION, NORMAL, TEXCOORD_0 and the indices. Each mesh is
returned once with the world matrices of the nodes that place it, as instances.

Texture coordinates are written as the file has them. A scene file's image texture reads a
mesh's coordinates as OBJ's, v up from the bottom row (docs/scene-format.md), whatever file the
mesh came from; Mitsuba's OBJ loader flips v and its bitmap reads v down from the top row, so
Mitsuba reads an OBJ's vt the same way. Written unchanged, the coordinates reach both renderers
alike (measured: with vt = 1 - v the logo came out upside down in Mitsuba against raylab's
render). A glTF file's own textures, which read v down, are not translated.
"""

import base64
import json
import os
import struct

import numpy as np

COMPONENTS = {5120: "i1", 5121: "u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
WIDTHS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


class GltfError(Exception):
    pass


def _load(path):
    with open(path, "rb") as f:
        data = f.read()
    if data[:4] == b"glTF":
        length = struct.unpack_from("<I", data, 12)[0]
        doc = json.loads(data[20:20 + length])
        rest = data[20 + length:]
        binary = rest[8:8 + struct.unpack_from("<I", rest, 0)[0]] if len(rest) >= 8 else None
        return doc, binary
    return json.loads(data), None


def _buffers(doc, folder, binary):
    out = []
    for i, b in enumerate(doc.get("buffers", [])):
        uri = b.get("uri")
        if uri is None:
            if binary is None:
                raise GltfError(f"buffer {i}: no uri and no GLB chunk")
            out.append(binary)
        elif uri.startswith("data:"):
            out.append(base64.b64decode(uri.split(",", 1)[1]))
        else:
            with open(os.path.join(folder, uri), "rb") as f:
                out.append(f.read())
    return out


def _accessor(doc, buffers, index):
    a = doc["accessors"][index]
    if "bufferView" not in a or "sparse" in a:
        raise GltfError(f"accessor {index}: without a bufferView, or sparse: not translated")
    view = doc["bufferViews"][a["bufferView"]]
    dtype = np.dtype(COMPONENTS[a["componentType"]])
    width = WIDTHS[a["type"]]
    start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
    stride = view.get("byteStride", dtype.itemsize * width)
    raw = buffers[view["buffer"]]
    rows = [np.frombuffer(raw, dtype, width, start + k * stride) for k in range(a["count"])]
    out = np.array(rows).reshape(a["count"], width)
    if a.get("normalized") and dtype.kind in "iu":
        # glTF's normalized integers: unsigned to [0, 1], signed to [-1, 1].
        out = np.maximum(out.astype(np.float64) / np.iinfo(dtype).max, -1.0)
    return out


def _quaternion(q):
    x, y, z, w = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def _local(node):
    if "matrix" in node:
        return np.array(node["matrix"], dtype=np.float64).reshape(4, 4).T  # column-major
    m = np.eye(4)
    m[:3, :3] = _quaternion(node.get("rotation", [0, 0, 0, 1])) @ np.diag(
        node.get("scale", [1, 1, 1]))
    m[:3, 3] = node.get("translation", [0, 0, 0])
    return m


def read(path):
    """[(triangles, instances)] per mesh: triangles a dict of positions (N, 3), normals (N, 3)
    or None, uvs (N, 2) or None and indices (M, 3); instances the world matrices (4x4)."""
    doc, binary = _load(path)
    buffers = _buffers(doc, os.path.dirname(path), binary)
    scene = doc["scenes"][doc.get("scene", 0)]
    placed = {}

    def visit(index, parent):
        node = doc["nodes"][index]
        world = parent @ _local(node)
        if "mesh" in node:
            placed.setdefault(node["mesh"], []).append(world)
        for child in node.get("children", []):
            visit(child, world)

    for root in scene["nodes"]:
        visit(root, np.eye(4))
    meshes = []
    for mesh_index, worlds in sorted(placed.items()):
        for p in doc["meshes"][mesh_index]["primitives"]:
            if p.get("mode", 4) != 4:
                raise GltfError(f"mesh {mesh_index}: only triangle primitives")
            attr = p["attributes"]
            positions = _accessor(doc, buffers, attr["POSITION"]).astype(np.float64)
            if "indices" in p:
                indices = _accessor(doc, buffers, p["indices"]).reshape(-1, 3).astype(np.int64)
            else:
                indices = np.arange(len(positions)).reshape(-1, 3)
            normals = (_accessor(doc, buffers, attr["NORMAL"]).astype(np.float64)
                       if "NORMAL" in attr else None)
            uvs = (_accessor(doc, buffers, attr["TEXCOORD_0"]).astype(np.float64)
                   if "TEXCOORD_0" in attr else None)
            meshes.append(({"positions": positions, "normals": normals, "uvs": uvs,
                            "indices": indices}, worlds))
    return meshes


def write_obj(path, triangles):
    """The triangles as an OBJ (v, vt, vn, f), for Mitsuba's OBJ loader."""
    pos, nrm, uv, idx = (triangles[k] for k in ("positions", "normals", "uvs", "indices"))
    with open(path, "w") as f:
        for p in pos:
            f.write(f"v {float(p[0])!r} {float(p[1])!r} {float(p[2])!r}\n")
        if uv is not None:
            for t in uv:
                f.write(f"vt {float(t[0])!r} {float(t[1])!r}\n")
        if nrm is not None:
            for n in nrm:
                f.write(f"vn {float(n[0])!r} {float(n[1])!r} {float(n[2])!r}\n")
        for a, b, c in idx + 1:
            if uv is not None and nrm is not None:
                f.write(f"f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}\n")
            elif uv is not None:
                f.write(f"f {a}/{a} {b}/{b} {c}/{c}\n")
            elif nrm is not None:
                f.write(f"f {a}//{a} {b}//{b} {c}//{c}\n")
            else:
                f.write(f"f {a} {b} {c}\n")
