"""The `diffuse_transmission` kind (pbrt-v4's diffusetransmission): its sampling against its pdf
(chi-square over the whole sphere), the sample weight against f |cos| / pdf, reciprocity, the
split between the two sides (pbrt's: by the colours' largest channels), and a white sheet that keeps
all the light it receives.

Statistics: fixed seeds; ALPHA = 0.01 family-wise over the chi-square tests with Sidak's correction.
Deterministic checks state their tolerance."""
import numpy as np
import pytest
from scipy import stats

from renderer.scene.description import MaterialSpec
from renderer.scene.features import Features
from tests.materials.bsdf_kernels import FixedBench, chi2_adaptive, direction, frame_about, uniforms

ALPHA = 0.01
N = 400_000
SHEETS = {
    "leaf": MaterialSpec("leaf", kind="diffuse_transmission", base_color=(0.2, 0.5, 0.1), transmittance=(0.1, 0.4, 0.05)),
    "mostly-through": MaterialSpec("through", kind="diffuse_transmission", base_color=(0.1, 0.1, 0.1),
                                   transmittance=(0.7, 0.6, 0.5)),
    "white": MaterialSpec("white", kind="diffuse_transmission", base_color=(0.6, 0.6, 0.6),
                          transmittance=(0.4, 0.4, 0.4)),
    "opaque": MaterialSpec("opaque", kind="diffuse_transmission", base_color=(0.5, 0.5, 0.5),
                           transmittance=(0.0, 0.0, 0.0)),
}
CHI2_CASES = [(name, cos) for name in ("leaf", "mostly-through") for cos in (0.9, 0.15)]
FEATURES = Features(material_kinds=frozenset({"diffuse_transmission"}))


@pytest.fixture(scope="module")
def bench(taichi_runtime):
    return FixedBench(list(SHEETS.values()), FEATURES)


def _reflect_probability(spec):
    pr, pt = max(spec.base_color), max(spec.transmittance)
    return pr / (pr + pt)


@pytest.mark.parametrize("name, cos", CHI2_CASES)
def test_sampling_follows_the_pdf(bench, tmp_path, name, cos):
    frame = frame_about((0.2, 0.3, 0.9))
    wo = direction(cos) @ frame
    mat = bench.material(SHEETS[name])
    s = bench.sample(mat, frame[2], wo, uniforms(N, 100 + len(name) + int(cos * 10)))
    result = chi2_adaptive(s.wi, bench.pdf_callable(mat, frame[2], wo), frame=frame, valid=s.valid,
                           domain="sphere", alpha=ALPHA, num_tests=len(CHI2_CASES))
    if not result.passed:
        result.write_png(tmp_path / f"{name}.png")
    assert result.passed, f"{name}\n{result.report}"
    # pbrt's split: the share of samples on wo's side is pr / (pr + pt) (a z-test at the same level)
    below = (s.wi @ frame[2] < 0.0)[s.valid]
    p = 1.0 - _reflect_probability(SHEETS[name])
    z = (below.mean() - p) / np.sqrt(p * (1 - p) / len(below))
    assert abs(z) < stats.norm.ppf(1 - (1 - (1 - ALPHA) ** (1 / len(CHI2_CASES))) / 2), (below.mean(), p)


@pytest.mark.parametrize("name", list(SHEETS))
def test_weight_is_f_cos_over_pdf_and_eval_agrees(bench, name):
    frame = frame_about((0.0, 0.0, 1.0))
    wo = direction(0.6) @ frame
    mat = bench.material(SHEETS[name])
    s = bench.sample(mat, frame[2], wo, uniforms(4096, 7))
    ok = s.valid
    assert ok.mean() > 0.99 and not s.delta.any()
    np.testing.assert_allclose(s.eval_pdf[ok], s.pdf[ok], rtol=1e-5)
    np.testing.assert_allclose(s.weight[ok] * s.pdf[ok, None], s.eval_value[ok], rtol=1e-5, atol=1e-7)
    spec = SHEETS[name]
    side = np.where((s.wi[ok] @ frame[2] > 0.0)[:, None], np.array(spec.base_color), np.array(spec.transmittance))
    np.testing.assert_allclose(s.eval_value[ok], side * np.abs(s.wi[ok] @ frame[2])[:, None] / np.pi, rtol=1e-5)
    if max(spec.transmittance) == 0.0:  # nothing goes through: no sample is drawn there
        assert (s.wi[ok] @ frame[2] > 0.0).all()


def test_reciprocity_on_both_sides(bench):
    frame = frame_about((0.1, -0.4, 0.8))
    mat = bench.material(SHEETS["leaf"])
    rng = np.random.default_rng(5)
    a = rng.normal(size=(2000, 3))
    b = rng.normal(size=(2000, 3))
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b /= np.linalg.norm(b, axis=1, keepdims=True)
    n = frame[2]
    f_ab = bench.eval(mat, np.repeat(n[None], len(a), 0), a, b)[0] / np.abs(b @ n)[:, None]
    f_ba = bench.eval(mat, np.repeat(n[None], len(a), 0), b, a)[0] / np.abs(a @ n)[:, None]
    np.testing.assert_allclose(f_ab, f_ba, rtol=1e-4, atol=1e-6)


def test_a_white_sheet_keeps_all_the_light(bench):
    """Reflectance + transmittance = 1: every sample's weight is exactly 1 (float rounding), so
    the albedo is 1 from any direction."""
    frame = frame_about((0.0, 0.0, 1.0))
    mat = bench.material(SHEETS["white"])
    for cos in (0.95, 0.3, 0.02):
        s = bench.sample(mat, frame[2], direction(cos) @ frame, uniforms(20000, 11))
        np.testing.assert_allclose(s.weight[s.valid], 1.0, rtol=1e-6)
        assert s.valid.mean() > 0.999
