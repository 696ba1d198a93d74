"""A camera path: a scene's keyframes turned into the camera at any time, as plain numpy.

Position and look-at point follow a cubic Hermite spline in time whose velocity at an inner
keyframe is the derivative of the parabola through it and its two neighbours (non-uniform
Catmull-Rom), and zero at the first and last keyframe: the curve is C1 everywhere, the holds
before and after the keyframes included, and the camera eases in and out. The up direction
follows the same spline (unit vectors in, the frame normalises). The field of view follows a
monotone spline (Fritsch-Butland slopes, as scipy's PCHIP), which never leaves the range of the
two keyframes around it, so it stays a valid angle. At a keyframe's time the camera is the
keyframe's, exactly as a still camera with those values.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from renderer.camera import CameraFrame
from renderer.scene.description import CameraSpec


@dataclass(frozen=True)
class Keyframes:
    """The keyframes as arrays (n keyframes, n >= 2, times strictly increasing)."""

    times: np.ndarray  # (n,)
    positions: np.ndarray  # (n, 3)
    look_ats: np.ndarray  # (n, 3)
    ups: np.ndarray  # (n, 3), as written (the camera's where a keyframe names none)
    fovs: np.ndarray  # (n,)

    @classmethod
    def from_spec(cls, spec: CameraSpec) -> "Keyframes":
        """The scene camera's keyframes (the loader has checked them), with the camera's up and
        fov where a keyframe names none."""
        rows = [dict(k) for k in spec.keyframes]
        return cls(times=np.array([r["time"] for r in rows], np.float64),
                   positions=np.array([r["position"] for r in rows], np.float64),
                   look_ats=np.array([r["look_at"] for r in rows], np.float64),
                   ups=np.array([r["up"] if r["up"] is not None else spec.up for r in rows], np.float64),
                   fovs=np.array([r["fov"] if r["fov"] is not None else spec.fov for r in rows], np.float64))


def catmull_rom_velocities(times: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Velocities (d value / d time) at the keyframes: zero at the ends; inside, the derivative at
    t_i of the parabola through keyframes i - 1, i, i + 1 (the secants weighted by the other
    interval's length)."""
    velocities = np.zeros_like(values)
    h = np.diff(times)
    secants = np.diff(values, axis=0) / h.reshape((-1,) + (1,) * (values.ndim - 1))
    if len(times) > 2:
        before, after = h[:-1], h[1:]
        shape = (-1,) + (1,) * (values.ndim - 1)
        velocities[1:-1] = ((after.reshape(shape) * secants[:-1] + before.reshape(shape) * secants[1:])
                            / (before + after).reshape(shape))
    return velocities


def monotone_velocities(times: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Slopes of a monotone cubic through scalar keyframes: zero at the ends and at local extrema,
    else the weighted harmonic mean of the two secants (Fritsch-Butland), which keeps each segment
    within its two values."""
    slopes = np.zeros_like(values)
    h = np.diff(times)
    secants = np.diff(values) / h
    for i in range(1, len(times) - 1):
        s0, s1 = secants[i - 1], secants[i]
        if s0 * s1 > 0.0:
            w0, w1 = 2.0 * h[i] + h[i - 1], h[i] + 2.0 * h[i - 1]
            slopes[i] = (w0 + w1) / (w0 / s0 + w1 / s1)
    return slopes


def hermite(times: np.ndarray, values: np.ndarray, velocities: np.ndarray, t: float):
    """The cubic Hermite spline through (times, values) with `velocities`, at time t; the first
    and last values held outside [times[0], times[-1]]. At a keyframe's time, its value exactly."""
    if t <= times[0]:
        return values[0]
    if t >= times[-1]:
        return values[-1]
    k = int(np.searchsorted(times, t, side="right")) - 1
    h = times[k + 1] - times[k]
    u = (t - times[k]) / h
    u2, u3 = u * u, u * u * u
    return ((2.0 * u3 - 3.0 * u2 + 1.0) * values[k] + (u3 - 2.0 * u2 + u) * h * velocities[k]
            + (3.0 * u2 - 2.0 * u3) * values[k + 1] + (u3 - u2) * h * velocities[k + 1])


class CameraPath:
    """The camera of a scene at any time: its keyframes' path, or its still camera when it has none."""

    def __init__(self, spec: CameraSpec):
        self.spec = spec
        self.keyframes = Keyframes.from_spec(spec) if spec.keyframes else None
        if self.keyframes is not None:
            k = self.keyframes
            unit_ups = k.ups / np.linalg.norm(k.ups, axis=1, keepdims=True)
            self._unit_ups = unit_ups
            self._velocities = {name: catmull_rom_velocities(k.times, values)
                                for name, values in (("position", k.positions), ("look_at", k.look_ats),
                                                     ("up", unit_ups))}
            self._fov_slopes = monotone_velocities(k.times, k.fovs)

    @property
    def animated(self) -> bool:
        return self.keyframes is not None

    def describe(self) -> str:
        if self.keyframes is None:
            return "a still camera (the scene has no keyframes)"
        k = self.keyframes
        return f"a camera path of {len(k.times)} keyframes from {k.times[0]:g} s to {k.times[-1]:g} s"

    def camera_at(self, t: float) -> CameraFrame:
        spec = self.spec
        if self.keyframes is None:
            return CameraFrame.from_spec(spec)
        k = self.keyframes
        i = self._keyframe_at(t)
        if i is not None:  # the keyframe as written (its up unnormalised), as a still camera would be
            position, look_at, up, fov = k.positions[i], k.look_ats[i], k.ups[i], k.fovs[i]
        else:
            position = hermite(k.times, k.positions, self._velocities["position"], t)
            look_at = hermite(k.times, k.look_ats, self._velocities["look_at"], t)
            up = hermite(k.times, self._unit_ups, self._velocities["up"], t)
            fov = hermite(k.times, k.fovs, self._fov_slopes, t)
        return CameraFrame.look_at(tuple(float(c) for c in position), tuple(float(c) for c in look_at),
                                   tuple(float(c) for c in up), float(fov), spec.aperture, spec.focus_distance,
                                   spec.projection, spec.ortho_height)

    def _keyframe_at(self, t: float) -> int | None:
        """The keyframe the camera is at time t: one held (before the first, after the last), one
        whose time t is; None between keyframes."""
        times = self.keyframes.times
        if t <= times[0]:
            return 0
        if t >= times[-1]:
            return len(times) - 1
        exact = np.flatnonzero(times == t)
        return int(exact[0]) if exact.size else None
