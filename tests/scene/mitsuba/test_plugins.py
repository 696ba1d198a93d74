"""Mitsuba 3 scene files, the scene language: typed properties, <ref>s, and transforms composed in
the order they are written (checked against matrices built here with numpy)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from renderer.scene.errors import SceneError
from renderer.scene.mitsuba.plugins import Rgb, Spectrum, read_plugins
from renderer.scene.mitsuba.xml_document import Resolution, resolve_document


def plugins(tmp_path, body: str):
    path = tmp_path / "s.xml"
    path.write_text(f'<scene version="3.0.0">\n{body}\n</scene>\n')
    resolution = Resolution({}, [tmp_path], [path])
    return read_plugins(resolve_document(path, resolution), resolution)


def rot(axis, degrees):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    a = math.radians(degrees)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    m = np.eye(4)
    m[:3, :3] = np.eye(3) + math.sin(a) * k + (1 - math.cos(a)) * k @ k
    return m


def test_typed_properties(tmp_path):
    root = plugins(tmp_path, '''<bsdf type="x">
        <integer name="i" value="3"/><float name="f" value="-2.5e-1"/><boolean name="b" value="True"/>
        <string name="s" value="hello"/><point name="p" x="1" z="3"/><vector name="v" value="1, 2 3"/>
        <rgb name="c" value="0.1 0.2, 0.3"/><rgb name="g" value="0.5"/><spectrum name="u" value="0.25"/>
        <spectrum name="w" value="400:0.1, 500:0.2 600:0.3"/>
    </bsdf>''')
    bsdf = root.children[0]
    assert (bsdf.kind, bsdf.type) == ("bsdf", "x")
    p = bsdf.properties
    assert p["i"] == 3 and p["f"] == -0.25 and p["b"] is True and p["s"] == "hello"
    assert p["p"] == (1.0, 0.0, 3.0) and p["v"] == (1.0, 2.0, 3.0)
    assert p["c"] == Rgb((0.1, 0.2, 0.3)) and p["g"] == Rgb((0.5, 0.5, 0.5))
    assert p["u"] == Spectrum(uniform=0.25)
    assert p["w"] == Spectrum((400.0, 500.0, 600.0), (0.1, 0.2, 0.3))


def test_spectrum_from_a_file(tmp_path):
    (tmp_path / "s.spd").write_text("# a comment\n400 1.5\n500 1.6 # trailing\n\n700 1.7\n")
    root = plugins(tmp_path, '<bsdf type="x"><spectrum name="eta" filename="s.spd"/></bsdf>')
    assert root.children[0].properties["eta"] == Spectrum((400.0, 500.0, 700.0), (1.5, 1.6, 1.7))


def test_refs_name_the_same_object(tmp_path):
    root = plugins(tmp_path, '''<bsdf type="diffuse" id="white"/>
        <shape type="sphere"><ref id="white"/></shape>
        <shape type="sphere"><ref name="bsdf" id="white"/></shape>''')
    white = root.children[0]
    assert root.children[1].children[0] is white
    assert root.children[2].properties["bsdf"] is white


@pytest.mark.parametrize("body, problem", [
    ('<shape type="sphere"><ref id="later"/></shape><bsdf type="diffuse" id="later"/>', "no object with that id"),
    ('<bsdf type="diffuse" id="a"/><bsdf type="diffuse" id="a"/>', 'id "a" is used twice'),
    ('<shape type="sphere"><float name="radius" value="big"/></shape>', "'big' is not a number"),
    ('<shape type="sphere"><float value="1"/></shape>', "<float> needs a name"),
    ('<shape/>', "<shape> needs a type"),
    ('<shape type="sphere"><wobble/></shape>', "unknown element <wobble>"),
    ('<shape type="sphere"><boolean name="b" value="maybe"/></shape>', "neither true nor false"),
    ('<shape type="sphere"><transform name="to_world"><shear/></transform></shape>', "unknown transform step"),
    ('<shape type="sphere"><spectrum name="s" value="500:1, 400:2"/></shape>', "increasing wavelengths"),
    ('<sensor type="perspective"><transform name="to_world"><lookat origin="0,0,0" target="0,1,0" up="0,1,0"/>'
     '</transform></sensor>', "up is parallel"),
])
def test_bad_input_is_one_line_naming_the_line(tmp_path, body, problem):
    with pytest.raises(SceneError) as error:
        plugins(tmp_path, body)
    assert problem in str(error.value) and "line 2" in str(error.value) and "\n" not in str(error.value)


def test_transform_steps_apply_in_order(tmp_path):
    root = plugins(tmp_path, '''<shape type="sphere"><transform name="to_world">
        <scale x="2" y="3"/><rotate y="1" angle="30"/><translate x="1" y="-2" z="0.5"/>
        <rotate value="1, 1, 0" angle="-45"/><matrix value="1 0 0 0  0 1 0 0  0 0 1 4  0 0 0 1"/>
    </transform></shape>''')
    matrix = root.children[0].properties["to_world"]
    translate = np.eye(4)
    translate[:3, 3] = (1, -2, 0.5)
    shift = np.eye(4)
    shift[2, 3] = 4
    expected = shift @ rot((1, 1, 0), -45) @ translate @ rot((0, 1, 0), 30) @ np.diag([2.0, 3.0, 1.0, 1.0])
    np.testing.assert_allclose(matrix, expected, atol=1e-12)


def test_lookat_is_mitsubas_frame(tmp_path):
    root = plugins(tmp_path, '''<sensor type="perspective"><transform name="to_world">
        <lookat origin="1, 2, 3" target="1, 2, 0" up="0, 1, 0"/></transform></sensor>''')
    m = root.children[0].properties["to_world"]
    np.testing.assert_allclose(m[:3, 2], (0, 0, -1))  # forward
    np.testing.assert_allclose(m[:3, 1], (0, 1, 0))  # up
    np.testing.assert_allclose(m[:3, 0], np.cross((0, 1, 0), (0, 0, -1)))  # left = up x forward
    np.testing.assert_allclose(m[:3, 3], (1, 2, 3))
