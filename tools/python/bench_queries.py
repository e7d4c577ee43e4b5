"""raylab's Python queries against embreex and trimesh, side by side, on 1 M random rays.

    python tools/python/bench_queries.py MESH [MESH ...] [--rays 1000000] [--reps 7]
        [--raylab-bin target/release/raylab]

For each mesh: 1 M rays from a sphere around it toward random points in its box (seed 1), the
median (min) wall time of `--reps` rounds after a warm-up round, in one process, each round
running every query once in turn:
- raylab `Mesh.intersect` (t, triangle, u, v) on 1 and 2 threads, and `Mesh.occluded`;
- embreex `EmbreeScene.run(origins, directions, output=1)` (distances and ids; one thread:
  embreex traces rays one by one in a loop) and `run(...)` for the ids alone;
- trimesh's `ray.intersects_first` with its embreex intersector;
- with `--raylab-bin`, `raylab bench MESH --rays DIR` on the very same rays (written as
  `diffuse.rays`), the binding's overhead being the difference;
- mesh build time (raylab.Mesh against an embreex scene), import time, the BVH's bytes
  per triangle, and what a call with one ray costs (raylab on 1, 2 and all threads; embreex).

Needs numpy, raylab (`pip install ./python`), embreex and trimesh.
"""

import argparse
import json
import os
import pathlib
import statistics
import struct
import subprocess
import sys
import tempfile
import time

import numpy as np


def timed(f, reps):
    f()  # warm-up
    times = []
    for _ in range(reps):
        start = time.perf_counter()
        f()
        times.append(time.perf_counter() - start)
    return statistics.median(times), min(times)


def alternating(queries, reps):
    """Each query's median (min) time over `reps` rounds, every round running each query once
    in turn (after one warm-up round), so that a noisy minute touches them all alike."""
    times = {name: [] for name in queries}
    for round_ in range(reps + 1):
        for name, query in queries.items():
            start = time.perf_counter()
            query()
            if round_ > 0:
                times[name].append(time.perf_counter() - start)
    return {name: (statistics.median(t), min(t)) for name, t in times.items()}


def random_rays(vertices, n, seed=1):
    rng = np.random.default_rng(seed)
    lo, hi = vertices.min(0), vertices.max(0)
    centre, radius = (lo + hi) / 2, np.linalg.norm(hi - lo)
    outward = rng.normal(size=(n, 3))
    outward /= np.linalg.norm(outward, axis=1)[:, None]
    origins = (centre + outward * radius).astype(np.float32)
    targets = (lo + rng.random((n, 3)) * (hi - lo)).astype(np.float32)
    directions = targets - origins
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    return origins, directions.astype(np.float32)


def write_rays(path, origins, directions):
    records = np.zeros((len(origins), 8), dtype="<f4")
    records[:, 0:3] = origins
    records[:, 4:7] = directions
    records[:, 7] = np.inf
    with open(path, "wb") as out:
        out.write(struct.pack("<4sIII", b"RAYS", 1, len(origins), 0))
        out.write(records.tobytes())


def import_time():
    code = "import time; s = time.perf_counter(); import raylab; print(time.perf_counter() - s)"
    runs = [float(subprocess.check_output([sys.executable, "-c", code])) for _ in range(5)]
    return statistics.median(runs)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("meshes", nargs="+")
    parser.add_argument("--rays", type=int, default=1_000_000)
    parser.add_argument("--reps", type=int, default=7)
    parser.add_argument("--raylab-bin")
    args = parser.parse_args()

    import raylab
    import trimesh
    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh

    print(f"import raylab: {import_time() * 1e3:.0f} ms (median of 5 fresh interpreters)")
    for path in args.meshes:
        start = time.perf_counter()
        mesh = raylab.load_mesh(path)
        load = time.perf_counter() - start
        vertices, faces = mesh.vertices, mesh.faces.astype(np.int64)
        n = len(faces)
        build_raylab = timed(lambda: raylab.Mesh(vertices, faces), 3)

        def embree_scene():
            scene = rtcore_scene.EmbreeScene()
            TriangleMesh(scene, vertices[faces])
            # embreex builds its BVH on the first query.
            scene.run(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32))
            return scene

        build_embree = timed(embree_scene, 3)
        scene = embree_scene()
        origins, directions = random_rays(vertices, args.rays)
        tm = trimesh.Trimesh(vertices, faces, process=False)
        intersector = trimesh.ray.ray_pyembree.RayMeshIntersector(tm)
        queries = {
            "raylab intersect, 1 thread": lambda: mesh.intersect(origins, directions, threads=1),
            "raylab intersect, 2 threads": lambda: mesh.intersect(origins, directions, threads=2),
            "raylab occluded, 1 thread": lambda: mesh.occluded(origins, directions, threads=1),
            "embreex run(output=1)": lambda: scene.run(origins, directions, output=1),
            "embreex run (ids)": lambda: scene.run(origins, directions),
            "trimesh intersects_first (embreex)": lambda: intersector.intersects_first(
                origins, directions),
        }
        rows = alternating(queries, args.reps)
        # What a call costs besides its rays: one ray per call.
        one_o, one_d = origins[:1].copy(), directions[:1].copy()
        calls = {
            f"threads={threads}": timed(lambda t=threads: [mesh.intersect(one_o, one_d, threads=t)
                                                           for _ in range(1000)], 5)[0] / 1000
            for threads in (1, 2, None)
        } | {"embreex": timed(lambda: [scene.run(one_o, one_d, output=1)
                                       for _ in range(1000)], 5)[0] / 1000}
        ours, theirs = mesh.intersect(origins, directions), scene.run(origins, directions)
        agree = ((ours.triangle >= 0) == (theirs >= 0)).mean()
        print(f"\n{path}: {n} triangles, loaded in {load:.2f} s; {args.rays} rays, "
              f"{(ours.triangle >= 0).mean():.1%} hit, hit/miss agreement with Embree {agree:.5%}")
        print(f"build: raylab.Mesh {build_raylab[0] * 1e3:.0f} ms, embreex scene "
              f"{build_embree[0] * 1e3:.0f} ms; raylab BVH {mesh.bvh_bytes / n:.1f} bytes "
              f"per triangle (+{(12 + 12 * len(vertices) / n):.1f} for the vertices and faces)")
        print("a call with one ray: " + ", ".join(f"{name} {t * 1e6:.0f} µs"
                                                   for name, t in calls.items()))
        base = rows["embreex run(output=1)"][0]
        print(f"{'':38} {'median (min) s':>16} {'Mrays/s':>8} {'vs embreex':>10}")
        for name, (median, least) in rows.items():
            print(f"{name:38} {median:8.3f} ({least:.3f}) {args.rays / median / 1e6:8.2f} "
                  f"{base / median:9.2f}×")
        if args.raylab_bin:
            with tempfile.TemporaryDirectory() as directory:
                # The command traces three sets; the rays are the diffuse set, the other two a
                # token 8×8 of them.
                for name, count in (("primary", 64), ("shadow", 64), ("diffuse", len(origins))):
                    write_rays(os.path.join(directory, f"{name}.rays"), origins[:count],
                               directions[:count])
                report = os.path.join(directory, "bench.json")
                subprocess.run([args.raylab_bin, "bench", path, "--rays", directory,
                                "--size", "8x8", "--threads", "2", "--reps", str(args.reps),
                                "--json", report],
                               check=True, capture_output=True)
                figures = json.loads(pathlib.Path(report).read_text())["sets"]["diffuse"]
                one, two = figures["closest"]["1"], figures["closest"]["2"]
                print(f"raylab bench on the same rays: {one:.2f} Mrays/s on 1 thread, "
                      f"{two:.2f} on 2 (median of {args.reps})")


if __name__ == "__main__":
    main()
