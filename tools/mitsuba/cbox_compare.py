#!/usr/bin/env python3
"""Compare a render against a reference: RMSE and per-channel means.

Images: .npy (float32 H x W x 3, row 0 = top), .pfm (standard, rows
bottom-to-top) or .exr (read with mitsuba's Bitmap; needs `pip install mitsuba`).

RMSE is in linear radiance over all pixels and channels:
    sqrt(mean((a - b)^2))
Also prints the RMSE per channel, the mean per channel and overall of both
images, and the relative difference of the means.

Usage: python3 tools/mitsuba/cbox_compare.py TEST REFERENCE
"""

import sys

import os

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pfm import read_pfm  # noqa: E402


def load(path):
    if path.endswith(".npy"):
        return np.load(path).astype(np.float64)
    if path.endswith(".pfm"):
        return read_pfm(path).astype(np.float64)
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    return np.array(mi.Bitmap(path), dtype=np.float64)[..., :3]


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    a, b = load(sys.argv[1]), load(sys.argv[2])
    if a.shape != b.shape:
        sys.exit(f"shape mismatch: {a.shape} vs {b.shape}")
    d = a - b
    print(f"test      {sys.argv[1]}  {a.shape}")
    print(f"reference {sys.argv[2]}  {b.shape}")
    print(f"RMSE (all pixels and channels): {np.sqrt(np.mean(d * d)):.6f}")
    print("RMSE per channel R G B: " +
          " ".join(f"{np.sqrt(np.mean(d[..., k] ** 2)):.6f}" for k in range(3)))
    for name, x in (("test", a), ("reference", b)):
        m = x.reshape(-1, 3).mean(axis=0)
        print(f"mean {name:9s} R G B: {m[0]:.6f} {m[1]:.6f} {m[2]:.6f}  "
              f"overall {x.mean():.6f}")
    rel = a.reshape(-1, 3).mean(axis=0) / b.reshape(-1, 3).mean(axis=0) - 1
    print("relative mean difference R G B: " + " ".join(f"{r:+.4%}" for r in rel) +
          f"  overall {a.mean() / b.mean() - 1:+.4%}")


if __name__ == "__main__":
    main()
