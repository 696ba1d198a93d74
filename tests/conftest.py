import pytest
import taichi as ti

from renderer.arch import taichi_options


@pytest.fixture(scope="module", autouse=True)
def taichi_runtime():
    """A fresh Taichi runtime per test module (never at import time).

    Every field a test allocates lives until the runtime is reset, and one runtime holds a bounded
    number of field trees: a whole suite in one runtime exhausts it (a crash inside Taichi). A reset
    per module frees them; compiled kernels come back from the offline cache. Kernels are
    optimised for compile time: a clean checkout compiles every kernel of the suite afresh.
    """
    ti.init(arch=ti.cpu, random_seed=0, offline_cache=True, **taichi_options("compile"))
    yield
    ti.reset()
