"""The benchmarks' shared helpers (renderer/bench/common.py) exactly, and the registry of
benchmark names (renderer/bench/__init__.py)."""
import importlib
import json
import math
import shlex
import sys
from datetime import datetime, timedelta, timezone
from pathlib import Path

import numpy as np
import pytest

from renderer.bench import BENCHMARKS
from renderer.bench.common import (
    REL_MSE_EPS,
    Timing,
    error_difference,
    format_table,
    load_average,
    rel_mse,
    rel_mse_trimmed,
    report_header,
    rmse,
    time_call,
    time_interleaved,
    write_json,
)


class FakeClock:
    """Each call advances by the next of `steps` (then by 0)."""

    def __init__(self, steps):
        self.now = 0.0
        self.steps = list(steps)

    def __call__(self):
        value = self.now
        self.now += self.steps.pop(0) if self.steps else 0.0
        return value


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


def test_every_benchmark_name_maps_to_a_module_with_run():
    assert set(BENCHMARKS) == {"sdf", "startup", "bvh", "integrators", "features", "photons", "interactive", "denoise", "scale",
                               "mitsuba-tests", "scenes", "texture-filter", "report"}
    for name, module in BENCHMARKS.items():
        assert module == f"renderer.bench.{name.replace('-', '_')}" and callable(importlib.import_module(module).run)


def test_report_header_says_what_ran_when_and_where():
    before = load_average()
    header = report_header("sdf", True, before, arch="cpu", config={"size": [4, 2]})
    assert list(header)[:5] == ["benchmark", "quick", "date", "command", "machine"]
    assert header["benchmark"] == "sdf" and header["quick"] is True
    assert header["arch"] == "cpu" and header["config"] == {"size": [4, 2]}
    assert list(header)[-1] == "load_average" and header["load_average"]["before"] == before
    age = datetime.now(timezone.utc) - datetime.fromisoformat(header["date"])
    assert timedelta(0) <= age < timedelta(minutes=1)
    assert shlex.split(header["command"])[1:] == sys.argv
    assert header["machine"]["cpus"] >= 1 and header["machine"]["python"] == sys.version.split()[0]
