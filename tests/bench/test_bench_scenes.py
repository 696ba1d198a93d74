"""`bench scenes`: finding scene folders and their references, the bench's size and the reduction
of a reference to it, exactly; the run itself on a scene folder written here."""
from __future__ import annotations

import numpy as np
import pytest

from renderer.bench.scenes import bench_size, find_scenes, reduce_to


def test_scene_folders_are_found_with_their_references(tmp_path):
    (tmp_path / "a" / "pbrt").mkdir(parents=True)
    (tmp_path / "a" / "pbrt" / "scene-v4.pbrt").write_text("")
    (tmp_path / "a" / "pbrt" / "other.pbrt").write_text("")
    (tmp_path / "a" / "pbrt" / "TungstenRender.exr").write_bytes(b"")
    (tmp_path / "b").mkdir()
    (tmp_path / "b" / "x.pbrt").write_text("")
    (tmp_path / "c").mkdir()  # no scene file: not a scene
    found = find_scenes(tmp_path)
    assert [(n, p.name, r.name if r else None) for n, p, r in found] == [
        ("a", "scene-v4.pbrt", "TungstenRender.exr"), ("b", "x.pbrt", None)]


@pytest.mark.parametrize("size, long_side, expected", [((1280, 720), 160, (160, 90)), ((512, 512), 64, (64, 64)),
                                                       ((100, 2000), 160, (8, 160))])
def test_the_bench_keeps_the_scenes_aspect(size, long_side, expected):
    assert bench_size(size, long_side) == expected


def test_a_reference_is_reduced_by_block_means_that_keep_its_mean():
    rng = np.random.default_rng(1)
    image = rng.random((90, 160, 3))
    small = reduce_to(image, (16, 9))
    assert small.shape == (9, 16, 3)
    assert np.allclose(small[0, 0], image[:10, :10].mean(axis=(0, 1)))
    assert np.allclose(small.mean(axis=(0, 1)), image.mean(axis=(0, 1)))  # equal blocks: the mean is kept
