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
from renderer.scene.srgb import linear_to_srgb, srgb_oetf_array, srgb_to_linear


# Linear values at the boundaries between consecutive 8-bit sRGB codes: code k encodes the linear
# values in [_SRGB8_EDGES[k - 1], _SRGB8_EDGES[k]), i.e. round(255 * encode(value)).
_SRGB8_EDGES = srgb_to_linear((np.arange(255) + 0.5) / 255.0).astype(np.float32)
# Level 0 is decoded and halved along its width this many rows at a time (a 4096x4096 8-bit image
# would take 256 MiB as float32 at once).
STRIP_ROWS = 256


def srgb8_codes(linear: np.ndarray) -> np.ndarray:
    """The 8-bit sRGB code of each linear value: the curve in float32, then corrected by one where
    that rounding put a value on the wrong side of a code's edge (_SRGB8_EDGES decides)."""
    c = np.clip(np.asarray(linear, np.float32), 0.0, 1.0)
    k = np.clip(np.rint(srgb_oetf_array(c) * np.float32(255.0)), 0, 255).astype(np.int32)
    edges = np.append(_SRGB8_EDGES, np.float32(np.inf))  # edges[k]: where code k ends
    k += c >= edges[k]
    k -= (k > 0) & (c < edges[np.maximum(k - 1, 0)])
    return k.astype(np.uint8)


def encoded(linear: np.ndarray, like: TextureImage) -> TextureImage:
    """Linear values stored as `like` stores its texels (storage kind and sRGB flag)."""
    if like.pixels.dtype == np.uint8:
        pixels = np.rint(np.clip(linear, 0.0, 1.0) * 255.0).astype(np.uint8)
        if like.srgb:
            pixels[..., :3] = srgb8_codes(linear[..., :3])
    else:
        values = np.array(linear, dtype=np.float64)
        if like.srgb:
            values[..., :3] = linear_to_srgb(values[..., :3])
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
    if n % 2 == 0:  # pairs
        out = 0.5 * (x[0::2] + x[1::2])
        return np.moveaxis(out, 0, axis)
    prefix = np.concatenate([np.zeros((1,) + x.shape[1:]), np.cumsum(x, axis=0, dtype=np.float64)])
    edges = np.arange(m + 1) * (n / m)
    whole = np.minimum(np.floor(edges).astype(np.int64), n - 1)
    frac = (edges - whole).reshape((-1,) + (1,) * (x.ndim - 1))
    integral = prefix[whole] + frac * x[whole]  # the sum of x over [0, edge)
    out = ((integral[1:] - integral[:-1]) / (n / m)).astype(values.dtype)
    return np.moveaxis(out, 0, axis)


def _first_level(image: TextureImage) -> np.ndarray:
    """Level 1's linear values (float32), level 0 decoded a strip of rows at a time."""
    pixels = image.pixels
    halved = np.empty((pixels.shape[0], max(1, pixels.shape[1] // 2), 4), np.float32)  # along the width
    for y in range(0, pixels.shape[0], STRIP_ROWS):
        halved[y:y + STRIP_ROWS] = area_halve(TextureImage(pixels[y:y + STRIP_ROWS], image.srgb).linear(), 1)
    return area_halve(halved, 0)


def mip_chain(image: TextureImage) -> list[TextureImage]:
    """Levels 1, 2, ... of `image` (level 0 is the image itself) down to 1x1: empty for a 1x1 image."""
    levels = []
    values = None
    while values is None or values.shape[0] > 1 or values.shape[1] > 1:
        if values is None:
            if image.shape == (1, 1):
                break
            values = _first_level(image)
        else:
            values = area_halve(area_halve(values, 0), 1)
        levels.append(encoded(values, image))
    return levels
