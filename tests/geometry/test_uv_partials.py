"""dp/du and dp/dv (renderer/geometry/uv_partials.py): a triangle's reproduce its edges from their
texture-coordinate differences; a sphere's are the derivatives of its (phi / 2 pi, theta / pi)
parametrisation, against central differences."""
import math

import numpy as np
import taichi as ti

from renderer.geometry.uv_partials import sphere_uv_partials, triangle_uv_partials
from renderer.sampling.warps import orthonormal_basis

vec3 = ti.math.vec3
vec2 = ti.math.vec2


@ti.kernel
def _triangle(v: ti.types.ndarray(), uv: ti.types.ndarray(), out: ti.types.ndarray()):
    for i in range(v.shape[0]):
        p = [vec3(v[i, k, 0], v[i, k, 1], v[i, k, 2]) for k in ti.static(range(3))]
        t = [vec2(uv[i, k, 0], uv[i, k, 1]) for k in ti.static(range(3))]
        n = ti.math.normalize((p[1] - p[0]).cross(p[2] - p[0]))
        du, dv = triangle_uv_partials(p[0], p[1], p[2], t[0], t[1], t[2], n)
        for c in ti.static(range(3)):
            out[i, 0, c] = du[c]
            out[i, 1, c] = dv[c]


@ti.kernel
def _sphere(axes: ti.types.ndarray(), radius: ti.f32, n: ti.types.ndarray(), out: ti.types.ndarray()):
    for i in range(n.shape[0]):
        f = [vec3(axes[k, 0], axes[k, 1], axes[k, 2]) for k in ti.static(range(3))]
        du, dv = sphere_uv_partials(f[0], f[1], f[2], radius, vec3(n[i, 0], n[i, 1], n[i, 2]))
        for c in ti.static(range(3)):
            out[i, 0, c] = du[c]
            out[i, 1, c] = dv[c]


@ti.kernel
def _basis(n: ti.types.ndarray(), out: ti.types.ndarray()):
    for i in range(1):
        t, b = orthonormal_basis(vec3(n[0], n[1], n[2]))
        for c in ti.static(range(3)):
            out[0, c] = t[c]
            out[1, c] = b[c]


def test_triangle_partials_reproduce_its_edges():
    rng = np.random.default_rng(3)
    v = rng.normal(size=(200, 3, 3)).astype(np.float32)
    uv = rng.uniform(-1, 2, (200, 3, 2)).astype(np.float32)
    out = np.zeros((200, 2, 3), np.float32)
    _triangle(v, uv, out)
    for k in (1, 2):
        duv = (uv[:, k] - uv[:, 0]).astype(np.float64)
        edge = out[:, 0] * duv[:, :1] + out[:, 1] * duv[:, 1:]
        np.testing.assert_allclose(edge, v[:, k] - v[:, 0], atol=2e-3 * np.abs(v).max())


def test_degenerate_texture_coordinates_give_a_basis_of_the_plane():
    v = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], np.float32)
    uv = np.full((1, 3, 2), 0.5, np.float32)
    out = np.zeros((1, 2, 3), np.float32)
    _triangle(v, uv, out)
    expected = np.zeros((2, 3), np.float32)
    _basis(np.array([0, 0, 1], np.float32), expected)
    np.testing.assert_allclose(out[0], expected, atol=1e-6)


def _sphere_point(axes, radius, u, v):
    phi, theta = 2 * math.pi * u, math.pi * v
    local = np.array([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)])
    return radius * local @ axes


def test_sphere_partials_are_the_parametrisations_derivatives():
    rng = np.random.default_rng(4)
    axes, _ = np.linalg.qr(rng.normal(size=(3, 3)))  # a rotated (possibly mirrored) frame, rows = axes
    radius = 1.7
    uvs = rng.uniform([0.0, 0.05], [1.0, 0.95], (100, 2))
    normals = np.array([_sphere_point(axes, 1.0, u, v) for u, v in uvs], np.float32)
    out = np.zeros((100, 2, 3), np.float32)
    _sphere(axes.astype(np.float32), radius, normals, out)
    h = 1e-6
    for axis in range(2):
        step = np.eye(2)[axis] * h
        expected = np.array([(_sphere_point(axes, radius, *(uv + step)) - _sphere_point(axes, radius, *(uv - step)))
                             / (2 * h) for uv in uvs])
        np.testing.assert_allclose(out[:, axis], expected, atol=1e-4 * radius * 2 * math.pi)
