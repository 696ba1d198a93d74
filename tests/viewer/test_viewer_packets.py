"""`view --packets N`: the viewer's frames traced N rays a packet where the scene allows.

The viewer (off-screen, frames through ViewerApp.step() as in the real loop) renders its still
frames and its moving, lower-resolution frames with the packet program, and its image is the
one-ray-at-a-time renderer's (z-tests at the suite's level, different seeds). Where packets are
not taken, the HUD says why.
"""
import numpy as np
import pytest

from renderer.camera import CameraFrame
from renderer.packets.program import PacketProgram
from renderer.renderer import Renderer
from renderer.scene.catalog import load_any, resolve_scene
from tests.stats.image_tests import assert_agree
from viewer import hud
from viewer.window import FrameInput, ViewerApp

SIZE = (32, 24)
SPP = 48


@pytest.fixture(scope="module")
def app(tmp_path_factory):
    # One viewer (one GGUI window) for the module, as the viewer is used: scenes are switched in it.
    return ViewerApp(resolve_scene("cornell_box"), size=SIZE, show_window=False,
                     screenshot_folder=tmp_path_factory.mktemp("shots"), settle_seconds=0.0,
                     still_present_interval=0.0, packets=8)


def current_program(app):
    r = app.renderer
    return r.program(app.session.integrator, r.features(app._camera_frame()), r.scene.render.sampler)


def test_the_viewer_traces_packets_and_shows_the_one_ray_at_a_time_image(app):
    for _ in range(2000):
        if app.renderer.samples_done >= SPP:
            break
        app.step()
    r = app.renderer
    assert r.samples_done >= SPP
    program = current_program(app)
    assert isinstance(program, PacketProgram)
    assert program.occupancy()["closest_traces"] > 0  # the frames ran the packet kernel
    assert "packets of 8 rays: taken" in hud.hud_lines(app.hud_stats())

    scalar = Renderer(load_any(resolve_scene("cornell_box")), SIZE)
    scalar.render(CameraFrame.from_spec(scalar.scene.camera), r.samples_done, integrator=app.session.integrator,
                  seed=12345)
    a = (r.image(), r.film.variance_of_mean_image())
    b = (scalar.image(), scalar.film.variance_of_mean_image())
    assert b[0].mean() > 0.05
    assert_agree(a, b, ("viewer with packets", "one ray at a time"))

    # Moving frames: a smaller film each frame, still through the packet kernel
    program.reset_occupancy()
    for _ in range(6):
        app.step(FrameInput(held=frozenset({"w"})))
    assert app.last_plan.interactive
    assert program.occupancy()["closest_traces"] > 0
    assert np.isfinite(app.renderer.image()).all()


def test_the_hud_says_why_a_scene_is_not_traced_in_packets(app):
    app.select_scene(resolve_scene("textured"))  # textures: the denoiser's feature samples have no packet form
    for _ in range(4):
        app.step()
    assert not isinstance(current_program(app), PacketProgram)
    text = " ".join(" ".join(hud.hud_lines(app.hud_stats())).split())  # the HUD wraps long lines
    assert "packets of 8 rays: not taken, the denoiser's feature samples" in text
