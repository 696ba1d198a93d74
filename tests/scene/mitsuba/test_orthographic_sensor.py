"""Mitsuba's orthographic sensor as Lantern's orthographic camera: its to_world's scale is the view's
extent (Mitsuba's view spans 2 x-scales across the image and 2 y-scales / aspect up it, which
Mitsuba 3.9.1 renders so: a 1 x 0.5 rectangle under scale 2 covers 10 of 40 columns and 5 of 20
rows); unequal x and y scales are one warning."""
from __future__ import annotations

import pytest

from tests.scene.mitsuba.test_scene_builder import SHAPE, load


def sensor(scale: str, width: int = 40, height: int = 20) -> str:
    return f'''<sensor type="orthographic"><transform name="to_world"><scale {scale}/>
        <lookat origin="0, 0, -5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="{width}"/><integer name="height" value="{height}"/></film>
        </sensor>'''


@pytest.mark.parametrize("scale, height", [('value="2"', 2.0), ('value="1"', 1.0), ('x="1.5" y="1.5"', 1.5)])
def test_the_view_height_is_two_y_scales_over_the_aspect(tmp_path, scale, height):
    scene, _ = load(tmp_path, sensor(scale) + SHAPE)
    camera = scene.camera
    assert camera.projection == "orthographic"
    assert camera.ortho_height == pytest.approx(height)  # 2 * scale_y * 20 / 40
    assert camera.position == (0.0, 0.0, -5.0) and camera.look_at == pytest.approx((0.0, 0.0, -4.0))


def test_unequal_scales_are_one_warning_keeping_the_height(tmp_path):
    scene, messages = load(tmp_path, sensor('x="2" y="1"') + SHAPE, expect_warnings=1)
    assert "scales x and y differently" in messages[0]
    assert scene.camera.ortho_height == pytest.approx(1.0)


def test_a_perspective_sensor_stays_perspective(tmp_path):
    scene, _ = load(tmp_path, '<sensor type="perspective"><float name="fov" value="40"/></sensor>' + SHAPE)
    assert scene.camera.projection == "perspective"
