"""The chi-square harness itself: it accepts correct samplers and rejects subtly wrong ones.

Samplers here are numpy warps with fixed seeds, so every outcome is deterministic. Significance:
alpha = 0.01 with a Sidak correction over the NUM_TESTS chi-square tests in this file.
"""
import math

import numpy as np
import pytest

from tests.stats.chi2 import ENV_FRAME, chi2_test, integrate_pdf, sidak_alpha

ALPHA = 0.01
NUM_TESTS = 18  # chi-square tests run in this file (for the Sidak correction)
N = 1_000_000


def power_cosine(n, exponent, seed):
    """Directions with pdf (exponent + 1) / (2 pi) cos^exponent(theta) on the z-up hemisphere."""
    rng = np.random.default_rng(seed)
    u = rng.random((n, 2))
    z = u[:, 0] ** (1.0 / (exponent + 1.0))
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    phi = 2.0 * math.pi * u[:, 1]
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def cosine_pdf(d):
    return np.maximum(d[:, 2], 0.0) / math.pi


def power_cosine_pdf(exponent):
    return lambda d: (exponent + 1.0) / (2.0 * math.pi) * np.maximum(d[:, 2], 0.0) ** exponent


def uniform_sphere(n, seed):
    rng = np.random.default_rng(seed)
    u = rng.random((n, 2))
    z = 1.0 - 2.0 * u[:, 0]
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    phi = 2.0 * math.pi * u[:, 1]
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def check(result, tmp_path, name):
    if not result.passed:
        result.write_png(tmp_path / f"{name}.png")
    return result


def test_sidak_alpha():
    assert sidak_alpha(0.01, 1) == pytest.approx(0.01)
    assert sidak_alpha(0.01, 10) == pytest.approx(1.0 - 0.99 ** 0.1)
    assert sidak_alpha(0.01, 10) < 0.01 / 9.9  # a little above Bonferroni's 0.001
    with pytest.raises(ValueError):
        sidak_alpha(0.0, 3)


@pytest.mark.parametrize("seed", [1, 2, 3, 4, 5])
def test_accepts_cosine_hemisphere_across_seeds(seed, tmp_path):
    result = chi2_test(power_cosine(N, 1.0, seed), cosine_pdf, domain="hemisphere",
                       alpha=ALPHA, num_tests=NUM_TESTS)
    assert check(result, tmp_path, "cosine").passed, result.report
    assert result.pdf_integral == pytest.approx(1.0, abs=1e-6)
    assert result.observed.sum() == N and result.failed_count == 0


def test_accepts_uniform_sphere_in_another_frame(tmp_path):
    """Pole along +y with the environment map's phi: a uniform pdf does not care, but the binning
    and quadrature must map the frame consistently."""
    result = chi2_test(uniform_sphere(N, 7), lambda d: np.full(len(d), 1.0 / (4.0 * math.pi)),
                       frame=ENV_FRAME, alpha=ALPHA, num_tests=NUM_TESTS)
    assert check(result, tmp_path, "uniform").passed, result.report


def test_accepts_lobe_about_a_tilted_pole(tmp_path):
    """A cos^8 lobe whose pole is +y, tested in ENV_FRAME (rows: -z, +x, +y)."""
    d = power_cosine(N, 8.0, 11)[:, [1, 2, 0]]  # local (x, y, z) -> world (z, x, y): pole +y
    pdf = lambda w: 9.0 / (2.0 * math.pi) * np.maximum(w[:, 1], 0.0) ** 8
    result = chi2_test(d, pdf, frame=ENV_FRAME, domain="hemisphere", alpha=ALPHA, num_tests=NUM_TESTS)
    assert check(result, tmp_path, "lobe").passed, result.report


def test_rejects_wrong_exponent():
    """cos^1.05 samples against the cosine pdf: a 5 % error in the exponent."""
    result = chi2_test(power_cosine(N, 1.05, 1), cosine_pdf, domain="hemisphere",
                       alpha=ALPHA, num_tests=NUM_TESTS)
    assert not result.passed, result.report
    assert not result.messages  # rejected by the statistic, not by a sanity check


def test_rejects_uniform_against_cosine():
    result = chi2_test(power_cosine(N, 0.0, 1), cosine_pdf, domain="hemisphere",
                       alpha=ALPHA, num_tests=NUM_TESTS)
    assert not result.passed and result.p_value < 1e-100, result.report


def test_rejects_a_pdf_that_does_not_integrate_to_one():
    result = chi2_test(power_cosine(N, 1.0, 1), lambda d: 1.02 * cosine_pdf(d), domain="hemisphere",
                       alpha=ALPHA, num_tests=NUM_TESTS)
    assert not result.passed
    assert any("integrates to" in m for m in result.messages), result.report


def test_samples_where_the_pdf_is_zero_fail():
    """A hemisphere sampler that leaks 50 samples below the horizon."""
    d = power_cosine(N, 1.0, 1)
    d[:50, 2] *= -1.0
    result = chi2_test(d, cosine_pdf, domain="hemisphere", alpha=ALPHA, num_tests=NUM_TESTS)
    assert not result.passed and result.out_of_domain == 50
    assert any("expected count is 0" in m for m in result.messages), result.report


def lossy_cosine(n, fail_phi, seed):
    """Cosine samples that fail when phi < fail_phi (like a reflected microfacet direction below
    the horizon); the pdf of the successful ones integrates to 1 - fail_phi / (2 pi)."""
    d = power_cosine(n, 1.0, seed)
    phi = np.mod(np.arctan2(d[:, 1], d[:, 0]), 2.0 * math.pi)
    return d, phi >= fail_phi


def lossy_pdf(fail_phi):
    def pdf(d):
        phi = np.mod(np.arctan2(d[:, 1], d[:, 0]), 2.0 * math.pi)
        return np.where(phi >= fail_phi, cosine_pdf(d), 0.0)
    return pdf


def test_accepts_a_lossy_sampler(tmp_path):
    fail_phi = 0.1 * 2.0 * math.pi  # inside a cell: passed as a break so the quadrature is exact
    d, ok = lossy_cosine(N, fail_phi, 3)
    result = chi2_test(d, lossy_pdf(fail_phi), valid=ok, lossy=True, domain="hemisphere",
                       phi_breaks=[fail_phi], alpha=ALPHA, num_tests=NUM_TESTS)
    assert check(result, tmp_path, "lossy").passed, result.report
    assert result.pdf_integral == pytest.approx(0.9, abs=1e-6)
    assert result.expected_failed == pytest.approx(0.1 * N, rel=1e-5)


def test_rejects_a_lossy_sampler_that_fails_too_often():
    """The sampler fails on 11 % of samples, but its pdf accounts for 10 % only."""
    d, ok = lossy_cosine(N, 0.11 * 2.0 * math.pi, 3)
    result = chi2_test(d, lossy_pdf(0.1 * 2.0 * math.pi), valid=ok, lossy=True, domain="hemisphere",
                       phi_breaks=[0.1 * 2.0 * math.pi], alpha=ALPHA, num_tests=NUM_TESTS)
    assert not result.passed and not result.messages, result.report
    assert result.failed_count > 0.105 * N


def test_lossless_sampler_must_not_fail():
    d = power_cosine(N, 1.0, 4)
    ok = np.ones(N, bool)
    ok[:20] = False
    result = chi2_test(d, cosine_pdf, valid=ok, domain="hemisphere", alpha=ALPHA, num_tests=NUM_TESTS)
    assert not result.passed and result.failed_count == 20, result.report


def mirror_plus_diffuse(n, p_delta, seed):
    rng = np.random.default_rng(seed + 100)
    d = power_cosine(n, 1.0, seed)
    is_delta = rng.random(n) < p_delta
    d[is_delta] = [0.0, 0.0, 1.0]  # the specular direction: not binned
    return d, is_delta


def test_delta_component(tmp_path):
    d, is_delta = mirror_plus_diffuse(N, 0.3, 5)
    pdf = lambda w: 0.7 * cosine_pdf(w)
    good = chi2_test(d, pdf, delta=is_delta, delta_probability=0.3, domain="hemisphere",
                     alpha=ALPHA, num_tests=NUM_TESTS)
    assert check(good, tmp_path, "delta").passed, good.report
    assert good.delta_count == np.count_nonzero(is_delta)
    # the caller claims the wrong delta probability (and a matching continuous part)
    bad = chi2_test(d, lambda w: 0.71 * cosine_pdf(w), delta=is_delta, delta_probability=0.29,
                    domain="hemisphere", alpha=ALPHA, num_tests=NUM_TESTS)
    assert not bad.passed and not bad.messages, bad.report


def test_pooling_with_few_samples(tmp_path):
    """1,000 samples in 128 cells: the cells near the horizon expect fewer than 5 and are pooled."""
    good = chi2_test(power_cosine(1000, 1.0, 6), cosine_pdf, domain="hemisphere", res=8,
                     alpha=ALPHA, num_tests=NUM_TESTS)
    assert check(good, tmp_path, "few").passed, good.report
    assert good.pooled_categories > 10 and good.dof >= 50
    bad = chi2_test(power_cosine(1000, 0.0, 6), cosine_pdf, domain="hemisphere", res=4,
                    alpha=ALPHA, num_tests=NUM_TESTS)
    assert not bad.passed and not bad.messages, bad.report
    # 1,000 samples in 2048 cells: everything pools into one category, and that is not a pass
    nothing = chi2_test(power_cosine(1000, 1.0, 6), cosine_pdf, domain="hemisphere")
    assert not nothing.passed and "nothing to test" in nothing.report


def test_breaks_make_piecewise_constant_pdfs_exact():
    """A pdf with a jump inside cells integrates exactly once the jump is passed as a break."""
    theta_jump, phi_jump = 0.3, 1.0

    def pdf(d):
        theta = np.arccos(np.clip(d[:, 2], -1, 1))
        phi = np.mod(np.arctan2(d[:, 1], d[:, 0]), 2 * math.pi)
        return np.where((theta < theta_jump) & (phi < phi_jump), 5.0, 0.0)

    exact = 5.0 * phi_jump * (1.0 - math.cos(theta_jump))
    with_breaks = integrate_pdf(pdf, subdivisions=1, phi_breaks=[phi_jump], theta_breaks=[theta_jump])
    without = integrate_pdf(pdf, subdivisions=1)
    assert with_breaks.sum() == pytest.approx(exact, rel=1e-10)
    assert abs(without.sum() - exact) > 1e-4 * exact
    with pytest.raises(ValueError, match="negative"):
        integrate_pdf(lambda d: d[:, 2])


def test_png(tmp_path):
    result = chi2_test(power_cosine(10_000, 0.0, 1), cosine_pdf, domain="hemisphere", res=8)
    path = result.write_png(tmp_path / "hist.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "FAIL" in result.report
