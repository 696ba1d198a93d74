"""The exact conductor Fresnel (microfacet.fresnel_conductor, f32 on the device; its float64 numpy
twin in conductor_ior.py) and the host-side average F_avg that energy compensation uses.

References written here, independently of the renderer: the Fresnel equations in complex float64
arithmetic (numpy complex128), scipy's adaptive quadrature for F_avg, and the closed forms at
normal incidence and for k = 0. Every comparison is deterministic; tolerances are float32 rounding
(stated where they are set).
"""
import numpy as np
import pytest
import taichi as ti
from scipy import integrate

from renderer.materials import microfacet as mf
from renderer.materials.conductor_ior import fresnel_average, fresnel_conductor_np

vec3 = ti.math.vec3
# (eta, k) per channel: k = 0 (a dielectric, eta above and below 1), measured metals' range (k up
# to ~10), large k, eta far below 1 (silver), eta = 1 with small k (near-cancelling terms), and
# the limits eta = k = 0 (a perfect mirror) and n = 1 (no interface).
IORS = [((1.5, 1.33, 2.4), (0.0, 0.0, 0.0)), ((0.5, 0.8, 0.95), (0.0, 0.0, 0.0)),
        ((0.143, 0.375, 1.442), (3.983, 2.386, 1.603)), ((0.155, 0.117, 0.138), (4.828, 3.122, 2.147)),
        ((1.658, 0.880, 0.521), (9.224, 6.270, 4.837)), ((2.0, 20.0, 0.05), (50.0, 80.0, 99.0)),
        ((1.0, 1.0, 1.0), (1e-3, 0.1, 1.0)), ((0.0, 3.0, 1e-4), (1.0, 0.0, 2.0)),
        ((0.0, 1.0, 0.2), (0.0, 0.0, 0.0))]  # the degenerate u = 0 points: eta = k = 0 head-on, n = 1 at grazing
COSINES = np.concatenate([[0.0, 1e-6, 1e-4, 1e-3, 1e-2], np.linspace(0.02, 0.98, 49), [0.999, 0.99999, 1.0]])


def reference(cos_i, eta, k):
    """Unpolarised Fresnel reflectance, complex float64: n = eta + i k relative to the outside,
    cos_t n = sqrt(n^2 - sin^2 i), r_s = (cos_i - n cos_t) / (cos_i + n cos_t),
    r_p = (n cos_i - cos_t) / (n cos_i + cos_t) (with cos_t = that root / n)."""
    c = np.asarray(cos_i, np.float64)[:, None]
    n = np.asarray(eta, np.float64)[None, :] + 1j * np.asarray(k, np.float64)[None, :]
    root = np.sqrt(n * n - (1.0 - c * c) + 0j)
    root = np.where(root.real < 0.0, -root, root)  # the branch with decaying transmitted wave
    with np.errstate(divide="ignore", invalid="ignore"):
        rs = (c - root) / (c + root)
        rp = (n * n * c - root) / (n * n * c + root)
    f = 0.5 * (np.abs(rs) ** 2 + np.abs(rp) ** 2)
    return np.where(np.isfinite(f), f, 1.0)  # 0/0 only at c = 0 with n = 1: the grazing limit 1


def near_branch_point(cos_i, eta, k, width=1e-3):
    """(N, 3): where |(eta + i k)^2 - sin^2| < width (see the test below)."""
    e, kk = np.float32(eta).astype(np.float64), np.float32(k).astype(np.float64)
    c = np.asarray(cos_i, np.float32).astype(np.float64)[:, None]
    return np.hypot(e ** 2 - kk ** 2 - (1.0 - c ** 2), 2.0 * e * kk) < width


@ti.kernel
def _fresnel_kernel(cos_i: ti.types.ndarray(dtype=ti.f32, ndim=1), eta: ti.types.ndarray(dtype=vec3, ndim=1),
                    k: ti.types.ndarray(dtype=vec3, ndim=1), out: ti.types.ndarray(dtype=vec3, ndim=1),
                    dielectric: ti.types.ndarray(dtype=vec3, ndim=1)):
    for i in range(cos_i.shape[0]):
        out[i] = mf.fresnel_conductor(cos_i[i], eta[i], k[i])
        d = vec3(0.0)
        for c in ti.static(range(3)):
            if cos_i[i] > 0.0:
                d[c], _ = mf.fresnel_dielectric(cos_i[i], eta[i][c])
        dielectric[i] = d


def device(cos_i, eta, k):
    """(fresnel_conductor, fresnel_dielectric with eta as a real index) on the device, (N, 3) each."""
    cos_i = np.ascontiguousarray(cos_i, np.float32)
    n = len(cos_i)
    eta = np.ascontiguousarray(np.broadcast_to(np.asarray(eta, np.float32), (n, 3)))
    k = np.ascontiguousarray(np.broadcast_to(np.asarray(k, np.float32), (n, 3)))
    out, dielectric = np.zeros((n, 3), np.float32), np.zeros((n, 3), np.float32)
    _fresnel_kernel(cos_i, eta, k, out, dielectric)
    return out.astype(np.float64), dielectric.astype(np.float64)


@pytest.mark.parametrize("eta, k", IORS)
def test_device_fresnel_matches_complex_reference(eta, k):
    """f32 against complex float64 at the same f32 inputs: within 2e-6 absolute + 2e-5 relative
    (tens of f32 ulps: no cancellation in the formula), at grazing angles and large k too.

    Left out: points next to the square root's branch point, (eta + i k)^2 = sin^2 (the critical
    angle of k = 0, eta < 1), where F has an infinite slope in cos^2: there the f32 rounding of
    cos^2 alone (6e-8) moves F by ~sqrt(6e-8) = 2e-4, in any f32 formula (fresnel_dielectric too)."""
    cos_f32 = COSINES.astype(np.float32)
    got, _ = device(cos_f32, eta, k)
    want = reference(cos_f32, np.float32(eta), np.float32(k))
    branch = near_branch_point(cos_f32, eta, k)
    np.testing.assert_allclose(got[~branch], want[~branch], rtol=2e-5, atol=2e-6)
    np.testing.assert_allclose(fresnel_conductor_np(cos_f32, np.float32(eta), np.float32(k)), want,
                               rtol=1e-12, atol=1e-13)


@pytest.mark.parametrize("eta", [(1.5, 1.33, 2.4), (0.5, 0.8, 0.95), (1.1, 3.9, 1.2)])
def test_zero_extinction_is_the_dielectric_fresnel(eta):
    """k = 0 gives microfacet.fresnel_dielectric's value, total internal reflection included (both
    in f32; points next to a critical angle left out, as above)."""
    cos_i = np.linspace(1e-3, 1.0, 400).astype(np.float32)
    got, dielectric = device(cos_i, eta, (0.0, 0.0, 0.0))
    branch = near_branch_point(cos_i, eta, (0.0, 0.0, 0.0))
    np.testing.assert_allclose(got[~branch], dielectric[~branch], rtol=2e-5, atol=2e-6)


@pytest.mark.parametrize("eta, k", IORS)
def test_normal_incidence_closed_form(eta, k):
    eta32, k32 = np.float32(eta).astype(np.float64), np.float32(k).astype(np.float64)
    want = ((eta32 - 1.0) ** 2 + k32 ** 2) / ((eta32 + 1.0) ** 2 + k32 ** 2)
    got, _ = device(np.array([1.0]), eta, k)
    np.testing.assert_allclose(got[0], want, rtol=2e-6, atol=1e-7)


def test_grazing_incidence_reflects_everything():
    eta, k = np.array([e for e, _ in IORS]), np.array([k for _, k in IORS])
    got, _ = device(np.zeros(len(IORS)), eta, k)
    np.testing.assert_allclose(got, 1.0, atol=1e-6)


@pytest.mark.parametrize("eta, k", IORS)
def test_fresnel_average_matches_adaptive_quadrature(eta, k):
    """The host's F_avg (composite Gauss-Legendre) against scipy's adaptive quad of the complex
    reference, 2 int_0^1 F(mu) mu dmu, per channel, to 1e-6: a hundred times finer than the energy
    compensation needs (its albedo table is good to ~1e-4). The hardest case is eta = 1, k = 1e-3,
    whose F falls from 1 within mu ~ 1e-3 of grazing (2e-7 off); the kink at a critical angle
    (k = 0, eta < 1) is a break point for quad and a panel edge for the renderer's rule."""
    got = fresnel_average(eta, k)
    for c in range(3):
        breaks = [np.sqrt(1.0 - eta[c] ** 2)] if k[c] == 0.0 and eta[c] < 1.0 else None
        want, _ = integrate.quad(lambda mu: 2.0 * mu * reference([mu], [eta[c]], [k[c]])[0, 0], 0.0, 1.0,
                                 points=breaks, epsabs=1e-12, epsrel=1e-12, limit=200)
        assert abs(got[c] - want) < 1e-6, (c, got[c], want)
