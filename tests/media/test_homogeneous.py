"""The homogeneous medium (renderer/media/homogeneous.py): transmittance, free-flight sampling with
spectral MIS, and the exponential-fog blend.

Statistical tests: fixed seeds, ALPHA = 0.01 family-wise over NUM_TESTS z-tests (two-sided,
Sidak-corrected); each mean is compared with its closed form using the sample's own standard error.
"""
import math

import numpy as np
import pytest
import taichi as ti
from scipy import stats

from renderer.media import homogeneous as hm
from tests.stats.chi2 import sidak_alpha

ALPHA = 0.01
N = 1_000_000
SLABS = (0.1, 1.0, 3.0)  # optical thickness sigma_t * d of the grey slabs
RGB_CASES = (  # (sigma_a, sigma_s, thickness d)
    ((0.2, 0.5, 1.5), (0.8, 0.3, 0.05), 1.0),
    ((0.0, 0.0, 4.0), (2.0, 0.5, 0.0), 0.7),  # a channel that only absorbs, one that only scatters
    ((0.0, 0.0, 0.0), (0.0, 1.0, 3.0), 2.0),  # a channel with sigma_t = 0: never scatters
)
NUM_TESTS = len(SLABS) + len(RGB_CASES) * 6  # per RGB case: 3 channels x (scattered, surface)
vec3 = ti.math.vec3


@ti.kernel
def _sample_kernel(sigma_a: vec3, sigma_s: vec3, t_max: ti.f32, u: ti.types.ndarray(dtype=ti.math.vec2, ndim=1),
                   t: ti.types.ndarray(dtype=ti.f32, ndim=1), scattered: ti.types.ndarray(dtype=ti.i32, ndim=1),
                   weight: ti.types.ndarray(dtype=vec3, ndim=1)):
    for i in range(u.shape[0]):
        s = hm.sample_distance(sigma_a, sigma_s, t_max, u[i].x, u[i].y)
        t[i] = s.t
        scattered[i] = s.scattered
        weight[i] = s.weight


@ti.kernel
def _pointwise_kernel(sigma_t: vec3, d: ti.types.ndarray(dtype=ti.f32, ndim=1),
                      tr: ti.types.ndarray(dtype=vec3, ndim=1), fog: ti.types.ndarray(dtype=vec3, ndim=1),
                      colour: vec3, fog_colour: vec3, density: ti.f32):
    for i in range(d.shape[0]):
        tr[i] = hm.transmittance(sigma_t, d[i])
        fog[i] = hm.exponential_fog(colour, fog_colour, density, d[i])


def sample(sigma_a, sigma_s, t_max, u):
    n = len(u)
    t, scattered, weight = np.zeros(n, np.float32), np.zeros(n, np.int32), np.zeros((n, 3), np.float32)
    _sample_kernel(vec3(*sigma_a), vec3(*sigma_s), t_max, np.ascontiguousarray(u, np.float32), t, scattered, weight)
    return t.astype(np.float64), scattered.astype(bool), weight.astype(np.float64)


def z_p_value(values, expected):
    """Two-sided p-value of the mean of `values` against `expected`, by its standard error."""
    mean = values.mean()
    sem = values.std(ddof=1) / math.sqrt(len(values))
    if sem == 0.0:
        return 1.0 if abs(mean - expected) <= 1e-6 * max(1.0, abs(expected)) else 0.0
    return 2.0 * stats.norm.sf(abs(mean - expected) / sem)


def test_transmittance_and_fog_are_the_closed_forms():
    d = np.array([0.0, 0.01, 0.5, 1.0, 7.0, 100.0], np.float32)
    sigma_t = (0.3, 1.0, 2.5)
    tr, fog = np.zeros((len(d), 3), np.float32), np.zeros((len(d), 3), np.float32)
    colour, fog_colour, density = (0.9, 0.2, 0.1), (0.5, 0.6, 0.7), 0.4
    _pointwise_kernel(vec3(*sigma_t), d, tr, fog, vec3(*colour), vec3(*fog_colour), density)
    np.testing.assert_allclose(tr, hm.transmittance_np(sigma_t, d), rtol=1e-5, atol=1e-30)  # f32 sigma * d
    np.testing.assert_allclose(fog, hm.exponential_fog_np(colour, fog_colour, density, d[:, None]), rtol=1e-6)
    np.testing.assert_allclose(fog[0], np.float32(colour), rtol=1e-6)  # no distance: the surface colour
    np.testing.assert_allclose(fog[-1], fog_colour, rtol=1e-6)  # far away: the fog colour


@pytest.mark.parametrize("thickness", SLABS)
def test_grey_slab_transmission(thickness):
    """Free-flight sampling through a grey slab of thickness d = 1: the fraction of samples that
    reach t_max is Binomial(N, exp(-sigma_t d)), tested by a z-test on that fraction."""
    sigma = thickness  # d = 1 m
    u = np.random.default_rng(int(thickness * 100)).random((N, 2), dtype=np.float32)
    t, scattered, weight = sample((0.25 * sigma,) * 3, (0.75 * sigma,) * 3, 1.0, u)
    p = math.exp(-thickness)
    passed = ~scattered
    z = (passed.mean() - p) / math.sqrt(p * (1.0 - p) / N)
    assert 2.0 * stats.norm.sf(abs(z)) >= sidak_alpha(ALPHA, NUM_TESTS), f"passed {passed.mean():.5f} vs {p:.5f}"
    # Grey weights are exact: the albedo for a scattering event, 1 for the surface.
    np.testing.assert_allclose(weight[scattered], 0.75, rtol=1e-5)
    np.testing.assert_allclose(weight[passed], 1.0, rtol=1e-5)
    assert np.all(t[passed] == 1.0) and np.all((t[scattered] >= 0.0) & (t[scattered] < 1.0))
    # The distances of the scattering events follow the truncated exponential (KS test, informative
    # only: not counted in the family, its p-value must merely not be absurd).
    cdf = lambda x: (1.0 - np.exp(-sigma * x)) / (1.0 - p)
    assert stats.kstest(t[scattered], cdf).pvalue > 1e-6


@pytest.mark.parametrize("case", range(len(RGB_CASES)))
def test_rgb_weights_are_unbiased(case):
    """E[weight; scattered] = sigma_s / sigma_t (1 - exp(-sigma_t d)) (the single-scattered
    fraction, sigma_s d where sigma_t = 0) and E[weight; surface] = exp(-sigma_t d), per channel."""
    sigma_a, sigma_s, d = RGB_CASES[case]
    u = np.random.default_rng(500 + case).random((N, 2), dtype=np.float32)
    _, scattered, weight = sample(sigma_a, sigma_s, d, u)
    assert np.all(np.isfinite(weight)) and np.all(weight >= 0.0)
    sigma_s = np.array(sigma_s)
    sigma_t = np.array(sigma_a) + sigma_s
    with np.errstate(invalid="ignore", divide="ignore"):
        single = np.where(sigma_t > 0.0, sigma_s / sigma_t * -np.expm1(-sigma_t * d), sigma_s * d)
    tr = np.exp(-sigma_t * d)
    alpha = sidak_alpha(ALPHA, NUM_TESTS)
    for c in range(3):
        p_scatter = z_p_value(np.where(scattered, weight[:, c], 0.0), single[c])
        p_surface = z_p_value(np.where(scattered, 0.0, weight[:, c]), tr[c])
        assert p_scatter >= alpha, f"channel {c}: scattered {np.where(scattered, weight[:, c], 0).mean()} vs {single[c]}"
        assert p_surface >= alpha, f"channel {c}: surface {np.where(scattered, 0, weight[:, c]).mean()} vs {tr[c]}"


def test_matches_numpy_reference_and_handles_infinite_t_max():
    u = np.random.default_rng(3).random((10_000, 2), dtype=np.float32)
    sigma_a, sigma_s = (0.2, 0.5, 1.5), (0.8, 0.3, 0.05)
    t, scattered, weight = sample(sigma_a, sigma_s, 2.0, u)
    t_ref, s_ref, w_ref = hm.sample_distance_np(sigma_a, sigma_s, 2.0, u[:, 0], u[:, 1])
    assert np.array_equal(scattered, s_ref)
    np.testing.assert_allclose(t, t_ref, rtol=2e-6)
    np.testing.assert_allclose(weight, w_ref, rtol=2e-5)
    # A ray leaving the scene: every sample scatters unless its channel has sigma_t = 0.
    t, scattered, weight = sample((0.0, 0.0, 0.0), (1.0, 0.5, 0.0), math.inf, u)
    assert np.all(np.isfinite(t)) and np.all(np.isfinite(weight))
    blue = np.minimum((u[:, 0] * 3).astype(int), 2) == 2
    assert np.all(scattered[~blue]) and not np.any(scattered[blue])
    np.testing.assert_allclose(weight[blue], np.broadcast_to([0.0, 0.0, 3.0], weight[blue].shape))
