"""The checks behind the scene format's rules: each takes a table's converted values (defaults
filled in) and returns a one-line problem, or None when the values are fine.

The Rule entries of schema.py say in words what each check enforces (the text docs/scene-format.md
shows); the loader runs them.
"""
from __future__ import annotations

import math
from typing import Callable, Optional

from .conductor_fresnel import FRESNEL_DESCRIPTIONS
from .schema_types import WRITTEN, Field, format_number


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _norm(v) -> float:
    return math.sqrt(sum(c * c for c in v))


def check_fixed_relaxation(v: dict) -> Optional[str]:
    if not v["adaptive"] and v["over_relaxation"] >= 2.0:
        return f"over_relaxation {v['over_relaxation']:g} needs adaptive = true (a fixed factor must be below 2)"
    return None


def check_camera(v: dict) -> Optional[str]:
    view = tuple(b - a for a, b in zip(v["position"], v["look_at"]))
    if _norm(view) == 0.0:
        return "position and look_at are the same point"
    # Relative test so that tiny or huge scenes behave the same.
    if _norm(_cross(view, v["up"])) <= 1e-9 * _norm(view) * _norm(v["up"]):
        return "up is zero or parallel to the view direction (look_at - position)"
    return None


def check_crop(v: dict) -> Optional[str]:
    if v["crop"] is None:
        return None
    x, y, w, h = v["crop"]
    if w < 1 or h < 1:
        return f"crop [{x}, {y}, {w}, {h}] has no pixels (its width and height must be at least 1)"
    if x + w > v["width"] or y + h > v["height"]:
        return (f"crop [{x}, {y}, {w}, {h}] reaches outside the {v['width']}x{v['height']} image "
                f"(x + width <= {v['width']}, y + height <= {v['height']})")
    return None


def check_keyframes(v: dict) -> Optional[str]:
    keyframes = [dict(k) for k in v["keyframes"]]
    if not keyframes:
        return None
    if len(keyframes) < 2:
        return "keyframes: a camera path needs at least 2 keyframes, got 1"
    for i, k in enumerate(keyframes):
        if i and k["time"] <= keyframes[i - 1]["time"]:
            return (f"keyframes[{i}].time {format_number(k['time'])} is not after keyframes[{i - 1}].time "
                    f"{format_number(keyframes[i - 1]['time'])} (times must increase strictly)")
        view = {"position": k["position"], "look_at": k["look_at"], "up": k["up"] or v["up"]}
        problem = check_camera(view)
        if problem:
            return f"keyframes[{i}]: {problem}"
    return None


def check_light_up(v: dict) -> Optional[str]:
    if v["texture"] is not None and _norm(_cross(v["direction"], v["up"])) <= 1e-9 * _norm(v["up"]):
        return "up is zero or parallel to direction, which leaves the projected image's orientation undefined"
    return None


def check_spot_beam(v: dict) -> Optional[str]:
    if v["type"] == "spot" and v["beam_width"] is not None and v["beam_width"] > v["cutoff_angle"]:
        return (f"beam_width {format_number(v['beam_width'])} is larger than cutoff_angle "
                f"{format_number(v['cutoff_angle'])} (the full beam lies within the cutoff)")
    return None


def check_rounded_box(v: dict) -> Optional[str]:
    half = min(v["size"]) / 2.0
    if v["radius"] > half:
        return (f"radius {format_number(v['radius'])} is larger than half the smallest size "
                f"component ({format_number(half)})")
    return None


def check_profile(v: dict) -> Optional[str]:
    from renderer.geometry.bezier import profile_problem

    return profile_problem(v["profile"], v["degree"])


def check_conductor_fresnel(v: dict) -> Optional[str]:
    if v["type"] != "conductor":
        return None
    if (v["eta"] is None) != (v["k"] is None):
        given, missing = ("eta", "k") if v["k"] is None else ("k", "eta")
        return f"`{given}` needs `{missing}` (the complex index eta + i k)"
    given = ["/".join(f"`{name}`" for name in d) for d in FRESNEL_DESCRIPTIONS if v[WRITTEN] & set(d)]
    if len(given) > 1:
        return (f"{', '.join(given[:-1])} and {given[-1]} cannot be combined: each describes the "
                "conductor's Fresnel (keep `metal`, or `eta` with `k`, or `base_color` with `edge_tint`)")
    return None


def check_one_surface_map(v: dict) -> Optional[str]:
    if v["normal_map"] is not None and v["bump_map"] is not None:
        return "`normal_map` and `bump_map` cannot be combined: each tilts the shading normal (keep one)"
    return None


def check_torus(v: dict) -> Optional[str]:
    if v["minor_radius"] >= v["major_radius"]:
        minor, major = format_number(v["minor_radius"]), format_number(v["major_radius"])
        return f"minor_radius {minor} must be smaller than major_radius {major}"
    return None


def water_fields_check(random_set: tuple[Field, ...]) -> Callable[[dict], Optional[str]]:
    """The check that a water surface's `waves` and the fields of a random wave set (`random_set`,
    whose defaults say what was left out) are not combined."""
    defaults = {f.name: f.default for f in random_set}

    def check_water_fields(v: dict) -> Optional[str]:
        if not v["waves"]:
            return None
        given = [name for name in defaults if v[name] != defaults[name]]
        if given:
            one = len(given) == 1
            return (f"{', '.join(given)} describe{'s' if one else ''} a random wave set and cannot be "
                    f"combined with `waves` (remove {'it' if one else 'them'} or the waves)")
        return None

    return check_water_fields


def check_water_waves(v: dict) -> Optional[str]:
    from renderer.scene import waves  # numpy only; imported here to keep the schema light

    wave_set, names = waves.from_params(v)
    return waves.problems(wave_set, v["size"] / v["resolution"], names)
