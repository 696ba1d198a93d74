import pytest
import taichi as ti

from renderer.runtime import taichi_frontend
from renderer.runtime.arch import cpu_scheduling_options, offline_cache_options, taichi_options


@pytest.fixture(scope="module", autouse=True)
def taichi_runtime():
    """A fresh Taichi runtime per test module (never at import time).

    Every field a test allocates lives until the runtime is reset, and one runtime holds a bounded
    number of field trees: a whole suite in one runtime exhausts it (a crash inside Taichi). A reset
    per module frees them; compiled kernels come back from the offline cache. Kernels are
    optimised for compile time: a clean checkout compiles every kernel of the suite afresh.
    """
    taichi_frontend.install()  # as init_taichi does: cheaper compiles
    ti.init(arch=ti.cpu, random_seed=0, **offline_cache_options(), **taichi_options("compile"),
            **cpu_scheduling_options())
    yield
    ti.reset()


# The longest test files run first. Whole files go to a worker (--dist loadfile) in collection
# order, and tests/viewer comes last alphabetically: its offscreen window file (every catalog scene
# compiled) then ran alone at the end while the other core idled. Longest first shortens the run.
LONGEST_FILES = (  # a cold run's order (clean offline cache, as in CI)
    "tests/commands/distributed/test_ray_render.py",
    "tests/packets/test_packet_shading.py",
    "tests/viewer/test_window_offscreen.py",
    "tests/render/test_glass_furnace.py",
    "tests/render/test_integrator_agreement.py",
    "tests/test_vulkan.py",
    "tests/materials/test_bsdf_chi2.py",
    "tests/render/test_sppm.py",
    "tests/geometry/test_wide_bvh.py",
    "tests/geometry/test_traversal.py",
)


def pytest_collection_modifyitems(items):
    rank = {path: i for i, path in enumerate(LONGEST_FILES)}
    # A stable sort: the other files, and the tests within every file, keep their order.
    items.sort(key=lambda item: rank.get(item.nodeid.split("::")[0], len(rank)))
