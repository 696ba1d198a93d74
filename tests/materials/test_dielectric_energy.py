"""Multiple-scattering compensation of rough dielectric interfaces (renderer/materials/dielectric_energy.py).

- The tables against an independent estimate: R(mu) and T(mu) by Monte Carlo in numpy (float64)
  with Walter et al.'s half-vector sampling (D(h) cos theta_h, not the renderer's visible-normal
  sampler) and their own BRDF/BTDF formulas, at nodes and between nodes (the interpolation).
- White furnace per interface: the compensated lobe's sample weights, in energy units
  (transmission times eta^2), average to E_ss(mu) + (1 - E_table(mu)), i.e. 1 up to the table's
  error, from outside and from inside (total internal reflection included), where single scattering
  loses up to half.
- The compensated lobe is sampled as its pdf says (chi-square), sample weights average to the
  integral of eval, reflection is reciprocal and transmission obeys generalised reciprocity
  (f(o, i) / n_i^2 = f(i, o) / n_o^2).
- The principled coat layering: a white base under a rough coat returns exactly what the coat
  does not reflect.

Significance: ALPHA = 0.01 family-wise over the statistical tests of this file, Sidak-corrected.
"""
import dataclasses
import math

import numpy as np
import pytest
from scipy import stats

from renderer.materials import dielectric_energy as de
from renderer.scene.description import MaterialSpec
from tests.materials.bsdf_kernels import (ALL_KINDS, BsdfBench, cell_probabilities, chi2_adaptive, direction,
                                          frame_about, uniforms)
from tests.stats.chi2 import sidak_alpha

ALPHA = 0.01
N = 1_000_000
MC_SAMPLES = 2_000_000
# (roughness, ior, cos, side) where the table is checked against the independent estimate.
TABLE_CASES = [(0.3, 1.5, 0.8, 0), (0.6, 1.5, 0.3, 0), (1.0, 1.33, 0.6, 0), (0.45, 2.4, 0.5, 0),
               (0.3, 1.5, 0.8, 1), (0.6, 1.5, 0.5, 1), (1.0, 1.7, 0.9, 1), (0.2, 1.5, 0.95, 1)]
FURNACE_CASES = [(r, ior, cos, side) for r in (0.3, 0.7, 1.0) for ior, cos, side in
                 ((1.5, 0.9, 0), (1.5, 0.2, 0), (1.5, 0.9, 1), (1.5, 0.6, 1), (2.4, 0.5, 0))]
CHI2_CASES = [(0.3, 0.8, 0), (0.8, 0.4, 0), (0.5, 0.9, 1), (1.0, 0.3, 1)]
UNBIASED_CASES = [(0.5, 0.7, 0), (0.9, 0.5, 1)]
NUM_TESTS = 2 * len(TABLE_CASES) + len(FURNACE_CASES) + len(CHI2_CASES) + len(UNBIASED_CASES) + 1
LEVEL = sidak_alpha(ALPHA, NUM_TESTS)
# What interpolating the table may cost (the node spacing in sqrt(mu), sqrt(roughness) and x
# against the curvature of E): checked between nodes below; the furnace expectation carries it.
INTERPOLATION_TOLERANCE = 3e-3


@pytest.fixture(scope="module")
def table():
    return de.load_table()


@pytest.fixture(scope="module")
def bench():
    return BsdfBench(capacity=32, features=dataclasses.replace(ALL_KINDS, energy_compensation=True))


def glass(roughness, ior, tint=(1.0, 1.0, 1.0)):
    return MaterialSpec(name="glass", kind="dielectric", base_color=tint, roughness=roughness, ior=ior)


def z_check(samples, expected, what, expected_se=0.0):
    samples = np.asarray(samples, np.float64)
    se = math.hypot(samples.std(ddof=1) / math.sqrt(len(samples)), expected_se)
    z = (samples.mean() - expected) / se
    p = 2.0 * stats.norm.sf(abs(z))
    assert p >= LEVEL, f"{what}: mean {samples.mean():.6f} vs {expected:.6f} (se {se:.1e}), z = {z:.2f}"
    return samples.mean(), se


# --- an independent estimate of R(mu) and T(mu) ------------------------------------------------------
def _lambda(cos2, alpha):
    return 0.5 * (np.sqrt(1.0 + alpha * alpha * (1.0 - cos2) / np.maximum(cos2, 1e-300)) - 1.0)


def _fresnel(c, eta):
    """Unpolarised Fresnel reflectance for cos c (> 0) on the incident side, eta = n_t / n_i."""
    s2 = (1.0 - c * c) / (eta * eta)
    ct = np.sqrt(np.maximum(1.0 - s2, 0.0))
    rs = (c - eta * ct) / (c + eta * ct)
    rp = (eta * c - ct) / (eta * c + ct)
    return np.where(s2 >= 1.0, 1.0, 0.5 * (rs * rs + rp * rp)), ct


def walter_estimate(roughness, eta, mu, n, seed):
    """Per-sample estimates (R, T) of the energy a white rough interface reflects and transmits
    for wo at cos mu, eta = n_far / n_near, single scattering, height-correlated Smith G2.
    Half vectors from D(h) cos theta_h (Walter et al. 2007, eq. 35); the weights are f |cos| / pdf
    of each lobe in energy units, so E[R] + E[T] is the interface's energy albedo."""
    alpha = roughness * roughness
    rng = np.random.default_rng(seed)
    u1, u2 = rng.random(n), rng.random(n)
    tan2 = alpha * alpha * u1 / (1.0 - u1)
    ch = 1.0 / np.sqrt(1.0 + tan2)
    sh = np.sqrt(np.maximum(0.0, 1.0 - ch * ch))
    phi = 2.0 * np.pi * u2
    h = np.stack([sh * np.cos(phi), sh * np.sin(phi), ch], axis=1)
    wo = np.array([math.sqrt(1.0 - mu * mu), 0.0, mu])
    oh = h @ wo
    ok = oh > 0.0
    f, ct = _fresnel(np.clip(oh, 1e-12, 1.0), eta)
    lam_o = _lambda(mu * mu, alpha)
    # weight = F G2 (wo.h) / (mu cos theta_h) for both lobes (Walter's pdf and Jacobians cancel
    # the same way for reflection and, in energy units, for refraction).
    common = oh / (mu * ch)
    wr = 2.0 * oh[:, None] * h - wo  # reflection
    wt = (oh / eta - ct)[:, None] * h - wo / eta  # refraction (Snell, vector form)
    g_r = 1.0 / (1.0 + lam_o + _lambda(wr[:, 2] ** 2, alpha))
    g_t = 1.0 / (1.0 + lam_o + _lambda(wt[:, 2] ** 2, alpha))
    r = np.where(ok & (wr[:, 2] > 0.0), f * g_r * common, 0.0)
    t = np.where(ok & (wt[:, 2] < 0.0) & (f < 1.0), (1.0 - f) * g_t * common, 0.0)
    return r, t


@pytest.mark.parametrize("roughness,ior,cos,side", TABLE_CASES)
def test_table_matches_an_independent_estimate(table, roughness, ior, cos, side):
    """Between nodes in every coordinate: this is the table's whole error, generation and
    interpolation, against an estimator that shares no code with it. (Inside, R and T each jump
    at the critical angle, too steeply for the nodes; their sum, all the compensation uses from
    that side, stays smooth.)"""
    eta = ior if side == 0 else 1.0 / ior
    r, t = walter_estimate(roughness, eta, cos, MC_SAMPLES, seed=hash((roughness, ior, cos, side)) % 2**32)
    looked_r = float(de.albedo_lookup(table, "reflect", side, np.array(cos), np.array(roughness), np.array(ior)))
    looked_e = float(de.albedo_lookup(table, "albedo", side, np.array(cos), np.array(roughness), np.array(ior)))
    checks = [("R + T", r + t, looked_e)]
    if side == 0:  # R alone is used only from outside (the principled coat's layering)
        checks.append(("R", r, looked_r))
    for what, samples, value in checks:
        mean = samples.mean()
        se = samples.std(ddof=1) / math.sqrt(len(samples))
        # Equivalence within the interpolation tolerance, tested at the stated level.
        excess = max(abs(mean - value) - INTERPOLATION_TOLERANCE, 0.0) / se
        assert 2.0 * stats.norm.sf(excess) >= LEVEL, (
            f"{what} at r {roughness}, ior {ior}, cos {cos}, side {side}: table {value:.5f}, "
            f"estimate {mean:.5f} +- {se:.1e}")


def test_cosine_averages_are_integrals_of_the_lookup(table):
    """Eavg must be the integral of what the device interpolates, or the lobe does not return
    exactly what single scattering lost."""
    x, w = np.polynomial.legendre.leggauss(64)
    edges = np.linspace(0.0, 1.0, table["albedo"].shape[-1])
    for roughness, ior, side in ((0.33, 1.5, 0), (0.71, 1.9, 1), (1.0, 1.33, 0)):
        total = 0.0
        for a, b in zip(edges[:-1], edges[1:]):
            xs = a + (b - a) * 0.5 * (x + 1.0)
            e = de.albedo_lookup(table, "albedo", side, xs ** 2, np.full_like(xs, roughness), np.full_like(xs, ior))
            total += 0.5 * (b - a) * np.sum(w * e * 4.0 * xs ** 3)
        average = float(de.average_lookup(table, "average", np.array(roughness), np.array(ior), side))
        assert abs(average - total) < 1e-9


@pytest.mark.parametrize("roughness,ior,cos,side", FURNACE_CASES)
def test_white_interface_keeps_its_energy(bench, table, roughness, ior, cos, side):
    """Energy weights of the compensated sampler average to E_ss + (1 - E_table): 1 up to the
    table's error (the independent estimate of E_ss enters with its own standard error)."""
    eta = ior if side == 0 else 1.0 / ior
    normal = np.array([0.0, 0.0, 1.0 if side == 0 else -1.0])
    mat = bench.material(glass(roughness, ior))
    s = bench.sample(mat, normal, direction(cos), uniforms(N, 700 + FURNACE_CASES.index((roughness, ior, cos, side))))
    transmitted = s.wi[:, 2] < 0.0  # wo = direction(cos) has z > 0: the other side is z < 0
    energy = np.where(s.valid, s.weight[:, 1] * np.where(transmitted, eta * eta, 1.0), 0.0)
    r, t = walter_estimate(roughness, eta, cos, MC_SAMPLES, seed=800 + FURNACE_CASES.index((roughness, ior, cos, side)))
    single = (r + t).mean()
    single_se = (r + t).std(ddof=1) / math.sqrt(len(r))
    table_e = float(de.albedo_lookup(table, "albedo", side, np.array(cos), np.array(roughness), np.array(ior)))
    assert single < 0.999 or roughness < 0.5  # the test is not vacuous: single scattering loses light
    z_check(energy, single + 1.0 - table_e, f"r {roughness} ior {ior} cos {cos} side {side}", single_se)


@pytest.mark.parametrize("roughness,cos,side", CHI2_CASES)
def test_compensated_glass_samples_follow_its_pdf(bench, roughness, cos, side):
    frame = frame_about([0.2, -0.1, 0.95])
    normal = frame[2] if side == 0 else -frame[2]
    wo = direction(cos) @ frame * (1.0 if side == 0 else -1.0)
    mat = bench.material(glass(roughness, 1.5, tint=(0.9, 0.8, 0.7)))
    s = bench.sample(mat, normal, wo, uniforms(N, 750 + CHI2_CASES.index((roughness, cos, side))))
    result = chi2_adaptive(s.wi, bench.pdf_callable(mat, normal, wo), frame=frame, valid=s.valid, lossy=True,
                           domain="sphere", alpha=ALPHA, num_tests=NUM_TESTS)
    assert result.passed, result.report


@pytest.mark.parametrize("roughness,cos,side", UNBIASED_CASES)
def test_sample_weights_average_to_the_integral_of_eval(bench, roughness, cos, side):
    frame = frame_about([0.1, -0.3, 0.9])
    normal = frame[2] if side == 0 else -frame[2]
    wo = direction(cos) @ frame * (1.0 if side == 0 else -1.0)
    mat = bench.material(glass(roughness, 1.5, tint=(0.9, 0.8, 0.7)))
    s = bench.sample(mat, normal, wo, uniforms(N, 780 + UNBIASED_CASES.index((roughness, cos, side))))
    integral = cell_probabilities(lambda d: bench.eval(mat, normal, wo, d)[0].astype(np.float64).mean(axis=1),
                                  frame=frame, abs_tol=1e-9).sum()
    z_check(np.where(s.valid, s.weight.mean(axis=1), 0.0), integral, f"r {roughness} cos {cos} side {side}")


def _random_pairs(rng, n):
    a = rng.normal(size=(n, 3))
    b = rng.normal(size=(n, 3))
    return a / np.linalg.norm(a, axis=1, keepdims=True), b / np.linalg.norm(b, axis=1, keepdims=True)


def test_compensated_glass_is_reciprocal(bench):
    """Reflection: f(a, b) = f(b, a). Transmission: f(wo, wi) / n_o^2 = f(wi, wo) / n_i^2 (Veach
    1997, 5.2; n on the side of each direction), with the outward normal +z (outside n = 1,
    inside n = ior)."""
    ior = 1.5
    rng = np.random.default_rng(78)
    n = 100_000
    mat = bench.material(glass(0.7, ior, tint=(0.9, 0.8, 0.7)))
    normal = np.broadcast_to(np.array([0.0, 0.0, 1.0]), (n, 3))
    a, b = _random_pairs(rng, n)
    ok = (np.abs(a[:, 2]) > 1e-2) & (np.abs(b[:, 2]) > 1e-2)
    f_ab = bench.eval(mat, normal, a, b)[0] / np.abs(b[:, 2:3])
    f_ba = bench.eval(mat, normal, b, a)[0] / np.abs(a[:, 2:3])
    index_a = np.where(a[:, 2] > 0.0, 1.0, ior)[:, None]
    index_b = np.where(b[:, 2] > 0.0, 1.0, ior)[:, None]
    np.testing.assert_allclose((f_ab / index_a ** 2)[ok], (f_ba / index_b ** 2)[ok], rtol=5e-4, atol=1e-6)


def test_white_base_under_a_coat_returns_what_the_coat_lets_through(bench, table):
    """Principled, metallic 0, transmission 0, white base: coat reflection plus the layered base
    is 1 up to the table's error, where the smooth-Fresnel form lost the light the coat reflects
    back down (about 10% at ior 1.5)."""
    mat = bench.material(MaterialSpec(name="coated", kind="principled", base_color=(1.0, 1.0, 1.0), roughness=0.5,
                                      metallic=0.0, transmission=0.0, ior=1.5))
    s = bench.sample(mat, [0.0, 0.0, 1.0], direction(0.6), uniforms(N, 790))
    r, _ = walter_estimate(0.5, 1.5, 0.6, MC_SAMPLES, seed=791)
    table_r = float(de.albedo_lookup(table, "reflect", 0, np.array(0.6), np.array(0.5), np.array(1.5)))
    z_check(np.where(s.valid, s.weight[:, 1], 0.0), r.mean() + 1.0 - table_r, "coated white base",
            r.std(ddof=1) / math.sqrt(len(r)))
