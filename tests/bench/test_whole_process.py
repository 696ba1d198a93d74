"""`bench integrators`' whole-process comparison (renderer/bench/whole_process.py): its parsing,
and its orchestration with stand-in commands that write known images (the real one runs Lantern's
and Mitsuba's renders, minutes)."""
import sys

import numpy as np
import pytest

from renderer.bench import whole_process as wp


def test_render_seconds_reads_the_last_summary_line():
    out = "[####] 3/4 spp\n/tmp/a.exr  (4 spp in 1.5 s)\nlater (16 spp in 12.25 s)\n"
    assert wp.render_seconds(out) == 12.25
    assert wp.render_seconds("no summary here") is None


def _writer(value: float, suffix: str, seconds_line: str = ""):
    """A command writing a 4x4 image of `value` to its --out path, as each side's command does."""
    def command(config, seed, out):
        if suffix == ".exr":
            code = ("import sys, numpy as np; from renderer.output.image_io import write_exr; "
                    f"write_exr(sys.argv[1], np.full((4, 4, 3), {value}, np.float32)); print('{seconds_line}')")
        else:
            code = f"import sys, numpy as np; np.save(sys.argv[1], np.full((4, 4, 3), {value}, np.float32))"
        return [sys.executable, "-c", code, str(out)]
    return command


def test_compare_times_both_sides_and_reads_their_error(monkeypatch):
    monkeypatch.setattr(wp, "lantern_command", _writer(0.75, ".exr", "(4 spp in 0.01 s)"))
    monkeypatch.setattr(wp, "mitsuba_command", _writer(0.25, ".npy"))
    reference = np.full((4, 4, 3), 0.5)
    result = wp.compare(wp.WholeProcessConfig(size=4, spp=4, runs=2), reference, reference_spp=64)
    for side in ("lantern", "mitsuba"):
        assert len(result[side]["seconds"]) == 2 and result[side]["median_s"] > 0.0
        assert result[side]["rmse"] == pytest.approx(0.25)
    assert result["lantern"]["render_median_s"] == 0.01
    assert result["ratio"] == pytest.approx(result["lantern"]["median_s"] / result["mitsuba"]["median_s"])
    assert result["passed"] == (result["ratio"] <= wp.WHOLE_PROCESS_TARGET)
    rows = wp.summary_rows(result)
    assert [row[0] for row in rows] == ["Mitsuba (process)", "Lantern render mis"] and rows[0][-1] == "1.00x"
    assert ("PASS" if result["passed"] else "FAIL") in wp.caption(result)


def test_a_failing_process_is_a_note_not_a_crash(monkeypatch):
    monkeypatch.setattr(wp, "lantern_command", lambda config, seed, out: [sys.executable, "-c", "raise SystemExit(2)"])
    result = wp.compare_or_note(wp.WholeProcessConfig(size=4, spp=4, runs=1), np.zeros((4, 4, 3)), 64)
    assert result["available"] is False and "lantern exited with 2" in result["note"]
