"""Point, spot, directional and projector lights in scene files: the `[[lights]]` section of the TOML
format (schema, loader, one-line errors) and the Mitsuba 3 reader's point, spot and directional
emitters. (Their rendering is tests/lights/test_delta_lights.py and test_projected_lights.py; the
reader's spot textures and projectors tests/scene/mitsuba/test_emitters.py.)"""
from __future__ import annotations

import dataclasses
import warnings

import pytest

from renderer.scene import load_scene, schema
from renderer.scene.description import LIGHT_KINDS, LightSpec
from renderer.scene.errors import SceneError
from renderer.scene.features import scene_features
from renderer.scene.mitsuba import MitsubaSceneWarning, load_mitsuba_scene

HEAD = """
[scene]
geometry = "sdf"
[materials.white]
[[objects]]
type = "plane"
material = "white"
"""

LIGHTS = """
[[lights]]
type = "point"
position = [1, 2, 3]
intensity = [4, 5, 6]
[[lights]]
type = "spot"
position = [0, 3, 0]
direction = [0, -2, 0]
cutoff_angle = 40
[[lights]]
type = "directional"
direction = [3, -4, 0]
irradiance = [0.5, 0.5, 0.5]
[[lights]]
type = "projector"
position = [0, 2, 0]
direction = [0, -1, 0]
up = [0, 0, 1]
fov = 30
fov_axis = "diagonal"
"""


def write(tmp_path, body: str):
    path = tmp_path / "s.toml"
    path.write_text(HEAD + body)
    return path


def test_lights_load(tmp_path):
    scene = load_scene(write(tmp_path, LIGHTS))
    point, spot, sun, projector = scene.lights
    assert point == LightSpec("point", position=(1.0, 2.0, 3.0), intensity=(4.0, 5.0, 6.0))
    assert (spot.kind, spot.position, spot.direction) == ("spot", (0.0, 3.0, 0.0), (0.0, -1.0, 0.0))
    assert spot.cutoff_angle == 40.0 and spot.beam_width is None and spot.beam == 30.0  # Mitsuba's 3/4
    assert sun.kind == "directional" and sun.irradiance == (0.5, 0.5, 0.5)
    assert sun.direction == pytest.approx((0.6, -0.8, 0.0))  # normalised
    assert projector == LightSpec("projector", position=(0.0, 2.0, 0.0), direction=(0.0, -1.0, 0.0),
                                  up=(0.0, 0.0, 1.0), fov=30.0, fov_axis="diagonal")
    assert scene_features(scene).light_kinds == frozenset(LIGHT_KINDS)
    assert load_scene(write(tmp_path, "")).lights == ()
    assert scene_features(load_scene(write(tmp_path, ""))).light_kinds == frozenset()


@pytest.mark.parametrize("body, message", [
    ('type = "lamp"', "lights[0].type: unknown value 'lamp' (allowed: point, spot, directional, projector)"),
    ('type = "point"', "lights[0]: missing required field 'position'"),
    ('type = "directional"', "lights[0]: missing required field 'direction'"),
    ('type = "point"\nposition = [0, 1, 0]\nirradiance = [1, 1, 1]',
     "lights[0].irradiance: only allowed with type 'directional' or 'projector', not 'point'"),
    ('type = "directional"\ndirection = [0, -1, 0]\nposition = [0, 1, 0]',
     "lights[0].position: only allowed with type 'point' or 'spot' or 'projector', not 'directional'"),
    ('type = "directional"\ndirection = [0, 0, 0]', "lights[0].direction: must not be the zero vector"),
    ('type = "point"\nposition = [0, 1]', "lights[0].position: expected 3 numbers, got 2"),
    ('type = "point"\nposition = [0, 1, 0]\nintensity = [1, -1, 1]',
     "lights[0].intensity[1]: -1 is out of range (allowed: >= 0)"),
    ('type = "spot"\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\ncutoff_angle = 180',
     "lights[0].cutoff_angle: 180 is out of range (allowed: (0, 180))"),
    ('type = "spot"\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\ncutoff_angle = 10\nbeam_width = 20',
     "lights[0]: beam_width 20 is larger than cutoff_angle 10 (the full beam lies within the cutoff)"),
    ('type = "projector"\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\nup = [0, 0, 1]\ntexture = "image.gif"',
     "lights[0].texture: unsupported image extension '.gif' (expected .png, .jpg, .jpeg, .bmp, .tga, .tif, .tiff, "
     ".webp or .exr)"),
    ('type = "spot"\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\nup = [0, 0, 1]\ntexture = "missing.png"',
     "lights[0].texture: missing image file missing.png (looked for {folder}/missing.png)"),
    ('type = "projector"\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\nfov_axis = "z"',
     "lights[0].fov_axis: unknown value 'z' (allowed: x, y, diagonal, smaller, larger)"),
    ('type = "point"\nposition = [0, 1, 0]\ncolour = [1, 1, 1]',
     "lights[0]: unknown field 'colour' (allowed: type, position, intensity)"),
])
def test_bad_light_fields_are_one_line_errors(tmp_path, body, message):
    path = write(tmp_path, "[[lights]]\n" + body + "\n")
    with pytest.raises(SceneError) as error:
        load_scene(path)
    assert str(error.value) == f"{path}: {message.format(folder=tmp_path)}"
    assert "\n" not in str(error.value)


def test_a_projected_image_needs_an_up_across_the_axis(tmp_path):
    from PIL import Image

    Image.new("RGB", (4, 2), (200, 100, 50)).save(tmp_path / "slide.png")
    body = '[[lights]]\ntype = "projector"\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\ntexture = "slide.png"\n'
    path = write(tmp_path, body)
    with pytest.raises(SceneError) as error:
        load_scene(path)
    assert str(error.value) == (f"{path}: lights[0]: up is zero or parallel to direction, which leaves the projected "
                                "image's orientation undefined")
    (light,) = load_scene(write(tmp_path, body + "up = [0, 0, -1]\n")).lights
    assert light.texture.file == (tmp_path / "slide.png").resolve() and light.texture.srgb
    assert scene_features(load_scene(write(tmp_path, body + "up = [0, 0, -1]\n"))).has_light_textures
    assert not scene_features(load_scene(write(tmp_path, LIGHTS))).has_light_textures


def test_lights_must_be_an_array_of_tables(tmp_path):
    path = write(tmp_path, '[lights]\ntype = "point"\n')
    with pytest.raises(SceneError, match=r"lights: expected an array of tables, got table$"):
        load_scene(path)


def test_schema_matches_the_model():
    model = {f.name: f.default for f in dataclasses.fields(LightSpec) if f.default is not dataclasses.MISSING}
    covered = set()
    for field in schema.LIGHT.fields:
        covered.add(field.model_attr)
        if not field.required:
            assert field.default == model[field.model_attr], field.name
    assert covered == {f.name for f in dataclasses.fields(LightSpec)}
    assert schema.LIGHT.field("type").choices == LIGHT_KINDS
    assert "lights" in schema.TOP_LEVEL and schema.LIGHT in schema.SECTIONS


# --- the Mitsuba 3 reader -----------------------------------------------------------------------

SHAPE = '<shape type="sphere"><bsdf type="diffuse"/></shape>'


def mitsuba(tmp_path, body: str, expect_warnings: int = 0):
    path = tmp_path / "s.xml"
    path.write_text(f'<scene version="3.0.0">\n{body}\n{SHAPE}\n</scene>\n')
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = load_mitsuba_scene(path)
    messages = [str(w.message) for w in caught if issubclass(w.category, MitsubaSceneWarning)]
    assert len(messages) == expect_warnings, messages
    return scene, messages


def test_mitsuba_point_light(tmp_path):
    scene, _ = mitsuba(tmp_path, '''<emitter type="point"><point name="position" x="-4" y="0" z="6"/>
        <rgb name="intensity" value="300"/></emitter>
        <emitter type="point"><transform name="to_world"><translate x="1" y="2" z="3"/></transform></emitter>''')
    assert scene.lights == (LightSpec("point", position=(-4.0, 0.0, 6.0), intensity=(300.0,) * 3),
                            LightSpec("point", position=(1.0, 2.0, 3.0), intensity=(1.0,) * 3))


def test_mitsuba_spot_light(tmp_path):
    from PIL import Image

    Image.new("RGB", (4, 4), (10, 20, 30)).save(tmp_path / "x.png")
    scene, _ = mitsuba(tmp_path, '''<emitter type="spot"><rgb name="intensity" value="5, 4, 3"/>
        <float name="cutoff_angle" value="30"/>
        <texture name="texture" type="bitmap"><string name="filename" value="x.png"/></texture>
        <transform name="to_world"><lookat origin="1, 1, 1" target="1, 2, 1" up="0, 0, 1"/></transform>
        </emitter>''')
    (spot,) = scene.lights
    assert (spot.kind, spot.position, spot.intensity) == ("spot", (1.0, 1.0, 1.0), (5.0, 4.0, 3.0))
    assert spot.direction == pytest.approx((0.0, 1.0, 0.0))  # local +z: towards the lookat target
    assert spot.up == pytest.approx((0.0, 0.0, 1.0))  # local +y: the lookat's up, which orients the image
    assert spot.cutoff_angle == 30.0 and spot.beam == 22.5  # Mitsuba's default beam: 3/4 of the cutoff
    assert spot.texture.file == tmp_path / "x.png" and spot.texture.srgb
    scene, _ = mitsuba(tmp_path, '<emitter type="spot"/>')
    assert scene.lights == (LightSpec("spot", direction=(0.0, 0.0, 1.0), cutoff_angle=20.0, beam_width=15.0),)


def test_mitsuba_directional_light(tmp_path):
    scene, _ = mitsuba(tmp_path, '''<emitter type="directional"><vector name="direction" value="0, 0, -2"/>
        <rgb name="irradiance" value="2"/></emitter>
        <emitter type="directional"><transform name="to_world"><rotate x="1" angle="90"/></transform></emitter>''')
    a, b = scene.lights
    assert a == LightSpec("directional", direction=(0.0, 0.0, -1.0), irradiance=(2.0,) * 3)
    # Rotating local +z by 90 degrees about +x gives -y.
    assert b.kind == "directional" and b.direction == pytest.approx((0.0, -1.0, 0.0), abs=1e-12)


def test_mitsuba_light_spectra_are_emission(tmp_path):
    from renderer.spectral.mitsuba_rgb import spectrum_to_rgb

    spectrum = "400:0, 500:8, 600:15.6, 700:18.4"
    scene, _ = mitsuba(tmp_path, f'<emitter type="point"><spectrum name="intensity" value="{spectrum}"/></emitter>')
    expected = spectrum_to_rgb((400, 500, 600, 700), (0.0, 8.0, 15.6, 18.4), bounded=False, d65=False)
    assert scene.lights[0].intensity == pytest.approx(expected)


@pytest.mark.parametrize("body, message", [
    ('<emitter type="point"><point name="position" x="1"/><transform name="to_world"><translate x="1"/>'
     '</transform></emitter>', "give position or to_world, not both"),
    ('<emitter type="directional"><vector name="direction" value="0, 0, 0"/></emitter>',
     "its direction gives no direction (a zero vector)"),
    ('<emitter type="spot"><float name="cutoff_angle" value="10"/><float name="beam_width" value="12"/></emitter>',
     "beam_width 12 is not between 0 and cutoff_angle 10"),
])
def test_mitsuba_bad_lights_are_one_line_errors(tmp_path, body, message):
    with pytest.raises(SceneError) as error:
        mitsuba(tmp_path, body)
    assert message in str(error.value) and "\n" not in str(error.value)
    assert str(error.value).startswith(str(tmp_path / "s.xml"))


def test_mitsuba_unknown_emitters_are_left_out(tmp_path):
    scene, messages = mitsuba(tmp_path, '<emitter type="sunsky"/>', expect_warnings=1)
    assert scene.lights == () and "this emitter type is not supported yet and is left out" in messages[0]


def test_sppm_refuses_delta_lights(tmp_path):
    from renderer.renderer import Renderer

    renderer = Renderer(load_scene(write(tmp_path, LIGHTS)), (8, 8))
    with pytest.raises(ValueError, match="^sppm: point, spot and directional lights emit no photons yet"):
        renderer.program("sppm", renderer.features())
