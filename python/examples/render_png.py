"""A scene rendered into numpy, then written as a PNG (and as linear EXR).

    python examples/render_png.py [SCENE] [OUT.png]
"""

import sys

import numpy as np

import raylab

scene = sys.argv[1] if len(sys.argv) > 1 else "scenes/cornell-mitsuba.toml"
output = sys.argv[2] if len(sys.argv) > 2 else "render.png"

result = raylab.render(
    scene,
    size=(256, 256),
    spp=16,
    aovs=["albedo"],
    progress=lambda fraction: print(f"\r{fraction:4.0%}", end="", flush=True),
)
print(f"\n{result.samples} samples per pixel, mean radiance {result.image.mean(axis=(0, 1))}")
# Linear radiance in the array: tone-mapped and sRGB-encoded only when written to 8 bits.
raylab.write_image(output, result.image)
raylab.write_image(output.rsplit(".", 1)[0] + ".exr", result.image)
raylab.write_image(output.rsplit(".", 1)[0] + "_albedo.png", result.aovs["albedo"])
assert np.isfinite(result.image).all()
