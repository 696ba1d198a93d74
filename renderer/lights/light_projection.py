"""Images that lights project (numpy, no Taichi): a spot's texture and a projector's image.

Both follow Mitsuba 3. A light's frame is a camera's look-at frame: local z along its `direction`,
local y towards `up`, local x = y cross z (the camera's left). A point or direction (x, y, z) in
that frame reads the light's image at

  uv = 1/2 + 1/2 (k_u x / z, k_v y / z)          (uv (0, 0) the image's top-left texel corner)

  spot       k = (1, 1) / tan(cutoff): the cone's cutoff circle is the image's inscribed circle;
             the texture multiplies the intensity and the falloff.
  projector  k = -(1, aspect) / tan(fov_x / 2) (Mitsuba's perspective projection: its u grows
             towards the light's right); only 0 <= u, v <= 1 in front of it is lit, with
             irradiance pi E(uv) on a plane at distance 1 facing it, that is the value
             pi E(uv) r / z^3 at distance r and depth z (`projector_value`).

The device side (renderer/lights/delta_lights.py) uses the same `projection_scale` and frames;
the functions here are also its numpy reference in the tests.
"""
from __future__ import annotations

import math

import numpy as np

from renderer.scene.description import LightSpec
from renderer.scene.mesh_model import STORAGES, TextureImage
from renderer.scene.textures import decode_texels
from renderer.spectral.luminance import LUMINANCE_WEIGHTS


def light_frame(spec: LightSpec) -> np.ndarray:
    """Rows: the light's local x, y and z axes in world space (orthonormal)."""
    z = np.asarray(spec.direction, np.float64)
    z = z / np.linalg.norm(z)
    x = np.cross(np.asarray(spec.up, np.float64), z)
    length = np.linalg.norm(x)
    if length < 1e-9:  # up along the axis: any perpendicular (the loaders refuse this where it matters)
        x = np.cross([1.0, 0.0, 0.0] if abs(z[0]) < 0.9 else [0.0, 1.0, 0.0], z)
        length = np.linalg.norm(x)
    x = x / length
    return np.stack([x, np.cross(z, x), z])


def x_fov_tangent(fov_deg: float, axis: str, aspect: float) -> float:
    """tan(fov_x / 2) of an image `aspect` (width / height) wide, for a field of view `fov_deg`
    along `axis` (Mitsuba's fov_axis: x, y, diagonal, smaller or larger)."""
    if axis == "smaller":
        axis = "x" if aspect < 1.0 else "y"
    elif axis == "larger":
        axis = "x" if aspect > 1.0 else "y"
    extent = {"x": aspect, "y": 1.0, "diagonal": math.hypot(aspect, 1.0)}[axis]
    return math.tan(math.radians(fov_deg) / 2.0) * aspect / extent


def projection_scale(spec: LightSpec, aspect: float) -> tuple[float, float]:
    """(k_u, k_v) of the module docs, for a light whose image is `aspect` wide."""
    if spec.kind == "spot":
        k = 1.0 / math.tan(math.radians(spec.cutoff_angle))
        return k, k
    cot = 1.0 / x_fov_tangent(spec.fov, spec.fov_axis, aspect)
    return -cot, -aspect * cot


def image_uv(scale, local: np.ndarray) -> np.ndarray:
    """uv (..., 2) where local points or directions (..., 3) meet the light's image."""
    local = np.asarray(local, np.float64)
    return 0.5 + 0.5 * np.stack([scale[0] * local[..., 0], scale[1] * local[..., 1]], axis=-1) / local[..., 2:3]


def projector_value(uv: np.ndarray, depth: np.ndarray, distance: np.ndarray) -> np.ndarray:
    """The factor pi r / z^3 that multiplies a projector's E(uv) (0 outside its image or behind it)."""
    inside = (depth > 0.0) & np.all((uv >= 0.0) & (uv <= 1.0), axis=-1)
    return np.where(inside, math.pi * distance / np.where(inside, depth, 1.0) ** 3, 0.0)


def mean_luminance(image: TextureImage) -> float:
    """The image's mean linear luminance (a light's power, for choosing among lights)."""
    texels = decode_texels(image.pixels, STORAGES.index(image.storage), image.srgb)
    return float(np.mean(texels[..., :3].astype(np.float64) @ np.asarray(LUMINANCE_WEIGHTS)))


def projector_power(spec: LightSpec, image: TextureImage | None) -> float:
    """A projector's luminance power (W): pi E over its image at distance 1, whose area is
    2 tan(fov_x / 2) by 2 tan(fov_x / 2) / aspect."""
    aspect = image_aspect(image)
    tan_x = x_fov_tangent(spec.fov, spec.fov_axis, aspect)
    mean = mean_luminance(image) if image is not None else 1.0
    irradiance = float(np.asarray(LUMINANCE_WEIGHTS) @ np.asarray(spec.irradiance))
    return math.pi * irradiance * mean * 4.0 * tan_x * tan_x / aspect


def image_aspect(image: TextureImage | None) -> float:
    """Width over height (1 without an image: a constant projector's image is square, as Mitsuba's)."""
    if image is None:
        return 1.0
    height, width = image.pixels.shape[:2]
    return width / height
