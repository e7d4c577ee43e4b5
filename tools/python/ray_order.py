"""What tracing a batch in the tree's order is worth, on 1 M random rays (one thread).

    python tools/python/ray_order.py MESH [MESH ...] [--rays 1000000] [--reps 7]

raylab's queries trace a batch of at least `_raylab.ORDER_MIN_RAYS` rays on a tree of at least
`_raylab.ORDER_MIN_TREE_BYTES` sorted by `raylab::bvh::order`'s key (the Morton code of each
ray's segment through the mesh's box). Batches smaller than the threshold are traced as given,
so this script can time, on the same rays, in alternating rounds (median of `--reps` after a
warm-up round):
- `as given`: the rays in batches just below the threshold, each traced as it comes (a call
  costs tens of microseconds besides its rays: the batches' rows pay that alike);
- `one call`: the whole batch in one call, in the binding's order when the mesh is large enough
  (the keys, the sort and the answers put back included; on a small mesh, as given in one
  call);
- `pre-sorted, segment key`: the rays sorted here (numpy) by the same key and traced in the
  same batches: the order's gain without its cost;
- `pre-sorted, origin and direction`: sorted by a Morton code of origin and direction instead
  (Garanzha and Loop's kind of key);
- `pre-sorted in blocks of B`: the segment key, each block of B rays sorted on its own.

Needs numpy and raylab (`pip install ./python`).
"""

import argparse
import pathlib
import statistics
import sys
import time

import numpy as np

import raylab
from raylab import _raylab

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from bench_queries import random_rays  # noqa: E402

# Just below the order's threshold, so that each batch is traced as given.
SMALL = _raylab.ORDER_MIN_RAYS - 1


def morton6(cells, bits):
    """Interleaves six columns of `bits`-bit cells, the first column's bit highest."""
    key = np.zeros(len(cells), np.uint64)
    for b in range(bits):
        for a in range(6):
            key |= ((cells[:, a] >> np.uint64(b)) & np.uint64(1)) << np.uint64(6 * b + 5 - a)
    return key


def segment_keys(o, d, lo, hi, bits=4):
    """`raylab::bvh::order::segment_key` in numpy, near enough: the vertices' box for the
    tree's, rays without limits, and cell boundaries rounded differently."""
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / d
        t0, t1 = (lo - o) * inv, (hi - o) * inv
    near = np.maximum(np.minimum(t0, t1).max(1), 0)
    far = np.maximum(t0, t1).min(1)
    top = (1 << bits) - 1
    ends = [(o + d * t[:, None] - lo) / (hi - lo) for t in (near, far)]
    cells = np.clip(np.floor(np.concatenate(ends, 1) * (top + 1)), 0, top).astype(np.uint64)
    key = morton6(cells, bits)
    key[~(near <= far)] = np.uint64((1 << (6 * bits)) - 1)
    return key


def origin_direction_keys(o, d, bits=5):
    top = (1 << bits) - 1
    olo, ohi = o.min(0), o.max(0)
    unit = d / np.linalg.norm(d, axis=1)[:, None]
    both = np.concatenate([(o - olo) / (ohi - olo), (unit + 1) / 2], 1)
    return morton6(np.clip(np.rint(both * top), 0, top).astype(np.uint64), bits)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("meshes", nargs="+", type=pathlib.Path)
    parser.add_argument("--rays", type=int, default=1_000_000)
    parser.add_argument("--reps", type=int, default=7)
    args = parser.parse_args()
    print(f"order thresholds: {_raylab.ORDER_MIN_RAYS} rays, {_raylab.ORDER_MIN_TREE_BYTES} bytes")
    for path in args.meshes:
        mesh = raylab.load_mesh(path)
        o, d = random_rays(mesh.vertices, args.rays)
        lo, hi = mesh.vertices.min(0), mesh.vertices.max(0)
        seg = segment_keys(o, d, lo, hi)
        orders = {
            "pre-sorted, segment key": np.argsort(seg, kind="stable"),
            "pre-sorted, origin and direction": np.argsort(origin_direction_keys(o, d), kind="stable"),
        }
        for block in (1 << 16, 1 << 18):
            orders[f"pre-sorted in blocks of {block}"] = np.concatenate(
                [s + np.argsort(seg[s : s + block], kind="stable") for s in range(0, len(o), block)]
            )
        sets = {name: (np.ascontiguousarray(o[i]), np.ascontiguousarray(d[i])) for name, i in orders.items()}

        def in_batches(oo, dd):
            return lambda: [mesh.intersect(oo[s : s + SMALL], dd[s : s + SMALL], threads=1)
                            for s in range(0, len(oo), SMALL)]

        queries = {
            "as given": in_batches(o, d),
            "one call": lambda: mesh.intersect(o, d, threads=1),
            **{name: in_batches(*rays) for name, rays in sets.items()},
        }
        times = {name: [] for name in queries}
        for round_ in range(args.reps + 1):
            for name, query in queries.items():
                start = time.perf_counter()
                query()
                if round_ > 0:
                    times[name].append(time.perf_counter() - start)
        ordered = mesh.bvh_bytes >= _raylab.ORDER_MIN_TREE_BYTES
        print(f"\n{path}: {len(mesh)} triangles, tree {mesh.bvh_bytes / 1e6:.1f} MB "
              f"({'one call is ordered' if ordered else 'one call is traced as given'})")
        given = statistics.median(times["as given"])
        for name, t in times.items():
            m = statistics.median(t)
            print(f"  {name:40s} {m:.3f} ({min(t):.3f}) s  {given / m:.2f}× as given")


if __name__ == "__main__":
    main()
