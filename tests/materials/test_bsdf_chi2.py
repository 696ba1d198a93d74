"""Chi-square goodness of fit of every BSDF's sampling against its own pdf (from `eval`), after
Mitsuba's BSDF tests, plus the discrete choices and exact directions of the delta lobes.

Each continuous case draws N = 10^6 samples on the device with a fixed seed and tests their
directions with `tests.stats.chi2.chi2_test` against `Bsdf.eval`'s pdf. Samplers that can fail (a
microfacet reflection or refraction that ends on the wrong side of the macro surface) are tested
in the harness's lossy mode: the failure count is one more category of the multinomial, expected
N * (1 - integral of the pdf).

Expected counts: the pdfs have jumps along curves that are not cell edges (a rough dielectric's
transmission support ends where the microfacets turn horizontal, and GGX's D(h) is still
alpha^2 / pi there: at roughness 1 the harness's fixed Gauss rule overestimated the first row of
transmitted cells by ~10 %, i.e. 8,000 samples). So each cell's probability is integrated
adaptively to 0.1 / N and passed to the harness as a pdf constant on each cell, which its
quadrature integrates exactly (`chi2_adaptive` in bsdf_kernels.py).

Narrow GGX lobes (alpha <= 0.01, i.e. roughness <= 0.1) are far thinner than the harness's cells
in direction space, so those cases are tested after an exact change of variables: every sampled
direction is mapped to its (generalised) half vector h, and h to the *stretched* half vector
h' = normalize(h.x / alpha, h.y / alpha, h.z), where the lobe has unit width. Reflections go to
the upper hemisphere and refractions to the lower one, so the map is one-to-one. The pdf is
carried over with the exact Jacobians:
  d(w_i)/d(h) = 4 |wo.h| (reflection), (wo.h + eta wi.h)^2 / (eta^2 |wi.h|) (refraction; Walter
  et al. 2007, eq. 16-17), and d(h)/d(h') = alpha^2 / |diag(alpha, alpha, 1) h'|^3 (the solid-angle
  Jacobian of a linear map followed by normalisation).
These Jacobians are written here independently of the renderer, so the test still checks eval's
pdf against the samples.

Limit of f32 directions: a sampled wi is a float32 vector, quantised to ~6e-8; its half vector,
(wo + wi) / (2 wo.h), carries that error divided by 2 wo.h, and the stretched slope divides it by
alpha once more: ~6e-8 / (2 cos alpha) ~ 6e-3 for alpha = 1e-4 at cos 0.05, comparable with the
cells. Exact VNDF samples rounded to float32 (a numpy simulation) already fail the test there while
the same samples in float64 pass, so roughness 0.01 is tested from cos 0.99 down to cos 0.2 only;
grazing incidence (0.05, 0.01) is covered from roughness 0.1 up, where the error is < 3e-4.

A rough dielectric at grazing incidence is tested in direction space, even at roughness 0.1: there
its refractions need microfacets tilted by tens of degrees, i.e. slopes of ~100 / alpha, which the
stretch squeezes into a band of height ~1e-3 along the equator of the h' sphere (and reflections
that only just clear the horizon into similar slivers), too thin for any cell quadrature to find.
In direction space those boundaries are the horizon, a cell edge, and the adaptive integration
resolves the narrow lobes.

Significance: ALPHA = 0.01 family-wise over every statistical test in this file (chi-square,
binomial), with Sidak's correction; NUM_TESTS counts them.
"""
import dataclasses
import math

import numpy as np
import pytest
from scipy import stats

from renderer.scene.description import MaterialSpec
from tests.materials.bsdf_kernels import BsdfBench, chi2_adaptive, direction, frame_about, uniforms
from tests.stats.chi2 import sidak_alpha

ALPHA = 0.01
N = 1_000_000
Z = np.array([0.0, 0.0, 1.0])
TILTED = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
BASE = (0.8, 0.5, 0.3)


@dataclasses.dataclass(frozen=True)
class Case:
    name: str
    spec: MaterialSpec
    cos: float  # cos(theta) of wo about the normal on wo's side
    leaving: bool = False  # the normal is flipped relative to wo (inside a dielectric: eta = 1 / ior)
    normal: tuple = tuple(Z)  # the normal on wo's side, world space
    space: str = "direction"  # or "slope": the stretched half-vector space (see the module doc)
    seed: int = 0

    def __str__(self):
        return self.name


def conductor(roughness, tint=(1.0, 1.0, 1.0)):
    return MaterialSpec(name="conductor", kind="conductor", base_color=(0.95, 0.64, 0.54), roughness=roughness,
                        edge_tint=tint)


def dielectric(roughness, ior=1.5, tint=(1.0, 1.0, 1.0)):
    return MaterialSpec(name="glass", kind="dielectric", base_color=tint, roughness=roughness, ior=ior)


def principled(roughness, metallic, transmission, ior=1.5):
    return MaterialSpec(name="principled", kind="principled", base_color=BASE, roughness=roughness,
                        metallic=metallic, transmission=transmission, ior=ior)


def _space(roughness, kind="conductor", cos=1.0):
    """Slope space for the narrow lobes, except a dielectric's at grazing incidence (see the module doc)."""
    if roughness > 0.1 or (kind == "dielectric" and cos < 0.2):
        return "direction"
    return "slope"


def _cases():
    cases = []
    seed = 1000
    for cos in (0.99, 0.05):
        seed += 1
        cases.append(Case(f"diffuse-cos{cos}", MaterialSpec(name="d", kind="diffuse"), cos, seed=seed))
    cases.append(Case("diffuse-tilted-cos0.5", MaterialSpec(name="d", kind="diffuse"), 0.5, normal=tuple(TILTED),
                      seed=seed + 1))
    # Roughness 0.01 (alpha 1e-4) stops at cos 0.2: see the module doc (f32 directions).
    for r, cosines in ((0.01, (0.99, 0.5, 0.2)),) + tuple((r, (0.99, 0.5, 0.05)) for r in (0.1, 0.3, 0.6, 1.0)):
        for cos in cosines:
            seed += 1
            cases.append(Case(f"conductor-r{r}-cos{cos}", conductor(r), cos, space=_space(r), seed=seed))
    for r in (0.1, 0.6):
        seed += 1
        cases.append(Case(f"conductor-r{r}-cos0.01", conductor(r), 0.01, space=_space(r), seed=seed))
    seed += 1
    cases.append(Case("conductor-tint-r0.3-cos0.5", conductor(0.3, tint=(0.6, 0.8, 0.9)), 0.5, seed=seed))
    seed += 1
    cases.append(Case("conductor-tilted-r0.6-cos0.3", conductor(0.6), 0.3, normal=tuple(TILTED), seed=seed))
    for leaving in (False, True):
        for r in (0.1, 0.3, 0.6, 1.0):
            for cos in (0.99, 0.5, 0.05):
                seed += 1
                side = "leaving" if leaving else "entering"
                cases.append(Case(f"dielectric-{side}-r{r}-cos{cos}", dielectric(r), cos, leaving=leaving,
                                  space=_space(r, "dielectric", cos), seed=seed))
    for r, leaving in ((0.1, False), (0.6, True)):
        seed += 1
        side = "leaving" if leaving else "entering"
        cases.append(Case(f"dielectric-{side}-r{r}-cos0.01", dielectric(r), 0.01, leaving=leaving,
                          space=_space(r, "dielectric", 0.01), seed=seed))
    seed += 1
    cases.append(Case("dielectric-tilted-leaving-r0.3-cos0.8", dielectric(0.3, tint=(0.9, 0.7, 0.5)), 0.8,
                      leaving=True, normal=tuple(TILTED), seed=seed))
    seed += 1
    cases.append(Case("dielectric-tilted-entering-r0.1-cos0.4", dielectric(0.1, ior=2.4), 0.4,
                      normal=tuple(TILTED), space="slope", seed=seed))
    # (roughness, metallic, transmission). The mixes of glass with the metal or coat lobes guard the
    # rule that a metal/coat reflection sampled below the surface is a failed sample: counted as a
    # glass refraction it made the sampled density exceed the mixture pdf there.
    mixes = ((0.5, 0.0, 0.0), (0.3, 1.0, 0.0), (0.5, 0.0, 1.0), (0.8, 0.5, 0.6), (1.0, 0.3, 0.0), (0.3, 0.0, 0.5))
    for r, m, t in mixes:
        for cos in (0.99, 0.5, 0.05):
            seed += 1
            cases.append(Case(f"principled-r{r}-m{m}-t{t}-cos{cos}", principled(r, m, t), cos, seed=seed))
    for r, m, t in ((0.5, 0.0, 1.0), (0.3, 0.0, 0.5)):
        seed += 1
        cases.append(Case(f"principled-leaving-r{r}-m{m}-t{t}-cos0.5", principled(r, m, t), 0.5, leaving=True,
                          seed=seed))
    # A conductor with an exact Fresnel from a complex index (a named metal): same lobe, other Fresnel.
    seed += 1
    cases.append(Case("conductor-metal-Au-r0.3-cos0.5", MaterialSpec(name="gold", kind="conductor", metal="Au",
                                                                     roughness=0.3), 0.5, seed=seed))
    return cases


CASES = _cases()
SMOOTH_PRINCIPLED = [  # (metallic, transmission, cos, leaving): a delta part plus the coated diffuse
    (0.0, 0.0, 0.5, False), (0.4, 0.3, 0.5, False), (0.4, 0.3, 0.05, False), (0.0, 0.6, 0.7, True)]
SMOOTH_DIELECTRIC = [  # (ior, cos, leaving): P(reflect) = Fresnel, binomial test
    (1.5, 0.99, False), (1.5, 0.5, False), (1.5, 0.05, False), (1.5, 0.01, False),
    (1.5, 0.99, True), (1.5, 0.8, True), (2.4, 0.3, False)]
NUM_TESTS = len(CASES) + len(SMOOTH_PRINCIPLED) + len(SMOOTH_DIELECTRIC)


@pytest.fixture(scope="module")
def bench(taichi_runtime):
    return BsdfBench()


# --- geometry of a case --------------------------------------------------------------------------


def setup(case):
    """(frame (rows: x, y, the normal on wo's side), world wo, world normal passed to the BSDF, eta)."""
    frame = frame_about(case.normal)
    wo = direction(case.cos) @ frame
    n_side = frame[2]
    normal = -n_side if case.leaving else n_side
    eta = case.spec.ior if not case.leaving else 1.0 / case.spec.ior
    return frame, wo, normal, eta


def alpha_of(roughness):
    return max(roughness * roughness, 1e-4)


def to_slope_space(wi, wo, alpha, eta):
    """Local directions wi (wo.z > 0) -> stretched half vectors h'; refractions in the lower half."""
    refl = wi[:, 2] > 0.0
    scale = 1.0 if eta is None else eta
    h = np.where(refl[:, None], wo + wi, wo + scale * wi)
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    h *= np.where(h[:, 2] < 0.0, -1.0, 1.0)[:, None]
    hp = np.stack([h[:, 0] / alpha, h[:, 1] / alpha, h[:, 2]], axis=1)
    hp /= np.linalg.norm(hp, axis=1, keepdims=True)
    hp[~refl, 2] *= -1.0
    return hp


def slope_space_pdf(pdf_wi, wo, alpha, eta):
    """The density of h' given the density `pdf_wi(local wi)` of wi (solid angle, both)."""

    def pdf(hp):
        up = hp[:, 2] >= 0.0
        m = np.stack([alpha * hp[:, 0], alpha * hp[:, 1], np.abs(hp[:, 2])], axis=1)
        length = np.linalg.norm(m, axis=1)
        h = m / length[:, None]
        jac_stretch = alpha * alpha / length ** 3
        cos_o = h @ wo
        wi_r = 2.0 * cos_o[:, None] * h - wo
        ok = cos_o > 0.0
        if eta is None:
            wi, jac_dir = wi_r, 4.0 * np.abs(cos_o)
            ok &= up & (wi_r[:, 2] > 0.0)
        else:
            sin2_t = (1.0 - cos_o ** 2) / eta ** 2
            cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin2_t))
            wi_t = -wo / eta + (cos_o / eta - cos_t)[:, None] * h
            wi = np.where(up[:, None], wi_r, wi_t)
            cos_ih = np.sum(wi * h, axis=1)
            with np.errstate(divide="ignore", invalid="ignore"):
                jac_t = (cos_o + eta * cos_ih) ** 2 / (eta ** 2 * np.abs(cos_ih))
            jac_dir = np.where(up, 4.0 * np.abs(cos_o), jac_t)
            ok &= np.where(up, wi_r[:, 2] > 0.0, (sin2_t < 1.0) & (wi_t[:, 2] < 0.0) & (np.abs(cos_ih) > 0.0))
        out = np.zeros(len(hp))
        if ok.any():
            out[ok] = pdf_wi(wi[ok]) * jac_dir[ok] * jac_stretch[ok]
        return out

    return pdf


# --- continuous lobes ------------------------------------------------------------------------------


@pytest.mark.parametrize("case", CASES, ids=str)
def test_chi2(bench, case, tmp_path):
    frame, wo, normal, eta = setup(case)
    mat = bench.material(case.spec)
    s = bench.sample(mat, normal, wo, uniforms(N, case.seed))
    assert not s.delta.any()
    pdf_world = bench.pdf_callable(mat, normal, wo)
    common = dict(valid=s.valid, lossy=True, domain="sphere", alpha=ALPHA, num_tests=NUM_TESTS)
    if case.space == "direction":
        result = chi2_adaptive(s.wi, pdf_world, frame=frame, **common)
    else:
        alpha = alpha_of(case.spec.roughness)
        slope_eta = None if case.spec.kind == "conductor" else eta
        wo_local = frame @ wo
        hp = to_slope_space(s.wi.astype(np.float64) @ frame.T, wo_local, alpha, slope_eta)
        pdf = slope_space_pdf(lambda wi_local: pdf_world(wi_local @ frame), wo_local, alpha, slope_eta)
        result = chi2_adaptive(hp, pdf, **common)
    if not result.passed:
        result.write_png(tmp_path / f"{case.name}.png")
    assert result.passed, f"{case.name}\n{result.report}"
    if case.spec.kind == "diffuse":
        assert result.failed_count == 0  # the cosine warp never fails


# --- delta lobes -------------------------------------------------------------------------------------


def fresnel_dielectric(cos_i, eta):
    """Unpolarised Fresnel reflectance (numpy, float64); eta = n_transmitted / n_incident."""
    sin2_t = (1.0 - cos_i ** 2) / eta ** 2
    if sin2_t >= 1.0:
        return 1.0, 0.0
    cos_t = math.sqrt(1.0 - sin2_t)
    rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return 0.5 * (rs * rs + rp * rp), cos_t


def check_delta_directions(wi, wo, n_side, eta, reflect):
    """Mirror directions for reflections, Snell's law in the plane of incidence for refractions."""
    wi = wi.astype(np.float64)
    cos_i = wo @ n_side
    mirror = 2.0 * cos_i * n_side - wo
    assert np.abs(wi[reflect] - mirror).max(initial=0.0) < 2e-6
    if (~reflect).any():
        _, cos_t = fresnel_dielectric(cos_i, eta)
        snell = -wo / eta + (cos_i / eta - cos_t) * n_side
        t = wi[~reflect]
        assert np.abs(t - snell).max() < 2e-6
        sin_t = np.linalg.norm(t - np.outer(t @ n_side, n_side), axis=1)
        sin_i = math.sqrt(max(0.0, 1.0 - cos_i * cos_i))
        assert np.abs(eta * sin_t - sin_i).max() < 4e-6  # n_t sin(theta_t) = n_i sin(theta_i)


@pytest.mark.parametrize("ior,cos,leaving", SMOOTH_DIELECTRIC)
def test_smooth_dielectric_reflects_with_the_fresnel_probability(bench, ior, cos, leaving):
    case = Case("smooth", dielectric(0.0, ior=ior, tint=(0.9, 0.8, 0.7)), cos, leaving=leaving,
                normal=tuple(TILTED))
    frame, wo, normal, eta = setup(case)
    seed = 7000 + SMOOTH_DIELECTRIC.index((ior, cos, leaving))
    s = bench.sample(bench.material(case.spec), normal, wo, uniforms(N, seed))
    assert s.valid.all() and s.delta.all()
    n_side = frame[2]
    reflect = s.wi.astype(np.float64) @ n_side > 0.0
    f, _ = fresnel_dielectric(cos, eta)
    k = int(reflect.sum())
    p_value = stats.binomtest(k, N, f).pvalue
    assert p_value >= sidak_alpha(ALPHA, NUM_TESTS), f"P(reflect) {k / N:.5f} vs Fresnel {f:.5f}: p = {p_value:.3g}"
    # the pdf of a delta choice is its probability; weights: 1 (reflection), tint / eta^2 (refraction)
    np.testing.assert_allclose(s.pdf[reflect], f, rtol=1e-5)
    np.testing.assert_allclose(s.pdf[~reflect], 1.0 - f, rtol=1e-5)
    np.testing.assert_allclose(s.weight[reflect], 1.0, rtol=1e-6)
    np.testing.assert_allclose(s.weight[~reflect], np.broadcast_to(np.array([0.9, 0.8, 0.7]) / eta ** 2,
                                                                    (N - k, 3)), rtol=1e-5)
    check_delta_directions(s.wi, wo, n_side, eta, reflect)


def test_smooth_conductor_is_a_mirror(bench):
    for cos in (1.0, 0.7, 0.05, 1e-3):
        case = Case("mirror", conductor(0.0, tint=(0.5, 0.8, 1.0)), cos, normal=tuple(TILTED))
        frame, wo, normal, _ = setup(case)
        s = bench.sample(bench.material(case.spec), normal, wo, uniforms(1000, 3))
        assert s.valid.all() and s.delta.all()
        np.testing.assert_allclose(s.pdf, 1.0)
        check_delta_directions(s.wi, wo, frame[2], 1.0, np.ones(len(s.wi), bool))
        assert np.ptp(s.weight, axis=0).max() == 0.0  # the weight depends on wo only
        value, pdf = bench.eval(bench.material(case.spec), normal, wo, s.wi)
        assert not value.any() and not pdf.any()  # eval covers the non-delta parts only


def principled_lobe_probabilities(m, t, base, ior, cos):
    """The principled model's lobe-selection probabilities (metal, glass, coat specular, coat
    diffuse), as documented in renderer/materials/bsdf.py, written out in numpy."""
    lum = lambda c: 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
    schlick = np.asarray(base) + (1.0 - np.asarray(base)) * (1.0 - cos) ** 5
    f_view, _ = fresnel_dielectric(cos, ior)
    opaque = (1.0 - m) * (1.0 - t)
    a = np.array([m * max(lum(schlick), 0.05), (1.0 - m) * t, opaque * f_view,
                  opaque * (1.0 - f_view) * max(lum(base), 0.05)])
    return a / a.sum()


@pytest.mark.parametrize("metallic,transmission,cos,leaving", SMOOTH_PRINCIPLED)
def test_smooth_principled(bench, metallic, transmission, cos, leaving, tmp_path):
    """Roughness 0: delta metal, glass and coat lobes plus the (continuous) coated diffuse base.
    The delta samples are one category of the chi-square test with probability 1 - p(diffuse)."""
    case = Case("smooth-principled", principled(0.0, metallic, transmission), cos, leaving=leaving)
    frame, wo, normal, eta = setup(case)
    mat = bench.material(case.spec)
    seed = 9000 + SMOOTH_PRINCIPLED.index((metallic, transmission, cos, leaving))
    s = bench.sample(mat, normal, wo, uniforms(N, seed))
    p = principled_lobe_probabilities(metallic, transmission, BASE, case.spec.ior, cos)
    result = chi2_adaptive(s.wi, bench.pdf_callable(mat, normal, wo), frame=frame, valid=s.valid, delta=s.delta,
                           delta_probability=1.0 - p[3], domain="sphere", alpha=ALPHA, num_tests=NUM_TESTS)
    if not result.passed:
        result.write_png(tmp_path / "smooth-principled.png")
    assert result.passed, result.report
    assert s.valid.all()
    d = s.delta
    reflect = s.wi[d].astype(np.float64) @ frame[2] > 0.0
    check_delta_directions(s.wi[d], wo, frame[2], eta, reflect)
