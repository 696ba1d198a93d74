"""Sampling points on emissive shapes (renderer/geometry/emitter_shapes.py), seen from a point.

For triangles, quads, discs and spheres (from outside, where the sampler is uniform in the cone
the sphere subtends, and from inside, where it is uniform in area):
- chi-square: the directions from the reference point to 10^6 sampled points against the
  routine's own solid-angle pdf (the `*_pdf` function, at the point a ray in that direction hits),
  on the whole sphere of directions;
- normalisation: E[1 / pdf] over the samples is the solid angle the emitter subtends (its pdf
  integrates to 1 over that solid angle exactly when this holds), z-tested against the exact solid
  angle: Van Oosterom and Strackee (1983) for triangles (and quads as two triangles), a numpy
  quadrature for discs, 2 pi (1 - cos theta_max) for a sphere seen from outside, 4 pi from inside;
- each sample's pdf equals the `*_pdf` function at the sampled point, which lies on the shape.

Expected chi-square counts are adaptive integrals of the pdf over each cell (an emitter's outline
is a jump that no cell edge follows; `chi2_adaptive` in tests/materials/bsdf_kernels.py).
Significance: ALPHA = 0.01 family-wise over the NUM_TESTS tests (chi-square and z) of this file,
Sidak's correction; fixed seeds.
"""
import dataclasses
import math

import numpy as np
import pytest
import taichi as ti
from scipy import stats

from renderer.geometry import emitter_shapes as es
from tests.materials.bsdf_kernels import chi2_adaptive, frame_about
from tests.stats.chi2 import sidak_alpha

vec3 = ti.math.vec3
ALPHA = 0.01
N = 1_000_000


@dataclasses.dataclass(frozen=True)
class Emitter:
    name: str
    kind: str  # triangle (a, b, c = vertices) | quad (a = corner, b, c = edges) | disc (a = centre,
    #            b = normal) | sphere (a = centre)
    a: tuple
    b: tuple = (0.0, 0.0, 0.0)
    c: tuple = (0.0, 0.0, 0.0)
    radius: float = 0.0
    ref: tuple = (0.0, 0.0, 0.0)
    seed: int = 0

    def __str__(self):
        return self.name


EMITTERS = [
    Emitter("triangle-near", "triangle", (1.0, -0.5, -0.3), (0.6, 0.8, 0.2), (1.2, 0.1, 0.9), seed=1),
    Emitter("triangle-far-grazing", "triangle", (-3.0, 0.2, -0.1), (-2.6, -1.0, 0.3), (-3.4, 0.6, 0.35),
            ref=(0.1, 0.0, 0.05), seed=2),
    Emitter("quad-tilted", "quad", (0.3, 0.9, -0.6), (0.9, 0.2, 0.1), (-0.1, 0.3, 1.0), ref=(0.0, -0.2, 0.0), seed=3),
    Emitter("disc-off-axis", "disc", (0.5, -1.2, 0.2), tuple(np.array([0.3, 0.8, -0.2]) / math.sqrt(0.77)),
            radius=0.7, seed=4),
    Emitter("disc-on-axis", "disc", (0.0, 1.5, 0.0), (0.0, -1.0, 0.0), radius=1.0, seed=5),
    Emitter("sphere-outside", "sphere", (2.5, 0.4, -0.3), radius=1.0, seed=6),
    Emitter("sphere-outside-near", "sphere", (0.0, 1.1, 0.2), radius=1.0, ref=(0.0, 0.0, 0.2), seed=7),
    Emitter("sphere-inside", "sphere", (0.2, -0.1, 0.3), radius=1.0, ref=(0.65, 0.2, 0.1), seed=8),
]
# a chi-square test each, and a z-test each except the spheres seen from outside (1 / pdf is constant)
NUM_TESTS = len(EMITTERS) + sum(1 for e in EMITTERS if e.kind != "sphere" or e.ref == (0.65, 0.2, 0.1))


@ti.kernel
def _sample_kernel(kind: ti.template(), a: vec3, b: vec3, c: vec3, radius: ti.f32, ref: vec3,
                   u: ti.types.ndarray(dtype=ti.math.vec2, ndim=1), p: ti.types.ndarray(dtype=vec3, ndim=1),
                   n: ti.types.ndarray(dtype=vec3, ndim=1), pdf: ti.types.ndarray(dtype=ti.f32, ndim=1),
                   again: ti.types.ndarray(dtype=ti.f32, ndim=1)):
    for i in range(u.shape[0]):
        if ti.static(kind == "triangle"):
            e = es.triangle_sample(a, b, c, ref, u[i])
            p[i] = e.p
            n[i] = e.n
            pdf[i] = e.pdf
            again[i] = es.triangle_pdf(a, b, c, ref, e.p, e.n)
        if ti.static(kind == "quad"):
            e = es.quad_sample(a, b, c, ref, u[i])
            p[i] = e.p
            n[i] = e.n
            pdf[i] = e.pdf
            again[i] = es.quad_pdf(b, c, ref, e.p, e.n)
        if ti.static(kind == "disc"):
            e = es.disc_sample(a, b, radius, ref, u[i])
            p[i] = e.p
            n[i] = e.n
            pdf[i] = e.pdf
            again[i] = es.disc_pdf(b, radius, ref, e.p, e.n)
        if ti.static(kind == "sphere"):
            e = es.sphere_sample(a, radius, ref, u[i])
            p[i] = e.p
            n[i] = e.n
            pdf[i] = e.pdf
            again[i] = es.sphere_pdf(a, radius, ref, e.p, e.n)


@ti.kernel
def _pdf_kernel(kind: ti.template(), a: vec3, b: vec3, c: vec3, radius: ti.f32, ref: vec3,
                p: ti.types.ndarray(dtype=vec3, ndim=1), n: ti.types.ndarray(dtype=vec3, ndim=1),
                out: ti.types.ndarray(dtype=ti.f32, ndim=1)):
    for i in range(p.shape[0]):
        if ti.static(kind == "triangle"):
            out[i] = es.triangle_pdf(a, b, c, ref, p[i], n[i])
        if ti.static(kind == "quad"):
            out[i] = es.quad_pdf(b, c, ref, p[i], n[i])
        if ti.static(kind == "disc"):
            out[i] = es.disc_pdf(b, radius, ref, p[i], n[i])
        if ti.static(kind == "sphere"):
            out[i] = es.sphere_pdf(a, radius, ref, p[i], n[i])


def _args(e):
    return (e.kind, vec3(*e.a), vec3(*e.b), vec3(*e.c), float(e.radius), vec3(*e.ref))


def sample(e, n):
    u = np.random.default_rng(e.seed).random((n, 2), dtype=np.float32)
    p, nrm = np.zeros((n, 3), np.float32), np.zeros((n, 3), np.float32)
    pdf, again = np.zeros(n, np.float32), np.zeros(n, np.float32)
    _sample_kernel(*_args(e), u, p, nrm, pdf, again)
    return p, nrm, pdf, again


# --- ray casts in numpy (float64): the point a direction from the reference point reaches -------------


def _plane_hit(ref, d, origin, normal):
    with np.errstate(divide="ignore", invalid="ignore"):
        t = ((origin - ref) @ normal) / (d @ normal)
    ok = np.isfinite(t) & (t > 0.0)
    return np.where(ok, t, 0.0), ok


def cast(e, d):
    """(hit (M,), p (M, 3), n (M, 3)) for unit directions d from e.ref."""
    ref = np.asarray(e.ref, np.float64)
    a, b, c = (np.asarray(v, np.float64) for v in (e.a, e.b, e.c))
    if e.kind in ("triangle", "quad"):
        eu, ev = (b - a, c - a) if e.kind == "triangle" else (b, c)
        normal = np.cross(eu, ev)
        normal /= np.linalg.norm(normal)
        t, ok = _plane_hit(ref, d, a, normal)
        p = ref + t[:, None] * d
        # coordinates of p - a in the (eu, ev) basis of the plane (dual basis)
        g = np.array([[eu @ eu, eu @ ev], [eu @ ev, ev @ ev]])
        rhs = np.stack([(p - a) @ eu, (p - a) @ ev], axis=1)
        uv = np.linalg.solve(g, rhs.T).T
        upper = uv.sum(axis=1) <= 1.0 if e.kind == "triangle" else (uv <= 1.0).all(axis=1)
        inside = (uv >= 0.0).all(axis=1) & upper
        return ok & inside, p, np.broadcast_to(normal, p.shape)
    if e.kind == "disc":
        t, ok = _plane_hit(ref, d, a, b)
        p = ref + t[:, None] * d
        return ok & (np.linalg.norm(p - a, axis=1) <= e.radius), p, np.broadcast_to(b, p.shape)
    oc = ref - a
    half_b = d @ oc
    disc = half_b ** 2 - (oc @ oc - e.radius ** 2)
    root = np.sqrt(np.maximum(disc, 0.0))
    near, far = -half_b - root, -half_b + root
    t = np.where(near > 0.0, near, far)  # outside: the nearest hit; inside: the only one ahead
    hit = (disc >= 0.0) & (t > 0.0)
    p = ref + t[:, None] * d
    return hit, p, (p - a) / e.radius


def pdf_callable(e):
    def pdf(d):
        d = np.asarray(d, np.float64)
        hit, p, n = cast(e, d)
        out = np.zeros(len(d))
        if hit.any():
            values = np.zeros(int(hit.sum()), np.float32)
            _pdf_kernel(*_args(e), np.ascontiguousarray(p[hit], np.float32), np.ascontiguousarray(n[hit], np.float32),
                        values)
            out[hit] = values
        return out

    return pdf


# --- exact solid angles --------------------------------------------------------------------------------


def triangle_solid_angle(ref, v0, v1, v2):
    """Van Oosterom and Strackee 1983: tan(omega / 2) = |a . (b x c)| / (abc + (a.b) c + (a.c) b + (b.c) a)."""
    a, b, c = (np.asarray(v, np.float64) - np.asarray(ref, np.float64) for v in (v0, v1, v2))
    la, lb, lc = (np.linalg.norm(v) for v in (a, b, c))
    numerator = abs(a @ np.cross(b, c))
    denominator = la * lb * lc + (a @ b) * lc + (a @ c) * lb + (b @ c) * la
    return 2.0 * math.atan2(numerator, denominator)


def disc_solid_angle(ref, centre, normal, radius, n_r=256, n_phi=512):
    """The integral of |cos| / dist^2 over the disc (Gauss-Legendre in r, periodic rule in phi)."""
    ref, centre, normal = (np.asarray(v, np.float64) for v in (ref, centre, normal))
    t = frame_about(normal)
    x, w = np.polynomial.legendre.leggauss(n_r)
    r = 0.5 * radius * (x + 1.0)
    wr = 0.5 * radius * w * r
    phi = (np.arange(n_phi) + 0.5) * (2.0 * np.pi / n_phi)
    p = centre + r[:, None, None] * (np.cos(phi)[None, :, None] * t[0] + np.sin(phi)[None, :, None] * t[1])
    to = p - ref
    dist2 = np.sum(to * to, axis=-1)
    integrand = np.abs(to @ normal) / dist2 ** 1.5
    return float(np.sum(wr[:, None] * integrand) * (2.0 * np.pi / n_phi))


def solid_angle(e):
    ref = np.asarray(e.ref, np.float64)
    if e.kind == "triangle":
        return triangle_solid_angle(ref, e.a, e.b, e.c)
    if e.kind == "quad":
        a, eu, ev = (np.asarray(v, np.float64) for v in (e.a, e.b, e.c))
        return triangle_solid_angle(ref, a, a + eu, a + eu + ev) + triangle_solid_angle(ref, a, a + eu + ev, a + ev)
    if e.kind == "disc":
        return disc_solid_angle(ref, e.a, e.b, e.radius)
    d = np.linalg.norm(np.asarray(e.a) - ref)
    if d <= e.radius:
        return 4.0 * math.pi
    return 2.0 * math.pi * (1.0 - math.sqrt(1.0 - (e.radius / d) ** 2))


# --- tests -----------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def samples(taichi_runtime):
    return {e.name: sample(e, N) for e in EMITTERS}


def test_exact_solid_angles():
    """The references themselves: a disc seen on its axis, 2 pi (1 - d / sqrt(d^2 + R^2)); the
    triangle formula summed over an octant's triangle (pi / 2) and over a cube face seen from the
    centre (4 pi / 6, as two triangles)."""
    assert disc_solid_angle((0, 0, 0), (0, 1.5, 0), (0, -1, 0), 1.0) == pytest.approx(
        2 * math.pi * (1 - 1.5 / math.sqrt(1.5 ** 2 + 1.0)), rel=1e-12)
    assert triangle_solid_angle((0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)) == pytest.approx(math.pi / 2, rel=1e-12)
    face = Emitter("face", "quad", (-1.0, -1.0, 1.0), (2.0, 0.0, 0.0), (0.0, 2.0, 0.0))
    assert solid_angle(face) == pytest.approx(4 * math.pi / 6, rel=1e-12)


@pytest.mark.parametrize("emitter", EMITTERS, ids=str)
def test_points_lie_on_the_emitter_and_pdfs_agree(emitter, samples):
    p, n, pdf, again = samples[emitter.name]
    p = p.astype(np.float64)
    assert np.isfinite(pdf).all() and (pdf > 0.0).all()
    np.testing.assert_allclose(again, pdf, rtol=1e-5)
    if emitter.kind == "sphere":
        np.testing.assert_allclose(np.linalg.norm(p - emitter.a, axis=1), emitter.radius, rtol=1e-5)
        to_ref = np.asarray(emitter.ref) - p
        outside = np.linalg.norm(np.asarray(emitter.a) - emitter.ref) > emitter.radius
        if outside:  # only the visible cap: the point faces the reference point
            assert (np.sum(to_ref * n, axis=1) >= -1e-5).all()
    else:
        hit, _, _ = cast(emitter, (p - emitter.ref) / np.linalg.norm(p - emitter.ref, axis=1, keepdims=True))
        assert hit.mean() > 0.9999  # on the shape (up to float32 rounding at its outline)


@pytest.mark.parametrize("emitter", EMITTERS, ids=str)
def test_chi2_of_directions(emitter, samples, tmp_path):
    p, _, pdf, _ = samples[emitter.name]
    d = p.astype(np.float64) - emitter.ref
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    frame, breaks = None, None
    if emitter.kind == "sphere":  # about the direction to the centre: the cone's edge is a circle of constant theta
        frame = frame_about(np.asarray(emitter.a) - emitter.ref)
        if solid_angle(emitter) < 4.0 * math.pi:
            breaks = [math.acos(1.0 - solid_angle(emitter) / (2.0 * math.pi))]
    # lossless: the harness also checks that the pdf integrates to 1 (to its quadrature tolerance)
    result = chi2_adaptive(d, pdf_callable(emitter), valid=pdf > 0.0, frame=frame, theta_breaks=breaks,
                           domain="sphere", alpha=ALPHA, num_tests=NUM_TESTS)
    if not result.passed:
        result.write_png(tmp_path / f"{emitter.name}.png")
    assert result.passed, f"{emitter.name}\n{result.report}"


@pytest.mark.parametrize("emitter", EMITTERS, ids=str)
def test_inverse_pdf_averages_to_the_solid_angle(emitter, samples, record_property):
    _, _, pdf, _ = samples[emitter.name]
    inverse = 1.0 / pdf.astype(np.float64)
    exact = solid_angle(emitter)
    se = inverse.std(ddof=1) / math.sqrt(len(inverse))
    record_property("solid_angle", f"{inverse.mean():.6f} +- {se:.6f} vs {exact:.6f}")
    if emitter.kind == "sphere" and exact < 4.0 * math.pi:
        # uniform in the cone: 1 / pdf is the cone's solid angle itself (float32)
        np.testing.assert_allclose(inverse, exact, rtol=1e-5)
        return
    z = (inverse.mean() - exact) / se
    p_value = 2.0 * stats.norm.sf(abs(z))
    assert p_value >= sidak_alpha(ALPHA, NUM_TESTS), (
        f"{emitter.name}: E[1/pdf] = {inverse.mean():.6f} +- {se:.6f}, solid angle {exact:.6f} (z = {z:.2f})")
