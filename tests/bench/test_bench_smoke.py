"""Smoke tests of the benchmarks: the shared helpers exactly, and each benchmark end to end on a
tiny scene and tiny settings (the real runs take minutes)."""
import json
import math
from pathlib import Path

import numpy as np
import pytest

from renderer.bench import BENCHMARKS
from renderer.bench.common import (
    REL_MSE_EPS,
    Timing,
    error_difference,
    format_table,
    rel_mse,
    rel_mse_trimmed,
    rmse,
    time_call,
    time_interleaved,
    write_json,
)
from tests.scene_builder import tiny_bench_toml

TINY_SCENE = tiny_bench_toml("tiny")


@pytest.fixture
def tiny_scene(tmp_path):
    path = tmp_path / "tiny.toml"
    path.write_text(TINY_SCENE)
    return path


class FakeClock:
    """Each call advances by the next of `steps` (then by 0)."""

    def __init__(self, steps):
        self.now = 0.0
        self.steps = list(steps)

    def __call__(self):
        value = self.now
        self.now += self.steps.pop(0) if self.steps else 0.0
        return value


# --- common.py -------------------------------------------------------------------------------

def test_rmse_and_rel_mse_on_known_arrays():
    ref = np.ones((2, 3, 3))
    img = ref + 0.5
    assert rmse(img, ref) == pytest.approx(0.5)
    assert rel_mse(img, ref) == pytest.approx(0.25 / (1.0 + REL_MSE_EPS))
    assert rmse(ref, ref) == 0.0 and rel_mse(ref, ref) == 0.0
    # relMSE weighs dark pixels up: an error of 0.1 on 0 counts 0.01 / 0.01 = 1
    dark = np.zeros((1, 1, 3))
    assert rel_mse(dark + 0.1, dark) == pytest.approx(1.0)
    with pytest.raises(ValueError):
        rmse(np.zeros((2, 2, 3)), np.zeros((2, 3, 3)))


def test_trimmed_rel_mse_drops_the_fireflies():
    ref = np.ones((10, 100, 3))
    img = ref.copy()
    img[0, 0] = 1000.0  # one firefly among 1000 pixels
    assert rel_mse(img, ref) > 100
    assert rel_mse_trimmed(img, ref, trim=1e-3) == 0.0
    assert rel_mse_trimmed(img, ref, trim=0.0) == pytest.approx(rel_mse(img, ref))


def test_error_difference_is_paired():
    rng = np.random.default_rng(0)
    ref = np.ones((40, 50, 3))
    noise = rng.normal(0.0, 0.1, ref.shape)
    same = error_difference(ref + noise, ref + noise, ref, "mse")
    assert same.difference == 0.0 and same.z == 0.0
    worse = error_difference(ref + 1.5 * noise, ref + noise, ref, "mse")
    assert worse.difference == pytest.approx(1.25 * np.mean(noise ** 2), rel=1e-9)
    assert worse.z > 10 and worse.relative == pytest.approx(1.25)
    d = error_difference(ref + 1.1 * noise, ref + noise, ref, "rel_mse")
    assert d.a > d.b and math.isfinite(d.standard_error)


def test_time_call_takes_the_median_after_warmup():
    # warm-up 10 s (compile), then runs of 3, 1, 2 s
    timing = time_call(lambda: None, runs=3, warmup=1, clock=FakeClock([10, 0, 3, 0, 1, 0, 2]))
    assert timing.warmup_times == [10]
    assert timing.times == [3, 1, 2]
    assert timing.median == 2
    assert Timing([1.0, 3.0]).median == 2.0
    with pytest.raises(ValueError):
        time_call(lambda: None, runs=0)


def test_time_interleaved_runs_round_robin():
    order = []
    calls = {"a": lambda: order.append("a"), "b": lambda: order.append("b")}
    timings = time_interleaved(calls, runs=2, warmup=1, after=lambda name: order.append(name.upper()))
    assert order == ["a", "b", "a", "A", "b", "B", "a", "A", "b", "B"]
    assert len(timings["a"].times) == 2 and len(timings["b"].warmup_times) == 1


def test_table_and_json(tmp_path):
    text = format_table(["name", "value"], [["x", 1.5], ["longer", 12345.0]], title="t")
    lines = text.splitlines()
    assert lines[0] == "t" and lines[1].startswith("name")
    assert lines[3].endswith("1.500") and lines[4].endswith("1.23e+04")
    path = write_json(tmp_path / "sub" / "r.json", {"a": np.float32(0.5), "b": np.arange(2), "c": math.inf,
                                                   "p": Path("x")})
    assert json.loads(path.read_text()) == {"a": 0.5, "b": [0, 1], "c": "inf", "p": "x"}


def test_benchmarks_are_registered():
    assert {"sdf", "startup"} <= set(BENCHMARKS)


# --- sdf.py ----------------------------------------------------------------------------------

def test_sdf_benchmark_on_a_tiny_scene(tiny_scene, tmp_path, capsys):
    from renderer.bench.sdf import SdfBenchConfig, run

    config = SdfBenchConfig(size=(32, 18), ref_spp=4, ref_chunk=2, compare_spp=2, geometry_spp=2, runs=1,
                            sweep_rate_spp=1, sweep_seconds=0.02, max_sweep_spp=4, omegas=(1.0, 1.6),
                            thresholds=(0.5, 2.0), step_limits=(8, 64))
    out = tmp_path / "reports"
    assert run(quick=True, out_dir=out, scenes=[tiny_scene], config=config) == 0
    report = json.loads((out / "bench_sdf.json").read_text())
    (scene,) = report["scenes"]
    assert scene["scene"] == "tiny"
    rows = scene["over_relaxation"]
    assert [r["omega"] for r in rows] == [1.0, 1.6]
    assert rows[0]["step_reduction"] == 0.0 and rows[0]["path_vs_plain"]["difference"] == 0.0
    assert all(r["steps_per_ray"] > 0 and r["samples_per_s"] > 0 for r in rows)
    assert scene["target"]["passed"] in (True, False)
    for key, values in (("hit_threshold", [0.5, 2.0]), ("max_steps", [8, 64])):
        sweep = scene["sweeps"][key]
        assert [r["value"] for r in sweep["rows"]] == values
        for r in sweep["rows"]:
            assert 1 <= r["path"]["spp"] <= 4 and r["path"]["curve"]
            assert r["geometry_rmse"] >= 0.0
    # a coarser threshold takes fewer steps on the camera rays
    sweep = scene["sweeps"]["hit_threshold"]["rows"]
    assert sweep[1]["primary_steps_per_ray"] < sweep[0]["primary_steps_per_ray"]
    for name in report["plots"]:
        assert (out / name).stat().st_size > 1000
    assert "bench_sdf_steps_vs_omega.png" in report["plots"]
    printed = capsys.readouterr().out
    assert "tiny" in printed and ("PASS" in printed or "FAIL" in printed)


# --- startup.py ------------------------------------------------------------------------------

def test_startup_report_parsing():
    from renderer.bench.startup import MARKER, parse_child_output, summarise

    marks = {"launch": 100.0, "main": 100.2, "imported": 101.0, "initialised": 101.1, "scene_loaded": 101.2,
             "built": 101.5, "first_frame": 102.5}
    stdout = "noise\n" + MARKER + json.dumps({"mode": "renderer", "marks": marks}) + "\n"
    result = parse_child_output(stdout, "", 0, 3.0, "renderer")
    assert result["start_to_first_frame"] == pytest.approx(2.5)
    assert result["import_and_init"] == pytest.approx(1.1)
    assert result["phases"]["first_frame"] == pytest.approx(1.0)
    assert result["phases"]["interpreter"] == pytest.approx(0.2)
    failed = parse_child_output("", "Traceback\nBoom", 1, 0.5, "renderer")
    assert "Boom" in failed["error"]
    summary = summarise([result, dict(result, start_to_first_frame=4.5), failed])
    assert summary["ok"] == 2 and summary["start_to_first_frame"] == pytest.approx(3.5)


def test_startup_optimization_levels_and_moving_summary():
    from renderer.bench.startup import optimization_level, summarise

    phases = {"first_frame": 3.0, "next_frame": 0.5}
    entry = {"optimize": "run", "cold": {"phases": {"first_frame": 20.0, "next_frame": 0.5}, "size": [100, 50]},
             "warm": {"phases": phases}}
    level = optimization_level(entry)
    assert level["optimize"] == "run" and level["cold_kernels"] == pytest.approx(19.5)
    assert level["warm_kernels"] == pytest.approx(2.5)
    assert level["msamples_per_second"] == pytest.approx(100 * 50 / 0.5 / 1e6)
    runs = [{"phases": phases, "start_to_first_frame": 3.0, "moving": {"median_ms": m}} for m in (40.0, 60.0, 45.0)]
    assert summarise(runs)["moving_ms"] == pytest.approx(45.0)


def test_startup_target_is_the_viewer_frame_unless_the_viewer_failed():
    from renderer.bench.startup import start_up_targets

    renderer = {"mode": "renderer", "warm": {"start_to_first_frame": 3.4}}
    viewer = {"mode": "viewer", "warm": {"start_to_first_frame": 2.5, "moving_ms": 47.0}}
    rows = start_up_targets([renderer, viewer])
    judged = [r for r in rows if r.get("judged") and "seconds" in r]
    assert [(r["mode"], r["passed"]) for r in judged] == [("viewer", True)]
    assert [r["passed"] for r in rows if "moving_ms" in r] == [True]
    broken = {"mode": "viewer", "warm": {"error": "no Vulkan"}}
    rows = start_up_targets([renderer, broken])
    assert [(r["mode"], r["passed"]) for r in rows if r.get("judged")] == [("renderer", False), ("viewer", False)]


def test_startup_child_process_once(tiny_scene, tmp_path):
    """One real, tiny subprocess: imports, initialises, renders, reports its marks."""
    from renderer.bench.startup import measure

    result = measure("renderer", tmp_path / "cache", scene=str(tiny_scene), size=(16, 9), integrator="normals",
                     timeout=120)
    assert "error" not in result, result.get("error")
    assert result["spp"] == 1 and result["scene"] == "tiny"
    assert 0 < result["import_and_init"] < result["start_to_first_frame"] <= result["process_seconds"]
    assert set(result["phases"]) == {"interpreter", "import", "init", "scene", "build", "first_frame", "next_frame"}
