"""Signed distance functions of the primitives, each in its local frame (centred, y is the axis).

Each takes the local point q and a vec4 of packed parameters `a` (see `pack_parameters`).
All are exact Euclidean distances (Lipschitz 1), which sphere tracing relies on.
"""
import numpy as np
import taichi as ti


@ti.func
def sd_sphere(q, a):
    return q.norm() - a.x


@ti.func
def sd_box(q, a):
    d = ti.abs(q) - a.xyz
    return ti.max(d, 0.0).norm() + ti.min(ti.max(d.x, ti.max(d.y, d.z)), 0.0)


@ti.func
def sd_rounded_box(q, a):
    return sd_box(q, ti.math.vec4(a.xyz, 0.0)) - a.w


@ti.func
def sd_torus(q, a):
    return ti.math.vec2(ti.math.vec2(q.x, q.z).norm() - a.x, q.y).norm() - a.y


@ti.func
def sd_capsule(q, a):
    p = ti.math.vec3(q.x, q.y - ti.math.clamp(q.y, -a.x, a.x), q.z)
    return p.norm() - a.y


@ti.func
def sd_cylinder(q, a):
    d = ti.abs(ti.math.vec2(ti.math.vec2(q.x, q.z).norm(), q.y)) - ti.math.vec2(a.y, a.x)
    return ti.min(ti.max(d.x, d.y), 0.0) + ti.max(d, 0.0).norm()


@ti.func
def sd_cone(q, a):
    """Capped cone: base radius a.y at y = -a.x, apex at y = +a.x (exact distance)."""
    h = a.x
    r = a.y
    w = ti.math.vec2(ti.math.vec2(q.x, q.z).norm(), q.y)
    # Distance to the base disc's rim region, and to the slanted side segment from (r,-h) to (0,h).
    ca = ti.math.vec2(w.x - ti.min(w.x, r if w.y < 0.0 else 0.0), ti.abs(w.y) - h)
    k1 = ti.math.vec2(0.0, h)
    k2 = ti.math.vec2(-r, 2.0 * h)
    cb = w - k1 + k2 * ti.math.clamp((k1 - w).dot(k2) / k2.dot(k2), 0.0, 1.0)
    s = -1.0 if (cb.x < 0.0 and ca.y < 0.0) else 1.0
    return s * ti.sqrt(ti.min(ca.dot(ca), cb.dot(cb)))


@ti.func
def sd_plane(q, a):
    return q.dot(a.xyz) - a.w


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
