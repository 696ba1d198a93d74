"""Mitsuba's heterogeneous medium (renderer/scene/mitsuba/media.py): gridvolumes, constvolumes and
plain values become grid specs placed where Mitsuba places them, scale and filters carry over, the
scene compiles its grid code, and bad input is one line or one warning."""
from __future__ import annotations

import numpy as np
import pytest

from renderer.scene.errors import SceneError
from renderer.scene.features import scene_grid_media
from renderer.scene.vol_files import write_vol
from tests.scene.mitsuba.test_scene_builder import load

SHAPE = '<shape type="cube"><bsdf type="null"/><ref name="interior" id="smoke"/></shape>'
PLACE = '<transform name="to_world"><scale value="2"/><translate x="-1" y="-1" z="-1"/></transform>'


def smoke(tmp_path, inner: str, expect_warnings: int = 0):
    scene, messages = load(tmp_path, f'<medium type="heterogeneous" id="smoke">{inner}</medium>{SHAPE}',
                           expect_warnings)
    (medium,) = scene.media
    return scene, medium, messages


def test_gridvolumes_map_onto_a_grid_medium(tmp_path):
    density = np.random.default_rng(1).random((2, 3, 4)).astype(np.float32)
    write_vol(tmp_path / "d.vol", density, bounds=((5, 5, 5), (6, 7, 8)))  # the box is Mitsuba's only with use_grid_bbox
    write_vol(tmp_path / "a.vol", np.full((1, 1, 2, 3), 0.5, np.float32))
    scene, medium, _ = smoke(tmp_path, f'''<float name="scale" value="4"/>
        <volume name="sigma_t" type="gridvolume"><string name="filename" value="d.vol"/>{PLACE}</volume>
        <volume name="albedo" type="gridvolume"><string name="filename" value="a.vol"/>
            <string name="filter_type" value="nearest"/></volume>
        <phase type="hg"><float name="g" value="0.4"/></phase>''')
    assert (medium.kind, medium.scale, medium.g) == ("grid", 4.0, 0.4)
    assert medium.sigma_a == medium.sigma_s == (0.0, 0.0, 0.0)  # the homogeneous row adds nothing
    np.testing.assert_array_equal(medium.density.values[..., 0], density)
    np.testing.assert_allclose(medium.density.to_world, [[2, 0, 0, -1], [0, 2, 0, -1], [0, 0, 2, -1], [0, 0, 0, 1]])
    assert medium.density.file == tmp_path / "d.vol" and not medium.density.nearest
    assert medium.albedo.nearest and medium.albedo.values.shape == (1, 1, 2, 3)
    assert scene_grid_media(scene)


def test_use_grid_bbox_places_the_file_box_first(tmp_path):
    write_vol(tmp_path / "d.vol", np.ones((1, 1, 1)), bounds=((1, 2, 3), (2, 4, 7)))
    _, medium, _ = smoke(tmp_path, '''<volume name="sigma_t" type="gridvolume">
        <string name="filename" value="d.vol"/><boolean name="use_grid_bbox" value="true"/>
        <transform name="to_world"><translate x="10"/></transform></volume>''')
    np.testing.assert_allclose(medium.density.to_world, [[1, 0, 0, 11], [0, 2, 0, 2], [0, 0, 4, 3], [0, 0, 0, 1]])


def test_constants_fill_their_unit_cube(tmp_path):
    """A constvolume lives in its to_world's unit cube; a plain value in [0, 1]^3 (Mitsuba's box)."""
    _, medium, _ = smoke(tmp_path, f'''<volume name="sigma_t" type="constvolume"><rgb name="value" value="0.5, 0.4, 0.3"/>
        {PLACE}</volume><float name="albedo" value="0.2"/>''')
    assert medium.density.constant == (0.5, 0.4, 0.3) and medium.density.values.shape == (1, 1, 1, 3)
    assert medium.density.to_world[0] == (2.0, 0.0, 0.0, -1.0)  # the cube shape's [-1, 1]^3
    assert medium.albedo.constant == (0.2, 0.2, 0.2) and medium.albedo.to_world[0] == (1.0, 0.0, 0.0, 0.0)
    _, medium, _ = smoke(tmp_path, "")  # Mitsuba's defaults: sigma_t 1, albedo 0.75
    assert (medium.density.constant, medium.albedo.constant, medium.scale) == ((1.0,) * 3, (0.75,) * 3, 1.0)


def test_what_is_not_supported_is_one_warning(tmp_path):
    write_vol(tmp_path / "d.vol", np.ones((2, 2, 2)))
    _, medium, messages = smoke(tmp_path, '''<volume name="sigma_t" type="gridvolume"><string name="filename" value="d.vol"/>
        <string name="wrap_mode" value="repeat"/></volume>
        <volume name="albedo" type="sphericalvolume"><float name="radius" value="1"/></volume>''', expect_warnings=2)
    assert "wrap_mode 'repeat' is rendered as clamp" in messages[0]
    assert '<volume type="sphericalvolume">: this volume type is not supported' in messages[1]
    assert medium.albedo.constant == (0.75,) * 3


@pytest.mark.parametrize("inner,problem", [
    ('<volume name="sigma_t" type="gridvolume"/>', "needs a filename"),
    ('<volume name="sigma_t" type="gridvolume"><string name="filename" value="none.vol"/></volume>', "none.vol"),
    ('<volume name="sigma_t" type="gridvolume"><string name="filename" value="neg.vol"/></volume>',
     "sigma_t (neg.vol) holds negative values"),
    ('<volume name="sigma_t" type="gridvolume"><string name="filename" value="bad.vol"/></volume>',
     "bad.vol: not a Mitsuba volume file"),
    ('<volume name="sigma_t" type="gridvolume"><string name="filename" value="neg.vol"/>'
     '<string name="filter_type" value="cubic"/></volume>', "filter_type 'cubic'"),
    ('<volume name="sigma_t" type="constvolume"><transform name="to_world"><scale x="0"/></transform></volume>',
     "singular"),
    ('<float name="scale" value="-1"/>', "scale -1 is negative"),
])
def test_bad_media_are_one_line_errors(tmp_path, inner, problem):
    write_vol(tmp_path / "neg.vol", -np.ones((1, 1, 1)))
    (tmp_path / "bad.vol").write_bytes(b"VOX" + bytes(60))
    with pytest.raises(SceneError) as error:
        smoke(tmp_path, inner)
    text = str(error.value)
    assert problem in text and "\n" not in text


def test_a_scene_with_homogeneous_media_only_compiles_no_grid_code(tmp_path):
    scene, _ = load(tmp_path, '<medium type="homogeneous" id="smoke"/>' + SHAPE)
    assert scene.media[0].kind == "homogeneous" and not scene_grid_media(scene)
