"""Emissive spheres in the packet path: light samples drawn in the cone a sphere subtends (from
outside) or by its area (from inside), and the densities MIS asks back at a BSDF-sampled hit, give
the scalar path's image (the suite's per-pixel and image-mean z-tests, independent seeds)."""
from pathlib import Path

import numpy as np
import pytest
import taichi as ti

from renderer.geometry import emitter_shapes
from renderer.packets import sphere_lights
from renderer.packets.program import PacketProgram
from tests.packets.test_packet_render import CORNELL, render
from tests.stats.image_tests import assert_agree


def cornell_with_spheres(directory: Path, case: str) -> Path:
    """The Cornell box (its ceiling light kept) with, for `outside`, a small bright bulb and a
    larger dim sphere inside the box, both seen from outside; for `inside`, the whole scene,
    camera too, in a large sphere that emits from both faces (every point sees its inner face)."""
    text = Path(CORNELL).read_text()
    if case == "outside":
        spheres = (("bulb", "[6, 5, 4]", "false", 0.08, (0.35, 0.45, 0.3)),
                   ("globe", "[0.6, 0.8, 1.2]", "false", 0.25, (-0.45, -0.1, 0.45)))
    else:
        spheres = (("sky_dome", "[0.4, 0.5, 0.7]", "true", 8.0, (0.0, 0.0, 0.0)),)
    for name, emission, two_sided, radius, at in spheres:
        text += (f'\n[materials.{name}]\ntype = "diffuse"\nbase_color = [0.5, 0.5, 0.5]\nemission = {emission}\n'
                 f'two_sided_emission = {two_sided}\n\n[[objects]]\ntype = "sphere"\nmaterial = "{name}"\n'
                 f'radius = {radius}\ntranslate = {list(at)}\n')
    path = directory / f"cornell_spheres_{case}.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("case", ["outside", "inside"])
def test_packets_sample_emissive_spheres_as_the_scalar_path_does(tmp_path, case):
    scene = cornell_with_spheres(tmp_path, case)
    scalar = render(scene, 0, "mis", seed=71, spp=128)
    packed = render(scene, 8, "mis", seed=72, spp=128)
    assert packed.packet_reason("mis", packed.features(), "independent") is None
    assert isinstance(packed.program("mis", packed.features(), "independent"), PacketProgram)
    assert packed.geometry.data.counts["sphere"] == (2 if case == "outside" else 1)
    image = scalar.image()
    assert image.mean() > 0.05
    assert_agree((packed.image(), packed.film.variance_of_mean_image()),
                 (image, scalar.film.variance_of_mean_image()), ("packets", "scalar"))


W = 8


@ti.kernel
def _sphere_lanes(c: ti.types.ndarray(dtype=ti.math.vec4), p: ti.types.ndarray(dtype=ti.math.vec3),
                  u: ti.types.ndarray(dtype=ti.math.vec2), out: ti.types.ndarray()):
    for packet in range(p.shape[0] // W):
        cx, cy, cz, r = ti.Vector([0.0] * W), ti.Vector([0.0] * W), ti.Vector([0.0] * W), ti.Vector([0.0] * W)
        px, py, pz = ti.Vector([0.0] * W), ti.Vector([0.0] * W), ti.Vector([0.0] * W)
        u1, u2 = ti.Vector([0.0] * W), ti.Vector([0.0] * W)
        for k in ti.static(range(W)):
            i = packet * W + k
            cx[k], cy[k], cz[k], r[k] = c[i].x, c[i].y, c[i].z, c[i].w
            px[k], py[k], pz[k] = p[i].x, p[i].y, p[i].z
            u1[k], u2[k] = u[i].x, u[i].y
        qx, qy, qz, nx, ny, nz, inside, cone = sphere_lights.sample(cx, cy, cz, r, px, py, pz, u1, u2)
        inside_again, per_cone = sphere_lights.pdf_scale(cx, cy, cz, r, px, py, pz)
        for k in ti.static(range(W)):
            i = packet * W + k
            out[i, 0], out[i, 1], out[i, 2] = qx[k], qy[k], qz[k]
            out[i, 3], out[i, 4], out[i, 5] = nx[k], ny[k], nz[k]
            out[i, 6], out[i, 7], out[i, 8] = ti.cast(inside[k], ti.f32), cone[k], per_cone[k]
            out[i, 9] = ti.cast(inside_again[k], ti.f32)
            # the scalar code's density (1 / cone from outside; by area from inside)
            q = ti.math.vec3(qx[k], qy[k], qz[k])
            out[i, 10] = emitter_shapes.sphere_pdf(ti.math.vec3(cx[k], cy[k], cz[k]), r[k], p[i], q,
                                                   ti.math.vec3(nx[k], ny[k], nz[k]))


def test_sphere_lanes_draw_visible_points_uniformly_in_the_cone_and_by_area_inside():
    """Points land on the sphere; from outside they are the nearest point along their direction and
    the direction's 1 - cos(theta) about the axis is u1 (1 - cos theta_max), so u1 uniform gives
    directions uniform in the cone, at the scalar code's density 1 / cone; from inside the normal's
    z is 1 - 2 u1 (uniform by area). Spheres from a sun-like 1e-3 of the distance to touching."""
    rng = np.random.default_rng(3)
    count = 8192
    centre = rng.normal(size=(count, 3)) * 3.0
    radius = np.exp(rng.uniform(np.log(0.01), np.log(2.0), count))
    direction = rng.normal(size=(count, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    # distances from the centre: half outside (1.01 to 1000 radii), a quarter inside, a quarter on it
    scale = np.concatenate([np.exp(rng.uniform(np.log(1.01), np.log(1000.0), count // 2)),
                            rng.uniform(0.0, 0.99, count // 4), np.full(count - count // 2 - count // 4, 1.0)])
    p = centre + direction * (radius * scale)[:, None]
    u = rng.random((count, 2))
    c4 = np.concatenate([centre, radius[:, None]], axis=1).astype(np.float32)
    out = np.zeros((count, 11), np.float32)
    p32, u32 = p.astype(np.float32), u.astype(np.float32)
    _sphere_lanes(c4, p32, u32, out)
    centre, radius, p, u = (c4[:, :3].astype(np.float64), c4[:, 3].astype(np.float64), p32.astype(np.float64),
                            u32.astype(np.float64))  # the numbers the kernel had
    q, n = out[:, 0:3].astype(np.float64), out[:, 3:6].astype(np.float64)
    inside = out[:, 6] == 1
    np.testing.assert_array_equal(inside, out[:, 9] == 1)
    clear = np.abs(scale - 1.0) > 0.005  # (points on the sphere fall either way after rounding to f32)
    np.testing.assert_array_equal(inside[clear], scale[clear] < 1.0)
    # on the sphere, the normal its outward one
    np.testing.assert_allclose(np.linalg.norm(q - centre, axis=1) / radius, 1.0, atol=2e-5 * 1000)
    np.testing.assert_allclose(n, (q - centre) / radius[:, None], atol=5e-3)
    out_ = ~inside
    # from outside: the nearest hit of the ray from p through q is q itself ...
    to_q = q[out_] - p[out_]
    length = np.linalg.norm(to_q, axis=1)
    d = to_q / length[:, None]
    oc = p[out_] - centre[out_]
    b = np.einsum("ij,ij->i", oc, d)
    disc = b * b - (np.einsum("ij,ij->i", oc, oc) - radius[out_] ** 2)
    t_near = -b - np.sqrt(np.maximum(disc, 0.0))
    away = scale[out_] > 1.05  # (at the cone's rim the ray grazes the sphere: t_near is ill-conditioned)
    np.testing.assert_allclose((t_near / length)[away], 1.0, atol=1e-3)
    # ... and its angle off the axis is the warp of u1
    axis = -oc / np.linalg.norm(oc, axis=1, keepdims=True)
    sin2_max = radius[out_] ** 2 / np.einsum("ij,ij->i", oc, oc)
    one_minus_cos_max = sin2_max / (1.0 + np.sqrt(1.0 - sin2_max))
    one_minus_cos = 1.0 - np.clip(np.einsum("ij,ij->i", d, axis), -1, 1)
    np.testing.assert_allclose(one_minus_cos[away] / one_minus_cos_max[away], u[out_, 0][away], atol=0.02)
    # the density: one over the cone's solid angle, the scalar code's
    cone = 2.0 * np.pi * one_minus_cos_max
    np.testing.assert_allclose(out[out_, 7], cone, rtol=1e-3)
    np.testing.assert_allclose(out[out_, 8], 1.0 / cone, rtol=1e-3)
    np.testing.assert_allclose(out[out_, 10], 1.0 / cone, rtol=1e-3)
    # from inside: uniform by area (the normal's z is 1 - 2 u1)
    np.testing.assert_allclose(n[inside, 2], 1.0 - 2.0 * u[inside, 0], atol=1e-4)


@ti.kernel
def _sample_and_ask_back(lights: ti.template(), p: ti.types.ndarray(dtype=ti.math.vec3),
                         u: ti.types.ndarray(dtype=ti.math.vec3), out: ti.types.ndarray()):
    for packet in range(p.shape[0] // W):
        px, py, pz = ti.Vector([0.0] * W), ti.Vector([0.0] * W), ti.Vector([0.0] * W)
        u0, u1, u2 = ti.Vector([0.0] * W), ti.Vector([0.0] * W), ti.Vector([0.0] * W)
        for k in ti.static(range(W)):
            i = packet * W + k
            px[k], py[k], pz[k] = p[i].x, p[i].y, p[i].z
            u0[k], u1[k], u2[k] = u[i].x, u[i].y, u[i].z
        wx, wy, wz, dist, pdf, qx, qy, qz, nx, ny, nz, er, eg, eb, prim = lights.sample(px, py, pz, u0, u1, u2)
        # what path.py asks at a BSDF-sampled hit on that point
        hx, hy, hz = qx - px, qy - py, qz - pz
        dist2 = hx * hx + hy * hy + hz * hz
        cos_l = (hx * nx + hy * ny + hz * nz) / ti.sqrt(ti.max(dist2, 1e-30))
        back = lights.pdf_hit(prim, dist2, cos_l, px, py, pz)
        for k in ti.static(range(W)):
            i = packet * W + k
            out[i, 0], out[i, 1], out[i, 2] = pdf[k], back[k], ti.cast(prim[k], ti.f32)


def test_light_samples_density_is_the_one_mis_asks_back_at_the_point(tmp_path):
    """PacketLights.sample's solid-angle density of each point (a triangle, quad or sphere's) is
    pdf_hit's at that point seen from the same place: MIS weighs both strategies with one density."""
    scene = cornell_with_spheres(tmp_path, "outside")
    r = render(scene, 8, "mis", seed=1, spp=1, size=(8, 8))
    lights = r.program("mis", r.features(), "independent").lights
    rng = np.random.default_rng(5)
    count = 4096
    p = rng.uniform([-0.95, -0.95, -0.95], [0.95, 0.95, 0.95], (count, 3)).astype(np.float32)
    u = rng.random((count, 3)).astype(np.float32)
    out = np.zeros((count, 3), np.float32)
    _sample_and_ask_back(lights, p, u, out)
    prim = out[:, 2].astype(int)
    spheres = (prim >= r.geometry.data.counts["triangle"]) & (prim < r.geometry.data.counts["triangle"] + 2)
    assert spheres.sum() > 100 and (~spheres & (prim >= 0)).sum() > 100  # both kinds were drawn
    drawn = out[:, 0] > 0
    np.testing.assert_allclose(out[drawn, 1], out[drawn, 0], rtol=2e-3)
