"""A camera framed on a bounding box: what a model file opens with (renderer.scene.model_scene)."""
from __future__ import annotations

import math

import numpy as np


def frame_camera(bounds, fov_deg: float, aspect: float = 1.0,
                 direction=(0.0, 0.25, 1.0), margin: float = 1.1):
    """(position, look_at) that frames a bounding box: look at its centre from `direction`.

    The camera backs off until the bounding sphere fits the narrower of the vertical field of view
    `fov_deg` (degrees) and the horizontal one implied by `aspect` (width / height), times `margin`.
    """
    b = np.asarray(bounds, dtype=np.float64).reshape(2, 3)
    if not np.all(np.isfinite(b)):
        raise ValueError("bounds must be finite")
    centre = 0.5 * (b[0] + b[1])
    radius = 0.5 * float(np.linalg.norm(b[1] - b[0]))
    if radius <= 0.0:
        radius = 1.0  # a single point: frame a unit sphere around it
    half_v = math.radians(min(max(fov_deg, 1e-3), 179.0)) / 2.0
    half_h = math.atan(math.tan(half_v) * max(aspect, 1e-6))
    half = min(half_v, half_h)
    distance = margin * radius / math.sin(half)
    d = np.asarray(direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    position = centre + d * distance
    return tuple(float(v) for v in position), tuple(float(v) for v in centre)
