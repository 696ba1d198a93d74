"""A turntable: the scene's camera orbiting once about the vertical axis through the scene's centre.

The camera keeps its distance and height relative to the centre: its position, look-at point and
up direction turn together about the axis (counter-clockwise seen from above, the right-hand rule
about +y, as the environment's `rotation`), so it sees the scene as it does at the start, from
every side in turn. The centre of a mesh scene is the centre of the bounds of its assembled
primitives (triangles, analytic shapes and Bezier patches, instances placed); SDF code offers no
bound (a plane or an unlimited repeat is infinite), so an SDF scene turns about its camera's
look_at point.
"""
from __future__ import annotations

import math
import warnings

import numpy as np

from renderer.camera import CameraFrame
from renderer.scene.description import CameraSpec, Scene


def orbit_centre(scene: Scene) -> tuple[tuple[float, float, float], str]:
    """(the point the turntable turns about, what that point is) for a loaded scene."""
    if scene.geometry == "mesh":
        from renderer.scene.mesh_assembly import assemble

        with warnings.catch_warnings():  # the renderer assembles the scene again, and warns then
            warnings.simplefilter("ignore")
            lo, hi = assemble(scene).data.scene_bounds()
        return tuple(float(c) for c in 0.5 * (lo + hi)), "the centre of the scene's bounds"
    return tuple(float(c) for c in scene.camera.look_at), "the camera's look_at point (an SDF has no bounds)"


def turn_about_y(vector: np.ndarray, angle: float) -> np.ndarray:
    """`vector` turned by `angle` radians about +y (right-handed: +z goes to +x at a quarter turn)."""
    c, s = math.cos(angle), math.sin(angle)
    x, y, z = vector
    return np.array([c * x + s * z, y, -s * x + c * z])


class Turntable:
    def __init__(self, spec: CameraSpec, centre, seconds: float, centre_text: str = ""):
        if not seconds > 0.0:
            raise ValueError(f"a turntable takes a positive number of seconds, got {seconds}")
        self.spec = spec
        self.centre = np.asarray(centre, np.float64)
        self.seconds = seconds
        self.centre_text = centre_text

    def describe(self) -> str:
        where = ", ".join(f"{c:.3g}" for c in self.centre)
        return f"a turntable of {self.seconds:g} s about ({where}), {self.centre_text}"

    def camera_at(self, t: float) -> CameraFrame:
        spec = self.spec
        turns = math.fmod(t / self.seconds, 1.0)
        if turns == 0.0:  # the start, and every whole turn: the scene's camera exactly
            return CameraFrame.from_spec(spec)
        angle = 2.0 * math.pi * turns
        centre = self.centre
        position = centre + turn_about_y(np.asarray(spec.position, np.float64) - centre, angle)
        look_at = centre + turn_about_y(np.asarray(spec.look_at, np.float64) - centre, angle)
        up = turn_about_y(np.asarray(spec.up, np.float64), angle)
        return CameraFrame.look_at(tuple(float(c) for c in position), tuple(float(c) for c in look_at),
                                   tuple(float(c) for c in up), spec.fov, spec.aperture, spec.focus_distance,
                                   spec.projection, spec.ortho_height)
