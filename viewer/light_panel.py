"""The panel of a light without a surface (point, spot, directional, projector), opened from the
environment's panel since no click can hit one: its intensity (or irradiance) as a colour times a
strength, its place, its direction as azimuth and elevation (never a zero vector), and the cone or
field of view its kind has, as the scene format describes them (renderer/scene/schema.py, LIGHT).
Images are listed and kept.

draw_light_panel returns the edited light (the same object when nothing changed) and the actions
of the buttons clicked; the window applies them (viewer/scene_editor.py).
"""
from __future__ import annotations

import math
from dataclasses import replace

from renderer.editing import SceneLight
from renderer.scene.schema import LIGHT
from viewer.hud import slider_float, text_line
from viewer.material_panel import emission_control, field_control, notes_and_actions, panel_rect

# Fields drawn as sliders of their own (the value, place and direction have the controls below).
SLIDERS = ("cutoff_angle", "fov", "fov_axis")


def direction_angles(direction) -> tuple[float, float]:
    """(azimuth about +y from +z towards +x, elevation above the xz plane), degrees."""
    x, y, z = direction
    length = math.sqrt(x * x + y * y + z * z) or 1.0
    return math.degrees(math.atan2(x, z)), math.degrees(math.asin(max(-1.0, min(1.0, y / length))))


def angles_direction(azimuth: float, elevation: float) -> tuple[float, float, float]:
    a, e = math.radians(azimuth), math.radians(elevation)
    return (math.cos(e) * math.sin(a), math.sin(e), math.cos(e) * math.cos(a))


def _position(g, value: tuple, extent: float) -> tuple:
    """Sliders per axis over +-extent about the origin (a light beyond it keeps its place)."""
    new = tuple(slider_float(g, f"position {axis}", float(c), -extent, extent) for axis, c in zip("xyz", value))
    return value if new == tuple(float(c) for c in value) else new


def _direction(g, value: tuple) -> tuple:
    azimuth, elevation = direction_angles(value)
    new_azimuth = slider_float(g, "azimuth [-180, 180]", azimuth, -180.0, 180.0)
    new_elevation = slider_float(g, "elevation [-90, 90]", elevation, -90.0, 90.0)
    if (new_azimuth, new_elevation) == (azimuth, elevation):
        return value
    return angles_direction(new_azimuth, new_elevation)


def draw_light_panel(gui, window_size: tuple[int, int], light: SceneLight, extent: float,
                     notes: list[str] = ()) -> tuple[SceneLight, list[str]]:
    """Draw the panel of `light` (extent: the span of the position sliders, metres, e.g. the
    scene's radius); returns (the light as edited, actions)."""
    spec = light.spec
    r = panel_rect(window_size)
    actions: list[str] = []
    changes = {}
    with gui.sub_window("Light", r.x, r.y, r.width, r.height) as g:
        text_line(g, f"{light.name}: {spec.kind} light")
        value_name = "irradiance" if spec.kind in ("directional", "projector") else "intensity"
        value = getattr(spec, value_name)
        new = emission_control(g, value, value_name)
        if new != value:
            changes[value_name] = new
        if spec.kind != "directional":
            new = _position(g, spec.position, max(extent, *(abs(c) for c in spec.position)))
            if new != spec.position:
                changes["position"] = new
        if spec.kind != "point":
            new = _direction(g, spec.direction)
            if new != spec.direction:
                changes["direction"] = new
        for f in LIGHT.fields:
            if f.name in SLIDERS and f.applies_to(spec.kind):
                new = field_control(g, f, getattr(spec, f.model_attr))
                if new != getattr(spec, f.model_attr):
                    changes[f.model_attr] = new
        if spec.kind == "spot":
            beam = slider_float(g, f"beam_width [0, {spec.cutoff_angle:g}]", spec.beam, 0.0, spec.cutoff_angle)
            if beam != spec.beam:
                changes["beam_width"] = beam
        if spec.texture is not None:
            text_line(g, f"image {spec.texture.file.name if spec.texture.file else spec.texture.kind} (kept)")
        actions += notes_and_actions(g, notes)
    return (replace(light, spec=replace(spec, **changes)) if changes else light), actions
