#!/usr/bin/env python3
"""Reference renders of Mitsuba 3's built-in Cornell box (mi.cornell_box()).

Renders the scene that shared/scenes/mitsuba-cbox/ exports (see its README.md
and cbox.json) with Mitsuba itself, so that raylab's path tracer can be
compared against it.

Scene: mi.cornell_box() unchanged except for
  * film:       hdrfilm, rfilter box, SIZE x SIZE, pixel_format rgb, float32
  * sampler:    --sampler (independent, Mitsuba's default; multijitter, its best
                on this scene; orthogonal, stratified), sample_count SPP (seed
                passed to mi.render)
  * integrator: path, max_depth 8, rr_depth 5 (Mitsuba's default, made explicit)

Output: linear float32 RGB, no tonemapping, row 0 = top of the image.
  OUT            OpenEXR (via mi.Bitmap)
  --npy          OUT with .npy suffix: float32 array (H, W, 3)
  --pfm          OUT with .pfm suffix: little-endian PFM, 'PF\\nW H\\n-1.0\\n',
                 rows bottom-to-top (standard PFM)

--passes N renders N independent passes of SPP samples each (seeds SEED,
SEED+1, ..., SEED+N-1) and averages them: with a box filter every pixel gets
exactly SPP samples per pass, so the average equals one render with N*SPP spp.

Timing: prints the wall time of the rendering proper (mi.render + evaluation
+ sync, summed over passes), the scene load time, and the time since the
interpreter started (whole process, minus interpreter start-up; measure the
whole process from outside with /usr/bin/time -v for the exact figure).

Requirements: pip install mitsuba; for the llvm_* variants a libLLVM
(Debian: apt-get install libllvm19) and
DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so.

Example:
  DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \\
  python3 tools/mitsuba/cbox_reference.py --variant llvm_ad_rgb \\
      --size 512 --spp 64 --seed 0 --out refs/cbox_512_64spp.exr --npy
"""

import time

T_PROCESS0 = time.perf_counter()

import argparse
import os
import sys

import numpy as np


sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mitsuba_run import Render, load_mitsuba  # noqa: E402
from pfm import write_pfm  # noqa: E402


def build_scene_dict(mi, size, spp, max_depth, rr_depth, sampler="independent"):
    d = mi.cornell_box()
    d["sensor"]["film"] = {
        "type": "hdrfilm",
        "width": size,
        "height": size,
        "rfilter": {"type": "box"},
        "pixel_format": "rgb",
        "component_format": "float32",
    }
    d["sensor"]["sampler"] = {"type": sampler, "sample_count": spp}
    d["integrator"] = {"type": "path", "max_depth": max_depth, "rr_depth": rr_depth}
    return d


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--size", type=int, default=512, help="film width = height")
    ap.add_argument("--spp", type=int, default=64, help="samples per pixel per pass")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--sampler", default="independent",
                    choices=["independent", "multijitter", "orthogonal", "stratified", "ldsampler"])
    ap.add_argument("--warmup", action="store_true",
                    help="render once untimed first (Dr.Jit compiles its kernels then)")
    ap.add_argument("--passes", type=int, default=1,
                    help="independent passes (seeds seed..seed+passes-1), averaged")
    ap.add_argument("--max-depth", type=int, default=8)
    ap.add_argument("--rr-depth", type=int, default=5)
    ap.add_argument("--threads", type=int, default=0,
                    help="Dr.Jit worker threads (0 = Dr.Jit default = all cores)")
    ap.add_argument("--out", required=True, help="output .exr path")
    ap.add_argument("--npy", action="store_true", help="also write OUT.npy")
    ap.add_argument("--pfm", action="store_true", help="also write OUT.pfm")
    args = ap.parse_args()

    dr, mi = load_mitsuba(args.variant, args.threads)

    t0 = time.perf_counter()
    scene = mi.load_dict(build_scene_dict(mi, args.size, args.spp,
                                          args.max_depth, args.rr_depth, args.sampler))
    t_load = time.perf_counter() - t0

    if args.warmup:
        dr.eval(mi.render(scene, spp=args.spp, seed=args.seed + 1000))
        dr.sync_thread()
    render = Render(dr, mi, scene, args.spp, args.seed, args.passes)
    img = render.image
    assert img.shape == (args.size, args.size, 3), img.shape

    os.makedirs(os.path.dirname(os.path.abspath(args.out)) or ".", exist_ok=True)
    mi.Bitmap(img, pixel_format=mi.Bitmap.PixelFormat.RGB).write(args.out)
    stem = os.path.splitext(args.out)[0]
    if args.npy:
        np.save(stem + ".npy", img)
    if args.pfm:
        write_pfm(stem + ".pfm", img)

    total_spp = args.spp * args.passes
    print(f"mitsuba {mi.__version__} drjit {dr.__version__} variant {args.variant} sampler {args.sampler}")
    print(f"size {args.size}x{args.size} spp {total_spp} ({args.passes} pass(es) x "
          f"{args.spp}) seed {args.seed} max_depth {args.max_depth} "
          f"rr_depth {args.rr_depth}")
    render.report(t_load, T_PROCESS0)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    sys.exit(main())
