"""The Henyey-Greenstein phase function (renderer/media/phase.py).

Samples come from the Taichi sampler through a small kernel; the pdf the chi-square test
integrates is the Taichi evaluation. Two goodness-of-fit tests per g: the binned sphere of
tests/stats/chi2.py (pole = the forward direction -wo, which also tests that the azimuth is
uniform), and a finer one-dimensional test of the scattering cosine whose bins shrink
geometrically toward the peak, where the sphere's cells are too coarse for g = 0.9 and 0.99.
ALPHA = 0.01 family-wise over the NUM_TESTS goodness-of-fit tests, Sidak-corrected.
"""
import math

import numpy as np
import pytest
import taichi as ti
from scipy import stats

from renderer.media import phase
from tests.stats.chi2 import chi2_test, sidak_alpha

ALPHA = 0.01
N = 1_000_000
G_VALUES = (-0.9, -0.3, 0.0, 0.3, 0.9, 0.99)
NUM_TESTS = 2 * len(G_VALUES)
vec2 = ti.math.vec2
vec3 = ti.math.vec3


def wo_for(g) -> np.ndarray:
    """A different unit wo per case; g = 0 uses +z, whose forward direction -z is the special
    branch of the orthonormal basis (Duff et al.)."""
    if g == 0.0:
        return np.array([0.0, 0.0, 1.0])
    v = np.array([0.3 + g, -0.5, 0.8 - 0.2 * g])
    return v / np.linalg.norm(v)


@ti.kernel
def _sample_kernel(g: ti.f32, wo: vec3, u: ti.types.ndarray(dtype=vec2, ndim=1),
                   wi: ti.types.ndarray(dtype=vec3, ndim=1), pdf: ti.types.ndarray(dtype=ti.f32, ndim=1),
                   by_cos: ti.types.ndarray(dtype=ti.f32, ndim=1), by_dirs: ti.types.ndarray(dtype=ti.f32, ndim=1)):
    for i in range(u.shape[0]):
        d, p = phase.hg_sample(g, wo, u[i])
        wi[i] = d
        pdf[i] = p
        by_cos[i] = phase.hg_eval(g, wo.dot(d))
        by_dirs[i] = phase.hg_phase(g, wo, d)


@ti.kernel
def _phase_kernel(g: ti.f32, wo: vec3, wi: ti.types.ndarray(dtype=vec3, ndim=1),
                  out: ti.types.ndarray(dtype=ti.f32, ndim=1)):
    for i in range(wi.shape[0]):
        out[i] = phase.hg_phase(g, wo, wi[i])


@ti.kernel
def _eval_kernel(g: ti.f32, cos_theta: ti.types.ndarray(dtype=ti.f32, ndim=1),
                 out: ti.types.ndarray(dtype=ti.f32, ndim=1)):
    for i in range(cos_theta.shape[0]):
        out[i] = phase.hg_eval(g, cos_theta[i])


def sample(g, wo, u):
    n = len(u)
    wi = np.zeros((n, 3), np.float32)
    pdf, by_cos, by_dirs = (np.zeros(n, np.float32) for _ in range(3))
    _sample_kernel(g, vec3(*wo), np.ascontiguousarray(u, np.float32), wi, pdf, by_cos, by_dirs)
    return wi, pdf, by_cos, by_dirs


def phase_at(g, wo, wi):
    wi = np.ascontiguousarray(wi, np.float32).reshape(-1, 3)
    out = np.zeros(len(wi), np.float32)
    _phase_kernel(g, vec3(*wo), wi, out)
    return out.astype(np.float64)


def eval_at(g, cos_theta):
    c = np.ascontiguousarray(cos_theta, np.float32)
    out = np.zeros(len(c), np.float32)
    _eval_kernel(g, c, out)
    return out.astype(np.float64)


def frame_about(pole):
    z = pole / np.linalg.norm(pole)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z])


def angle_between(a, b):
    """Angles (radians) between rows of a and the vector b, by atan2: exact to the inputs' rounding
    at any angle (acos of a dot product loses everything near 0 and pi), and scale-invariant."""
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), a @ b)


def exact_hg(g, wo, wi):
    """float64 HG at f32 directions, with 1 + cos(wo, wi) = 2 sin^2(angle(wi, -wo) / 2)."""
    wo32 = np.float32(wo).astype(np.float64)  # as the kernel saw it
    one_plus = 2.0 * np.sin(0.5 * angle_between(wi.astype(np.float64), -wo32)) ** 2
    return (1.0 - g * g) / (4.0 * math.pi * (1.0 + g * g - 2.0 * g + 2.0 * g * one_plus) ** 1.5)


def peak_edges(lo=1e-7, hi=2.0, count=48):
    """Bin edges in w = 1 - mu (mu the cosine from the peak): 0, then geometric up to 2."""
    return np.concatenate([[0.0], np.geomspace(lo, hi, count)])


def integrate_bins(f, edges, order=8):
    """Integral of f over each interval of edges, Gauss-Legendre per interval."""
    x, w = np.polynomial.legendre.leggauss(order)
    half = 0.5 * np.diff(edges)
    nodes = edges[:-1, None] + half[:, None] * (x[None, :] + 1.0)
    return (f(nodes.ravel()).reshape(nodes.shape) * w[None, :]).sum(axis=1) * half


@pytest.mark.parametrize("g", G_VALUES)
def test_chi2_sphere(g, tmp_path):
    wo = wo_for(g)
    u = np.random.default_rng(int(1000 * (g + 2))).random((N, 2), dtype=np.float32)
    wi, _, _, _ = sample(g, wo, u)
    # Break lines near the peak, where the pdf changes on a scale of (1 - |g|)^2 in cos theta.
    breaks = np.geomspace(1e-4, 0.5, 40)
    result = chi2_test(wi, lambda d: phase_at(g, wo, d), frame=frame_about(-wo), alpha=ALPHA,
                       num_tests=NUM_TESTS, theta_breaks=breaks, integral_tolerance=2e-4)
    if not result.passed:
        result.write_png(tmp_path / f"hg_{g}.png")
    assert result.passed, f"g = {g}\n{result.report}"


@pytest.mark.parametrize("g", G_VALUES)
def test_chi2_scattering_cosine(g):
    """The distribution of w = 1 - dot(-wo, wi) (0 at the forward peak for g > 0), in bins that
    shrink toward the peak; the expected count of a bin is 2 pi times the integral of hg_eval."""
    wo = wo_for(g)
    u = np.random.default_rng(int(1000 * (g + 5))).random((N, 2), dtype=np.float32)
    wi, _, _, _ = sample(g, wo, u)
    peak_forward = g >= 0.0
    # w = 1 - cos(angle to the peak) = 2 sin^2(angle / 2), the angle by atan2 of the cross and dot
    # products: exact to the f32 rounding of wi (a plain 1 - dot would cancel to 1e-7 absolute).
    peak = np.float32(-wo if peak_forward else wo).astype(np.float64)  # as the kernel saw wo
    w = 2.0 * np.sin(0.5 * angle_between(wi.astype(np.float64), peak)) ** 2
    edges = peak_edges()
    observed = np.histogram(w, edges)[0].astype(np.float64)
    # mu measured from the peak; hg_eval takes cos(wo, wi) = -mu for the forward peak, +mu otherwise.
    sign = -1.0 if peak_forward else 1.0
    expected = 2.0 * math.pi * integrate_bins(lambda x: eval_at(g, sign * (1.0 - x)), edges) * N
    assert abs(expected.sum() / N - 1.0) < 2e-4
    # Pool the sparse bins at the peak end (tiny w) into their neighbour until each expects >= 5.
    obs, exp = [], []
    o_acc = e_acc = 0.0
    for o, e in zip(observed, expected):
        o_acc, e_acc = o_acc + o, e_acc + e
        if e_acc >= 5.0:
            obs.append(o_acc)
            exp.append(e_acc)
            o_acc = e_acc = 0.0
    obs[-1] += o_acc
    exp[-1] += e_acc
    obs, exp = np.array(obs), np.array(exp)
    exp *= obs.sum() / exp.sum()
    p_value = stats.chisquare(obs, exp).pvalue
    assert p_value >= sidak_alpha(ALPHA, NUM_TESTS), f"g = {g}: p = {p_value:.3g} over {len(obs)} bins"


@pytest.mark.parametrize("g", G_VALUES + (0.999, -0.999, 1e-3, -1e-5))
def test_pdf_equals_eval_and_reference(g):
    wo = wo_for(g)
    u = np.random.default_rng(7).random((20_000, 2), dtype=np.float32)
    wi, pdf, by_cos, by_dirs = sample(g, wo, u)
    assert np.all(np.isfinite(wi)) and np.all(np.isfinite(pdf)) and np.all(pdf > 0.0)
    np.testing.assert_allclose(np.linalg.norm(wi.astype(np.float64), axis=1), 1.0, atol=2e-6)
    # The sample's pdf, the direction-based evaluation and the float64 formula agree.
    wi64 = wi.astype(np.float64)
    exact = exact_hg(float(np.float32(g)), wo, wi)
    np.testing.assert_allclose(by_dirs, exact, rtol=2e-4)
    np.testing.assert_allclose(pdf, exact, rtol=2e-4)
    # The cosine-based evaluation loses digits at the peak through dot(wo, wi) in f32, where
    # 1 + cos ~ (1 - g)^2 (hence hg_phase): 5 % at g = 0.99, a factor 1.5 at 0.999.
    if abs(g) <= 0.99:
        np.testing.assert_allclose(by_cos, exact, rtol=1e-3 if abs(g) < 0.99 else 5e-2)
    # The sampled cosine matches the textbook inversion (numpy, float64) for the same u.
    ref, _ = phase.hg_sample_np(g, wo, u.astype(np.float64))
    np.testing.assert_allclose(wi64 @ -wo, ref @ -wo, atol=2e-5 if abs(g) < 0.99 else 2e-4)


@pytest.mark.parametrize("g", G_VALUES + (0.999, -0.999))
def test_normalised_over_the_sphere(g):
    """2 pi times the integral of hg_eval over cos theta in [-1, 1] is 1 (Gauss-Legendre on pieces
    that shrink geometrically toward both poles, where a peak may sit)."""
    tail = np.geomspace(1e-9, 1.0, 80)
    edges = np.unique(np.concatenate([-1.0 + tail, 1.0 - tail, [-1.0, 1.0]]))
    integral = 2.0 * math.pi * integrate_bins(lambda c: eval_at(g, c), edges).sum()
    assert abs(integral - 1.0) < 1e-4 if abs(g) < 0.999 else abs(integral - 1.0) < 2e-3
    if g == 0.0:
        np.testing.assert_allclose(eval_at(0.0, np.linspace(-1, 1, 11)), 1.0 / (4.0 * math.pi), rtol=1e-7)


def test_extreme_g_is_finite():
    wo = wo_for(0.5)
    u = np.random.default_rng(1).random((10_000, 2), dtype=np.float32)
    u[:4] = [[0.0, 0.0], [0.99999994, 0.5], [0.5, 0.99999994], [1e-7, 0.1]]
    for g in (0.999, -0.999, 1.0, -1.0, 2.0):
        wi, pdf, by_cos, by_dirs = sample(g, wo, u)
        for a in (wi, pdf, by_cos, by_dirs):
            assert np.all(np.isfinite(a)), g
        assert np.all(pdf > 0.0)
    c = np.linspace(-1.0, 1.0, 1001)
    for g in (0.999, -0.999, 1.0, -1.0):
        values = eval_at(g, c)
        assert np.all(np.isfinite(values)) and np.all(values > 0.0)
