"""The heads-up display: what the text says (pure functions) and how it is drawn (GGUI's imgui).

GGUI places a sub-window once, at the position and size given in window-relative units; the user
may drag it elsewhere afterwards. Widgets return their new value every frame, so `draw_hud`
returns the edited `Controls` and the actions of any button clicked; the caller applies them.
"""
from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass, replace
from typing import Optional, Sequence

import numpy as np

from renderer.film.pixel_slices import spp_text
from viewer.controller import MIN_SPEED
from viewer.session import Controls

HUD_WIDTH_PX = 360
HUD_HEIGHT_PX = 590
EFFECTS_WIDTH = 44  # characters per line of the effects list (wrapped)
MARGIN_PX = 8
HELP_WIDTH_PX = 330
NOTICE_WIDTH_PX = 300
NOTICE_HEIGHT_PX = 60
ERROR_COLOR = (1.0, 0.45, 0.35)
MESSAGE_COLOR = (0.55, 1.0, 0.55)
NOTICE_COLOR = (1.0, 0.85, 0.3)

# Slider ranges. Distances scale with the scene: `scale` is the camera's distance to its target.
EXPOSURE_RANGE = (-10.0, 10.0)  # EV
MAX_DEPTH_RANGE = (-1, 32)  # -1 = unlimited (Russian roulette ends paths)
FOV_RANGE = (5.0, 120.0)  # degrees
APERTURE_PER_SCALE = 0.1  # largest lens radius, as a fraction of the scene scale
FOCUS_PER_SCALE = 4.0  # farthest focus, as a multiple of the scene scale
MIN_FOCUS = 0.01  # metres; CameraState needs a positive focus distance
SPEED_PER_SCALE = 5.0  # fastest move speed on the slider, scene scales per second
MAX_NOISE_THRESHOLD = 0.2  # adaptive sampling's slider: relative standard error of a pixel's mean


@dataclass(frozen=True)
class Rect:
    """A sub-window's place in window-relative units (x, y from the top-left corner)."""

    x: float
    y: float
    width: float
    height: float

    def contains(self, u: float, v_down: float) -> bool:
        """(u, v_down) in [0, 1]^2 with v growing downwards."""
        return self.x <= u <= self.x + self.width and self.y <= v_down <= self.y + self.height


def hud_rect(window_size: tuple[int, int]) -> Rect:
    w, h = window_size
    return Rect(MARGIN_PX / w, MARGIN_PX / h, min(HUD_WIDTH_PX / w, 0.6), min(HUD_HEIGHT_PX / h, 1 - 2 * MARGIN_PX / h))


def help_rect(window_size: tuple[int, int], lines: int) -> Rect:
    w, h = window_size
    width = min(HELP_WIDTH_PX / w, 0.6)
    height = min((lines * 17 + 40) / h, 1 - 2 * MARGIN_PX / h)
    return Rect(1 - width - MARGIN_PX / w, MARGIN_PX / h, width, height)


def notice_rect(window_size: tuple[int, int]) -> Rect:
    w, h = window_size
    width, height = min(NOTICE_WIDTH_PX / w, 0.9), min(NOTICE_HEIGHT_PX / h, 0.5)
    return Rect(0.5 - width / 2, 0.5 - height / 2, width, height)


# --- text ---------------------------------------------------------------------------------------


@dataclass
class HudStats:
    scene: str = ""
    scene_position: str = ""  # "1/3"
    integrator: str = ""
    effects: Sequence[str] = ()
    fps: float = 0.0
    frame_ms: float = 0.0
    spp: float = 0.0  # on average over the pixels: a round of pixel slices in progress counts by its share
    samples_per_second: float = 0.0
    internal_size: tuple[int, int] = (0, 0)
    window_size: tuple[int, int] = (0, 0)
    interactive: bool = False
    noise: Optional[float] = None  # relative standard error (RMS over pixels), None = not yet, NaN = none
    rejected: int = 0
    work_per_ray: Optional[float] = None
    tests_per_ray: Optional[float] = None
    work_label: str = "march steps/ray"  # or "node visits/ray" on BVH scenes
    image: str = "raw"  # which image is shown: "raw", "denoised (8 spp)", "denoising..."
    adaptive: Optional[str] = None  # e.g. "35% of pixels stopped"; None when adaptive sampling is off
    rays: Optional[str] = None  # what became of the packets asked for (Renderer.packet_status); None: none asked


def format_rate(per_second: float) -> str:
    """Samples per second with an SI prefix: '830 k/s', '12.4 M/s'."""
    for factor, prefix in ((1e9, "G"), (1e6, "M"), (1e3, "k")):
        if per_second >= factor:
            return f"{per_second / factor:.3g} {prefix}/s"
    return f"{per_second:.0f} /s"


def format_noise(noise: Optional[float]) -> str:
    if noise is None:
        return "..."
    if math.isnan(noise):  # the integrator's image is not a mean of samples (sppm)
        return "n/a (not a sample mean)"
    if not math.isfinite(noise):
        return "n/a (< 2 spp)"
    return f"{100.0 * noise:.2f} %"


def hud_lines(s: HudStats) -> list[str]:
    w, h = s.internal_size
    full_w = max(s.window_size[0], 1)
    percent = 100.0 * w / full_w
    state = "moving" if s.interactive else "still"
    work = "..." if s.work_per_ray is None else f"{s.work_per_ray:.1f}"
    effects = textwrap.wrap(f"effects  {', '.join(s.effects) or '-'}", EFFECTS_WIDTH, subsequent_indent="  ")
    return [
        f"scene  {s.scene}  ({s.scene_position})",
        f"integrator  {s.integrator}",
        *effects,
        f"{s.fps:5.1f} fps   frame {s.frame_ms:6.1f} ms",
        f"spp {spp_text(s.spp)}   {format_rate(s.samples_per_second)}",
        f"resolution {w}x{h} ({percent:.0f}%, {state})",
        f"image {s.image}",
        f"noise {format_noise(s.noise)}" + ("" if s.adaptive is None else f"   adaptive: {s.adaptive}"),
        f"non-finite dropped {s.rejected}",
        f"{s.work_label} {work}" + ("" if not s.tests_per_ray else f"   prim tests/ray {s.tests_per_ray:.1f}"),
        *textwrap.wrap(s.rays or "", EFFECTS_WIDTH, subsequent_indent="  "),
    ]


# --- drawing ------------------------------------------------------------------------------------


def same_f32(a: float, b: float) -> bool:
    return np.float32(a) == np.float32(b)


def slider_float(gui, label: str, value: float, lo: float, hi: float) -> float:
    """A float slider that returns `value` itself (not its float32 copy) when untouched, so an
    untouched slider never looks like a change."""
    new = gui.slider_float(label, value, min(lo, value), max(hi, value))
    return value if same_f32(new, value) else float(new)


def text_line(gui, line: str, color=None) -> None:
    gui.text(line, color) if color is not None else gui.text(line)


def draw_hud(gui, window_size: tuple[int, int], stats: HudStats, controls: Controls, scale: float,
             forced_tonemapper: Optional[str] = None, error: Optional[str] = None,
             message: Optional[str] = None) -> tuple[Controls, list[str]]:
    """Draw the HUD; returns (possibly edited controls, actions of clicked buttons)."""
    r = hud_rect(window_size)
    actions: list[str] = []
    with gui.sub_window("Lantern", r.x, r.y, r.width, r.height) as g:
        for line in hud_lines(stats):
            text_line(g, line)
        if error:
            text_line(g, error, ERROR_COLOR)
        if message:
            text_line(g, message, MESSAGE_COLOR)
        exposure = slider_float(g, "exposure EV", controls.exposure, *EXPOSURE_RANGE)
        if forced_tonemapper:
            text_line(g, f"tone mapper {forced_tonemapper} (set by {stats.integrator})")
        elif g.button(f"tone mapper: {controls.tonemapper}"):
            actions.append("cycle_tonemapper")
        lo, hi = MAX_DEPTH_RANGE
        depth = int(g.slider_int("max depth", controls.max_depth, lo, max(hi, controls.max_depth)))
        fov = slider_float(g, "field of view", controls.fov, *FOV_RANGE)
        aperture = slider_float(g, "aperture (m)", controls.aperture, 0.0, APERTURE_PER_SCALE * scale)
        focus = slider_float(g, "focus (m)", controls.focus_distance, MIN_FOCUS, FOCUS_PER_SCALE * scale)
        focus = max(focus, MIN_FOCUS)
        threshold = slider_float(g, "adaptive noise (0 = off)", controls.noise_threshold, 0.0, MAX_NOISE_THRESHOLD)
        speed = controls.move_speed
        if speed is not None:
            speed = slider_float(g, "move speed (m/s)", speed, MIN_SPEED, SPEED_PER_SCALE * scale)
        for label, action in ((f"integrator: {stats.integrator}  [i]", "next_integrator"),
                              ("next scene  [n]", "next_scene"),
                              ("reset view  [r]", "reset"),
                              ("screenshot  [p]", "screenshot"),
                              (f"denoised view: {'on' if stats.image != 'raw' else 'off'}  [x]", "toggle_denoise"),
                              ("help: all keys", "help")):
            if g.button(label):
                actions.append(action)
        text_line(g, "max depth -1: no limit.  h hides this panel")
    edited = replace(controls, exposure=exposure, max_depth=depth, fov=fov, aperture=aperture, focus_distance=focus,
                     move_speed=speed, noise_threshold=threshold)
    return edited, actions


def draw_help(gui, window_size: tuple[int, int], help_text: str) -> None:
    lines = help_text.splitlines()
    r = help_rect(window_size, len(lines) + 2)
    with gui.sub_window("Keys", r.x, r.y, r.width, r.height) as g:
        for line in lines:
            text_line(g, line)
        text_line(g, "drag (left/right button)  look around")


def draw_notice(gui, window_size: tuple[int, int], text: str) -> None:
    r = notice_rect(window_size)
    with gui.sub_window("Please wait", r.x, r.y, r.width, r.height) as g:
        text_line(g, text, NOTICE_COLOR)
