"""pbrt-v4 light sources made into Lantern's lights and environment, and area lights into a
shape's emission. Intensities: an RGB light is its colour times scale; a spectrum or blackbody is
normalised to luminance 1 first (spectra.py), as pbrt-v4 normalises light spectra; `power`
(point, spot) and `illuminance` (distant) rescale as pbrt does. An image infinite light becomes a
latitude-longitude environment map (environment_map.py)."""
from __future__ import annotations

import math

import numpy as np

from renderer.scene.description import EnvironmentSpec, LightSpec
from renderer.scene.pbrt.directives import Directive
from renderer.scene.pbrt.scene_warnings import warn, warn_unused
from renderer.scene.pbrt.spectra import ILLUMINANT, NamedSpectrum, colour

BLACK = EnvironmentSpec(kind="constant", color=(0.0, 0.0, 0.0))


def spectrum(d: Directive, name: str):
    p = d.params.find(name)
    if p is None:
        return np.ones(3)
    value = colour(p, ILLUMINANT)
    if isinstance(value, NamedSpectrum):
        warn(d, f"the named spectrum '{value}' is not supported: white is used")
        return np.ones(3)
    return np.array(value, np.float64)


def _vec(v) -> tuple:
    return tuple(float(x) for x in v)


def _point(ctm: np.ndarray, p) -> np.ndarray:
    return (ctm @ np.array([*p, 1.0]))[:3]


def _direction(ctm: np.ndarray, v) -> np.ndarray:
    d = ctm[:3, :3] @ np.asarray(v, np.float64)
    n = np.linalg.norm(d)
    return d / n if n > 0 else np.array([0.0, 0.0, 1.0])


def _perpendicular(d: np.ndarray) -> tuple:
    other = np.array([0.0, 1.0, 0.0]) if abs(d[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    up = other - d * np.dot(other, d)
    return _vec(up / np.linalg.norm(up))


def read_lights(lights: list[Directive]) -> tuple[list[LightSpec], EnvironmentSpec | Directive]:
    """The lights, and the environment (or the image infinite light, which image_environment makes
    one once the scene's mirror is known)."""
    out, environment = [], None
    for d in lights:
        p = d.params
        scale = p.float("scale", 1.0)
        if d.type == "point":
            power = p.float("power", -1.0)
            rgb = spectrum(d, "I") * scale * (power / (4.0 * math.pi) if power > 0 else 1.0)
            out.append(LightSpec("point", position=_vec(_point(d.ctm, p.point3("from", (0, 0, 0)))), intensity=_vec(rgb)))
        elif d.type == "spot":
            cone, delta = p.float("coneangle", 30.0), p.float("conedeltaangle", 5.0)
            source, target = p.point3("from", (0, 0, 0)), p.point3("to", (0, 0, 1))
            rgb = spectrum(d, "I") * scale
            power = p.float("power", -1.0)
            if power > 0:
                start, end = math.cos(math.radians(cone - delta)), math.cos(math.radians(cone))
                rgb *= power / (2.0 * math.pi * ((1.0 - start) + (start - end) / 2.0))
            direction = _direction(d.ctm, np.subtract(target, source))
            out.append(LightSpec("spot", position=_vec(_point(d.ctm, source)), direction=_vec(direction),
                                 intensity=_vec(rgb), cutoff_angle=cone, beam_width=max(cone - delta, 0.0),
                                 up=_perpendicular(direction)))
        elif d.type == "distant":
            source, target = p.point3("from", (0, 0, 0)), p.point3("to", (0, 0, 1))
            illuminance = p.float("illuminance", -1.0)
            rgb = spectrum(d, "L") * scale * (illuminance if illuminance > 0 else 1.0)
            out.append(LightSpec("directional", direction=_vec(_direction(d.ctm, np.subtract(target, source))),
                                 irradiance=_vec(rgb)))
        elif d.type == "infinite":
            if environment is not None:
                warn(d, "a second infinite light is left out (Lantern has one environment)")
                for q in p.params:
                    q.used = True
            elif p.has("filename"):
                environment = d
                continue  # its parameters are read by image_environment
            else:
                rgb = spectrum(d, "L") * scale
                environment = EnvironmentSpec(kind="constant", color=_vec(rgb))
        else:
            for q in p.params:
                q.used = True
            warn(d, f"the {d.type} light is not supported: left out")
        warn_unused(d)
    return out, environment or BLACK


def area_emission(d: Directive | None) -> tuple[tuple, float, bool]:
    """The radiance a shape emits under an AreaLightSource (zero without one), the factor `power`
    asks for (the radiance is then that times power / (pi area), twice the area where two-sided,
    as pbrt-v4 has it; -1: no power given), and whether it emits from both faces."""
    if d is None:
        return (0.0, 0.0, 0.0), -1.0, False
    if d.type != "diffuse":
        warn(d, f"the {d.type} area light is not supported: the shape does not emit")
        return (0.0, 0.0, 0.0), -1.0, False
    p = d.params
    rgb = spectrum(d, "L") * p.float("scale", 1.0)
    two_sided = p.boolean("twosided", False)
    power = p.float("power", -1.0)
    if p.has("filename"):
        p.find("filename")
        warn(d, "an image on an area light is not supported: L is used")
    warn_unused(d)
    return _vec(rgb), (power / (2.0 if two_sided else 1.0) if power > 0 else -1.0), two_sided


def image_environment(d: Directive, mirror: np.ndarray | None, budget=None) -> EnvironmentSpec:
    """An image infinite light as a lat-long map (environment_map.py); a missing map is a uniform
    white one, a format that cannot be read black, each with a warning."""
    from renderer.scene.pbrt.environment_map import converted_map
    from renderer.scene.pbrt.parameters import resolve

    p = d.params
    name = p.string("filename")
    scale = p.float("scale", 1.0)
    if p.has("illuminance"):
        p.find("illuminance")
        warn(d, "illuminance is not supported: the map's own values times scale are used")
    warn_unused(d)
    path = resolve(p.find("filename").token, name)
    if path.suffix.lower() not in (".exr", ".hdr", ".pfm"):
        warn(d, f"{name}: only .exr, .hdr and .pfm maps are supported: the environment is black")
        return BLACK
    if not path.is_file():  # a neutral stand-in, as 0.5 is for a missing texture: the scene stays visible
        warn(d, f"{name}: file not found (looked for {path}): a uniform white environment (times its scale) "
                "stands in")
        return EnvironmentSpec(kind="constant", color=(1.0, 1.0, 1.0), intensity=scale)
    m3 = d.ctm[:3, :3] if mirror is None else mirror[:3, :3] @ d.ctm[:3, :3]
    try:
        file = converted_map(path, np.linalg.inv(m3), budget)
    except ValueError as e:
        raise d.error(f"{name} {e}") from None
    return EnvironmentSpec(kind="map", file=file, intensity=scale)
