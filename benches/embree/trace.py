"""Traces the rays `benches/embree.rs` wrote through Embree 4 (embreex).

Usage: trace.py DIR REPEATS. Prints one line per figure, tab-separated:
mode, query, threads, rays per second (the fastest of REPEATS passes),
answers (rays that hit, or segments found occluded). The mode is
"default" (Embree's own scene flags) or "robust" (RTC_SCENE_FLAG_ROBUST:
no optimisation that costs accuracy, which is the guarantee lmanim's
traversal keeps: conservative box tests and a watertight triangle test).

embreex traces one ray per rtcIntersect1 / rtcOccluded1 call in a loop that
holds Python's lock, so two threads means two processes, each building its
own copy of the scene and tracing every other ray; their rays per second
is all rays over the slower one's time. The loop's own cost is measured on
the same number of rays pointing away from the scene's bounds
("-binding"), so the binding can be told apart from Embree's traversal.
"""

import multiprocessing as mp
import sys
import time

import numpy as np
from embreex.mesh_construction import TriangleMesh
from embreex.rtcore_scene import EmbreeScene


def load(folder):
    def vectors(name):
        return np.fromfile(f"{folder}/{name}", dtype="<f4").reshape(-1, 3)

    triangles = np.fromfile(f"{folder}/triangles.u32", dtype="<u4").reshape(-1, 3)
    rays = {
        query: (
            vectors(f"{query}-origins.f32"),
            vectors(f"{query}-directions.f32"),
            np.fromfile(f"{folder}/{query}-tmax.f32", dtype="<f4"),
        )
        for query in ("primary", "shadow")
    }
    return vectors("positions.f32"), triangles.astype(np.int32), rays


def away_from(origins, positions):
    """Rays from above the scene's bounds pointing further up: they miss."""
    top = positions[:, 1].max() + 1.0
    lifted = origins.copy()
    lifted[:, 1] = top
    up = np.zeros_like(origins)
    up[:, 1] = 1.0
    return lifted, up


def trace(scene, query, origins, directions, tmax):
    """Answers of one pass: rays that hit (closest) or segments occluded."""
    if query.startswith("primary"):
        ids = scene.run(origins, directions, dists=tmax.copy(), query="INTERSECT")
        return int((ids >= 0).sum())
    ids = scene.run(origins, directions, dists=tmax.copy(), query="OCCLUDED")
    return int((ids >= 0).sum())


def ray_sets(positions, rays):
    sets = {}
    for query in ("primary", "shadow"):
        origins, directions, tmax = rays[query]
        sets[query] = (origins, directions, tmax)
        lifted, up = away_from(origins, positions)
        sets[f"{query}-binding"] = (lifted, up, np.full_like(tmax, np.inf))
    return sets


def worker(folder, robust, share, shares, repeats, barrier, results):
    positions, triangles, rays = load(folder)
    scene = EmbreeScene(robust=robust)
    TriangleMesh(scene, positions, triangles)
    sets = {
        query: tuple(np.ascontiguousarray(a[share::shares]) for a in arrays)
        for query, arrays in ray_sets(positions, rays).items()
    }
    trace(scene, "primary", *(a[:1000] for a in sets["primary"]))  # builds the BVH
    for query, arrays in sets.items():
        for _ in range(repeats):
            barrier.wait()
            start = time.perf_counter()
            answers = trace(scene, query, *arrays)
            results.put((query, share, time.perf_counter() - start, answers))


def measure(folder, robust, processes, repeats):
    barrier = mp.Barrier(processes)
    results = mp.Queue()
    workers = [
        mp.Process(
            target=worker, args=(folder, robust, share, processes, repeats, barrier, results)
        )
        for share in range(processes)
    ]
    for w in workers:
        w.start()
    queries = 4
    passes = {}
    for _ in range(queries * repeats * processes):
        query, share, seconds, answers = results.get()
        passes.setdefault(query, []).append((share, seconds, answers))
    for w in workers:
        w.join()
        if w.exitcode != 0:
            sys.exit(f"an Embree worker failed with exit code {w.exitcode}")
    return passes


def main():
    folder, repeats = sys.argv[1], int(sys.argv[2])
    _, _, rays = load(folder)
    for mode, robust in (("default", False), ("robust", True)):
        for processes in (1, 2):
            report(mode, processes, measure(folder, robust, processes, repeats), rays, repeats)


def report(mode, processes, passes, rays, repeats):
    """Prints one line per query of `passes`, from `measure`."""
    for query, runs in passes.items():
        count = len(rays[query.split("-")[0]][0])
        # Pass r of every process ran between the same barriers: its
        # time is the slowest share's.
        by_pass = [runs[r * processes:(r + 1) * processes] for r in range(repeats)]
        fastest = min(max(s for _, s, _ in one) for one in by_pass)
        answers = sum(a for _, _, a in by_pass[0])
        print(f"{mode}\t{query}\t{processes}\t{count / fastest:.0f}\t{answers}")


if __name__ == "__main__":
    mp.set_start_method("spawn")
    main()
