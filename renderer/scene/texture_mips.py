"""Mip-map levels of a texture image: each level half the one before (rounded down, at least one
texel) down to 1x1, every texel the exact area average of the texels of the level above it covers.

Averages are taken over what lookups read: the decoded, linear values (an sRGB colour image is
averaged in linear light, then encoded again), so a level's texel is the mean of the light the
level above shows, not the mean of its codes. Odd sizes are handled by area weights (a level of
width 2 made from width 5 averages texels 0-2.5 and 2.5-5), so no texel of the image is dropped
and a constant image stays constant at every level. Levels keep their image's storage kind:
8-bit images round to 8 bits again (what GPUs do with their mips), half and float keep theirs.
"""
from __future__ import annotations

import numpy as np

from renderer.scene.mesh_model import TextureImage


def linear_to_srgb(c) -> np.ndarray:
    """The sRGB encoding curve (the inverse of srgb_to_linear), elementwise, for values >= 0."""
    c = np.maximum(np.asarray(c, dtype=np.float64), 0.0)
    return np.where(c <= 0.0031308, c * 12.92, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)


def encoded(linear: np.ndarray, like: TextureImage) -> TextureImage:
    """Linear values stored as `like` stores its texels (storage kind and sRGB flag)."""
    values = np.array(linear, dtype=np.float64)
    if like.srgb:
        values[..., :3] = linear_to_srgb(values[..., :3])
    if like.pixels.dtype == np.uint8:
        pixels = np.rint(np.clip(values, 0.0, 1.0) * 255.0).astype(np.uint8)
    else:
        pixels = values.astype(like.pixels.dtype)
    return TextureImage(pixels, srgb=like.srgb, label=like.label)


def area_halve(values: np.ndarray, axis: int) -> np.ndarray:
    """Resample `values` along `axis` from n texels to max(1, n // 2), each new texel the exact
    average over the span of the old ones it covers (fractional texels weighted by their share)."""
    n = values.shape[axis]
    m = max(1, n // 2)
    if m == n:
        return values
    x = np.moveaxis(values, axis, 0)
    prefix = np.concatenate([np.zeros((1,) + x.shape[1:]), np.cumsum(x, axis=0)])  # prefix[k] = sum x[:k]
    edges = np.arange(m + 1) * (n / m)
    whole = np.minimum(np.floor(edges).astype(np.int64), n - 1)
    frac = (edges - whole).reshape((-1,) + (1,) * (x.ndim - 1))
    integral = prefix[whole] + frac * x[whole]  # the sum of x over [0, edge)
    out = (integral[1:] - integral[:-1]) / (n / m)
    return np.moveaxis(out, 0, axis)


def mip_chain(image: TextureImage) -> list[TextureImage]:
    """Levels 1, 2, ... of `image` (level 0 is the image itself) down to 1x1: empty for a 1x1 image."""
    levels = []
    values = image.linear().astype(np.float64)
    while values.shape[0] > 1 or values.shape[1] > 1:
        values = area_halve(area_halve(values, 0), 1)
        levels.append(encoded(values, image))
    return levels
