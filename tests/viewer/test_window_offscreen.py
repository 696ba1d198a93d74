"""The viewer's frame loop on an off-screen GGUI window (show_window=False), with synthetic input.

One ViewerApp serves the whole module: the first render of a scene compiles for seconds, so each
scene and integrator compiles once here. Frames go through `ViewerApp.step()`, exactly what the
real loop runs, with `FrameInput`s made up instead of GGUI events.
"""
import re
import time

import numpy as np
import pytest

from renderer.bench.interactive import settle_still
from renderer.output.image_io import read_exr
from renderer.integrators import INTEGRATORS
from renderer.scene.catalog import resolve_scene, scene_files
from renderer.film.pixel_slices import BANDS, ROUND_SLICES, filled_mean_array, slice_mask
from renderer.output.tonemap import tonemap_array, unpack_rgba8
from viewer import hud
from viewer.display import UPDATE_SLICES
from viewer.session import MOVING_PROBE_SLICES
from viewer.window import FrameInput, StillClocks, ViewerApp, window_buffer_to_image

SIZE = (128, 72)
# A frame counts as "not blank" above this standard deviation of its 8-bit pixel values. A
# constant image (black canvas, failed upload, all-sky miss) has 0; the scenes' objects against
# floor and sky put the deviation in the tens, and Monte Carlo noise alone at a few spp on a
# uniform surface stays well below 10 after tone mapping.
MIN_PIXEL_STD = 10.0
SCENES = scene_files()  # SDF and mesh scenes alike: one viewer shows both worlds


@pytest.fixture(scope="module")
def app(tmp_path_factory):
    # Every frame presents (the tests read each frame's image back); the still view's present
    # interval has its own test.
    viewer = ViewerApp(resolve_scene("showcase"), size=SIZE, show_window=False,
                       screenshot_folder=tmp_path_factory.mktemp("shots"), settle_seconds=0.0,
                       still_present_interval=0.0)
    yield viewer


def settle(app, frames=3):
    """Render until a scene's kernels are compiled and a few still frames accumulated."""
    for _ in range(frames + 1):  # the first may only show the 'compiling...' notice
        app.step()
    while app.notice:
        app.step()


def sample_every_pixel(app, max_frames=400):
    """Render still frames until each pixel holds a sample. How far a few frames get into the
    interleaved first round depends on the machine's speed, and an image of scattered samples
    filled from their neighbours says little about whether the scene shows."""
    for _ in range(max_frames):
        if app.renderer.film.sample_counts().min() >= 1:
            return
        app.step()
    raise AssertionError(f"{max_frames} still frames left pixels without a sample")


def expected_display(app):
    """The film tone-mapped, pixels a partial first round has not reached filled from their
    nearest sampled grid point (renderer/film/pixel_slices.py)."""
    s, film = app.session, app.renderer.film
    mapper = s.display_tonemapper(INTEGRATORS[s.integrator].display_tonemapper)
    shown = filled_mean_array(app.renderer.image(), film.sample_counts() + film.rejected_counts())
    np.testing.assert_array_equal(shown, app.renderer.shown_image())
    return tonemap_array(shown, s.exposure, mapper)


@pytest.mark.parametrize("path", SCENES, ids=[p.stem for p in SCENES])
def test_each_scene_shows_the_film(app, path):
    app.select_scene(path)
    app.session.set_integrator("path")
    app.session.hud_visible = False
    settle(app)
    sample_every_pixel(app)
    assert app.renderer.scene.path.resolve() == path.resolve()
    assert (app.renderer.film.width, app.renderer.film.height) == SIZE
    # no NaN or infinite sample anywhere in a shipped scene (the film counts those it rejects)
    assert app.renderer.film.stats()["rejected"] == 0
    shown = window_buffer_to_image(app.last_frame)
    assert shown.shape == (SIZE[1], SIZE[0], 3)
    assert shown.std() > MIN_PIXEL_STD
    # The canvas shows exactly the tone-mapped film (8-bit rounding apart), upright: the display
    # image's bytes, unaltered.
    difference = np.abs(shown.astype(int) - expected_display(app).astype(int))
    assert difference.max() <= 1
    np.testing.assert_array_equal(shown, unpack_rgba8(app.display.shown))


def test_hud_is_drawn_over_the_image(app):
    app.select_scene(resolve_scene("showcase"))
    app.session.hud_visible = True
    settle(app, 2)
    shown = window_buffer_to_image(app.last_frame).astype(int)
    expected = expected_display(app).astype(int)
    rect = hud.hud_rect(SIZE)
    x1, y1 = int(rect.x * SIZE[0]) + 1, int(rect.y * SIZE[1]) + 1
    inside = np.abs(shown[y1:y1 + 10, x1:x1 + 20] - expected[y1:y1 + 10, x1:x1 + 20])
    assert (inside > 2).mean() > 0.5  # the panel covers its corner of the image
    assert np.abs(shown[-3:, -3:] - expected[-3:, -3:]).max() <= 1  # and not the opposite one
    app.step(FrameInput(pressed=("h",)))
    assert not app.session.hud_visible


def test_idle_frames_accumulate_without_reset(app):
    app.session.hud_visible = True  # untouched sliders must not count as changes
    app.session.set_focus_distance(3.1234567)  # not representable in float32, like the slider's
    settle(app, 1)  # frames with the new focus distance
    # (alone in a session, the app's first frames are the preview's, then a still frame that resets)
    assert settle_still(app)
    resets, slices = app.session.resets, app.renderer.slices_done
    for _ in range(3):
        app.step(FrameInput(cursor=(0.5, 0.5)))  # a cursor without a button is no motion
    assert app.session.resets == resets
    assert app.renderer.slices_done > slices
    # Every pixel has the whole rounds; those of the round in progress's slices one more.
    counts = app.renderer.film.sample_counts() + app.renderer.film.rejected_counts()
    assert counts.min() == app.renderer.samples_done
    assert counts.mean() == pytest.approx(app.renderer.mean_spp, rel=0.05)


def test_movement_lowers_the_resolution_then_returns_to_full(app):
    settle(app, 1)
    resolution = app.session.resolution
    target = resolution.target_seconds
    resolution.target_seconds = 1e-4  # nothing renders this fast: forces the smallest size
    try:
        position = app.session.controller.state.position
        for _ in range(3):
            app.step(FrameInput(held=frozenset({"w"})))
            assert app.last_plan.interactive and app.last_plan.reset
        assert app.session.controller.state.position != position
        film = app.renderer.film
        assert (film.width, film.height) == resolution.size_for(1 / 16) == (8, 4)
        # The canvas got the reduced image at its own size (GGUI stretches it over the window).
        assert app.display.shown.shape == (8, 4)
        shown = window_buffer_to_image(app.last_frame)
        assert shown.shape == (SIZE[1], SIZE[0], 3) and shown.std() > MIN_PIXEL_STD / 2
        # Dragging with the right button looks around, also at the reduced size.
        yaw = app.session.controller.state.yaw
        app.step(FrameInput(cursor=(0.5, 0.5), buttons=frozenset({"RMB"})))
        app.step(FrameInput(cursor=(0.6, 0.5), buttons=frozenset({"RMB"})))
        assert app.session.controller.state.yaw < yaw  # dragged right: turned right
        assert film.width < SIZE[0]
    finally:
        resolution.target_seconds = target
    app.step(FrameInput(cursor=(0.6, 0.5)))  # still (settle time 0 here): full size, reset
    assert (film.width, film.height) == SIZE and app.last_plan.reset
    assert app.display.shown is app.display.window_image
    slices = app.renderer.slices_done
    app.step()
    assert not app.last_plan.reset and app.renderer.slices_done > slices


def test_a_moving_frame_stops_where_its_budget_ends_and_shows_every_pixel(app):
    """A moving frame renders a quarter of its pixel slices, then what its budget allows at the
    cost they measured: a frame that got dearer ends short, its other pixels filled from the grid
    it rendered; a cheap one renders the whole round."""
    app.session.hud_visible = False
    settle(app, 1)
    resolution = app.session.resolution
    target = resolution.target_seconds
    try:
        resolution.target_seconds = 1e-4  # the quarter alone overruns this budget
        app.step(FrameInput(held=frozenset({"w"})))
        assert app.last_plan.interactive and app.last_plan.reset
        assert app.moving_slices == MOVING_PROBE_SLICES == app.renderer.slices_done
        film = app.renderer.film
        counts = film.sample_counts() + film.rejected_counts()
        assert (film.width, film.height) == (8, 4) and counts.sum() == 8  # every other pixel of every other row
        shown = window_buffer_to_image(app.last_frame)
        assert shown.std() > MIN_PIXEL_STD / 2
        assert np.abs(unpack_rgba8(app.display.shown).astype(int) - expected_display(app).astype(int)).max() <= 1
        resolution.target_seconds = 10.0  # every frame fits
        app.step(FrameInput(held=frozenset({"w"})))
        assert app.last_plan.reset and app.moving_slices == ROUND_SLICES == app.renderer.slices_done
    finally:
        resolution.target_seconds = target
        app.session.hud_visible = True


def test_left_drag_on_the_hud_does_not_turn_the_camera(app):
    settle(app, 1)
    app.session.hud_visible = True
    rect = hud.hud_rect(SIZE)
    inside = (rect.x + rect.width / 2, 1.0 - (rect.y + rect.height / 2))  # GGUI y is up
    state = app.session.controller.state
    app.step(FrameInput(cursor=inside, buttons=frozenset({"LMB"})))
    app.step(FrameInput(cursor=(inside[0] + 0.05, inside[1]), buttons=frozenset({"LMB"})))
    assert app.session.controller.state == state
    app.step(FrameInput(cursor=(0.9, 0.2)))  # released
    app.step(FrameInput(cursor=(0.9, 0.2), buttons=frozenset({"LMB"})))
    app.step(FrameInput(cursor=(0.95, 0.2), buttons=frozenset({"LMB"})))
    assert app.session.controller.state.yaw != state.yaw
    app.step(FrameInput(cursor=(0.95, 0.2)))


def test_screenshot_writes_png_and_exr(app, tmp_path):
    app.screenshot_folder = tmp_path
    app.session.hud_visible = True  # the HUD is not part of the screenshot
    settle(app, 2)
    for _ in range(50):  # still frames may render a share of a round each: wait for a whole sample
        if app.renderer.slices_done >= ROUND_SLICES:
            break
        app.step()
    app.step(FrameInput(pressed=("p",)))
    s = app.session
    pngs = sorted(tmp_path.glob("*.png"))
    exrs = sorted(tmp_path.glob("*.exr"))
    assert len(pngs) == len(exrs) == 1
    match = re.fullmatch(r"showcase_(\w+)_(\d{4})spp_\d{8}-\d{6}", pngs[0].stem)
    assert match and match.group(1) == s.integrator and exrs[0].stem == pngs[0].stem
    import imageio.v3 as iio

    png = iio.imread(pngs[0])
    linear = read_exr(exrs[0])
    assert png.shape == (SIZE[1], SIZE[0], 3) and linear.shape == png.shape
    assert png.std() > MIN_PIXEL_STD
    # The PNG is the EXR tone-mapped the way the display does it.
    mapper = s.display_tonemapper(INTEGRATORS[s.integrator].display_tonemapper)
    assert np.abs(png.astype(int) - tonemap_array(linear, s.exposure, mapper).astype(int)).max() <= 1
    assert int(match.group(2)) >= 1


def test_exposure_changes_display_not_accumulation(app):
    settle(app, 1)
    app.session.hud_visible = False
    resets = app.session.resets
    app.session.exposure = 2.0
    try:
        app.step()
        assert app.session.resets == resets
        bright = window_buffer_to_image(app.last_frame)
        assert np.abs(bright.astype(int) - expected_display(app).astype(int)).max() <= 1
    finally:
        app.session.exposure = 0.0


def test_integrator_switch_shows_a_notice_then_renders(app):
    settle(app, 1)
    app.session.hud_visible = False
    spp = app.renderer.samples_done
    app.step(FrameInput(pressed=("i",)))
    name = app.session.integrator
    assert name != "path"
    if app.notice:  # not compiled yet in this process: this frame only showed the notice
        assert name in app.notice and "compiling" in app.notice
        assert app.renderer.samples_done == spp  # nothing rendered (or reset) on that frame
        app.step()
        assert app.notice is None
        assert app.compile_seconds > 0
    renderer, plan = app.renderer, app.last_plan
    whole_passes = max(1, plan.slices // ROUND_SLICES) * ROUND_SLICES  # an integrator without slices
    sliced = renderer.is_sliced(name, renderer.features())
    assert plan.reset and renderer.slices_done == (plan.slices if sliced else whole_passes)
    settle(app, 1)
    shown = window_buffer_to_image(app.last_frame)
    assert np.abs(shown.astype(int) - expected_display(app).astype(int)).max() <= 1
    assert shown.std() > MIN_PIXEL_STD
    app.session.set_integrator("path")


def floor_distance_under(camera, u: float, v: float, size) -> float:
    """Distance along the view direction to the plane y = 0 (showcase's floor) under (u, v) in
    [0,1]^2 (y up), the pinhole camera's ray worked out here in float64."""
    position, forward, right, up = (np.array(x, np.float64) for x in (camera.position, camera.forward,
                                                                        camera.right, camera.up))
    tan_half = np.tan(np.radians(camera.fov) / 2.0)
    direction = forward + (2 * u - 1) * tan_half * size[0] / size[1] * right + (2 * v - 1) * tan_half * up
    direction /= np.linalg.norm(direction)
    assert direction[1] < 0.0  # the ray goes down to the floor
    return float(-position[1] / direction[1] * direction.dot(forward))


def test_focus_at_cursor(app):
    """Key f: the focus distance becomes the distance along the view to the surface under the
    cursor, here showcase's floor, worked out independently. The probe is a kernel of the scene's
    program; a failure to compile or run it shows as the session's error line, and fails this test
    (it once failed to compile: a `break` of the SDF march in the kernel's outermost scope, which
    Taichi refuses; it now runs the march in a parallel loop of one). Its ray once carried the cone
    of a pixel of a 1x1 film, as wide as the view, and on SDF scenes the march stopped within that
    cone, metres short (1.56 m for this floor at 3.97 m); it now marches without a cone."""
    app.select_scene(resolve_scene("showcase"))
    settle(app, 1)
    app.session.error = None
    before = app.session.controller.state.focus_distance
    resets = app.session.resets
    cursor = (0.5, 0.2)  # the floor, below the centre and in front of the objects
    camera = app._camera_frame()
    expected = floor_distance_under(camera, *cursor, (app.renderer.film.width, app.renderer.film.height))
    app.step(FrameInput(pressed=("f",), cursor=cursor))
    assert app.session.error is None, app.session.error
    after = app.session.controller.state.focus_distance
    assert after != before and 0.1 < after < 20.0
    # The SDF march stops within its finest hit threshold of the surface: here 6e-5 of the distance.
    assert after == pytest.approx(expected, rel=1e-3)
    assert app.session.resets == resets + 1
    assert app.session.message is not None and f"focus {after:.3g} m" in app.session.message


def test_unreadable_scene_is_skipped(app, tmp_path):
    bad = tmp_path / "broken.toml"
    bad.write_text("[scene\nname = ")
    s = app.session
    saved = list(s.scenes)
    s.scenes[:] = [s.scene_path, bad]
    try:
        app.step(FrameInput(pressed=("n",)))
        assert app.notice == "loading broken..."  # this frame only showed the notice
        before = s.scene_path
        app.step()  # the next one tried to load it
        assert s.scene_path == before and s.scene_path != bad
        assert "skipped broken.toml" in s.error and app.notice is None
        app.step()  # the HUD shows the error line; the loop goes on
    finally:
        s.scenes[:] = saved
        s.error = None


def test_a_new_scene_shows_a_loading_then_a_compiling_notice(app, tmp_path):
    """'n' to a scene not loaded yet: one frame shows "loading..." over the last image, the next
    loads it and shows "compiling..." (its kernels are new), the next compiles and renders; keys
    typed meanwhile wait for that frame."""
    copy = tmp_path / "prism_copy.toml"
    copy.write_text(resolve_scene("prism").read_text())
    s = app.session
    saved = list(s.scenes)
    s.scenes[:] = [s.scene_path, copy]
    app.session.hud_visible = False
    settle(app, 1)
    try:
        image = window_buffer_to_image(app.last_frame)
        app.step(FrameInput(pressed=("n", "Tab")))
        assert app.notice == "loading prism_copy..." and s.scene_path != copy
        app.step()
        assert s.scene_path == copy and app.notice.startswith("compiling")
        assert not s.help_visible  # 'Tab' still waits
        # Both notice frames kept showing the last image around the notice box.
        shown = window_buffer_to_image(app.last_frame)
        box = hud.notice_rect(SIZE)
        rows = np.r_[0:int(box.y * SIZE[1]) - 2, int((box.y + box.height) * SIZE[1]) + 2:SIZE[1]]
        assert len(rows) > 0
        np.testing.assert_array_equal(shown[rows], image[rows])
        app.step()
        assert app.notice is None and app.renderer.slices_done > 0 and app.compile_seconds > 0
        app.step()
        assert s.help_visible
    finally:
        s.help_visible = False
        s.scenes[:] = saved
        app.select_scene(saved[0])


def test_still_frames_redraw_only_the_pixels_they_rendered(app):
    """Past the first round's fill, a still frame tone-maps the pixels of its own slices; the
    canvas then shows the whole film's tone map."""
    app.session.hud_visible = False
    settle(app, 1)
    resolution = app.session.resolution
    target = resolution.target_seconds
    try:
        while app.renderer.slices_done < ROUND_SLICES:
            app.step()
        resolution.target_seconds = 1e-6  # a budget of one slice per frame
        banded_rows = 0
        for _ in range(64):  # until three bands held rows (at 72 rows, a band holds 72/256 on average)
            slices, counts = app.renderer.slices_done, app.renderer.film.sample_counts()
            app.step()
            assert app.renderer.slices_done == slices + 1 and not app.last_plan.reset
            assert app.last_display_update == UPDATE_SLICES
            # past the first round a still frame's slice is a band of rows (renderer/film/pixel_slices.py)
            band = slice_mask(slices % ROUND_SLICES, 1, *SIZE, BANDS)[::-1]
            np.testing.assert_array_equal(app.renderer.film.sample_counts() != counts, band)
            banded_rows += band.any(axis=1).sum()
            if banded_rows >= 3:
                break
        assert banded_rows >= 3
        shown = window_buffer_to_image(app.last_frame)
        np.testing.assert_array_equal(shown, unpack_rgba8(app.display.shown))
        assert np.abs(shown.astype(int) - expected_display(app).astype(int)).max() <= 1
        resolution.target_seconds = target  # frames of several bands, spread over the image
        for _ in range(3):
            app.step()
        assert not app.last_plan.reset and app.renderer.slices_done % ROUND_SLICES != 0
        shown = window_buffer_to_image(app.last_frame)
        np.testing.assert_array_equal(shown, unpack_rgba8(app.display.shown))
        assert np.abs(shown.astype(int) - expected_display(app).astype(int)).max() <= 1
    finally:
        resolution.target_seconds = target


def test_sppm_still_frames_take_steps_of_an_iteration(app):
    """A still frame whose budget is less than an SPPM iteration renders a share of one (its
    steps: renderer.render_slices with whole_iterations False); the canvas changes when an
    iteration completes."""
    app.select_scene(resolve_scene("cornell_box"))
    app.session.set_integrator("sppm")
    app.session.hud_visible = False
    settle(app, 1)
    resolution = app.session.resolution
    target = resolution.target_seconds
    try:
        resolution.target_seconds = 1e-6  # a budget of one step per frame
        app.step()
        done = app.renderer.slices_done
        assert done % ROUND_SLICES != 0 or app.last_plan.slices == 1
        for _ in range(3):
            app.step()
            assert app.renderer.slices_done == done + 1 and not app.last_plan.reset
            done += 1
        resolution.target_seconds = target
        while app.renderer.slices_done % ROUND_SLICES:
            app.step()
        app.step()
        shown = window_buffer_to_image(app.last_frame)
        assert np.abs(shown.astype(int) - expected_display(app).astype(int)).max() <= 1
    finally:
        resolution.target_seconds = target
        app.session.set_integrator("path")


def test_an_untouched_still_view_renders_without_presenting_until_an_input(app):
    """Between redraws a still frame only renders (and reads input); an input presents on its own
    frame, showing every slice rendered so far."""
    app.session.hud_visible = False
    # A transient message of an earlier test ("scene ...", "integrator ...": shown for
    # MESSAGE_SECONDS) expiring between these frames changes what the window says, which rightly
    # presents (failed once in the suite: a present with no input): none here.
    app.session.message = None
    settle(app, 1)
    app.still_present_interval = 3600.0
    try:
        app.step()
        presents, slices = app.presents, app.renderer.slices_done
        for _ in range(3):
            app.step()
            assert not app.last_plan.reset and app.last_display_update is None
        assert app.presents == presents and app.renderer.slices_done > slices
        app.step(FrameInput(pressed=("Tab",)))
        assert app.session.help_visible and app.presents == presents + 1
        app.step(FrameInput(pressed=("Tab",)))
        assert not app.session.help_visible and app.presents == presents + 2
        shown = window_buffer_to_image(app.last_frame)
        np.testing.assert_array_equal(shown, unpack_rgba8(app.display.shown))
        assert np.abs(shown.astype(int) - expected_display(app).astype(int)).max() <= 1
        app.step()
        assert app.presents == presents + 2
        app.resume_still_clocks(None)  # due (bench interactive starts each kind's first block so)
        app.step()
        app.step()
        assert app.presents == presents + 3  # the first frame only
        # Clocks resumed as read: the time in between does not count (bench interactive's blocks
        # of the other kind), so an hour's interval less a minute has not passed yet; resumed at
        # an hour's age it has.
        clocks = app.still_clocks()
        assert 0.0 <= clocks.since_present < 60.0
        time.sleep(0.2)
        app.resume_still_clocks(clocks)
        assert app.still_clocks().since_present - clocks.since_present < 0.1
        app.resume_still_clocks(StillClocks(3600.0 - 60.0, None))
        app.step()
        assert app.presents == presents + 3
        app.resume_still_clocks(StillClocks(3600.0, None))
        app.step()
        assert app.presents == presents + 4
        app.still_present_interval = 0.0  # the interval has passed: the next frame presents
        app.step()
        assert app.presents == presents + 5
    finally:
        app.still_present_interval = 0.0


@pytest.mark.skipif(__import__("renderer.output.denoise", fromlist=["x"]).unavailable_reason() is not None,
                    reason="pyoidn is not installed here")
def test_denoised_view_shows_the_denoiser_output_and_screenshots_save_both(app, tmp_path):
    """Key x: while still, a worker denoises the film as its samples double; the canvas shows its
    tone-mapped output, the HUD says so, and a screenshot writes the raw and the denoised images."""
    import time

    app.select_scene(resolve_scene("cornell_box"))
    app.session.set_integrator("mis")
    app.session.hud_visible = False
    settle(app, 2)
    app.step(FrameInput(pressed=("x",)))
    assert app.session.denoise_view
    deadline = time.monotonic() + 60
    while app.shown_denoised is None and time.monotonic() < deadline:
        app.step()
        app._denoiser.wait(5.0)
    result = app.shown_denoised
    assert result is not None and result.spp >= 1 and app.image_label.startswith("denoised")
    assert np.isfinite(result.image).all() and result.image.shape == (SIZE[1], SIZE[0], 3)
    shown = window_buffer_to_image(app.last_frame)
    s = app.session
    mapper = s.display_tonemapper(INTEGRATORS[s.integrator].display_tonemapper)
    assert np.abs(shown.astype(int) - tonemap_array(result.image, s.exposure, mapper).astype(int)).max() <= 1
    app.screenshot_folder = tmp_path
    app.save_screenshot()
    names = sorted(p.name for p in tmp_path.iterdir())
    assert len(names) == 4 and sum("_denoised" in n for n in names) == 2
    app.step(FrameInput(pressed=("x",)))
    assert not app.session.denoise_view and app.image_label == "raw"


def test_adaptive_slider_stops_converged_pixels(app):
    app.select_scene(resolve_scene("cornell_box"))
    app.session.set_integrator("mis")
    controls = app.session.controls()
    from dataclasses import replace

    app.session.apply_controls(replace(controls, noise_threshold=1e6))  # every pixel converged at once
    try:
        for _ in range(400):
            app.step()
            if app.renderer.pixels_active == 0:
                break
        counts = app.renderer.film.sample_counts()
        assert app.renderer.pixels_active == 0 and counts.min() >= 16
        assert any("adaptive: 100% stopped" in line for line in hud.hud_lines(app.hud_stats()))
    finally:
        app.session.apply_controls(replace(app.session.controls(), noise_threshold=0.0))
        app.step()
    assert app.renderer.adaptive is None


def test_quit_key_ends_the_loop(app):
    assert app.step(FrameInput(pressed=("Escape",))) is False
    assert not app.running
    app.running = True
    assert app.run(max_frames=app.frames + 2) == 0  # headless: bounded by frames


def test_feature_samples_only_for_a_still_image_under_the_denoised_view(app):
    """The AOVs' feature samples (renderer/film/aovs.py) cost render time: a scene with textures takes
    them while the denoised view is on and the camera still, never in moving frames, and not
    with the view off; the AOVs then count them."""
    from renderer.film.aovs import FEATURE_BOOSTED_SAMPLES

    app.select_scene(resolve_scene("textured"))
    app.session.set_integrator("path")
    app.session.hud_visible = False
    settle(app, 1)
    renderer = app.renderer
    assert renderer.scene_feature_boost > 0 and renderer.feature_boost == 0  # the view is off
    app.session.denoise_view = True
    try:
        app.step(FrameInput(held=frozenset({"w"})))
        assert app.last_plan.interactive and renderer.feature_boost == 0
        moving = renderer.film.sample_counts()  # (kept where the moving frame was at full size)
        app.step(FrameInput())  # still again (settle time 0 here)
        assert not app.last_plan.interactive and renderer.feature_boost == renderer.scene_feature_boost
        if app.last_plan.reset:  # (at a reduced size it always is)
            moving = 0
        sample_every_pixel(app)
        counts = renderer.film.sample_counts()
        aov_counts = renderer.aovs.state()[2]
        boosted = np.minimum(counts, FEATURE_BOOSTED_SAMPLES) - np.minimum(moving, FEATURE_BOOSTED_SAMPLES)
        assert boosted.max() > 0
        np.testing.assert_array_equal(aov_counts, counts + renderer.feature_boost * boosted)
    finally:
        app.session.denoise_view = False


def test_a_mitsuba_scene_opens_as_a_toml_scene_does(app, tmp_path):
    """A Mitsuba 3 .xml in the viewer: the film shows, integrators switch, a screenshot writes its
    PNG and EXR, and the denoised view shows the denoiser's output."""
    import warnings

    from pathlib import Path

    scene = Path(__file__).resolve().parents[1] / "data" / "mitsuba" / "cornell_box.xml"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # its Gaussian film filter (tests/scene/mitsuba checks the warning)
        app.select_scene(scene)
    app.session.set_integrator("mis")
    app.session.hud_visible = False
    settle(app, 2)
    sample_every_pixel(app)
    assert app.renderer.scene.path == scene
    shown = window_buffer_to_image(app.last_frame)
    assert np.abs(shown.astype(int) - expected_display(app).astype(int)).max() <= 1
    assert shown.std() > MIN_PIXEL_STD
    app.step(FrameInput(pressed=("i",)))  # the next integrator
    assert app.session.integrator != "mis"
    settle(app, 1)
    assert window_buffer_to_image(app.last_frame).std() > MIN_PIXEL_STD
    app.session.set_integrator("mis")
    settle(app, 2)
    app.screenshot_folder = tmp_path
    app.save_screenshot()
    assert sorted(p.suffix for p in tmp_path.iterdir()) == [".exr", ".png"]
    assert all(p.name.startswith("cornell_box_mis_") for p in tmp_path.iterdir())
    app.step(FrameInput(pressed=("x",)))
    deadline = time.monotonic() + 60
    while app.shown_denoised is None and time.monotonic() < deadline:
        app.step()
        app._denoiser.wait(5.0)
    assert app.shown_denoised is not None and app.image_label.startswith("denoised")
    app.step(FrameInput(pressed=("x",)))
