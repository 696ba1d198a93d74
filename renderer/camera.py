"""The camera as the kernels see it: an orthonormal frame, a projection (perspective with a vertical
field of view, or orthographic with the height of the view) and a thin lens."""

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
    fov: float  # vertical, degrees (perspective)
    aperture: float = 0.0  # lens radius, metres
    focus_distance: float = 1.0  # along forward, metres
    projection: str = "perspective"  # one of renderer.scene.description.PROJECTIONS
    ortho_height: float = 2.0  # orthographic: the height of the view, metres

    @property
    def orthographic(self) -> bool:
        return self.projection == "orthographic"

    @classmethod
    def look_at(cls, position, target, up=(0.0, 1.0, 0.0), fov=45.0, aperture=0.0, focus_distance=None,
                projection="perspective", ortho_height=2.0):
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
        return cls(tuple(p), tuple(f), tuple(r), tuple(u), fov, aperture, focus, projection, ortho_height)

    @classmethod
    def from_spec(cls, spec):
        return cls.look_at(spec.position, spec.look_at, spec.up, spec.fov, spec.aperture, spec.focus_distance,
                           spec.projection, spec.ortho_height)

    @property
    def half_height(self) -> float:
        """Half the view's height: at unit distance (tan(fov/2)) for a perspective camera, in
        metres for an orthographic one."""
        return 0.5 * self.ortho_height if self.orthographic else math.tan(math.radians(self.fov) * 0.5)

    def kernel_args(self):
        """The values `generate_ray` takes, in order; made once per frame (a still view launches
        every frame with the same camera, and building Taichi vectors in Python costs ~0.1 ms each)."""
        args = self.__dict__.get("_kernel_args")
        if args is None:
            v = ti.math.vec3
            args = (v(*self.position), v(*self.forward), v(*self.right), v(*self.up), self.half_height,
                    self.aperture, self.focus_distance)
            object.__setattr__(self, "_kernel_args", args)  # a cache, not a field: eq and hash ignore it
        return args

    def __getstate__(self):
        """Pickled (to a distributed worker) without the cached Taichi values."""
        return {k: v for k, v in self.__dict__.items() if k != "_kernel_args"}


@ti.func
def pinhole_ray(u, v, aspect, origin, forward, right, up, half_height, orthographic: ti.template()):
    """(origin, unit direction) of the ray through the point (u, v) of the image, each in [-1, 1]
    (y up), before any lens: through the eye (perspective), or along `forward` from that point of
    the view's plane (orthographic)."""
    sx = u * half_height * aspect
    sy = v * half_height
    o = origin
    d = forward
    if ti.static(orthographic):
        o = origin + sx * right + sy * up
    else:
        d = ti.math.normalize(forward + sx * right + sy * up)
    return o, d


@ti.func
def pixel_footprint(half_height, height):
    """A pixel's footprint, which ray cones start from and the SDF marcher scales its hit threshold
    with: 2 half_height / height radians wide (perspective) or metres wide (orthographic)."""
    return 2.0 * half_height / height


@ti.func
def generate_ray(x, y, width, height, jitter, sampler: ti.template(), state, origin, forward, right, up,
                 half_height, aperture, focus, depth_of_field: ti.template(), orthographic: ti.template()):
    """A camera ray through the point `jitter` of pixel (x, y)'s own [0, 1)^2 frame (y up; the pixel
    filter may put it outside), through the lens. `half_height`: CameraFrame.half_height."""
    o, d = pinhole_ray(2.0 * (x + jitter.x) / width - 1.0, 2.0 * (y + jitter.y) / height - 1.0, width / height,
                       origin, forward, right, up, half_height, orthographic)
    if ti.static(depth_of_field):
        focus_point = o + d * (focus / d.dot(forward))
        lens = concentric_disk(sampler.get2d(state, dims.LENS)) * aperture
        o = o + lens.x * right + lens.y * up
        d = ti.math.normalize(focus_point - o)
    pixel = pixel_footprint(half_height, height)
    cone_width = 0.0
    cone_spread = pixel
    if ti.static(orthographic):
        cone_width = pixel
        cone_spread = 0.0
    return Ray(o=o, d=d, cone_width=cone_width, cone_spread=cone_spread)
