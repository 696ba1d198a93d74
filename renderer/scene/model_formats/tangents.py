"""Per-vertex tangents from UV derivatives (for normal maps), MikkTSpace-like."""
from __future__ import annotations

import numpy as np

from renderer.scene.model_formats.normals import normalize_or


def any_perpendicular(n: np.ndarray) -> np.ndarray:
    """A unit vector orthogonal to each (unit) row of n (the branchless frame of Duff et al. 2017)."""
    s = np.where(n[:, 2] >= 0.0, 1.0, -1.0)
    a = -1.0 / (s + n[:, 2])
    b = n[:, 0] * n[:, 1] * a
    return np.stack([1.0 + s * n[:, 0] ** 2 * a, s * b, -s * n[:, 0]], axis=1)


def generate_tangents(positions: np.ndarray, normals: np.ndarray, uvs: np.ndarray,
                      indices: np.ndarray) -> np.ndarray:
    """Per-vertex tangents (V, 4) from UV derivatives, MikkTSpace-like.

    Each triangle's tangent (direction of increasing u) and bitangent (direction of increasing
    "v up", i.e. decreasing stored v, see `mesh_model`) are accumulated at its corners weighted by
    the corner angle, then the tangent is orthogonalised against the vertex normal
    (Gram-Schmidt) and w = sign(dot(cross(N, T), B)). Triangles whose UVs are degenerate
    contribute nothing; a vertex left without a tangent gets an arbitrary unit vector orthogonal
    to its normal (w = 1). Unlike MikkTSpace, vertices are not split where mirrored UV islands
    meet; such vertices get w = +1 or -1 by majority.
    """
    p = np.asarray(positions, dtype=np.float64)
    n = normalize_or(np.asarray(normals, dtype=np.float64), np.array([0.0, 0.0, 1.0]))
    uv = np.asarray(uvs, dtype=np.float64) * np.array([1.0, -1.0])  # to the v-up frame
    tri = np.asarray(indices, dtype=np.int64)
    p0, p1, p2 = p[tri[:, 0]], p[tri[:, 1]], p[tri[:, 2]]
    t0, t1, t2 = uv[tri[:, 0]], uv[tri[:, 1]], uv[tri[:, 2]]
    e1, e2 = p1 - p0, p2 - p0
    d1, d2 = t1 - t0, t2 - t0
    r = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
    sign = np.sign(r)[:, None]
    # Dividing by r only rescales; its sign keeps the directions right. Faces with r == 0 drop out.
    sdir = (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) * sign
    tdir = (e2 * d1[:, 0:1] - e1 * d2[:, 0:1]) * sign
    sdir = normalize_or(sdir, np.zeros(3))
    tdir = normalize_or(tdir, np.zeros(3))

    corners = (p0, p1, p2)
    t_acc = np.zeros_like(p)
    b_acc = np.zeros_like(p)
    for k in range(3):
        a = corners[(k + 1) % 3] - corners[k]
        b = corners[(k + 2) % 3] - corners[k]
        cos = np.einsum("ij,ij->i", normalize_or(a, np.zeros(3)), normalize_or(b, np.zeros(3)))
        angle = np.arccos(np.clip(cos, -1.0, 1.0))[:, None]
        np.add.at(t_acc, tri[:, k], sdir * angle)
        np.add.at(b_acc, tri[:, k], tdir * angle)

    t = t_acc - n * np.einsum("ij,ij->i", n, t_acc)[:, None]
    length = np.linalg.norm(t, axis=1)
    scale = np.maximum(np.abs(t_acc).max(axis=1), 1e-300)
    missing = ~(length > 1e-6 * scale) | ~np.isfinite(length)
    t = np.where(missing[:, None], any_perpendicular(n), t / np.where(missing, 1.0, length)[:, None])
    w = np.where(np.einsum("ij,ij->i", np.cross(n, t), b_acc) < 0.0, -1.0, 1.0)
    return np.concatenate([t, w[:, None]], axis=1).astype(np.float32)
