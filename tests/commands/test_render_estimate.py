"""The estimate of a render's length that turns on automatic checkpoints (over a minute) comes
from a pass long enough to measure the rate: a pass also costs a launch and a sync, and the
one-slice pass after the compiling one, taken as the rate, overstated a render of a second or two
by a factor of 60 to 400 (and checkpointed it)."""
import re
import subprocess
import sys
import time
from pathlib import Path

from renderer.commands.headless import RATE_PASS_SECONDS, RenderJob, render
from renderer.commands.render import LONG_RENDER_SECONDS
from renderer.scene.catalog import load_any, resolve_scene

ROOT = Path(__file__).resolve().parents[2]


def test_a_short_render_with_many_passes_is_not_taken_for_a_long_one(tmp_path):
    """16x16 pixels at 4000 spp: a million samples, about a second, in thousands of slices."""
    out = tmp_path / "y.png"
    proc = subprocess.run([sys.executable, str(ROOT / "app.py"), "render", "cornell_box", "--size", "16x16",
                           "--spp", "4000", "--arch", "cpu", "--out", str(out)],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    seconds = float(re.search(rf"{re.escape(str(out))}  \(4000 spp in ([\d.]+) s", proc.stdout).group(1))
    assert seconds < LONG_RENDER_SECONDS / 4, proc.stdout  # (the premise: a short render)
    assert "a long render" not in proc.stderr and "checkpointing" not in proc.stderr, proc.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["y.png"]


class Recorder:
    """The checkpoint policy's view of a render: the expected length told after each pass."""

    def __init__(self):
        self.expected = []

    def after_pass(self, film, spp_done, seconds_rendered, expected_seconds, slices_in_round=0):
        self.expected.append(expected_seconds)


def test_the_expected_length_is_measured_on_a_long_enough_pass():
    """No estimate until a pass of RATE_PASS_SECONDS has measured the rate; then every estimate is
    close to the rendering time the render really took (within a factor 3 either way, for a
    machine shared with other work)."""
    scene = load_any(resolve_scene("cornell_box"))
    recorder = Recorder()
    start = time.perf_counter()
    result = render(scene, RenderJob(spp=1500, size=(64, 64), integrator="path", max_depth=3), checkpoints=recorder)
    assert result.spp == 1500
    rendering = result.seconds_rendered
    assert rendering > 10 * RATE_PASS_SECONDS, rendering  # (the premise: passes long enough to measure)
    assert recorder.expected[0] is None  # the pass after the compiling one is a single slice
    estimates = [e for e in recorder.expected if e is not None]
    assert estimates, recorder.expected
    assert all(rendering / 3 <= e <= 3 * rendering for e in estimates), (rendering, estimates)
    assert time.perf_counter() - start < 120
