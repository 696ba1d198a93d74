"""Choosing points on emissive shapes for direct lighting, with their solid-angle densities.

Area sampling converts to solid angle with dist^2 / |cos| at the light; a sphere seen from outside
is sampled uniformly inside the cone it subtends (pbrt's method), which never wastes a sample on
its hidden half. Returned densities are 0 where a point cannot be chosen (e.g. the emitter is seen
edge-on), which callers treat as "no sample".
"""
import taichi as ti

from renderer.geometry.interface import EmitterPoint
from renderer.sampling.warps import PI, concentric_disk, orthonormal_basis

vec3 = ti.math.vec3


@ti.func
def area_to_solid_angle(pdf_area, ref, p, n):
    to = p - ref
    dist2 = to.dot(to)
    cos_l = ti.abs(n.dot(to)) / ti.sqrt(ti.max(dist2, 1e-30))
    pdf = 0.0
    if cos_l > 0.0 and dist2 > 0.0:
        pdf = pdf_area * dist2 / cos_l
    return pdf


@ti.func
def triangle_sample(v0, v1, v2, ref, u):
    su = ti.sqrt(u.x)
    b1 = 1.0 - su
    b2 = u.y * su
    p = (1.0 - b1 - b2) * v0 + b1 * v1 + b2 * v2
    c = (v1 - v0).cross(v2 - v0)
    area2 = c.norm()
    n = c / area2 if area2 > 0.0 else vec3(0.0, 1.0, 0.0)
    pdf = 0.0
    if area2 > 0.0:
        pdf = area_to_solid_angle(2.0 / area2, ref, p, n)
    return EmitterPoint(p=p, n=n, uv=ti.math.vec2(b1, b2), pdf=pdf)


@ti.func
def triangle_pdf(v0, v1, v2, ref, p, n):
    area2 = (v1 - v0).cross(v2 - v0).norm()
    pdf = 0.0
    if area2 > 0.0:
        pdf = area_to_solid_angle(2.0 / area2, ref, p, n)
    return pdf


@ti.func
def quad_sample(corner, edge_u, edge_v, ref, u):
    p = corner + u.x * edge_u + u.y * edge_v
    c = edge_u.cross(edge_v)
    area = c.norm()
    n = c / area if area > 0.0 else vec3(0.0, 1.0, 0.0)
    pdf = 0.0
    if area > 0.0:
        pdf = area_to_solid_angle(1.0 / area, ref, p, n)
    return EmitterPoint(p=p, n=n, uv=u, pdf=pdf)


@ti.func
def quad_pdf(edge_u, edge_v, ref, p, n):
    area = edge_u.cross(edge_v).norm()
    pdf = 0.0
    if area > 0.0:
        pdf = area_to_solid_angle(1.0 / area, ref, p, n)
    return pdf


@ti.func
def disc_sample(centre, normal, radius, ref, u):
    t, b = orthonormal_basis(normal)
    d = concentric_disk(u)
    p = centre + radius * (d.x * t + d.y * b)
    pdf = area_to_solid_angle(1.0 / (PI * radius * radius), ref, p, normal)
    return EmitterPoint(p=p, n=normal, uv=ti.math.vec2(d.norm(), 0.0), pdf=pdf)


@ti.func
def disc_pdf(normal, radius, ref, p, n):
    return area_to_solid_angle(1.0 / (PI * radius * radius), ref, p, normal)


# A reference point within this many r^2 (squared distance) of a sphere's centre counts as inside or
# on it: its points are then chosen by area, not by the cone (renderer/packets/sphere_lights.py too)
SPHERE_INSIDE_SLACK = 1.0001


@ti.func
def cone_solid_angle(sin2_max):
    # 2 pi (1 - cos(theta_max)), written as 2 pi sin^2 / (1 + cos) to keep small cones accurate.
    cos_max = ti.sqrt(ti.max(0.0, 1.0 - sin2_max))
    return 2.0 * PI * sin2_max / (1.0 + cos_max), cos_max


@ti.func
def sphere_sample(centre, radius, ref, u):
    to_c = centre - ref
    d2 = to_c.dot(to_c)
    r2 = radius * radius
    result = EmitterPoint(p=centre, n=vec3(0.0, 1.0, 0.0), uv=ti.math.vec2(0.0), pdf=0.0)
    if d2 <= r2 * SPHERE_INSIDE_SLACK:
        # Inside (or on) the sphere: uniform over its area.
        z = 1.0 - 2.0 * u.x
        s = ti.sqrt(ti.max(0.0, 1.0 - z * z))
        phi = 2.0 * PI * u.y
        n = vec3(s * ti.cos(phi), s * ti.sin(phi), z)
        p = centre + radius * n
        result = EmitterPoint(p=p, n=n, uv=u, pdf=area_to_solid_angle(1.0 / (4.0 * PI * r2), ref, p, n))
    else:
        dc = ti.sqrt(d2)
        wc = to_c / dc
        sin2_max = r2 / d2
        cone, cos_max = cone_solid_angle(sin2_max)
        # Uniform in the cone; 1 - cos(theta) = u (1 - cos_max), kept in that form for precision.
        one_minus_cos = u.x * sin2_max / (1.0 + cos_max)
        cos_t = 1.0 - one_minus_cos
        sin2_t = ti.max(0.0, one_minus_cos * (2.0 - one_minus_cos))
        # The point on the sphere along that direction (nearest intersection), via the angle at the centre.
        ds = dc * cos_t - ti.sqrt(ti.max(0.0, r2 - d2 * sin2_t))
        cos_a = ti.math.clamp((d2 + r2 - ds * ds) / (2.0 * dc * radius), -1.0, 1.0)
        sin_a = ti.sqrt(ti.max(0.0, 1.0 - cos_a * cos_a))
        phi = 2.0 * PI * u.y
        t, b = orthonormal_basis(-wc)
        n = ti.cos(phi) * sin_a * t + ti.sin(phi) * sin_a * b + cos_a * (-wc)
        result = EmitterPoint(p=centre + radius * n, n=n, uv=u, pdf=1.0 / cone)
    return result


@ti.func
def sphere_pdf(centre, radius, ref, p, n):
    to_c = centre - ref
    d2 = to_c.dot(to_c)
    r2 = radius * radius
    pdf = 0.0
    if d2 <= r2 * SPHERE_INSIDE_SLACK:
        pdf = area_to_solid_angle(1.0 / (4.0 * PI * r2), ref, p, n)
    else:
        cone, _ = cone_solid_angle(r2 / d2)
        pdf = 1.0 / cone
    return pdf
