"""The viewer's state machine without a window: reset rules, adaptive resolution, names."""
import math
from dataclasses import replace
from datetime import datetime
from pathlib import Path
from types import SimpleNamespace

import pytest

from renderer.film.pixel_slices import ROUND_SLICES
from viewer.controller import MAX_SPEED
from viewer.session import (MAX_PRESENT_INTERVAL, MIN_PRESENT_INTERVAL, MIN_SCALE, MOVING_PROBE_SLICES,
                            STILL_OVERRUN_SECONDS, STILL_PRESENT_SHARE, Controls, Every, RateMeter,
                            ResolutionController, ViewerSession, fix_max_depth, screenshot_dir, screenshot_paths,
                            screenshot_stem)

FULL = (960, 540)
PIXELS = FULL[0] * FULL[1]


def fake_scene(name="a", position=(0.0, 1.0, 5.0), max_depth=8, exposure=0.0):
    camera = SimpleNamespace(position=position, look_at=(0.0, 1.0, 0.0), up=(0.0, 1.0, 0.0), fov=40.0,
                             aperture=0.0, focus_distance=5.0, projection="perspective", ortho_height=2.0)
    return SimpleNamespace(name=name, camera=camera, render=SimpleNamespace(max_depth=max_depth, exposure=exposure))


def make_session(settle=0.1, scenes=("a", "b", "c"), skip_preview=True):
    """A session on scene "a". With skip_preview, the scene's first (reduced-resolution preview)
    frame has been planned already, at t = -1 s, so tests start from the full-resolution state."""
    paths = [Path(f"/scenes/{n}.toml") for n in scenes]
    s = ViewerSession(paths, 0, ["path", "normals"], "path", FULL, target_seconds=0.05, settle_seconds=settle)
    s.enter_scene(0, fake_scene(scenes[0]))
    if skip_preview:
        s.plan_frame(-1.0)
        s.resets = 0
    return s


# --- resolution controller ----------------------------------------------------------------------


def simulate(ctl, seconds_per_pixel, frames, overhead=0.0):
    """Moving frames whose render time is exactly cost * pixels; returns the sizes chosen."""
    sizes = []
    for i in range(frames):
        size = ctl.moving_size(starting=(i == 0))
        render = seconds_per_pixel * size[0] * size[1]
        ctl.record(render, size[0] * size[1], render + overhead)
        sizes.append(size)
    return sizes


def test_moving_lowers_resolution_to_meet_the_target():
    ctl = ResolutionController(FULL, target_seconds=0.05)
    ctl.record(2.0, PIXELS, 2.0)  # a still frame: full resolution took 2 s
    sizes = simulate(ctl, 2.0 / PIXELS, 20)
    w, h = sizes[-1]
    render = 2.0 / PIXELS * w * h
    assert render == pytest.approx(0.05, rel=0.1)
    # From the still frame's cost the very first moving frame is already about right.
    assert 2.0 / PIXELS * sizes[0][0] * sizes[0][1] <= 0.05 * 1.1
    assert w / h == pytest.approx(FULL[0] / FULL[1], rel=0.05)


def test_overhead_outside_rendering_is_taken_from_the_budget():
    ctl = ResolutionController(FULL, target_seconds=0.05)
    ctl.record(1.0, PIXELS, 1.0)
    sizes = simulate(ctl, 1.0 / PIXELS, 40, overhead=0.02)
    w, h = sizes[-1]
    assert 1.0 / PIXELS * w * h + 0.02 == pytest.approx(0.05, rel=0.1)


def test_cheap_render_goes_back_up_to_full_resolution_smoothly():
    ctl = ResolutionController(FULL, target_seconds=0.05)
    ctl.record(50.0, PIXELS)  # expensive: drops to the floor
    assert ctl.moving_size(starting=True) == ctl.size_for(MIN_SCALE)
    # Now it is cheap (say a debug view): the scale rises by a fraction per frame, no jump.
    sizes = simulate(ctl, 1e-9, 30)[1:]
    widths = [w for w, _ in sizes]
    assert widths == sorted(widths)
    assert widths[0] < FULL[0]
    assert sizes[-1] == FULL


def test_scale_is_clamped_to_one_sixteenth():
    ctl = ResolutionController(FULL, target_seconds=0.05)
    ctl.record(1000.0, PIXELS)
    w, h = ctl.moving_size(starting=True)
    assert (w, h) == (60, 34)  # 960/16, 540/16 rounded
    tiny = ResolutionController((20, 10), target_seconds=0.05)
    tiny.record(1000.0, 200)
    assert tiny.moving_size(starting=True) == (1, 1)


def test_costs_are_kept_per_context():
    ctl = ResolutionController(FULL, target_seconds=0.05)
    ctl.set_context("path")
    ctl.record(2.0, PIXELS)
    ctl.set_context("normals")
    assert ctl.cost is None
    ctl.record(0.01, PIXELS)
    ctl.set_context("path")
    assert ctl.cost == pytest.approx(2.0 / PIXELS)


def test_a_dearer_view_is_taken_at_once_a_cheaper_one_smoothly():
    """The camera flies into a wall 3x dearer per pixel: the next frame is planned for the new
    cost at once; a cheaper view is approached by COST_SMOOTHING per frame."""
    from viewer.session import COST_SMOOTHING

    ctl = ResolutionController(FULL, target_seconds=0.05)
    ctl.record(1.0, PIXELS)
    ctl.record(3.0, PIXELS)
    assert ctl.cost == pytest.approx(3.0 / PIXELS)
    ctl.record(1.0, PIXELS)
    assert ctl.cost == pytest.approx((3.0 + COST_SMOOTHING * (1.0 - 3.0)) / PIXELS)


def test_a_moving_frame_plans_its_rest_from_its_first_quarter():
    ctl = ResolutionController(FULL, target_seconds=0.05)
    budget = ctl.render_budget()
    rest = ROUND_SLICES - MOVING_PROBE_SLICES
    assert ctl.moving_rest_slices(budget / 10) == rest  # cheap as planned: the whole round
    # Four times dearer than planned: the quarter took the whole budget, nothing more renders.
    assert ctl.moving_rest_slices(budget) == 0 and ctl.moving_rest_slices(4 * budget) == 0
    # In between, as many slices as fit at the quarter's own cost.
    assert abs(ctl.moving_rest_slices(budget / 2) - MOVING_PROBE_SLICES) <= 1  # (rounding down)
    assert abs(ctl.moving_rest_slices(budget / 3) - 2 * MOVING_PROBE_SLICES) <= 1
    for bad in (0.0, -1.0, math.nan, math.inf):
        assert ctl.moving_rest_slices(bad) == rest  # nothing measured: render as planned


def test_still_slices_fill_the_budget():
    ctl = ResolutionController(FULL, target_seconds=0.05)
    assert ctl.still_slices() == 1  # nothing measured: the cheapest frame there is
    ctl.record(0.005, PIXELS)  # 5 ms per full-resolution sample
    assert ctl.still_slices() == 10 * ROUND_SLICES
    ctl.record(10.0, PIXELS * 1000)  # noise in the measurements never gives 0
    assert ctl.still_slices() >= 1
    ctl2 = ResolutionController(FULL, target_seconds=0.05, max_spp=4)
    ctl2.record(1e-6, PIXELS)
    assert ctl2.still_slices() == 4 * ROUND_SLICES


def test_a_slow_scene_renders_a_share_of_a_sample_per_still_frame():
    """1.2 s per sample per pixel (the showcase at 960x540 on two cores) and a 50 ms budget: a
    still frame renders the slices that fit (floor(0.05 / (1.2 / 256)) = 10), not a whole sample."""
    ctl = ResolutionController(FULL, target_seconds=0.05)
    ctl.record(1.2, PIXELS)
    assert ctl.still_slices() == int(0.05 // (1.2 / ROUND_SLICES)) == 10


def test_time_reserved_for_other_work_comes_out_of_the_render_budget():
    """A still frame that also refreshes the HUD's statistics (say 20 ms of a 50 ms budget)
    renders the slices that fit the other 30 ms, so it is no longer than the frames around it."""
    ctl = ResolutionController(FULL, target_seconds=0.05)
    ctl.record(1.2, PIXELS)
    slice_cost = 1.2 / ROUND_SLICES
    assert ctl.still_slices(0.020) == int(0.030 // slice_cost) == 6
    assert ctl.still_slices(1.0) == 1  # never less than a slice
    s = make_session(settle=0.0)
    s.resolution.record(1.2, PIXELS)
    assert s.plan_frame(0.0, reserved_seconds=0.020).slices == 6
    assert s.plan_frame(0.1).slices == 10


def test_a_frame_that_presents_leaves_the_present_out_of_its_render_budget():
    """Presenting costs 13 ms of a 50 ms frame: a frame that presents renders 37 ms worth of
    slices, one that only renders and reads input the whole 50 ms."""
    ctl = ResolutionController(FULL, target_seconds=0.05)
    ctl.record(1.2, PIXELS)
    for _ in range(60):
        ctl.record_present(0.013)
    assert ctl.present_seconds == pytest.approx(0.013)
    slice_cost = 1.2 / ROUND_SLICES
    assert ctl.still_slices(presenting=True) == int(0.037 // slice_cost) == 7
    # (10 slices end 3.1 ms short of 50 ms, 11 end 1.6 ms past it: nearer, within the overrun)
    assert ctl.still_slices(presenting=False) == int(0.05 // slice_cost) + 1 == 11
    s = make_session(settle=0.0)
    s.resolution.record(1.2, PIXELS)
    s.resolution.present_seconds = 0.013
    assert s.plan_frame(0.0, presenting=False).reset  # (the first full-size frame presents anyway)
    assert s.plan_frame(0.1, presenting=False).slices == 11
    assert s.plan_frame(0.2, presenting=True).slices == 7
    ctl.record_present(math.nan)  # a bad measurement is ignored
    assert ctl.present_seconds == pytest.approx(0.013)


def test_a_still_frame_that_resets_leaves_its_present_out_of_its_budget():
    """The first still frame after a change restarts the accumulation and presents it, asked or
    not: it plans as a presenting frame (no overrun, the present out of its budget), and the
    frames after it, which only render, as those do."""
    s = make_session(settle=0.0)
    s.resolution.record(1.2, PIXELS)
    s.resolution.present_seconds = 0.013
    s.request_reset(interactive=False)  # a render setting changed while still
    first = s.plan_frame(0.0, presenting=False)
    assert first.reset and not first.interactive and first.presents
    assert first.slices == s.resolution.still_slices(presenting=True) == 7
    after = s.plan_frame(0.1, presenting=False)
    assert not after.reset and after.slices == s.resolution.still_slices(presenting=False) == 11
    assert not after.presents


@pytest.mark.parametrize("slice_ms, slices", [(11.4, 4),  # 3 end 10.1 short, 4 end 1.3 past: the nearer
                                               (8.4, 5),  # 5 end 2.9 short, 6 end 5.5 past: beyond the overrun
                                               (14.0, 3),  # 3 end 2.9 short, 4 end 11.1 past
                                               (7.0, 6),  # 6 end 2.9 short, 7 end 4.1 past: further than short
                                               (60.0, 1)])  # a slice dearer than the budget: one, as before
def test_a_frame_that_only_renders_takes_the_slice_count_nearest_its_budget(slice_ms, slices):
    """Without presenting, a still frame of a slow scene (a slice costs 8-14 ms) takes one slice
    more when that ends nearer the 45 ms budget, at most STILL_OVERRUN_SECONDS past it; a frame
    that presents (the frame an input waits for) keeps within its budget."""
    assert STILL_OVERRUN_SECONDS == 0.005
    ctl = ResolutionController(FULL, target_seconds=0.045)
    ctl.record(slice_ms * 1e-3 * ROUND_SLICES, PIXELS)
    assert ctl.still_slices(presenting=False) == slices
    assert ctl.still_slices(presenting=True) == max(1, int(0.045 // (slice_ms * 1e-3)))


@pytest.mark.parametrize("present, interval", [(0.0, MIN_PRESENT_INTERVAL), (0.006, 0.006 / STILL_PRESENT_SHARE),
                                               (0.013, 0.013 / STILL_PRESENT_SHARE), (1.0, MAX_PRESENT_INTERVAL)])
def test_a_still_view_redraws_so_that_presenting_costs_a_small_share(present, interval):
    ctl = ResolutionController(FULL)
    ctl.present_seconds = present
    assert ctl.present_interval() == pytest.approx(interval)
    assert present / ctl.present_interval() <= STILL_PRESENT_SHARE + 1e-12 or interval == MAX_PRESENT_INTERVAL


def test_bad_measurements_are_ignored():
    ctl = ResolutionController(FULL)
    for render, pixels in ((0.0, 100), (1.0, 0), (math.inf, 100), (math.nan, 100)):
        ctl.record(render, pixels)
    assert ctl.cost is None


# --- reset rules --------------------------------------------------------------------------------


def test_first_frame_is_a_preview_then_idle_frames_do_not_reset():
    s = make_session(skip_preview=False)
    first = s.plan_frame(0.0)  # a scene's first frame: a reduced preview, so a picture comes at once
    assert first.reset and first.interactive and first.size[0] < FULL[0]
    still = s.plan_frame(1.0)  # then full resolution from a clean film
    assert still.reset and still.size == FULL and not still.interactive
    for i in range(1, 50):
        s.update_camera(1 / 30, set(), (100.0, 100.0 + i), False)  # cursor moves, no button
        plan = s.plan_frame(1.0 + i / 30)
        assert not plan.reset
        assert plan.size == FULL
    assert s.resets == 2


def test_camera_motion_resets_at_reduced_resolution_then_full_once_still():
    s = make_session(settle=0.1)
    s.plan_frame(0.0)
    s.resolution.record(2.0, PIXELS)
    t = 0.0
    for _ in range(5):
        t += 0.05
        assert s.update_camera(0.05, {"w"}, None, False)
        plan = s.plan_frame(t)
        assert plan.reset and plan.interactive
        assert plan.size[0] < FULL[0]
    # Still, but within the settle time: keeps accumulating at the reduced size.
    t += 0.05
    assert not s.update_camera(0.05, set(), None, False)
    plan = s.plan_frame(t)
    assert not plan.reset and plan.interactive
    # Settled: one reset at full resolution, then accumulation.
    t += 0.1
    plan = s.plan_frame(t)
    assert plan.reset and plan.size == FULL and not plan.interactive
    t += 0.1
    assert not s.plan_frame(t).reset


def test_drag_rotates_and_resets():
    s = make_session(settle=0.0)
    s.plan_frame(0.0)
    s.update_camera(0.03, set(), (100.0, 100.0), True)  # the first drag frame only records
    assert not s.plan_frame(0.03).reset
    assert s.update_camera(0.03, set(), (140.0, 100.0), True)
    assert s.plan_frame(0.06).reset
    assert s.plan_frame(0.09).reset  # settle 0: the next still frame returns to full size
    assert not s.plan_frame(0.12).reset


@pytest.mark.parametrize("change", [
    lambda s: s.set_integrator("normals"),
    lambda s: s.next_integrator(),
    lambda s: s.cycle_scene(+1, lambda p: fake_scene(p.stem)),
    lambda s: s.apply_controls(Controls(0.0, "aces", 3, 40.0, 0.0, 5.0)),  # max depth
    lambda s: s.apply_controls(Controls(0.0, "aces", 8, 60.0, 0.0, 5.0)),  # field of view
    lambda s: s.apply_controls(Controls(0.0, "aces", 8, 40.0, 0.1, 5.0)),  # aperture
    lambda s: s.apply_controls(Controls(0.0, "aces", 8, 40.0, 0.0, 2.0)),  # focus distance
    lambda s: s.set_focus_distance(1.5),
    lambda s: s.reset_camera(),
])
def test_settings_scene_and_integrator_changes_reset(change):
    s = make_session(settle=0.0)
    s.apply_controls(Controls(0.0, "aces", 8, 40.0, 0.0, 5.0))
    s.plan_frame(0.0)
    assert not s.plan_frame(0.1).reset
    change(s)
    assert s.plan_frame(0.2).reset


@pytest.mark.parametrize("controls", [
    Controls(2.5, "aces", 8, 40.0, 0.0, 5.0),
    Controls(0.0, "reinhard", 8, 40.0, 0.0, 5.0),
    Controls(0.0, "aces", 8, 40.0, 0.0, 5.0),
])
def test_display_settings_do_not_reset(controls):
    s = make_session(settle=0.0)
    s.apply_controls(Controls(0.0, "aces", 8, 40.0, 0.0, 5.0))
    s.plan_frame(0.0)
    assert not s.apply_controls(controls)
    assert not s.plan_frame(0.1).reset
    assert s.exposure == controls.exposure and s.tonemapper == controls.tonemapper


def test_switching_to_the_same_integrator_is_no_change():
    s = make_session()
    s.plan_frame(0.0)
    assert not s.set_integrator("path")
    assert not s.plan_frame(1.0).reset
    with pytest.raises(ValueError):
        s.set_integrator("nonsense")


def test_max_depth_slider_steps_over_zero():
    assert fix_max_depth(0, -1) == 1
    assert fix_max_depth(0, 1) == -1
    assert fix_max_depth(5, 4) == 5
    assert fix_max_depth(-7, 4) == -1


def test_debug_integrator_tonemapper_wins():
    s = make_session()
    assert s.display_tonemapper(None) == "aces"
    assert s.display_tonemapper("none") == "none"
    assert s.cycle_tonemapper(["aces", "reinhard", "none"]) == "reinhard"


# --- scenes -------------------------------------------------------------------------------------


def test_cycle_scene_wraps_and_goes_back():
    s = make_session()
    load = lambda p: fake_scene(p.stem)
    assert s.cycle_scene(+1, load).name == "b"
    assert s.cycle_scene(+1, load).name == "c"
    assert s.cycle_scene(+1, load).name == "a"
    assert s.cycle_scene(-1, load).name == "c"
    assert s.error is None


def test_unreadable_scene_is_skipped_with_a_one_line_error():
    s = make_session()

    def load(path):
        if path.stem == "b":
            raise ValueError("b.toml: line 3: expected '='\nmore detail")
        return fake_scene(path.stem)

    assert s.cycle_scene(+1, load).name == "c"
    assert s.scene_path.stem == "c"
    assert "skipped b.toml" in s.error and "\n" not in s.error
    assert s.cycle_scene(+1, load).name == "a"
    assert s.error is None  # nothing was skipped this time


def test_no_loadable_scene_keeps_the_current_one():
    s = make_session()
    s.plan_frame(0.0)

    def load(path):
        raise OSError("unreadable")

    assert s.cycle_scene(+1, load) is None
    assert s.scene_path.stem == "a"
    assert s.error.count("skipped") == 3


def test_scene_camera_is_remembered():
    s = make_session()
    load = lambda p: fake_scene(p.stem)
    s.update_camera(0.1, {"w"}, None, False)
    moved = s.controller.state
    s.cycle_scene(+1, load)
    assert s.controller.state != moved
    s.cycle_scene(-1, load)
    assert s.controller.state == moved


def test_a_scene_brings_its_exposure():
    s = make_session()
    s.exposure = 3.0  # the slider's, for the scene being left
    s.switch_scene(1, fake_scene("b", exposure=-1.5))
    assert s.exposure == -1.5


def test_move_speed_scales_with_the_scene():
    s = make_session()
    near = s.controller.move_speed
    s.enter_scene(1, fake_scene("b", position=(0.0, 1.0, 50.0)))
    assert s.controller.move_speed == pytest.approx(10 * near)


# --- helpers ------------------------------------------------------------------------------------


def test_screenshot_names(tmp_path):
    when = datetime(2026, 11, 22, 1, 2, 3)
    assert screenshot_stem("showcase", "path", 128, when) == "showcase_path_0128spp_20261122-010203"
    png, exr = screenshot_paths(tmp_path, "showcase", "path", 128, when)
    assert png == tmp_path / "showcase_path_0128spp_20261122-010203.png"
    assert exr == tmp_path / "showcase_path_0128spp_20261122-010203.exr"
    png.write_bytes(b"x")  # taken within the same second: no overwrite
    png2, exr2 = screenshot_paths(tmp_path, "showcase", "path", 128, when)
    assert png2.name == "showcase_path_0128spp_20261122-010203-2.png" and exr2.suffix == ".exr"
    assert screenshot_stem("my scene/x", "path", 5, when).startswith("my-scene-x_path_0005spp")


def test_screenshot_dir_setting(tmp_path, monkeypatch):
    monkeypatch.delenv("LANTERN_SCREENSHOT_DIR", raising=False)
    assert screenshot_dir().name == "screenshots"
    monkeypatch.setenv("LANTERN_SCREENSHOT_DIR", str(tmp_path))
    assert screenshot_dir() == tmp_path
    assert screenshot_dir(tmp_path / "x") == tmp_path / "x"


def test_every_limits_the_rate():
    every = Every(0.25)
    calls = [t / 100 for t in range(100)]  # 1 s at 100 fps
    assert sum(every(t) for t in calls) == 4


def test_every_can_be_asked_without_taking_its_turn():
    every = Every(1.0)
    assert every.ready(0.0) and every.ready(0.0)  # asking twice takes nothing
    every.mark(0.0)
    assert not every.ready(0.5) and every.ready(1.0)
    assert not every(0.9) and every(1.0) and not every.ready(1.5)


def test_rate_meter():
    meter = RateMeter(window=1.0)
    for i in range(61):
        meter.add(i / 30, 1000)
    assert meter.rate() == pytest.approx(30_000, rel=0.05)


def test_move_speed_control_is_not_a_change():
    s = make_session(settle=0.0)
    s.plan_frame(0.0)
    assert s.controls().move_speed == s.controller.move_speed
    assert not s.apply_controls(replace(s.controls(), move_speed=3.0))
    assert s.controller.move_speed == 3.0
    assert not s.plan_frame(0.1).reset
    s.apply_controls(replace(s.controls(), move_speed=1e9))
    assert s.controller.move_speed == MAX_SPEED
