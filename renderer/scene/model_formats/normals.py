"""Unit vectors from rows that may be zero, and vertex normals where a file has none or bad ones."""
from __future__ import annotations

import numpy as np


def normalize_or(v: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """Rows of v scaled to unit length; rows that are zero or non-finite become `fallback`."""
    v = np.asarray(v, dtype=np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        length = np.sqrt(np.einsum("ij,ij->i", v, v))
    ok = np.isfinite(length) & (length > 0.0)
    out = v / np.where(ok, length, 1.0)[:, None]
    if not ok.all():
        out[~ok] = fallback
    return out


def vertex_normals(positions: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """Area-weighted average of adjacent face normals, unit length ((0, 0, 1) where undefined)."""
    p = np.asarray(positions, dtype=np.float64)
    tri = np.asarray(indices, dtype=np.int64)
    face = np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]])  # length = 2 * area
    acc = np.zeros_like(p)
    for k in range(3):
        np.add.at(acc, tri[:, k], face)
    return normalize_or(acc, np.array([0.0, 0.0, 1.0]))
