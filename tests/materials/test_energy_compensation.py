"""Kulla-Conty energy compensation of GGX reflection (renderer/materials/energy.py).

- The albedo table against an independent quadrature (tests/materials/ggx_reference.py), at its
  nodes (the generator's accuracy) and between them (the interpolation's).
- White furnace: a white rough conductor with compensation returns E_ss(mu) + (1 - E_table(mu)),
  i.e. 1 up to the table's error, by z-test on the mean sample weight, where without compensation
  it loses up to 69% (tests/materials/test_bsdf_properties.py).
- The compensated lobes are sampled as their pdf says (chi-square), sample weights average to the
  integral of eval, f is reciprocal, and a coloured metal stays below the white one.

Significance: ALPHA = 0.01 family-wise over every statistical test in this file, Sidak-corrected.
"""
import dataclasses
import math

import numpy as np
import pytest
from scipy import stats

from renderer.materials import energy
from renderer.scene.description import MaterialSpec
from tests.materials.bsdf_kernels import (ALL_KINDS, BsdfBench, cell_probabilities, chi2_adaptive, direction,
                                          frame_about, uniforms)
from tests.materials.ggx_reference import ggx_albedo_reference
from tests.stats.chi2 import sidak_alpha

ALPHA = 0.01
N = 1_000_000
FURNACE_ROUGHNESS = (0.1, 0.3, 0.6, 1.0)
FURNACE_COS = (1.0, 0.5, 0.1, 0.02)
CHI2_CASES = ([(kind, r, cos) for kind in ("conductor", "metal") for r in (0.2, 0.6, 1.0) for cos in (0.9, 0.3)]
              + [("complex", 0.6, 0.3)])
UNBIASED_CASES = [("conductor", 0.5, 0.7), ("metal", 0.8, 0.4), ("complex", 0.5, 0.7)]
NUM_TESTS = len(FURNACE_ROUGHNESS) * len(FURNACE_COS) + len(CHI2_CASES) + len(UNBIASED_CASES)

# The table's own accuracy at its nodes (a 1024^2 midpoint rule over the sampler's uniforms; the
# largest difference from the quadrature is 3e-4, at roughness ~0.13 head-on where the lobe is
# narrowest), and between nodes (bilinear in sqrt(mu), sqrt(roughness)): see the tests below.
NODE_TOLERANCE = 5e-4


@pytest.fixture(scope="module")
def table():
    return energy.load_table()


@pytest.fixture(scope="module")
def bench():
    return BsdfBench(capacity=32, features=dataclasses.replace(ALL_KINDS, energy_compensation=True))


def white_conductor(roughness):
    return MaterialSpec(name="white", kind="conductor", base_color=(1.0, 1.0, 1.0), roughness=roughness)


def spec_of(kind, roughness):
    if kind == "complex":  # exact Fresnel from a named metal's complex index; F_avg from the row
        return MaterialSpec(name="copper", kind="conductor", metal="Cu", roughness=roughness)
    if kind == "conductor":
        return MaterialSpec(name="gold", kind="conductor", base_color=(1.0, 0.78, 0.34), roughness=roughness,
                            edge_tint=(0.9, 0.8, 0.6))
    return MaterialSpec(name="metal", kind="principled", base_color=(0.95, 0.64, 0.54), roughness=roughness,
                        metallic=1.0)


def z_test(samples, expected, what):
    samples = np.asarray(samples, np.float64)
    se = samples.std(ddof=1) / math.sqrt(len(samples))
    z = (samples.mean() - expected) / se
    p = 2.0 * stats.norm.sf(abs(z))
    assert p >= sidak_alpha(ALPHA, NUM_TESTS), f"{what}: mean {samples.mean():.6f} vs {expected:.6f}, z = {z:.2f}"
    return samples.mean(), se


def test_table_matches_the_quadrature_at_its_nodes(table):
    size = table["albedo"].shape[0]
    nodes = np.linspace(0.0, 1.0, size) ** 2
    worst = 0.0
    for i in range(1, size, 3):
        alpha = max(nodes[i] ** 2, 1e-4)
        for j in range(1, size, 3):
            worst = max(worst, abs(table["albedo"][i, j] - ggx_albedo_reference(alpha, nodes[j])))
    assert worst < NODE_TOLERANCE, worst


def test_interpolated_albedo_stays_close_between_nodes(table):
    """Between nodes the lookup is within 0.5% of the truth from roughness 0.1 up (the grazing dip
    of a near-mirror moves fast with roughness, and is where the error peaks)."""
    worst = 0.0
    for roughness in np.linspace(0.1, 1.0, 12):
        for mu in (0.003, 0.01, 0.03, 0.07, 0.15, 0.3, 0.55, 0.8, 0.97):
            truth = ggx_albedo_reference(roughness * roughness, mu)
            worst = max(worst, abs(float(energy.albedo_lookup(table, np.array(mu), np.array(roughness))) - truth))
    assert worst < 5e-3, worst


def test_cosine_average_is_the_integral_of_the_lookup(table):
    """E_avg must be the integral of what the kernel interpolates, or the lobe does not return
    exactly the energy single scattering lost."""
    x, w = np.polynomial.legendre.leggauss(64)
    for roughness in (0.05, 0.3, 0.77, 1.0):
        total = 0.0
        edges = np.linspace(0.0, 1.0, table["albedo"].shape[0])  # x = sqrt(mu): E is linear in x between
        for a, b in zip(edges[:-1], edges[1:]):
            xs = a + (b - a) * 0.5 * (x + 1.0)
            e = energy.albedo_lookup(table, xs ** 2, np.full_like(xs, roughness))
            total += 0.5 * (b - a) * np.sum(w * e * 4.0 * xs ** 3)
        assert abs(float(energy.average_lookup(table, np.array(roughness))) - total) < 2e-3 * (1.0 - total) + 1e-6


@pytest.mark.parametrize("roughness", FURNACE_ROUGHNESS)
def test_white_furnace_keeps_the_energy(bench, table, roughness, record_property):
    mat = bench.material(white_conductor(roughness))
    report = []
    for k, cos in enumerate(FURNACE_COS):
        single = ggx_albedo_reference(roughness * roughness, cos)
        added = 1.0 - float(energy.albedo_lookup(table, np.array(cos), np.array(roughness)))
        expected = single + added
        assert abs(expected - 1.0) < 5e-3  # what is left is the table's error
        s = bench.sample(mat, [0.0, 0.0, 1.0], direction(cos), uniforms(N, 900 + 10 * k + FURNACE_ROUGHNESS.index(roughness)))
        mean, se = z_test(np.where(s.valid, s.weight[:, 0], 0.0), expected, f"roughness {roughness}, cos {cos}")
        report.append(f"cos {cos}: {mean:.4f} +- {se:.4f} (single scattering {single:.4f})")
    record_property("furnace", "; ".join(report))
    print(f"roughness {roughness}: " + "; ".join(report))


@pytest.mark.parametrize("kind,roughness,cos", CHI2_CASES, ids=[f"{k}-r{r}-cos{c}" for k, r, c in CHI2_CASES])
def test_compensated_sampling_matches_its_pdf(bench, kind, roughness, cos):
    frame = frame_about([0.2, -0.1, 0.95])
    wo = direction(cos) @ frame
    normal = frame[2]
    mat = bench.material(spec_of(kind, roughness))
    s = bench.sample(mat, normal, wo, uniforms(N, 950 + CHI2_CASES.index((kind, roughness, cos))))
    result = chi2_adaptive(s.wi, bench.pdf_callable(mat, normal, wo), frame=frame, valid=s.valid, lossy=True,
                           domain="sphere", alpha=ALPHA, num_tests=NUM_TESTS)
    assert result.passed, result.report


@pytest.mark.parametrize("kind,roughness,cos", UNBIASED_CASES)
def test_sample_weights_average_to_the_integral_of_eval(bench, kind, roughness, cos):
    frame = frame_about([0.1, -0.3, 0.9])
    wo = direction(cos) @ frame
    mat = bench.material(spec_of(kind, roughness))
    s = bench.sample(mat, frame[2], wo, uniforms(N, 980 + UNBIASED_CASES.index((kind, roughness, cos))))
    integral = cell_probabilities(lambda d: bench.eval(mat, frame[2], wo, d)[0].astype(np.float64).mean(axis=1),
                                  frame=frame, abs_tol=1e-9).sum()
    z_test(np.where(s.valid, s.weight.mean(axis=1), 0.0), integral, f"{kind} r {roughness} cos {cos}")


@pytest.mark.parametrize("kind", ["conductor", "metal"])
def test_compensated_reflection_is_reciprocal(bench, kind):
    rng = np.random.default_rng(77)
    n = 100_000
    mat = bench.material(spec_of(kind, 0.7))
    normal = np.broadcast_to(np.array([0.0, 0.0, 1.0]), (n, 3))
    a = rng.normal(size=(n, 3))
    b = rng.normal(size=(n, 3))
    a = a / np.linalg.norm(a, axis=1, keepdims=True) * np.sign(a[:, 2:3])
    b = b / np.linalg.norm(b, axis=1, keepdims=True) * np.sign(b[:, 2:3])
    ok = (a[:, 2] > 1e-2) & (b[:, 2] > 1e-2)  # eval's own float32 cosine divides out exactly only off the horizon
    f_ab = bench.eval(mat, normal, a, b)[0] / b[:, 2:3]
    f_ba = bench.eval(mat, normal, b, a)[0] / a[:, 2:3]
    np.testing.assert_allclose(f_ab[ok], f_ba[ok], rtol=2e-4, atol=1e-6)


def test_compensation_never_creates_energy_for_coloured_metals(bench):
    """A coloured metal (every channel of F0 below 1) stays below 1, and compensation raises its
    albedo (the multiple-scattering lobe adds, it never subtracts). Both margins are tens of
    standard errors at these roughnesses, so a plain comparison decides."""
    plain = BsdfBench(capacity=4)
    for roughness in (0.6, 1.0):
        spec = MaterialSpec(name="brass", kind="conductor", base_color=(0.9, 0.7, 0.3), roughness=roughness,
                            edge_tint=(0.9, 0.8, 0.6))
        for cos in (0.9, 0.2):
            u = uniforms(200_000, 990)
            comp = bench.sample(bench.material(spec), [0.0, 0.0, 1.0], direction(cos), u)
            single = plain.sample(plain.material(spec), [0.0, 0.0, 1.0], direction(cos), u)
            e_comp = np.where(comp.valid[:, None], comp.weight, 0.0).mean(axis=0)
            e_single = np.where(single.valid[:, None], single.weight, 0.0).mean(axis=0)
            assert (e_comp < 0.95).all() and (e_comp > e_single * 1.02).all(), (roughness, cos, e_comp, e_single)


def test_complex_index_mirror_compensates_like_the_white_conductor(bench):
    """eta = 0, k = 1 reflects everything (F = 1 exactly, and its stored F_avg is 1), so with the same
    uniforms it must return exactly what the white base_color conductor returns: the
    multiple-scattering lobe gets the row's F_avg (a missing one would drop the lobe)."""
    for roughness in (0.4, 1.0):
        mirror = MaterialSpec(name="mirror", kind="conductor", eta=(0.0, 0.0, 0.0), k=(1.0, 1.0, 1.0),
                              roughness=roughness)
        u = uniforms(100_000, 995)
        a = bench.sample(bench.material(mirror), [0.0, 0.0, 1.0], direction(0.4), u)
        b = bench.sample(bench.material(white_conductor(roughness)), [0.0, 0.0, 1.0], direction(0.4), u)
        np.testing.assert_array_equal(a.valid, b.valid)
        np.testing.assert_allclose(a.weight[a.valid], b.weight[b.valid], rtol=1e-6)
        assert a.weight[a.valid].mean() > 0.99  # compensated: not the single-scattering loss


def test_only_scenes_with_rough_microfacet_materials_compile_compensation():
    """Rough conductors and dielectrics need it; principled materials always (their coat layering);
    smooth glass, mirrors and diffuse surfaces never."""
    from renderer.scene.features import features_from

    uses = lambda *kinds, rough: {"kinds": set(kinds), "textures": False, "normal_maps": False, "emission": False,
                                  "rough": rough}
    assert features_from("mesh", uses("conductor", rough=True), "sky", 0.0).energy_compensation
    assert features_from("mesh", uses("diffuse", "dielectric", rough=True), "sky", 0.0).energy_compensation
    assert features_from("sdf", uses("diffuse", "principled", rough=False), "sky", 0.0).energy_compensation
    assert not features_from("mesh", uses("diffuse", "dielectric", "conductor", rough=False), "sky", 0.0).energy_compensation
    assert not features_from("mesh", uses("conductor", rough=True), "sky", 0.0,
                             energy_compensation=False).energy_compensation
