"""`bench mitsuba-tests`: Mitsuba's render-test rule, the scene/reference pairing, and a whole run on
a test folder laid out as mitsuba-data's, whose reference is known exactly."""
from __future__ import annotations

import json

import numpy as np
import pytest

from renderer.bench.mitsuba_tests import find_test_scenes, mitsuba_verdict, run
from renderer.output.image_io import write_exr

# A diffuse wall filling the view under a uniform sky of radiance 1, direct light only: every pixel
# is the wall's albedo exactly (a convex view of a plane sees nothing but the sky above it).
WALL = """<scene version="3.0.0">
    <integrator type="direct"/>
    <sensor type="perspective"><float name="fov" value="20"/>
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><rfilter type="box"/><integer name="width" value="8"/>
        <integer name="height" value="6"/></film></sensor>
    <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
    <shape type="rectangle"><transform name="to_world"><scale value="10"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.25, 0.5, 0.75"/></bsdf></shape>
</scene>"""


def test_the_rule_passes_noise_and_fails_a_bias():
    rng = np.random.default_rng(7)
    reference = rng.uniform(0.2, 0.8, (32, 32, 3))
    variance = np.full_like(reference, 0.05)  # per sample, as Mitsuba's variance references are
    spp = 256
    noisy = reference + rng.normal(0, np.sqrt(0.05 / spp), reference.shape)
    assert mitsuba_verdict(noisy, spp, reference, variance)["passed"]
    judged = mitsuba_verdict(noisy * 1.2, spp, reference, variance)
    assert not judged["passed"] and judged["failing_fraction"] > 0.5
    # One bad pixel in 1024 is within Mitsuba's 0.25 % allowance; ten are not.
    one = noisy.copy()
    one[3, 4] += 10.0
    assert mitsuba_verdict(one, spp, reference, variance)["passed"]
    ten = noisy.copy()
    ten[:10, 4] += 10.0
    assert not mitsuba_verdict(ten, spp, reference, variance)["passed"]


def test_scenes_pair_with_their_references(tmp_path):
    group = tmp_path / "tests" / "scenes" / "walls"
    (group / "refs").mkdir(parents=True)
    for name in ("test_wall_direct.xml", "test_lonely_path.xml"):
        (group / name).write_text(WALL)
    for name in ("test_wall_ref_rgb.exr", "test_wall_ref_rgb_var.exr", "test_lonely_ref_mono.exr"):
        (group / "refs" / name).write_bytes(b"")
    found, missing = find_test_scenes(tmp_path)
    assert [t.name for t in found] == ["walls/test_wall_direct"] and [p.name for p in missing] == ["test_lonely_path.xml"]
    assert found[0].reference.name == "test_wall_ref_rgb.exr"


@pytest.mark.parametrize("albedo, verdict", [((0.25, 0.5, 0.75), "PASS"), ((0.25, 0.5, 0.8), "FAIL")])
def test_a_whole_run(tmp_path, albedo, verdict):
    group = tmp_path / "tests" / "scenes" / "walls"
    (group / "refs").mkdir(parents=True)
    (group / "test_wall_direct.xml").write_text(WALL)
    write_exr(group / "refs" / "test_wall_ref_rgb.exr", np.full((6, 8, 3), albedo, np.float32))
    write_exr(group / "refs" / "test_wall_ref_rgb_var.exr", np.full((6, 8, 3), 0.05, np.float32))
    out = tmp_path / "out"
    assert run(out_dir=out, data=tmp_path) == 0
    report = json.loads((out / "bench_mitsuba_tests.json").read_text())
    (row,) = report["results"]
    assert report["benchmark"] == "mitsuba-tests" and row["scene"] == "walls/test_wall_direct"
    assert row["verdict"] == verdict and row["spp"] == 2_000_000 // 48
    assert (verdict == "FAIL") == (out / "mitsuba_tests_walls_test_wall_direct.png").exists()


def test_without_data_it_says_so(tmp_path):
    with pytest.raises(ValueError, match="needs --data DIR"):
        run(out_dir=tmp_path)
    with pytest.raises(ValueError, match="no scene with an RGB reference"):
        run(out_dir=tmp_path, data=tmp_path)


def test_the_page_section_counts_passes_and_says_why_a_scene_fails():
    from renderer.bench.report_mitsuba_section import mitsuba_tests_section

    report = {"rule": {"significance": 0.01, "pass_fraction": 0.9975}, "sample_budget": 2_000_000,
              "results": [{"scene": "a/test_one_path", "verdict": "PASS", "failing_percent": 0.0},
                          {"scene": "a/test_two_path", "verdict": "FAIL", "failing_percent": 3.0,
                           "left_out": ["<bsdf type=\"hair\">: left out"]},
                          {"scene": "b/test_three_path", "verdict": "FAIL", "failing_percent": 0.4, "left_out": []},
                          {"scene": "b/test_four_path", "verdict": "not loaded", "note": "x.xml: line 3: bad"}]}
    section = mitsuba_tests_section(report)
    assert section.findings[0].startswith("1 of 4 of Mitsuba 3's render tests pass")
    why = section.blocks[0]
    assert "&lt;bsdf type=\"hair\"&gt;: left out" in why and "the image differs" in why and "x.xml: line 3: bad" in why
    assert "test_one_path" not in why and "test_one_path" in section.blocks[1]
