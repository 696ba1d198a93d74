import math

import numpy as np
import pytest

from viewer.camera_state import PITCH_LIMIT, CameraState
from viewer.controller import MAX_DT, MAX_SPEED, MIN_SPEED, FreeLookController

ORIGIN = CameraState(position=(0.0, 0.0, 0.0))


def moved(keys, dt=0.1, state=ORIGIN, speed=2.0):
    ctl = FreeLookController(state, move_speed=speed)
    changed = ctl.update(dt, set(keys), None, False)
    return changed, np.array(ctl.state.position) - np.array(state.position)


@pytest.mark.parametrize("key, direction", [
    ("w", (0, 0, -1)), ("s", (0, 0, 1)), ("a", (-1, 0, 0)),
    ("d", (1, 0, 0)), ("q", (0, -1, 0)), ("e", (0, 1, 0)),
])
def test_held_key_moves_speed_times_dt(key, direction):
    changed, delta = moved({key}, dt=0.1, speed=2.0)
    assert changed
    np.testing.assert_allclose(delta, 0.2 * np.array(direction), atol=1e-12)


def test_forward_follows_pitch_and_yaw():
    state = CameraState(position=(1, 2, 3), yaw=0.7, pitch=0.3)
    _, delta = moved({"w"}, dt=0.05, state=state)
    np.testing.assert_allclose(delta, 0.1 * state.basis()[0], atol=1e-12)


def test_shift_multiplies_speed_by_four():
    _, slow = moved({"d"})
    _, fast = moved({"d", "Shift"})
    np.testing.assert_allclose(fast, 4 * slow)


@pytest.mark.parametrize("keys", [{"w", "s"}, {"a", "d"}, {"q", "e"}, {"w", "s", "a", "d", "shift"}])
def test_opposite_keys_cancel(keys):
    changed, delta = moved(keys)
    assert not changed
    assert not delta.any()


def test_dt_is_clamped():
    _, delta = moved({"w"}, dt=5.0, speed=1.0)
    assert np.linalg.norm(delta) == pytest.approx(MAX_DT)


def test_idle_frames_report_no_change():
    ctl = FreeLookController(ORIGIN)
    for i in range(100):
        assert not ctl.update(1 / 60, set(), (100.0 + i, 50.0), False)
        assert not ctl.update(1 / 60, set(), None, True)
    # dragging without motion is not a change either
    for _ in range(10):
        assert not ctl.update(1 / 60, set(), (10.0, 10.0), True)
    assert ctl.state == ORIGIN


def test_a_still_frame_keeps_the_very_same_state():
    """Nothing held, no drag: the controller returns at once (a still view's frames recompute no
    camera basis), keeping the state object itself."""
    state = CameraState(position=(1, 2, 3), yaw=0.4, pitch=-0.2)
    ctl = FreeLookController(state)
    assert not ctl.update(1 / 60, {"shift", "x"}, (5.0, 5.0), False)
    assert ctl.state is state
    assert ctl.update(1 / 60, {"w"}, None, False) and ctl.state is not state


def drag(path, dt):
    ctl = FreeLookController(ORIGIN)
    for p in path:
        ctl.update(dt, set(), p, True)
    ctl.update(dt, set(), path[-1], False)
    return ctl.state


def test_look_is_frame_rate_independent():
    total = np.array([173.0, -61.0])  # pixels
    start = np.array([400.0, 300.0])
    s30 = drag([tuple(start + total * t) for t in np.linspace(0, 1, 31)], 1 / 30)
    s240 = drag([tuple(start + total * t) for t in np.linspace(0, 1, 241)], 1 / 240)
    assert s30.yaw == pytest.approx(s240.yaw, abs=1e-9)
    assert s30.pitch == pytest.approx(s240.pitch, abs=1e-9)
    assert s30.yaw == pytest.approx(-173 * 0.004, abs=1e-9)  # right drag turns right
    assert s30.pitch == pytest.approx(61 * 0.004, abs=1e-9)  # up drag looks up


def test_drag_right_turns_view_right():
    s = drag([(0.0, 0.0), (50.0, 0.0)], 1 / 60)
    assert s.basis()[0][0] > 0  # forward gained +x, the initial right


def test_first_drag_update_does_not_jump():
    ctl = FreeLookController(ORIGIN)
    ctl.update(0.1, set(), (0.0, 0.0), False)
    assert not ctl.update(0.1, set(), (500.0, 500.0), True)
    assert ctl.state == ORIGIN
    assert ctl.update(0.1, set(), (510.0, 500.0), True)
    # release, move the cursor elsewhere, press again: no jump either
    ctl.update(0.1, set(), (510.0, 500.0), False)
    before = ctl.state
    assert not ctl.update(0.1, set(), (0.0, 0.0), True)
    assert ctl.state == before


def test_pitch_clamps():
    s = drag([(0.0, 0.0), (0.0, -1e6)], 1 / 60)
    assert s.pitch == pytest.approx(PITCH_LIMIT)
    s = drag([(0.0, 0.0), (0.0, 1e6)], 1 / 60)
    assert s.pitch == pytest.approx(-PITCH_LIMIT)
    assert CameraState((0, 0, 0), pitch=10.0).pitch == PITCH_LIMIT
    ctl = FreeLookController(CameraState((0, 0, 0), pitch=PITCH_LIMIT))
    ctl.update(0.1, set(), (0.0, 0.0), True)
    assert not ctl.update(0.1, set(), (0.0, -100.0), True)  # pushing past the limit is no change


def test_change_speed_clamps_and_is_not_a_change():
    ctl = FreeLookController(ORIGIN)
    ctl.change_speed(1)
    assert ctl.move_speed == pytest.approx(2.5)
    ctl.change_speed(1000)
    assert ctl.move_speed == MAX_SPEED
    ctl.change_speed(-10000)
    assert ctl.move_speed == MIN_SPEED
    assert not ctl.update(0.1, set(), None, False)


def test_set_state_reports_difference():
    ctl = FreeLookController(ORIGIN)
    assert not ctl.set_state(ORIGIN.replace())
    assert ctl.set_state(ORIGIN.replace(fov=60.0))
    assert ctl.state.fov == 60.0


def test_basis_orthonormal_right_handed():
    rng = np.random.default_rng(1)
    for _ in range(500):
        s = CameraState(tuple(rng.normal(size=3)), yaw=rng.uniform(-10, 10), pitch=rng.uniform(-2, 2))
        f, r, u = s.basis()
        m = np.stack([f, r, u])
        np.testing.assert_allclose(m @ m.T, np.eye(3), atol=1e-12)
        np.testing.assert_allclose(np.cross(r, u), -f, atol=1e-12)  # camera looks down -z: z = -forward
        assert abs(r[1]) < 1e-12  # no roll


def test_default_basis():
    f, r, u = ORIGIN.basis()
    np.testing.assert_allclose(f, [0, 0, -1], atol=1e-15)
    np.testing.assert_allclose(r, [1, 0, 0], atol=1e-15)
    np.testing.assert_allclose(u, [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(ORIGIN.replace(yaw=math.pi / 2).basis()[0], [-1, 0, 0], atol=1e-15)


def test_from_look_at_round_trip():
    rng = np.random.default_rng(2)
    for _ in range(200):
        pos, target = rng.normal(size=3) * 5, rng.normal(size=3) * 5
        s = CameraState.from_look_at(pos, target, fov=30, aperture=0.01)
        d = target - pos
        np.testing.assert_allclose(s.basis()[0], d / np.linalg.norm(d), atol=1e-9)
        assert s.focus_distance == pytest.approx(np.linalg.norm(d))
        assert (s.fov, s.aperture) == (30.0, 0.01)


@pytest.mark.parametrize("target", [(0, 0, 0), (0, 5, 0), (0, -5, 0)])
def test_from_look_at_degenerate_has_no_nan(target):
    s = CameraState.from_look_at((0, 0, 0), target)
    assert all(np.isfinite(v).all() for v in s.basis())
    assert abs(s.pitch) <= PITCH_LIMIT
    assert s.focus_distance > 0


def test_an_orthographic_camera_flies_and_stays_orthographic():
    from renderer.scene.description import CameraSpec
    from viewer.session import camera_from_spec
    from viewer.window import camera_frame

    spec = CameraSpec(position=(0.0, 0.0, 5.0), look_at=(0.0, 0.0, 0.0), projection="orthographic", ortho_height=3.0)
    state = camera_from_spec(spec)
    ctl = FreeLookController(state, move_speed=2.0)
    assert ctl.update(0.1, {"w", "d"}, None, False)
    ctl.update(0.1, set(), (10.0, 0.0), True)
    assert ctl.update(0.1, set(), (30.0, 0.0), True)  # a drag turns it
    moved_state = ctl.state
    assert (moved_state.projection, moved_state.ortho_height) == ("orthographic", 3.0)
    frame = camera_frame(moved_state)
    assert frame.orthographic and frame.half_height == 1.5
    np.testing.assert_allclose(frame.forward, moved_state.basis()[0])
