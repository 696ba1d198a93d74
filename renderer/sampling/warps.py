"""Warps from uniform samples in [0,1)^2 to disks, hemispheres and frames."""
import taichi as ti

PI = 3.14159265358979323846
INV_PI = 1.0 / PI


@ti.func
def concentric_disk(u):
    """Shirley-Chiu concentric map: low distortion, so stratified samples stay stratified."""
    a = 2.0 * u - 1.0
    r = 0.0
    phi = 0.0
    if a.x != 0.0 or a.y != 0.0:
        if ti.abs(a.x) > ti.abs(a.y):
            r = a.x
            phi = (PI / 4.0) * (a.y / a.x)
        else:
            r = a.y
            phi = (PI / 2.0) - (PI / 4.0) * (a.x / a.y)
    return ti.math.vec2(r * ti.cos(phi), r * ti.sin(phi))


@ti.func
def cosine_hemisphere(u):
    """Malley's method; z is the pole. pdf = cos(theta) / pi."""
    d = concentric_disk(u)
    z = ti.sqrt(ti.max(0.0, 1.0 - d.dot(d)))
    return ti.math.vec3(d.x, d.y, z)


@ti.func
def orthonormal_basis(n):
    """Tangents t, b with (t, b, n) right-handed; Duff et al. 2017, branch-free and stable at n.z = -1."""
    sign = 1.0 if n.z >= 0.0 else -1.0
    a = -1.0 / (sign + n.z)
    b = n.x * n.y * a
    t = ti.math.vec3(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x)
    bt = ti.math.vec3(b, sign + n.y * n.y * a, -n.y)
    return t, bt


@ti.func
def to_local(v, t, b, n):
    return ti.math.vec3(v.dot(t), v.dot(b), v.dot(n))


@ti.func
def to_world(v, t, b, n):
    return v.x * t + v.y * b + v.z * n
