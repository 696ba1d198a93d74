"""The BVH builder's input, checked and prepared: primitive boxes and split keys as f32 rows in a
scattered order (see _scattered_order), or a ValueError naming what is wrong with them."""
from __future__ import annotations

import math

import numpy as np

from renderer.geometry.box_rounding import round_out_f32


def _scattered_order(n: int) -> np.ndarray:
    """A fixed permutation of range(n) that sends neighbours far apart: i -> i * s mod n with a
    stride s near n / golden ratio, coprime to n."""
    s = max(1, int(n * 0.6180339887498949))
    while math.gcd(s, n) != 1:
        s += 1
    return (np.arange(n, dtype=np.int64) * s) % n


def prepare_boxes(lo, hi, centroids):
    """Validate the input and return (X, order): X (9, N) f32 holds rows lo xyz, -hi xyz,
    centroid xyz of the primitives order[0], order[1], ... (a scattered order, see
    _scattered_order).

    The upper bounds are stored negated so that every box reduction is a minimum.
    """
    arrays = []
    for name, a in (("lo", lo), ("hi", hi), ("centroids", centroids)):
        a = np.asarray(a)
        if a.ndim != 2 or a.shape[1] != 3:
            raise ValueError(f"{name} must have shape (N, 3), got {a.shape}")
        if not np.issubdtype(a.dtype, np.number) or np.issubdtype(a.dtype, np.complexfloating):
            raise ValueError(f"{name} must be a real numeric array, got {a.dtype}")
        arrays.append(a)
    lo, hi, c = arrays
    if not (lo.shape[0] == hi.shape[0] == c.shape[0]):
        raise ValueError(f"lo, hi and centroids must have the same length, "
                         f"got {lo.shape[0]}, {hi.shape[0]}, {c.shape[0]}")
    n = lo.shape[0]
    if n == 0:
        raise ValueError("cannot build a BVH over zero primitives")
    for name, a in (("lo", lo), ("hi", hi), ("centroids", c)):
        if np.issubdtype(a.dtype, np.floating) and not np.isfinite(a).all():
            raise ValueError(f"{name} contains NaN or infinite values")
    if (lo > hi).any():
        raise ValueError("some primitive boxes have lo > hi")
    lo32, hi32 = round_out_f32(lo, hi)
    with np.errstate(over="ignore"):
        c32 = c.astype(np.float32)
    if not np.isfinite(c32).all() or not np.isfinite(lo32).all() or not np.isfinite(hi32).all():
        raise ValueError("input values overflow float32")
    order = _scattered_order(n)
    x = np.empty((9, n), np.float32)
    x[0:3] = np.take(lo32, order, axis=0).T
    np.negative(np.take(hi32, order, axis=0).T, out=x[3:6])
    x[6:9] = np.take(c32, order, axis=0).T
    return x, order
