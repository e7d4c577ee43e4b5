#!/usr/bin/env python3
"""Camera-convention check for Mitsuba 3's mi.cornell_box() (512x512 film).

For a few pixel centres, asks Mitsuba for the camera ray (sensor.sample_ray at
film position (px/W, py/H), no jitter) and its first hit (scene.ray_intersect),
and prints ray origin / direction, hit point, hit shape and the hit's geometric
normal.  Also recomputes the direction with the closed form that
shared/scenes/mitsuba-cbox/cbox.json -> camera.ray_generation states, and
probes the back side of the area light (emission and BSDF seen from above).

Usage:  python3 tools/mitsuba/cbox_camera_check.py [--variant scalar_rgb]
        [--size 512] [--px X,Y ...]
"""

import argparse
import math

import numpy as np


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--variant", default="scalar_rgb")
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--px", nargs="*",
                    default=["0.5,0.5", "255.5,255.5", "100.5,400.5"],
                    help="film positions in pixels, x,y (x right, y down)")
    args = ap.parse_args()

    import mitsuba as mi
    mi.set_variant(args.variant)

    d = mi.cornell_box()
    d["sensor"]["film"] = {"type": "hdrfilm", "width": args.size,
                           "height": args.size, "rfilter": {"type": "box"},
                           "pixel_format": "rgb"}
    # optimize=False: Mitsuba's loader otherwise merges all shapes sharing the
    # 'white' BSDF (floor, ceiling, back, both boxes) into one unnamed mesh,
    # so si.shape.id() would be ''.  Geometry is identical either way.
    scene = mi.load_dict(d, optimize=False)
    scene_opt = mi.load_dict(d)
    sensor = scene.sensors()[0]
    W = H = args.size

    # Closed form from cbox.json
    fov = 39.3077
    t = math.tan(math.radians(fov) / 2)
    R = np.array(d["sensor"]["to_world"].matrix, dtype=np.float64)[:3, :3]

    print(f"mitsuba {mi.__version__} variant {args.variant} film {W}x{H}")
    for s in args.px:
        px, py = map(float, s.split(","))
        u, v = px / W, py / H
        ray, w = sensor.sample_ray(0.0, 0.5, mi.Point2f(u, v), mi.Point2f(0.5, 0.5))
        si = scene.ray_intersect(ray)
        o = np.array(ray.o, dtype=np.float64).ravel()
        dd = np.array(ray.d, dtype=np.float64).ravel()
        dl = np.array([(1 - 2 * u) * t, (1 - 2 * v) * t, 1.0])
        dj = R @ (dl / np.linalg.norm(dl))
        print(f"pixel ({px}, {py})  u,v = ({u:.8f}, {v:.8f})")
        print(f"  origin    {o.tolist()}")
        print(f"  dir       {dd.tolist()}")
        print(f"  dir(json) {dj.tolist()}  max|diff| {np.abs(dj - dd).max():.3g}")
        if bool(np.array(si.is_valid()).ravel()[0]):
            p = np.array(si.p, dtype=np.float64).ravel()
            n = np.array(si.n, dtype=np.float64).ravel()
            print(f"  hit t={float(np.array(si.t).ravel()[0]):.7f} p={p.tolist()}")
            print(f"  shape {si.shape.id()}  geometric normal {n.tolist()}")
            si2 = scene_opt.ray_intersect(ray)
            p2 = np.array(si2.p, dtype=np.float64).ravel()
            print(f"  (optimized/merged scene: shape id {si2.shape.id()!r}, "
                  f"max|p diff| {np.abs(p2 - p).max():.3g})")
        else:
            print("  no hit")

    # Back side of the light: a ray from between light (y=0.99) and ceiling
    # (y=1) pointing down hits the light quad from behind.
    for name, oy, dy in (("light from below (front)", 0.5, 1.0),
                         ("light from above (back)", 0.995, -1.0)):
        ray = mi.Ray3f(mi.Point3f(0.0, oy, 0.0), mi.Vector3f(0.0, dy, 0.0))
        si = scene.ray_intersect(ray)
        em = si.emitter(scene)
        Le = np.array(em.eval(si), dtype=np.float64).ravel() if em is not None else None
        bsdf = si.bsdf()
        ctx = mi.BSDFContext()
        # reflect toward the side the ray came from
        wo = mi.Vector3f(0.0, 0.0, 1.0) if float(np.array(si.wi.z).ravel()[0]) > 0 \
            else mi.Vector3f(0.0, 0.0, -1.0)
        f = np.array(bsdf.eval(ctx, si, wo), dtype=np.float64).ravel()
        print(f"{name}: shape {si.shape.id()} p={np.array(si.p).ravel().tolist()} "
              f"cos(wi)={float(np.array(si.wi.z).ravel()[0]):+.3f} "
              f"Le={None if Le is None else Le.tolist()} f*cos(normal dir)={f.tolist()}")


if __name__ == "__main__":
    main()
