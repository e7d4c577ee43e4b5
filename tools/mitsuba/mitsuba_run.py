"""What the Mitsuba reference scripts share: loading Mitsuba, rendering in passes, and the
report of a render (times, samples per second, mean, standard error, non-finite pixels)."""

import os
import time

import numpy as np


def load_mitsuba(variant, threads=0):
    """Imports Dr.Jit and Mitsuba with `variant` set; for LLVM variants, points Dr.Jit at Debian's
    libLLVM-19 unless DRJIT_LIBLLVM_PATH is set. `threads` > 0 sets Dr.Jit's worker count."""
    if variant.startswith("llvm") and "DRJIT_LIBLLVM_PATH" not in os.environ:
        cand = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"
        if os.path.exists(cand):
            os.environ["DRJIT_LIBLLVM_PATH"] = cand

    import drjit as dr
    import mitsuba as mi

    mi.set_variant(variant)
    if threads > 0:
        dr.set_thread_count(threads)
    return dr, mi


class Render:
    """The mean of `passes` renders (seeds seed..seed+passes-1) as float32 (H, W, 3), the render
    wall time, and the RMS standard error estimated from the pass-to-pass spread (None for one
    pass)."""

    def __init__(self, dr, mi, scene, spp, seed, passes):
        acc = acc2 = None
        self.seconds = 0.0
        for i in range(passes):
            t0 = time.perf_counter()
            img = mi.render(scene, spp=spp, seed=seed + i)
            dr.eval(img)
            dr.sync_thread()
            dt = time.perf_counter() - t0
            self.seconds += dt
            a = np.array(img, dtype=np.float64)
            acc = a if acc is None else acc + a
            acc2 = a * a if acc2 is None else acc2 + a * a
            if passes > 1:
                print(f"pass {i + 1}/{passes} seed {seed + i}: {dt:.3f} s", flush=True)
        self.image = (acc / passes).astype(np.float32)
        self.samples = self.image.shape[0] * self.image.shape[1] * spp * passes
        self.standard_error = None
        if passes > 1:
            mean = acc / passes
            var = np.maximum(acc2 / passes - mean * mean, 0.0) * (passes / (passes - 1))
            self.standard_error = np.sqrt(np.mean(var / passes))
        self.passes = passes

    def report(self, t_load, t_process0):
        """Prints the render's figures (after the caller's own header lines)."""
        img = self.image
        m = img.reshape(-1, 3).astype(np.float64).mean(axis=0)
        print(f"scene load: {t_load:.3f} s")
        print(f"render wall time (mi.render + eval + sync): {self.seconds:.3f} s "
              f"({self.samples / self.seconds / 1e6:.2f} M samples/s)")
        print(f"process time since interpreter start: {time.perf_counter() - t_process0:.3f} s")
        print(f"mean R G B: {m[0]:.6f} {m[1]:.6f} {m[2]:.6f}  overall "
              f"{img.astype(np.float64).mean():.6f}")
        if self.standard_error is not None:
            print(f"estimated RMS standard error of the result (from {self.passes} passes): "
                  f"{self.standard_error:.6f}")
        print(f"nonfinite: {int((~np.isfinite(img)).sum())}  min {img.min():.6g} "
              f"max {img.max():.6g}")
