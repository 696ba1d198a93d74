"""Microfacet models other than Lantern's default (renderer/materials/microfacet.py): Beckmann and
GGX with Smith's separable masking, as Mitsuba 3 has them, and anisotropic widths, on conductors
and dielectrics. Their sampling against their pdf (chi-square), their sample weights against the
integral of eval, reciprocity, and their values against Mitsuba's own BSDFs (where Mitsuba is
installed).

Statistics: fixed seeds; ALPHA = 0.01 family-wise over the chi-square and z-tests of this file
(NUM_TESTS) with Sidak's correction. The comparisons with Mitsuba and the reciprocity are
deterministic (float32: 2e-4 and 1e-4 relative).
"""
import math

import numpy as np
import pytest
from scipy import stats

from renderer.scene.description import MaterialSpec
from renderer.scene.features import Features
from tests.materials.bsdf_kernels import (BsdfBench, cell_probabilities, chi2_adaptive, direction, frame_about,
                                          uniforms)
from tests.stats.chi2 import sidak_alpha

ALPHA = 0.01
N = 1_000_000
FEATURES = Features(material_kinds=frozenset({"conductor", "dielectric"}), has_microfacet_models=True,
                    has_anisotropy=True)
COPPER = dict(eta=(0.27, 0.68, 1.22), k=(3.61, 2.63, 2.29))


def _v(alpha_v):
    return None if alpha_v is None else math.sqrt(alpha_v)


def conductor(model, alpha, alpha_v=None):
    return MaterialSpec(f"c-{model}-{alpha}-{alpha_v}", kind="conductor", roughness=math.sqrt(alpha),
                        roughness_v=_v(alpha_v), microfacet=model, **COPPER)


def dielectric(model, alpha, ior=1.5, alpha_v=None):
    return MaterialSpec(f"g-{model}-{alpha}-{alpha_v}", kind="dielectric", base_color=(1.0, 1.0, 1.0),
                        roughness=math.sqrt(alpha), roughness_v=_v(alpha_v), microfacet=model, ior=ior)


CHI2_CASES = [  # (spec, cos, leaving)
    *((conductor(m, a), c, False) for m in ("beckmann", "ggx_separable") for a in (0.1, 0.5) for c in (0.9, 0.2)),
    *((dielectric("beckmann", a), c, leaving) for a in (0.1, 0.5) for c in (0.9, 0.3) for leaving in (False, True)),
    (dielectric("ggx_separable", 0.3), 0.6, False),
    # Anisotropic widths (alpha along the frame's x, alpha_v along y), the lobe stretched across wo's plane.
    *((conductor(m, 0.05, alpha_v=0.4), c, False) for m in ("beckmann", "ggx_separable", "ggx") for c in (0.9, 0.3)),
    (dielectric("beckmann", 0.3, alpha_v=0.05), 0.7, False), (dielectric("ggx", 0.05, alpha_v=0.3), 0.5, True),
]


@pytest.fixture(scope="module")
def bench(taichi_runtime):
    return BsdfBench(features=FEATURES)


@pytest.mark.parametrize("spec, cos, leaving", CHI2_CASES,
                         ids=[f"{s.name}-cos{c}{'-leaving' if lv else ''}" for s, c, lv in CHI2_CASES])
def test_chi2(bench, spec, cos, leaving, tmp_path):
    """Directions against eval's pdf, in direction space; a sample whose normal makes the
    direction leave on the wrong side is a failure, the multinomial's extra category."""
    frame = frame_about((0.0, 0.0, 1.0))
    wo = direction(cos) @ frame
    normal = -frame[2] if leaving else frame[2]
    mat = bench.material(spec)
    s = bench.sample(mat, normal, wo, uniforms(N, 500 + int(cos * 100) + (7 if leaving else 0) + len(spec.name)))
    assert not s.delta.any()
    result = chi2_adaptive(s.wi, bench.pdf_callable(mat, normal, wo), frame=frame, valid=s.valid, lossy=True,
                           domain="sphere", alpha=ALPHA, num_tests=NUM_TESTS)
    if not result.passed:
        result.write_png(tmp_path / f"{spec.name}.png")
    assert result.passed, f"{spec.name}\n{result.report}"


def _lobe_pairs(count, seed, alpha, transmit_share=0.0, eta=1.5, alpha_v=None):
    """wo above the surface and wi around its lobe: reflected (or, for a share, refracted) about
    microfacet normals of slopes spread over a few alpha, so that narrow lobes are exercised."""
    rng = np.random.default_rng(seed)
    wo = rng.normal(size=(count, 3))
    wo[:, 2] = np.abs(wo[:, 2]) + 0.1
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    widths = np.array([alpha, alpha if alpha_v is None else alpha_v])
    h = np.column_stack([2.0 * widths * rng.normal(size=(count, 2)), np.ones(count)])
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    cos_oh = np.sum(wo * h, axis=1)
    reflected = 2.0 * cos_oh[:, None] * h - wo
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - (1.0 - cos_oh ** 2) / eta ** 2))
    refracted = -wo / eta + (cos_oh / eta - cos_t)[:, None] * h
    wi = np.where((rng.random(count) < transmit_share)[:, None], refracted, reflected)
    keep = (cos_oh > 0.0) & (np.abs(wi[:, 2]) > 0.02)
    return wo[keep], wi[keep] / np.linalg.norm(wi[keep], axis=1, keepdims=True)


def _mitsuba_eval(mi, props, wo, wi):
    bsdf = mi.load_dict(props)
    ctx = mi.BSDFContext()
    out = []
    for o, i in zip(wo, wi):
        si = mi.SurfaceInteraction3f()
        si.sh_frame = mi.Frame3f(mi.Vector3f(0.0, 0.0, 1.0))
        si.wi = mi.Vector3f(*o)
        out.append(list(bsdf.eval(ctx, si, mi.Vector3f(*i))))
    return np.array(out)


MITSUBA_CASES = [("conductor", "beckmann", 0.05, None), ("conductor", "beckmann", 0.4, None),
                 ("conductor", "ggx", 0.3, None), ("dielectric", "beckmann", 0.3, None),
                 ("dielectric", "ggx", 0.2, None), ("conductor", "beckmann", 0.05, 0.3),
                 ("conductor", "ggx", 0.3, 0.05), ("dielectric", "beckmann", 0.2, 0.04)]


@pytest.mark.parametrize("kind, distribution, alpha, alpha_v", MITSUBA_CASES)
def test_values_match_mitsubas(bench, kind, distribution, alpha, alpha_v):
    """f |cos| at 400 direction pairs about the lobe equals Mitsuba 3's roughconductor (copper's eta, k)
    or roughdielectric (index 1.5; half the pairs transmit, with the radiance scale 1 / eta^2), also
    with anisotropic widths (Mitsuba's alpha_u along the shading frame's x, here the frame the
    bench's normal gives, whose x is +x for the normal +z)."""
    mi = pytest.importorskip("mitsuba", reason="Mitsuba is the project's optional `reference` extra")
    mi.set_variant("scalar_rgb")
    model = "beckmann" if distribution == "beckmann" else "ggx_separable"
    wo, wi = _lobe_pairs(400, 5 + len(kind) + int(alpha * 100), alpha, 0.5 if kind == "dielectric" else 0.0,
                         alpha_v=alpha_v)
    widths = {"alpha": alpha} if alpha_v is None else {"alpha_u": alpha, "alpha_v": alpha_v}
    if kind == "dielectric":
        spec = dielectric(model, alpha, alpha_v=alpha_v)
        props = {"type": "roughdielectric", "distribution": distribution, "int_ior": 1.5, "ext_ior": 1.0, **widths}
    else:
        spec = conductor(model, alpha, alpha_v=alpha_v)
        props = {"type": "roughconductor", "distribution": distribution, **widths,
                 "eta": {"type": "rgb", "value": list(COPPER["eta"])}, "k": {"type": "rgb", "value": list(COPPER["k"])}}
    ours, _ = bench.eval(bench.material(spec), (0.0, 0.0, 1.0), wo, wi)
    theirs = _mitsuba_eval(mi, props, wo, wi)
    assert len(wo) > 200 and (theirs[:, 0] > 1e-3).mean() > 0.5  # the pairs exercise the lobe
    np.testing.assert_allclose(ours, theirs, rtol=2e-4, atol=1e-6)


UNBIASED = [  # (spec, cos, leaving): E[weight] = integral of eval over the sphere
    (conductor("beckmann", 0.3), 0.6, False), (conductor("beckmann", 0.05, alpha_v=0.4), 0.4, False),
    (conductor("ggx_separable", 0.5, alpha_v=0.1), 0.8, False), (dielectric("beckmann", 0.4), 0.5, False),
    (dielectric("beckmann", 0.2, alpha_v=0.5), 0.7, True)]
NUM_TESTS = len(CHI2_CASES) + len(UNBIASED)  # the statistical tests of this file
RECIPROCAL = [conductor("beckmann", 0.3), conductor("beckmann", 0.05, alpha_v=0.4), conductor("ggx", 0.2, alpha_v=0.5),
              dielectric("beckmann", 0.3, alpha_v=0.1)]


@pytest.mark.parametrize("spec, cos, leaving", UNBIASED, ids=[f"{s.name}-cos{c}" for s, c, _ in UNBIASED])
def test_sample_weights_average_to_the_integral_of_eval(bench, spec, cos, leaving):
    """Whatever a sample's lobe and normal, E[weight] = the integral of eval (f |cos|) over the
    sphere: the adaptive quadrature of bsdf_kernels.cell_probabilities against the mean weight of
    10^6 samples, a two-sided z-test at the file's Sidak level."""
    frame = frame_about([0.1, -0.3, 0.9])
    wo = direction(cos) @ frame
    normal = -frame[2] if leaving else frame[2]
    mat = bench.material(spec)
    s = bench.sample(mat, normal, wo, uniforms(N, 900 + len(spec.name) + int(cos * 10)))
    weights = np.where(s.valid, s.weight.mean(axis=1), 0.0).astype(np.float64)
    integral = cell_probabilities(lambda d: bench.eval(mat, normal, wo, d)[0].astype(np.float64).mean(axis=1),
                                  frame=frame, abs_tol=1e-9).sum()
    z = (weights.mean() - integral) / (weights.std(ddof=1) / math.sqrt(N))
    assert 2.0 * stats.norm.sf(abs(z)) > sidak_alpha(ALPHA, NUM_TESTS), (weights.mean(), integral, z)


GRAZING = [conductor("beckmann", 0.3), dielectric("beckmann", 0.3), conductor("beckmann", 0.05, alpha_v=0.4)]


@pytest.mark.parametrize("spec", GRAZING, ids=[s.name for s in GRAZING])
def test_beckmann_weights_stay_bounded_at_grazing_incidence(bench, spec):
    """Beckmann's normals come from its visible normals, as Mitsuba draws them: a sample's weight
    is G2 / G1(wo) times Fresnel (and 1 / eta^2 into glass), about 1 at most however grazing wo
    is. Drawn from D(h) cos(h), weights reached |wo.h| / wo.z (tens at cos 0.05): the fireflies
    of rough glass seen edge-on. Deterministic (fixed uniforms, a bound; the fitted G1 in G2 is
    within 0.35% of the exact one in the pdf)."""
    frame = frame_about((0.0, 0.0, 1.0))
    mat = bench.material(spec)
    for cos in (0.3, 0.05, 0.01):
        s = bench.sample(mat, frame[2], direction(cos) @ frame, uniforms(100_000, 40 + int(cos * 100)))
        assert s.valid.mean() > 0.2, cos
        assert s.weight[s.valid].max() <= 1.01, (cos, s.weight[s.valid].max())


@pytest.mark.parametrize("spec", RECIPROCAL, ids=[s.name for s in RECIPROCAL])
def test_reflection_is_reciprocal(bench, spec):
    """f(wo, wi) = f(wi, wo) for reflection, pairs about the lobe (float32: 1e-4 relative)."""
    alpha_v = None if spec.roughness_v is None else spec.roughness_v ** 2
    wo, wi = _lobe_pairs(2000, 77, spec.roughness ** 2, alpha_v=alpha_v)
    wo, wi = wo[wi[:, 2] > 0.0], wi[wi[:, 2] > 0.0]  # reflections
    mat = bench.material(spec)
    forward, _ = bench.eval(mat, (0.0, 0.0, 1.0), wo, wi)
    backward, _ = bench.eval(mat, (0.0, 0.0, 1.0), wi, wo)
    np.testing.assert_allclose(forward / wi[:, 2:3], backward / wo[:, 2:3], rtol=1e-4, atol=1e-7)
    assert (forward > 0).mean() > 0.5
