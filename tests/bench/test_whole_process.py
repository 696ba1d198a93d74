"""`bench integrators`' whole-process comparison (renderer/bench/whole_process.py): its parsing,
and its orchestration with stand-in commands that write known images (the real one runs Lantern's
and Mitsuba's renders, minutes)."""
import subprocess
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
            code = (f"import sys, numpy as np; np.save(sys.argv[1], np.full((4, 4, 3), {value}, np.float32)); "
                    f"print('{seconds_line}')")
        return [sys.executable, "-c", code, str(out)]
    return command


def test_compare_times_both_sides_and_reads_their_error(monkeypatch):
    monkeypatch.setattr(wp, "lantern_command", _writer(0.75, ".exr", "(4 spp in 0.01 s)"))
    monkeypatch.setattr(wp, "mitsuba_command", _writer(0.25, ".npy", "(4 spp in 0.04 s)"))
    reference = np.full((4, 4, 3), 0.5)
    result = wp.compare(wp.WholeProcessConfig(size=4, spp=4, runs=2), reference, reference_spp=64)
    for side in ("lantern", "mitsuba"):
        assert len(result[side]["seconds"]) == 2 and result[side]["median_s"] > 0.0
        assert result[side]["rmse"] == pytest.approx(0.25)
    assert result["lantern"]["render_median_s"] == 0.01 and result["mitsuba"]["render_median_s"] == 0.04
    assert result["render_ratio"] == pytest.approx(0.25)
    assert result["mitsuba"]["outside_render_median_s"] == pytest.approx(result["mitsuba"]["median_s"] - 0.04)
    assert result["ratio"] == pytest.approx(result["lantern"]["median_s"] / result["mitsuba"]["median_s"])
    assert result["passed"] == (result["ratio"] <= wp.WHOLE_PROCESS_TARGET)
    rows = wp.summary_rows(result)
    assert [row[0] for row in rows] == ["Mitsuba (process)", "Lantern render mis"] and rows[0][-1] == "1.00x"
    assert ("PASS" if result["passed"] else "FAIL") in wp.caption(result)


@pytest.mark.parametrize("lantern_s, mitsuba_s, passed", [(1.0, 2.0, True), (4.0, 2.0, False),
                                                         (3.0, 2.0, True)],  # (the target itself: "at most")
                         ids=["half-as-long", "twice-as-long", "at-the-target"])
def test_the_verdict_follows_the_timed_ratio(monkeypatch, tmp_path, lantern_s, mitsuba_s, passed):
    """Known timings in place of the clock: Lantern at 0.5x Mitsuba's time passes, at 2x fails,
    at the target (1.5x) passes. The processes are stood in for too: each writes its image."""
    from renderer.output.image_io import write_exr

    seconds = {"lantern": lantern_s, "mitsuba": mitsuba_s}
    monkeypatch.setattr(wp, "lantern_command", lambda config, seed, out: ["lantern", str(out)])
    monkeypatch.setattr(wp, "mitsuba_command", lambda config, seed, out: ["mitsuba", str(out)])

    def timed_process(command):
        side, out = command
        if side == "lantern":
            write_exr(out, np.full((4, 4, 3), 0.75, np.float32))
            return seconds[side], subprocess.CompletedProcess(command, 0, "(4 spp in 0.01 s)\n", "")
        np.save(out, np.full((4, 4, 3), 0.25, np.float32))
        return seconds[side], subprocess.CompletedProcess(command, 0, "", "")

    monkeypatch.setattr(wp, "timed_process", timed_process)
    result = wp.compare(wp.WholeProcessConfig(size=4, spp=4, runs=3), np.full((4, 4, 3), 0.5), reference_spp=64)
    assert result["lantern"]["seconds"] == [lantern_s] * 3 and result["mitsuba"]["seconds"] == [mitsuba_s] * 3
    assert result["ratio"] == pytest.approx(lantern_s / mitsuba_s)
    assert result["passed"] is passed and result["render_ratio"] is None  # no render line from Mitsuba here
    assert f"{'PASS' if passed else 'FAIL'} ({lantern_s / mitsuba_s:.2f}x)" in wp.caption(result)
    assert wp.summary_rows(result)[1][-1] == f"{lantern_s / mitsuba_s:.2f}x"


def test_a_failing_process_is_a_note_not_a_crash(monkeypatch):
    monkeypatch.setattr(wp, "lantern_command", lambda config, seed, out: [sys.executable, "-c", "raise SystemExit(2)"])
    result = wp.compare_or_note(wp.WholeProcessConfig(size=4, spp=4, runs=1), np.zeros((4, 4, 3)), 64)
    assert result["available"] is False and "lantern exited with 2" in result["note"]


def test_the_mitsuba_process_prints_its_render_time(tmp_path):
    """The real process (when Mitsuba is installed): its "(N spp in T s)" line is what compare reads."""
    from renderer.bench import mitsuba_side

    if not mitsuba_side.is_available():
        pytest.skip("Mitsuba 3 is not installed")
    out = tmp_path / "m.npy"
    done = subprocess.run(wp.mitsuba_command(wp.WholeProcessConfig(size=8, spp=2, max_depth=2), 0, out),
                          cwd=wp.REPO_ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert wp.render_seconds(done.stdout) is not None and np.load(out).shape == (8, 8, 3)
