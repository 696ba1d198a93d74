"""The sRGB transfer curve, decoded exactly: one formula, and its 256-entry table for 8-bit texels;
and encoded (float64, and float32 as the display kernels compute it).

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


def linear_to_srgb(c) -> np.ndarray:
    """The sRGB encoding curve (the inverse of srgb_to_linear), elementwise (float64), for values >= 0."""
    c = np.maximum(np.asarray(c, dtype=np.float64), 0.0)
    return np.where(c <= 0.0031308, c * 12.92, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)


def srgb_oetf_array(linear: np.ndarray) -> np.ndarray:
    """The sRGB encoding curve in float32, as the display kernels compute it (renderer/output/tonemap.py)."""
    linear = np.asarray(linear, dtype=np.float32)
    with np.errstate(invalid="ignore"):
        curve = np.float32(1.055) * np.power(np.maximum(linear, 0.0), np.float32(1.0 / 2.4)) - np.float32(0.055)
    return np.where(linear > np.float32(0.0031308), curve, np.float32(12.92) * linear).astype(np.float32)
