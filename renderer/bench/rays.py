"""The BVH benchmark's ray sets: a pinhole camera's coherent rays and incoherent random rays (with
their shadow segments) around a box, and the rate figures of a timed ray call."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

FAR = 1e30  # t_max of closest-hit rays (the geometry interface's INF)


@dataclass
class Rays:
    origins: np.ndarray  # (N, 3) f32
    directions: np.ndarray  # (N, 3) f32, unit
    t_max: np.ndarray  # (N,) f32

    def __len__(self) -> int:
        return int(self.origins.shape[0])

    def head(self, n: int) -> "Rays":
        return Rays(self.origins[:n], self.directions[:n], self.t_max[:n])


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def camera_rays(lo, hi, width: int, height: int, fov_deg: float = 40.0,
                direction=(0.0, 0.75, 1.0), margin: float = 0.6) -> Rays:
    """One ray through each pixel centre of a pinhole camera looking at the centre of the box
    [lo, hi] from `direction`. margin 1 fits the box's bounding sphere in the view, which leaves
    most pixels empty; 0.6 is a closer view where most rays hit (about 60 % on the bunny and
    the terrains), as in a rendered frame."""
    from renderer.scene.framing import frame_camera

    position, look_at = frame_camera(np.stack([lo, hi]), fov_deg, width / height, direction, margin=margin)
    eye = np.asarray(position, np.float64)
    forward = _unit(np.asarray(look_at, np.float64) - eye)
    right = _unit(np.cross(forward, (0.0, 1.0, 0.0)))
    up = np.cross(right, forward)
    tan_v = math.tan(math.radians(fov_deg) / 2.0)
    tan_h = tan_v * width / height
    xs = ((np.arange(width) + 0.5) / width * 2.0 - 1.0) * tan_h
    ys = (1.0 - (np.arange(height) + 0.5) / height * 2.0) * tan_v
    gx, gy = np.meshgrid(xs, ys)  # row-major: scanlines, the order a renderer fires them
    d = _unit(forward + gx[..., None] * right + gy[..., None] * up).reshape(-1, 3)
    o = np.broadcast_to(eye, d.shape)
    return Rays(np.ascontiguousarray(o, np.float32), np.ascontiguousarray(d, np.float32),
                np.full(len(d), FAR, np.float32))


def random_rays(lo, hi, n: int, seed: int) -> tuple[Rays, Rays]:
    """Incoherent rays: origins uniform on a sphere of 1.5x the box's bounding radius around its
    centre, aimed at uniform random points in the box. Returns (closest-hit rays with t_max = FAR,
    the same rays as shadow segments ending at their target points)."""
    rng = np.random.default_rng(seed)
    lo = np.asarray(lo, np.float64)
    hi = np.asarray(hi, np.float64)
    centre = 0.5 * (lo + hi)
    radius = 1.5 * max(0.5 * float(np.linalg.norm(hi - lo)), 1e-6)
    origins = centre + radius * _unit(rng.normal(size=(n, 3)))
    targets = rng.uniform(lo, hi, size=(n, 3))
    delta = targets - origins
    length = np.linalg.norm(delta, axis=1)
    o = np.ascontiguousarray(origins, np.float32)
    d = np.ascontiguousarray(delta / length[:, None], np.float32)
    return (Rays(o, d, np.full(n, FAR, np.float32)), Rays(o, d, length.astype(np.float32)))


def ray_rates(rays: int, timing) -> dict:
    """Millions of rays per second of a timed call over `rays` rays: from the median run and from
    the fastest (the least disturbed on a busy machine), with the timing itself."""
    return {"rays": rays, "mrays_per_s": rays / timing.median / 1e6, "mrays_per_s_best": rays / timing.min / 1e6,
            "timing": timing.as_dict()}
