"""`python app.py bench bvh`: BVH build and traversal, side by side with Embree.

On three meshes (the bunny model, 5,648 triangles; a 100,352-triangle terrain; a 1,002,528-triangle
terrain), in one process so that ratios are meaningful:

1. Build: `build_bvh` seconds (median of repeats; the per-primitive boxes and centroids are
   computed once beforehand and timed apart) and triangles/s per split strategy (sah, midpoint,
   equal_count), the SAH cost of each tree, its node count and depth, and the bytes per triangle
   the BVH plus the triangle intersection data take on the device (`MeshGeometry.device_bytes()`).
   Issue targets: at most 64 bytes per triangle (the Renderer's configuration: SAH, leaves of 4),
   and the SAH build of the 1M mesh in at most 2 s.
2. Trace: closest-hit Mrays/s for every split strategy x traversal (stack, stackless: the binary
   tree; wide4: the tree collapsed into 4-wide nodes; with "+packets": leaves tested four slots
   at a time from structure-of-arrays triangles, on sah trees with the Renderer's leaf size for
   packets, 8, where the others have 4) x triangle test (watertight,
   moller), on
   coherent rays (a pinhole camera grid on the mesh) and on incoherent rays (origins on a sphere
   around the mesh, aimed at uniform random points in its box), with the mean node visits (a
   wide4 visit tests four boxes) and primitive tests per ray (`Hit.work`, `Hit.tests`), and
   wide4 / stack per strategy and triangle test, and packet / scalar leaves (medians of the same
   interleaved runs).
   Any-hit (`occluded`) rays on the Renderer's configuration (and on the binary "stack"
   traversal): the incoherent rays as segments ending at their random target points (shadow
   rays), against closest-hit on the same segments.
   Each configuration is compiled (first call, on a few rays) before timing; the timed calls run
   round-robin over all configurations of a mesh (and Embree), medians of several launches.
3. Embree (the optional `embreex` package: `pip install embreex`, or the project's `bench` extra)
   on the same meshes and the same rays: its build time (scene commit), Mrays/s, and the ratio
   Lantern / Embree on incoherent rays. Issue target: at least 0.3x Embree's rays/s on incoherent
   closest-hit rays, judged on the Renderer's configuration (sah, wide8 with packet leaves, watertight). Cross-check:
   the fraction of rays on which every Lantern configuration agrees with Embree (both miss, or
   both hit with distances within 1e-4 relative). Without embreex the Embree columns are skipped.
4. Leaf size: SAH builds with max_leaf_size 1, 2, 4, 8, 16 on the 100k mesh: build time, bytes per
   triangle, SAH cost and incoherent Mrays/s (the Renderer's traversal and triangle test).

Threads: Taichi's CPU back-end runs kernels on `cpu_max_num_threads` (all cores by default, 2 on
the machine this was written on). embreex traces one ray at a time in a loop that releases the
GIL, so the rays are cut into chunks run by as many Python threads as Taichi uses; Embree builds
with its own thread pool over all cores. Both thread counts are printed and stored.

Writes <out_dir>/bench_bvh.json and PNG plots next to it, and prints tables. The measurements are
in bvh_measure.py, the tables and plots in bvh_report.py, Embree in embree_side.py.
"""
from __future__ import annotations

import os
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict
from pathlib import Path

import taichi as ti

from renderer.bench import embree_side
from renderer.bench.bvh_measure import (
    BYTES_PER_TRIANGLE_TARGET,
    EMBREE_RATIO_TARGET,
    EMBREE_RATIO_TARGET_1M,
    FULL,
    QUICK,
    SAH_BUILD_TARGET_MIN_TRIANGLES,
    SAH_BUILD_TARGET_S,
    BvhBenchConfig,
    leaf_size_sweep,
    measure_mesh,
)
from renderer.bench.bvh_report import print_report, write_plots
from renderer.bench.common import load_average, report_header, speed_runtime, write_json

NOTES = ("Build times are build_bvh alone (per-primitive boxes and centroids prepared beforehand, "
         "bounds_s). Device bytes = MeshGeometry.device_bytes() (BVH nodes + primitive index, triangle "
         "vertices). Trace: ndarray rays, one kernel launch per call followed by ti.sync(); every "
         "configuration compiled before timing; timed calls round-robin over all configurations of a "
         "mesh and Embree; Mrays/s from the median. Embree: embreex's rtcIntersect1/rtcOccluded1 loop "
         "(robust scene flag), rays cut into chunks over as many Python threads as Taichi's CPU "
         "threads. Agreement: both miss, or both hit with |t_lantern - t_embree| <= 1e-4 t_embree. "
         "Shadow rays: the incoherent rays as segments ending at their random target points.")


def _embree(config: BvhBenchConfig):
    """(load_embree()'s triple, the report's "embree" entry); the triple's first item is None
    when Embree is disabled or not importable."""
    embree = (None, None, "disabled in the configuration")
    if config.embree:
        embree = embree_side.load_embree()
        if embree[0] is None:
            print(f"note: the embreex package is not importable ({embree[2]}); the Embree columns are skipped. "
                  f"Install it with `pip install embreex` (or the project's `bench` extra).", flush=True)
    if embree[0] is not None:
        return embree, {"available": True, "version": embree[2]}
    return embree, {"available": False, "note": embree[2]}


def _targets(meshes: list[dict], embree_available: bool) -> dict:
    big = [m for m in meshes if m["triangles"] >= SAH_BUILD_TARGET_MIN_TRIANGLES]
    targets = {"bytes_per_triangle": BYTES_PER_TRIANGLE_TARGET, "sah_build_seconds": SAH_BUILD_TARGET_S,
               "embree_ratio": EMBREE_RATIO_TARGET, "agreement_rtol": embree_side.AGREEMENT_RTOL}
    if big:
        m = big[-1]
        b = next((b for b in m["builds"] if b["strategy"] == "sah"), None)
        if b is not None:
            targets["sah_build_1m"] = {"mesh": m["name"], "triangles": m["triangles"], "seconds": b["seconds"],
                                       "passed": b["seconds"] <= SAH_BUILD_TARGET_S}
    targets["bytes_per_triangle_passed"] = {
        m["name"]: b["device_bytes"]["target_passed"] for m in meshes for b in m["builds"] if b["strategy"] == "sah"}
    if embree_available:
        targets["embree_ratio_passed"] = {m["name"]: m.get("embree_target_passed") for m in meshes}
        for m in big[-1:]:
            ratio = m.get("ratio_to_embree", {}).get("incoherent", {}).get("default")
            if ratio is not None:
                targets["embree_ratio_1m"] = {"mesh": m["name"], "target": EMBREE_RATIO_TARGET_1M, "ratio": ratio,
                                              "passed": ratio >= EMBREE_RATIO_TARGET_1M}
    return targets


def run(quick: bool = False, out_dir: Path = Path("reports"), config: BvhBenchConfig | None = None) -> int:
    """Measure every mesh of the configuration; print tables, write JSON and plots."""
    config = config or (QUICK if quick else FULL)
    out_dir = Path(out_dir)
    t_start = time.perf_counter()
    arch = speed_runtime()
    threads = int(ti.lang.impl.current_cfg().cpu_max_num_threads)
    load_before = load_average()
    embree, embree_info = _embree(config)

    pool = ThreadPoolExecutor(max_workers=threads) if embree[0] is not None else None
    meshes, leaf = [], None
    try:
        for spec in config.meshes:
            t0 = time.perf_counter()
            tris = spec.load()
            print(f"{spec.name}: {len(tris):,} triangles (loaded in {time.perf_counter() - t0:.2f} s)", flush=True)
            meshes.append(measure_mesh(spec.name, tris, config, embree if embree[0] is not None else None, pool))
            if spec.name == config.leaf_mesh and config.leaf_sizes:
                leaf = leaf_size_sweep(spec.name, tris, config)
            del tris
    finally:
        if pool is not None:
            pool.shutdown()

    threads_used = {"taichi": threads, "bvh_builder": sorted({b["builder_threads"] for m in meshes
                                                             for b in m["builds"] if b["builder_threads"]}),
                    "embree_trace": threads if embree_info["available"] else None, "embree_build": os.cpu_count()}
    report = {
        **report_header("bvh", quick, load_before, arch=arch, threads=threads_used, embree=embree_info,
                        config={**asdict(config), "meshes": [asdict(s) for s in config.meshes]}),
        "targets": _targets(meshes, embree_info["available"]),
        "notes": NOTES,
        "meshes": meshes,
        "leaf_size": leaf,
    }
    print()
    print_report(report)
    plots = write_plots(report, out_dir)
    report["plots"] = [p.name for p in plots]
    report["total_seconds"] = time.perf_counter() - t_start
    path = write_json(out_dir / "bench_bvh.json", report)
    print(f"wrote {path} and {', '.join(p.name for p in plots)} in {out_dir}  "
          f"(total {report['total_seconds']:.0f} s)", flush=True)
    return 0
