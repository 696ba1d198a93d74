"""The sRGB transfer curve, decoded exactly: one formula, and its 256-entry table for 8-bit texels.

Texture lookups (the numpy reference in `renderer.scene.textures` and the device sampler) decode
8-bit colour texels through `SRGB8_TO_LINEAR`, so both read the same float32 for every byte.
"""
from __future__ import annotations

import numpy as np


def srgb_to_linear(c) -> np.ndarray:
    """The exact sRGB decoding curve, elementwise (float64), for values in [0, 1]."""
    c = np.asarray(c, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((np.maximum(c, 0.04045) + 0.055) / 1.055) ** 2.4)


# Linear value of each 8-bit sRGB code k (k / 255 decoded), float32.
SRGB8_TO_LINEAR = srgb_to_linear(np.arange(256) / 255.0).astype(np.float32)
