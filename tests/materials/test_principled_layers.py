"""The principled model's layers (renderer/materials/principled.py) and thin walls.

- White furnace per surface: every layer combination over a white base returns 1 (clearcoat smooth
  and rough, sheen, specular strength and colour, all at once over a metal and over a diffuse
  base), and a white thin wall, smooth or rough, reflects plus transmits 1 from either side; what
  single scattering would have lost is stated beside (a test that could not fail otherwise).
  The expectation is 1 up to the albedo tables' error: each table is held to TABLE_TOLERANCE
  against an independent estimate (the dielectric's in test_dielectric_energy.py, the sheen's
  here), and the furnace is an equivalence test at that margin, at the stated significance.
- Layered and thin lobes are sampled as their pdf says (chi-square) and their weights average to
  the integral of eval.

Significance: ALPHA = 0.01 family-wise over the statistical tests of this file, Sidak-corrected.
"""
import dataclasses
import math

import numpy as np
import pytest
from scipy import stats

from renderer.materials import sheen
from renderer.materials.kinds import LAYER_NAMES
from renderer.scene.description import MaterialSpec
from tests.materials.bsdf_kernels import (ALL_KINDS, BsdfBench, cell_probabilities, chi2_adaptive, direction,
                                          frame_about, uniforms)
from tests.stats.chi2 import sidak_alpha

ALL_LAYERS = frozenset(LAYER_NAMES)

ALPHA = 0.01
N = 1_000_000
WHITE = (1.0, 1.0, 1.0)
# Interpolation error of the albedo tables the layering reads (dielectric: 3e-3 bound tested in
# test_dielectric_energy.py; sheen: tested below), added up over at most three layers.
TABLE_TOLERANCE = 5e-3

LAYERED = {
    "smooth coat": dict(roughness=0.4, clearcoat=1.0, clearcoat_roughness=0.0),
    "rough coat": dict(roughness=0.4, clearcoat=1.0, clearcoat_roughness=0.35),
    "half coat": dict(roughness=0.2, clearcoat=0.5, clearcoat_roughness=0.1),
    "sheen": dict(roughness=0.5, sheen_color=WHITE, sheen_roughness=0.4),
    "specular": dict(roughness=0.3, specular=0.5, specular_color=(1.0, 0.6, 0.3)),
    "all over metal": dict(roughness=0.6, metallic=1.0, clearcoat=1.0, clearcoat_roughness=0.2,
                           sheen_color=WHITE, sheen_roughness=0.3),
    "all over diffuse": dict(roughness=0.5, clearcoat=0.8, clearcoat_roughness=0.25, sheen_color=WHITE,
                             sheen_roughness=0.6, specular=0.7),
}
THIN = {
    "thin smooth": MaterialSpec("t0", "dielectric", WHITE, roughness=0.0, thin=True),
    "thin rough": MaterialSpec("t1", "dielectric", WHITE, roughness=0.5, thin=True),
    "thin very rough": MaterialSpec("t2", "dielectric", WHITE, roughness=1.0, ior=1.7, thin=True),
    "thin principled": MaterialSpec("t3", "principled", WHITE, roughness=0.7, metallic=0.0, transmission=1.0,
                                    thin=True),
}
FURNACE_COS = (0.9, 0.4, 0.1)
CHI2_CASES = [("all over metal", 0.7), ("all over diffuse", 0.3), ("rough coat", 0.8), ("thin rough", 0.6),
              ("thin very rough", 0.2)]
UNBIASED_CASES = [("all over diffuse", 0.6), ("thin rough", 0.5)]
SHEEN_TABLE_CASES = [(0.2, 0.13), (0.55, 0.61), (0.9, 0.97), (0.3, 0.02)]
NUM_TESTS = ((len(LAYERED) + len(THIN)) * len(FURNACE_COS) + len(CHI2_CASES) + len(UNBIASED_CASES)
             + len(SHEEN_TABLE_CASES))
LEVEL = sidak_alpha(ALPHA, NUM_TESTS)


def spec_of(name):
    if name in THIN:
        return THIN[name]
    return MaterialSpec(name.replace(" ", "_"), "principled", WHITE, **{"metallic": 0.0, **LAYERED[name]})


@pytest.fixture(scope="module")
def bench():
    features = dataclasses.replace(ALL_KINDS, energy_compensation=True, material_layers=ALL_LAYERS, has_thin=True)
    return BsdfBench(capacity=24, features=features)


@pytest.fixture(scope="module")
def single(bench):
    """The same materials without compensation: what single scattering returns (so that the
    furnace is seen not to pass vacuously)."""
    features = dataclasses.replace(ALL_KINDS, material_layers=ALL_LAYERS, has_thin=True)
    return BsdfBench(capacity=24, features=features)


def equivalent(samples, expected, margin, what):
    samples = np.asarray(samples, np.float64)
    se = samples.std(ddof=1) / math.sqrt(len(samples))
    excess = max(abs(samples.mean() - expected) - margin, 0.0) / max(se, 1e-12)
    assert 2.0 * stats.norm.sf(excess) >= LEVEL, f"{what}: mean {samples.mean():.5f} vs {expected} (se {se:.1e})"
    return samples.mean()


@pytest.mark.parametrize("name", list(LAYERED) + list(THIN))
def test_white_layers_keep_their_energy(bench, single, name):
    spec = spec_of(name)
    thin = name in THIN
    mat = bench.material(spec)
    report = []
    for k, cos in enumerate(FURNACE_COS):
        for side in ((1.0, -1.0) if thin else (1.0,)):
            u = uniforms(N // 2 if thin else N, 300 + 10 * list(LAYERED).index(name) if not thin else 600 + k)
            s = bench.sample(mat, [0.0, 0.0, side], direction(cos) * np.array([1.0, 1.0, side]), u)
            w = np.where(s.valid, s.weight[:, 1], 0.0)
            mean = equivalent(w, 1.0, TABLE_TOLERANCE, f"{name}, cos {cos}, side {side}")
            report.append(f"cos {cos}: {mean:.4f}")
    if thin and spec.roughness > 0.0 or name == "all over metal":
        # Without compensation a rough wall or a rough metal loses light at grazing incidence.
        # The equivalence test above would reject it: below 1 by more than the margin plus 5 se.
        plain = single.sample(single.material(spec), [0.0, 0.0, 1.0], direction(0.1), uniforms(N, 999))
        w = np.where(plain.valid, plain.weight[:, 1], 0.0)
        assert w.mean() + 5.0 * w.std() / math.sqrt(len(w)) < 1.0 - TABLE_TOLERANCE
    print(name, "; ".join(report))


@pytest.mark.parametrize("name,cos", CHI2_CASES)
def test_layered_samples_follow_the_pdf(bench, name, cos):
    frame = frame_about([0.2, -0.1, 0.95])
    wo = direction(cos) @ frame
    spec = dataclasses.replace(spec_of(name), base_color=(0.9, 0.6, 0.4))
    mat = bench.material(spec)
    s = bench.sample(mat, frame[2], wo, uniforms(N, 450 + CHI2_CASES.index((name, cos))))
    result = chi2_adaptive(s.wi, bench.pdf_callable(mat, frame[2], wo), frame=frame, valid=s.valid & ~s.delta,
                           lossy=True, domain="sphere", alpha=ALPHA, num_tests=NUM_TESTS)
    assert result.passed, result.report


@pytest.mark.parametrize("name,cos", UNBIASED_CASES)
def test_sample_weights_average_to_the_integral_of_eval(bench, name, cos):
    frame = frame_about([0.1, -0.3, 0.9])
    wo = direction(cos) @ frame
    mat = bench.material(dataclasses.replace(spec_of(name), base_color=(0.9, 0.6, 0.4)))
    s = bench.sample(mat, frame[2], wo, uniforms(N, 470 + UNBIASED_CASES.index((name, cos))))
    assert not s.delta.any()
    integral = cell_probabilities(lambda d: bench.eval(mat, frame[2], wo, d)[0].astype(np.float64).mean(axis=1),
                                  frame=frame, abs_tol=1e-9).sum()
    samples = np.where(s.valid, s.weight.mean(axis=1), 0.0)
    equivalent(samples, integral, 0.0, f"{name} cos {cos}")


@pytest.mark.parametrize("roughness,cos", SHEEN_TABLE_CASES)
def test_sheen_table_matches_an_independent_estimate(roughness, cos):
    """The sheen albedo by Monte Carlo with uniform hemisphere sampling (the table was made by
    quadrature), between nodes: table error plus interpolation within TABLE_TOLERANCE / 2."""
    table = sheen.load_table()
    rng = np.random.default_rng(int(roughness * 1000 + cos * 10))
    n = 4_000_000
    mu_i = rng.random(n)
    phi = 2.0 * np.pi * rng.random(n)
    s_i = np.sqrt(1.0 - mu_i ** 2)
    s_o = math.sqrt(1.0 - cos * cos)
    h = np.stack([s_o + s_i * np.cos(phi), s_i * np.sin(phi), cos + mu_i], axis=1)
    cos_h = h[:, 2] / np.linalg.norm(h, axis=1)
    f = sheen.charlie_np(cos_h, roughness) * sheen.visibility_np(cos, mu_i) * mu_i * 2.0 * np.pi
    looked = float(sheen.albedo_lookup(table, np.array(cos), np.array(roughness)))
    equivalent(f, looked, TABLE_TOLERANCE / 2, f"sheen roughness {roughness} cos {cos}")
