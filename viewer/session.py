"""The viewer's state machine, without a window: testable with fake clocks and fake timings.

`ViewerSession` holds what the user controls (scene, integrator, camera, render and display
settings) and decides, frame by frame, whether the accumulation must start over and at which
internal resolution and sample count the next frame renders:

- Only a change resets: camera motion, a scene or integrator switch, or a render setting (max
  depth, field of view, aperture, focus distance). Exposure and tone mapper act on the display
  only. An idle frame never resets; it adds samples.
- While the camera moves (or a slider is being dragged) the frame renders fewer pixels so the
  frame time stays near a target: `ResolutionController` picks the internal resolution from the
  measured cost of the previous frames. Once the camera has been still for `settle_seconds`, the
  next frame resets at full resolution and accumulates from there.
- A still frame renders what fits the same budget: whole samples per pixel when one fits, else a
  share of the pixel slices of a sample (renderer/film/pixel_slices.py), continuing where the last
  frame stopped; so a frame never waits for a whole sample of a slow scene, and input is read
  every frame.
- Presenting (tone mapping, canvas upload, HUD, the window's own frame) costs ~22 ms at 960x540
  on a 2-core CPU with software Vulkan where the whole image is redrawn, 12-15 ms in a still view
  (the display redraws the slices since its last present). A moving view or an input presents
  at once; an untouched still view redraws every `present_interval()` (about once a second:
  presenting then costs at most STILL_PRESENT_SHARE of the time), and its frames in between only
  render and read input, so sampling keeps its speed without making an input wait.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from typing import Callable, Hashable, Iterable, Optional

from renderer.film.pixel_slices import ROUND_SLICES
from viewer.camera_state import CameraState
from viewer.controller import MAX_SPEED, MIN_SPEED, FreeLookController

ROOT = Path(__file__).resolve().parents[1]
SCREENSHOT_ENV = "LANTERN_SCREENSHOT_DIR"
DEFAULT_SCREENSHOT_DIR = ROOT / "screenshots"

DEFAULT_TARGET_SECONDS = 0.045  # ~22 fps: an input waits the rest of a frame and the next, p95 under 100 ms
MIN_SCALE = 1.0 / 16.0  # smallest internal resolution, as a fraction of the window's width/height
# However long the rest of the frame (tone mapping, upload, HUD, present) takes, the render gets
# at least this fraction of the target: the resolution then bottoms out at MIN_SCALE instead of
# chasing a budget of zero.
MIN_RENDER_BUDGET_FRACTION = 0.25
SETTLE_SECONDS = 0.10  # still this long before going back to full resolution (see plan_frame)
MAX_SPP_PER_FRAME = 64
COST_SMOOTHING = 0.35  # weight of the newest measurement in the moving averages
# A render cost that rises is taken at once, one that falls is smoothed: a view that gets dearer
# (flying into a textured wall, an SPPM iteration reaching its photons) costs one long frame, not
# a run of them while an average catches up; a long frame is what an input waits for.
SCALE_RISE = 0.5  # fraction of the way towards a larger target scale taken per frame
INITIAL_MOVING_SCALE = 0.25  # before anything was measured
# A moving frame's cost per pixel can jump several-fold from one frame to the next (the camera
# flies into a sphere whose every path then runs to the maximum depth: 1.5 -> 7.9 us a pixel on
# the textured scene, a 117 ms frame planned as 45), which no measurement of the frames before
# can predict. So a moving frame renders this many pixel slices first (a quarter: the grid of
# every other pixel, which the display fills out) and plans the rest from their measured time:
# a frame that got dearer ends near its budget with fewer pixels, and the next is planned anew.
MOVING_PROBE_SLICES = ROUND_SLICES // 4
# A still frame that only renders and reads input may end up to this much past its budget when
# one more pixel slice gets it nearer the budget than stopping short: on a slow scene a slice
# costs 8-12 ms at 960x540 on 2 cores, and frames planned strictly within 45 ms rendered three
# or four slices in 34-37 ms, each paying a launch's fixed cost (Taichi's threads woken: a
# round in passes of five slices ran at 0.95-0.96 of whole-round launches). In a restricted
# `bench interactive` run, foggy / mis and nee went from 0.927 and 0.941 of whole-sample frames'
# samples/s to 0.945 and 0.945 with this overrun. An input waits for the rest of such a frame
# and a presenting one, which keeps the strict budget.
STILL_OVERRUN_SECONDS = 0.005

# An untouched still view redraws seldom enough that presenting (with the HUD's statistics, which
# refresh on such frames) takes at most this share of the time, within these bounds in seconds:
# at 960x540 on a 2-core CPU a still view's present costs 12-15 ms (the display's redraw of the
# slices since the last one 2 ms, canvas and HUD 1 ms, GGUI's frame read back or shown 9 ms) and
# the statistics 1-2 ms, so the still view redraws about once a second. (At 2.5% it redrew 1.8
# times a second: presents took 2.5% of a sliced still view's time on showcase / mis, where
# frames of whole samples take 1.5-3 s and present once each, under 1% of theirs.)
STILL_PRESENT_SHARE = 0.015
MIN_PRESENT_INTERVAL = 0.1
MAX_PRESENT_INTERVAL = 1.0

# Seconds between refreshes of the HUD's figures that need a reduction over the film (noise, then
# work per ray, in turn), time a still frame's render gives up for them (each figure is then at
# most two seconds old): 0.9 and 0.4 ms at 960x540 on a 2-core CPU (mirror_field / mis, measured
# 2026-12-05; 10-30 ms when this interval was first chosen).
STATS_INTERVAL = 1.0
MESSAGE_SECONDS = 4.0


# --- internal resolution ----------------------------------------------------------------------


class ResolutionController:
    """Picks the internal resolution while moving and the samples per frame while still.

    It keeps an exponential moving average of the render cost in seconds per pixel-sample (one
    per context, e.g. per (scene, integrator), so switching back to a cheap view is right at
    once), of the frame's overhead outside rendering and presenting, and of presenting. The render
    budget is the target frame time minus that overhead, and minus the present on a frame that
    presents (at least MIN_RENDER_BUDGET_FRACTION of the target).

    Moving: pixels = budget / cost, i.e. the pixel count scaled by target/measured; as a linear
    scale of the window clamped to [min_scale, 1]. A lower target applies at once (the view
    must stay responsive); a higher one is approached by SCALE_RISE per frame (no oscillation).
    Still: full resolution with as many pixel slices as fit the budget (at least one slice,
    ROUND_SLICES of which make a sample per pixel).
    """

    def __init__(self, full_size: tuple[int, int], target_seconds: float = DEFAULT_TARGET_SECONDS,
                 min_scale: float = MIN_SCALE, max_spp: int = MAX_SPP_PER_FRAME):
        if target_seconds <= 0:
            raise ValueError(f"target frame time must be positive, got {target_seconds}")
        if not 0.0 < min_scale <= 1.0:
            raise ValueError(f"min_scale must be in (0, 1], got {min_scale}")
        self.full_size = (int(full_size[0]), int(full_size[1]))
        self.target_seconds = float(target_seconds)
        self.min_scale = float(min_scale)
        self.max_spp = int(max_spp)
        # Fewest pixel slices a still frame renders: 1 lets a frame take any share of a sample;
        # ROUND_SLICES makes every still frame whole samples (the viewer before pixel slices,
        # which `bench interactive` measures against).
        self.min_still_slices = 1
        self.scale = INITIAL_MOVING_SCALE
        self.overhead = 0.0
        self.present_seconds = 0.0
        self._costs: dict[Hashable, float] = {}
        self.context: Hashable = None

    # -- measurements --
    def set_context(self, key: Hashable) -> None:
        """Costs are kept per context (scene, integrator...); a new one starts unmeasured."""
        self.context = key

    @property
    def cost(self) -> Optional[float]:
        """Smoothed seconds per pixel-sample in the current context, None before a measurement."""
        return self._costs.get(self.context)

    def record_present(self, seconds: float) -> None:
        """What presenting a frame took (display update, canvas, HUD, the window's frame, and the
        HUD's statistics refreshed on it)."""
        if math.isfinite(seconds) and seconds >= 0.0:
            self.present_seconds += COST_SMOOTHING * (seconds - self.present_seconds)

    def present_interval(self) -> float:
        """Seconds between redraws of an untouched still view: presenting then takes about
        STILL_PRESENT_SHARE of the time."""
        return min(max(self.present_seconds / STILL_PRESENT_SHARE, MIN_PRESENT_INTERVAL), MAX_PRESENT_INTERVAL)

    def record(self, render_seconds: float, pixel_samples: int, frame_seconds: Optional[float] = None) -> None:
        """One frame's measurement: render time for `pixel_samples`, and the frame's time outside
        presenting (the caller leaves that out: see record_present)."""
        if pixel_samples <= 0 or render_seconds <= 0 or not math.isfinite(render_seconds):
            return
        cost = render_seconds / pixel_samples
        old = self._costs.get(self.context)
        self._costs[self.context] = cost if old is None or cost > old else old + COST_SMOOTHING * (cost - old)
        if frame_seconds is not None and math.isfinite(frame_seconds):
            overhead = max(0.0, frame_seconds - render_seconds)
            self.overhead += COST_SMOOTHING * (overhead - self.overhead)

    # -- decisions --
    def render_budget(self, presenting: bool = True) -> float:
        spent = self.overhead + (self.present_seconds if presenting else 0.0)
        return max(self.target_seconds - spent, MIN_RENDER_BUDGET_FRACTION * self.target_seconds)

    def target_scale(self) -> float:
        """The linear scale whose pixel count fits the budget at the measured cost."""
        cost = self.cost
        if cost is None:
            return self.scale
        full_pixels = self.full_size[0] * self.full_size[1]
        pixels = self.render_budget() / cost
        return min(max(math.sqrt(pixels / full_pixels), self.min_scale), 1.0)

    def moving_size(self, starting: bool = False) -> tuple[int, int]:
        """Advance the smoothed scale one frame and return the internal size to render.

        `starting`: the first frame of a motion jumps straight to the target (the cost measured
        while still is the best estimate there is).
        """
        target = self.target_scale()
        if starting or target < self.scale:
            self.scale = target
        else:
            self.scale += SCALE_RISE * (target - self.scale)
        self.scale = min(max(self.scale, self.min_scale), 1.0)
        return self.size_for(self.scale)

    def moving_rest_slices(self, probe_seconds: float, probe_slices: int = MOVING_PROBE_SLICES) -> int:
        """Pixel slices a moving frame renders after its first `probe_slices` took `probe_seconds`:
        the rest of the round, or as many as fit the render budget at the probe's own cost."""
        rest = ROUND_SLICES - probe_slices
        if probe_slices <= 0 or not math.isfinite(probe_seconds) or probe_seconds <= 0.0:
            return rest
        left = self.render_budget() - probe_seconds
        return int(min(max(left * probe_slices / probe_seconds, 0.0), rest))

    def size_for(self, scale: float) -> tuple[int, int]:
        w, h = self.full_size
        return max(1, min(w, round(w * scale))), max(1, min(h, round(h * scale)))

    def still_budget(self, reserved_seconds: float = 0.0, presenting: bool = True) -> float:
        """Seconds a still frame renders for: the render budget less `reserved_seconds`."""
        return max(self.render_budget(presenting) - reserved_seconds, 0.0)

    def still_slices(self, reserved_seconds: float = 0.0, presenting: bool = True) -> int:
        """Pixel slices for a full-resolution frame that takes about the render budget, less
        `reserved_seconds` the frame spends on something else (before anything is measured: one
        slice, the cheapest frame there is). A frame that presents fits its budget; one that only
        renders takes the slice count nearest its budget, up to STILL_OVERRUN_SECONDS past it."""
        cost = self.cost
        if cost is None:
            return self.min_still_slices
        slice_cost = cost * self.full_size[0] * self.full_size[1] / ROUND_SLICES
        budget = self.still_budget(reserved_seconds, presenting)
        slices = budget // slice_cost
        if not presenting and (slices + 1) * slice_cost - budget < min(budget - slices * slice_cost,
                                                                       STILL_OVERRUN_SECONDS):
            slices += 1
        slices = min(slices, self.max_spp * ROUND_SLICES)
        return int(max(slices, self.min_still_slices))


# --- settings ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class Controls:
    """The values the HUD's widgets edit."""

    exposure: float  # EV, display only
    tonemapper: str  # display only
    max_depth: int  # -1 = unlimited
    fov: float  # degrees
    aperture: float  # lens radius, metres
    focus_distance: float  # metres
    move_speed: Optional[float] = None  # m/s; None leaves it alone. Not a change of the image
    noise_threshold: float = 0.0  # adaptive sampling's relative standard error (renderer/film/adaptive.py); 0 = off


@dataclass(frozen=True)
class FramePlan:
    size: tuple[int, int]  # internal resolution of the film's active region
    slices: int  # pixel slices this frame (ROUND_SLICES make one sample per pixel)
    reset: bool  # start the accumulation over before rendering
    interactive: bool  # rendering at the moving (reduced) resolution
    presents: bool  # the frame shows what it renders (asked to, moving, or restarted): planned without the present

    @property
    def spp(self) -> float:
        """Samples per pixel this frame, on average over the image."""
        return self.slices / ROUND_SLICES


def fix_max_depth(new: int, old: int) -> int:
    """A slider over -1..N passes through 0, which is not a depth: step over it."""
    new = int(new)
    if new == 0:
        return 1 if old < 0 else -1
    return max(new, -1)


def camera_from_spec(spec) -> CameraState:
    """The viewer's camera for a scene's CameraSpec (only a +y up vector is supported)."""
    return CameraState.from_look_at(spec.position, spec.look_at, (0.0, 1.0, 0.0), spec.fov,
                                    spec.aperture, spec.focus_distance, spec.projection, spec.ortho_height)


def scene_scale(spec) -> float:
    """A length that says how big the scene looks from its camera: the distance to the target."""
    d = math.dist(tuple(spec.position), tuple(spec.look_at))
    return max(d, 0.1)


class ViewerSession:
    """All state of a viewing session except the window, the GPU and the clock.

    `scenes` is the cycle of scene files ('n'/'b'); `integrators` the names ('i', digit keys).
    Scene switching goes through `cycle_scene(step, load)` with a loader that raises on a bad
    file; the session skips such files and reports them in `error`.
    """

    def __init__(self, scenes: list[Path], scene_index: int, integrators: list[str], integrator: str,
                 window_size: tuple[int, int], target_seconds: float = DEFAULT_TARGET_SECONDS,
                 settle_seconds: float = SETTLE_SECONDS, tonemapper: str = "aces"):
        if not scenes:
            raise ValueError("no scenes to show")
        if integrator not in integrators:
            raise ValueError(f"unknown integrator '{integrator}' (known: {', '.join(integrators)})")
        self.scenes = list(scenes)
        self.scene_index = scene_index
        self.integrators = list(integrators)
        self.integrator = integrator
        self.window_size = (int(window_size[0]), int(window_size[1]))
        self.resolution = ResolutionController(self.window_size, target_seconds)
        self.settle_seconds = float(settle_seconds)
        self.controller = FreeLookController(CameraState((0.0, 0.0, 0.0)))
        self.home_camera = self.controller.state
        self.scene_cameras: dict[Path, CameraState] = {}
        self.max_depth = 8
        self.exposure = 0.0
        self.noise_threshold = 0.0  # adaptive sampling while still; 0 = every pixel keeps sampling
        self.denoise_view = False  # show the denoised image (viewer/denoise_worker.py) when there is one
        self.tonemapper = tonemapper
        self.hud_visible = True
        self.help_visible = False
        self.error: Optional[str] = None
        self.message: Optional[str] = None
        self._message_until = 0.0
        self._pending_reset = True
        self._pending_interactive = False
        self._last_motion: Optional[float] = None
        self._was_interactive = False
        self.active_size: Optional[tuple[int, int]] = None
        self.resets = 0

    # -- scene ---------------------------------------------------------------------------------
    @property
    def scene_path(self) -> Path:
        return self.scenes[self.scene_index]

    def enter_scene(self, index: int, scene) -> None:
        """Make `scene` (loaded from scenes[index]) current: its camera, depth and move speed."""
        self.scene_index = index
        self.home_camera = camera_from_spec(scene.camera)
        # Coming back to a scene seen before restores the view it was left with.
        self.controller.set_state(self.scene_cameras.get(self.scene_path, self.home_camera))
        self.controller.move_speed = 0.5 * scene_scale(scene.camera)
        self.max_depth = scene.render.max_depth
        self.exposure = float(scene.render.exposure)
        # The first frame of a scene is a reduced-resolution preview (as while moving): a picture
        # appears at once, and the full-resolution accumulation starts on the next frame.
        self.request_reset(interactive=True)

    def switch_scene(self, index: int, scene) -> None:
        """Leave the current scene (its view is remembered) for scenes[index]."""
        self.scene_cameras[self.scene_path] = self.controller.state
        self.enter_scene(index, scene)

    def cycle_scene(self, step: int, load: Callable[[Path], object]) -> Optional[object]:
        """Move `step` (+1/-1) through the scene list, skipping files `load` fails on.

        Returns the loaded scene (already entered) or None when no other scene could be loaded;
        failures are reported in `error` as one line each.
        """
        errors = []
        n = len(self.scenes)
        for k in range(1, n + 1):
            index = (self.scene_index + step * k) % n
            path = self.scenes[index]
            try:
                scene = load(path)
            except Exception as error:  # a bad file must not end the session
                errors.append(f"skipped {path.name}: {_one_line(error)}")
                continue
            self.error = "; ".join(errors) if errors else None
            self.switch_scene(index, scene)
            return scene
        self.error = "; ".join(errors) if errors else None
        return None

    # -- integrator ----------------------------------------------------------------------------
    def set_integrator(self, name: str) -> bool:
        if name not in self.integrators:
            raise ValueError(f"unknown integrator '{name}'")
        if name == self.integrator:
            return False
        self.integrator = name
        self.request_reset()
        return True

    def next_integrator(self, step: int = 1) -> str:
        i = self.integrators.index(self.integrator)
        self.set_integrator(self.integrators[(i + step) % len(self.integrators)])
        return self.integrator

    # -- settings ------------------------------------------------------------------------------
    def controls(self) -> Controls:
        s = self.controller.state
        return Controls(self.exposure, self.tonemapper, self.max_depth, s.fov, s.aperture, s.focus_distance,
                        self.controller.move_speed, self.noise_threshold)

    def apply_controls(self, new: Controls) -> bool:
        """Take the HUD's values; True if the accumulation must restart.

        Exposure and tone mapper only change the display. The others change what is rendered;
        they count as interaction (reduced resolution while a slider is dragged).
        """
        self.exposure = float(new.exposure)
        self.tonemapper = new.tonemapper
        if new.move_speed is not None and new.move_speed != self.controller.move_speed:
            self.controller.move_speed = min(max(float(new.move_speed), MIN_SPEED), MAX_SPEED)
        changed = False
        threshold = max(float(new.noise_threshold), 0.0)
        if threshold != self.noise_threshold:  # stopped pixels would stay stopped: start over
            self.noise_threshold = threshold
            changed = True
        depth = fix_max_depth(new.max_depth, self.max_depth)
        if depth != self.max_depth:
            self.max_depth = depth
            changed = True
        state = self.controller.state
        try:
            camera = state.replace(fov=new.fov, aperture=max(new.aperture, 0.0),
                                   focus_distance=new.focus_distance)
        except ValueError:  # out-of-range slider value: keep the old camera
            camera = state
        if self.controller.set_state(camera):
            changed = True
        if changed:
            self.request_reset(interactive=True)
        return changed

    def set_focus_distance(self, distance: float) -> bool:
        changed = self.controller.set_state(self.controller.state.replace(focus_distance=float(distance)))
        if changed:
            self.request_reset()
        return changed

    def reset_camera(self) -> None:
        """The 'r' key: back to the scene's own camera, and start the accumulation over."""
        self.controller.set_state(self.home_camera)
        self.request_reset()

    def cycle_tonemapper(self, names: Iterable[str]) -> str:
        names = list(names)
        i = names.index(self.tonemapper) if self.tonemapper in names else -1
        self.tonemapper = names[(i + 1) % len(names)]
        return self.tonemapper

    def display_tonemapper(self, forced: Optional[str]) -> str:
        """A debug integrator's own mapper (e.g. 'none' for normals) wins over the user's."""
        return forced or self.tonemapper

    # -- messages ------------------------------------------------------------------------------
    def notify(self, text: str, now: float) -> None:
        self.message = text
        self._message_until = now + MESSAGE_SECONDS

    def current_message(self, now: float) -> Optional[str]:
        return self.message if self.message and now < self._message_until else None

    # -- frame planning ------------------------------------------------------------------------
    def request_reset(self, interactive: bool = False) -> None:
        """Something that changes the image happened: the next frame starts over."""
        self._pending_reset = True
        self._pending_interactive = self._pending_interactive or interactive

    def update_camera(self, dt: float, held_keys: set[str], cursor_px, dragging: bool) -> bool:
        """Feed input to the free-look controller; a moved camera resets (interactively)."""
        moved = self.controller.update(dt, held_keys, cursor_px, dragging)
        if moved:
            self.request_reset(interactive=True)
        return moved

    def plan_frame(self, now: float, reserved_seconds: float = 0.0, presenting: bool = True) -> FramePlan:
        """Decide size, samples and reset for the frame about to render; a still frame leaves
        `reserved_seconds` of its budget to other work (the viewer's rate-limited statistics),
        and the present's share of it only if it will present (a moving frame always does, and
        so does one that resets).

        Interactive changes (camera motion, slider drags) render at the reduced resolution. A
        frame counts as still only after `settle_seconds` without such a change: a drag whose
        cursor paused for one frame must not flip to a full-resolution frame and back. The first
        still frame at full resolution resets (the reduced image is not reused); later still
        frames accumulate without resetting.
        """
        if self._pending_reset and self._pending_interactive:
            self._last_motion = now
        interactive = self._last_motion is not None and (now - self._last_motion) < self.settle_seconds
        if self._pending_reset and self._pending_interactive:
            interactive = True
        if interactive:
            size, slices = self.resolution.moving_size(starting=not self._was_interactive), ROUND_SLICES
        else:
            self._last_motion = None
            size = self.window_size
        reset = self._pending_reset or size != self.active_size
        presents = presenting or reset or interactive  # a frame that restarts shows what it restarted
        if not interactive:
            slices = self.resolution.still_slices(reserved_seconds, presents)
        if reset:
            self.resets += 1
        self._pending_reset = False
        self._pending_interactive = False
        self.active_size = size
        self._was_interactive = interactive
        return FramePlan(size=size, slices=slices, reset=reset, interactive=interactive, presents=presents)


# --- rate limiting (noise estimate) -----------------------------------------------------------


class Every:
    """True at most once per `interval` seconds (and on the first call)."""

    def __init__(self, interval: float = STATS_INTERVAL):
        self.interval = interval
        self._last: Optional[float] = None

    def __call__(self, now: float) -> bool:
        if self.ready(now):
            self.mark(now)
            return True
        return False

    def ready(self, now: float, interval: Optional[float] = None) -> bool:
        """Whether it is time, without taking the turn (mark() takes it); `interval` for this
        call instead of the usual one (the still view's present interval follows its cost)."""
        return self._last is None or now - self._last >= (self.interval if interval is None else interval)

    def mark(self, now: float) -> None:
        self._last = now

    def force(self) -> None:
        self._last = None

    def age(self, now: float) -> Optional[float]:
        """Seconds since the last turn (None: none yet)."""
        return None if self._last is None else now - self._last

    def set_age(self, now: float, age: Optional[float]) -> None:
        """As if the last turn was `age` seconds before `now` (None: none yet, so it is time)."""
        self._last = None if age is None else now - age


@dataclass
class RateMeter:
    """Events per second over a sliding window of about `window` seconds (fps, samples/s)."""

    window: float = 1.0
    _samples: list = field(default_factory=list)

    def add(self, now: float, amount: float = 1.0) -> None:
        self._samples.append((now, amount))
        while len(self._samples) > 2 and now - self._samples[0][0] > self.window:
            self._samples.pop(0)

    def rate(self) -> float:
        if len(self._samples) < 2:
            return 0.0
        span = self._samples[-1][0] - self._samples[0][0]
        # The first entry opens the window; what came after it happened within `span`.
        total = sum(a for _, a in self._samples[1:])
        return total / span if span > 0 else 0.0


# --- screenshots ------------------------------------------------------------------------------


def screenshot_dir(configured: Optional[os.PathLike] = None) -> Path:
    """Where screenshots go: the argument, else $LANTERN_SCREENSHOT_DIR, else <repo>/screenshots."""
    if configured:
        return Path(configured)
    env = os.environ.get(SCREENSHOT_ENV)
    return Path(env) if env else DEFAULT_SCREENSHOT_DIR


def _safe(text: str) -> str:
    return "".join(c if c.isalnum() or c in "-_." else "-" for c in text) or "scene"


def screenshot_stem(scene: str, integrator: str, spp: int, when: datetime) -> str:
    """e.g. showcase_path_0128spp_20261122-010203"""
    return f"{_safe(scene)}_{_safe(integrator)}_{int(spp):04d}spp_{when:%Y%m%d-%H%M%S}"


def screenshot_paths(directory: os.PathLike, scene: str, integrator: str, spp: int,
                     when: datetime) -> tuple[Path, Path]:
    """(png, exr) paths that do not overwrite earlier screenshots (a -2, -3... suffix if needed)."""
    directory = Path(directory)
    stem = screenshot_stem(scene, integrator, spp, when)
    candidate, n = stem, 1
    while (directory / f"{candidate}.png").exists() or (directory / f"{candidate}.exr").exists():
        n += 1
        candidate = f"{stem}-{n}"
    return directory / f"{candidate}.png", directory / f"{candidate}.exr"


def _one_line(error: BaseException) -> str:
    text = str(error).strip().splitlines()
    return text[0] if text else type(error).__name__


__all__ = [
    "Controls", "Every", "FramePlan", "RateMeter", "ResolutionController", "ViewerSession",
    "camera_from_spec", "fix_max_depth", "scene_scale", "screenshot_dir", "screenshot_paths",
    "screenshot_stem", "SCREENSHOT_ENV",
]
