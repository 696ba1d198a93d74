"""The camera as the kernels see it: an orthonormal frame, a vertical field of view and a thin lens."""

import math
from dataclasses import dataclass

import numpy as np
import taichi as ti

from renderer.geometry.interface import Ray
from renderer.sampling import dims
from renderer.sampling.warps import concentric_disk


@dataclass(frozen=True)
class CameraFrame:
    position: tuple
    forward: tuple
    right: tuple
    up: tuple
    fov: float  # vertical, degrees
    aperture: float = 0.0  # lens radius, metres
    focus_distance: float = 1.0  # along forward, metres

    @classmethod
    def look_at(cls, position, target, up=(0.0, 1.0, 0.0), fov=45.0, aperture=0.0, focus_distance=None):
        p = np.asarray(position, np.float64)
        f = np.asarray(target, np.float64) - p
        dist = float(np.linalg.norm(f))
        f = f / dist if dist > 0 else np.array([0.0, 0.0, -1.0])
        r = np.cross(f, np.asarray(up, np.float64))
        if np.linalg.norm(r) < 1e-9:  # looking along `up`: any perpendicular right vector will do
            r = np.cross(f, [0.0, 0.0, 1.0])
        r /= np.linalg.norm(r)
        u = np.cross(r, f)
        focus = focus_distance if focus_distance is not None else (dist if dist > 0 else 1.0)
        return cls(tuple(p), tuple(f), tuple(r), tuple(u), fov, aperture, focus)

    @classmethod
    def from_spec(cls, spec):
        return cls.look_at(spec.position, spec.look_at, spec.up, spec.fov, spec.aperture, spec.focus_distance)

    def kernel_args(self):
        """The values `generate_ray` takes, in order; made once per frame (a still view launches
        every frame with the same camera, and building Taichi vectors in Python costs ~0.1 ms each)."""
        args = self.__dict__.get("_kernel_args")
        if args is None:
            v = ti.math.vec3
            args = (v(*self.position), v(*self.forward), v(*self.right), v(*self.up),
                    math.tan(math.radians(self.fov) * 0.5), self.aperture, self.focus_distance)
            object.__setattr__(self, "_kernel_args", args)  # a cache, not a field: eq and hash ignore it
        return args

    def __getstate__(self):
        """Pickled (to a distributed worker) without the cached Taichi values."""
        return {k: v for k, v in self.__dict__.items() if k != "_kernel_args"}


@ti.func
def generate_ray(x, y, width, height, jitter, sampler: ti.template(), state, origin, forward, right, up,
                 tan_half_fov, aperture, focus, depth_of_field: ti.template()):
    """A camera ray through the point `jitter` of pixel (x, y)'s own [0, 1)^2 frame (y up; the pixel
    filter may put it outside), through the lens."""
    aspect = width / height
    sx = (2.0 * (x + jitter.x) / width - 1.0) * tan_half_fov * aspect
    sy = (2.0 * (y + jitter.y) / height - 1.0) * tan_half_fov
    d = ti.math.normalize(forward + sx * right + sy * up)
    o = origin
    if ti.static(depth_of_field):
        focus_point = o + d * (focus / d.dot(forward))
        lens = concentric_disk(sampler.get2d(state, dims.LENS)) * aperture
        o = origin + lens.x * right + lens.y * up
        d = ti.math.normalize(focus_point - o)
    # A pixel subtends about 2 tan(fov/2) / height radians: the cone the SDF marcher scales with.
    return Ray(o=o, d=d, cone_width=0.0, cone_spread=2.0 * tan_half_fov / height)
