"""Taichi initialisation, done once from an entry point (never at import time)."""
import ctypes.util
import os

import taichi as ti

from renderer import taichi_frontend

ARCHES = ("auto", "cpu", "cuda", "vulkan")
# "compile": skip Taichi's own IR optimisations (LLVM still optimises the code): a path tracer
# kernel compiles 3-10x sooner, and runs up to ~10% slower (`python app.py bench startup`).
# "run": every optimisation, for long renders (`render` picks it for them by itself:
# renderer/optimize_choice.py) and benchmarks. Kernels of both levels live side by side in the
# offline cache.
OPTIMIZE_FOR = ("compile", "run")
# Taichi's offline cache keeps 100 MB by default and, past that, drops the least recently used
# quarter, to be compiled again when next needed. One compiled render kernel takes 0.1-2 MB (a
# scene's features x integrator x optimisation level x field shapes): the test suite's kernels
# alone come to ~99 MB, and a few dozen scenes fill the default. Compiling costs far more than
# loading (one test file: 306 s on a clean cache, 119 s cached). Taichi holds the cap in a 32-bit
# int: 2 GiB is the most it takes.
OFFLINE_CACHE_MAX_BYTES = 2**31 - 1


def taichi_options(optimize: str = "compile") -> dict:
    """ti.init keyword arguments of an optimisation level (also used by the tests' runtime)."""
    if optimize not in OPTIMIZE_FOR:
        raise ValueError(f"unknown optimisation level '{optimize}' (choose from {', '.join(OPTIMIZE_FOR)})")
    return {"advanced_optimization": optimize == "run"}


def offline_cache_options(enabled: bool = True, cache_dir: str | None = None) -> dict:
    """ti.init keyword arguments of the offline cache (also used by the tests' runtime)."""
    kwargs = {"offline_cache": enabled, "offline_cache_max_size_of_files": OFFLINE_CACHE_MAX_BYTES}
    if cache_dir:
        kwargs["offline_cache_file_path"] = cache_dir
    return kwargs


def init_taichi(arch: str = "auto", offline_cache: bool = True, cache_dir: str | None = None,
                optimize: str = "compile", cpu_threads: int | None = None, cheaper_frontend: bool = True) -> str:
    """Initialise Taichi on `arch` and return the name of the back-end actually in use.
    cpu_threads: the CPU back-end's thread count (default: every core).

    'auto' takes CUDA when a CUDA GPU is there, else the CPU. It does not take Vulkan by itself:
    on a machine without a GPU the Vulkan device is a software rasteriser, far slower than the
    CPU back-end.
    """
    if arch not in ARCHES:
        raise ValueError(f"unknown arch '{arch}' (choose from {', '.join(ARCHES)})")
    kwargs = {"log_level": ti.WARN, **offline_cache_options(offline_cache, cache_dir), **taichi_options(optimize)}
    if cpu_threads is not None:
        kwargs["cpu_max_num_threads"] = cpu_threads
    if os.environ.get("LANTERN_TAICHI_DEBUG"):
        kwargs["debug"] = True
    if arch == "auto" and cpu_expected(arch):
        arch = "cpu"  # no CUDA driver: skip Taichi's noisy probe-and-fall-back
    wanted = {"auto": ti.cuda, "cpu": ti.cpu, "cuda": ti.cuda, "vulkan": ti.vulkan}[arch]
    if cheaper_frontend:  # a third less compile time for large kernels (False: scripts/frontend_cost.py)
        taichi_frontend.install()
    ti.init(arch=wanted, **kwargs)
    used = ti.lang.impl.current_cfg().arch
    if arch in ("cuda", "vulkan") and used != wanted:
        raise RuntimeError(f"arch '{arch}' is not available on this machine")
    return str(used).split(".")[-1]


def cpu_expected(arch: str) -> bool:
    """Whether `arch` (an --arch choice) will run on the CPU, as far as is known before ti.init:
    'cpu', or 'auto' without a CUDA driver (with one, 'auto' may still fall back to the CPU)."""
    return arch == "cpu" or (arch == "auto" and ctypes.util.find_library("cuda") is None)
