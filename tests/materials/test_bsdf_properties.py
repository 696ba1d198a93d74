"""Properties every BSDF must have: `sample` agrees with `eval`, reciprocity (Veach's generalised
form across a refraction), energy (white furnaces, and sample weights averaging to the integral of
`eval`), finite output at roughness 0 and 1 and at grazing angles, total internal reflection.

Conventions under test (renderer/materials/lobes.py): `eval` returns f |cos wi|; `eta` = n on the
far side / n on wo's side; transmitted radiance is scaled by 1 / eta^2, i.e. `eval` is the radiance
BSDF of Walter et al. 2007 (the eta_o^2 / (eta_i (i.h) + eta_o (o.h))^2 form). Such a BSDF is not
symmetric across a refraction. With f(wo, wi) = eval(wo, wi) / |cos wi|, n_o the index on wo's
side and n_i the index on wi's side, the relation that holds (Veach 1997, section 5.2) is

    f(wo, wi) / n_o^2 = f(wi, wo) / n_i^2,  i.e.  f(wi, wo) = (n_i / n_o)^2 f(wo, wi),

so with wo outside (air) and wi inside glass of index 1.5, f(wi, wo) = 2.25 f(wo, wi).

Statistics: fixed seeds; ALPHA = 0.01 family-wise over the NUM_TESTS z-tests of this file with
Sidak's correction. Everything else is deterministic up to float32 rounding (tolerances stated).
"""
import math

import numpy as np
import pytest
from scipy import stats

from renderer.scene.description import MaterialSpec
from tests.materials.bsdf_kernels import BsdfBench, cell_probabilities, direction, frame_about, uniforms
from tests.materials.ggx_reference import ggx_albedo_reference
from tests.stats.chi2 import sidak_alpha

ALPHA = 0.01
TINT = (0.9, 0.7, 0.5)
BASE = (0.8, 0.5, 0.3)

FURNACE_ROUGHNESS = (0.3, 0.6, 1.0)
FURNACE_COS = (0.99, 0.5, 0.1)
SMOOTH_GLASS = ((1.5, 0.9, False), (1.5, 0.3, False), (1.5, 0.9, True), (2.4, 0.05, False))  # (ior, cos, leaving)
UNBIASED = [  # (name, spec, cos, leaving): E[weight] = integral of eval over the sphere
    ("diffuse", MaterialSpec(name="d", kind="diffuse", base_color=BASE), 0.5, False),
    ("conductor-r0.3-tint", MaterialSpec(name="c", kind="conductor", base_color=(0.95, 0.64, 0.54),
                                         roughness=0.3, edge_tint=(0.5, 0.7, 0.9)), 0.3, False),
    ("dielectric-r0.6-entering", MaterialSpec(name="g", kind="dielectric", base_color=TINT, roughness=0.6), 0.5,
     False),
    ("dielectric-r0.6-leaving", MaterialSpec(name="g", kind="dielectric", base_color=TINT, roughness=0.6), 0.9,
     True),
    ("dielectric-r1.0-grazing", MaterialSpec(name="g", kind="dielectric", roughness=1.0), 0.05, False),
    ("principled-coat", MaterialSpec(name="p", kind="principled", base_color=BASE, roughness=0.5), 0.5, False),
    ("principled-metal-glass", MaterialSpec(name="p", kind="principled", base_color=BASE, roughness=0.8,
                                            metallic=0.5, transmission=0.6), 0.5, False),
    ("principled-coat-glass", MaterialSpec(name="p", kind="principled", base_color=BASE, roughness=0.3,
                                           transmission=0.5), 0.05, False),
    ("conductor-Cu-r0.4", MaterialSpec(name="c", kind="conductor", metal="Cu", roughness=0.4), 0.3, False),
]
NUM_TESTS = len(FURNACE_ROUGHNESS) * len(FURNACE_COS) + 1 + len(SMOOTH_GLASS) + len(UNBIASED)
N = 1_000_000


@pytest.fixture(scope="module")
def bench(taichi_runtime):
    return BsdfBench()


def z_test(samples, expected, what):
    """Two-sided z-test of the mean of `samples` against `expected` at the Sidak level (samples
    that are all equal have no variance: their mean must then equal `expected` to float32 rounding)."""
    samples = np.asarray(samples, np.float64)
    se = samples.std(ddof=1) / math.sqrt(len(samples))
    if se == 0.0:
        assert abs(samples[0] - expected) <= 1e-6 * max(1.0, abs(expected)), f"{what}: {samples[0]} vs {expected}"
        return samples[0], 0.0
    z = (samples.mean() - expected) / se
    p = 2.0 * stats.norm.sf(abs(z))
    assert p >= sidak_alpha(ALPHA, NUM_TESTS), f"{what}: mean {samples.mean():.6f} vs {expected:.6f}, z = {z:.2f}"
    return samples.mean(), se


def random_unit(rng, n):
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def random_frames(rng, n):
    """Random normals (n, 3) and a random wo about each, cos uniform in [0.02, 1): (normal, wo, cos)."""
    normal = random_unit(rng, n)
    t = np.cross(normal, random_unit(rng, n))
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    cos = rng.uniform(0.02, 1.0, n)
    wo = cos[:, None] * normal + np.sqrt(1.0 - cos * cos)[:, None] * t
    return normal, wo, cos


# --- sample / eval consistency -----------------------------------------------------------------------

CONSISTENCY = {
    "diffuse": [MaterialSpec(name="d", kind="diffuse", base_color=BASE)],
    "conductor": [MaterialSpec(name="c", kind="conductor", base_color=(0.95, 0.64, 0.54), roughness=r,
                               edge_tint=(0.6, 0.8, 1.0)) for r in (0.1, 0.3, 0.6, 1.0)]
                 + [MaterialSpec(name="c", kind="conductor", metal=m, roughness=r) for m, r in (("Au", 0.1), ("Al", 0.6))]
                 + [MaterialSpec(name="c", kind="conductor", eta=(1.5, 0.2, 3.0), k=(0.0, 4.0, 60.0), roughness=0.3)],
    "dielectric": [MaterialSpec(name="g", kind="dielectric", base_color=TINT, roughness=r, ior=ior)
                   for r in (0.1, 0.3, 1.0) for ior in (1.5, 1.33)],
    "principled": [MaterialSpec(name="p", kind="principled", base_color=BASE, roughness=r, metallic=m, transmission=t)
                   for r in (0.2, 0.5, 1.0) for m, t in ((0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (0.4, 0.5))],
}
PDF_FLOOR = 1e-3  # per steradian: below it, f32 rounding of a near-zero pdf is not a disagreement
REL = 1e-3
# float32 rounding (~6e-8) of a cosine is amplified by 1 / cosine: eval recomputes the (generalised)
# half vector h from wo and wi, Smith's Lambda(wi) grows as 1 / cos(wi), and 1 - F has an infinite
# slope at grazing refraction (relative error ~6e-8 eta^2 / (2 cos_t^2)). Samples with a microfacet
# cosine min(|wo.h|, |wi.h|) < GRAZING_H or with |cos wi| < GRAZING_WI are left out of the 1e-3
# comparisons (they are covered by the finiteness test and, statistically, by the chi-square tests).
# For the same reason roughness 0.01 (alpha 1e-4: a slope error ~6e-8 / (wo.h alpha) ~ 1e-3) is not
# compared here.
GRAZING_H = 0.1
GRAZING_WI = 1e-3


def half_vector(wo, wi, eta, n_side):
    """The (generalised) half vector on wo's side: wo + wi for reflections, wo + eta wi for
    refractions (eta = n on wi's side / n on wo's side)."""
    refracted = np.sum(wi * n_side, axis=1) < 0.0
    h = wo + np.where(refracted, eta, 1.0)[:, None] * wi
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    return h * np.sign(np.sum(h * n_side, axis=1))[:, None]


@pytest.mark.parametrize("kind", list(CONSISTENCY))
def test_sample_weight_and_pdf_match_eval(bench, kind):
    """For non-delta samples: pdf == eval's pdf and weight == eval's f|cos| / eval's pdf (relative
    1e-3), on random normals (both sides for the dielectrics), wo and materials."""
    rng = np.random.default_rng(11)
    n = 400_000
    ids = np.array([bench.material(spec) for spec in CONSISTENCY[kind]], np.int32)
    mat = ids[rng.integers(0, len(ids), n)]
    normal, wo, _ = random_frames(rng, n)
    if kind in ("dielectric", "principled"):
        normal *= np.where(rng.random(n) < 0.5, -1.0, 1.0)[:, None]  # half of them from inside
    s = bench.sample(mat, normal, wo, uniforms(n, 12))
    wi = s.wi.astype(np.float64)
    entering = np.sum(normal * wo, axis=1) >= 0.0
    n_side = normal * np.where(entering, 1.0, -1.0)[:, None]
    ior_of = np.zeros(bench.capacity)
    ior_of[ids] = [spec.ior for spec in CONSISTENCY[kind]]
    ior = ior_of[mat]
    h = half_vector(wo, wi, np.where(entering, ior, 1.0 / ior), n_side)
    micro = np.minimum(np.abs(np.sum(wo * h, axis=1)), np.abs(np.sum(wi * h, axis=1)))
    well_conditioned = (np.abs(np.sum(wi * n_side, axis=1)) > GRAZING_WI) & (micro > GRAZING_H)
    use = s.valid & ~s.delta & (s.eval_pdf > PDF_FLOOR) & well_conditioned
    assert use.mean() > 0.5
    np.testing.assert_allclose(s.pdf[use], s.eval_pdf[use], rtol=REL)
    expected = s.eval_value[use] / s.eval_pdf[use][:, None]
    np.testing.assert_allclose(s.weight[use], expected, rtol=REL, atol=1e-6)
    # A valid non-delta sample always has eval's pdf > 0 (the sampler cannot produce what eval excludes).
    assert (s.eval_pdf[s.valid & ~s.delta] > 0.0).all()


# --- reciprocity -------------------------------------------------------------------------------------

RECIPROCAL = [
    MaterialSpec(name="d", kind="diffuse", base_color=BASE),
    MaterialSpec(name="c", kind="conductor", base_color=(0.95, 0.64, 0.54), roughness=0.3, edge_tint=(0.5, 0.7, 0.9)),
    MaterialSpec(name="c", kind="conductor", base_color=(0.95, 0.64, 0.54), roughness=1.0),
    MaterialSpec(name="c", kind="conductor", metal="Cu", roughness=0.5),
    MaterialSpec(name="g", kind="dielectric", roughness=0.5),
    MaterialSpec(name="p", kind="principled", base_color=BASE, roughness=0.2),  # coat specular + coated diffuse
    MaterialSpec(name="p", kind="principled", base_color=BASE, roughness=0.7, metallic=0.3, transmission=0.4),
]


def f_of(bench, mat, normal, wo, wi):
    """f itself: eval's f |cos wi| divided by |cos wi|."""
    value, _ = bench.eval(mat, normal, wo, wi)
    return value / np.abs(np.sum(wi * normal, axis=1))[:, None]


@pytest.mark.parametrize("spec", RECIPROCAL, ids=lambda s: f"{s.kind}-r{s.roughness}-m{s.metallic}-t{s.transmission}")
def test_reflection_is_reciprocal(bench, spec):
    rng = np.random.default_rng(21)
    n = 200_000
    mat = bench.material(spec)
    normal = np.broadcast_to(frame_about([0.2, 0.4, 0.9])[2], (n, 3))
    frame = frame_about(normal[0])
    a = random_unit(rng, n) @ frame
    b = random_unit(rng, n) @ frame
    a *= np.sign(a @ frame[2])[:, None]  # both above the surface, down to grazing
    b *= np.sign(b @ frame[2])[:, None]
    f_ab = f_of(bench, mat, normal, a, b)
    f_ba = f_of(bench, mat, normal, b, a)
    assert (f_ab > 0.0).mean() > 0.5
    # eval multiplies by its own float32 cos(wi): dividing by a float64 one is exact only away from
    # the tangent plane (relative error ~6e-8 / cos)
    ok = (np.abs(a @ frame[2]) > GRAZING_WI) & (np.abs(b @ frame[2]) > GRAZING_WI)
    np.testing.assert_allclose(f_ab[ok], f_ba[ok], rtol=2e-4, atol=1e-6)


@pytest.mark.parametrize("spec", [MaterialSpec(name="g", kind="dielectric", base_color=TINT, roughness=r, ior=ior)
                                  for r, ior in ((0.3, 1.5), (1.0, 1.5), (0.6, 2.4))]
                         + [MaterialSpec(name="p", kind="principled", base_color=BASE, roughness=0.5,
                                         transmission=1.0)],
                         ids=lambda s: f"{s.kind}-r{s.roughness}-ior{s.ior}")
def test_transmission_obeys_generalised_reciprocity(bench, spec):
    """f(wo, wi) / n_o^2 == f(wi, wo) / n_i^2 (see the module doc), and plain symmetry does not hold."""
    rng = np.random.default_rng(22)
    n = 200_000
    mat = bench.material(spec)
    normal = np.broadcast_to(np.array([0.0, 0.0, 1.0]), (n, 3))  # outward: wo outside (n_o = 1)
    outside = random_unit(rng, n)
    outside[:, 2] = np.abs(outside[:, 2])
    inside = random_unit(rng, n)
    inside[:, 2] = -np.abs(inside[:, 2])
    f_out_in = f_of(bench, mat, normal, outside, inside)  # wo outside, wi inside glass
    f_in_out = f_of(bench, mat, normal, inside, outside)  # wo inside, wi outside
    n_o, n_i = 1.0, spec.ior
    # ill-conditioned pairs left out as in the consistency test (GRAZING_H, GRAZING_WI)
    h = half_vector(outside, inside, n_i / n_o, normal)
    micro = np.minimum(np.abs(np.sum(outside * h, axis=1)), np.abs(np.sum(inside * h, axis=1)))
    some = ((f_out_in[:, 0] > 0.0) & (micro > GRAZING_H) & (np.abs(outside[:, 2]) > GRAZING_WI)
            & (np.abs(inside[:, 2]) > GRAZING_WI))
    assert some.mean() > 0.1
    np.testing.assert_allclose(f_out_in[some] / n_o ** 2, f_in_out[some] / n_i ** 2, rtol=2e-4)
    assert np.all(np.abs(f_in_out[some] / f_out_in[some] - 1.0) > 0.5)  # not symmetric: the ratio is n_i^2


# --- energy ------------------------------------------------------------------------------------------


def test_white_lambert_and_perfect_mirror_return_exactly_one(bench):
    """Albedo 1 and F0 = 1 (with edge tint 1: by design an edge tint below 1 darkens grazing
    reflection even when F0 = 1, Hoffman's F82) return weight exactly 1 on every sample."""
    rng = np.random.default_rng(31)
    n = 200_000
    normal, wo, _ = random_frames(rng, n)
    for spec in (MaterialSpec(name="w", kind="diffuse", base_color=(1.0, 1.0, 1.0)),
                 MaterialSpec(name="m", kind="conductor", base_color=(1.0, 1.0, 1.0), roughness=0.0)):
        s = bench.sample(bench.material(spec), normal, wo, uniforms(n, 32))
        valid = s.valid
        assert valid.mean() > 0.999  # a cosine sample exactly on the horizon is the only failure
        assert (s.weight[valid] == 1.0).all(), spec.kind


@pytest.mark.parametrize("roughness", FURNACE_ROUGHNESS)
def test_rough_conductor_furnace_loses_the_single_scattering_energy(bench, roughness, record_property):
    """F0 = 1: E(mu) = mean sample weight (invalid samples count 0) against an independent numpy
    quadrature of f cos over the hemisphere, z-test per incidence."""
    alpha = roughness * roughness
    mat = bench.material(MaterialSpec(name="m", kind="conductor", base_color=(1.0, 1.0, 1.0), roughness=roughness))
    report = []
    for k, cos in enumerate(FURNACE_COS):
        reference = ggx_albedo_reference(alpha, cos)
        finer = ggx_albedo_reference(alpha, cos, n_u=4096, n_phi=64)
        assert abs(reference - finer) < 1e-7  # the quadrature has converged (the MC error is ~3e-4)
        wo = direction(cos)
        seed = 400 + 10 * FURNACE_ROUGHNESS.index(roughness) + k
        s = bench.sample(mat, [0.0, 0.0, 1.0], wo, uniforms(N, seed))
        assert (s.weight[s.valid] <= 1.0 + 1e-6).all()  # G2 / G1 <= 1: a single bounce never gains
        weights = np.where(s.valid, s.weight[:, 0], 0.0)
        mean, se = z_test(weights, reference, f"GGX albedo, roughness {roughness}, cos {cos}")
        report.append(f"cos {cos}: E = {mean:.4f} +- {se:.4f} (quadrature {reference:.4f}), loss {1 - reference:.1%}")
    record_property("furnace", "; ".join(report))
    print(f"roughness {roughness}: " + "; ".join(report))


def test_ggx_albedo_at_normal_incidence_is_one_minus_ln2(bench):
    """alpha = 1, wo = n: Lambda(wo) = 0, h is cosine-distributed and wi.z = cos(2 theta_h), so
    E = integral over theta_h < pi/4 of cos(2 theta) / cos^2(theta) * 2 sin cos d theta = 1 - ln 2
    (a loss of 69 %). Checks the quadrature above against a closed form, and the sampler at exactly
    normal incidence."""
    exact = 1.0 - math.log(2.0)
    assert abs(ggx_albedo_reference(1.0, 1.0 - 1e-12) - exact) < 1e-7
    mat = bench.material(MaterialSpec(name="m", kind="conductor", base_color=(1.0, 1.0, 1.0), roughness=1.0))
    s = bench.sample(mat, [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], uniforms(N, 45))
    z_test(np.where(s.valid, s.weight[:, 0], 0.0), exact, "GGX albedo at normal incidence, alpha 1")


@pytest.mark.parametrize("ior,cos,leaving", SMOOTH_GLASS)
def test_smooth_dielectric_furnace(bench, ior, cos, leaving):
    """Tint 1. Reflection weight 1, transmission weight 1 / eta^2, chosen with probabilities F and
    1 - F, so E[weight] = F + (1 - F) / eta^2, which is 1 only for eta = 1: radiance is not conserved
    across an interface, L / n^2 is. In those units every sample carries exactly 1: the weight of a
    transmission times eta^2 (= (n_far / n_near)^2) is 1, so the interface neither creates nor
    destroys energy."""
    normal = np.array([0.0, 0.0, -1.0 if leaving else 1.0])
    eta = 1.0 / ior if leaving else ior
    mat = bench.material(MaterialSpec(name="g", kind="dielectric", base_color=(1.0, 1.0, 1.0), roughness=0.0, ior=ior))
    seed = 500 + SMOOTH_GLASS.index((ior, cos, leaving))
    s = bench.sample(mat, normal, direction(cos), uniforms(N, seed))
    assert s.valid.all() and s.delta.all()
    transmitted = s.wi[:, 2] < 0.0
    w = s.weight[:, 0].astype(np.float64)
    np.testing.assert_allclose(w[~transmitted], 1.0, rtol=1e-7)
    np.testing.assert_allclose(w[transmitted] * eta * eta, 1.0, rtol=1e-6)
    sin2_t = (1.0 - cos * cos) / eta ** 2
    cos_t = math.sqrt(1.0 - sin2_t)
    rs = (cos - eta * cos_t) / (cos + eta * cos_t)
    rp = (eta * cos - cos_t) / (eta * cos + cos_t)
    fresnel = 0.5 * (rs * rs + rp * rp)
    z_test(w, fresnel + (1.0 - fresnel) / eta ** 2, f"smooth glass ior {ior} cos {cos} leaving {leaving}")


@pytest.mark.parametrize("name,spec,cos,leaving", UNBIASED, ids=[u[0] for u in UNBIASED])
def test_sample_weights_average_to_the_integral_of_eval(bench, name, spec, cos, leaving):
    """The estimator sample -> weight is unbiased for the integral of f |cos| over the sphere (what
    eval returns), whatever lobe produced each sample: E[weight] = integral of eval(wo, wi) d wi.
    The reference is an adaptive quadrature of eval (to ~1e-6), z-test on the mean over channels."""
    frame = frame_about([0.1, -0.3, 0.9])
    wo = direction(cos) @ frame
    normal = -frame[2] if leaving else frame[2]
    mat = bench.material(spec)
    s = bench.sample(mat, normal, wo, uniforms(N, 600 + [u[0] for u in UNBIASED].index(name)))
    weights = np.where(s.valid, s.weight.mean(axis=1), 0.0)
    integral = cell_probabilities(lambda d: bench.eval(mat, normal, wo, d)[0].astype(np.float64).mean(axis=1),
                                  frame=frame, abs_tol=1e-9).sum()
    z_test(weights, integral, name)


# --- robustness --------------------------------------------------------------------------------------

ROBUST = ([MaterialSpec(name="d", kind="diffuse", base_color=(1.0, 1.0, 1.0))]
          + [MaterialSpec(name="c", kind="conductor", base_color=(1.0, 0.7, 0.2), roughness=r,
                          edge_tint=(0.4, 0.6, 1.0))
             for r in (0.0, 0.01, 0.5, 1.0)]
          + [MaterialSpec(name="c", kind="conductor", eta=eta, k=k, roughness=r)  # k = 0, eta = k = 0, large k
             for r in (0.0, 0.5, 1.0) for eta, k in (((0.5, 0.0, 2.0), (0.0, 0.0, 99.0)),)]
          + [MaterialSpec(name="g", kind="dielectric", base_color=TINT, roughness=r, ior=ior)
             for r in (0.0, 0.01, 0.5, 1.0) for ior in (1.5, 1.01, 2.4)]
          + [MaterialSpec(name="p", kind="principled", base_color=BASE, roughness=r, metallic=m, transmission=t)
             for r in (0.0, 0.01, 0.5, 1.0) for m, t in ((0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (0.5, 0.5))])


def test_outputs_stay_finite_at_extremes(bench):
    """4 x 10^6 random (material, normal, wo, u) with cos(wo) log-uniform in [1e-6, 1] plus exactly 0
    and exactly 1, both sides of the surface: sample and eval never produce NaN or inf, valid samples
    have finite weights >= 0 and pdfs > 0 (delta choices: a probability in (0, 1])."""
    ids = np.array([bench.material(spec) for spec in ROBUST], np.int32)
    up = np.array([0.0, 0.0, 1.0])
    for batch in range(4):
        rng = np.random.default_rng(70 + batch)
        n = 1_000_000
        mat = ids[rng.integers(0, len(ids), n)]
        cos = 10.0 ** rng.uniform(-6.0, 0.0, n)
        cos[:1000] = 0.0
        cos[1000:2000] = 1.0
        phi = rng.uniform(0.0, 2.0 * np.pi, n)
        sin = np.sqrt(1.0 - cos * cos)
        wo = np.stack([sin * np.cos(phi), sin * np.sin(phi), cos], axis=1)
        normal = np.broadcast_to(up, (n, 3)) * np.where(rng.random(n) < 0.5, -1.0, 1.0)[:, None]
        u = uniforms(n, 80 + batch)
        u[:3000] = np.float32(1.0 - 2.0 ** -24)  # the largest uniforms
        u[3000:6000] = 0.0
        s = bench.sample(mat, normal, wo, u)
        for name in ("wi", "weight", "pdf", "eval_value", "eval_pdf"):
            values = getattr(s, name)
            assert np.isfinite(values).all(), f"{name}: {np.count_nonzero(~np.isfinite(values))} not finite"
        v = s.valid
        assert (s.weight[v] >= 0.0).all() and (s.pdf[v] > 0.0).all()
        assert (s.pdf[v & s.delta] <= 1.0 + 1e-6).all()
        assert np.abs(np.linalg.norm(s.wi[v], axis=1) - 1.0).max() < 1e-5
        assert (s.eval_value >= 0.0).all() and (s.eval_pdf >= 0.0).all()
        assert not s.valid[cos == 0.0].any()  # wo in the tangent plane: nothing to sample
        # eval towards random directions, grazing ones included
        wi = random_unit(rng, n)
        wi[:100_000, 2] = 0.0
        wi[100_000:200_000, 2] = np.sign(wi[100_000:200_000, 2]) * 1e-6
        wi /= np.linalg.norm(wi, axis=1, keepdims=True)
        value, pdf = bench.eval(mat, normal, wo, wi)
        assert np.isfinite(value).all() and np.isfinite(pdf).all()
        assert (value >= 0.0).all() and (pdf >= 0.0).all()


@pytest.mark.parametrize("spec", [MaterialSpec(name="g", kind="dielectric", base_color=TINT, roughness=0.0, ior=1.5),
                                  MaterialSpec(name="g", kind="dielectric", roughness=0.0, ior=2.4),
                                  MaterialSpec(name="p", kind="principled", base_color=BASE, roughness=0.0,
                                               transmission=1.0, ior=1.5)],
                         ids=lambda s: f"{s.kind}-ior{s.ior}")
def test_total_internal_reflection(bench, spec):
    """From inside, beyond the critical angle (cos < sqrt(1 - 1 / ior^2)): every sample reflects,
    to the mirror direction, with weight exactly 1 and probability 1."""
    mat = bench.material(spec)
    cos_critical = math.sqrt(1.0 - 1.0 / spec.ior ** 2)
    for cos in (0.999 * cos_critical, 0.5 * cos_critical, 0.01, 1e-4):
        wo = direction(cos)
        s = bench.sample(mat, [0.0, 0.0, -1.0], wo, uniforms(200_000, 90))  # the normal points away from wo
        assert s.valid.all() and s.delta.all()
        assert (s.weight == 1.0).all() and (s.pdf == 1.0).all()
        np.testing.assert_allclose(s.wi, np.broadcast_to([-wo[0], -wo[1], wo[2]], s.wi.shape), atol=2e-7)
