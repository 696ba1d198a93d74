"""Signed distance functions of the primitives, each in its local frame (centred, y is the axis).

Each takes the local point q and a vec4 of packed parameters `a` (see `pack_parameters`).
All are exact Euclidean distances (Lipschitz 1), which sphere tracing relies on.
"""
import numpy as np
import taichi as ti

# Lengths and dot products written out: every SDF call site inlines every primitive kind, and
# Taichi builds its generic `norm` / `dot` through several nested library functions each time
# (~1.5 ms of kernel building per use, paid again at every start).


@ti.func
def _dot2(u, v):
    return u.x * v.x + u.y * v.y


@ti.func
def _len2(v):
    return ti.sqrt(v.x * v.x + v.y * v.y)


@ti.func
def _len3(v):
    return ti.sqrt(v.x * v.x + v.y * v.y + v.z * v.z)


@ti.func
def sd_sphere(q, a):
    return _len3(q) - a.x


@ti.func
def sd_box(q, a):
    d = ti.abs(q) - a.xyz
    return _len3(ti.max(d, 0.0)) + ti.min(ti.max(d.x, ti.max(d.y, d.z)), 0.0)


@ti.func
def sd_rounded_box(q, a):
    return sd_box(q, ti.math.vec4(a.xyz, 0.0)) - a.w


@ti.func
def sd_torus(q, a):
    return _len2(ti.math.vec2(_len2(q.xz) - a.x, q.y)) - a.y


@ti.func
def sd_capsule(q, a):
    p = ti.math.vec3(q.x, q.y - ti.min(ti.max(q.y, -a.x), a.x), q.z)
    return _len3(p) - a.y


@ti.func
def sd_cylinder(q, a):
    d = ti.abs(ti.math.vec2(_len2(q.xz), q.y)) - ti.math.vec2(a.y, a.x)
    return ti.min(ti.max(d.x, d.y), 0.0) + _len2(ti.max(d, 0.0))


@ti.func
def sd_cone(q, a):
    """Capped cone: base radius a.y at y = -a.x, apex at y = +a.x (exact distance)."""
    h = a.x
    r = a.y
    w = ti.math.vec2(_len2(q.xz), q.y)
    # Distance to the base disc's rim region, and to the slanted side segment from (r,-h) to (0,h).
    ca = ti.math.vec2(w.x - ti.min(w.x, r if w.y < 0.0 else 0.0), ti.abs(w.y) - h)
    k1 = ti.math.vec2(0.0, h)
    k2 = ti.math.vec2(-r, 2.0 * h)
    cb = w - k1 + k2 * ti.min(ti.max(_dot2(k1 - w, k2) / _dot2(k2, k2), 0.0), 1.0)
    s = -1.0 if (cb.x < 0.0 and ca.y < 0.0) else 1.0
    return s * ti.sqrt(ti.min(_dot2(ca, ca), _dot2(cb, cb)))


@ti.func
def sd_plane(q, a):
    return q.x * a.x + q.y * a.y + q.z * a.z - a.w


PRIMITIVE_FUNCS = {
    "sphere": sd_sphere, "box": sd_box, "rounded_box": sd_rounded_box, "torus": sd_torus,
    "capsule": sd_capsule, "cylinder": sd_cylinder, "cone": sd_cone, "plane": sd_plane,
}


def pack_parameters(node) -> np.ndarray:
    """A node's parameters as the vec4 its distance function reads."""
    p = dict(node.params)
    k = node.kind
    if k == "sphere":
        return np.array([p["radius"], 0, 0, 0], np.float32)
    if k == "box":
        return np.array([*(0.5 * np.asarray(p["size"])), 0], np.float32)
    if k == "rounded_box":
        inner = 0.5 * np.asarray(p["size"]) - p["radius"]
        return np.array([*inner, p["radius"]], np.float32)
    if k == "torus":
        return np.array([p["major_radius"], p["minor_radius"], 0, 0], np.float32)
    if k in ("capsule", "cylinder", "cone"):
        return np.array([0.5 * p["height"], p["radius"], 0, 0], np.float32)
    if k == "plane":
        n = np.asarray(p["normal"], np.float64)
        return np.array([*(n / np.linalg.norm(n)), p["offset"]], np.float32)
    if k == "smooth_union":
        return np.array([p["k"], 0, 0, 0], np.float32)
    if k == "repeat":
        return np.array([*p["period"], 0], np.float32)
    return np.zeros(4, np.float32)
