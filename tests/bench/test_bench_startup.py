"""`bench startup`: its child-output parsing, summaries and targets exactly, and one real, tiny
child process."""
import json

import pytest


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
