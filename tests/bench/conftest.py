import pytest

from tests.scene_builder import tiny_bench_toml


@pytest.fixture
def tiny_scene(tmp_path):
    """tiny.toml: the benchmarks' tiny SDF scene (a white ball on a white plane under a sky)."""
    path = tmp_path / "tiny.toml"
    path.write_text(tiny_bench_toml("tiny"))
    return path
