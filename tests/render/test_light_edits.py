"""Edits of lights without a surface (point, spot, directional) in a rendering Renderer: values,
places, directions and cones taken in place are the edited scene's image bit for bit from the same
programs (nothing compiles); a light turned off needs the lights built again and changes nothing."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from renderer.camera import CameraFrame
from renderer.renderer import Renderer
from renderer.scene import load_scene
from tests.render.test_material_edits import kernels_compiled

SIZE = (16, 16)
LAMPS = """
[scene]
geometry = "mesh"
[camera]
position = [0, 1.5, 4]
look_at = [0, 0.3, 0]
fov = 50
[environment]
type = "constant"
color = [0.02, 0.02, 0.02]
[materials.floor]
base_color = [0.7, 0.7, 0.7]
[materials.ball]
base_color = [0.8, 0.3, 0.2]
[[objects]]
type = "quad"
material = "floor"
size = [8, 8]
[[objects]]
type = "sphere"
material = "ball"
translate = [0, 0.5, 0]
radius = 0.5
[[lights]]
type = "point"
position = [1.5, 2, 1]
intensity = [4, 4, 4]
[[lights]]
type = "spot"
position = [-1, 3, 0]
direction = [0.3, -1, 0]
intensity = [20, 18, 15]
cutoff_angle = 30
[[lights]]
type = "directional"
direction = [0.2, -1, -0.3]
irradiance = [0.5, 0.5, 0.6]
"""


@pytest.fixture
def lamps(tmp_path):
    path = tmp_path / "lamps.toml"
    path.write_text(LAMPS)
    return load_scene(path)


def render(renderer, scene):
    renderer.render(CameraFrame.from_spec(scene.camera), 2, "mis", seed=4)
    return renderer.image()


def test_light_edits_are_the_edited_scenes_image_and_compile_nothing(lamps):
    renderer = Renderer(lamps, max_size=SIZE)
    before = render(renderer, lamps)
    compiled, programs = kernels_compiled(), dict(renderer._programs)
    point, spot, sun = lamps.lights
    edited = (replace(point, intensity=(12.0, 6.0, 2.0), position=(1.0, 1.5, 1.5)),
              replace(spot, direction=(0.0, -1.0, 0.2), cutoff_angle=45.0, beam_width=10.0),
              replace(sun, irradiance=(1.5, 1.0, 0.5)))
    assert renderer.edit_lights(edited)
    after = render(renderer, replace(lamps, lights=edited))
    assert kernels_compiled() == compiled and renderer._programs == programs
    assert not np.array_equal(before, after)
    expected = replace(lamps, lights=edited)
    np.testing.assert_array_equal(after, render(Renderer(expected, max_size=SIZE), expected))


def test_a_light_turned_off_needs_the_lights_built_again(lamps):
    renderer = Renderer(lamps, max_size=SIZE)
    render(renderer, lamps)
    off = (replace(lamps.lights[0], intensity=(0.0, 0.0, 0.0)),) + lamps.lights[1:]
    assert not renderer.edit_lights(off) and renderer.scene is lamps
    assert not renderer.edit_lights(lamps.lights[:2])  # another list
