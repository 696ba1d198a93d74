"""Mitsuba 3 emitters read into Lantern's lights and emission (renderer/scene/mitsuba/emitters.py):
a spot's projected texture and orientation, the projector (irradiance texture or colour, scale,
fov along fov_axis or from focal_length, a scaled to_world), textured area emitters, and
one-line errors or one warning for what is wrong or left out. (Their rendering:
tests/lights/test_projected_lights.py; point, spot and directional basics:
tests/scene/test_light_fields.py.)"""
from __future__ import annotations

import math
import warnings

import pytest
from PIL import Image

from renderer.scene.errors import SceneError
from renderer.scene.mitsuba import MitsubaSceneWarning, load_mitsuba_scene

SHAPE = '<shape type="sphere"><bsdf type="diffuse"/></shape>'
LOOK_DOWN = '<transform name="to_world"><lookat origin="0, 2, 0" target="0, 0, 0" up="0, 0, 1"/></transform>'


def load(tmp_path, body: str, expect_warnings: int = 0):
    Image.new("RGB", (6, 3), (200, 100, 50)).save(tmp_path / "slide.png")
    path = tmp_path / "s.xml"
    path.write_text(f'<scene version="3.0.0">\n{body}\n{SHAPE}\n</scene>\n')
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = load_mitsuba_scene(path)
    messages = [str(w.message) for w in caught if issubclass(w.category, MitsubaSceneWarning)]
    assert len(messages) == expect_warnings, messages
    return scene, messages


SLIDE = '<texture name="irradiance" type="bitmap"><string name="filename" value="slide.png"/></texture>'


def test_a_textured_projector(tmp_path):
    scene, _ = load(tmp_path, f'<emitter type="projector">{SLIDE}<float name="scale" value="15"/>'
                              f'<float name="fov" value="30"/><string name="fov_axis" value="y"/>{LOOK_DOWN}</emitter>')
    (light,) = scene.lights
    assert light.kind == "projector" and light.texture.file == tmp_path / "slide.png"
    assert light.irradiance == (15.0, 15.0, 15.0)  # scale multiplies the image
    assert (light.fov, light.fov_axis) == (30.0, "y")
    assert light.position == (0.0, 2.0, 0.0)
    assert light.direction == pytest.approx((0.0, -1.0, 0.0)) and light.up == pytest.approx((0.0, 0.0, 1.0))


def test_a_constant_projector_and_its_default_field_of_view(tmp_path):
    scene, _ = load(tmp_path, f'<emitter type="projector"><rgb name="irradiance" value="0.5, 1, 2"/>{LOOK_DOWN}'
                              '</emitter>')
    (light,) = scene.lights
    assert light.texture is None and light.irradiance == (0.5, 1.0, 2.0)
    # Mitsuba's default: a 50 mm lens on 35 mm film, the angle spanning the image's diagonal.
    assert light.fov_axis == "diagonal"
    assert light.fov == pytest.approx(math.degrees(2 * math.atan(math.hypot(36, 24) / 100)))


def test_a_scaled_projector_is_brighter_as_in_mitsuba(tmp_path):
    """Mitsuba divides by the depth in its scaled frame squared but by the scaled axis once: a
    projector scaled by s lights s times as brightly (checked against Mitsuba 3.9's render)."""
    scene, _ = load(tmp_path, '<emitter type="projector"><rgb name="irradiance" value="1"/><transform name="to_world">'
                              '<scale value="2"/><lookat origin="0, 2, 0" target="0, 0, 0" up="0, 0, 1"/></transform>'
                              '</emitter>')
    assert scene.lights[0].irradiance == pytest.approx((2.0, 2.0, 2.0))


def test_a_textured_area_emitter(tmp_path):
    scene, _ = load(tmp_path, '<shape type="rectangle"><emitter type="area"><texture name="radiance" type="bitmap">'
                              '<string name="filename" value="slide.png"/></texture></emitter></shape>')
    (lamp,) = [m for m in scene.materials if m.is_emissive]
    assert lamp.emission == (1.0, 1.0, 1.0) and lamp.emission_texture.file == tmp_path / "slide.png"
    assert lamp.textures["emission"] is lamp.emission_texture


@pytest.mark.parametrize("body, message", [
    (f'<emitter type="projector">{LOOK_DOWN}</emitter>', "needs an irradiance (a texture or a colour)"),
    (f'<emitter type="projector">{SLIDE}<float name="fov" value="180"/></emitter>',
     "fov 180 is not between 0 and 180 degrees"),
    (f'<emitter type="projector">{SLIDE}<float name="fov" value="40"/><string name="fov_axis" value="z"/></emitter>',
     "fov_axis 'z' (x, y, diagonal, smaller, larger)"),
    (f'<emitter type="projector">{SLIDE}<float name="fov" value="40"/><string name="focal_length" value="20mm"/>'
     '</emitter>', "give fov or focal_length, not both"),
    (f'<emitter type="projector">{SLIDE}<transform name="to_world"><scale value="0"/></transform></emitter>',
     "its to_world gives no direction (a zero vector)"),
])
def test_bad_projectors_are_one_line_errors(tmp_path, body, message):
    with pytest.raises(SceneError) as error:
        load(tmp_path, body)
    assert message in str(error.value) and "\n" not in str(error.value)
    assert str(error.value).startswith(f"{tmp_path / 's.xml'}: line ")


def test_what_cannot_be_projected_is_one_warning(tmp_path):
    scene, messages = load(tmp_path, '<emitter type="spot"><texture name="texture" type="mesh_attribute">'
                                     '<string name="name" value="vertex_color"/></texture></emitter>',
                           expect_warnings=1)
    assert scene.lights[0].texture is None
    assert '<emitter type="spot">: a <texture type="mesh_attribute"> on \'texture\' is not supported' in messages[0]
    scene, messages = load(tmp_path, '<emitter type="spot"><float name="cutoff_angle" value="100"/>'
                                     '<float name="beam_width" value="50"/><texture name="texture" type="bitmap">'
                                     '<string name="filename" value="slide.png"/></texture></emitter>',
                           expect_warnings=1)
    assert scene.lights[0].texture is None and "maps nowhere" in messages[0]
