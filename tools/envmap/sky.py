#!/usr/bin/env python3
"""A procedural sky with a small bright sun, written as a Radiance .hdr (run-length encoded RGBE),
in Mitsuba 3's envmap convention (which raylab's follows): row 0 is straight up (+y), the left
edge looks along -z, a quarter of the way across along +x; texel (x, y) is the direction at
u = (x + 1/2)/w, v = y/(h - 1), where the bilinear lookup of both renderers puts it.

The sky: a gradient from a pale horizon to a blue zenith above the horizon, a dim brown ground
below, and a sun disc of constant radiance (--sun-radiance) and angular radius --sun-radius
(degrees) at --sun-elevation / --sun-azimuth (degrees; azimuth 0 looks along -z, 90 along +x).
Each texel is the mean of --samples x --samples points (8 x 8) spread over the solid angle
around its direction, so the sun's edge is anti-aliased.

Made for crates/raylab/tests/data/mitsuba-envmap/sky.hdr:
  python3 tools/envmap/sky.py crates/raylab/tests/data/mitsuba-envmap/sky.hdr
(defaults: 128 x 65, sun at elevation 35, azimuth 60, radius 2.5 degrees, radiance 800).
An 8k x 4k map for the load figures in BENCHMARKS.md (about 130 MB, not committed):
  python3 tools/envmap/sky.py /tmp/sky-8k.hdr --width 8192 --height 4096 --samples 1 \
      --sun-radius 0.27 --sun-radiance 50000
Needs numpy.
"""
import argparse
import math

import numpy as np


def direction(u, v):
    theta, phi = v * math.pi, u * 2.0 * math.pi
    return np.stack([np.sin(phi) * np.sin(theta), np.cos(theta), -np.cos(phi) * np.sin(theta)], -1)


def sky(d, sun, sun_cos, sun_radiance):
    up = d[..., 1]
    horizon = np.array([0.9, 0.85, 0.8])
    zenith = np.array([0.15, 0.35, 0.9])
    ground = np.array([0.2, 0.16, 0.12])
    t = np.sqrt(np.clip(up, 0.0, 1.0))[..., None]
    colour = np.where(up[..., None] >= 0.0, horizon * (1.0 - t) + zenith * t, ground)
    in_sun = (d @ sun) >= sun_cos
    return np.where(in_sun[..., None], sun_radiance, colour)


def write_hdr(path, image):
    """Image (h, w, 3) float, row 0 on top, as new-style run-length RGBE scanlines (literal
    runs only)."""
    h, w, _ = image.shape
    assert 8 <= w < 0x8000
    m = image.max(axis=-1)
    mantissa, exponent = np.frexp(m)
    scale = np.where(m > 1e-32, mantissa * 256.0 / np.where(m > 0, m, 1.0), 0.0)
    rgbe = np.zeros((h, w, 4), np.uint8)
    rgbe[..., :3] = np.clip(np.floor(image * scale[..., None]), 0, 255).astype(np.uint8)
    rgbe[..., 3] = np.where(m > 1e-32, exponent + 128, 0).astype(np.uint8)
    out = bytearray(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n")
    out += f"-Y {h} +X {w}\n".encode()
    for row in rgbe:
        out += bytes([2, 2, w >> 8, w & 255])
        for channel in range(4):
            data = row[:, channel].tobytes()
            for start in range(0, w, 128):
                chunk = data[start:start + 128]
                out += bytes([len(chunk)]) + chunk
    with open(path, "wb") as f:
        f.write(out)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("out")
    p.add_argument("--width", type=int, default=128)
    p.add_argument("--height", type=int, default=65)
    p.add_argument("--sun-elevation", type=float, default=35.0)
    p.add_argument("--sun-azimuth", type=float, default=60.0)
    p.add_argument("--sun-radius", type=float, default=2.5)
    p.add_argument("--sun-radiance", type=float, default=800.0)
    p.add_argument("--samples", type=int, default=8, help="points per texel across and down")
    a = p.parse_args()
    w, h = a.width, a.height
    el, az = math.radians(a.sun_elevation), math.radians(a.sun_azimuth)
    sun = np.array([math.sin(az) * math.cos(el), math.sin(el), -math.cos(az) * math.cos(el)])
    sun_cos = math.cos(math.radians(a.sun_radius))
    n = a.samples
    total = np.zeros((h, w, 3))
    xs, ys = np.meshgrid(np.arange(w), np.arange(h))
    for j in range(n):
        for i in range(n):
            # Points within the texel's cell around its grid point (u over one texel, v over
            # one row spacing, clamped at the poles).
            u = (xs + 0.5 + (i + 0.5) / n - 0.5) / w
            v = np.clip((ys + (j + 0.5) / n - 0.5) / (h - 1), 0.0, 1.0)
            total += sky(direction(u, v), sun, sun_cos, a.sun_radiance)
    write_hdr(a.out, total / (n * n))


if __name__ == "__main__":
    main()
