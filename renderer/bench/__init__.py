"""Benchmarks behind "what accuracy costs in time": each prints a table and writes JSON + plots.

The package owns the benchmarks (one module with a `run(quick, out_dir)` entry per name below),
their shared measurement and report helpers (common.py), the independent renderers they measure
against (embree_side.py, mitsuba_side.py) and the ray kernels the BVH benchmark and the geometry
tests share (ray_batch.py). A benchmark module is imported only when it runs: most of them start
Taichi and compile kernels.
"""
from importlib import import_module

BENCHMARKS = {name: f"renderer.bench.{name.replace('-', '_')}"
              for name in ("sdf", "startup", "bvh", "integrators", "features", "photons", "interactive", "denoise",
                           "scale", "mitsuba-tests", "scenes", "texture-filter", "report")}


def run_benchmark(name: str, **options) -> int:
    """Run benchmark `name` (a key of BENCHMARKS) with its run() options; its exit status."""
    return import_module(BENCHMARKS[name]).run(**options)
