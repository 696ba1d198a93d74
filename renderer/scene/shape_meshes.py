"""Simple shapes as triangle meshes with texture coordinates: the generators `cylinder`, `disc_fan`
and `cube` (renderer/scene/generators.py), made so that a texture lies on them as on Mitsuba 3's
cylinder, disk and cube.

Each returns (positions (V, 3), indices (T, 3) counter-clockwise seen from the front, unit normals
(V, 3), uvs (V, 2)), float32 / int32, in the shape's own frame.

cylinder   an open tube of `radius` about the y axis, y in [0, height]: `sectors` + 1 columns of two
           vertices (the seam's column twice, so that u runs to 1) at angles phi = 2 pi k / sectors
           from +x towards -z, each with the exact normal (cos phi, 0, -sin phi) and uv (k / sectors,
           y / height). Facing outwards. Its silhouette lies within radius (1 - cos(pi / sectors))
           (about 5 radius / sectors^2) of the round one.
disc_fan   a disc of `radius` in the xz plane facing +y: `sectors` thin triangles from the centre, uv
           = (distance from the centre / radius, phi / 2 pi) with phi as the cylinder's. The rim's
           vertices carry u = 1 and their own phi; each triangle's centre vertex u = 0 and the phi
           of the triangle's middle, so interpolation is off by at most one sector in v and by
           1 - cos(pi / sectors) in u.
cube       the cube [-size / 2, size / 2]^3, 4 vertices and 2 triangles a face, face normals, each
           face's uv spanning [0, 1]^2 in Mitsuba's cube's layout (FACES).
"""
from __future__ import annotations

import numpy as np

# Per face of the cube [-1, 1]^3 as Mitsuba lays its texture out: the corner at uv (0, 0) and the
# edges along u and along v. On every face u x v points inwards.
FACES = (
    ((-1, -1, -1), (0, 0, 2), (2, 0, 0)),  # -y
    ((1, 1, 1), (-2, 0, 0), (0, 0, -2)),  # +y
    ((1, -1, 1), (0, 2, 0), (0, 0, -2)),  # +x
    ((-1, -1, 1), (0, 2, 0), (2, 0, 0)),  # +z
    ((-1, -1, -1), (0, 2, 0), (0, 0, 2)),  # -x
    ((-1, 1, -1), (0, -2, 0), (2, 0, 0)),  # -z
)


def _ring(sectors: int):
    """(k, unit directions at phi_k = 2 pi k / sectors from +x towards -z in the xz plane), k = 0..sectors."""
    k = np.arange(sectors + 1)
    phi = 2.0 * np.pi * k / sectors
    cos, sin = np.cos(phi), np.sin(phi)
    cos[-1], sin[-1] = 1.0, 0.0  # the seam's two columns meet exactly
    return k, np.stack([cos, np.zeros_like(cos), -sin], axis=1)


def _arrays(positions, indices, normals, uvs):
    return (np.asarray(positions, np.float32), np.asarray(indices, np.int32), np.asarray(normals, np.float32),
            np.asarray(uvs, np.float32))


def cylinder(radius: float = 1.0, height: float = 1.0, sectors: int = 256):
    if sectors < 3 or not (radius > 0 and height > 0):
        raise ValueError("a cylinder needs 3 or more sectors and a positive radius and height")
    k, ring = _ring(sectors)
    positions = np.concatenate([radius * ring, radius * ring + [0.0, height, 0.0]])  # bottom row, top row
    u = k / sectors
    uvs = np.concatenate([np.stack([u, np.zeros_like(u)], 1), np.stack([u, np.ones_like(u)], 1)])
    bottom, top = k[:-1], k[:-1] + sectors + 1
    # (B_k, B_k+1, T_k+1) and (B_k, T_k+1, T_k): counter-clockwise seen from outside.
    indices = np.concatenate([np.stack([bottom, bottom + 1, top + 1], 1), np.stack([bottom, top + 1, top], 1)])
    return _arrays(positions, indices, np.concatenate([ring, ring]), uvs)


def disc_fan(radius: float = 1.0, sectors: int = 1024):
    if sectors < 3 or not radius > 0:
        raise ValueError("a disc needs 3 or more sectors and a positive radius")
    k, ring = _ring(sectors)
    rim = radius * ring
    centres = np.zeros((sectors, 3))
    positions = np.concatenate([rim, centres])
    uvs = np.concatenate([np.stack([np.ones(sectors + 1), k / sectors], 1),
                          np.stack([np.zeros(sectors), (k[:-1] + 0.5) / sectors], 1)])
    # (centre_k, rim_k, rim_k+1): (rim_k x rim_k+1) points along +y.
    indices = np.stack([k[:-1] + sectors + 1, k[:-1], k[:-1] + 1], 1)
    normals = np.tile([0.0, 1.0, 0.0], (len(positions), 1))
    return _arrays(positions, indices, normals, uvs)


def cube(size: float = 2.0):
    if not size > 0:
        raise ValueError("a cube needs a positive size")
    positions, normals, uvs, indices = [], [], [], []
    for f, (corner, u, v) in enumerate(FACES):
        corner, u, v = (np.array(x, np.float64) for x in (corner, u, v))
        positions += [corner, corner + u, corner + u + v, corner + v]
        normals += [np.cross(v, u) / 4.0] * 4  # u x v points inwards
        uvs += [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
        base = 4 * f
        indices += [(base, base + 3, base + 2), (base, base + 2, base + 1)]  # counter-clockwise from outside
    return _arrays(0.5 * size * np.array(positions), indices, normals, uvs)
