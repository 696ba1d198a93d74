"""Smoke test of `bench features`: its decision rule and statistics exactly, its summary over several
unused effects on made-up results, and one real run on a tiny scene at 16x9 (report structure,
every build renders; not speed)."""
import json

import numpy as np
import pytest

from renderer.bench.common import verdict
from renderer.bench.features import (
    QUICK,
    EffectCase,
    FeaturesBenchConfig,
    image_difference,
    mean_change,
    optional_effects,
    paired_ratio,
    print_report,
    short,
    unused_effect_passes,
)
from renderer.scene.features import Features
from tests.bench.report_fixtures import features_report
from tests.scene_builder import tiny_bench_toml

# Diffuse and glass under a sky: the glass case strips the dielectric (a scene variant), and the
# unused effect forced on has no data here (its branches are compiled, never taken). Each build
# costs a cold compile and a cache load, in runtimes of its own, so one unused effect: media
# forced on renders in the `everything` build, and the summary over several effects is tested on
# made-up results (test_summary_over_several_unused_effects).
TINY_SCENE = tiny_bench_toml("tiny_features", 16, 9, glass_ball=True)

TINY = FeaturesBenchConfig(size=(16, 9), rounds=2, pass_seconds=0.005, max_pass_spp=4, image_spp=2,
                           unused_effects=("energy_compensation",),
                           effect_cases=(EffectCase("glass", "tiny_features", "own", "no glass"),),
                           child_timeout_s=600.0)


def test_paired_ratio_and_the_rule():
    base = [1.0, 1.0, 1.0, 1.0, 1.0]
    same = paired_ratio([1.0] * 5, base)
    assert same["median"] == same["lo"] == same["hi"] == 1.0 and unused_effect_passes(same)
    slower = paired_ratio([1.10, 1.12, 1.08, 1.11, 1.09], base)
    assert slower["lo"] > 1.0 and unused_effect_passes(slower)  # an unused effect that costs: fine
    noisy = paired_ratio([0.90, 1.05, 0.97, 1.02, 0.95], base)
    assert noisy["lo"] < 1.0 < noisy["hi"] and unused_effect_passes(noisy)  # zero within noise
    faster = paired_ratio([0.90, 0.91, 0.89, 0.90, 0.92], base)
    assert faster["hi"] < 0.98 and not unused_effect_passes(faster)  # own build measurably slower
    slight = paired_ratio([0.99, 0.985, 0.99, 0.99, 0.99], base)
    assert slight["hi"] < 1.0 and unused_effect_passes(slight)  # within the 2 % layout tolerance


def test_optional_effects_are_the_bools_everything_adds():
    own = Features(geometry="mesh", material_kinds=frozenset({"diffuse"}), has_emission=True)
    effects = optional_effects(own)
    assert "diffuse" not in effects and "has_emission" not in effects
    assert {"dielectric", "clearcoat", "has_media", "has_textures", "energy_compensation", "analytic_fog"} <= set(effects)
    assert "environment" not in effects and "mesh_primitives" not in effects
    assert "has_textures" not in optional_effects(Features(geometry="sdf"))  # SDF scenes have no uv textures


def test_image_difference():
    a = np.ones((2, 3, 3))
    assert image_difference(a, a) == 0.0
    assert image_difference(1.5 * a, a) == pytest.approx(0.5)
    assert mean_change(1.5 * a, a) == pytest.approx(0.5) and mean_change(a, a) == 0.0


def test_summary_over_several_unused_effects(tmp_path, capsys):
    """Two scenes with a passing (+dielectric, 1.01) and a failing (+media, 0.9: the own build
    measurably slower) unused effect each, and a scene that errored: one verdict per build, the
    target fails, and the printed target line counts and names the failures."""
    report = features_report(tmp_path)
    summary = report["summary"]
    verdicts = {(v["scene"], v["effect"]): v["passed"] for v in summary["unused_effects"]}
    assert verdicts == {("alpha", "dielectric"): True, ("alpha", "has_media"): False,
                        ("beta", "dielectric"): True, ("beta", "has_media"): False}
    assert summary["passed"] is False
    print_report(report["scenes"], summary, QUICK, [])
    assert "FAIL  (2/4 effects pass; failing: alpha+media, beta+media)" in capsys.readouterr().out


def test_run_on_a_tiny_scene(tmp_path, capsys):
    from renderer.bench.features import run

    scene = tmp_path / "tiny_features.toml"
    scene.write_text(TINY_SCENE)
    out = tmp_path / "reports"
    assert run(out_dir=out, scenes=[scene], config=TINY) == 0
    report = json.loads((out / "bench_features.json").read_text())
    assert (out / report["plot"]).stat().st_size > 1000
    (res,) = report["scenes"]
    assert "error" not in res, res.get("traceback", res.get("error"))
    assert res["scene"] == "tiny_features" and "dielectric" in res["own_features"]["material_kinds"]
    builds = res["builds"]
    assert set(builds) == {"own", "everything", "+energy_compensation", "no glass"}
    for name, b in builds.items():
        assert "error" not in b, (name, b.get("error"))
        assert b["compile_s"] > 0 and b["cache_bytes"] >= 0 and b["load_s"] > 0
        assert len(b["times_s"]) == TINY.rounds and b["samples_per_s"] > 0
        assert b["vs_own"]["lo"] <= b["vs_own"]["median"] <= b["vs_own"]["hi"]
        assert b["finite"] and b["rejected"] == 0
    assert builds["own"]["vs_own"]["median"] == 1.0
    assert builds["own"]["cache_bytes"] > 0
    # Energy compensation forced on a scene whose only microfacet material is smooth glass: its
    # code is compiled in (a new kernel in the cache) but never taken, so the image is the own
    # build's, bit for bit
    assert builds["+energy_compensation"]["cache_bytes"] > 0
    assert builds["+energy_compensation"]["identical_to_own"]
    assert builds["everything"]["cache_bytes"] > builds["own"]["cache_bytes"]
    (case,) = res["cases"]
    assert case["effect"] == "glass" and case["without"] == "no glass"
    # two renders with the effect on independent seeds differ: the floor is a measured figure
    assert case["image_difference"] > 0 and case["noise_floor"] > 0
    assert case["mean_change"] != 0.0 and case["ratio"]["lo"] <= case["ratio"]["hi"]
    verdicts = report["summary"]["unused_effects"]
    assert {v["effect"] for v in verdicts} == {"energy_compensation"}
    for v in verdicts:  # each verdict is the decision rule applied to its build's measured ratio
        assert v["passed"] == unused_effect_passes(builds["+" + short(v["effect"])]["vs_own"])
    passed = report["summary"]["passed"]
    assert passed == all(v["passed"] for v in verdicts)
    printed = capsys.readouterr().out
    assert "tiny_features" in printed
    assert f"{verdict(passed)}  ({sum(v['passed'] for v in verdicts)}/1 effects pass" in printed
