"""A depth image of the bunny from rays: a pinhole camera's rays, their closest hits' t.

    python examples/depth_image.py [MESH] [OUT.png]
"""

import sys

import numpy as np

import raylab

mesh_path = sys.argv[1] if len(sys.argv) > 1 else "crates/raylab/tests/data/meshes/bunny.obj.gz"
output = sys.argv[2] if len(sys.argv) > 2 else "bunny_depth.png"

mesh = raylab.load_mesh(mesh_path)
lo, hi = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
centre, size = (lo + hi) / 2, np.linalg.norm(hi - lo)

# A camera 0.9 sizes in front of the model (+z), looking at its centre, 60° field of view.
width, height = 320, 240
eye = centre + np.array([0, 0, 0.9 * size])
x = (np.arange(width) + 0.5) / width * 2 - 1
y = 1 - (np.arange(height) + 0.5) / height * 2
focal = 1 / np.tan(np.radians(30))
px, py = np.meshgrid(x * width / height, y)
directions = np.stack([px, py, np.full_like(px, -focal)], axis=-1).reshape(-1, 3)
origins = np.broadcast_to(eye, directions.shape)

hits = mesh.intersect(origins, directions)
depth = hits.t.reshape(height, width)
seen = np.isfinite(depth)
# Near is bright, far is dark, the background black.
near, far = depth[seen].min(), depth[seen].max()
shade = np.where(seen, 1 - 0.8 * (depth - near) / (far - near), 0).astype(np.float32)
raylab.write_image(output, shade, srgb=False)
print(f"{output}: {seen.mean():.0%} of the pixels see the model, t from {near:.3f} to {far:.3f}")
