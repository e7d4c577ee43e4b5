"""Shadow and visibility queries: which points on a floor the bunny shadows from a light, and
which pairs of points see each other.

    python examples/visibility.py [MESH]
"""

import sys

import numpy as np

import raylab

mesh_path = sys.argv[1] if len(sys.argv) > 1 else "crates/raylab/tests/data/meshes/bunny.obj.gz"
mesh = raylab.load_mesh(mesh_path)
lo, hi = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
size = hi - lo

# A grid of points on the floor under the model, and a point light above it.
rng = np.random.default_rng(1)
n = 100_000
floor = np.column_stack([
    rng.uniform(lo[0] - size[0], hi[0] + size[0], n),
    np.full(n, lo[1] - 1e-3 * size[1]),
    rng.uniform(lo[2] - size[2], hi[2] + size[2], n),
])
light = np.array([(lo[0] + hi[0]) / 2, hi[1] + 2 * size[1], (lo[2] + hi[2]) / 2])

# Shadow rays: from each floor point toward the light, t in (0, 1) (the light's own point
# excluded: direction = light − point, so t = 1 is the light).
in_shadow = mesh.occluded(floor, light - floor, t_max=1.0)
print(f"{in_shadow.mean():.1%} of the floor points are in the bunny's shadow")

# Visibility between pairs of points: the segment from a to b is clear when nothing is hit.
a = floor[:1000]
b = floor[rng.permutation(n)[:1000]] + np.array([0, 0.5 * size[1], 0])
visible = ~mesh.occluded(a, b - a, t_max=1.0)
print(f"{visible.mean():.1%} of 1000 random pairs see each other")

# Inside or outside: a closed mesh contains a point when a ray from it crosses the surface an
# odd number of times.
points = lo + rng.random((10_000, 3)) * size
print(f"{mesh.contains(points).mean():.1%} of its bounding box is inside the model")
