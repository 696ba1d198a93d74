"""Many-light selection: the light tree (renderer/lights/light_tree_build.py, light_tree.py) and the
uniform and power selectors (renderer/lights/light_select.py).

Statistical tests use fixed seeds and a family-wise significance ALPHA = 0.01, split over the
tests of a family with Sidak's correction (1 - (1 - ALPHA)^(1 / number of tests)).
"""

import math
import time

import numpy as np
import pytest
import taichi as ti
from scipy import stats

from renderer.lights.light_select import (AUTO_TREE_MIN, SELECTOR_KINDS, PowerSelector,
                                          SingleEmitterSelector, UniformSelector, alias_table, make_light_selector,
                                          resolve_kind)
from renderer.lights.light_tree import LightTree
from renderer.lights.light_tree_build import (EmitterBounds, build_light_tree, cone_union, orientation_measure,
                                              triangle_emitters)
from renderer.scene.generators import generate

ALPHA = 0.01
PI = math.pi


def sidak(alpha: float, num_tests: int) -> float:
    return 1.0 - (1.0 - alpha) ** (1.0 / num_tests)


# --- emitter sets ----------------------------------------------------------------------------


def random_triangles(seed: int, n: int, extent: float = 4.0, size: float = 0.3):
    """n one-sided triangles with random positions, orientations and radiances (log-normal, so
    powers spread over an order of magnitude or two). Returns (EmitterBounds, v0, v1, v2)."""
    rng = np.random.default_rng(seed)
    centre = rng.uniform(-extent, extent, (n, 3))
    v0 = centre + rng.normal(0.0, size, (n, 3))
    v1 = centre + rng.normal(0.0, size, (n, 3))
    v2 = centre + rng.normal(0.0, size, (n, 3))
    radiance = rng.lognormal(0.0, 1.0, n)
    return triangle_emitters(v0, v1, v2, radiance), v0, v1, v2


def mixed_emitters(seed: int, n: int) -> EmitterBounds:
    """Boxes with every kind of cone: flat one-sided (theta_o 0), curved (0.4), two-sided or
    point-like (pi), narrow emission (theta_e 0.3, spot-like) and Lambertian, some of them points
    (lo == hi)."""
    rng = np.random.default_rng(seed)
    c = rng.uniform(-3.0, 3.0, (n, 3))
    half = rng.uniform(0.0, 0.2, (n, 3)) * (rng.random((n, 1)) < 0.8)
    return EmitterBounds(
        lo=(c - half).astype(np.float32), hi=(c + half).astype(np.float32),
        power=rng.lognormal(0.0, 1.5, n), axis=rng.normal(size=(n, 3)),
        theta_o=rng.choice([0.0, 0.4, PI], n), theta_e=rng.choice([0.5 * PI, 0.3], n))


def panel_triangles(**params):
    """The light_panels generator's triangles as emitters of radiance 1: (EmitterBounds, the
    triangles' vertices (T, 3, 3))."""
    positions, indices, _ = generate("light_panels", params)
    v = positions.astype(np.float64)[indices]
    return triangle_emitters(v[:, 0], v[:, 1], v[:, 2], np.ones(len(indices))), v


def random_points(seed: int, m: int, extent: float = 5.0, zero_normals: float = 0.25):
    """m points in a cube and unit normals (a share of them zero: points in a medium)."""
    rng = np.random.default_rng(seed)
    p = rng.uniform(-extent, extent, (m, 3))
    n = rng.normal(size=(m, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    n[rng.random(m) < zero_normals] = 0.0
    return p.astype(np.float32), n.astype(np.float32)


# --- device helpers --------------------------------------------------------------------------


@ti.kernel
def _pmf_table(sel: ti.template(), pts: ti.types.ndarray(dtype=ti.math.vec3, ndim=1),
               nrm: ti.types.ndarray(dtype=ti.math.vec3, ndim=1),
               out: ti.types.ndarray(dtype=ti.f32, ndim=2)):
    for i, e in ti.ndrange(out.shape[0], out.shape[1]):
        out[i, e] = sel.pmf(pts[i], nrm[i], e)


@ti.kernel
def _select(sel: ti.template(), p: ti.math.vec3, n: ti.math.vec3,
            us: ti.types.ndarray(dtype=ti.f32, ndim=1), em: ti.types.ndarray(dtype=ti.i32, ndim=1),
            pm: ti.types.ndarray(dtype=ti.f32, ndim=1), again: ti.types.ndarray(dtype=ti.f32, ndim=1)):
    for s in range(us.shape[0]):
        e, q = sel.select(p, n, us[s])
        em[s] = e
        pm[s] = q
        again[s] = sel.pmf(p, n, e)


def pmf_table(sel, points, normals) -> np.ndarray:
    """(points, emitters) f32 pmf of every emitter at every point."""
    out = np.zeros((len(points), sel.num_emitters), np.float32)
    _pmf_table(sel, np.ascontiguousarray(points, np.float32),
               np.ascontiguousarray(normals, np.float32), out)
    return out


def draw(sel, p, n, samples: int, seed: int):
    """(emitters, pmf returned by select, pmf recomputed for that emitter) of `samples` draws."""
    us = np.random.default_rng(seed).random(samples).astype(np.float32)
    us = np.minimum(us, np.float32(1.0 - 2.0 ** -24))
    em = np.zeros(samples, np.int32)
    pm = np.zeros(samples, np.float32)
    again = np.zeros(samples, np.float32)
    _select(sel, ti.math.vec3(*map(float, p)), ti.math.vec3(*map(float, n)), us, em, pm, again)
    return em, pm, again


# --- the tree on the host --------------------------------------------------------------------


def check_tree(data, e: EmitterBounds, max_leaf_size: int):
    """Structure and bounds of a built tree: every node bounds exactly the emitters of its range."""
    n = len(e)
    m = data.num_nodes
    right, first, count = (data.node_right.astype(np.int64), data.node_first.astype(np.int64),
                           data.node_count.astype(np.int64))
    assert count[0] == n and first[0] == 0
    inner = np.flatnonzero(right >= 0)
    leaves = np.flatnonzero(right < 0)
    assert np.all(right[inner] > inner + 1) and np.all(right[inner] < m)
    np.testing.assert_array_equal(count[inner], count[inner + 1] + count[right[inner]])
    np.testing.assert_array_equal(first[inner + 1], first[inner])
    np.testing.assert_array_equal(first[right[inner]], first[inner] + count[inner + 1])
    assert np.all((count[leaves] >= 1) & (count[leaves] <= max_leaf_size))
    assert count[leaves].sum() == n
    np.testing.assert_array_equal(np.sort(data.order), np.arange(n))
    np.testing.assert_array_equal(data.order[data.rank], np.arange(n))
    leaf = data.emitter_leaf
    assert np.all(right[leaf] < 0)
    assert np.all((first[leaf] <= data.rank) & (data.rank < first[leaf] + count[leaf]))
    if max_leaf_size == 1:
        assert m == 2 * n - 1

    # every (node, emitter below it) pair
    node = np.repeat(np.arange(m), count)
    starts = np.repeat(first - np.cumsum(count) + count, count)
    em = data.order[starts + np.arange(node.shape[0])]
    lo = np.asarray(e.lo, np.float32)
    hi = np.asarray(e.hi, np.float32)
    assert np.all(data.node_lo[node] <= lo[em]) and np.all(data.node_hi[node] >= hi[em])
    assert np.all(data.node_theta_e[node] >= np.asarray(e.theta_e, np.float32)[em])
    axis = np.asarray(e.axis, np.float64)
    length = np.linalg.norm(axis, axis=1)
    unit = axis / np.where(length > 0, length, 1.0)[:, None]
    theta_o = np.where(length > 0, np.asarray(e.theta_o, np.float64), PI)
    node_axis = data.node_axis.astype(np.float64)[node]
    cosang = np.einsum("ij,ij->i", node_axis / np.linalg.norm(node_axis, axis=1, keepdims=True),
                       unit[em])
    angle = np.arccos(np.clip(cosang, -1.0, 1.0))
    spread = data.node_theta_o.astype(np.float64)[node]
    assert np.all((angle + theta_o[em] <= spread + 1e-5) | (spread >= PI - 1e-6))
    power = np.bincount(node, weights=np.asarray(e.power, np.float64)[em], minlength=m)
    np.testing.assert_allclose(data.node_power, power, rtol=1e-5)


@pytest.mark.parametrize("case, max_leaf_size", [
    ("triangles", 1), ("triangles", 4), ("saoh only", 1), ("mixed", 1), ("mixed", 3),
    ("panels", 1), ("coincident", 1), ("one", 1), ("two", 1), ("line", 2)])
def test_tree_structure_and_bounds(case, max_leaf_size):
    options = {}
    if case == "saoh only":  # no Morton-order finish of small nodes
        e = random_triangles(1, 1000)[0]
        options = {"small_node": 1}
    elif case == "triangles":
        e = random_triangles(1, 3000)[0]
    elif case == "mixed":
        e = mixed_emitters(2, 2000)
    elif case == "panels":
        e = panel_triangles(count_x=40, count_z=30)[0]
    elif case == "coincident":  # no plane separates them: split by count
        e = EmitterBounds(lo=np.zeros((50, 3)), hi=np.zeros((50, 3)), power=np.arange(1.0, 51.0),
                          axis=np.tile([0.0, 1.0, 0.0], (50, 1)), theta_o=np.full(50, PI),
                          theta_e=np.full(50, 0.5 * PI))
    elif case == "line":  # zero-area boxes along a line
        x = np.linspace(0.0, 1.0, 101)[:, None] * np.array([[1.0, 0.0, 0.0]])
        e = EmitterBounds(lo=x, hi=x, power=np.ones(101), axis=np.tile([0.0, -1.0, 0.0], (101, 1)),
                          theta_o=np.zeros(101), theta_e=np.full(101, 0.5 * PI))
    else:
        k = 1 if case == "one" else 2
        e = random_triangles(3, k)[0]
    data = build_light_tree(e, max_leaf_size=max_leaf_size, **options)
    check_tree(data, e, max_leaf_size)
    for emitter in range(0, len(e), max(1, len(e) // 50)):
        assert len(data.trail(emitter)) <= data.depth() - 1
    if case == "line":  # splits, not a chain: depth stays logarithmic
        assert data.depth() <= 2 + math.ceil(math.log2(101))


def test_tree_is_deterministic():
    e = mixed_emitters(4, 500)
    a, b = build_light_tree(e), build_light_tree(e)
    for name in a.__dataclass_fields__:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))


def angle_between(a, b):
    """Angles between rows of a and b, accurate near 0 and pi (unlike arccos of the dot)."""
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.einsum("...i,...i->...", a, b))


def test_cone_union_contains_both_cones():
    rng = np.random.default_rng(5)
    m = 20000
    wa = rng.normal(size=(m, 3))
    wa /= np.linalg.norm(wa, axis=1, keepdims=True)
    wb = rng.normal(size=(m, 3))
    wb /= np.linalg.norm(wb, axis=1, keepdims=True)
    # near-parallel and near-antiparallel pairs too
    wb[:2000] = wa[:2000] + 1e-7 * rng.normal(size=(2000, 3))
    wb[2000:4000] = -wa[2000:4000] + 1e-7 * rng.normal(size=(2000, 3))
    wb /= np.linalg.norm(wb, axis=1, keepdims=True)
    ta = rng.uniform(0.0, PI, m) * (rng.random(m) < 0.7)
    tb = rng.uniform(0.0, PI, m) * (rng.random(m) < 0.7)
    w, t = cone_union(wa, ta, wb, tb)
    np.testing.assert_allclose(np.linalg.norm(w, axis=1), 1.0, atol=1e-12)
    for axis, spread in ((wa, ta), (wb, tb)):
        assert np.all((angle_between(w, axis) + spread <= t + 1e-9) | (t >= PI))
    # never wider than the cone around either axis that holds both
    d = angle_between(wa, wb)
    assert np.all(t <= np.minimum(np.maximum(ta, d + tb), np.maximum(tb, d + ta)) + 1e-9)
    # known cases
    w, t = cone_union([0.0, 0.0, 1.0], 0.0, [0.0, 0.0, -1.0], 0.0)
    assert t == PI
    w, t = cone_union([1.0, 0.0, 0.0], 0.0, [0.0, 1.0, 0.0], 0.0)
    np.testing.assert_allclose(w, [math.sqrt(0.5), math.sqrt(0.5), 0.0], atol=1e-12)
    assert t == pytest.approx(PI / 4)
    w, t = cone_union([1.0, 0.0, 0.0], -1.0, [0.0, 1.0, 0.0], 0.2)  # empty + cone
    np.testing.assert_allclose(w, [0.0, 1.0, 0.0])
    assert t == 0.2


def test_orientation_measure():
    assert orientation_measure(0.0, 0.5 * PI) == pytest.approx(PI)  # a flat Lambertian emitter
    assert orientation_measure(PI, 0.5 * PI) == pytest.approx(4.0 * PI)  # every direction
    spreads = np.linspace(0.0, PI, 50)
    assert np.all(np.diff(orientation_measure(spreads, 0.5 * PI)) > 0)


def test_triangle_emitters():
    v0 = np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]])
    v1 = np.array([[2.0, 0.0, 0.0], [1.0, 1.0, 1.0]])  # the second is degenerate
    v2 = np.array([[0.0, 0.0, -1.0], [1.0, 1.0, 1.0]])
    e = triangle_emitters(v0, v1, v2, [3.0, 3.0])
    np.testing.assert_allclose(e.axis[0], [0.0, 1.0, 0.0])  # (2,0,0) x (0,0,-1) = (0,2,0)
    assert e.power[0] == pytest.approx(3.0 * 1.0 * PI)  # radiance x area (1) x pi
    assert (e.theta_o[0], e.theta_e[0]) == (0.0, pytest.approx(0.5 * PI))
    assert e.power[1] == 0.0 and e.theta_o[1] == pytest.approx(PI)
    np.testing.assert_array_equal(e.lo[0], [0.0, 0.0, -1.0])
    np.testing.assert_array_equal(e.hi[0], [2.0, 0.0, 0.0])


def test_build_rejects_bad_input():
    e = random_triangles(6, 10)[0]
    with pytest.raises(ValueError, match="total power"):
        build_light_tree(EmitterBounds(e.lo, e.hi, np.zeros(10), e.axis, e.theta_o, e.theta_e))
    with pytest.raises(ValueError, match="NaN"):
        bad = e.lo.copy()
        bad[3, 1] = np.nan
        build_light_tree(EmitterBounds(bad, e.hi, e.power, e.axis, e.theta_o, e.theta_e))
    with pytest.raises(ValueError, match="lo > hi"):
        build_light_tree(EmitterBounds(e.hi + 1.0, e.hi, e.power, e.axis, e.theta_o, e.theta_e))
    with pytest.raises(ValueError, match="shape"):
        build_light_tree(EmitterBounds(e.lo[:5], e.hi, e.power, e.axis, e.theta_o, e.theta_e))
    with pytest.raises(ValueError, match=">= 0"):
        build_light_tree(EmitterBounds(e.lo, e.hi, -e.power, e.axis, e.theta_o, e.theta_e))


def test_build_time_100k():
    """100k emitters (random boxes with random cones) and the 20k triangles of the default
    light_panels build; the times are printed (run with -s), and the trees are complete."""
    rng = np.random.default_rng(7)
    n = 100_000
    c = rng.uniform(-10.0, 10.0, (n, 3))
    e = EmitterBounds(lo=(c - 0.02).astype(np.float32), hi=(c + 0.02).astype(np.float32),
                      power=rng.uniform(0.1, 1.0, n), axis=rng.normal(size=(n, 3)),
                      theta_o=np.zeros(n), theta_e=np.full(n, 0.5 * PI))
    start = time.perf_counter()
    data = build_light_tree(e)
    random_time = time.perf_counter() - start
    panels = panel_triangles()[0]
    start = time.perf_counter()
    panel_data = build_light_tree(panels)
    panel_time = time.perf_counter() - start
    print(f"\nlight tree build: {n} random emitters {random_time:.3f} s (depth {data.depth()}), "
          f"{len(panels)} panel triangles {panel_time:.3f} s (depth {panel_data.depth()})")
    assert data.num_nodes == 2 * n - 1 and panel_data.num_nodes == 2 * len(panels) - 1
    assert data.depth() < 40


# --- the selectors on the device -------------------------------------------------------------


def make(kind: str, e: EmitterBounds, **options):
    return make_light_selector(kind, e, **options)


SUM_CASES = [("tree", "triangles", 1), ("tree", "triangles", 4), ("tree", "mixed", 1),
             ("tree", "mixed", 3), ("tree", "panels", 1), ("power", "mixed", 1),
             ("uniform", "mixed", 1)]


def emitter_set(name: str) -> EmitterBounds:
    if name == "triangles":
        return random_triangles(11, 2000)[0]
    if name == "mixed":
        return mixed_emitters(12, 1500)
    return panel_triangles(count_x=50, count_z=50, size=8.0, panel_size=0.05, height=3.0)[0]


@pytest.mark.parametrize("kind, name, max_leaf_size", SUM_CASES)
def test_pmf_sums_to_one(kind, name, max_leaf_size):
    e = emitter_set(name)
    options = {"max_leaf_size": max_leaf_size} if kind == "tree" else {}
    sel = make(kind, e, **options)
    points, normals = random_points(13, 64)
    table = pmf_table(sel, points, normals)
    assert np.all(np.isfinite(table)) and np.all(table >= 0)
    np.testing.assert_allclose(table.astype(np.float64).sum(axis=1), 1.0, atol=1e-4)


# (kind, emitter set, max_leaf_size): 6 points each, one chi-square test per point
CHI2_CASES = [("tree", "triangles", 1), ("tree", "mixed", 3), ("tree", "panels", 1),
              ("power", "mixed", 1), ("uniform", "mixed", 1)]
CHI2_POINTS = 6
CHI2_SAMPLES = 200_000
CHI2_ALPHA = sidak(ALPHA, len(CHI2_CASES) * CHI2_POINTS)


@pytest.mark.parametrize("kind, name, max_leaf_size", CHI2_CASES)
def test_select_frequencies_match_pmf(kind, name, max_leaf_size):
    """Pearson's chi-square of the emitter counts of CHI2_SAMPLES draws against pmf, bins with
    an expected count below 5 pooled; any draw of an emitter with pmf 0 fails outright. Also:
    the pmf select returns is the pmf of the emitter it returns, and never 0."""
    sub = {"triangles": 400, "mixed": 300}
    e = emitter_set(name) if name == "panels" else (
        random_triangles(21, sub[name])[0] if name == "triangles" else mixed_emitters(22, sub[name]))
    options = {"max_leaf_size": max_leaf_size} if kind == "tree" else {}
    sel = make(kind, e, **options)
    points, normals = random_points(23, CHI2_POINTS, extent=3.5)
    table = pmf_table(sel, points, normals).astype(np.float64)
    for i in range(CHI2_POINTS):
        em, pm, again = draw(sel, points[i], normals[i], CHI2_SAMPLES, seed=100 + i)
        # The same formula at two call sites: equal up to how each site's code contracts its
        # multiply-adds when Taichi's own IR optimisations are off; the pmf is a product of one
        # factor per tree level, so a few ulp each (2.3e-6 relative seen here).
        np.testing.assert_allclose(pm, again, rtol=1e-5)
        np.testing.assert_allclose(pm, table[i, em], rtol=1e-5)  # as above: one f32 factor per level
        assert np.all(pm > 0)
        observed = np.bincount(em, minlength=len(e))
        assert observed[table[i] == 0].sum() == 0
        expected = table[i] / table[i].sum() * CHI2_SAMPLES
        keep = expected >= 5.0
        obs = observed[keep].astype(np.float64)
        exp = expected[keep]
        if (~keep).any() and expected[~keep].sum() > 0:
            obs = np.append(obs, observed[~keep].sum())
            exp = np.append(exp, expected[~keep].sum())
        exp *= obs.sum() / exp.sum()
        p_value = stats.chisquare(obs, exp).pvalue
        assert p_value >= CHI2_ALPHA, (i, p_value, CHI2_ALPHA)


def test_facing_emitters_never_get_pmf_zero():
    """Every triangle whose front faces the point (it can light it) has pmf > 0: at random
    points, at points seen by a triangle at a grazing angle (1e-4 to 1e-2 rad above its plane,
    near and far), with random, zero and tangent normals; and under the panels, just below
    their plane."""
    e, v0, v1, v2 = random_triangles(31, 2000)
    sel = LightTree(e)
    normal = np.asarray(e.axis, np.float64)
    rng = np.random.default_rng(32)
    pts, nrm = [], []
    p, n = random_points(33, 64)
    pts += list(p.astype(np.float64))
    nrm += list(n.astype(np.float64))
    for t in rng.choice(len(e), 24, replace=False):
        centre = (v0[t] + v1[t] + v2[t]) / 3.0
        tangent = np.cross(normal[t], rng.normal(size=3))
        tangent /= np.linalg.norm(tangent)
        for elevation in (1e-4, 1e-3, 1e-2):
            for dist in (0.05, 1.0, 10.0):
                q = centre + dist * (math.cos(elevation) * tangent + math.sin(elevation) * normal[t])
                to_tri = centre - q
                tangent_normal = np.cross(to_tri, rng.normal(size=3))  # the triangle on its horizon
                for nn in (np.zeros(3), normal[t], tangent_normal / np.linalg.norm(tangent_normal)):
                    pts.append(q)
                    nrm.append(nn)
    pts = np.array(pts, np.float32)
    nrm = np.array(nrm, np.float32)
    table = pmf_table(sel, pts, nrm)
    # facing: the point strictly in front of the triangle's plane (in f64, from the f32 point)
    facing = np.einsum("ej,pej->pe", normal, pts.astype(np.float64)[:, None, :] - v0[None]) > 0
    assert facing.sum() > 0.3 * facing.size
    bad = np.argwhere(facing & (table <= 0))
    assert bad.shape[0] == 0, f"{bad.shape[0]} facing (point, emitter) pairs with pmf 0: {bad[:5]}"

    panels, _ = panel_triangles(count_x=60, count_z=60, size=6.0, panel_size=0.05, height=3.0)
    sel = LightTree(panels)
    below = np.array([[0.0, 3.0 - 1e-3, 0.0], [2.9, 2.999, -2.9], [40.0, 2.99, 0.0],
                      [0.0, 0.0, 0.0]], np.float32)
    ups = np.tile(np.float32([0.0, 1.0, 0.0]), (len(below), 1))
    for normals in (ups, np.zeros_like(ups), np.tile(np.float32([1.0, 0.0, 0.0]), (len(below), 1))):
        table = pmf_table(sel, below, normals)
        assert np.all(table > 0), np.argwhere(table <= 0)[:5]  # every panel faces these points


def test_zero_power_and_degenerate_emitters():
    # a single emitter
    e = random_triangles(41, 1)[0]
    sel = LightTree(e)
    em, pm, _ = draw(sel, (0.0, 5.0, 0.0), (0.0, -1.0, 0.0), 100, seed=1)
    assert np.all(em == 0) and np.all(pm == 1.0)
    # point lights at one place (no plane separates them): pmf = power share, even at the point
    n = 40
    power = np.arange(1.0, n + 1.0)
    e = EmitterBounds(lo=np.ones((n, 3)), hi=np.ones((n, 3)), power=power,
                      axis=np.zeros((n, 3)), theta_o=np.full(n, PI), theta_e=np.full(n, 0.5 * PI))
    sel = LightTree(e)
    pts = np.array([[1.0, 1.0, 1.0], [0.0, 3.0, 0.0]], np.float32)
    table = pmf_table(sel, pts, np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 0.0]], np.float32))
    np.testing.assert_allclose(table, np.tile(power / power.sum(), (2, 1)), rtol=1e-5)
    # emitters of power 0 among others: pmf 0, never drawn, the rest still sums to 1
    e = mixed_emitters(42, 300)
    power = np.asarray(e.power).copy()
    power[::7] = 0.0
    e = EmitterBounds(e.lo, e.hi, power, e.axis, e.theta_o, e.theta_e)
    for sel in (LightTree(e), LightTree(e, max_leaf_size=4), PowerSelector(e)):
        points, normals = random_points(43, 16)
        table = pmf_table(sel, points, normals)
        assert np.all(table[:, ::7] == 0)
        np.testing.assert_allclose(table.sum(axis=1), 1.0, atol=1e-4)
        em, pm, _ = draw(sel, points[0], normals[0], 20000, seed=2)
        assert np.all(em % 7 != 0) and np.all(pm > 0)


# --- the tree's importance at work ---------------------------------------------------------------


def contributions(v, e: EmitterBounds, p, n):
    """Each triangle's contribution to the irradiance at p (normal n), the triangle (vertices v)
    taken as a point at its centroid: L * A * cos(at the emitter) * cos(at p) / d^2, in f64."""
    d = v.mean(axis=1) - p
    dist2 = np.einsum("ij,ij->i", d, d)
    w = d / np.sqrt(dist2)[:, None]
    cos_e = np.maximum(-np.einsum("ij,ij->i", w, np.asarray(e.axis, np.float64)), 0.0)
    cos_p = np.maximum(w @ n, 0.0)
    return np.asarray(e.power, np.float64) / PI * cos_e * cos_p / dist2


# shading points (position, normal) in and around the panels' 20 m x 20 m field, 3 m above the
# floor: on the floor in the middle, off-centre, in a corner and outside the field, on a wall, and
# close under the panels
VARIANCE_POINTS = [((0.0, 0.0, 0.0), (0.0, 1.0, 0.0)), ((-3.1, 0.0, 2.3), (0.0, 1.0, 0.0)),
                   ((9.7, 0.0, -9.6), (0.0, 1.0, 0.0)), ((13.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
                   ((9.9, 1.5, 0.4), (-1.0, 0.0, 0.0)), ((0.52, 2.7, -0.3), (0.0, 1.0, 0.0))]
VARIANCE_SAMPLES = 100_000


def test_tree_lowers_variance_on_a_panel_grid():
    """On 10,000 panel triangles (light_panels 100 x 50), the one-sample estimate of the
    irradiance sum_e f_e with e drawn by the tree has a lower variance than with power selection.

    Exact: V = sum_e f_e^2 / pmf_e - (sum_e f_e)^2 from the pmf tables (no sampling error), and the
    ratio V_tree / V_power < 1 at every point. Sampled, from VARIANCE_SAMPLES draws of each
    selector: the means agree with sum_e f_e (two-sided z-test with the exact variances), and
    V_power - V_tree > z * se, one-sided, with se from the samples' fourth moments (the variance
    of a sample variance is (m4 - V^2) / S): the margin comes from the data. Sidak over the
    points and tests, family-wise ALPHA."""
    e, v = panel_triangles(count_x=100, count_z=50, size=20.0, panel_size=0.05, height=3.0)
    assert len(e) == 10_000
    tree, power = LightTree(e), PowerSelector(e)
    points = np.array([p for p, _ in VARIANCE_POINTS], np.float64)
    normals = np.array([n for _, n in VARIANCE_POINTS], np.float64)
    tables = {s.kind: pmf_table(s, points, normals).astype(np.float64) for s in (tree, power)}
    alpha = sidak(ALPHA, 3 * len(points))
    z_two = stats.norm.ppf(1.0 - alpha / 2.0)
    z_one = stats.norm.ppf(1.0 - alpha)
    ratios = []
    for i, (p, n) in enumerate(zip(points, normals)):
        f = contributions(v, e, p, n)
        total = f.sum()
        assert total > 0
        exact = {}
        for kind, table in tables.items():
            pmf = table[i]
            assert np.all(pmf[f > 0] > 0)
            lit = f > 0
            exact[kind] = np.sum(f[lit] ** 2 / pmf[lit]) - total ** 2
        ratio = exact["tree"] / exact["power"]
        ratios.append(ratio)
        assert ratio < 1.0, (i, ratio)
        sampled = {}
        for s in (tree, power):
            em, pm, _ = draw(s, p, n, VARIANCE_SAMPLES, seed=200 + i)
            x = f[em] / pm.astype(np.float64)
            mean = x.mean()
            assert abs(mean - total) <= z_two * math.sqrt(exact[s.kind] / VARIANCE_SAMPLES), (i, s.kind)
            var = x.var()
            m4 = np.mean((x - mean) ** 4)
            sampled[s.kind] = (var, (m4 - var ** 2) / VARIANCE_SAMPLES)
        (v_t, se2_t), (v_p, se2_p) = sampled["tree"], sampled["power"]
        assert v_p - v_t > z_one * math.sqrt(se2_t + se2_p), (i, v_t, v_p)
    print("\nvariance ratio tree / power at the test points:", ", ".join(f"{r:.3g}" for r in ratios))


def test_tree_prefers_near_bright_facing_lights():
    """Under a panel the tree gives the panel's triangles, and the nearest 1 % of the panels,
    well more than their power share (the ideal, pmf in proportion to the contribution, gives
    this panel about 5 times its power share: 1/9 of the power over 3 m, against a field
    sum near 25 panels/m^2 * pi * 0.735); panels turned away get nothing."""
    e, v = panel_triangles(count_x=50, count_z=50, size=10.0, panel_size=0.05, height=3.0)
    axis = np.asarray(e.axis).copy()
    axis[100:200] *= -1.0  # these face up, away from the floor
    e = EmitterBounds(e.lo, e.hi, e.power, axis, e.theta_o, e.theta_e)
    tree, power = LightTree(e), PowerSelector(e)
    k = 1234  # a panel triangle; its centroid, projected onto the floor
    centre = v[k].mean(axis=0)
    p = np.array([[centre[0], 0.0, centre[2]]], np.float32)
    n = np.array([[0.0, 1.0, 0.0]], np.float32)
    t = pmf_table(tree, p, n)[0].astype(np.float64)
    w = pmf_table(power, p, n)[0].astype(np.float64)
    f = contributions(v, e, p[0].astype(np.float64), n[0].astype(np.float64))
    ideal = f / f.sum()
    assert ideal[k] > 4.0 * w[k]
    assert t[k] > 2.0 * w[k]
    near = np.argsort(np.linalg.norm(v.mean(axis=1) - p[0], axis=1))[:len(e) // 100]
    assert t[near].sum() > 2.0 * w[near].sum()
    assert np.all(t[100:200] == 0) and np.all(w[100:200] > 0)


# --- the selectors' API ------------------------------------------------------------------------


def test_auto_rule_and_factory():
    assert SELECTOR_KINDS == ("auto", "uniform", "power", "tree")
    assert resolve_kind("auto", AUTO_TREE_MIN) == "power"
    assert resolve_kind("auto", AUTO_TREE_MIN + 1) == "tree"
    assert resolve_kind("uniform", 10 ** 6) == "uniform"
    assert all(resolve_kind(kind, 1) == "single" for kind in SELECTOR_KINDS)
    with pytest.raises(ValueError, match="unknown light selector 'best'"):
        resolve_kind("best", 10)
    small = mixed_emitters(51, AUTO_TREE_MIN)
    large = mixed_emitters(52, AUTO_TREE_MIN + 1)
    assert isinstance(make_light_selector("auto", small), PowerSelector)
    assert isinstance(make_light_selector("auto", large), LightTree)
    assert isinstance(make_light_selector("uniform", large), UniformSelector)
    tree = make_light_selector("tree", small, max_leaf_size=2)
    assert np.all(tree.data.node_count[tree.data.node_right < 0] <= 2)
    sel = make_light_selector("uniform", small)
    table = pmf_table(sel, *random_points(53, 2))
    np.testing.assert_allclose(table, 1.0 / AUTO_TREE_MIN, rtol=1e-6)


@pytest.mark.parametrize("kind", SELECTOR_KINDS)
def test_one_emitter_is_chosen_with_probability_one(kind):
    """Every kind, given one emitter, is the single-emitter selector: emitter 0 with pmf 1 for any
    u, point and normal, as the other selectors give it (the alias table's and the tree's)."""
    one = mixed_emitters(71, 1)
    sel = make_light_selector(kind, one)
    assert isinstance(sel, SingleEmitterSelector) and sel.num_emitters == 1
    points, normals = random_points(72, 16)
    np.testing.assert_array_equal(pmf_table(sel, points, normals), 1.0)
    for p, n in zip(points[:4], normals[:4]):
        em, pm, again = draw(sel, p, n, 256, seed=73)
        assert np.all(em == 0) and np.all(pm == 1.0) and np.all(again == 1.0)
    for other in (PowerSelector(one), UniformSelector(one), LightTree(one)):  # what they would give
        em, pm, _ = draw(other, points[0], normals[0], 256, seed=74)
        assert np.all(em == 0) and np.allclose(pm, 1.0)
    with pytest.raises(ValueError, match="exactly one emitter"):
        SingleEmitterSelector(2)


def test_alias_table_gives_the_pmf():
    rng = np.random.default_rng(61)
    for w in (rng.lognormal(0.0, 2.0, 1000), np.array([0.0, 1.0, 0.0, 3.0]), np.ones(7),
              np.array([5.0])):
        q, alias, pmf = alias_table(w)
        n = len(w)
        implied = q.astype(np.float64) / n
        np.add.at(implied, alias, (1.0 - q.astype(np.float64)) / n)
        np.testing.assert_allclose(implied, w / w.sum(), atol=1e-6)
        np.testing.assert_allclose(pmf, w / w.sum(), rtol=1e-6)
        assert np.all(pmf[w > 0] > 0) and np.all(implied[w == 0] < 1e-7)
    with pytest.raises(ValueError):
        alias_table(np.zeros(3))


@pytest.mark.parametrize("kind", ["power", "tree"])
def test_a_refit_for_new_powers_is_the_selector_built_for_them(kind):
    """An emission edit reweighs the selector in place (renderer/lights/light_select.py refit): its
    probabilities are then those of a selector built for the new powers, in the same fields."""
    from dataclasses import replace

    emitters = mixed_emitters(11, 40)
    selector = make_light_selector(kind, emitters)
    fields_before = [id(f) for f in vars(selector).values() if hasattr(f, "shape")]
    rng = np.random.default_rng(12)
    reweighed = replace(emitters, power=emitters.power * rng.lognormal(0.0, 1.0, 40))
    assert selector.refit(reweighed)
    assert [id(f) for f in vars(selector).values() if hasattr(f, "shape")] == fields_before
    points, normals = random_points(13, 16)
    np.testing.assert_array_equal(pmf_table(selector, points, normals),
                                  pmf_table(make_light_selector(kind, reweighed), points, normals))
    assert not selector.refit(mixed_emitters(11, 39))  # other emitters: built anew
