"""`bench scenes`: finding scene folders and their references, the bench's size and the reduction
of a reference to it, exactly; the run itself on a scene folder written here."""
from __future__ import annotations

import numpy as np
import pytest

from renderer.bench.scenes import bench_size, comparable_reference, find_scenes, reduce_to


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


def test_a_non_finite_reference_pixel_leaves_its_neighbourhood_out_of_both_means():
    reference = np.ones((90, 160, 3))
    reference[42, 75] = (np.inf, 5e4, 1e4)  # a half-float overflow where a small light is seen
    reference[43, 74] = 4e4  # the same light, finite, in the bench pixel beside it
    reduced, kept = comparable_reference(reference, (16, 9))
    assert np.isfinite(reduced).all() and kept.shape == (9, 16)
    assert not kept[3:6, 6:9].any() and kept.sum() == 16 * 9 - 9  # the overflow's block and its 8 neighbours
    assert np.allclose(reduced[kept], 1.0)  # what stays is untouched by the light
    _, everything = comparable_reference(np.ones((90, 160, 3)), (16, 9))
    assert everything.all()


def test_the_mitsuba_side_renders_what_converts_and_says_why_not_otherwise(tmp_path):
    """`bench scenes --mitsuba` on two small pbrt-v4 scenes: a diffuse room converts and Mitsuba's
    figures sit beside Lantern's; a coated sphere (pbrt's layered BSDF, which Mitsuba lacks) is a note."""
    pytest.importorskip("mitsuba", reason="--mitsuba needs the optional mitsuba package")
    import json

    from renderer.bench.scenes import run
    from tests.commands.test_compare import PBRT_ROOM

    for name, text in (("room", PBRT_ROOM),
                       ("coated", PBRT_ROOM.replace('Material "diffuse" "rgb reflectance" [0.2 0.5 0.8]',
                                                    'Material "coateddiffuse"'))):
        folder = tmp_path / "data" / name / "pbrt"
        folder.mkdir(parents=True)
        (folder / "scene-v4.pbrt").write_text(text)
    assert run(quick=True, out_dir=tmp_path / "out", data=tmp_path / "data", seconds=0.2, mitsuba=True) == 0
    rows = {r["scene"]: r for r in json.loads((tmp_path / "out" / "bench_scenes.json").read_text())["results"]}
    room, coated = rows["room"], rows["coated"]
    assert room["mitsuba_spp"] > 0 and all(v > 0 for v in room["mitsuba_to_lantern_rgb"])
    assert "mitsuba_spp" not in coated and "coated" in coated["mitsuba_note"]
