"""The camera path of a scene's keyframes (renderer/commands/animation/camera_path.py) and the scene format's
keyframes: through every keyframe exactly, C1 in time (finite differences on both sides of each
keyframe), held outside the keyframes' range, the field of view within its keyframes' range; bad
keyframes are one-line SceneErrors naming the file."""
from __future__ import annotations

import numpy as np
import pytest

from renderer.commands.animation.camera_path import CameraPath, Keyframes, catmull_rom_velocities, hermite
from renderer.camera import CameraFrame
from renderer.scene import CameraSpec, load_scene
from tests.scene.scene_file_helpers import load_error, scene_text, write

# Uneven times and a turn in every direction, so that no symmetry hides a kink.
KEYFRAMES = """
[camera]
fov = 40
up = [0, 2, 0]
[[camera.keyframes]]
time = 0.5
position = [0, 1.5, 3]
look_at = [0, 0.4, 0]
[[camera.keyframes]]
time = 1.25
position = [2.5, 1.0, 2.0]
look_at = [0.2, 0.5, 0]
fov = 60
[[camera.keyframes]]
time = 3.0
position = [3, 2.5, -1]
look_at = [0, 0.3, 0.4]
fov = 25
up = [0.1, 1, 0]
[[camera.keyframes]]
time = 3.5
position = [0.5, 0.8, -3]
look_at = [0, 0.5, 0]
"""


@pytest.fixture(scope="module")
def spec(tmp_path_factory) -> CameraSpec:
    return load_scene(write(tmp_path_factory.mktemp("path"), scene_text(KEYFRAMES))).camera


def frame_vector(frame: CameraFrame) -> np.ndarray:
    return np.concatenate([frame.position, frame.forward, frame.up, [frame.fov]])


def test_the_loader_keeps_the_keyframes_and_the_camera_fills_in_fov_and_up(spec):
    rows = [dict(k) for k in spec.keyframes]
    assert [r["time"] for r in rows] == [0.5, 1.25, 3.0, 3.5]
    assert rows[0]["fov"] is None and rows[0]["up"] is None and rows[2]["up"] == (0.1, 1.0, 0.0)
    keyframes = Keyframes.from_spec(spec)
    np.testing.assert_array_equal(keyframes.fovs, [40, 60, 25, 40])
    np.testing.assert_array_equal(keyframes.ups[[0, 1, 3]], [[0, 2, 0]] * 3)


def test_the_path_passes_through_every_keyframe_exactly(spec):
    path = CameraPath(spec)
    for row in (dict(k) for k in spec.keyframes):
        expected = CameraFrame.look_at(row["position"], row["look_at"], row["up"] or spec.up,
                                       row["fov"] or spec.fov, spec.aperture, spec.focus_distance)
        assert path.camera_at(row["time"]) == expected


def test_the_path_holds_the_end_keyframes_outside_their_range(spec):
    path = CameraPath(spec)
    assert path.camera_at(0.0) == path.camera_at(0.5) == path.camera_at(-7.0)
    assert path.camera_at(3.5) == path.camera_at(3.6) == path.camera_at(1e6)
    assert path.camera_at(0.5 + 1e-3) != path.camera_at(0.5)  # it does move inside the range


def kink(f, t: float, lo: float, hi: float, step: float = 1e-6) -> float:
    """How far the slopes on the two sides of t differ, over what a C1 curve allows there: with a
    continuous derivative they differ by at most step * max |f''| (a share per side; f'' bounded
    by second differences on a grid over [lo, hi]), plus the rounding of the values (a few ulps of
    the largest) divided by the step. Above 1: a kink."""
    grid = np.linspace(lo, hi, 401)
    values = np.array([f(x) for x in grid])
    h = grid[1] - grid[0]
    curvature = np.abs(values[2:] - 2 * values[1:-1] + values[:-2]).max() / h**2
    rounding = 4 * np.abs(values).max() * np.finfo(np.float64).eps / step
    left = (f(t) - f(t - step)) / step
    right = (f(t + step) - f(t)) / step
    return float(np.abs(left - right).max() / (2 * step * curvature + rounding))


def test_the_path_is_c1_at_every_keyframe_including_the_holds(spec):
    path = CameraPath(spec)
    camera = lambda t: frame_vector(path.camera_at(t))  # noqa: E731 (position, forward, up, fov)
    for t in (0.5, 1.25, 3.0, 3.5):
        assert kink(camera, t, 0.0, 4.0) <= 1.0, t
    # The check finds a kink where there is one: straight lines between the keyframes.
    k = Keyframes.from_spec(spec)
    linear = lambda t: np.array([np.interp(t, k.times, k.positions[:, i]) for i in range(3)])  # noqa: E731
    assert kink(linear, 1.25, 0.0, 4.0) > 100.0


def test_the_velocity_at_an_inner_keyframe_is_the_parabola_through_its_neighbours():
    times = np.array([0.0, 1.0, 3.0])
    parabola = lambda t: 2.0 * t * t - t + 0.5  # noqa: E731
    values = parabola(times).reshape(3, 1)
    velocities = catmull_rom_velocities(times, values)
    assert velocities[0, 0] == velocities[2, 0] == 0.0
    assert velocities[1, 0] == pytest.approx(4.0 * 1.0 - 1.0, rel=1e-12)
    assert hermite(times, values, velocities, 1.0)[0] == values[1, 0]


def test_the_field_of_view_never_leaves_the_range_of_the_keyframes_around_it(spec):
    path = CameraPath(spec)
    times = Keyframes.from_spec(spec).times
    fovs = Keyframes.from_spec(spec).fovs
    for i in range(len(times) - 1):
        for t in np.linspace(times[i], times[i + 1], 101):
            fov = path.camera_at(float(t)).fov
            assert min(fovs[i], fovs[i + 1]) <= fov <= max(fovs[i], fovs[i + 1]), (t, fov)


def test_a_scene_without_keyframes_is_a_still_camera(tmp_path):
    spec = load_scene(write(tmp_path, scene_text("[camera]\nposition = [1, 2, 3]\n"))).camera
    path = CameraPath(spec)
    assert not path.animated and spec.keyframes == ()
    assert path.camera_at(0.0) == path.camera_at(12.5) == CameraFrame.from_spec(spec)


def keyframe(time, position="[0, 1, 3]", look_at="[0, 0, 0]", extra="") -> str:
    return f"[[camera.keyframes]]\ntime = {time}\nposition = {position}\nlook_at = {look_at}\n{extra}"


@pytest.mark.parametrize("camera, expected", [
    (keyframe(0), "camera: keyframes: a camera path needs at least 2 keyframes, got 1"),
    (keyframe(0) + keyframe(2) + keyframe(1),
     "camera: keyframes[2].time 1 is not after keyframes[1].time 2 (times must increase strictly)"),
    (keyframe(0) + keyframe(0), "keyframes[1].time 0 is not after keyframes[0].time 0"),
    (keyframe(0) + keyframe(1, look_at="[0, 1, 3]"), "camera: keyframes[1]: position and look_at are the same point"),
    (keyframe(0) + keyframe(1, extra="up = [0, -2, -6]\n"), "keyframes[1]: up is zero or parallel to the view"),
    (keyframe(0) + "[[camera.keyframes]]\nposition = [0, 1, 3]\nlook_at = [0, 0, 0]\n",
     "camera.keyframes[1]: missing required field 'time'"),
    (keyframe(0) + keyframe(1, extra="fov = 180\n"), "camera.keyframes[1].fov: 180 is out of range"),
    (keyframe(0) + keyframe(1, extra="roll = 3\n"), "camera.keyframes[1]: unknown field 'roll'"),
    (keyframe(0) + keyframe("true"), "camera.keyframes[1].time: expected a number, got boolean true"),
    ("keyframes = 3\n", "camera.keyframes: expected an array of tables, got integer 3"),
])
def test_bad_keyframes_are_one_line_errors_naming_the_file(tmp_path, camera, expected):
    text = scene_text("[camera]\n" + camera if not camera.startswith("[[") else camera)
    message = load_error(write(tmp_path, text))
    assert expected in message, message
