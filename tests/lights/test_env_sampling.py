"""Environment importance sampling: the sampler against its own pdf (chi-square), the pdf's
normalisation, sample/pdf agreement, bounded radiance/pdf on a map with a 10^4 peak, and an
unbiased estimate of the map's integral.

Statistics: alpha = 0.01 with a Sidak correction over NUM_TESTS tests in this file (chi-square and
z-tests); fixed seeds, so each outcome is deterministic.
"""
import math
import warnings

import numpy as np
import pytest
import taichi as ti
from scipy import stats

from renderer.output.image_io import read_environment
from renderer.lights.env_sampling import FLOOR, EnvironmentSampler, texel_bounds
from renderer.lights.environment import Environment
from renderer.scene.description import EnvironmentSpec
from tests.stats.chi2 import ENV_FRAME, chi2_test, integrate_pdf, sidak_alpha

ALPHA = 0.01
NUM_TESTS = 14  # 8 chi-square tests + 2 maps x 3 channels of z-tests
N = 1_000_000
ENVMAPS = "assets/envmaps"
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def load(name):
    with warnings.catch_warnings():  # lossy-compression ringing clamped to 0: expected here
        warnings.simplefilter("ignore")
        return read_environment(f"{ENVMAPS}/{name}.exr")


def one_hot(height=32, width=64, row=13, col=20, value=1000.0):
    image = np.zeros((height, width, 3), np.float32)
    image[row, col] = value
    return image


def make(image, rotation_degrees=0.0, intensity=1.0):
    env = Environment(EnvironmentSpec(kind="map", rotation=rotation_degrees, intensity=intensity), image)
    return EnvironmentSampler(image, env)


def set_rotation(sampler, degrees):
    """Change the rotation the way the viewer does: data, no rebuild, no recompile."""
    sampler.environment.scalars[1] = math.radians(degrees)


def uniforms(seed, n=N):
    return np.random.default_rng(seed).random((n, 2), dtype=np.float32)


@pytest.fixture(scope="module")
def maps(taichi_runtime):
    built = {}

    def get(name):
        if name not in built:
            built[name] = make(load(name))
        return built[name]

    return get


def run_chi2(sampler, seed, tmp_path, name, pdf=None):
    d, _, _ = sampler.sample_batch(uniforms(seed))
    phi, theta = sampler.texel_edges()
    result = chi2_test(d, pdf or sampler.pdf_batch, frame=ENV_FRAME, res=64, subdivisions=1,
                       phi_breaks=phi, theta_breaks=theta, alpha=ALPHA, num_tests=NUM_TESTS)
    if not result.passed:
        result.write_png(tmp_path / f"{name}.png")
    return result


# -- chi-square ------------------------------------------------------------------------------------

@pytest.mark.parametrize(
    "row, col, rotation",
    [(13, 20, 0.0), (0, 63, 70.7), (31, 0, -123.0)],
    ids=["middle", "zenith-row-wrapping-u-rotated", "nadir-row-rotated"],
)
def test_chi2_one_hot(taichi_runtime, tmp_path, row, col, rotation):
    """A single bright texel (plus the floor): nearly every sample lands in its bilinear footprint,
    the floor spreads the rest; the chi-square sees both."""
    sampler = make(one_hot(row=row, col=col), rotation)
    result = run_chi2(sampler, 10 + row, tmp_path, f"one_hot_{row}_{col}")
    assert result.passed, result.report
    assert result.pdf_integral == pytest.approx(1.0, abs=1e-5)
    # the 3x3 footprint holds all but the floor's share (< 2 * FLOOR)
    p = sampler.tables["probabilities"]
    rows = np.clip(np.arange(row - 1, row + 2), 0, 31)
    cols = np.arange(col - 1, col + 2) % 64
    assert p[np.ix_(np.unique(rows), cols)].sum() > 1.0 - 2.0 * FLOOR


@pytest.mark.parametrize("name, rotation", [("sky", 0.0), ("studio", 0.0), ("sky", -37.0), ("studio", 100.0)])
def test_chi2_real_map(maps, tmp_path, name, rotation):
    sampler = maps(name)
    set_rotation(sampler, rotation)
    try:
        result = run_chi2(sampler, 20, tmp_path, f"{name}_{rotation}")
    finally:
        set_rotation(sampler, 0.0)
    assert result.passed, result.report
    assert result.pdf_integral == pytest.approx(1.0, abs=1e-5)


def test_chi2_has_power(taichi_runtime, tmp_path):
    """The same test rejects a pdf that is off by half a texel in phi."""
    sampler = make(one_hot())
    half_texel = math.pi / sampler.width
    c, s = math.cos(half_texel), math.sin(half_texel)
    about_y = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    result = run_chi2(sampler, 30, tmp_path, "shifted", pdf=lambda d: sampler.pdf_batch(d @ about_y.T))
    assert not result.passed and result.p_value < 1e-100, result.report


# -- the pdf -----------------------------------------------------------------------------------------

@pytest.mark.parametrize("case", ["one_hot", "sky", "studio_rotated"])
def test_pdf_integrates_to_one(maps, case):
    """Quadrature of the device pdf over the sphere (exact per texel, with the texel edges as breaks)."""
    sampler = make(one_hot()) if case == "one_hot" else maps(case.split("_")[0])
    set_rotation(sampler, 33.3 if case.endswith("rotated") else 0.0)
    try:
        phi, theta = sampler.texel_edges()
        integral = integrate_pdf(sampler.pdf_batch, frame=ENV_FRAME, res=16, subdivisions=1,
                                 phi_breaks=phi, theta_breaks=theta).sum()
    finally:
        set_rotation(sampler, 0.0)
    assert integral == pytest.approx(1.0, abs=1e-5)
    tables = sampler.tables
    assert (tables["probabilities"].sum()) == pytest.approx(1.0, abs=1e-12)


def distance_to_texel_border(directions, sampler, rotation):
    """In texel units, from float64 coordinates of the (float32) directions."""
    d = directions.astype(np.float64)
    u = np.mod((np.arctan2(d[:, 0], -d[:, 2]) + rotation) / (2 * math.pi), 1.0) * sampler.width
    # row cells are centred on pi i / (H - 1): their borders sit at half-integers of v (H - 1)
    v = np.arctan2(np.hypot(d[:, 0], d[:, 2]), d[:, 1]) / math.pi * (sampler.height - 1) + 0.5
    du = np.abs(u - np.round(u))
    dv = np.abs(v - np.round(v))
    return np.minimum(du, dv)


@pytest.mark.parametrize("name, rotation", [("sky", 0.0), ("studio", 100.0), ("one_hot", 70.7)])
def test_sample_pdf_round_trip(maps, name, rotation):
    sampler = make(one_hot(row=0, col=63)) if name == "one_hot" else maps(name)
    set_rotation(sampler, rotation)
    try:
        d, pdf, radiance = sampler.sample_batch(uniforms(40, 200_000))
        again = sampler.pdf_batch(d)
        lookup = sampler.radiance_batch(d)
    finally:
        set_rotation(sampler, 0.0)
    assert np.isfinite(d).all() and np.isfinite(pdf).all() and np.isfinite(radiance).all()
    assert np.allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-6)
    assert (pdf > 0).all()
    np.testing.assert_array_equal(radiance, lookup)  # radiance is environment.radiance(direction)
    interior = distance_to_texel_border(d, sampler, math.radians(rotation)) > 1e-3
    assert interior.mean() > 0.99
    np.testing.assert_allclose(again[interior], pdf[interior], rtol=1e-3)
    # at borders the direction may map to the neighbour: then it is the neighbour's pdf
    mismatch = ~np.isclose(again, pdf, rtol=1e-3)
    assert mismatch.mean() < 1e-3


def test_poles_and_extreme_samples_are_finite(taichi_runtime):
    """u at 0, just below 1 and at 1 (clamped); a hot texel in the zenith row; directions exactly
    at the poles: all finite, unit, with a finite positive pdf."""
    sampler = make(one_hot(row=0, col=5))
    edge = np.float32(1.0) - np.float32(2.0 ** -24)
    corners = np.array([[a, b] for a in (0.0, edge, 1.0, 0.5) for b in (0.0, edge, 1.0, 0.5)], np.float32)
    d, pdf, radiance = sampler.sample_batch(corners)
    assert np.isfinite(d).all() and np.isfinite(pdf).all() and np.isfinite(radiance).all()
    assert np.allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-6) and (pdf > 0).all()
    poles = np.array([[0, 1, 0], [0, -1, 0], [0, 1, 1e-8], [1e-9, -1, 0]], np.float32)
    p = sampler.pdf_batch(poles)
    assert np.isfinite(p).all() and (p > 0).all()
    # texel 0's pdf is finite in all of it: P / Omega, not P / sin(theta)
    assert sampler.tables["texel_pdf"].max() < 1e7


def test_black_map_is_uniform(taichi_runtime):
    sampler = make(np.zeros((16, 32, 3), np.float32))
    np.testing.assert_allclose(sampler.tables["texel_pdf"], 1.0 / (4.0 * math.pi), rtol=1e-5)
    d, pdf, radiance = sampler.sample_batch(uniforms(41, 1000))
    assert (radiance == 0).all() and np.allclose(pdf, 1.0 / (4.0 * math.pi), rtol=1e-5)


@pytest.mark.parametrize("name", ["one_hot", "sky", "park"])
def test_pdf_positive_wherever_radiance_is(maps, name):
    """radiance(d) > 0 implies pdf(d) > 0, and luminance(radiance) <= ratio_bound * pdf: checked on
    random directions and, for the one-hot map, densely around the hot texel's footprint."""
    sampler = make(one_hot()) if name == "one_hot" else maps(name)
    rng = np.random.default_rng(42)
    d = rng.normal(size=(500_000, 3))
    if name == "one_hot":
        centre_u, centre_v = (20 + 0.5) / 64, 13 / 31  # row centres at i / (H - 1)
        u = centre_u + rng.uniform(-2.5, 2.5, 500_000) / 64
        v = centre_v + rng.uniform(-2.5, 2.5, 500_000) / 31
        phi, theta = 2 * math.pi * u, math.pi * v
        d = np.stack([np.sin(theta) * np.sin(phi), np.cos(theta), -np.sin(theta) * np.cos(phi)], axis=1)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    radiance = sampler.radiance_batch(d).astype(np.float64)
    pdf = sampler.pdf_batch(d).astype(np.float64)
    lit = radiance.max(axis=1) > 0
    assert lit.any() and (pdf[lit] > 0).all()
    assert (radiance @ LUMINANCE <= sampler.ratio_bound * pdf * (1 + 1e-4)).all()


def test_texel_bounds_match_the_bilinear_sup():
    """The conservative weight of a lone texel's neighbours: 1/2 across an edge, 1/4 across a corner,
    0 beyond; u wraps and v clamps."""
    image = one_hot(8, 16, row=0, col=0, value=1.0)
    bound = texel_bounds(image) / LUMINANCE.sum()
    assert bound[0, 0] == pytest.approx(1.0)
    assert bound[0, 1] == bound[0, 15] == pytest.approx(0.5)  # wraps in u
    assert bound[1, 0] == pytest.approx(0.5)
    assert bound[1, 1] == bound[1, 15] == pytest.approx(0.25)
    assert bound[2:].max() == 0.0 and bound[0, 2:15].max() == 0.0


# -- the estimator ------------------------------------------------------------------------------------

def test_radiance_over_pdf_is_bounded_on_sky(maps):
    """sky.exr peaks at ~22,000: uniform sampling would see radiance/pdf up to 4 pi * 22,000 = 2.8e5.
    Here the luminance of radiance/pdf stays below the map's conservative total power."""
    sampler = maps("sky")
    image = sampler.tables["bound"]
    d, pdf, radiance = sampler.sample_batch(uniforms(50))
    ratio = (radiance.astype(np.float64) @ LUMINANCE) / pdf
    peak = float((load("sky") @ LUMINANCE.astype(np.float32)).max())
    print(f"sky.exr: luminance radiance/pdf max {ratio.max():.3f}, mean {ratio.mean():.3f}, "
          f"max/mean {ratio.max() / ratio.mean():.3f}, bound {sampler.ratio_bound:.3f}, "
          f"uniform sampling max {4 * math.pi * peak:.0f}")
    assert ratio.max() <= sampler.ratio_bound * (1 + 1e-4)
    assert ratio.max() / ratio.mean() < 3.0
    assert image.max() > 1e4 and ratio.max() < 1e-3 * 4 * math.pi * peak


def exact_integral(sampler):
    """The integral over the sphere of the device's radiance (RGB), exact to rounding: between
    consecutive texel-centre lines the bilinear lookup is linear in phi and in theta, so
    Gauss-Legendre (2 points in phi, 5 in theta with the sin theta Jacobian) integrates each piece."""
    w, h = sampler.width, sampler.height
    rotation = float(sampler.environment.scalars[1])
    phi_lines = np.sort(np.mod(2 * math.pi * (np.arange(w) + 0.5) / w - rotation, 2 * math.pi))
    phi_edges = np.unique(np.concatenate([[0.0], phi_lines, [2 * math.pi]]))
    theta_edges = math.pi * np.arange(h) / (h - 1)  # the row centres: 0 (zenith) to pi (nadir)

    def nodes(edges, k):
        t, wt = np.polynomial.legendre.leggauss(k)
        mid, half = 0.5 * (edges[1:] + edges[:-1]), 0.5 * np.diff(edges)
        return (mid[:, None] + half[:, None] * t).ravel(), (half[:, None] * wt).ravel()

    phi, w_phi = nodes(phi_edges, 2)
    theta, w_theta = nodes(theta_edges, 5)
    total = np.zeros(3)
    for start in range(0, len(theta), 256):
        th = theta[start:start + 256]
        s, c = np.sin(th)[:, None], np.cos(th)[:, None]
        d = np.stack([s * np.sin(phi), np.broadcast_to(c, (len(th), len(phi))), -s * np.cos(phi)], axis=-1)
        radiance = sampler.radiance_batch(d.reshape(-1, 3)).astype(np.float64).reshape(len(th), len(phi), 3)
        weights = (w_theta[start:start + 256] * np.sin(th))[:, None] * w_phi[None, :]
        total += np.einsum("ij,ijk->k", weights, radiance)
    return total


@pytest.mark.parametrize("name, rotation, intensity", [("sky", 41.0, 2.5), ("studio", 0.0, 1.0)])
def test_estimator_is_unbiased(maps, name, rotation, intensity):
    """z-test per channel: mean of radiance/pdf over N samples vs the exact integral."""
    sampler = maps(name)
    set_rotation(sampler, rotation)
    sampler.environment.scalars[0] = intensity
    try:
        reference = exact_integral(sampler)
        _, pdf, radiance = sampler.sample_batch(uniforms(60))
    finally:
        set_rotation(sampler, 0.0)
        sampler.environment.scalars[0] = 1.0
    estimates = radiance.astype(np.float64) / pdf.astype(np.float64)[:, None]
    mean = estimates.mean(axis=0)
    standard_error = estimates.std(axis=0, ddof=1) / math.sqrt(len(estimates))
    z = (mean - reference) / standard_error
    p_values = 2.0 * stats.norm.sf(np.abs(z))
    print(f"{name}: integral {reference}, estimate {mean}, relative error {standard_error / reference}, z {z}")
    assert (p_values >= sidak_alpha(ALPHA, NUM_TESTS)).all(), (reference, mean, z)


def test_intensity_and_rotation_are_runtime_data(maps):
    """Intensity scales the radiance and leaves the pdf alone; rotation turns the samples about +y.
    Neither rebuilds the tables or recompiles (same sampler object, same kernels)."""
    sampler = maps("studio")
    u = uniforms(70, 10_000)
    d0, p0, r0 = sampler.sample_batch(u)
    sampler.environment.scalars[0] = 3.0
    try:
        d1, p1, r1 = sampler.sample_batch(u)
        set_rotation(sampler, 90.0)
        d2, p2, _ = sampler.sample_batch(u)
        rotated_pdf = sampler.pdf_batch(d2)
    finally:
        sampler.environment.scalars[0] = 1.0
        set_rotation(sampler, 0.0)
    np.testing.assert_array_equal(d0, d1)
    np.testing.assert_array_equal(p0, p1)
    np.testing.assert_allclose(r1, 3.0 * r0, rtol=1e-6)
    np.testing.assert_array_equal(p0, p2)
    # turning the map by +90 degrees about +y (right-hand rule) takes (x, y, z) to (z, y, -x)
    np.testing.assert_allclose(d2, np.stack([d0[:, 2], d0[:, 1], -d0[:, 0]], axis=1), atol=2e-5)
    assert np.mean(np.isclose(rotated_pdf, p2, rtol=1e-3)) > 0.99


def test_needs_a_map(taichi_runtime):
    env = Environment(EnvironmentSpec(kind="sky"), None)
    with pytest.raises(ValueError, match="needs a map"):
        EnvironmentSampler(np.zeros((4, 8, 3), np.float32), env)
