"""Typed parameter lists and colours (renderer/scene/pbrt/parameters.py, spectra.py)."""
from __future__ import annotations

import pytest

from renderer.scene.errors import SceneError
from renderer.scene.pbrt.parameters import read_params
from renderer.scene.pbrt.spectra import ILLUMINANT, REFLECTANCE, NamedSpectrum, colour, glass_index, luminance
from renderer.scene.pbrt.tokenizer import TokenStream

from tests.scene.pbrt.pbrt_helpers import write


def params(tmp_path, text: str):
    stream = TokenStream(write(tmp_path, text, "p.pbrt"))
    result = read_params(stream)
    return result, stream


def test_every_type_read_and_the_next_directive_left(tmp_path):
    p, stream = params(tmp_path, '"float fov" [45] "integer n" 3 "bool b" true "bool c" "false" "string s" "x"\n'
                                 '"point3 P" [0 1 2 3 4 5] "point2 uv" [0 1] "normal N" [0 0 1] "vector3 v" [1 0 0]\n'
                                 '"rgb L" [1 2 3] "texture reflectance" "wood" "blackbody I" [6500]\n'
                                 '"spectrum eta" "metal-Cu-eta"\nShape "sphere"')
    assert p.float("fov") == 45.0 and p.integer("n") == 3
    assert p.boolean("b", False) is True and p.boolean("c", True) is False
    assert p.string("s") == "x" and p.texture("reflectance") == "wood"
    assert p.tuples("P", ("point3",), 3) == [(0, 1, 2), (3, 4, 5)]
    assert p.tuples("uv", ("point2",), 2) == [(0, 1)]
    assert p.point3("N", (0, 0, 0)) == (0, 0, 1) and p.point3("v", (0, 0, 0)) == (1, 0, 0)
    assert colour(p.find("L"), REFLECTANCE) == (1.0, 2.0, 3.0)
    assert colour(p.find("eta"), REFLECTANCE) == NamedSpectrum("metal-Cu-eta")
    assert luminance(colour(p.find("I"), ILLUMINANT)) == pytest.approx(1.0)
    assert p.unused() == []
    assert stream.next().text == "Shape"


def test_unused_parameters_are_listed(tmp_path):
    p, _ = params(tmp_path, '"float a" 1 "float b" 2')
    p.float("a")
    assert [q.name for q in p.unused()] == ["b"]


def test_spectrum_pairs_and_file(tmp_path):
    (tmp_path / "flat.spd").write_text("# flat\n400 0.5\n700 0.5\n")
    p, _ = params(tmp_path, '"spectrum a" [300 0.5 800 0.5] "spectrum b" "flat.spd"')
    a, b = colour(p.find("a"), REFLECTANCE), colour(p.find("b"), REFLECTANCE)
    assert a == pytest.approx((0.5, 0.5, 0.5), abs=0.01)
    assert b[1] == pytest.approx(0.5, abs=0.03)


def test_blackbody_is_warm_at_luminance_one(tmp_path):
    p, _ = params(tmp_path, '"blackbody L" [2700]')
    r, g, b = colour(p.find("L"), ILLUMINANT)
    assert r > g > b and luminance((r, g, b)) == pytest.approx(1.0)


def test_named_glass_index_at_550nm():
    assert glass_index("glass-BK7") == pytest.approx(1.5185, abs=1e-3)
    assert glass_index("glass-unknown") is None


@pytest.mark.parametrize("text, problem", [
    ('"floaty x" 1', "unknown type 'floaty'"),
    ('"float" 1', 'expected "type name"'),
    ('"float x" [1 2', "'[' is never closed"),
    ('"integer x" 1.5', "is not an integer"),
    ('"float x" "one"', "is not a number"),
    ('"bool x" maybe', "is not true or false"),
])
def test_bad_parameters_are_one_line(tmp_path, text, problem):
    with pytest.raises(SceneError) as e:
        params(tmp_path, text)
    assert problem in str(e.value) and "p.pbrt: line 1:" in str(e.value)
