"""Smoke test of `bench integrators`: its pure helpers exactly, and its measurement on a tiny scene
with tiny budgets (the real run takes minutes)."""
import json
import math

import pytest

from renderer.bench.integrators import IntegratorBenchConfig, spp_to_reach, value_at
from tests.scene_builder import tiny_bench_toml

TINY_SCENE = tiny_bench_toml("tiny_integrators")

# One Renderer, three programs: mis/independent (the reference) and path with both samplers.
TINY = IntegratorBenchConfig(square_size=(16, 16), wide_size=(16, 9), budget_s=0.2, reference_s=0.3,
                             reference_launch_s=0.1, max_spp=256, integrators=("path",),
                             samplers=("independent", "sobol"), mitsuba=False)


@pytest.fixture
def tiny_scene(tmp_path):
    path = tmp_path / "tiny_integrators.toml"
    path.write_text(TINY_SCENE)
    return path


def test_value_at_interpolates_in_log_log():
    points = [{"seconds": 1.0, "rmse": 1.0}, {"seconds": 4.0, "rmse": 0.5}, {"seconds": 16.0, "rmse": 0.25}]
    assert value_at(points, "rmse", "seconds", 2.0) == pytest.approx(1.0 / math.sqrt(2.0))  # RMSE ~ t^-1/2
    assert value_at(points, "rmse", "seconds", 4.0) == pytest.approx(0.5)
    assert value_at(points, "rmse", "seconds", 0.5) == 1.0  # before the curve: its first point
    assert value_at(points, "rmse", "seconds", 99.0) == 0.25  # after it: its last point


def test_spp_to_reach_interpolates_then_extrapolates():
    points = [{"spp": 1, "rmse": 1.0}, {"spp": 4, "rmse": 0.5}, {"spp": 16, "rmse": 0.25}]
    spp, extrapolated = spp_to_reach(points, "rmse", 0.5 / math.sqrt(2.0))
    assert spp == pytest.approx(8.0) and not extrapolated
    assert spp_to_reach(points, "rmse", 2.0) == (1.0, False)
    spp, extrapolated = spp_to_reach(points, "rmse", 0.125)  # RMSE ~ spp^-1/2 past the curve
    assert spp == pytest.approx(64.0) and extrapolated
    spp, extrapolated = spp_to_reach([{"spp": 4, "m": 0.5}], "m", 0.25, power=1.0)  # an MSE-like metric
    assert spp == pytest.approx(8.0) and extrapolated


def test_run_on_a_tiny_scene(tiny_scene, tmp_path, capsys):
    """The whole measurement on one tiny scene (and a missing one, skipped with a note): compile
    times, a reference with its own noise, one progressive curve per integrator x sampler, the
    equal-time table, JSON and a plot."""
    from renderer.bench.integrators import run

    out = tmp_path / "reports"
    assert run(quick=True, out_dir=out, scenes=[tiny_scene, "no_such_scene"], config=TINY) == 0
    report = json.loads((out / "bench_integrators.json").read_text())
    scenes = {s["scene"]: s for s in report["scenes"]}
    assert "skipped" in scenes["no_such_scene"]
    result = scenes["tiny_integrators"]
    assert not result["errors"], result["errors"]
    assert set(result["compile_s"]) == {"mis/independent", "path/independent", "path/sobol"}
    ref = result["reference"]
    assert ref["integrator"] == "mis" and ref["spp"] >= 2 and ref["rejected_samples"] == 0
    assert 0 < ref["noise_floor"]["rmse"] < 1 and ref["noise_floor"]["rel_mse"] > 0
    assert [(c["integrator"], c["sampler"]) for c in result["curves"]] == [("path", "independent"), ("path", "sobol")]
    for c in result["curves"]:
        curve = c["curve"]
        spps = [p["spp"] for p in curve]
        # totals double (1, 2, 4, ...) but for the launches sized to land on the budget
        assert spps[0] == 1 and all(a < b <= 2 * a for a, b in zip(spps, spps[1:]))
        assert curve[-1]["seconds"] >= TINY.budget_s or curve[-1]["spp"] == TINY.max_spp
        assert all(b["seconds"] > a["seconds"] for a, b in zip(curve, curve[1:]))
        assert all(p["rmse"] > 0 and p["rel_mse"] > 0 for p in curve)
        if spps[-1] >= 16:  # the error falls as samples accumulate
            assert curve[-1]["rmse"] < curve[0]["rmse"]
        assert set(c["at_budget"]) >= {"rmse", "rel_mse", "rel_mse_trimmed", "spp"} and c["rejected_samples"] == 0
    assert (out / "bench_integrators_tiny_integrators.png").is_file()
    printed = capsys.readouterr().out
    assert "equal time" in printed and "Compile time" in printed and "no_such_scene: skipped" in printed
