"""Camera pose and lens parameters shared by the viewer and the renderer.

Conventions: right-handed, y up; with yaw = pitch = 0 the camera looks down -z.
Positive yaw turns left (counter-clockwise seen from above, towards -x),
positive pitch looks up. Angles are radians, except ``fov`` (vertical, degrees).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

WORLD_UP = np.array([0.0, 1.0, 0.0])
PITCH_LIMIT = math.pi / 2 - 1e-3  # keeps forward away from WORLD_UP so the basis never degenerates


def clamp_pitch(pitch: float) -> float:
    return min(max(float(pitch), -PITCH_LIMIT), PITCH_LIMIT)


@dataclass(frozen=True)
class CameraState:
    position: tuple[float, float, float]
    yaw: float = 0.0
    pitch: float = 0.0
    fov: float = 45.0  # vertical field of view, degrees
    aperture: float = 0.0  # lens radius, metres (0 = pinhole)
    focus_distance: float = 1.0  # metres
    projection: str = "perspective"  # or "orthographic": parallel rays, `ortho_height` metres tall
    ortho_height: float = 2.0  # metres

    def __post_init__(self):
        position = tuple(float(c) for c in self.position)
        if len(position) != 3:
            raise ValueError(f"position needs 3 components, got {self.position!r}")
        object.__setattr__(self, "position", position)
        object.__setattr__(self, "yaw", float(self.yaw))
        object.__setattr__(self, "pitch", clamp_pitch(self.pitch))
        object.__setattr__(self, "fov", float(self.fov))
        object.__setattr__(self, "aperture", float(self.aperture))
        object.__setattr__(self, "focus_distance", float(self.focus_distance))
        object.__setattr__(self, "ortho_height", float(self.ortho_height))
        if not 0.0 < self.fov < 180.0:
            raise ValueError(f"fov must be in (0, 180) degrees, got {self.fov}")
        if self.aperture < 0.0:
            raise ValueError(f"aperture must be >= 0, got {self.aperture}")
        if self.focus_distance <= 0.0:
            raise ValueError(f"focus_distance must be > 0, got {self.focus_distance}")
        if self.projection not in ("perspective", "orthographic"):
            raise ValueError(f"projection must be perspective or orthographic, got {self.projection!r}")
        if self.ortho_height <= 0.0:
            raise ValueError(f"ortho_height must be > 0, got {self.ortho_height}")

    def forward(self) -> np.ndarray:
        cp = math.cos(self.pitch)
        return np.array([-math.sin(self.yaw) * cp, math.sin(self.pitch), -math.cos(self.yaw) * cp])

    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Orthonormal right-handed camera frame ``(forward, right, up)``."""
        forward = self.forward()
        right = np.cross(forward, WORLD_UP)
        right /= np.linalg.norm(right)
        up = np.cross(right, forward)
        up /= np.linalg.norm(up)
        return forward, right, up

    @classmethod
    def from_look_at(cls, position, look_at, up=(0.0, 1.0, 0.0), fov=45.0, aperture=0.0,
                     focus_distance=None, projection="perspective", ortho_height=2.0) -> "CameraState":
        """Camera at ``position`` looking at ``look_at``.

        Only a +y world up is supported (yaw/pitch are relative to it). Looking
        straight up/down clamps the pitch; ``look_at == position`` looks down -z.
        ``focus_distance`` defaults to the distance to ``look_at`` (1 m if zero).
        """
        up = np.asarray(up, dtype=float)
        if np.linalg.norm(up) == 0 or np.dot(up / np.linalg.norm(up), WORLD_UP) < 1 - 1e-6:
            raise ValueError(f"only a +y up vector is supported, got {tuple(up)}")
        d = np.asarray(look_at, dtype=float) - np.asarray(position, dtype=float)
        dist = float(np.linalg.norm(d))
        if dist > 0.0:
            horizontal = math.hypot(d[0], d[2])
            yaw = math.atan2(-d[0], -d[2]) if horizontal > 0.0 else 0.0
            pitch = math.atan2(d[1], horizontal)
        else:
            yaw = pitch = 0.0
        if focus_distance is None:
            focus_distance = dist if dist > 0.0 else 1.0
        return cls(position=tuple(position), yaw=yaw, pitch=pitch, fov=fov,
                   aperture=aperture, focus_distance=focus_distance, projection=projection,
                   ortho_height=ortho_height)

    def replace(self, **changes) -> "CameraState":
        return dataclasses.replace(self, **changes)
