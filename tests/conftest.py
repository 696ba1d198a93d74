import pytest
import taichi as ti


@pytest.fixture(scope="session", autouse=True)
def taichi_runtime():
    """Initialise Taichi once per test session (never at import time)."""
    ti.init(arch=ti.cpu, random_seed=0, offline_cache=True)
    yield
