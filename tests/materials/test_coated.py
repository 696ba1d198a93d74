"""The `coated` kind (pbrt-v4's coateddiffuse and coatedconductor, renderer/materials/coated.py).

Its f and pdf are pbrt's Monte Carlo estimates, fixed functions of (wo, wi) through a hash, so:
- the numpy transcription (tests/materials/coated_reference.py) draws the same numbers from the same
  hash and must agree with the device's f and pdf to rounding (deterministic, relative 1e-4);
- `sample` draws pbrt's walk, whose density has no closed form: what must hold is that its weight
  integrates like f, E[weight 1{wi in C}] = int_C f |cos| dwi for every cell C, the right side
  estimated by evaluating f at stratified directions of C (each evaluation an independent walk);
  a z-test per cell with both sides' sample variances (a chi-square of the directions against
  the pdf would test pbrt's pdf estimate, which is not the walk's density and is not meant to be);
- the pdf `sample` reports for MIS is the pdf estimate at the sampled direction, the same number
  `evaluate` gives there (deterministic), so MIS weights of both techniques are computed alike;
- white furnace: a white diffuse base under a smooth clear coat with no medium keeps all the
  light: every walk leaves with weight 1, and the hemispherical integral of the f estimate plus
  the coat's Fresnel reflectance is 1 (z-test);
- reciprocity: the layered BSDF is reciprocal in expectation, f(wo, wi) = f(wi, wo); each
  estimate uses other numbers, so the means over replicates (directions jittered by 1e-6, which
  moves f by far less than its noise but changes the hash) are compared (two-sample z-test).

Statistics: fixed seeds; ALPHA = 0.01 family-wise over the NUM_TESTS statistical tests of this file
with Sidak's correction (per-cell tests share their case's level, Sidak again).
"""
import numpy as np
import pytest
from scipy import stats

from renderer.materials.table import MaterialRows
from renderer.scene.description import MaterialSpec
from tests.materials.bsdf_kernels import direction, uniforms
from tests.materials.coated_kernels import CoatBench, params_row
from tests.materials.coated_reference import Layered, fr_dielectric
from tests.stats.chi2 import sidak_alpha

ALPHA = 0.01
CASES = {
    "smooth-diffuse": params_row(reflectance=(0.8, 0.6, 0.4)),
    "rough-diffuse": params_row(alpha_x=0.3, reflectance=(0.9, 0.5, 0.2)),
    "aniso-conductor": params_row(alpha_x=0.2, alpha_y=0.05, base="conductor", c_alpha=0.1),
    "medium": params_row(alpha_x=0.1, albedo=(0.8, 0.5, 0.2), thickness=0.5, g=0.3, n_samples=4),
    "smooth-top-medium-conductor": params_row(base="conductor", c_alpha=0.2, albedo=(0.9, 0.9, 0.9), thickness=0.2,
                                              g=-0.4),
    "smooth-top-rough-conductor": params_row(base="conductor", c_alpha=0.25),
    "smooth-medium-diffuse": params_row(reflectance=(0.7, 0.7, 0.7), albedo=(0.9, 0.6, 0.3), thickness=0.3, g=0.5,
                                        n_samples=2),
}
WHITE = params_row(reflectance=(1.0, 1.0, 1.0), thickness=0.0, max_depth=100)
CASE_NAMES = list(CASES)
ROWS = [*CASES.values(), WHITE]
WHITE_ROW = len(ROWS) - 1
# Smooth coats only: with a rough coat pbrt's f estimate is not consistent with its sampling (see
# test_rough_coat_estimates_differ_as_pbrts).
CELL_CASES = [("smooth-diffuse", 0.5), ("smooth-top-rough-conductor", 0.7), ("smooth-top-medium-conductor", 0.6),
              ("smooth-medium-diffuse", 0.3)]
RECIPROCITY = ["smooth-diffuse", "smooth-top-rough-conductor", "smooth-top-medium-conductor", "smooth-medium-diffuse"]
FURNACE_COS = (0.9, 0.35)
NUM_TESTS = len(CELL_CASES) + len(RECIPROCITY) + len(FURNACE_COS)
N_CELL_COS, N_CELL_PHI = 6, 8


@pytest.fixture(scope="module")
def bench(taichi_runtime):
    return CoatBench(ROWS)


def test_matches_the_numpy_walk(bench):
    """Same hash, same walks: the device's f and pdf against the numpy transcription."""
    wos = np.array([direction(c, p) for c, p in [(0.9, 0.1), (0.5, 2.0), (0.15, 4.0)]], np.float32)
    wis = np.array([direction(c, p) for c, p in [(0.8, 1.1), (0.3, 3.0), (0.6, 5.5), (0.95, 0.2)]], np.float32)
    for row, name in enumerate(CASE_NAMES):
        reference = Layered(CASES[name])
        for wo in wos:
            f, pdf = bench.f(row, wo, wis), bench.pdf(row, wo, wis)
            for j, wi in enumerate(wis):
                ref_f = reference.f(wo.astype(np.float64), wi.astype(np.float64))
                ref_pdf = reference.pdf(wo.astype(np.float64), wi.astype(np.float64))
                assert np.all(ref_f > 0.0), (name, wo, wi)
                np.testing.assert_allclose(f[j], ref_f, rtol=1e-4, atol=1e-7, err_msg=f"{name} {wo} {wi}")
                np.testing.assert_allclose(pdf[j], ref_pdf, rtol=1e-4, err_msg=f"{name} {wo} {wi}")


def _cell_directions(m, seed):
    """m stratified directions in each of the hemisphere's equal-area cells (cos in equal steps,
    phi in equal steps): (cells, m, 3)."""
    rng = np.random.default_rng(seed)
    cells = []
    for i in range(N_CELL_COS):
        for k in range(N_CELL_PHI):
            c = (i + rng.random(m)) / N_CELL_COS
            phi = 2.0 * np.pi * (k + rng.random(m)) / N_CELL_PHI
            s = np.sqrt(np.maximum(0.0, 1.0 - c * c))
            cells.append(np.stack([s * np.cos(phi), s * np.sin(phi), c], axis=1))
    return np.array(cells)


def _cell_index(wi):
    c = np.clip((wi[:, 2] * N_CELL_COS).astype(int), 0, N_CELL_COS - 1)
    phi = np.mod(np.arctan2(wi[:, 1], wi[:, 0]), 2.0 * np.pi)
    k = np.clip((phi / (2.0 * np.pi) * N_CELL_PHI).astype(int), 0, N_CELL_PHI - 1)
    return c * N_CELL_PHI + k


@pytest.mark.parametrize("name, cos_o", CELL_CASES)
def test_sample_weights_integrate_like_f(bench, name, cos_o):
    row = CASE_NAMES.index(name)
    wo = direction(cos_o, 0.4)
    n, m = 400_000, 300
    s = bench.sample(row, wo, uniforms(n, 11 + row))
    keep = (s["valid"] == 1) & (s["delta"] == 0)
    x = np.zeros((n, N_CELL_COS * N_CELL_PHI))
    x[np.flatnonzero(keep), _cell_index(s["wi"][keep].astype(np.float64))] = s["weight"][keep].sum(axis=1)
    a_mean, a_var = x.mean(axis=0), x.var(axis=0, ddof=1) / n
    dirs = _cell_directions(m, 7 + row)
    area = 2.0 * np.pi / (N_CELL_COS * N_CELL_PHI)
    values = (bench.f(row, wo, dirs.reshape(-1, 3)).sum(axis=1) * dirs.reshape(-1, 3)[:, 2]).reshape(len(dirs), m)
    b_mean, b_var = area * values.mean(axis=1), area ** 2 * values.var(axis=1, ddof=1) / m
    z = (a_mean - b_mean) / np.sqrt(a_var + b_var + 1e-30)
    p_min = 2.0 * stats.norm.sf(np.abs(z)).min()
    assert p_min > sidak_alpha(sidak_alpha(ALPHA, NUM_TESTS), len(z)), (name, z.round(2), a_mean, b_mean)
    assert keep.mean() > 0.2  # the walks do leave


def test_sampled_pdf_is_the_evaluated_pdf(bench):
    """For MIS: the pdf of a non-delta sample is the pdf estimate `evaluate` gives at its direction."""
    for row, name in enumerate(CASE_NAMES):
        wo = direction(0.6, 1.0)
        s = bench.sample(row, wo, uniforms(2000, 3 + row))
        keep = (s["valid"] == 1) & (s["delta"] == 0)
        assert keep.sum() > 100, name
        pdf = bench.pdf(row, wo, s["wi"][keep])
        np.testing.assert_allclose(s["pdf"][keep], pdf, rtol=1e-6, err_msg=name)
        assert np.all(pdf > 0.0)


@pytest.mark.parametrize("cos_o", FURNACE_COS)
def test_white_furnace(bench, cos_o):
    wo = direction(cos_o, 2.0)
    s = bench.sample(WHITE_ROW, wo, uniforms(100_000, 5))
    # Every interface is lossless and the slab clear: each walk leaves, with weight exactly 1.
    assert np.all(s["valid"] == 1)
    np.testing.assert_allclose(s["weight"], 1.0, rtol=1e-5)
    # The delta reflection's share is the coat's Fresnel reflectance.
    f_r = fr_dielectric(cos_o, 1.5)
    assert abs(s["delta"].mean() - f_r) < 5.0 * np.sqrt(f_r * (1.0 - f_r) / len(s["delta"]))
    # The f estimate over the hemisphere (uniform stratified directions) carries the rest.
    dirs = _cell_directions(2000, 17).reshape(-1, 3)
    values = bench.f(WHITE_ROW, wo, dirs)[:, 0] * dirs[:, 2] * 2.0 * np.pi
    z = (values.mean() + f_r - 1.0) / (values.std(ddof=1) / np.sqrt(len(values)))
    assert 2.0 * stats.norm.sf(abs(z)) > sidak_alpha(ALPHA, NUM_TESTS), (values.mean() + f_r, z)


@pytest.mark.parametrize("name", RECIPROCITY)
def test_reciprocity(bench, name):
    row = CASE_NAMES.index(name)
    k = 20_000
    rng = np.random.default_rng(23 + row)
    a, b = direction(0.8, 0.5), direction(0.35, 2.5)

    def jittered(d):
        v = d + 1e-6 * rng.standard_normal((k, 3))
        return v / np.linalg.norm(v, axis=1, keepdims=True)

    wa, wb = jittered(a), jittered(b)
    f_ab = bench.f(row, wa, wb)  # pairwise: (wa[i], wb[i])
    f_ba = bench.f(row, wb, wa)
    d = f_ab.sum(axis=1) - f_ba.sum(axis=1)
    z = d.mean() / (d.std(ddof=1) / np.sqrt(k))
    assert 2.0 * stats.norm.sf(abs(z)) > sidak_alpha(ALPHA, NUM_TESTS), (name, f_ab.mean(0), f_ba.mean(0), z)


def test_scene_rows():
    """A scene material's row: the base's id, the slab's columns, the conductor's index (copper by
    default, pbrt's), and the interface's width from the perceptual roughness."""
    rows = MaterialRows()
    rows.add_spec(MaterialSpec("d", kind="coated", base_color=(0.2, 0.3, 0.4), roughness=0.5, coat_thickness=0.1,
                               coat_albedo=(0.5, 0.5, 0.5), coat_g=0.2, coat_maxdepth=20, coat_nsamples=2))
    rows.add_spec(MaterialSpec("c", kind="coated", coat_base="conductor", conductor_roughness=0.3))
    rows.add_spec(MaterialSpec("e", kind="coated", coat_base="conductor", eta=(0.2, 0.4, 1.5), k=(3.0, 2.5, 2.0)))
    a = rows.arrays()
    np.testing.assert_array_equal(a["coat_base"], [0, 1, 1])
    np.testing.assert_allclose(a["coat_thickness"], [0.1, 0.01, 0.01])
    np.testing.assert_allclose(a["coat_albedo"][0], 0.5)
    np.testing.assert_array_equal(a["coat_maxdepth"], [20, 10, 10])
    np.testing.assert_array_equal(a["coat_nsamples"], [2, 1, 1])
    np.testing.assert_allclose(a["conductor_roughness"], [0.0, 0.3, 0.0])
    np.testing.assert_array_equal(a["complex_ior"], [0, 1, 1])
    assert a["k"][1][0] > 3.0  # copper
    np.testing.assert_allclose(a["eta"][2], (0.2, 0.4, 1.5), rtol=1e-6)
    assert a["roughness"][1] == 0.0  # pbrt's coats are smooth unless given a roughness


def test_rough_coat_estimates_differ_as_pbrts(bench):
    """pbrt-v4's f with a rough coat weighs its exit connection by the power heuristic of the base's
    sample pdf against the coat's PDF(-w, wi), a density of wi rather than of the inside direction,
    so the two weights of that connection do not sum to one and f's estimate runs above what its
    walk samples (measured: 7% for the rough diffuse case). Lantern keeps pbrt's estimate (its
    images are pbrt's); this pins the size of the difference (a smooth coat has none: the cell
    tests above)."""
    row = CASE_NAMES.index("rough-diffuse")
    wo = direction(0.7, 0.4)
    n = 400_000
    s = bench.sample(row, wo, uniforms(n, 31))
    w = np.where(((s["valid"] == 1) & (s["delta"] == 0))[:, None], s["weight"], 0.0).sum(axis=1)
    dirs = _cell_directions(1000, 37).reshape(-1, 3)
    v = bench.f(row, wo, dirs).sum(axis=1) * dirs[:, 2] * 2.0 * np.pi
    ratio = v.mean() / w.mean()
    z = (v.mean() - w.mean()) / np.sqrt(v.var(ddof=1) / len(v) + w.var(ddof=1) / n)
    assert z > 5.0 and 1.03 < ratio < 1.12, (ratio, z)
