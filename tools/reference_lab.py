#!/usr/bin/env python3
"""Independent float64 reference renderer for raylab's lab frame.

What this is
------------
An independent reference implementation, in Python 3 + numpy (float64), of the
classic KTH DH2323 Lab 2 ray-tracing frame: the 30-triangle Cornell-box
"TestModel" seen through a pinhole camera, lit by one point light with hard
shadows and a constant ambient term.  Its output is the golden image for the
golden-image regression tests of raylab's lab frame.

It deliberately shares no code with the Rust renderer (nothing under
crates/ was read or ported while writing it); it was written from the textual
specification only, so that an agreement between the two is evidence that
both are right rather than that both copy the same mistake.

Model (summary of the specification)
------------------------------------
* Scene: Cornell units with L = 555, every vertex mapped to [-1, 1]^3 by
  x' = 1 - 2x/L, y' = 1 - 2y/L, z' = 2z/L - 1 (y points down).  Triangle
  normal n = normalize((v2 - v0) x (v1 - v0)), computed after the transform;
  walls face into the room, blocks face out (checked by asserts at import).
* Camera: pinhole at (0, 0, -3), x right, y down, z forward, optional yaw
  (d = R(yaw) . local).  Pixel (x, y) casts the direction
  (x + 0.5 - W/2, y + 0.5 - H/2, f), f = W unless --focal is given.
* Closest hit over all triangles (both faces count), t > 0, Moller-Trumbore;
  a miss is black.
* Light at (0, -0.5, -0.7), power P = 14 per channel.  At hit p with normal n:
  r = |light - p|, D = P max(r^ . n, 0) / (4 pi r^2); D = 0 when a shadow ray
  (origin offset 1e-9 along the normal toward the light's side) hits any
  triangle with 0 < t < 1 (t measured along light - origin).
  Colour R = rho * (D + N), N = 0.5.
* Output: clamp to [0, 1], floor(v * 255 + 0.5), no gamma, 8-bit RGB PNG
  written with the standard library only (zlib + struct).

Stages (--stage): flat (rho of the closest triangle), direct (D, no shadows,
grey), reflected (rho * D, no shadows), shadows (rho * D with shadows),
ambient (default; rho * (D + N) with shadows).

How to run
----------
    python3 tools/reference_lab.py --size 100x100 [--focal F] [--yaw DEG] \
        [--stage flat|direct|reflected|shadows|ambient] -o out.png
    python3 tools/reference_lab.py --self-test

Requires numpy.  A 500x500 frame takes well under a few seconds.
"""

import argparse
import math
import struct
import sys
import time
import zlib

import numpy as np

# --------------------------------------------------------------------------
# Scene
# --------------------------------------------------------------------------

L = 555.0

RED = (0.75, 0.15, 0.15)
YELLOW = (0.75, 0.75, 0.15)
GREEN = (0.15, 0.75, 0.15)
CYAN = (0.15, 0.75, 0.75)
BLUE = (0.15, 0.15, 0.75)
PURPLE = (0.75, 0.15, 0.75)
WHITE = (0.75, 0.75, 0.75)

LIGHT_POS = np.array([0.0, -0.5, -0.7])
LIGHT_POWER = 14.0
AMBIENT = 0.5
CAMERA_POS = np.array([0.0, 0.0, -3.0])
SHADOW_OFFSET = 1e-9

STAGES = ("flat", "direct", "reflected", "shadows", "ambient")


def _to_unit(p):
    """Cornell units -> [-1, 1]^3 with y pointing down."""
    x, y, z = p
    return np.array([1.0 - 2.0 * x / L, 1.0 - 2.0 * y / L, 2.0 * z / L - 1.0])


def _block(base, height, colour, group):
    """Ten triangles of a box with base corners A, B, C, D at y = 0."""
    a, b, c, d = base
    A = (a[0], 0.0, a[1])
    B = (b[0], 0.0, b[1])
    C = (c[0], 0.0, c[1])
    D = (d[0], 0.0, d[1])
    E = (a[0], height, a[1])
    F = (b[0], height, b[1])
    G = (c[0], height, c[1])
    H = (d[0], height, d[1])
    tris = [(E, B, A), (E, F, B), (F, D, B), (F, H, D), (H, C, D),
            (H, G, C), (G, E, C), (E, A, C), (G, F, E), (G, H, F)]
    return [(t, colour, group) for t in tris]


def build_scene():
    """Return (v0, v1, v2, normals, colours, groups) as float64 arrays."""
    A = (L, 0.0, 0.0)
    B = (0.0, 0.0, 0.0)
    C = (L, 0.0, L)
    D = (0.0, 0.0, L)
    E = (L, L, 0.0)
    F = (0.0, L, 0.0)
    G = (L, L, L)
    H = (0.0, L, L)
    tris = [
        ((C, B, A), GREEN, "room"), ((C, D, B), GREEN, "room"),      # floor
        ((A, E, C), PURPLE, "room"), ((C, E, G), PURPLE, "room"),    # left wall
        ((F, B, D), YELLOW, "room"), ((H, F, D), YELLOW, "room"),    # right wall
        ((E, F, G), CYAN, "room"), ((F, H, G), CYAN, "room"),        # ceiling
        ((G, D, C), WHITE, "room"), ((G, H, D), WHITE, "room"),      # back wall
    ]
    tris += _block([(290, 114), (130, 65), (240, 272), (82, 225)], 165.0,
                   RED, "short")
    tris += _block([(423, 247), (265, 296), (472, 406), (314, 456)], 330.0,
                   BLUE, "tall")
    assert len(tris) == 30

    v0 = np.array([_to_unit(t[0][0]) for t in tris])
    v1 = np.array([_to_unit(t[0][1]) for t in tris])
    v2 = np.array([_to_unit(t[0][2]) for t in tris])
    n = np.cross(v2 - v0, v1 - v0)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    colours = np.array([t[1] for t in tris], dtype=np.float64)
    groups = [t[2] for t in tris]
    return v0, v1, v2, n, colours, groups


V0, V1, V2, NORMALS, COLOURS, GROUPS = build_scene()


def _check_orientation():
    """Walls face into the room, blocks face out; walls are axis aligned."""
    centroids = (V0 + V1 + V2) / 3.0
    for group in ("short", "tall"):
        idx = [i for i, g in enumerate(GROUPS) if g == group]
        allv = np.concatenate([V0[idx], V1[idx], V2[idx]])
        centre = 0.5 * (allv.min(axis=0) + allv.max(axis=0))
        for i in idx:
            assert np.dot(NORMALS[i], centroids[i] - centre) > 0.0, \
                "block triangle %d does not face out" % i
    for i, g in enumerate(GROUPS):
        if g == "room":
            assert np.dot(NORMALS[i], -centroids[i]) > 0.0, \
                "wall triangle %d does not face into the room" % i
    expected = {0: (0, -1, 0), 1: (0, -1, 0),      # floor faces up (-y)
                2: (1, 0, 0), 3: (1, 0, 0),        # left wall (x' = -1) faces +x
                4: (-1, 0, 0), 5: (-1, 0, 0),      # right wall (x' = +1) faces -x
                6: (0, 1, 0), 7: (0, 1, 0),        # ceiling faces down (+y)
                8: (0, 0, -1), 9: (0, 0, -1)}      # back wall faces the camera
    for i, e in expected.items():
        assert np.allclose(NORMALS[i], e, atol=1e-12), (i, NORMALS[i], e)
    # Block tops face up, block triangles with y-extent are vertical.
    for i, g in enumerate(GROUPS):
        if g != "room" and i % 10 in (8, 9):
            assert np.allclose(NORMALS[i], (0, -1, 0), atol=1e-12)


_check_orientation()

# --------------------------------------------------------------------------
# Intersection
# --------------------------------------------------------------------------


def _dot(a, b):
    return np.einsum("ij,ij->i", a, b)


def intersect(orig, dirs, t_max=None, any_hit=False):
    """Closest hit of rays orig + t*dirs, t > 0 (and t < t_max if given).

    orig, dirs: (N, 3) float64.  Moller-Trumbore, both faces count.
    Returns (t, idx): t = inf and idx = -1 on a miss.  With any_hit=True only
    a boolean "blocked" array is returned.
    """
    n = dirs.shape[0]
    best_t = np.full(n, np.inf)
    best_i = np.full(n, -1, dtype=np.int64)
    blocked = np.zeros(n, dtype=bool)
    for i in range(V0.shape[0]):
        e1 = V1[i] - V0[i]
        e2 = V2[i] - V0[i]
        pvec = np.cross(dirs, e2)
        det = pvec @ e1
        ok = np.abs(det) > 1e-300
        inv = np.zeros(n)
        inv[ok] = 1.0 / det[ok]
        tvec = orig - V0[i]
        u = _dot(tvec, pvec) * inv
        qvec = np.cross(tvec, e1)
        v = _dot(dirs, qvec) * inv
        t = (qvec @ e2) * inv
        hit = ok & (u >= 0.0) & (v >= 0.0) & (u + v <= 1.0) & (t > 0.0)
        if t_max is not None:
            hit &= t < t_max
        if any_hit:
            blocked |= hit
            continue
        closer = hit & (t < best_t)
        best_t[closer] = t[closer]
        best_i[closer] = i
    if any_hit:
        return blocked
    return best_t, best_i


# --------------------------------------------------------------------------
# Shading
# --------------------------------------------------------------------------


def shade(orig, dirs, stage="ambient"):
    """Trace rays and return a dict with the unclamped colour and details."""
    assert stage in STAGES, stage
    n_rays = dirs.shape[0]
    t, idx = intersect(orig, dirs)
    hit = idx >= 0
    out = {"t": t, "idx": idx, "hit": hit}
    colour = np.zeros((n_rays, 3))
    rho = np.zeros((n_rays, 3))
    rho[hit] = COLOURS[idx[hit]]
    out["rho"] = rho
    if stage == "flat":
        colour[hit] = rho[hit]
        out["colour"] = colour
        return out

    p = orig[hit] + t[hit, None] * dirs[hit]
    nrm = NORMALS[idx[hit]]
    to_light = LIGHT_POS - p
    r = np.linalg.norm(to_light, axis=1)
    rhat = to_light / r[:, None]
    cos = np.maximum(_dot(rhat, nrm), 0.0)
    D = LIGHT_POWER * cos / (4.0 * math.pi * r * r)

    if stage in ("shadows", "ambient"):
        side = np.where(_dot(nrm, to_light) >= 0.0, 1.0, -1.0)
        s_orig = p + (SHADOW_OFFSET * side)[:, None] * nrm
        s_dir = LIGHT_POS - s_orig          # light at t = 1
        blocked = intersect(s_orig, s_dir, t_max=1.0, any_hit=True)
        D = np.where(blocked, 0.0, D)
        out["blocked"] = np.zeros(n_rays, dtype=bool)
        out["blocked"][hit] = blocked

    full = lambda a: _scatter(a, hit, n_rays)
    out["p"] = full(p)
    out["r"] = full(r)
    out["D"] = full(D)

    Dv = D[:, None] * np.ones(3)
    if stage == "direct":
        colour[hit] = Dv
    elif stage in ("reflected", "shadows"):
        colour[hit] = rho[hit] * Dv
    else:  # ambient
        colour[hit] = rho[hit] * (Dv + AMBIENT)
    out["colour"] = colour
    return out


def _scatter(a, mask, n):
    shape = (n,) + a.shape[1:]
    full = np.full(shape, np.nan)
    full[mask] = a
    return full


def yaw_matrix(yaw_deg):
    y = math.radians(yaw_deg)
    c, s = math.cos(y), math.sin(y)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def camera_rays(width, height, focal, yaw_deg=0.0):
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float64)
    local = np.stack([xs.ravel() + 0.5 - width / 2.0,
                      ys.ravel() + 0.5 - height / 2.0,
                      np.full(width * height, float(focal))], axis=1)
    dirs = local @ yaw_matrix(yaw_deg).T
    orig = np.broadcast_to(CAMERA_POS, dirs.shape).copy()
    return orig, dirs


def render(width, height, focal=None, stage="ambient", yaw_deg=0.0):
    """Return an (H, W, 3) uint8 image."""
    if focal is None:
        focal = float(width)
    orig, dirs = camera_rays(width, height, focal, yaw_deg)
    colour = shade(orig, dirs, stage)["colour"]
    return to_u8(colour).reshape(height, width, 3)


def to_u8(colour):
    c = np.clip(colour, 0.0, 1.0)
    return np.floor(c * 255.0 + 0.5).astype(np.uint8)


# --------------------------------------------------------------------------
# PNG (standard library only)
# --------------------------------------------------------------------------


def _chunk(kind, data):
    body = kind + data
    return struct.pack(">I", len(data)) + body + \
        struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)


def png_bytes(img):
    img = np.ascontiguousarray(img, dtype=np.uint8)
    height, width, ch = img.shape
    assert ch == 3
    raw = b"".join(b"\x00" + img[y].tobytes() for y in range(height))
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", ihdr) +
            _chunk(b"IDAT", zlib.compress(raw, 9)) + _chunk(b"IEND", b""))


def write_png(path, img):
    with open(path, "wb") as f:
        f.write(png_bytes(img))


def read_png_rgb8(data):
    """Minimal decoder for the files written above (filter 0 only)."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, width, height = 8, b"", None, None
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos:pos + 4])
        kind = data[pos + 4:pos + 8]
        body = data[pos + 8:pos + 8 + length]
        (crc,) = struct.unpack(">I", data[pos + 8 + length:pos + 12 + length])
        assert crc == zlib.crc32(kind + body) & 0xFFFFFFFF
        if kind == b"IHDR":
            width, height, depth, ctype, _, _, _ = struct.unpack(">IIBBBBB", body)
            assert (depth, ctype) == (8, 2)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw = zlib.decompress(idat)
    stride = 1 + 3 * width
    rows = []
    for y in range(height):
        row = raw[y * stride:(y + 1) * stride]
        assert row[0] == 0
        rows.append(np.frombuffer(row[1:], dtype=np.uint8))
    return np.stack(rows).reshape(height, width, 3)


# --------------------------------------------------------------------------
# Self-test
# --------------------------------------------------------------------------


def _ray_to(target):
    target = np.asarray(target, dtype=np.float64)
    return CAMERA_POS[None, :].copy(), (target - CAMERA_POS)[None, :]


def self_test():
    ok = []

    def check(cond, msg):
        assert cond, msg
        ok.append(msg)
        print("ok  " + msg)

    # Orientation (already asserted at import; repeated for the log).
    _check_orientation()
    check(True, "30 triangles; walls face into the room, blocks face out")

    # Floor point straight below the light.
    o, d = _ray_to((0.0, 1.0, -0.7))
    s = shade(o, d, "ambient")
    idx = int(s["idx"][0])
    check(idx in (0, 1), "floor ray hits the floor (triangle %d)" % idx)
    check(np.allclose(s["p"][0], (0.0, 1.0, -0.7), atol=1e-12),
          "floor hit point = %s" % np.array2string(s["p"][0], precision=15))
    check(abs(s["r"][0] - 1.5) < 1e-12, "floor r = %.15f" % s["r"][0])
    check(not s["blocked"][0], "floor point is lit (not in shadow)")
    g_exp = 0.75 * (14.0 / (4.0 * math.pi * 2.25) + 0.5)
    g = s["colour"][0, 1]
    check(abs(g - g_exp) < 1e-12 and abs(g - 0.7464) < 5e-5,
          "floor green = %.12f (expected %.12f ~ 0.7464)" % (g, g_exp))
    check(np.allclose(s["colour"][0],
                      np.array(GREEN) * (14.0 / (4 * math.pi * 2.25) + 0.5)),
          "floor colour = %s" % np.array2string(s["colour"][0], precision=6))

    # Ceiling point straight above the light.
    o, d = _ray_to((0.0, -1.0, -0.7))
    s = shade(o, d, "ambient")
    idx = int(s["idx"][0])
    check(idx in (6, 7), "ceiling ray hits the ceiling (triangle %d)" % idx)
    check(abs(s["r"][0] - 0.5) < 1e-12, "ceiling r = %.15f" % s["r"][0])
    r_exp = 0.15 * (14.0 / math.pi + 0.5)
    c = s["colour"][0]
    check(abs(c[0] - r_exp) < 1e-12 and abs(c[0] - 0.743) < 5e-4,
          "ceiling red = %.12f (expected %.12f ~ 0.743)" % (c[0], r_exp))
    check(c[1] > 1.0 and c[2] > 1.0,
          "ceiling green = %.6f, blue = %.6f, both > 1 before clamping"
          % (c[1], c[2]))
    check(tuple(to_u8(c[None])[0]) == (190, 255, 255),
          "ceiling 8-bit = %s" % (tuple(int(x) for x in to_u8(c[None])[0]),))

    # Stage consistency at the floor point.
    o, d = _ray_to((0.0, 1.0, -0.7))
    D_exp = 14.0 / (4.0 * math.pi * 2.25)
    sf = shade(o, d, "flat")["colour"][0]
    check(np.allclose(sf, GREEN), "flat stage at floor = rho")
    sd = shade(o, d, "direct")["colour"][0]
    check(np.allclose(sd, D_exp), "direct stage at floor = D = %.6f" % D_exp)
    sr = shade(o, d, "reflected")["colour"][0]
    check(np.allclose(sr, np.array(GREEN) * D_exp),
          "reflected stage at floor = rho*D")

    # A ray looking away from the room misses -> black.
    s = shade(CAMERA_POS[None], np.array([[0.0, 0.0, -1.0]]), "ambient")
    check(s["idx"][0] == -1 and np.all(s["colour"][0] == 0.0),
          "ray looking backwards misses -> black")

    # The floor point where the line from the light through the centre of the
    # short block's top meets the floor must be in the block's shadow.
    short_top = np.array([_to_unit(((290 + 130 + 240 + 82) / 4.0, 165.0,
                                    (114 + 65 + 272 + 225) / 4.0))])[0]
    dirl = short_top - LIGHT_POS
    tf = (1.0 - LIGHT_POS[1]) / dirl[1]        # where it meets the floor y'=1
    floor_pt = LIGHT_POS + tf * dirl
    # Shadow test from that floor point directly (not via the camera).
    o = np.array([floor_pt + np.array([0.0, -1e-9, 0.0])])
    blocked = intersect(o, LIGHT_POS - o, t_max=1.0, any_hit=True)[0]
    check(bool(blocked), "floor point %s is shadowed by the short block"
          % np.array2string(floor_pt, precision=4))

    # PNG round trip.
    img = render(40, 30, stage="ambient")
    back = read_png_rgb8(png_bytes(img))
    check(back.shape == (30, 40, 3) and np.array_equal(back, img),
          "PNG round trip (40x30) is lossless")

    # Yaw 0 equals the default; yaw rotates correctly.
    check(np.allclose(yaw_matrix(90.0) @ np.array([0.0, 0.0, 1.0]),
                      [1.0, 0.0, 0.0]), "R(90 deg) maps +z to +x")

    print("self-test passed (%d checks)" % len(ok))


# --------------------------------------------------------------------------
# CLI
# --------------------------------------------------------------------------


def _parse_size(text):
    try:
        w, h = text.lower().split("x")
        w, h = int(w), int(h)
    except ValueError:
        raise argparse.ArgumentTypeError("size must be WxH, e.g. 100x100")
    if w <= 0 or h <= 0:
        raise argparse.ArgumentTypeError("size must be positive")
    return w, h


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--size", type=_parse_size, default=(100, 100),
                    help="image size WxH (default 100x100)")
    ap.add_argument("--focal", type=float, default=None,
                    help="focal length in pixels (default: image width)")
    ap.add_argument("--yaw", type=float, default=0.0,
                    help="camera yaw in degrees (default 0)")
    ap.add_argument("--stage", choices=STAGES, default="ambient")
    ap.add_argument("-o", "--output", help="output PNG path")
    ap.add_argument("--self-test", action="store_true",
                    help="run known-answer checks and exit")
    args = ap.parse_args(argv)

    if args.self_test:
        self_test()
        return 0
    if not args.output:
        ap.error("-o/--output is required unless --self-test is given")
    w, h = args.size
    t0 = time.perf_counter()
    img = render(w, h, args.focal, args.stage, args.yaw)
    t1 = time.perf_counter()
    write_png(args.output, img)
    t2 = time.perf_counter()
    print("wrote %s (%dx%d, stage %s, focal %g, yaw %g): render %.3f s, "
          "png %.3f s" % (args.output, w, h, args.stage,
                          args.focal if args.focal is not None else w,
                          args.yaw, t1 - t0, t2 - t1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
