"""The partial derivatives of a surface point along its texture coordinates, dp/du and dp/dv, as
Mitsuba 3 computes them: the frame its normal and bump maps work in (Surface.dp_du, dp_dv).

Triangles: constant over the triangle, from its corners' texture coordinates (Mitsuba 3.9's
mesh.cpp); without texture coordinates the parametrisation is barycentric (dp/du = p1 - p0,
dp/dv = p2 - p0), and where the texture coordinates are degenerate an arbitrary basis of the
plane. Spheres: the (phi / 2 pi, theta / pi) parametrisation of renderer/geometry/intersect.py's
sphere_uv. Quads: their two edges, along which uv runs from 0 to 1.
"""
import math

import taichi as ti

from renderer.sampling.warps import orthonormal_basis

vec3 = ti.math.vec3


@ti.func
def triangle_uv_partials(v0, v1, v2, uv0, uv1, uv2, n_geo):
    """(dp/du, dp/dv) of a triangle with corners v0, v1, v2 and their texture coordinates."""
    e1 = v1 - v0
    e2 = v2 - v0
    d0 = uv1 - uv0
    d1 = uv2 - uv0
    det = d0.x * d1.y - d0.y * d1.x
    dp_du, dp_dv = orthonormal_basis(n_geo)
    if det != 0.0:
        inv = 1.0 / det
        dp_du = (d1.y * e1 - d0.y * e2) * inv
        dp_dv = (d0.x * e2 - d1.x * e1) * inv
    return dp_du, dp_dv


@ti.func
def uv_area(uv0, uv1, uv2):
    """Twice the signed area of a triangle in texture coordinates (zero: they do not vary over it)."""
    d0 = uv1 - uv0
    d1 = uv2 - uv0
    return d0.x * d1.y - d0.y * d1.x


@ti.func
def barycentric_partials(v0, v1, v2):
    """(dp/du, dp/dv) of a triangle without texture coordinates (Mitsuba's barycentric ones)."""
    return v1 - v0, v2 - v0


@ti.func
def sphere_uv_partials(axes_x, axes_y, axes_z, radius, n):
    """(dp/du, dp/dv) at outward normal n of a sphere of `radius` whose frame has the world axes
    axes_x, axes_y, axes_z (the frame sphere_uv reads its angles in)."""
    x, y, z = axes_x.dot(n), axes_y.dot(n), axes_z.dot(n)
    dp_du = (2.0 * math.pi * radius) * (axes_y * x - axes_x * y)
    rd = ti.sqrt(x * x + y * y)
    dp_dv = (math.pi * radius) * axes_x  # at the poles, as Mitsuba's sphere
    if rd > 0.0:
        dp_dv = (math.pi * radius) * ((axes_x * x + axes_y * y) * (z / rd) - axes_z * rd)
    return dp_du, dp_dv
