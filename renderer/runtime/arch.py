"""Taichi initialisation, done once from an entry point (never at import time)."""
import ctypes.util
import os

import taichi as ti
from taichi._lib import core as taichi_core  # CompileConfig: its default offline-cache folder here

from renderer.runtime import taichi_frontend

ARCHES = ("auto", "cpu", "cuda", "vulkan")
# "compile": skip Taichi's own IR optimisations (LLVM still optimises the code): a path tracer
# kernel compiles 3-10x sooner, and runs up to ~10% slower (`python app.py bench startup`).
# "run": every optimisation, for long renders (`render` picks it for them by itself:
# renderer/runtime/optimize_choice.py) and benchmarks. Kernels of both levels live side by side in the
# offline cache.
OPTIMIZE_FOR = ("compile", "run")
# Taichi's offline cache keeps 100 MB by default and, past that, drops the least recently used
# quarter, to be compiled again when next needed. One compiled render kernel takes 0.1-2 MB (a
# scene's features x integrator x optimisation level x field shapes): the test suite's kernels
# alone come to ~99 MB, and a few dozen scenes fill the default. Compiling costs far more than
# loading (one test file: 306 s on a clean cache, 119 s cached). Taichi holds the cap in a 32-bit
# int: 2 GiB is the most it takes.
OFFLINE_CACHE_MAX_BYTES = 2**31 - 1
LANTERN_CACHE_FOLDER = "lantern-dynamic-loops"  # see default_cache_dir
CACHE_PATH_VARIABLE = "TI_OFFLINE_CACHE_FILE_PATH"  # Taichi's cache root, read by default_cache_dir


def taichi_options(optimize: str = "compile") -> dict:
    """ti.init keyword arguments of an optimisation level (also used by the tests' runtime)."""
    if optimize not in OPTIMIZE_FOR:
        raise ValueError(f"unknown optimisation level '{optimize}' (choose from {', '.join(OPTIMIZE_FOR)})")
    return {"advanced_optimization": optimize == "run"}


def cpu_scheduling_options() -> dict:
    """ti.init keyword arguments of how the CPU back-end shares a parallel loop among its threads
    (also used by the tests' runtime).

    Taichi 1.7.4 by default rewrites every parallel loop into one contiguous share of its indices
    per thread (and runs a loop of a few hundred indices on one thread): a thread whose share
    holds the dearer pixels (the model rather than the sky) finishes last while the others wait.
    Without that rewrite (`make_cpu_multithreading_loop=False`) a loop is cut into blocks that
    the threads take in turn as they finish, so every thread works to the loop's end: whole
    rounds of uneven scenes 1.5-1.9x faster than under the static shares, a viewer still
    frame's passes ~1.1x (scripts/cpu_scheduling_cost.py; figures in
    docs/findings.md). GPUs schedule blocks dynamically anyway. Taichi reads the setting when
    a kernel compiles, and its offline cache key leaves it out: see default_cache_dir.
    """
    return {"make_cpu_multithreading_loop": False}


def default_cache_dir() -> str:
    """Where compiled kernels are kept unless a caller names a folder: a folder of Lantern's own
    within Taichi's cache (TI_OFFLINE_CACHE_FILE_PATH, else Taichi's default, ~/.cache/taichi/ticache
    on Linux).

    Taichi 1.7.4's cache key leaves out the loop scheduling of cpu_scheduling_options (a kernel
    compiled with the per-thread shares was loaded as it was under the dynamic setting:
    scripts/cpu_scheduling_cost.py shows it), so the kernels compiled under Lantern's setting
    are kept apart from any compiled under Taichi's default."""
    taichi_cache = os.environ.get(CACHE_PATH_VARIABLE) or taichi_core.CompileConfig().offline_cache_file_path
    return os.path.join(taichi_cache, LANTERN_CACHE_FOLDER)


def offline_cache_options(enabled: bool = True, cache_dir: str | None = None) -> dict:
    """ti.init keyword arguments of the offline cache (also used by the tests' runtime)."""
    return {"offline_cache": enabled, "offline_cache_max_size_of_files": OFFLINE_CACHE_MAX_BYTES,
            "offline_cache_file_path": cache_dir or default_cache_dir()}


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
    kwargs = {"log_level": ti.WARN, **offline_cache_options(offline_cache, cache_dir), **taichi_options(optimize),
              **cpu_scheduling_options()}
    if cpu_threads is not None:
        kwargs["cpu_max_num_threads"] = cpu_threads
    if os.environ.get("LANTERN_TAICHI_DEBUG"):
        kwargs["debug"] = True
    if arch == "auto" and cpu_expected(arch):
        arch = "cpu"  # no CUDA driver: skip Taichi's noisy probe-and-fall-back
    wanted = {"auto": ti.cuda, "cpu": ti.cpu, "cuda": ti.cuda, "vulkan": ti.vulkan}[arch]
    if cheaper_frontend:  # a third less compile time for large kernels (False: scripts/frontend_cost.py)
        taichi_frontend.install()
    # The cache folder passed is Lantern's own within TI_OFFLINE_CACHE_FILE_PATH (default_cache_dir):
    # hidden from ti.init, which would warn on every start that the argument overrides it.
    cache_root = os.environ.pop(CACHE_PATH_VARIABLE, None)
    try:
        ti.init(arch=wanted, **kwargs)
    finally:
        if cache_root is not None:
            os.environ[CACHE_PATH_VARIABLE] = cache_root
    used = ti.lang.impl.current_cfg().arch
    if arch in ("cuda", "vulkan") and used != wanted:
        raise RuntimeError(f"arch '{arch}' is not available on this machine")
    return str(used).split(".")[-1]


def cpu_expected(arch: str) -> bool:
    """Whether `arch` (an --arch choice) will run on the CPU, as far as is known before ti.init:
    'cpu', or 'auto' without a CUDA driver (with one, 'auto' may still fall back to the CPU)."""
    return arch == "cpu" or (arch == "auto" and ctypes.util.find_library("cuda") is None)
