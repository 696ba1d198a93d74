"""Mitsuba 3 emitters made into Lantern's environment, lights and emission (the emitter part of
scene_builder.py, which hands each emitter plugin here).

  constant, envmap                        the environment (one; a second is left out with a warning)
  point, spot, directional, projector     `LightSpec`s: lights without a surface (a spot's projected
                                          `texture` and a projector's `irradiance` image included)
  area (nested in a shape)                the shape's emission: a colour, or a bitmap / checkerboard
                                          texture on `radiance`

Mitsuba's emitters place themselves with a camera's look-at frame (to_world's columns: left, up,
forward); a light keeps its position, its forward axis and its up, which orient projected images.
"""
from __future__ import annotations

import math

import numpy as np

from renderer.scene.description import FOV_AXES, EnvironmentSpec, LightSpec, TextureSpec
from renderer.scene.mitsuba.plugins import Plugin
from renderer.scene.mitsuba.scene_warnings import leave_out, warn

DELTA_LIGHTS = ("point", "spot", "directional", "projector")
IMAGE_TEXTURES = ("bitmap", "checkerboard")  # the textures Lantern can project or emit
DEFAULT_FOCAL_LENGTH = "50mm"  # Mitsuba's projector, as its perspective camera
FILM_DIAGONAL_MM = math.hypot(36.0, 24.0)  # focal_length converts against 35 mm film's diagonal


class EmitterReader:
    """Reads emitter plugins with the scene builder's value readers (`colour`, `texture`, `find`,
    `visit`) and collects the lights into its `lights` list."""

    def __init__(self, builder):
        self.builder = builder

    # --- the scene's own emitters ----------------------------------------------------------------

    def environment(self, emitters: list[Plugin]) -> EnvironmentSpec:
        """The environment among the scene's top-level emitters; their lights join builder.lights."""
        chosen = None
        for emitter in emitters:
            self.builder.visit(emitter)
            if emitter.type in ("constant", "envmap"):
                if chosen is not None:
                    warn(emitter, "a second environment emitter is left out (Lantern has one environment)")
                    continue
                chosen = self.constant(emitter) if emitter.type == "constant" else self.envmap(emitter)
            elif emitter.type in DELTA_LIGHTS:
                self.builder.lights.append(self.light(emitter))
            else:
                leave_out(emitter, "this emitter type is not supported yet and is left out")
        return chosen or EnvironmentSpec(kind="constant", color=(0.0, 0.0, 0.0))

    def constant(self, emitter: Plugin) -> EnvironmentSpec:
        return EnvironmentSpec(kind="constant",
                               color=self.builder.colour(emitter, "radiance", (1.0, 1.0, 1.0), emitter=True))

    def envmap(self, emitter: Plugin) -> EnvironmentSpec:
        name = emitter.text("filename")
        if name is None:
            raise emitter.error("needs a filename")
        file = self.builder.find(emitter, name)
        frame = envmap_frame(emitter)
        spec = EnvironmentSpec(kind="map", file=file, intensity=emitter.number("scale", 1.0),
                               to_world=tuple(tuple(float(x) for x in row) for row in frame))
        angle = spec.y_rotation()
        if angle is not None:  # a turn about +y: the azimuth offset, no matrix compiled in
            return EnvironmentSpec(kind="map", file=file, intensity=spec.intensity, rotation=angle)
        return spec

    # --- lights without a surface ----------------------------------------------------------------

    def light(self, emitter: Plugin) -> LightSpec:
        """A point, spot, directional or projector emitter (Mitsuba's local frame: a spot and a
        projector shine along +z, a directional light travels along +z)."""
        t = emitter.type
        if t == "directional":
            irradiance = self.builder.colour(emitter, "irradiance", (1.0, 1.0, 1.0), emitter=True)
            return LightSpec("directional", direction=frame_vector(emitter, "direction"), irradiance=irradiance)
        if t == "projector":
            return self.projector(emitter)
        intensity = self.builder.colour(emitter, "intensity", (1.0, 1.0, 1.0), emitter=True)
        if t == "point":
            return LightSpec("point", position=light_position(emitter), intensity=intensity)
        return self.spot(emitter, intensity)

    def spot(self, emitter: Plugin, intensity: tuple) -> LightSpec:
        cutoff = emitter.number("cutoff_angle", 20.0)
        beam = emitter.number("beam_width", 0.75 * cutoff)
        if not 0.0 < cutoff < 180.0:
            raise emitter.error(f"cutoff_angle {cutoff:g} is not between 0 and 180 degrees")
        if not 0.0 <= beam <= cutoff:
            raise emitter.error(f"beam_width {beam:g} is not between 0 and cutoff_angle {cutoff:g}")
        texture = self.image(emitter, "texture")
        if texture is not None and cutoff >= 90.0:
            warn(emitter, f"a texture on a spot with cutoff_angle {cutoff:g} >= 90 degrees maps nowhere "
                          "(Mitsuba projects it over the cone's tangent plane): the spot is untextured")
            texture = None
        if not _similarity(emitter.transform()):
            warn(emitter, "its to_world scales unevenly or shears, which would make the cone elliptical: "
                          "the cone is kept round about its axis")
        position, direction, up, _ = look_at_frame(emitter)
        return LightSpec("spot", position=position, direction=direction, up=up, intensity=intensity,
                         cutoff_angle=cutoff, beam_width=beam, texture=texture)

    def projector(self, emitter: Plugin) -> LightSpec:
        """Mitsuba's projector: `irradiance` (a texture or a colour) times `scale`, through its field
        of view (fov along fov_axis, or focal_length)."""
        if not emitter.has("irradiance"):
            raise emitter.error("needs an irradiance (a texture or a colour)")
        texture = self.image(emitter, "irradiance")
        irradiance = (1.0, 1.0, 1.0) if texture is not None else self.builder.colour(
            emitter, "irradiance", (1.0, 1.0, 1.0), emitter=True)
        fov, axis = projector_fov(emitter)
        if not _similarity(emitter.transform()):
            warn(emitter, "its to_world scales unevenly or shears, which Lantern's projector does not: "
                          "only its position and orientation are kept")
        position, direction, up, scale = look_at_frame(emitter)
        # Mitsuba divides by the depth in its own (scaled) frame but by the length of its scaled axis
        # only once: a projector scaled by s is s times brighter.
        factor = emitter.number("scale", 1.0) * scale
        return LightSpec("projector", position=position, direction=direction, up=up,
                         irradiance=tuple(float(c) * factor for c in irradiance), texture=texture, fov=fov,
                         fov_axis=axis)

    def image(self, emitter: Plugin, name: str) -> TextureSpec | None:
        """The bitmap or checkerboard texture on parameter `name`, or None (no texture there; any
        other texture type is warned about and left out)."""
        value = emitter.properties.get(name)
        if not (isinstance(value, Plugin) and value.kind == "texture"):
            return None
        emitter.used.add(name)
        if value.type not in IMAGE_TEXTURES:
            warn(emitter, f"a <texture type=\"{value.type}\"> on '{name}' is not supported: left out")
            return None
        return self.builder.texture(self.builder.visit(value))

    # --- area emitters ---------------------------------------------------------------------------

    def area(self, emitter: Plugin) -> tuple[tuple, TextureSpec | None]:
        """An area emitter's (radiance colour, radiance texture or None): a texture's value is the
        radiance itself, so its colour is white."""
        texture = self.image(emitter, "radiance")
        if texture is not None:
            return (1.0, 1.0, 1.0), texture
        return self.builder.colour(emitter, "radiance", (1.0, 1.0, 1.0), emitter=True), None


def light_position(emitter: Plugin) -> tuple:
    """A light's `position`, else its to_world's origin (not both, as in Mitsuba)."""
    if emitter.has("position"):
        if emitter.has("to_world"):
            raise emitter.error("give position or to_world, not both")
        return _vec(_triple(emitter, "position"))
    return _vec(emitter.transform()[:3, 3])


def frame_vector(emitter: Plugin, name: str | None) -> tuple:
    """The unit direction of the light's local +z: the vector parameter `name` where given (not
    with to_world, as in Mitsuba), else its to_world's."""
    if name is not None and emitter.has(name):
        if emitter.has("to_world"):
            raise emitter.error(f"give {name} or to_world, not both")
        v = np.asarray(_triple(emitter, name), np.float64)
    else:
        v = emitter.transform()[:3, :3] @ np.array([0.0, 0.0, 1.0])
    length = float(np.linalg.norm(v))
    if not np.isfinite(length) or length == 0.0:
        raise emitter.error(f"its {name or 'to_world'} gives no direction (a zero vector)")
    return _vec(v / length)


def look_at_frame(emitter: Plugin) -> tuple[tuple, tuple, tuple, float]:
    """(position, unit forward, unit up, scale) of an emitter's to_world: its origin, its local +z
    and +y made orthonormal, and its mean axis length (1 for a rotation)."""
    matrix = emitter.transform()
    forward = frame_vector(emitter, None)
    up = matrix[:3, :3] @ np.array([0.0, 1.0, 0.0])
    up = up - np.dot(up, forward) * np.asarray(forward)
    length = float(np.linalg.norm(up))
    if not np.isfinite(length) or length < 1e-12:
        raise emitter.error("its to_world gives no up direction (local +y along +z, or zero)")
    scale = float(np.cbrt(abs(np.linalg.det(matrix[:3, :3]))))
    return _vec(matrix[:3, 3]), forward, _vec(up / length), scale


def projector_fov(emitter: Plugin) -> tuple[float, str]:
    """(fov in degrees, the axis it spans) from fov and fov_axis, or from focal_length (35 mm film's
    diagonal), as Mitsuba's perspective camera and projector read them."""
    if emitter.has("fov") and emitter.has("focal_length"):
        raise emitter.error("give fov or focal_length, not both")
    if emitter.has("fov"):
        fov, axis = emitter.number("fov", 0.0), emitter.text("fov_axis", "x").lower()
        if axis not in FOV_AXES:
            raise emitter.error(f"fov_axis '{axis}' ({', '.join(FOV_AXES)})")
    else:
        text = emitter.text("focal_length", DEFAULT_FOCAL_LENGTH)
        try:
            mm = float(text.lower().removesuffix("mm"))
        except ValueError:
            raise emitter.error(f"focal_length '{text}' is not a length in mm") from None
        if mm <= 0.0:
            raise emitter.error(f"focal_length '{text}' is not a positive length")
        fov, axis = math.degrees(2.0 * math.atan(FILM_DIAGONAL_MM / (2.0 * mm))), "diagonal"
        emitter.used.add("fov_axis")
    if not 0.0 < fov < 180.0:
        raise emitter.error(f"fov {fov:g} is not between 0 and 180 degrees")
    return fov, axis


def envmap_frame(emitter: Plugin) -> np.ndarray:
    """The orthogonal part of an envmap's to_world (3x3; a mirror kept, as Mitsuba mirrors the map).

    Mitsuba looks a direction up at to_world^-1 d without normalising it, so a scale or shear there
    bends its map (and its samples disagree with its lookups): that is one warning, and the
    orthogonal factor of the polar decomposition, the rotation nearest the matrix, is kept.
    Translation does not move directions and is ignored, as in Mitsuba."""
    matrix = emitter.transform()[:3, :3]
    u, sigma, vt = np.linalg.svd(matrix)
    if not sigma[-1] > 1e-12 * max(sigma[0], 1e-300):
        raise emitter.error("its to_world is singular: it gives the map no orientation")
    if not np.allclose(sigma, 1.0, rtol=0.0, atol=1e-5):
        warn(emitter, "its to_world scales or shears, which an environment cannot: only its rotation is kept")
    return u @ vt


def _similarity(matrix: np.ndarray) -> bool:
    """Whether a to_world's 3x3 part is a rotation times a uniform scale (no uneven scale or shear)."""
    m = matrix[:3, :3]
    scale = np.linalg.norm(m, axis=0)
    if not np.allclose(scale, scale.mean(), rtol=1e-5):
        return False
    columns = m / scale
    return bool(np.allclose(columns.T @ columns, np.eye(3), atol=1e-5))


def _vec(v) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))


def _triple(plugin: Plugin, name: str) -> tuple:
    value = plugin.get(name)
    if not (isinstance(value, tuple) and len(value) == 3):
        raise plugin.error(f"'{name}' must be a <point> or <vector>")
    return value
