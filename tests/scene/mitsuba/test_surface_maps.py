"""Mitsuba 3's normalmap and bumpmap read into material specs (renderer/scene/mitsuba/
surface_maps.py), their device rows and the Features they compile; bad ones are one-line errors,
what Lantern does not read one warning each."""
from __future__ import annotations

import warnings

import numpy as np
import pytest
from PIL import Image

from renderer.materials.kinds import HEIGHT_MAP, NO_TEXTURE, SHADING_FRAME_MAP, TANGENT_SPACE_MAP
from renderer.mesh_world import prepare_mesh_scene
from renderer.scene.errors import SceneError
from renderer.scene.mitsuba import MitsubaSceneWarning, load_mitsuba_scene

DIFFUSE = '<bsdf type="diffuse"><rgb name="reflectance" value="0.4"/></bsdf>'


def load(tmp_path, bsdf: str, expect_warnings: int = 0):
    Image.fromarray(np.full((4, 4, 3), (128, 128, 255), np.uint8)).save(tmp_path / "flat.png")
    path = tmp_path / "s.xml"
    path.write_text(f'<scene version="3.0.0"><shape type="rectangle">{bsdf}</shape></scene>')
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = load_mitsuba_scene(path)
    messages = [str(w.message) for w in caught if issubclass(w.category, MitsubaSceneWarning)]
    assert len(messages) == expect_warnings, messages
    return scene, messages


def bitmap(name="", raw=True):
    named = f' name="{name}"' if name else ""
    return (f'<texture type="bitmap"{named}><string name="filename" value="flat.png"/>'
            f'<boolean name="raw" value="{str(raw).lower()}"/><string name="format" value="variant"/></texture>')


def test_a_normalmap_gives_the_inner_bsdf_its_raw_texture(tmp_path):
    scene, _ = load(tmp_path, f'<bsdf type="normalmap">{bitmap("normalmap")}{DIFFUSE}</bsdf>')
    (material,) = scene.materials
    assert material.kind == "diffuse" and material.base_color == (0.4, 0.4, 0.4)
    assert material.sidedness == "back_black"  # the inner BSDF's
    assert material.normal_map.file.name == "flat.png" and material.normal_map.srgb is False
    assert material.bump_map is None
    mesh = prepare_mesh_scene(scene)
    row = mesh.rows.rows[0]
    assert row["textures"][2] != NO_TEXTURE and row["normal_map_model"] == SHADING_FRAME_MAP
    features = mesh.features(scene)
    assert features.has_mapped_frames and not features.has_bump_maps and not features.has_normal_maps


def test_a_bumpmap_gives_its_height_texture_and_scale(tmp_path):
    scene, _ = load(tmp_path, f'<bsdf type="twosided"><bsdf type="bumpmap"><float name="scale" value="0.02"/>'
                              f'{bitmap("height")}{DIFFUSE}</bsdf></bsdf>')
    (material,) = scene.materials
    assert material.bump_map.file.name == "flat.png" and material.bump_scale == 0.02
    assert material.normal_map is None and material.sidedness == "two_sided"
    mesh = prepare_mesh_scene(scene)
    row = mesh.rows.rows[0]
    assert row["normal_map_model"] == HEIGHT_MAP and row["normal_scale"] == pytest.approx(0.02)
    features = mesh.features(scene)
    assert features.has_mapped_frames and features.has_bump_maps


def test_a_rawconstant_normal_is_one_value_everywhere(tmp_path):
    scene, _ = load(tmp_path, '<bsdf type="normalmap"><texture name="normalmap" type="rawconstant">'
                              f'<vector name="value" value="0.5, 0.5, 1.0"/></texture>{DIFFUSE}</bsdf>')
    texture = scene.materials[0].normal_map
    assert texture.kind == "checkerboard" and texture.nearest
    assert texture.color0 == texture.color1 == (0.5, 0.5, 1.0)


def test_a_scene_without_maps_compiles_none_of_their_code(tmp_path):
    scene, _ = load(tmp_path, DIFFUSE)
    mesh = prepare_mesh_scene(scene)
    assert mesh.rows.rows[0]["normal_map_model"] == TANGENT_SPACE_MAP
    features = mesh.features(scene)
    assert not (features.has_mapped_frames or features.has_bump_maps or features.has_normal_maps)


def test_what_lantern_does_not_read_is_one_warning_each(tmp_path):
    _, messages = load(tmp_path, f'<bsdf type="normalmap"><boolean name="use_shadowing_function" value="false"/>'
                                 f'{bitmap("normalmap")}{DIFFUSE}</bsdf>', expect_warnings=1)
    assert "use_shadowing_function = false is not supported" in messages[0]
    scene, messages = load(tmp_path, '<bsdf type="normalmap"><texture name="normalmap" type="volume"/>'
                                     f'{DIFFUSE}</bsdf>', expect_warnings=1)
    assert 'a <texture type="volume"> as its map is not supported yet' in messages[0]
    assert scene.materials[0].normal_map is None
    scene, messages = load(tmp_path, f'<bsdf type="normalmap">{bitmap("normalmap")}<bsdf type="bumpmap">'
                                     f'{bitmap()}{DIFFUSE}</bsdf></bsdf>', expect_warnings=1)
    assert "around another normal or bump map: only the outer normalmap is used" in messages[0]
    assert scene.materials[0].normal_map is not None and scene.materials[0].bump_map is None


@pytest.mark.parametrize("bsdf, message", [
    (f'<bsdf type="normalmap">{DIFFUSE}</bsdf>', 'needs a <texture name="normalmap">'),
    (f'<bsdf type="bumpmap">{DIFFUSE}</bsdf>', "needs exactly one nested <texture> (the height), not 0"),
    (f'<bsdf type="bumpmap">{bitmap()}{bitmap()}{DIFFUSE}</bsdf>', "needs exactly one nested <texture>"),
    (f'<bsdf type="bumpmap">{bitmap()}</bsdf>', "needs a nested <bsdf>"),
    ('<bsdf type="normalmap"><texture name="normalmap" type="rawconstant"><string name="value" value="up"/>'
     f'</texture>{DIFFUSE}</bsdf>', "'value' must be a number, <vector> or <rgb>"),
])
def test_bad_maps_are_one_line_errors_naming_the_line(tmp_path, bsdf, message):
    with pytest.raises(SceneError) as error:
        load(tmp_path, bsdf)
    text = str(error.value)
    assert message in text and "line 1" in text and "\n" not in text
