"""Emissive spheres as packet light samples: renderer/geometry/emitter_shapes.py's sphere_sample and
sphere_pdf in lane arithmetic. Seen from outside, a direction uniform in the cone the sphere
subtends, to the nearest point along it; from inside (or on) it, a point uniform over its area.

The cone's solid angle is emitter_shapes.cone_solid_angle's (2 pi sin^2 / (1 + cos) of its half
angle), and a direction's 1 - cos theta is drawn in that form too, so small or distant spheres (a
sun) keep their precision in f32.
"""
import taichi as ti

from renderer.geometry.emitter_shapes import SPHERE_INSIDE_SLACK, cone_solid_angle
from renderer.packets.lanes import basis, sincos_2pi


@ti.func
def _cone(d2, r2):
    """(sin^2 of the cone's half angle, its cosine, the cone's solid angle) of a sphere of squared
    radius r2 seen from squared distance d2, and whether that point is inside (i32 lanes; there
    sin^2 is held at 1, the cone unused)."""
    sin2_max = ti.min(r2 / ti.max(d2, 1e-30), 1.0)
    cone, cos_max = cone_solid_angle(sin2_max)
    return sin2_max, cos_max, cone, ti.select(d2 <= r2 * SPHERE_INSIDE_SLACK, 1, 0)


@ti.func
def sample(cx, cy, cz, radius, px, py, pz, u1, u2):
    """Points on the spheres (centre c, radius) for the points p: (q xyz, outward normal xyz,
    inside: i32 lanes, 1 where p is in the sphere and q was drawn by area, and the cone's solid
    angle where it was drawn by direction)."""
    tx, ty, tz = cx - px, cy - py, cz - pz
    d2 = tx * tx + ty * ty + tz * tz
    r2 = radius * radius
    sin2_max, cos_max, cone, inside = _cone(d2, r2)
    s, c = sincos_2pi(u2)
    # from outside: a direction in the cone, then the angle at the centre of the point it meets
    dc = ti.sqrt(d2)
    inv = 1.0 / ti.max(dc, 1e-30)
    ax, ay, az = -tx * inv, -ty * inv, -tz * inv  # from the centre towards p
    one_minus_cos = u1 * sin2_max / (1.0 + cos_max)
    cos_t = 1.0 - one_minus_cos
    sin2_t = ti.max(0.0, one_minus_cos * (2.0 - one_minus_cos))
    ds = dc * cos_t - ti.sqrt(ti.max(0.0, r2 - d2 * sin2_t))
    cos_a = ti.math.clamp((d2 + r2 - ds * ds) / ti.max(2.0 * dc * radius, 1e-30), -1.0, 1.0)
    sin_a = ti.sqrt(ti.max(0.0, 1.0 - cos_a * cos_a))
    bx, by, bz, ex, ey, ez = basis(ax, ay, az)
    nx = sin_a * (c * bx + s * ex) + cos_a * ax
    ny = sin_a * (c * by + s * ey) + cos_a * ay
    nz = sin_a * (c * bz + s * ez) + cos_a * az
    # from inside: uniform over the whole sphere
    z = 1.0 - 2.0 * u1
    rz = ti.sqrt(ti.max(0.0, 1.0 - z * z))
    from_inside = inside == 1
    nx, ny, nz = ti.select(from_inside, rz * c, nx), ti.select(from_inside, rz * s, ny), ti.select(from_inside, z, nz)
    return cx + radius * nx, cy + radius * ny, cz + radius * nz, nx, ny, nz, inside, cone


@ti.func
def pdf_scale(cx, cy, cz, radius, px, py, pz):
    """For the points p: (inside, the factor that turns a sphere's chance of being chosen into the
    solid-angle density of its point, where p is outside: 1 / the cone's solid angle). Inside, the
    density is by area, as a flat emitter's (the caller's)."""
    tx, ty, tz = cx - px, cy - py, cz - pz
    d2 = tx * tx + ty * ty + tz * tz
    sin2_max, cos_max, cone, inside = _cone(d2, radius * radius)
    return inside, 1.0 / ti.max(cone, 1e-30)
