"""viewer/cache_warmer.py: the order a scene's integrators are warmed in, the stepping to a first
image, and the command's one-line errors. (Its end-to-end test, a warmed viewer start that
compiles nothing, is in test_viewer_e2e.py: it needs the real window.)"""
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

from viewer.cache_warmer import step_to_first_image, warm_order

ROOT = Path(__file__).resolve().parents[2]


def test_the_viewers_first_integrator_comes_first_and_sppm_last():
    names = ["path", "sppm", "nee", "mis", "normals"]
    assert warm_order("mis", names) == ["mis", "path", "nee", "normals", "sppm"]
    assert warm_order("sppm", names) == ["sppm", "path", "nee", "mis", "normals"]  # a scene that starts on it
    assert warm_order("mis", ["normals", "path"]) == ["normals", "path"]  # not asked for: not shown


class _Viewer:
    """Stands in for the viewer: `notices` frames show a notice, then each frame renders a slice."""

    def __init__(self, notices: int, renders: bool = True):
        self.notices, self.renders = notices, renders
        self.notice, self.last_plan = None, None
        self.renderer = SimpleNamespace(slices_done=0)

    def step(self, inp=None):
        if self.notices:
            self.notices -= 1
            self.notice = "compiling..."
            return
        self.notice = None
        self.last_plan = SimpleNamespace()
        self.renderer.slices_done += int(self.renders)


def test_stepping_stops_at_the_first_frame_that_shows_an_image():
    shown = step_to_first_image(_Viewer(notices=2))
    assert shown["shown"] and shown["frames"] == 3 and shown["notice_frames"] == 2
    never = step_to_first_image(_Viewer(notices=0, renders=False), frame_limit=5)
    assert not never["shown"] and never["frames"] == 5


def _app(*args):
    return subprocess.run([sys.executable, "app.py", *args], cwd=ROOT, capture_output=True, text=True, timeout=120)


def test_bad_scene_or_integrator_is_one_line_before_anything_starts():
    missing = _app("warm-cache", "no_such_scene")
    assert missing.returncode == 2 and missing.stderr.count("\n") == 1 and "no_such_scene" in missing.stderr
    unknown = _app("warm-cache", "cornell_box", "--integrators", "path,bogus")
    assert unknown.returncode == 2 and unknown.stderr.count("\n") == 1 and "bogus" in unknown.stderr
    assert "warming" not in unknown.stdout
