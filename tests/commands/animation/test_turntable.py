"""The turntable (renderer/commands/animation/turntable.py): the camera keeps its distance and height
relative to the centre, turns counter-clockwise seen from above, and is back at the scene's camera
after SECONDS; the centre is a mesh scene's bounds' centre, an SDF scene's look_at point."""
from __future__ import annotations

import numpy as np
import pytest

from renderer.commands.animation.frame_numbers import turntable_frames
from renderer.commands.animation.turntable import Turntable, orbit_centre
from renderer.camera import CameraFrame
from renderer.scene import CameraSpec, load_scene
from tests.scene.scene_file_helpers import scene_text, write

SPEC = CameraSpec(position=(1.0, 2.0, 4.0), look_at=(0.5, 0.3, -0.2), up=(0.0, 1.0, 0.0), fov=35.0,
                  aperture=0.01, focus_distance=3.0)
CENTRE = (0.2, 0.5, -0.4)
# Relative to values of a few metres, float64 rounding of a rotation stays far below this.
ROUNDING = 1e-12


def test_the_camera_keeps_its_distance_and_height_and_its_view_of_the_centre():
    turntable = Turntable(SPEC, CENTRE, 3.0)
    centre = np.array(CENTRE)
    start = np.array(SPEC.position) - centre
    start_gaze = np.array(SPEC.look_at) - np.array(SPEC.position)
    for t in np.linspace(0.0, 6.0, 37):
        frame = turntable.camera_at(float(t))
        offset = np.array(frame.position) - centre
        assert np.linalg.norm(offset) == pytest.approx(np.linalg.norm(start), rel=ROUNDING)
        assert offset[1] == pytest.approx(start[1], rel=ROUNDING)
        # The look-at point turns with it: the angle between the view and the way to the centre holds.
        to_centre = -offset / np.linalg.norm(offset)
        assert np.dot(frame.forward, to_centre) == pytest.approx(
            np.dot(start_gaze / np.linalg.norm(start_gaze), -start / np.linalg.norm(start)), rel=ROUNDING)
        assert (frame.fov, frame.aperture, frame.focus_distance) == (35.0, 0.01, 3.0)


def test_the_camera_is_back_at_the_start_after_seconds_and_turns_counter_clockwise_seen_from_above():
    turntable = Turntable(SPEC, CENTRE, 3.0)
    assert turntable.camera_at(0.0) == turntable.camera_at(3.0) == turntable.camera_at(6.0) == CameraFrame.from_spec(SPEC)
    assert turntable.camera_at(1.5) != turntable.camera_at(0.0)
    # A quarter turn takes +z (from the centre) to +x, the right-hand rule about +y.
    on_z = Turntable(CameraSpec(position=(0.0, 1.0, 2.0), look_at=(0.0, 1.0, 0.0)), (0.0, 0.0, 0.0), 4.0)
    np.testing.assert_allclose(on_z.camera_at(1.0).position, (2.0, 1.0, 0.0), atol=ROUNDING)
    np.testing.assert_allclose(on_z.camera_at(1.0).forward, (-1.0, 0.0, 0.0), atol=ROUNDING)
    np.testing.assert_allclose(on_z.camera_at(2.0).position, (0.0, 1.0, -2.0), atol=ROUNDING)


MESH_SCENE = """[scene]
geometry = "mesh"
[camera]
position = [0, 1, 5]
look_at = [0, 0.5, 0]
[materials.m]
[[objects]]
type = "sphere"
material = "m"
radius = 0.5
translate = [2, 1, -1]
[[objects]]
type = "quad"
material = "m"
size = [2, 4]
translate = [0, 0, 0.5]
"""


def test_the_centre_is_a_mesh_scenes_bounds_centre_and_an_sdf_scenes_look_at(tmp_path):
    centre, what = orbit_centre(load_scene(write(tmp_path, MESH_SCENE, "mesh.toml")))
    # The sphere spans x 1.5..2.5, y 0.5..1.5, z -1.5..-0.5; the quad x -1..1, y 0, z -1.5..2.5.
    np.testing.assert_allclose(centre, (0.75, 0.75, 0.5), rtol=1e-6)
    assert "bounds" in what
    sdf = load_scene(write(tmp_path, scene_text("[camera]\nlook_at = [0.5, 0.25, -1]\n"), "sdf.toml"))
    assert orbit_centre(sdf) == ((0.5, 0.25, -1.0), "the camera's look_at point (an SDF has no bounds)")


@pytest.mark.parametrize("seconds, fps, last", [(2.0, 24.0, 47), (0.1, 30.0, 2), (1.3, 24.0, 31), (0.01, 24.0, 0)])
def test_a_turntable_without_frames_renders_the_frames_of_one_turn(seconds, fps, last):
    first, end = turntable_frames(seconds, fps)
    assert (first, end) == (0, last)
    assert end / fps < seconds <= (end + 1) / fps + 1e-9  # the last frame before the turn ends
