"""The samplers: the Sobol sampler's exact structure (nets, strata, bit-exact reference) and the
statistics that matter to a renderer (uniformity, independence of dimensions and pixels,
unbiasedness, convergence rate), against the independent sampler where a comparison helps.

Every statistical check uses fixed seeds and a stated significance level ALPHA; where one test
function makes several checks, each is made at the Sidak-corrected level 1 - (1 - ALPHA)^(1/k),
so that the function as a whole fails with probability ALPHA when the sampler is right.
"""
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import taichi as ti
from scipy import stats

from renderer.sampling import dims
from renderer.sampling.sampler import IndependentSampler, make_sampler
from renderer.sampling.sobol import (DIRECTIONS, SobolSampler, reference_get1d, reference_get2d,
                                     reference_sobol_u32, sobol_directions, sobol_u32, to_unit)

ALPHA = 0.01


def sidak(k: int) -> float:
    return 1.0 - (1.0 - ALPHA) ** (1.0 / k)


# --- drawing samples from a kernel ----------------------------------------------------------------
GET2D, GET1D_PAIR, GET2D_Y_PAIR = 0, 1, 2


@ti.kernel
def _draw(sampler: ti.template(), out: ti.types.ndarray(), pixel0: ti.i32, pixel_stride: ti.i32,
          index0: ti.i32, dim_a: ti.i32, dim_b: ti.i32, seed: ti.u32, mode: ti.i32):
    for p, i in ti.ndrange(out.shape[0], out.shape[1]):
        state = sampler.start(pixel0 + p * pixel_stride, index0 + i, seed)
        v = ti.math.vec2(0.0)
        if mode == 0:
            v = sampler.get2d(state, dim_a)
        elif mode == 1:
            v = ti.math.vec2(sampler.get1d(state, dim_a), sampler.get1d(state, dim_b))
        else:
            v = ti.math.vec2(sampler.get2d(state, dim_a).y, sampler.get2d(state, dim_b).y)
        out[p, i, 0] = v.x
        out[p, i, 1] = v.y


def draw(sampler, pixels, n, dim_a=0, dim_b=1, seed=0, mode=GET2D, pixel0=0, pixel_stride=1, index0=0):
    """(pixels, n, 2) float32: samples index0 .. index0+n-1 of pixels pixel0 + p * pixel_stride."""
    out = np.empty((pixels, n, 2), dtype=np.float32)
    _draw(sampler, out, pixel0, pixel_stride, index0, dim_a, dim_b, seed, mode)
    return out


@pytest.fixture(scope="module")
def sobol():
    return SobolSampler()


@pytest.fixture(scope="module")
def independent():
    return IndependentSampler()


# --- structure ------------------------------------------------------------------------------------
def test_make_sampler_builds_sobol():
    s = make_sampler("sobol")
    assert isinstance(s, SobolSampler) and s.name == "sobol"


def test_generator_matrices_are_joe_kuo_sobol():
    """Unscrambled points of dims 0..3 equal scipy's Sobol points (which come in Gray-code order)."""
    from scipy.stats import qmc

    assert sobol_directions().shape == (4, 32) and len(DIRECTIONS) == 4
    n = 1 << 12
    expected = qmc.Sobol(4, scramble=False, bits=32).random_base2(12)
    i = np.arange(n)
    gray = i ^ (i >> 1)
    ours = np.stack([reference_sobol_u32(gray, d) for d in range(4)], axis=-1).astype(np.float64) / 2.0**32
    np.testing.assert_array_equal(ours, expected)


@ti.kernel
def _sobol_points(out: ti.types.ndarray(), index0: ti.i32):
    for i in range(out.shape[0]):
        for d in ti.static(range(4)):
            out[i, d] = sobol_u32(index0 + i, d)


def test_kernel_sobol_dimensions_match_reference():
    for index0 in (0, 2**31 - 300):
        out = np.empty((256, 4), dtype=np.uint32)
        _sobol_points(out, index0)
        for d in range(4):
            np.testing.assert_array_equal(out[:, d], reference_sobol_u32(np.arange(256) + index0, d))


def test_kernel_matches_numpy_reference_bit_for_bit(sobol):
    """The kernel and the numpy model of the same u32 arithmetic agree exactly, including at large
    pixel ids, sample indices, dimension ids and seeds (wrap-around of every product)."""
    cases = [(0, 1, 0, 0, 0), (5, 7, 2**20 + 3, 3, 0xFFFFFFFF), (123456, 3, 2**30 + 12345, 1000, 0xDEADBEEF),
             (2**31 - 40, 1, 77, 0x7FFF, 12345)]
    for pixel0, stride, index0, dim, seed in cases:
        pixels = np.arange(8)[:, None] * stride + pixel0
        index = np.arange(32)[None, :] + index0
        got2 = draw(sobol, 8, 32, dim, 0, seed, GET2D, pixel0, stride, index0)
        np.testing.assert_array_equal(got2, reference_get2d(pixels, index, dim, seed))
        got1 = draw(sobol, 8, 32, dim, dim + 5, seed, GET1D_PAIR, pixel0, stride, index0)
        np.testing.assert_array_equal(got1[..., 0], reference_get1d(pixels, index, dim, seed))
        np.testing.assert_array_equal(got1[..., 1], reference_get1d(pixels, index, dim + 5, seed))


@ti.kernel
def _to_unit(v: ti.u32) -> ti.f32:
    return to_unit(v)


def test_unit_conversion_never_reaches_one():
    assert _to_unit(0xFFFFFFFF) == np.float32(1.0 - 2.0**-24) < 1.0
    assert _to_unit(0) == 0.0


def test_values_in_unit_interval_deterministic_and_seeded(sobol):
    a = draw(sobol, 256, 256, 3, 0, seed=1)
    assert a.min() >= 0.0 and a.max() < 1.0
    assert np.array_equal(a, draw(sobol, 256, 256, 3, 0, seed=1)), "a pure function of its arguments"
    # A sample recomputed alone equals the same sample drawn in a batch.
    np.testing.assert_array_equal(draw(sobol, 1, 1, 3, 0, seed=1, pixel0=17, index0=33)[0, 0], a[17, 33])
    # Another seed, pixel or dimension gives another sequence: 24-bit values of unrelated
    # sequences coincide with probability ~2^-24 per value, so a handful of ties at most.
    for other in (draw(sobol, 256, 256, 3, 0, seed=2), draw(sobol, 256, 256, 3, 0, seed=1, pixel0=1),
                  draw(sobol, 256, 256, 4, 0, seed=1)):
        ties = np.mean(other == a)
        assert ties < 1e-3, ties


# --- stratification -------------------------------------------------------------------------------
NET_PIXELS = (0, 1, 777, 123456, 2**24 + 5)
NET_DIMS = (dims.PIXEL, dims.LENS, dims.bounce(0, dims.BSDF_DIRECTION), dims.bounce(7, dims.LIGHT_POINT), 1000)


def elementary_interval_counts(points, a, b):
    """Points per elementary interval [i/2^a, (i+1)/2^a) x [j/2^b, (j+1)/2^b) (exact: the values are
    multiples of 2^-24, so scaling by a power of two and flooring is exact)."""
    cx = np.floor(points[:, 0].astype(np.float64) * 2**a).astype(np.int64)
    cy = np.floor(points[:, 1].astype(np.float64) * 2**b).astype(np.int64)
    return np.bincount(cx * 2**b + cy, minlength=2 ** (a + b))


@pytest.mark.parametrize("seed", [0, 0xC0FFEE])
def test_get2d_every_aligned_block_of_2m_samples_is_a_0m2_net(sobol, seed):
    """For m = 1..8 and every shape 2^a x 2^b (a + b = m), each block of 2^m samples starting at a
    multiple of 2^m holds exactly one point per elementary interval: the first 2^m samples of a
    pixel, and each later aligned block (what a progressive render adds), are (0,m,2)-nets."""
    n = 1024
    for dim in NET_DIMS:
        for pixel in NET_PIXELS:
            pts = draw(sobol, 1, n, dim, 0, seed, GET2D, pixel0=pixel)[0]
            for m in range(1, 9):
                for start in range(0, n, 2**m):
                    block = pts[start:start + 2**m]
                    for a in range(m + 1):
                        counts = elementary_interval_counts(block, a, m - a)
                        assert np.all(counts == 1), (dim, pixel, m, start, a)


@pytest.mark.parametrize("seed", [0, 0xC0FFEE])
def test_get1d_first_2m_samples_are_one_per_stratum(sobol, seed):
    """The first 2^m values of get1d hold one value per interval of width 2^-m (m = 1..10)."""
    for pixel in NET_PIXELS:
        for dim in NET_DIMS:
            x = draw(sobol, 1, 1024, dim, dim + 1, seed, GET1D_PAIR, pixel0=pixel)[0, :, 0]
            for m in range(1, 11):
                strata = np.floor(x[: 2**m].astype(np.float64) * 2**m).astype(np.int64)
                assert np.array_equal(np.sort(strata), np.arange(2**m)), (pixel, dim, m)


# --- independence of dimensions and pixels --------------------------------------------------------
GRID = 8  # chi-square cells per axis: 64 cells, >= 64 expected points each below


def chi_square_uniform_p(points, g=GRID):
    """p-value of Pearson's chi-square test that iid points are uniform on a g x g grid."""
    counts = elementary_interval_counts(points, int(math.log2(g)), int(math.log2(g)))
    return stats.chisquare(counts).pvalue


DIM_PAIRS = ((dims.PIXEL, dims.LENS), (dims.bounce(0, dims.BSDF_LOBE), dims.bounce(0, dims.BSDF_DIRECTION)),
             (dims.bounce(0, dims.BSDF_DIRECTION), dims.bounce(1, dims.BSDF_DIRECTION)),
             (dims.bounce(2, dims.ROULETTE), dims.bounce(2, dims.LIGHT_SELECT)), (5, 1005))


def test_dimensions_and_pixels_are_independent_across_pixels(sobol):
    """Across pixels, one given sample index gives iid points (pixels have independent scrambles),
    so pairs of values from two dimension ids, or from two neighbouring pixels, must be uniform in
    the square: chi-square on an 8 x 8 grid with 4096 points (64 expected per cell, so the
    chi-square approximation holds)."""
    checks = []
    n_pix = 4096
    for index in (0, 1, 37, 255):
        for a, b in DIM_PAIRS:
            for mode in (GET1D_PAIR, GET2D_Y_PAIR):
                pts = draw(sobol, n_pix, 1, a, b, 9, mode, index0=index)[:, 0]
                checks.append((f"dims {a},{b} mode {mode} index {index}", chi_square_uniform_p(pts)))
        # Neighbouring pixels: x neighbours (2k, 2k+1) and y neighbours (row r, row r+1), width 64.
        for dim in (dims.PIXEL, dims.bounce(0, dims.BSDF_DIRECTION)):
            v = draw(sobol, 2 * n_pix, 1, dim, 0, 9, GET2D, index0=index)[:, 0]
            checks.append((f"x-neighbours dim {dim} index {index}", chi_square_uniform_p(v[:, 0].reshape(-1, 2))))
            rows = v[:, 1].reshape(-1, 2, 64)  # rows 2r and 2r + 1 of an image 64 wide
            checks.append((f"y-neighbours dim {dim} index {index}",
                           chi_square_uniform_p(np.stack([rows[:, 0].ravel(), rows[:, 1].ravel()], axis=-1))))
    level = sidak(len(checks))
    failed = [(name, p) for name, p in checks if p < level]
    assert not failed, f"rejected at the Sidak level {level:.2e}: {failed}"


def hotelling_uniform_p(points, g=4):
    """Within-pixel samples are stratified, not iid, so a pooled chi-square has no known null.
    Pixels are independent replicates, though: per pixel, count the points in a g x g grid; under
    the null the mean table over pixels is uniform. The free cells are the (g-1)^2 cells of a
    corner (stratified marginals fix every row and column total), tested with Hotelling's T^2 and
    the covariance estimated across pixels: a chi-square statistic with (g-1)^2 dof in the limit,
    and exactly F-distributed under normality.

    When the pairing of the two coordinates is random, the free cells vary independently of one
    another and their covariance is non-singular; a singular one means a deterministic relation
    between the coordinates (e.g. two dimension ids drawing the same sequence): p = 0."""
    r, n, _ = points.shape
    k = int(math.log2(g))
    cells = np.stack([elementary_interval_counts(p, k, k).reshape(g, g)[: g - 1, : g - 1].ravel() for p in points])
    diff = cells - n / g**2
    d = diff.shape[1]
    mean = diff.mean(axis=0)
    cov = np.cov(diff, rowvar=False)
    eig = np.linalg.eigvalsh(cov)
    if eig[0] <= 1e-9 * eig[-1]:
        return 0.0
    t2 = r * mean @ np.linalg.solve(cov, mean)
    return stats.f.sf((r - d) / (d * (r - 1)) * t2, d, r - d)


def test_dimensions_and_pixels_are_independent_over_the_samples_of_a_pixel(sobol):
    """Over the 64 samples of a pixel, (dim a, dim b) pairs and (pixel, neighbour pixel) pairs are
    uniform in the square in expectation (see hotelling_uniform_p), with 2048 pixels as replicates."""
    checks = []
    n_pix, n = 2048, 64
    for a, b in DIM_PAIRS:
        for mode in (GET1D_PAIR, GET2D_Y_PAIR):
            checks.append((f"dims {a},{b} mode {mode}", hotelling_uniform_p(draw(sobol, n_pix, n, a, b, 3, mode))))
    for dim in (dims.PIXEL, dims.bounce(0, dims.BSDF_DIRECTION)):
        v = draw(sobol, 2 * n_pix, n, dim, 0, 3, GET2D)[..., 0].reshape(n_pix, 2, n)
        checks.append((f"x-neighbours dim {dim}", hotelling_uniform_p(np.stack([v[:, 0], v[:, 1]], axis=-1))))
    level = sidak(len(checks))
    failed = [(name, p) for name, p in checks if p < level]
    assert not failed, f"rejected at the Sidak level {level:.2e}: {failed}"


# --- integration: unbiasedness and convergence ----------------------------------------------------
BUMP_CENTRE, BUMP_SIGMA = (0.45, 0.55), 0.2


def bump(p):
    d2 = (p[..., 0] - BUMP_CENTRE[0]) ** 2 + (p[..., 1] - BUMP_CENTRE[1]) ** 2
    return np.exp(-d2 / (2 * BUMP_SIGMA**2))


def bump_integral():
    s = BUMP_SIGMA * math.sqrt(2.0)
    one = [0.5 * math.sqrt(math.pi) * s * (math.erf((1 - c) / s) + math.erf(c / s)) for c in BUMP_CENTRE]
    return one[0] * one[1]


def quarter_disk(p):
    return ((p[..., 0] ** 2 + p[..., 1] ** 2) < 0.5).astype(np.float64)


def test_sobol_estimates_are_unbiased(sobol):
    """The mean over 8192 pixels (independent scrambles) of the 16-sample estimate equals the true
    integral, by a z-test whose standard error is the spread of the estimates over pixels: a smooth
    bump and a discontinuous quarter disk (get2d), u^3 (get1d), and the product of two dimension
    ids, E[u_a u_b] = 1/4 (padding must not correlate them)."""
    n_pix, n = 8192, 16
    p2 = draw(sobol, n_pix, n, dims.bounce(1, dims.BSDF_DIRECTION), 0, 11, GET2D).astype(np.float64)
    p1 = draw(sobol, n_pix, n, dims.bounce(0, dims.BSDF_LOBE), dims.bounce(0, dims.ROULETTE), 11,
              GET1D_PAIR).astype(np.float64)
    cases = {"bump": (bump(p2), bump_integral()), "quarter disk": (quarter_disk(p2), math.pi / 8),
             "u^3": (p1[..., 0] ** 3, 0.25), "u_a u_b": (p1[..., 0] * p1[..., 1], 0.25)}
    critical = stats.norm.ppf(1 - sidak(len(cases)) / 2)
    for name, (values, truth) in cases.items():
        estimates = values.mean(axis=1)
        z = (estimates.mean() - truth) / (estimates.std(ddof=1) / math.sqrt(n_pix))
        assert abs(z) < critical, f"{name}: mean {estimates.mean()} vs {truth} (z = {z:.2f})"


def rms_error_slope(points, ks):
    """Least-squares slope of log2(RMS error over pixels) against log2(N) for N = 2^k: each pixel's
    estimate uses its first N samples (a progressive render)."""
    values = bump(points.astype(np.float64))
    truth = bump_integral()
    rms = [math.sqrt(np.mean((values[:, : 2**k].mean(axis=1) - truth) ** 2)) for k in ks]
    return np.polyfit(ks, np.log2(rms), 1)[0], rms


CONVERGENCE = {}


def test_convergence_rates(sobol, independent):
    """RMS error over 1024 pixels of a smooth 2D integral with N = 2^4 .. 2^10 samples.

    Independent sampling: RMS = sigma / sqrt(N), slope -1/2. The RMS over P = 1024 pixels has a
    relative standard error of about 1/sqrt(2P) = 2.2% (error of a Gaussian sample's RMS), i.e.
    0.03 in log2 at each k, so the fitted slope over k = 4..10 has a standard error near 0.01:
    the +-0.1 band is ~10 standard errors wide, and a flatter or steeper slope is a real defect.
    Scrambled (0,2)-nets: Owen's variance bound gives RMS ~ N^-1.5 (times log factors) for smooth
    integrands; -0.9 leaves room for the pre-asymptotic regime and still fails anything that
    only converges like random sampling (-0.5) or stratified-jitter-like in 1D."""
    ks = list(range(4, 11))
    n_pix = 1024
    s_slope, s_rms = rms_error_slope(draw(sobol, n_pix, 1024, dims.LENS, 0, 5, GET2D), ks)
    i_slope, i_rms = rms_error_slope(draw(independent, n_pix, 1024, dims.LENS, 0, 5, GET2D), ks)
    CONVERGENCE.update(sobol=s_slope, independent=i_slope)
    print(f"\nRMS error slopes: sobol {s_slope:.3f}, independent {i_slope:.3f}")
    print("N:", [2**k for k in ks])
    print("sobol RMS:", [f"{v:.2e}" for v in s_rms])
    print("independent RMS:", [f"{v:.2e}" for v in i_rms])
    assert s_slope < -0.9, s_slope
    assert abs(i_slope + 0.5) < 0.1, i_slope
    assert all(s < i for s, i in zip(s_rms, i_rms)), "Sobol must beat independent sampling at every N"


# --- end to end -----------------------------------------------------------------------------------
def test_render_with_sobol_matches_and_beats_independent(tmp_path):
    """A diffuse ball of albedo 0.5 on a floor of albedo 0.5 under a constant sky, 24 x 16 pixels,
    against an independent-sampler reference of 4096 spp.

    The scene is grey, so the three channels are identical: statistics use one channel (summing
    the three channels' variances as if independent would understate the variance threefold).
    Renders with different seeds are independent (independent scrambles), so the variance of a
    pixel's estimate is measured from its spread over K renders: valid for the Sobol sampler,
    whose within-pixel samples are not independent (the film's s^2/n overestimates its variance).

    Mean: the mean image of K = 8 Sobol renders at 16 spp equals the reference, by a z-test at ALPHA.
    Error: at 16 spp, the per-pixel MSE against the reference, averaged over the K renders, with
    the reference's own variance of the mean subtracted so that only the samplers' errors are
    compared. Measured ratio Sobol / independent: about 0.25; each render's MSE varies by 12-17%
    from seed to seed, so the mean of 8 is known to ~7% and the bound 0.5 is far from both the
    measured value and 1 (no gain).
    """
    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer
    from tests.scene_builder import furnace_toml, scene_from_toml

    body = furnace_toml(albedo=0.5)
    ball = '[materials.ball]\ntype = "diffuse"\nbase_color = [1.0, 1.0, 1.0]'
    assert ball in body
    scene = scene_from_toml(tmp_path, body.replace(ball, ball.replace("1.0", "0.5")))
    camera = CameraFrame.from_spec(scene.camera)
    r = Renderer(scene)
    r.render(camera, 4096, seed=1, sampler="independent")
    ref = r.image()[..., 0].astype(np.float64)
    ref_var = r.film.variance_of_mean_image()[..., 0].astype(np.float64)
    n = ref.size

    # Counter-based: 3 + 5 spp equal 8 spp bit for bit (sample indices continue across passes).
    r.reset()
    r.render(camera, 8, seed=6, sampler="sobol")
    one = r.image().copy()
    r.reset()
    r.render(camera, 3, seed=6, sampler="sobol")
    r.render(camera, 5, seed=6, sampler="sobol")
    assert np.array_equal(one, r.image())

    spp, k = 16, 8
    images = {}
    for name in ("independent", "sobol"):
        renders = []
        for seed in range(2, 2 + k):
            r.reset()
            r.render(camera, spp, seed=seed, sampler=name)
            assert r.film.stats()["rejected"] == 0
            renders.append(r.image()[..., 0].astype(np.float64))
        images[name] = np.array(renders)

    sobol = images["sobol"]
    mean = sobol.mean(axis=0)
    var_of_mean = sobol.var(axis=0, ddof=1) / k
    z = (mean.mean() - ref.mean()) / math.sqrt(var_of_mean.sum() / n**2 + ref_var.sum() / n**2)
    print(f"\nimage mean: sobol {mean.mean():.5f} ({k} x {spp} spp), independent reference {ref.mean():.5f} "
          f"(4096 spp), z = {z:.2f}")
    assert abs(z) < stats.norm.ppf(1 - ALPHA / 2), z

    mse = {name: float(np.mean((imgs - ref) ** 2) - ref_var.mean()) for name, imgs in images.items()}
    ratio = mse["sobol"] / mse["independent"]
    print(f"MSE at {spp} spp: independent {mse['independent']:.3e}, sobol {mse['sobol']:.3e}, ratio {ratio:.3f}")
    assert ratio < 0.5, ratio


# --- GPU back-ends ----------------------------------------------------------------------------------


@pytest.mark.vulkan
def test_vulkan_sobol_matches_reference_bit_for_bit():
    """All-u32 arithmetic: the Vulkan kernels give the same bits as the CPU and the numpy model
    (in a subprocess: a process holds one Taichi runtime, and the suite's is on the CPU)."""
    root = Path(__file__).resolve().parents[2]
    try:
        proc = subprocess.run([sys.executable, "-m", "tests.sampling.sobol_vulkan_child"], cwd=root,
                              capture_output=True, text=True, timeout=300)
    except subprocess.TimeoutExpired:
        pytest.skip("Vulkan start-up timed out")
    if proc.returncode == 3 or "vulkan" in proc.stderr.lower() and proc.returncode not in (0, 1):
        pytest.skip("no Vulkan driver")
    assert proc.returncode == 0, proc.stderr[-2000:]
