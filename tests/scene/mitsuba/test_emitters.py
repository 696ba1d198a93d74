"""Mitsuba 3 emitters read into Lantern's lights and emission (renderer/scene/mitsuba/emitters.py):
a spot's projected texture and orientation, the projector (irradiance texture or colour, scale,
fov along fov_axis or from focal_length, a scaled to_world), textured area emitters, the
envmap's orientation (any rotation, a mirror kept, scale or shear one warning), and one-line
errors or one warning for what is wrong or left out. (Their rendering:
tests/lights/test_projected_lights.py; point, spot and directional basics:
tests/scene/test_light_fields.py.)"""
from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from renderer.scene.description import EnvironmentSpec
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


# --- the envmap's orientation ----------------------------------------------------------------------

SKY = Path(__file__).resolve().parents[3] / "assets" / "envmaps" / "sky.exr"


def envmap(tmp_path, steps: str, expect_warnings: int = 0):
    body = (f'<emitter type="envmap"><string name="filename" value="{SKY}"/><float name="scale" value="2"/>'
            f'<transform name="to_world">{steps}</transform></emitter>')
    scene, messages = load(tmp_path, body, expect_warnings)
    assert scene.environment.kind == "map" and scene.environment.intensity == 2.0
    return scene.environment, messages


def turn(axis, degrees) -> np.ndarray:
    return EnvironmentSpec(rotation=degrees, rotation_axis=axis).rotation_matrix()


def test_an_envmap_turned_about_y_stays_an_azimuth_offset(tmp_path):
    """As before the full rotation existed: no matrix, so the same kernels; translation moves no
    direction (Mitsuba ignores it too)."""
    env, _ = envmap(tmp_path, '<rotate y="1" angle="-35"/><translate x="3" y="1"/>')
    assert env.to_world is None and env.rotation == pytest.approx(-35.0) and not env.needs_matrix


def test_an_envmap_takes_any_rotation_without_a_warning(tmp_path):
    """Steps compose as written (each after the ones before it), as in Mitsuba."""
    env, _ = envmap(tmp_path, '<rotate x="1" angle="30"/><rotate y="1" angle="20"/><rotate z="1" angle="-50"/>')
    expected = turn((0, 0, 1), -50.0) @ turn((0, 1, 0), 20.0) @ turn((1, 0, 0), 30.0)
    assert env.needs_matrix
    np.testing.assert_allclose(env.rotation_matrix(), expected, atol=1e-12)


def test_a_mirrored_envmap_keeps_its_mirror(tmp_path):
    """Mitsuba looks a direction up at to_world^-1 d, a mirror included: so does Lantern."""
    env, _ = envmap(tmp_path, '<scale x="-1"/><rotate x="1" angle="25"/>')
    np.testing.assert_allclose(env.rotation_matrix(), turn((1, 0, 0), 25.0) @ np.diag([-1.0, 1.0, 1.0]), atol=1e-12)
    assert np.linalg.det(env.rotation_matrix()) == pytest.approx(-1.0)


@pytest.mark.parametrize("steps, kept", [
    ('<scale x="2" y="1" z="0.5"/><rotate x="1" angle="40"/>', turn((1, 0, 0), 40.0)),
    ('<scale value="3"/><rotate y="1" angle="10"/>', None),  # uniform: still a turn about +y, kept as one
    ('<matrix value="1 0.3 0 0  0 1 0 0  0 0 1 0  0 0 0 1"/>', "polar"),  # a shear
])
def test_a_scaled_or_sheared_envmap_is_one_warning_and_keeps_its_rotation(tmp_path, steps, kept):
    env, messages = envmap(tmp_path, steps, expect_warnings=1)
    assert messages[0].startswith(f"{tmp_path / 's.xml'}: line 2: <emitter type=\"envmap\">: its to_world scales "
                                  "or shears"), messages
    if kept is None:
        assert env.to_world is None and env.rotation == pytest.approx(10.0)
        return
    m = env.rotation_matrix()
    np.testing.assert_allclose(m @ m.T, np.eye(3), atol=1e-12)
    if isinstance(kept, str):  # the rotation nearest the shear: its polar factor, a turn about z
        shear = np.array([[1.0, 0.3, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
        np.testing.assert_allclose(m.T @ shear, (m.T @ shear).T, atol=1e-12)  # the rest is symmetric
        assert np.all(np.linalg.eigvalsh(m.T @ shear) > 0.0) and m[2, 2] == pytest.approx(1.0)
    else:
        np.testing.assert_allclose(m, kept, atol=1e-12)


def test_a_singular_envmap_to_world_is_a_one_line_error(tmp_path):
    with pytest.raises(SceneError) as error:
        envmap(tmp_path, '<scale x="0"/>')
    assert "its to_world is singular" in str(error.value) and "\n" not in str(error.value)
