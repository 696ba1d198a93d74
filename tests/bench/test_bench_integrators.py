"""Smoke test of `bench integrators`: its pure helpers exactly, and its measurement on a tiny scene
with tiny budgets (the real run takes minutes)."""
import json
import math

import pytest

import numpy as np

from renderer.bench.convergence import seeded_levels, seeded_points, spp_to_reach, value_at
from renderer.bench.integrator_config import IntegratorBenchConfig
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


def test_seeded_levels_bracket_every_crossing():
    # crossings 11-13 spp (RMSE) and 34-35 (relMSE): 8 up to 64
    assert seeded_levels([12.7, 11.1, 34.8, 34.4], cap=128) == [8, 16, 32, 64]
    assert seeded_levels([16.0, 16.0], cap=128) == [16, 32]  # a crossing on a level still gets one above
    assert seeded_levels([3.0, 300.0], cap=64) == [2, 4, 8, 16, 32, 64]  # capped
    assert seeded_levels([math.inf, float("nan"), 0.0], cap=64) == []


def test_seeded_points_average_squared_errors_over_seeds():
    """Renders with known errors: the RMSE of a level is the root of the mean of the seeds' mean
    squared errors (not the mean of their RMSEs), relMSE the mean, spp what each render took."""
    reference = np.full((4, 4, 3), 0.5)
    calls = []

    def exact(spp, seed):
        calls.append(("exact", spp, seed))
        return reference.copy(), spp

    def offset(spp, seed):  # error 0.1 * seed everywhere; rounds its spp up like multijitter;
        calls.append(("offset", spp, seed))  # its image read back by a function (untimed)
        return (lambda: reference + 0.1 * seed), spp + 3

    points = seeded_points({"exact": exact, "offset": offset}, [8, 16], [1, 2], reference)
    assert [p["spp"] for p in points["exact"]] == [8, 16] and [p["spp"] for p in points["offset"]] == [11, 19]
    assert all(p["rmse"] == 0.0 and p["rel_mse"] == 0.0 and p["renders"] == 2 and p["seconds"] >= 0.0
               for p in points["exact"])
    assert points["offset"][0]["rmse"] == pytest.approx(math.sqrt((0.01 + 0.04) / 2))
    # the names take turns at every level and seed
    assert calls[:4] == [("exact", 8, 1), ("offset", 8, 1), ("exact", 8, 2), ("offset", 8, 2)]


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
