"""A TOML material's `normal_map` and `bump_map` (with `bump_scale`): image files read as data
into the material spec; both at once, in an SDF scene, or a file that is missing or not an image
are one-line errors. (Their rendering: tests/render/test_surface_maps_render.py.)"""
from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from renderer.scene.errors import SceneError
from tests.scene_builder import scene_from_toml

SCENE = """
[scene]
geometry = "{geometry}"
[materials.card]
{maps}
[[objects]]
type = "{shape}"
material = "card"
"""


def load(tmp_path, maps, geometry="mesh"):
    Image.fromarray(np.full((2, 2, 3), 200, np.uint8)).save(tmp_path / "map.png")
    shape = "quad" if geometry == "mesh" else "sphere"
    return scene_from_toml(tmp_path, SCENE.format(geometry=geometry, maps=maps, shape=shape))


def test_a_normal_map_is_an_image_read_as_data(tmp_path):
    (card,) = load(tmp_path, 'normal_map = "map.png"').materials
    assert card.normal_map.kind == "bitmap" and card.normal_map.srgb is False
    assert card.normal_map.file == (tmp_path / "map.png").resolve()
    assert card.bump_map is None


def test_a_bump_map_has_its_scale(tmp_path):
    (card,) = load(tmp_path, 'bump_map = "map.png"\nbump_scale = -0.05').materials
    assert card.bump_map.file.name == "map.png" and card.bump_scale == -0.05 and card.normal_map is None


@pytest.mark.parametrize("maps, geometry, message", [
    ('normal_map = "map.png"\nbump_map = "map.png"', "mesh", "`normal_map` and `bump_map` cannot be combined"),
    ('normal_map = "map.png"', "sdf", "materials.card.normal_map: only allowed in scenes with geometry 'mesh'"),
    ('bump_map = "map.txt"', "mesh", "materials.card.bump_map: unsupported image"),
    ('normal_map = "gone.png"', "mesh", "materials.card.normal_map: missing image file gone.png"),
])
def test_bad_maps_are_one_line_errors(tmp_path, maps, geometry, message):
    with pytest.raises(SceneError) as error:
        load(tmp_path, maps, geometry)
    assert message in str(error.value) and "\n" not in str(error.value)
