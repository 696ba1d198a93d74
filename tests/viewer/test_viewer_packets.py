"""`view --packets N`: the viewer's frames traced N rays a packet where the scene allows.

The viewer (off-screen, in a process of its own: tests/viewer/viewer_packets_child.py, frames
through ViewerApp.step() as in the real loop) renders its still frames and its moving,
lower-resolution frames with the packet program, and its image is the one-ray-at-a-time
renderer's (z-tests at the suite's level, different seeds). Where packets are not taken, the HUD
says why.
"""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from renderer.camera import CameraFrame
from renderer.renderer import Renderer
from renderer.scene.catalog import load_any, resolve_scene
from tests.stats.image_tests import assert_agree
from tests.viewer.viewer_packets_child import SIZE, SPP

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def shown(tmp_path_factory):
    out = tmp_path_factory.mktemp("viewer_packets") / "shown.npz"
    proc = subprocess.run([sys.executable, "-m", "tests.viewer.viewer_packets_child", str(out)], cwd=ROOT,
                          capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    with np.load(out) as arrays:
        return {k: arrays[k] for k in arrays.files}


def test_the_viewer_traces_packets_and_shows_the_one_ray_at_a_time_image(shown):
    assert shown["spp"] >= SPP
    assert shown["still_packets"] and shown["still_traces"] > 0  # the frames ran the packet kernel
    assert "packets of 8 rays: taken" in str(shown["cornell_hud"])
    scalar = Renderer(load_any(resolve_scene("cornell_box")), SIZE)
    scalar.render(CameraFrame.from_spec(scalar.scene.camera), int(shown["spp"]), integrator=str(shown["integrator"]),
                  seed=12345)
    b = (scalar.image(), scalar.film.variance_of_mean_image())
    assert b[0].mean() > 0.05
    assert_agree((shown["mean"], shown["variance"]), b, ("viewer with packets", "one ray at a time"))
    # moving frames: a smaller film each frame, still through the packet kernel
    assert shown["moving_interactive"] and shown["moving_traces"] > 0 and shown["moving_finite"]


def test_the_hud_says_why_a_scene_is_not_traced_in_packets(shown):
    assert not shown["textured_packets"]  # textures: the denoiser's feature samples have no packet form
    text = " ".join(str(shown["textured_hud"]).split())  # the HUD wraps long lines
    assert "packets of 8 rays: not taken, the denoiser's feature samples" in text
