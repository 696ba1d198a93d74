"""Lane arithmetic (renderer/packets/lanes.py) against numpy and the scalar code it stands in for."""
import numpy as np
import taichi as ti

from renderer.geometry.intersect import offset_ray_origin
from renderer.packets.lanes import basis, cosine_hemisphere, offset_origin, sincos_2pi

W = 8


@ti.kernel
def _lanes(u: ti.types.ndarray(), v: ti.types.ndarray(), n: ti.types.ndarray(dtype=ti.math.vec3),
           out: ti.types.ndarray(), ref: ti.types.ndarray()):
    for p in range(u.shape[0] // W):
        a = ti.Vector([0.0] * W)
        b = ti.Vector([0.0] * W)
        nx, ny, nz = ti.Vector([0.0] * W), ti.Vector([0.0] * W), ti.Vector([0.0] * W)
        for k in ti.static(range(W)):
            a[k] = u[p * W + k]
            b[k] = v[p * W + k]
            nx[k], ny[k], nz[k] = n[p * W + k].x, n[p * W + k].y, n[p * W + k].z
        s, c = sincos_2pi(a)
        tx, ty, tz, bx, by, bz = basis(nx, ny, nz)
        wx, wy, wz, cos_t = cosine_hemisphere(a, b, nx, ny, nz)
        ox, oy, oz = offset_origin(a * 8.0 - 4.0, b * 0.1, -a, nx, ny, nz)
        for k in ti.static(range(W)):
            i = p * W + k
            out[i, 0], out[i, 1] = s[k], c[k]
            out[i, 2], out[i, 3], out[i, 4] = tx[k], ty[k], tz[k]
            out[i, 5], out[i, 6], out[i, 7] = bx[k], by[k], bz[k]
            out[i, 8], out[i, 9], out[i, 10], out[i, 11] = wx[k], wy[k], wz[k], cos_t[k]
            out[i, 12], out[i, 13], out[i, 14] = ox[k], oy[k], oz[k]
            r = offset_ray_origin(ti.math.vec3(u[i] * 8.0 - 4.0, v[i] * 0.1, -u[i]), n[i])
            ref[i, 0], ref[i, 1], ref[i, 2] = r.x, r.y, r.z


def run(count=4096):
    rng = np.random.default_rng(7)
    u = rng.random(count).astype(np.float32)
    u[:4] = [0.0, 0.25, 0.5, 0.9999999]
    v = rng.random(count).astype(np.float32)
    n = rng.normal(size=(count, 3))
    n[:3] = [[0, 0, 1], [0, 0, -1], [1, 0, 0]]
    n = (n / np.linalg.norm(n, axis=1, keepdims=True)).astype(np.float32)
    out = np.zeros((count, 15), np.float32)
    ref = np.zeros((count, 3), np.float32)
    _lanes(u, v, n, out, ref)
    return u, v, n, out, ref


def test_sine_and_cosine_polynomials_are_within_f32_rounding():
    u, _, _, out, _ = run()
    angle = 2.0 * np.pi * u.astype(np.float64)
    assert np.abs(out[:, 0] - np.sin(angle)).max() < 1e-6
    assert np.abs(out[:, 1] - np.cos(angle)).max() < 1e-6


def test_basis_is_orthonormal_about_every_normal():
    _, _, n, out, _ = run()
    t, b = out[:, 2:5].astype(np.float64), out[:, 5:8].astype(np.float64)
    for x, y in ((t, t), (b, b)):
        np.testing.assert_allclose(np.einsum("ij,ij->i", x, y), 1.0, atol=1e-5)
    for x, y in ((t, b), (t, n), (b, n)):
        np.testing.assert_allclose(np.einsum("ij,ij->i", x, y), 0.0, atol=1e-5)


def test_cosine_directions_are_unit_and_on_the_normals_side():
    _, _, n, out, _ = run()
    w, cos_t = out[:, 8:11].astype(np.float64), out[:, 11]
    np.testing.assert_allclose(np.linalg.norm(w, axis=1), 1.0, atol=1e-5)
    np.testing.assert_allclose(np.einsum("ij,ij->i", w, n), cos_t, atol=1e-5)
    assert (cos_t >= 0).all()


def test_offset_origin_is_the_scalar_offset_bit_for_bit():
    *_, out, ref = run()
    np.testing.assert_array_equal(out[:, 12:15], ref)
