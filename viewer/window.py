"""The interactive GGUI window: one `ViewerApp.step()` per frame.

`run_viewer` drives `step()` from real GGUI input; tests call `step()` with a synthetic
`FrameInput` on an off-screen window (`show_window=False`: GGUI then renders without presenting,
`window.running` stays True, and no events arrive, so loops are bounded by frame counts).

A frame: dispatch the keys pressed since the last frame, move the camera, decide (ViewerSession)
whether to reset and at which internal resolution and number of pixel slices to render, render
into the film, and, if the frame presents, bring the display image up to date (viewer/display.py:
packed RGBA8 as the canvas takes it, only the pixels the slices rendered since the last present
changed; while moving, at the reduced internal size, which the canvas stretches over the window),
put it on the canvas, draw the HUD and present. A frame presents when the view moves, on any
input, when what the HUD or notice says changes, and otherwise every
ResolutionController.present_interval() (viewer/session.py): an untouched still view spends its
frames rendering. The HUD's noise and work figures (reductions over the film) are refreshed one at
a time, at most once per STATS_INTERVAL, on still frames that present with the HUD up, whose render
then takes that much less time, so that frame is no longer than the others.

Loading a scene and compiling its kernels take seconds. Before either, one frame shows the
previous image with a "loading..." or "compiling..." notice; the next frame does the work.

Keys GGUI (Taichi 1.7) reports are the letters a-z and a few named keys (Escape, Shift, Tab,
arrows...); digits and punctuation never arrive, so the HUD has buttons for what the digit and
'/' keys do.
"""
from __future__ import annotations

import math
import os
import sys
import time
from datetime import datetime
from pathlib import Path
from typing import Callable, NamedTuple, Optional

import numpy as np
import taichi as ti

from renderer.camera import CameraFrame
from renderer.editing import SceneLight
from renderer.output.denoise import DenoiseInput, Denoiser, unavailable_reason
from renderer.output.image_io import write_exr, write_png
from renderer.integrators import INTEGRATORS, integrator_names
from renderer.film.pixel_slices import ROUND_SLICES, spp_text
from renderer.renderer import AdaptiveSettings, MeshOptions, Renderer
from renderer.scene.catalog import load_any, scene_files
from renderer.output.tonemap import TONEMAPPERS, quantize
from viewer import hud
from viewer.camera_state import CameraState
from viewer.denoise_worker import BackgroundDenoiser
from viewer.display import DenoisedDisplay, DisplayImages, DisplaySettings, show_on_canvas, tinted
from viewer.frame_input import FrameInput, poll_input
from viewer.hotkeys import KeyMap
from viewer.light_panel import draw_light_panel
from viewer.material_panel import draw_environment_panel, draw_material_panel, panel_rect
from viewer.model_material_panel import draw_model_material_panel
from viewer.scene_editor import SceneEditor
from viewer.session import (DEFAULT_TARGET_SECONDS, MAX_PRESENT_INTERVAL, MOVING_PROBE_SLICES, SETTLE_SECONDS,
                            STATS_INTERVAL, Every, RateMeter, ViewerSession, scene_scale, screenshot_dir,
                            screenshot_paths)

TITLE = "Lantern"
DEFAULT_SIZE = (960, 540)
MAX_QUEUED_KEYS = 32
CTRL_ACTIONS = {"ctrl+z": "undo_edit", "ctrl+y": "redo_edit", "ctrl+s": "save_scene"}
HIGHLIGHT_SECONDS = 1.0  # how long a picked object stays tinted
SAVE_OVER_SECONDS = 5.0  # a second ctrl+s within this saves over the scene's own file
CLICK_TOLERANCE = 0.004  # how far (window fractions) a press may move and still be a click, not a drag


def camera_frame(state: CameraState) -> CameraFrame:
    forward, right, up = state.basis()
    return CameraFrame(tuple(state.position), tuple(forward), tuple(right), tuple(up), state.fov,
                       state.aperture, state.focus_distance, state.projection, state.ortho_height)


def window_buffer_to_image(buffer: np.ndarray) -> np.ndarray:
    """GGUI's get_image_buffer_as_numpy() ([x, y, rgba] y-up floats) as uint8 (H, W, 3)."""
    return quantize(np.ascontiguousarray(np.transpose(buffer[:, :, :3], (1, 0, 2))[::-1]))


class StillClocks(NamedTuple):
    """Seconds since a view last presented and last refreshed the HUD's statistics (None: never)."""

    since_present: Optional[float]
    since_stats: Optional[float]


class ViewerApp:
    """The viewer: a GGUI window, one Renderer per scene visited, and a ViewerSession."""

    def __init__(self, scene_path, size: tuple[int, int] = DEFAULT_SIZE, integrator: Optional[str] = None,
                 show_window: bool = True, screenshot_folder=None, target_seconds: float = DEFAULT_TARGET_SECONDS,
                 settle_seconds: float = SETTLE_SECONDS, scenes: Optional[list] = None,
                 clock: Callable[[], float] = time.perf_counter, load_options=None,
                 still_present_interval: Optional[float] = None, packets: int = 0):
        self.size = (int(size[0]), int(size[1]))
        self.mesh_options = MeshOptions(packets=packets)  # rays a packet on the CPU where scenes allow
        self.load_options = load_options  # memory budget and model-folder rule (None: defaults)
        self.show_window = show_window
        self.clock = clock
        # Seconds between redraws of an untouched still view: None adapts it to what presenting
        # costs (ResolutionController.present_interval); 0 presents every frame (tests that read
        # every frame's image back).
        self.still_present_interval = still_present_interval
        self.screenshot_folder = screenshot_dir(screenshot_folder)
        self.keymap = KeyMap(integrator_names(), {name: cls.hotkey for name, cls in INTEGRATORS.items()})
        self.renderers: dict[Path, Renderer] = {}
        self.editors: dict[Path, SceneEditor] = {}  # the edits of each scene visited (made on first edit)
        self._press_cursor = None  # where the left button went down, for telling a click from a drag
        self.last_saved: Optional[Path] = None
        self._save_over_until = -1.0  # until when a ctrl+s saves over the scene's own file (asked once)
        self.highlight: Optional[tuple] = None  # (mask of the picked object's pixels, until when)
        self._last_input = FrameInput()  # the last frame's (poll_input reads Control's state from it)

        path = Path(scene_path).resolve()
        scene_list = [Path(p).resolve() for p in (scenes if scenes is not None else scene_files())]
        if path not in scene_list:
            scene_list.insert(0, path)
        first = self._renderer_for(path)  # a bad first scene is the caller's error: let it raise
        chosen = integrator or first.scene.render.integrator
        self.session = ViewerSession(scene_list, scene_list.index(path), integrator_names(), chosen, self.size,
                                     target_seconds=target_seconds, settle_seconds=settle_seconds)
        self.session.enter_scene(scene_list.index(path), first.scene)

        self.window = ti.ui.Window(TITLE, self.size, vsync=False, show_window=show_window)
        self.canvas = self.window.get_canvas()
        self.gui = self.window.get_gui()
        self.display = DisplayImages(self.size)
        # The denoised view (key x): a worker thread denoises the still image as its samples double.
        self._denoiser: Optional[BackgroundDenoiser] = None
        self.denoised_display = DenoisedDisplay()
        self.shown_denoised = None  # the Denoised result on screen, if any
        self._shown: Optional[np.ndarray] = None  # the packed image to present (None: the film's)
        self.image_label = "raw"
        self.last_display_update: Optional[str] = None  # what the last frame's display update did

        self.running = True
        self._queued_keys: list[str] = []
        self._awaiting_render = False
        self.frames = 0
        self.presents = 0  # frames that presented (the rest only rendered and read input)
        self._present_due = Every(MAX_PRESENT_INTERVAL)  # when the last frame presented
        self._presented_key = None  # what the HUD and notices said on the last present
        self._cursor_before = None
        self.last_plan = None
        self.moving_slices = None  # pixel slices the last moving frame rendered (ROUND_SLICES: all)
        self.last_frame: Optional[np.ndarray] = None  # off-screen: GGUI's image of the last frame
        self.last_screenshot: Optional[tuple[Path, Path]] = None
        # The notice ("loading..." or "compiling...") shown on the frame before a load or compile.
        self.notice: Optional[str] = None
        self._notice_key = None
        self._pending_cycle: Optional[tuple[int, bool]] = None  # (step, notice shown) of a scene to load
        self.compile_seconds: Optional[float] = None  # the last compiling frame's render call
        self._features = None  # this frame's Features (None until the frame knows them)
        self._camera = (None, None)  # (CameraState, its CameraFrame): still frames reuse the frame
        self._last_time: Optional[float] = None
        self._frame_ms = 0.0
        self._fps = RateMeter()
        self._samples = RateMeter()
        # The HUD's figures that need a reduction over the film, refreshed in turn (see step()),
        # and what each took last time: the budget its frame reserves for it.
        self._stats_due = Every(STATS_INTERVAL)
        self._stats_jobs = (self._refresh_noise, self._refresh_work)
        self._stats_next = 0
        self._stats_seconds = [0.0] * len(self._stats_jobs)
        self._stats = {"noise": None, "rejected": 0, "work_per_ray": None, "tests_per_ray": None}
        self._drag_blocked = False
        self._buttons_before: frozenset = frozenset()

    def _camera_frame(self) -> CameraFrame:
        """The controller's camera as the renderer takes it, made again only when it changed."""
        state = self.session.controller.state
        if self._camera[0] != state:
            self._camera = (state, camera_frame(state))
        return self._camera[1]

    # --- scenes -------------------------------------------------------------------------------
    @property
    def renderer(self) -> Renderer:
        return self.renderers[self.session.scene_path]

    def _renderer_for(self, path: Path) -> Renderer:
        """The cached Renderer of a scene file, built (loaded and uploaded) on first use."""
        path = Path(path).resolve()
        if path not in self.renderers:
            # With AOVs: the denoised view needs them, and toggling it must not recompile.
            renderer = Renderer(load_any(path, self.load_options), self.size, self.mesh_options, aovs=True)
            # Still frames render a few slices each: after the first round, bands of rows (cheaper
            # per sample than interleaved pixels: renderer/film/pixel_slices.py)
            renderer.bands_after_first_round = True
            self.renderers[path] = renderer
        return self.renderers[path]

    def select_scene(self, path) -> None:
        """Show a scene file (added to the cycle if it is not in it); raises if it cannot load."""
        path = Path(path).resolve()
        renderer = self._renderer_for(path)
        if path not in self.session.scenes:
            self.session.scenes.append(path)
        self.session.switch_scene(self.session.scenes.index(path), renderer.scene)

    def _cycle_scene(self, step: int, now: float) -> None:
        before = self.session.scene_index
        scene = self.session.cycle_scene(step, lambda p: self._renderer_for(p).scene)
        if scene is not None and self.session.scene_index != before:
            self._announce(f"scene {scene.name}", now)
        if self.session.error:
            print(f"warning: {self.session.error}", file=sys.stderr)

    def _request_cycle(self, step: int, now: float) -> None:
        """'n' / 'b': a scene loaded before comes at once; loading a new one takes seconds, so
        this frame shows a notice and the next one loads (see step())."""
        s = self.session
        target = s.scenes[(s.scene_index + step) % len(s.scenes)]
        if target in self.renderers:
            self._cycle_scene(step, now)
        else:
            self._pending_cycle = (step, False)
            self.notice = f"loading {target.stem}..."

    @property
    def editor(self) -> SceneEditor:
        path = self.session.scene_path
        if path not in self.editors:
            self.editors[path] = SceneEditor(self.renderer.scene, self._rebuilt)
        return self.editors[path]

    def _rebuilt(self, scene) -> Renderer:
        """A Renderer for an edited scene the one on screen cannot take in place."""
        renderer = Renderer(scene, self.size, self.mesh_options, aovs=True)
        renderer.bands_after_first_round = True
        self.renderers[self.session.scene_path] = renderer
        return renderer

    def pick_at(self, cursor, now: float):
        """Pick what is under `cursor` (GGUI's [0,1]^2, y up): the panel opens on its material."""
        if cursor is None:
            return None
        u, v = (min(max(float(c), 0.0), 1.0) for c in cursor)
        try:
            picked = self.editor.pick(self.renderer, self._camera_frame(), u, v, self.session.integrator)
        except Exception as error:  # e.g. the pick kernel failing to compile: report, go on
            self.session.error = f"pick failed: {_one_line(error)}"
            return None
        self._announce(picked.describe() if picked is not None else "the environment (nothing under the cursor)", now)
        self.highlight = None
        if picked is not None and picked.object_index >= 0:
            ids = self.renderer.object_ids(self._camera_frame(), self.session.integrator)
            self.highlight = (ids == picked.object_index, now + HIGHLIGHT_SECONDS)
        return picked

    def edit(self, change: Callable[[Renderer], Renderer], now: float) -> None:
        """Run an edit (a SceneEditor call taking and returning the renderer) and restart the image
        where it changed the scene (an undo with nothing to undo does not)."""
        before = self.renderer.scene
        try:
            change(self.renderer)
        except Exception as error:  # a bad edit must not end the session
            self.session.error = f"edit failed: {_one_line(error)}"
            return
        if self.renderer.scene is not before:
            self.session.request_reset()
        if self.editor.notes:
            self.session.notify("; ".join(self.editor.notes), now)

    def save_edits(self, now: float) -> Optional[Path]:
        """ctrl+s: the edited scene beside its file. Where that is the file itself (a saved
        `_edited.toml` opened again), the first press asks and a second within SAVE_OVER_SECONDS
        saves over it."""
        over = self.editor.saves_over_its_file
        if over and now > self._save_over_until:
            self._save_over_until = now + SAVE_OVER_SECONDS
            self._announce(f"{self.editor.save_path().name} is this scene's own file: ctrl+s again to save over it",
                           now)
            return None
        self._save_over_until = -1.0
        try:
            path = self.editor.save(self.renderer.scene, overwrite=over)
        except Exception as error:
            self.session.error = f"save failed: {_one_line(error)}"
            return None
        self.last_saved = path
        self._announce(f"saved {path}", now)
        return path

    def _announce(self, text: str, now: float) -> None:
        self.session.notify(text, now)
        print(text, file=sys.stderr)

    # --- actions ------------------------------------------------------------------------------
    def dispatch(self, action: Optional[str], inp: FrameInput, now: float) -> None:
        s = self.session
        if action is None:
            return
        if action == "quit":
            self.running = False
        elif action == "next_scene":
            self._request_cycle(+1, now)
        elif action == "prev_scene":
            self._request_cycle(-1, now)
        elif action == "next_integrator":
            s.next_integrator()
            self._announce(f"integrator {s.integrator}", now)
        elif action.startswith("integrator:"):
            if s.set_integrator(action.split(":", 1)[1]):
                self._announce(f"integrator {s.integrator}", now)
        elif action == "reset":
            s.reset_camera()
        elif action == "screenshot":
            self.save_screenshot(now)
        elif action == "focus_at_cursor":
            self.focus_at_cursor(inp.cursor, now)
        elif action == "pick_at_cursor":
            self.pick_at(inp.cursor, now)
        elif action == "undo_edit":
            self.edit(self.editor.undo, now)
        elif action == "redo_edit":
            self.edit(self.editor.redo, now)
        elif action == "reset_material":
            self.edit(self.editor.reset_material, now)
        elif action == "save_scene":
            self.save_edits(now)
        elif action == "close_panel":
            self.editor.close()
        elif action.startswith("open_light:"):
            self.editor.open_light(int(action.split(":", 1)[1]))
        elif action == "toggle_hud":
            s.hud_visible = not s.hud_visible
        elif action == "help":
            s.help_visible = not s.help_visible
        elif action == "speed_up":
            s.controller.change_speed(+1)
        elif action == "speed_down":
            s.controller.change_speed(-1)
        elif action == "cycle_tonemapper":
            s.cycle_tonemapper(TONEMAPPERS)
        elif action == "toggle_denoise":
            reason = unavailable_reason()
            if reason:
                s.error = reason
                return
            s.denoise_view = not s.denoise_view
            self._announce(f"denoised view {'on' if s.denoise_view else 'off'}", now)

    def save_screenshot(self, now: Optional[float] = None) -> tuple[Path, Path]:
        """The PNG exactly as the canvas shows the image (without the HUD) and the same image linear,
        as EXR (the film's mean at the internal resolution of the moment; in a first round of pixel
        slices, unreached pixels filled as shown)."""
        r, s = self.renderer, self.session
        png, exr = screenshot_paths(self.screenshot_folder, r.scene.name, s.integrator, r.samples_done, datetime.now())
        write_png(png, self.display.window_sized_image(r.film, self._accumulation(), r.slices_done,
                                                       self._display_settings(), self._pixel_sliced(),
                                                       r.round_order))
        write_exr(exr, r.shown_image())
        saved = f"{png} and {exr.name}"
        denoised = self.shown_denoised
        if denoised is not None:  # the denoised view: both images, the denoised one beside the raw
            self.denoised_display.update(denoised, self._display_settings())
            d_png, d_exr = (p.with_name(p.stem + "_denoised" + p.suffix) for p in (png, exr))
            write_png(d_png, self.denoised_display.display)
            write_exr(d_exr, denoised.image)
            saved += f" (raw), {d_png.name} and {d_exr.name} (denoised at {spp_text(denoised.spp)} spp)"
        self.last_screenshot = (png, exr)
        print(f"saved {saved}", file=sys.stderr)
        s.notify(f"saved {png.name} (+ .exr{', denoised' if denoised is not None else ''})",
                 self.clock() if now is None else now)
        return png, exr

    def focus_at_cursor(self, cursor, now: float) -> None:
        if cursor is None:
            return
        u, v = (min(max(float(c), 0.0), 1.0) for c in cursor)  # GGUI: y up, like the probe
        frame = self._camera_frame()
        try:
            distance = self.renderer.focus_distance_at(frame, u, v, self.session.integrator)
        except Exception as error:  # e.g. the probe kernel failing to compile: report, go on
            self.session.error = f"focus failed: {_one_line(error)}"
            return
        if distance is None:
            self.session.notify("focus: nothing under the cursor", now)
        else:
            self.session.set_focus_distance(distance)
            self.session.notify(f"focus {distance:.3g} m", now)

    # --- one frame ----------------------------------------------------------------------------
    def _handle_keys(self, inp: FrameInput, now: float) -> None:
        """Dispatch key presses in order. Keys typed after a scene or integrator switch wait until
        a frame of the new state has rendered: typed ahead during a compile, 'n p' saves the new
        scene, not the old image under the new name."""
        keys = self._queued_keys + list(inp.pressed)
        self._queued_keys = []
        for i, key in enumerate(keys):
            if self._awaiting_render:
                self._queued_keys = keys[i:][:MAX_QUEUED_KEYS]
                return
            action = CTRL_ACTIONS.get(key.lower()) if key.startswith("ctrl+") else self.keymap.action_for(key)
            before = (self.session.scene_index, self.session.integrator)
            self.dispatch(action, inp, now)
            if (self.session.scene_index, self.session.integrator) != before or self._pending_cycle:
                self._awaiting_render = True
            if not self.running:
                return

    def _drag(self, inp: FrameInput, now: float) -> bool:
        """Looking drags with either button; a left drag that starts on the HUD or the material
        panel is theirs. A left press and release in one place (a click) picks what is there."""
        lmb, rmb = ti.ui.LMB in inp.buttons, ti.ui.RMB in inp.buttons
        pressed = ti.ui.LMB in inp.pressed or (lmb and ti.ui.LMB not in self._buttons_before)
        if pressed:
            self._drag_blocked = False
            if inp.cursor is not None:
                u, v = inp.cursor
                panels = (([hud.hud_rect(self.size)] if self.session.hud_visible else [])
                          + ([panel_rect(self.size)] if self.editor.panel_open else []))
                self._drag_blocked = any(r.contains(u, 1.0 - v) for r in panels)
            self._press_cursor = None if self._drag_blocked else inp.cursor
        # a release (as an event: a quick click is down and up within one frame) where it went down
        if (ti.ui.LMB in inp.released or (not lmb and ti.ui.LMB in self._buttons_before)) \
                and self._press_cursor is not None:
            if inp.cursor is not None and max(abs(a - b) for a, b in zip(inp.cursor, self._press_cursor)) \
                    <= CLICK_TOLERANCE:
                self.pick_at(inp.cursor, now)
            self._press_cursor = None
        self._buttons_before = inp.buttons
        return rmb or (lmb and not self._drag_blocked)

    def step(self, inp: Optional[FrameInput] = None) -> bool:
        """Advance one frame; False once the viewer should quit."""
        inp = inp or FrameInput()
        start = time.perf_counter()
        now = self.clock()
        dt = 0.0 if self._last_time is None else now - self._last_time
        self._last_time = now
        self._fps.add(now)
        self.frames += 1
        s = self.session

        self._handle_keys(inp, now)
        if not self.running:
            return False

        w, h = self.size
        cursor_px = None if inp.cursor is None else (inp.cursor[0] * w, (1.0 - inp.cursor[1]) * h)
        s.update_camera(dt, set(inp.held) if not inp.ctrl else set(), cursor_px, self._drag(inp, now))

        self._features = None
        if self._pending_cycle is not None:
            step, announced = self._pending_cycle
            if not announced:  # this frame shows the "loading..." notice; the next one loads
                self._pending_cycle = (step, True)
                self._present(now)
                return True
            self._pending_cycle = None
            self.notice = None
            self._cycle_scene(step, now)

        renderer = self.renderer
        integrator = s.integrator
        frame = self._camera_frame()
        features = self._features = renderer.features(frame)
        key = (id(renderer), integrator, features)
        fresh = not renderer.is_compiled(integrator, features)
        if fresh and self._notice_key != key:
            # Show the notice on this frame; the next frame compiles (and blocks) while it is up.
            self._notice_key = key
            self.notice = f"compiling {integrator} for {renderer.scene.name}..."
            self._present(now)
            return True
        self.notice = None
        self._notice_key = None

        s.resolution.set_context((s.scene_path, integrator, features))
        asked = self._present_asked(inp, now)
        stats_due = asked and s.hud_visible and self._stats_due.ready(now)
        job = self._stats_next
        reserved = self._stats_seconds[job] if stats_due else 0.0
        plan = s.plan_frame(now, reserved_seconds=reserved, presenting=asked)
        self.last_plan = plan
        if plan.reset:
            renderer.reset(*plan.size)
            self._stats["noise"] = None  # "..." until the next (rate-limited) estimate
        wanted = AdaptiveSettings(s.noise_threshold) if s.noise_threshold > 0.0 else None
        if renderer.adaptive != wanted:
            renderer.set_adaptive(wanted)
        # Feature samples (renderer/film/aovs.py) only for a still image the denoised view will show.
        renderer.feature_boost = renderer.scene_feature_boost if s.denoise_view and not plan.interactive else 0
        t0 = time.perf_counter()
        slices_before = renderer.slices_done
        # sppm's frames take steps of its whole-image iterations (a share of one while still)
        if plan.interactive and plan.slices == ROUND_SLICES and self._pixel_sliced():
            self._render_moving(renderer, frame, integrator, features, t0)
        else:
            slices = plan.slices
            if not plan.interactive:  # sppm's steps are planned from their own measured costs
                steps = renderer.steps_within(integrator, features, s.resolution.still_budget(reserved, plan.presents))
                slices = slices if steps is None else steps
            renderer.render_slices(frame, slices, integrator, s.max_depth, features=features, whole_iterations=False)
        ti.sync()
        self._awaiting_render = False
        render_seconds = time.perf_counter() - t0
        if fresh:
            self.compile_seconds = render_seconds
        # What was rendered (an integrator with whole-image passes, sppm, rounds up to a sample)
        pixel_samples = plan.size[0] * plan.size[1] * (renderer.slices_done - slices_before) / ROUND_SLICES
        self._samples.add(now, pixel_samples)

        self._choose_image(renderer, integrator, plan)
        stats_seconds = 0.0
        if fresh:  # compile the reductions of a new film here, in the frame that waits for Taichi anyway
            for refresh in self._stats_jobs:
                refresh(renderer, integrator)
        elif stats_due and not plan.interactive:  # a moving film restarts every frame: nothing to report
            t0 = time.perf_counter()
            self._stats_jobs[job](renderer, integrator)
            stats_seconds = time.perf_counter() - t0
            self._stats_due.mark(now)
            self._stats_seconds[job] = min(stats_seconds, s.resolution.target_seconds)
            self._stats_next = (job + 1) % len(self._stats_jobs)
        present_seconds = 0.0
        self.last_display_update = None
        if plan.presents or fresh or self._display_key(now) != self._presented_key:
            t0 = time.perf_counter()
            self.last_display_update = self.display.update(renderer.film, self._accumulation(),
                                                           renderer.slices_done, self._display_settings(),
                                                           self._pixel_sliced(), renderer.round_order)
            self._present(now)
            present_seconds = time.perf_counter() - t0
            if not fresh:
                s.resolution.record_present(present_seconds + stats_seconds)
        frame_seconds = time.perf_counter() - start
        self._frame_ms = 1000.0 * frame_seconds
        if not fresh and pixel_samples > 0:  # a compiling frame says nothing about the render cost (nor
            # does one where adaptive sampling had stopped every pixel)
            s.resolution.record(render_seconds, pixel_samples, frame_seconds - stats_seconds - present_seconds)
        return self.running

    def _render_moving(self, renderer: Renderer, frame, integrator: str, features, start: float) -> None:
        """A moving frame: a quarter of its pixel slices, then as many more as its budget allows
        at what that quarter cost (viewer/session.py, MOVING_PROBE_SLICES); pixels a frame cut
        short did not reach show from the grid it did (the display's fill)."""
        renderer.render_slices(frame, MOVING_PROBE_SLICES, integrator, self.session.max_depth, features=features)
        ti.sync()
        rest = self.session.resolution.moving_rest_slices(time.perf_counter() - start, MOVING_PROBE_SLICES)
        self.moving_slices = MOVING_PROBE_SLICES + rest
        if rest > 0:
            renderer.render_slices(frame, rest, integrator, self.session.max_depth, features=features)

    def _present_asked(self, inp: FrameInput, now: float) -> bool:
        """Whether this frame presents whatever it renders: on input (a key, a held key or button,
        the cursor moving over the HUD, whose widgets react to it), and when the still view's
        present interval has passed."""
        cursor_moved = inp.cursor != self._cursor_before
        self._cursor_before = inp.cursor
        if inp.pressed or inp.held or inp.buttons:
            return True
        if cursor_moved and inp.cursor is not None and self.session.hud_visible:
            u, v = inp.cursor
            if hud.hud_rect(self.size).contains(u, 1.0 - v):
                return True
        interval = self.still_present_interval
        if interval is None:
            interval = self.session.resolution.present_interval()
        return self._present_due.ready(now, interval)

    def _display_key(self, now: float) -> tuple:
        """What the window says besides the image: a change presents at once."""
        s = self.session
        return (s.hud_visible, s.help_visible, self.notice, s.error, s.current_message(now), self.image_label,
                self._display_settings(), self.highlight is not None and now <= self.highlight[1])

    def _choose_image(self, renderer: Renderer, integrator: str, plan) -> None:
        """The raw film, or in the denoised view the newest denoised image of this accumulation
        (offered to the worker while still, at full size, as its samples double)."""
        self._shown, self.shown_denoised, self.image_label = None, None, "raw"
        if not (self.session.denoise_view and INTEGRATORS[integrator].denoisable):
            return
        if self._denoiser is None:
            denoiser = Denoiser(prefilter_aux=True)
            self._denoiser = BackgroundDenoiser(denoiser.denoise,
                                                first=lambda source: denoiser.denoise(source, prefilter_aux=False))
        worker, generation = self._denoiser, self._accumulation()
        if not plan.interactive and (renderer.film.width, renderer.film.height) == self.size:
            # sppm's film holds its completed iterations only (the steps of the next change nothing)
            spp = renderer.mean_spp if self._pixel_sliced() else renderer.samples_done
            worker.offer(generation, spp, lambda: self._denoise_input(renderer, integrator))
        result = worker.result_for(generation)
        if worker.error:
            self.session.error = f"denoising failed: {worker.error}"
        if result is not None:
            self._shown = self.denoised_display.update(result, self._display_settings())
            self.shown_denoised = result
            quick = ", quick" if result.quick else ""
            self.image_label = f"denoised ({spp_text(result.spp)} spp, {1000 * result.seconds:.0f} ms{quick})"
        else:
            self.image_label = "raw (denoising...)" if worker.busy else "raw (denoised from 1 spp on)"

    @staticmethod
    def _denoise_input(renderer: Renderer, integrator: str) -> DenoiseInput:
        if INTEGRATORS[integrator].writes_aovs:
            return DenoiseInput(renderer.shown_image(), *renderer.aov_images())
        return DenoiseInput(renderer.shown_image())

    def _refresh_noise(self, renderer: Renderer, integrator: str) -> None:
        """The HUD's noise estimate and dropped samples: a reduction over the film (~1 ms at
        960x540 on a 2-core CPU), rate-limited with the other statistics (STATS_INTERVAL)."""
        stats = renderer.film.stats()
        # An integrator whose film holds an estimate, not a mean of samples (sppm), has no
        # variance to estimate the noise from: say so rather than show the film's inf or 0.
        noise = stats["noise"] if getattr(INTEGRATORS[integrator], "noise_estimate", True) else math.nan
        self._stats.update(noise=noise, rejected=stats["rejected"])

    def _refresh_work(self, renderer: Renderer, integrator: str) -> None:
        """The HUD's geometry work per ray: a per-row reduction of the work field on the device."""
        work = renderer.work_stats()
        self._stats.update(work_per_ray=work["work_per_ray"], tests_per_ray=work["tests_per_ray"])

    def _accumulation(self) -> tuple:
        """Identifies the film's accumulation: another film, or the same one reset, is another."""
        return id(self.renderer.film), self.session.resets

    def _display_settings(self) -> DisplaySettings:
        return DisplaySettings(float(self.session.exposure), self._display_tonemapper())

    def _display_tonemapper(self) -> str:
        return self.session.display_tonemapper(INTEGRATORS[self.session.integrator].display_tonemapper)

    def _current_features(self):
        """This frame's Features (those of the camera now, before the frame knows them)."""
        if self._features is None:
            return self.renderer.features(self._camera_frame())
        return self._features

    def _pixel_sliced(self) -> bool:
        """Whether the film changes slice by slice (False: sppm's, as its iterations complete)."""
        return self.renderer.is_sliced(self.session.integrator, self._current_features())

    def hud_stats(self) -> hud.HudStats:
        s, r = self.session, self.renderer
        features = self._current_features()
        return hud.HudStats(
            scene=r.scene.name, scene_position=f"{s.scene_index + 1}/{len(s.scenes)}", integrator=s.integrator,
            effects=features.active_effects(), fps=self._fps.rate(), frame_ms=self._frame_ms,
            spp=r.mean_spp, samples_per_second=self._samples.rate(),
            internal_size=(r.film.width, r.film.height), window_size=self.size,
            interactive=bool(self.last_plan and self.last_plan.interactive),
            noise=self._stats["noise"], rejected=self._stats["rejected"],
            work_per_ray=self._stats["work_per_ray"], tests_per_ray=self._stats["tests_per_ray"],
            work_label="march steps/ray" if r.scene.geometry == "sdf" else "node visits/ray",
            image=self.image_label, adaptive=self._adaptive_text(r),
            rays=r.packet_status(s.integrator, features, r.scene.render.sampler))

    @staticmethod
    def _adaptive_text(r: Renderer) -> Optional[str]:
        if r.adaptive is None:
            return None
        pixels = r.film.width * r.film.height
        return f"{100.0 * (pixels - r.pixels_active) / max(pixels, 1):.0f}% stopped"

    def still_clocks(self) -> StillClocks:
        """How long ago this view last presented and refreshed the HUD's statistics."""
        now = self.clock()
        return StillClocks(self._present_due.age(now), self._stats_due.age(now))

    def resume_still_clocks(self, clocks: Optional[StillClocks] = None) -> None:
        """Set the present and statistics clocks as `clocks` (still_clocks()) left them, as if no
        time had passed since; None: both due, so the next frame presents, as a still view's
        first frame does. bench interactive alternates blocks of two kinds of still frames and
        resumes each kind's clocks, so each redraws as a continuous still view of its kind."""
        now = self.clock()
        since_present, since_stats = (None, None) if clocks is None else clocks
        self._present_due.set_age(now, since_present)
        self._stats_due.set_age(now, since_stats)

    def _present(self, now: float) -> None:
        s = self.session
        self.presents += 1
        self._present_due.mark(now)
        shown = self.display.shown if self._shown is None else self._shown
        if self.highlight is not None:
            mask, until = self.highlight
            if now > until:
                self.highlight = None
            elif mask.shape == shown.shape:  # (not while moving, at a smaller size)
                shown = tinted(shown, mask)
        show_on_canvas(self.canvas, shown)
        if s.hud_visible:
            forced = INTEGRATORS[s.integrator].display_tonemapper
            controls, actions = hud.draw_hud(self.gui, self.size, self.hud_stats(), s.controls(),
                                             scene_scale(self.renderer.scene.camera), forced,
                                             s.error, s.current_message(now))
            s.apply_controls(controls)
            for action in actions:
                self.dispatch(action, FrameInput(), now)
        editor = self.editors.get(s.scene_path)
        if editor is not None and editor.panel_open:
            # the material's (or the environment's, or a light's) panel, with or without the HUD
            scene = self.renderer.scene
            if editor.picked is not None and editor.picked.model_material >= 0:
                spec = None  # the panel returns an edit only where a factor changed
                model = self.renderer.model_material(editor.picked.model_material)
                edited, actions = draw_model_material_panel(self.gui, self.size, editor.picked, model, editor.notes)
            elif editor.picked is not None:
                spec = editor.picked_material(scene)
                edited, actions = draw_material_panel(self.gui, self.size, editor.picked, spec, editor.notes)
            elif editor.light_open is not None:
                spec = SceneLight(editor.light_open, scene.lights[editor.light_open])
                edited, actions = draw_light_panel(self.gui, self.size, spec, self.renderer.scene_radius(),
                                                   editor.notes)
            else:
                spec = scene.environment
                edited, actions = draw_environment_panel(self.gui, self.size, spec, editor.notes, scene.lights)
            if edited is not None and edited is not spec:
                self.edit(lambda renderer: editor.apply(renderer, edited, merge=True), now)
            for action in actions:
                self.dispatch(action, FrameInput(), now)
        if s.help_visible:
            hud.draw_help(self.gui, self.size, self.keymap.help_text())
        if self.notice:
            hud.draw_notice(self.gui, self.size, self.notice)
        self._presented_key = self._display_key(now)
        if self.show_window:
            self.window.show()
        else:
            # Off-screen, reading the image back is what ends GGUI's frame (show() must not be
            # called); keep it for tests.
            self.last_frame = self.window.get_image_buffer_as_numpy()

    # --- the loop -----------------------------------------------------------------------------
    def run(self, max_frames: Optional[int] = None) -> int:
        while self.running and self.window.running and (max_frames is None or self.frames < max_frames):
            inp = poll_input(self.window, self._last_input) if self.show_window else FrameInput()
            self._last_input = inp
            self.step(inp)
        return 0


def _one_line(error: BaseException) -> str:
    lines = [line.strip() for line in str(error).strip().splitlines() if line.strip()]
    return lines[-1] if lines else type(error).__name__


def run_viewer(path, size: tuple[int, int] = DEFAULT_SIZE, integrator: Optional[str] = None,
               max_frames: Optional[int] = None, screenshot_folder=None, load_options=None, packets: int = 0) -> int:
    """Open the viewer on a scene file; returns the process exit code.

    Screenshots go to `screenshot_folder`, else $LANTERN_SCREENSHOT_DIR, else <repo>/screenshots.
    """
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        # GLFW would print "cannot initialize GLFW" and exit the process; say what to do instead.
        raise RuntimeError("the viewer needs a display (DISPLAY is not set): use `app.py render`, "
                           "or run it under Xvfb")
    app = ViewerApp(path, size=size, integrator=integrator, screenshot_folder=screenshot_folder,
                    load_options=load_options, packets=packets)
    return app.run(max_frames)
