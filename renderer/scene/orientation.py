"""Which side of a triangle is its front, when winding and vertex normals disagree.

Glass, media and one-sided emitters read "outside" from a triangle's front, its counter-clockwise
side. A model whose winding runs against its own vertex normals (an exporter that flipped one but
not the other) would render inside out: a glass ball as a ball-shaped bubble in glass. The vertex
normals are what the artist saw shaded, so they decide, as in pbrt: a triangle whose geometric
normal points against the sum of its vertex normals is rewound. Without vertex normals the winding
is all there is (glTF's rule: counter-clockwise is the front), and a closed mesh wound inwards (a
room, a sky dome) stays as it is.
"""
from __future__ import annotations

import numpy as np


def rewind_to_normals(positions: np.ndarray, indices: np.ndarray, normals: np.ndarray | None):
    """(indices, number of triangles rewound): triangles facing against their vertex normals get
    two corners swapped. Indices are returned unchanged (the same array) when none is."""
    tri = np.asarray(indices)
    if normals is None or len(tri) == 0:
        return indices, 0
    p = np.asarray(positions, np.float64)
    n = np.asarray(normals, np.float64)
    face = np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]])
    against = np.einsum("ij,ij->i", face, n[tri].sum(axis=1)) < 0.0
    count = int(np.count_nonzero(against))
    if count == 0:
        return indices, 0
    out = tri.copy()
    out[against] = tri[against][:, [0, 2, 1]]
    return out, count
