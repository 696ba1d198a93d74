"""Smoke test of `bench integrators`: its pure helpers exactly, and its measurement on a tiny scene
with tiny budgets (the real run takes minutes)."""
import json
import math

import pytest

from renderer.bench import BENCHMARKS
from renderer.bench.integrators import IntegratorBenchConfig, spp_to_reach, value_at

TINY_SCENE = """
[scene]
name = "tiny_integrators"
geometry = "sdf"
[camera]
position = [0.0, 1.0, 3.0]
look_at = [0.0, 0.4, 0.0]
fov = 50
[render]
width = 32
height = 18
max_depth = 3
[environment]
type = "sky"
[materials.white]
type = "diffuse"
[[objects]]
type = "plane"
material = "white"
[[objects]]
type = "sphere"
material = "white"
radius = 0.5
translate = [0.0, 0.5, 0.0]
"""

TINY = IntegratorBenchConfig(square_size=(16, 16), wide_size=(16, 9), budget_s=0.2, reference_s=0.4,
                             reference_launch_s=0.2, integrators=("path", "mis"), samplers=("independent", "sobol"),
                             mitsuba=False)


@pytest.fixture
def tiny_scene(tmp_path):
    path = tmp_path / "tiny_integrators.toml"
    path.write_text(TINY_SCENE)
    return path


def test_registered():
    assert "integrators" in BENCHMARKS


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


def test_measurement_on_a_tiny_scene(tiny_scene, tmp_path, capsys):
    from renderer.bench.integrators import SceneBench, bench_scene, progressive
    from renderer.scene import load_scene

    scene = load_scene(tiny_scene)

    # progressive: totals double (1, 2, 4, ...) until the last launch, which lands on the budget
    bench = SceneBench(scene, (16, 9))
    bench.compile("path", "independent")
    run = progressive(bench.renderer, bench.camera, "path", "independent", seed=1, budget_s=0.2, max_spp=64,
                      observe=lambda image: {"mean": float(image.mean())})
    spps = [p["spp"] for p in run["points"]]
    assert spps[:3] == [1, 2, 4][: len(spps[:3])] and spps == sorted(spps) and spps[-1] == run["spp"] <= 64
    assert run["seconds"] >= 0.2 or run["spp"] == 64
    assert all(p["mean"] > 0 for p in run["points"]) and bench.renderer.samples_done == run["spp"]

    # one scene: compile times, a reference with its own noise, one curve per integrator x sampler
    result = bench_scene(scene, TINY)
    assert not result["errors"], result["errors"]
    assert set(result["compile_s"]) == {"path/independent", "path/sobol", "mis/independent", "mis/sobol"}
    ref = result["reference"]
    assert ref["spp"] >= 2 and ref["rejected_samples"] == 0 and 0 < ref["noise_floor"]["rmse"] < 1
    assert len(result["curves"]) == 4
    for c in result["curves"]:
        curve = c["curve"]
        assert curve[-1]["seconds"] >= TINY.budget_s or curve[-1]["spp"] == TINY.max_spp
        assert all(p["rmse"] > 0 and p["rel_mse"] > 0 for p in curve)
        # the error falls as samples accumulate (first launch against the last: >= 4x the spp)
        if curve[-1]["spp"] >= 4 * curve[0]["spp"]:
            assert curve[-1]["rmse"] < curve[0]["rmse"]
        assert set(c["at_budget"]) >= {"rmse", "rel_mse", "rel_mse_trimmed", "spp"}


def test_run_writes_report_and_skips_missing_scenes(tiny_scene, tmp_path, capsys):
    from renderer.bench.integrators import run

    config = IntegratorBenchConfig(square_size=(16, 16), wide_size=(16, 9), budget_s=0.1, reference_s=0.2,
                                   reference_launch_s=0.1, integrators=("path",), samplers=("independent",),
                                   mitsuba=False)
    out = tmp_path / "reports"
    assert run(quick=True, out_dir=out, scenes=[tiny_scene, "no_such_scene"], config=config) == 0
    report = json.loads((out / "bench_integrators.json").read_text())
    scenes = {s["scene"]: s for s in report["scenes"]}
    assert "skipped" in scenes["no_such_scene"]
    assert [c["integrator"] for c in scenes["tiny_integrators"]["curves"]] == ["path"]
    assert (out / "bench_integrators_tiny_integrators.png").is_file()
    printed = capsys.readouterr().out
    assert "equal time" in printed and "Compile time" in printed and "no_such_scene: skipped" in printed
