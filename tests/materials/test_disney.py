"""The `disney` kind (Mitsuba 3's principled and principledthin): its values and densities against
Mitsuba's own BSDF at the same directions, its sampling against its density (chi-square), the
sample weights against eval / pdf, reciprocity of its reflection, and its albedo (a white furnace)
against Mitsuba's sampled one.

Statistics: fixed seeds; ALPHA = 0.01 family-wise over the NUM_TESTS statistical tests of this file
with Sidak's correction. Deterministic checks state their tolerance.
"""
import math

import numpy as np
import pytest
from scipy import stats

from renderer.materials.table import MaterialRows
from renderer.scene.description import MaterialSpec
from renderer.scene.features import Features
from tests.materials.bsdf_kernels import FixedBench, chi2_adaptive, direction, frame_about, uniforms
from tests.stats.chi2 import sidak_alpha

ALPHA = 0.01
N = 400_000


def disney(name, **fields):
    return MaterialSpec(name, kind="disney", **{"base_color": (0.6, 0.35, 0.2), "roughness": 0.4, **fields})


# Mitsuba's parameters of each case (thin: principledthin) and Lantern's spec.
CASES = {
    "diffuse-retro": ({"roughness": 0.8}, disney("dr", roughness=0.8)),
    "metal-aniso": ({"metallic": 0.7, "anisotropic": 0.6, "roughness": 0.3},
                    disney("ma", metallic=0.7, anisotropic=0.6, roughness=0.3)),
    "coat-sheen-tints": ({"clearcoat": 0.8, "clearcoat_gloss": 0.4, "sheen": 0.9, "sheen_tint": 0.5,
                          "spec_tint": 0.6, "flatness": 0.5, "specular": 0.7},
                         disney("cs", clearcoat=0.8, clearcoat_gloss=0.4, sheen=0.9, sheen_tint=0.5, spec_tint=0.6,
                                flatness=0.5, ior=2.0 / (1.0 - math.sqrt(0.08 * 0.7)) - 1.0)),
    "glass-like": ({"spec_trans": 0.8, "eta": 1.45, "roughness": 0.25, "metallic": 0.1, "anisotropic": 0.3},
                   disney("gl", transmission=0.8, ior=1.45, roughness=0.25, metallic=0.1, anisotropic=0.3)),
    "thin": ({"thin": True, "spec_trans": 0.5, "diff_trans": 0.8, "eta": 1.33, "sheen": 0.5, "spec_tint": 0.3,
              "anisotropic": 0.4, "roughness": 0.5},
             disney("th", thin=True, transmission=0.5, diff_trans=0.8, ior=1.33, sheen=0.5, spec_tint=0.3,
                    anisotropic=0.4, roughness=0.5)),
}
# (case, cos(wo) on the normal's side, or below it: the back / inside).
SAMPLING = [("diffuse-retro", 0.7), ("metal-aniso", 0.3), ("coat-sheen-tints", 0.9), ("glass-like", 0.6),
            ("glass-like", -0.6), ("thin", 0.5), ("thin", -0.8)]
FURNACE = [("coat-sheen-tints", 0.5), ("glass-like", 0.8), ("glass-like", -0.5), ("thin", 0.4)]
NUM_TESTS = len(SAMPLING) + len(FURNACE)
FEATURES = Features(material_kinds=frozenset({"disney"}), has_anisotropy=True, has_thin=True)


@pytest.fixture(scope="module")
def bench(taichi_runtime):
    return FixedBench([spec for _, spec in CASES.values()], FEATURES)


def _mitsuba(variant):
    mi = pytest.importorskip("mitsuba", reason="Mitsuba is the project's optional `reference` extra")
    try:
        mi.set_variant(variant)
    except Exception:  # noqa: BLE001 - a wheel without LLVM
        pytest.skip(f"Mitsuba's {variant} variant is not available")
    return mi


def _mitsuba_bsdf(mi, params, spec):
    params = {"roughness": spec.roughness, **params}
    thin = params.pop("thin", False)
    colour = CASES["diffuse-retro"][1].base_color
    return mi.load_dict({"type": "principledthin" if thin else "principled",
                         "base_color": {"type": "rgb", "value": list(colour)}, **params})


def _surface(mi, dr, wi):
    """Mitsuba's interaction with the world frame as its shading frame (x: the tangent, z: the normal),
    which Lantern's frame for normal +z and no dp/du is too."""
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.sh_frame = mi.Frame3f(mi.Vector3f(1.0, 0.0, 0.0), mi.Vector3f(0.0, 1.0, 0.0), mi.Vector3f(0.0, 0.0, 1.0))
    si.n = mi.Normal3f(0.0, 0.0, 1.0)
    si.wi = mi.Vector3f(*(np.ascontiguousarray(wi[:, k]) for k in range(3)))
    return si


def _random_directions(rng, n):
    v = rng.normal(size=(n, 3))
    return (v / np.linalg.norm(v, axis=1, keepdims=True)).astype(np.float32)


@pytest.mark.parametrize("case", list(CASES))
def test_eval_and_pdf_match_mitsubas(bench, case):
    """At 2,000 random pairs of directions on both sides, Lantern's f |cos| and pdf are Mitsuba's:
    both compute the same f32 formulas in different orders, so they agree to 1e-3 relative (plus
    1e-5 of the case's largest value, for values rounding near zero), and at most 0.5% of the pairs
    may fall on opposite sides of a mask's edge (a compatibility test at a rounding distance)."""
    mi = _mitsuba("llvm_ad_rgb")
    import drjit as dr

    params, spec = CASES[case]
    rng = np.random.default_rng(7)
    wo, wi = _random_directions(rng, 2000), _random_directions(rng, 2000)
    wo = wo[np.abs(wo[:, 2]) > 1e-3]
    wi = wi[: len(wo)]
    value, pdf = bench.eval(bench.material(spec), (0.0, 0.0, 1.0), wo, wi)
    bsdf = _mitsuba_bsdf(mi, params, spec)
    theirs_value, theirs_pdf = bsdf.eval_pdf(mi.BSDFContext(), _surface(mi, dr, wo),
                                             mi.Vector3f(*(np.ascontiguousarray(wi[:, k]) for k in range(3))))
    theirs_value = np.stack([np.asarray(theirs_value[k]) for k in range(3)], axis=1)
    theirs_pdf = np.asarray(theirs_pdf)
    assert np.count_nonzero(theirs_value.max(axis=1) > 0) > len(wo) // 8  # the lobes are exercised
    for ours, theirs in ((value, theirs_value), (pdf, theirs_pdf)):
        close = np.isclose(ours, theirs, rtol=1e-3, atol=1e-5 * float(np.max(theirs)))
        close = close.all(axis=1) if close.ndim == 2 else close
        bad = np.flatnonzero(~close)
        assert len(bad) <= 0.005 * len(wo), (len(bad), wo[bad[:3]], wi[bad[:3]], ours[bad[:3]], theirs[bad[:3]])


@pytest.mark.parametrize("case, cos", SAMPLING, ids=[f"{c}-cos{v}" for c, v in SAMPLING])
def test_sampling_matches_pdf(bench, case, cos):
    """The directions `sample` draws follow `eval`'s pdf (chi-square over the sphere, failures
    counted as a cell of their own)."""
    spec = CASES[case][1]
    wo = direction(cos, 0.4)
    s = bench.sample(bench.material(spec), (0.0, 0.0, 1.0), wo, uniforms(N, 4000 + len(case) + int(cos * 10)))
    # Mitsuba's sampler fails where a microfacet sends the direction to the wrong side; the pdf
    # then integrates to the chance of success, which the test's failure cell holds it to.
    result = chi2_adaptive(s.wi.astype(np.float64), bench.pdf_callable(bench.material(spec), (0.0, 0.0, 1.0), wo),
                           valid=s.valid, lossy=True, frame=frame_about((0.0, 0.0, 1.0)))
    assert result.p_value > sidak_alpha(ALPHA, NUM_TESTS), result


@pytest.mark.parametrize("case, cos", SAMPLING, ids=[f"{c}-cos{v}" for c, v in SAMPLING])
def test_sample_weights_are_eval_over_pdf(bench, case, cos):
    """Each sample's weight and pdf are eval's value and pdf at its direction (f32 rounding)."""
    spec = CASES[case][1]
    s = bench.sample(bench.material(spec), (0.0, 0.0, 1.0), direction(cos, 0.4), uniforms(20_000, 17))
    v = s.valid
    assert v.mean() > 0.5
    np.testing.assert_allclose(s.pdf[v], s.eval_pdf[v], rtol=1e-4)
    np.testing.assert_allclose(s.weight[v] * s.pdf[v, None], s.eval_value[v], rtol=1e-3, atol=1e-6)


@pytest.mark.parametrize("case", ["diffuse-retro", "metal-aniso", "coat-sheen-tints", "thin"])
def test_reflection_is_reciprocal(bench, case):
    """f(wo, wi) = f(wi, wo) for reflection on the front: every reflecting lobe is symmetric (f32
    rounding: 1e-3 relative)."""
    spec = CASES[case][1]
    rng = np.random.default_rng(3)
    a, b = _random_directions(rng, 3000), _random_directions(rng, 3000)
    a[:, 2], b[:, 2] = np.abs(a[:, 2]) + 1e-3, np.abs(b[:, 2]) + 1e-3
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b /= np.linalg.norm(b, axis=1, keepdims=True)
    mat = bench.material(spec)
    forward, _ = bench.eval(mat, (0.0, 0.0, 1.0), a, b)
    backward, _ = bench.eval(mat, (0.0, 0.0, 1.0), b, a)
    np.testing.assert_allclose(forward / b[:, 2:], backward / a[:, 2:], rtol=1e-3, atol=1e-6)


@pytest.mark.parametrize("case, cos", FURNACE, ids=[f"{c}-cos{v}" for c, v in FURNACE])
def test_white_furnace_matches_mitsubas(bench, case, cos):
    """Under uniform white light the surface sends back what Mitsuba's does: the mean sample weight
    (the albedo, transmission included) of 400,000 samples each, held equal by a two-sample z-test.
    Disney's model is not energy-conserving (its retro-reflection and sheen can add light); what is
    tested is that it is Mitsuba's."""
    mi = _mitsuba("llvm_ad_rgb")
    import drjit as dr

    params, spec = CASES[case]
    wo = direction(cos, 0.4).astype(np.float32)
    s = bench.sample(bench.material(spec), (0.0, 0.0, 1.0), wo, uniforms(N, 900 + int(cos * 10) + len(case)))
    ours = np.where(s.valid[:, None], s.weight, 0.0).astype(np.float64)
    u = np.random.default_rng(41 + len(case)).random((3, N)).astype(np.float32)
    si = _surface(mi, dr, np.repeat(wo[None, :], N, axis=0))
    _, weight = _mitsuba_bsdf(mi, params, spec).sample(mi.BSDFContext(), si, mi.Float(u[0]),
                                                 mi.Point2f(mi.Float(u[1]), mi.Float(u[2])))
    theirs = np.stack([np.asarray(weight[k], np.float64) for k in range(3)], axis=1)
    for channel in range(3):
        a, b = ours[:, channel], theirs[:, channel]
        z = (a.mean() - b.mean()) / math.sqrt(a.var(ddof=1) / len(a) + b.var(ddof=1) / len(b))
        assert 2.0 * stats.norm.sf(abs(z)) > sidak_alpha(ALPHA, NUM_TESTS) / 3.0, (channel, a.mean(), b.mean(), z)


def test_anisotropic_rows_ask_for_the_surfaces_dp_du():
    """A Disney row with `anisotropic` (a number or a texture) orients its lobe along dp/du, so the
    geometry must carry it (without it the lobe turned with an arbitrary tangent: an analytic sphere
    rendered 0.4% darker than Mitsuba's, mean z = -16 at 35,000 spp)."""
    from renderer.materials.mapped_frame_rows import needs_uv_partials
    from renderer.scene.description import TextureSpec

    def needs(spec, slots=None):
        rows = MaterialRows()
        rows.add_spec(spec, slots)
        return needs_uv_partials(rows.arrays()), rows.uses()["anisotropy"]

    assert needs(disney("plain")) == (False, False)
    assert needs(disney("aniso", anisotropic=0.5)) == (True, True)
    textured = disney("tex", parameter_textures=(("anisotropic", TextureSpec("checkerboard")),))
    assert needs(textured, {"anisotropic": 0}) == (True, True)
