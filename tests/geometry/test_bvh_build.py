"""Structural tests of the numpy BVH builder (no Taichi involved)."""
import numpy as np
import pytest

from renderer.geometry.bvh_build import STRATEGIES, build_bvh
from renderer.geometry.bvh_tree import C_ISECT, C_TRAV, FlatBVH, sah_cost

HARD = 16  # build_bvh's default max_leaf_hard


# ------------------------------------------------------------------------------------------------
# inputs


def random_triangles(n, seed=0, size=None):
    """Triangles with centroids uniform in the unit cube; returns (lo, hi, centroids), f64."""
    rng = np.random.default_rng(seed)
    size = 0.5 / np.cbrt(n) if size is None else size
    c = rng.random((n, 3))
    v = c[:, None, :] + rng.normal(scale=size, size=(n, 3, 3))
    return v.min(axis=1), v.max(axis=1), v.mean(axis=1)


def boxes_around(c, half):
    c = np.asarray(c, np.float64)
    half = np.broadcast_to(np.asarray(half, np.float64), c.shape)
    return c - half, c + half, c


def identical_centroids(n=700, seed=1):
    """Many boxes sharing one centroid (different sizes), plus a few scattered ones."""
    rng = np.random.default_rng(seed)
    c = np.zeros((n, 3)) + 0.5
    half = rng.random((n, 1)) * 0.2 + 0.01
    lo, hi, c = boxes_around(c, np.repeat(half, 3, axis=1))
    lo2, hi2, c2 = random_triangles(60, seed=seed + 1)
    return np.concatenate((lo, lo2)), np.concatenate((hi, hi2)), np.concatenate((c, c2))


def clustered(seed=2):
    """Tight clusters far apart, a few huge primitives, and duplicated boxes."""
    rng = np.random.default_rng(seed)
    parts = []
    for k in range(6):
        centre = rng.normal(scale=100.0, size=3)
        c = centre + rng.normal(scale=1e-3, size=(300, 3))
        parts.append(boxes_around(c, 1e-4))
    big_c = rng.normal(scale=50.0, size=(5, 3))
    parts.append(boxes_around(big_c, 80.0))
    dup_c = np.repeat(rng.normal(size=(1, 3)), 40, axis=0)
    parts.append(boxes_around(dup_c, 0.5))
    return tuple(np.concatenate([p[i] for p in parts]) for i in range(3))


def flat_and_points(seed=3):
    """Zero-thickness boxes in the plane z = 0 and boxes that are single points."""
    rng = np.random.default_rng(seed)
    c = rng.random((400, 3))
    c[:, 2] = 0.0
    lo, hi, c = boxes_around(c, [0.01, 0.01, 0.0])
    p = rng.random((200, 3))
    return np.concatenate((lo, p)), np.concatenate((hi, p)), np.concatenate((c, p))


INPUTS = {
    "random": lambda: random_triangles(3000),
    "identical": identical_centroids,
    "all_identical": lambda: boxes_around(np.ones((500, 3)), 0.25),
    "clustered": clustered,
    "flat_points": flat_and_points,
    "n1": lambda: random_triangles(1),
    "n2": lambda: random_triangles(2),
    "n5": lambda: random_triangles(5),
    "n17": lambda: random_triangles(17),
    "collinear": lambda: boxes_around(np.linspace(0, 1, 300)[:, None] * [1.0, 0.0, 0.0], 0.0),
}


# ------------------------------------------------------------------------------------------------
# the checker


def check_bvh(bvh: FlatBVH, lo, hi, max_leaf: int):
    """Assert every structural invariant of a FlatBVH over the boxes [lo, hi]."""
    lo = np.asarray(lo, np.float64)
    hi = np.asarray(hi, np.float64)
    n = lo.shape[0]
    m = bvh.num_nodes
    assert bvh.node_lo.shape == (m, 3) and bvh.node_lo.dtype == np.float32
    assert bvh.node_hi.shape == (m, 3) and bvh.node_hi.dtype == np.float32
    for name in ("node_a", "node_count", "node_skip"):
        arr = getattr(bvh, name)
        assert arr.shape == (m,) and arr.dtype == np.int32, name
    assert bvh.node_axis.shape == (m,) and bvh.node_axis.dtype == np.int8
    assert bvh.prim_order.shape == (n,) and bvh.prim_order.dtype == np.int32
    assert 1 <= m <= 2 * n - 1

    # every primitive referenced exactly once
    assert np.array_equal(np.sort(bvh.prim_order), np.arange(n))

    cnt = bvh.node_count
    a = bvh.node_a
    skip = bvh.node_skip
    is_leaf = cnt > 0
    leaves = np.flatnonzero(is_leaf)
    inner = np.flatnonzero(~is_leaf)
    assert (cnt >= 0).all()
    assert (cnt <= max_leaf).all(), f"leaf of {cnt.max()} > {max_leaf}"

    # leaves cover prim_order in depth-first order, contiguously and without overlap
    assert a[leaves][0] == 0
    assert np.array_equal(a[leaves][1:], np.cumsum(cnt[leaves])[:-1])
    assert cnt.sum() == n
    assert (bvh.node_axis[leaves] == -1).all()

    # depth-first layout: left = i + 1, right > i + 1; each node but the root has one parent
    left = inner + 1
    right = a[inner]
    assert (left < m).all() and (right > left).all() and (right < m).all()
    children = np.concatenate((left, right))
    assert np.array_equal(np.sort(children), np.arange(1, m))
    assert ((bvh.node_axis[inner] >= 0) & (bvh.node_axis[inner] <= 2)).all()

    # skip links: the next node after the whole subtree (checked locally, which implies it
    # globally by induction over the depth-first layout)
    assert skip[0] == m
    assert (skip[leaves] == leaves + 1).all()
    assert (skip[left] == right).all()  # the left subtree ends where the right child starts
    assert (skip[inner] == skip[right]).all()
    assert (skip > np.arange(m)).all() and (skip <= m).all()

    # boxes: children inside parents, primitives inside their leaf (in exact f64 comparisons)
    nlo = bvh.node_lo.astype(np.float64)
    nhi = bvh.node_hi.astype(np.float64)
    assert (nlo <= nhi).all()
    for ch in (left, right):
        assert (nlo[ch] >= nlo[inner]).all() and (nhi[ch] <= nhi[inner]).all()
    leaf_of_slot = np.repeat(leaves, cnt[leaves])
    prims = bvh.prim_order
    assert (lo[prims] >= nlo[leaf_of_slot]).all()
    assert (hi[prims] <= nhi[leaf_of_slot]).all()
    # leaf boxes are tight: within one f32 rounding step of their primitives' union
    lmin = np.full((m, 3), np.inf)
    lmax = np.full((m, 3), -np.inf)
    np.minimum.at(lmin, leaf_of_slot, lo[prims])
    np.maximum.at(lmax, leaf_of_slot, hi[prims])
    tol = 1e-6 * (1.0 + np.abs(lmin[leaves]) + np.abs(lmax[leaves]))
    assert (lmin[leaves] - nlo[leaves] <= tol).all() and (nhi[leaves] - lmax[leaves] <= tol).all()


def stackless_query(bvh: FlatBVH, qlo, qhi):
    """Primitives of the leaves whose boxes overlap [qlo, qhi], by skip-link traversal."""
    found = []
    i = 0
    m = bvh.num_nodes
    visits = 0
    while i < m:
        visits += 1
        overlap = (bvh.node_lo[i] <= qhi).all() and (bvh.node_hi[i] >= qlo).all()
        if not overlap:
            i = bvh.node_skip[i]
        elif bvh.node_count[i] > 0:
            s = bvh.node_a[i]
            found.extend(bvh.prim_order[s:s + bvh.node_count[i]].tolist())
            i = bvh.node_skip[i]
        else:
            i += 1
    return found, visits


# ------------------------------------------------------------------------------------------------
# tests


@pytest.mark.parametrize("strategy", STRATEGIES)
@pytest.mark.parametrize("name", sorted(INPUTS))
def test_structure(strategy, name):
    lo, hi, c = INPUTS[name]()
    bvh = build_bvh(lo, hi, c, strategy=strategy)
    check_bvh(bvh, lo, hi, HARD if strategy == "sah" else 4)


@pytest.mark.parametrize("strategy", STRATEGIES)
@pytest.mark.parametrize("max_leaf", [1, 2, 7])
def test_max_leaf_size(strategy, max_leaf):
    lo, hi, c = random_triangles(1500, seed=5)
    bvh = build_bvh(lo, hi, c, strategy=strategy, max_leaf_size=max_leaf)
    check_bvh(bvh, lo, hi, max(max_leaf, HARD) if strategy == "sah" else max_leaf)


@pytest.mark.parametrize("strategy", STRATEGIES)
def test_identical_centroids_split_by_count(strategy):
    """No plane separates identical centroids: SAH keeps up to max_leaf_hard per leaf, the
    others split by count down to max_leaf_size."""
    lo, hi, c = boxes_around(np.full((1000, 3), 0.3), 0.1)
    bvh = build_bvh(lo, hi, c, strategy=strategy, max_leaf_size=4, max_leaf_hard=10)
    check_bvh(bvh, lo, hi, 10 if strategy == "sah" else 4)
    if strategy == "sah":
        assert bvh.node_count.max() > 4  # leaves beyond max_leaf_size, as documented


def test_sah_leaves_are_small_on_ordinary_input():
    lo, hi, c = random_triangles(20000, seed=6)
    bvh = build_bvh(lo, hi, c, strategy="sah", max_leaf_size=4)
    cnt = bvh.node_count[bvh.node_count > 0]
    assert (cnt <= HARD).all()
    assert np.mean(cnt > 4) < 0.05


@pytest.mark.parametrize("strategy", STRATEGIES)
def test_float64_input_rounds_outwards(strategy):
    """Boxes not representable in f32 must still be inside their (f32) leaf box."""
    rng = np.random.default_rng(7)
    c = rng.random((2000, 3)) * 3.0 + 1.0 / 3.0
    half = rng.random((2000, 3)) * 1e-3 + 1e-9
    lo, hi, c = boxes_around(c, half)
    assert (lo.astype(np.float32).astype(np.float64) != lo).any()
    bvh = build_bvh(lo, hi, c, strategy=strategy)
    check_bvh(bvh, lo, hi, HARD)
    # float32 input passes through exactly
    bvh32 = build_bvh(lo.astype(np.float32), hi.astype(np.float32), c.astype(np.float32),
                      strategy=strategy)
    assert np.array_equal(bvh32.node_lo[0], lo.astype(np.float32).min(axis=0))
    assert np.array_equal(bvh32.node_hi[0], hi.astype(np.float32).max(axis=0))


@pytest.mark.parametrize("strategy", STRATEGIES)
def test_stackless_query_matches_brute_force(strategy):
    lo, hi, c = random_triangles(2000, seed=8)
    bvh = build_bvh(lo, hi, c, strategy=strategy)
    rng = np.random.default_rng(9)
    for _ in range(25):
        q = rng.random(3)
        qlo, qhi = q - 0.05, q + 0.05
        found, visits = stackless_query(bvh, qlo, qhi)
        # leaf primitives whose own box overlaps the query
        found = [p for p in found if (lo[p] <= qhi).all() and (hi[p] >= qlo).all()]
        brute = np.flatnonzero((lo <= qhi).all(axis=1) & (hi >= qlo).all(axis=1))
        assert sorted(found) == brute.tolist()
        assert visits < bvh.num_nodes  # the tree actually culls


def test_sah_beats_other_strategies():
    lo, hi, c = random_triangles(20000, seed=10)
    cost = {s: sah_cost(build_bvh(lo, hi, c, strategy=s)) for s in STRATEGIES}
    assert cost["sah"] <= cost["midpoint"]
    assert cost["sah"] <= cost["equal_count"]


def test_sah_cost_of_a_single_leaf_and_a_split():
    lo, hi, c = random_triangles(3)
    leaf = build_bvh(lo, hi, c, max_leaf_size=4)
    assert leaf.num_nodes == 1
    assert sah_cost(leaf) == pytest.approx(C_ISECT * 3)
    lo, hi, c = boxes_around([[0.0, 0, 0], [10.0, 0, 0]], 0.5)
    two = build_bvh(lo, hi, c, max_leaf_size=1)
    assert two.num_nodes == 3
    # root extent (11, 1, 1): half area 11 + 1 + 11 = 23; each child 3
    assert sah_cost(two) == pytest.approx(C_TRAV + 2 * C_ISECT * 3.0 / 23.0, rel=1e-6)


def test_sah_separates_two_clusters_at_the_root():
    rng = np.random.default_rng(11)
    a = rng.random((500, 3)) * 0.1
    b = rng.random((500, 3)) * 0.1 + [5.0, 0.0, 0.0]
    lo, hi, c = boxes_around(np.concatenate((a, b)), 0.001)
    bvh = build_bvh(lo, hi, c)
    assert bvh.node_axis[0] == 0
    # the left subtree (nodes 1 .. right - 1) holds exactly one cluster
    right = bvh.node_a[0]
    first_right_prim = bvh.node_a[right:][bvh.node_count[right:] > 0][0]
    assert sorted(bvh.prim_order[:first_right_prim].tolist()) in (list(range(500)),
                                                                 list(range(500, 1000)))


def test_deterministic_and_thread_independent():
    lo, hi, c = random_triangles(120_000, seed=12)
    one = build_bvh(lo, hi, c, threads=1)
    two = build_bvh(lo, hi, c, threads=2)
    for f in ("node_lo", "node_hi", "node_a", "node_count", "node_skip", "node_axis",
              "prim_order"):
        assert np.array_equal(getattr(one, f), getattr(two, f)), f


@pytest.mark.parametrize("module, knob, value", [("bvh_split", "_CELLS_MAX_RATIO", 0.0),
                                                 ("bvh_build", "_COMPACT_FRACTION", 0.0),
                                                 ("bvh_build", "_COMPACT_FRACTION", 1.01)])
def test_fast_paths_are_exact(monkeypatch, module, knob, value):
    """Binning through cells (top levels) and compacting the active set change nothing."""
    import importlib
    lo, hi, c = random_triangles(30_000, seed=15)
    ref = build_bvh(lo, hi, c)
    monkeypatch.setattr(importlib.import_module(f"renderer.geometry.{module}"), knob, value)
    other = build_bvh(lo, hi, c)
    for f in ("node_lo", "node_a", "node_count", "prim_order"):
        assert np.array_equal(getattr(ref, f), getattr(other, f)), f


@pytest.mark.parametrize("strategy", STRATEGIES)
@pytest.mark.parametrize("scale", [2.0 ** -100, 2.0 ** 60])
def test_scale_invariant(strategy, scale):
    """Power-of-two scaling is exact in floating point, so it must not change the tree (SAH
    areas would underflow or overflow f32 if computed in scene units)."""
    lo, hi, c = random_triangles(5000, seed=16)
    ref = build_bvh(lo, hi, c, strategy=strategy)
    other = build_bvh(lo * scale, hi * scale, c * scale, strategy=strategy)
    for f in ("node_a", "node_count", "node_axis", "prim_order"):
        assert np.array_equal(getattr(ref, f), getattr(other, f)), f
    assert np.array_equal(ref.node_lo * np.float32(scale), other.node_lo)


def test_large_build_runs():
    lo, hi, c = random_triangles(100_000, seed=13)
    lo, hi, c = (x.astype(np.float32) for x in (lo, hi, c))
    bvh = build_bvh(lo, hi, c)
    check_bvh(bvh, lo, hi, HARD)
    assert bvh.depth() < 64


@pytest.mark.parametrize("bins", [2, 3, 12, 64])
def test_bin_counts(bins):
    lo, hi, c = random_triangles(3000, seed=14)
    check_bvh(build_bvh(lo, hi, c, bins=bins), lo, hi, HARD)


def test_cell_binning_matches_per_axis_binning(monkeypatch):
    # 64 bins on a root of more than 64**3 primitives takes the b x b x b cell path (its cell index
    # once overflowed int16 there and crashed); it must give the per-axis scatter's tree exactly.
    import renderer.geometry.bvh_split as split

    lo, hi, c = (x.astype(np.float32) for x in random_triangles(64 ** 3 + 5_000, seed=15))
    cells = build_bvh(lo, hi, c, bins=64)
    check_bvh(cells, lo, hi, HARD)
    monkeypatch.setattr(split, "_CELLS_MAX_RATIO", 0.0)
    per_axis = build_bvh(lo, hi, c, bins=64)
    for name in ("node_lo", "node_hi", "node_a", "node_count", "prim_order"):
        assert np.array_equal(getattr(cells, name), getattr(per_axis, name)), name


def test_bad_input():
    lo, hi, c = random_triangles(10)
    with pytest.raises(ValueError, match="zero primitives"):
        build_bvh(lo[:0], hi[:0], c[:0])
    for arr in ("lo", "hi", "c"):
        for bad in (np.nan, np.inf):
            x = {"lo": lo.copy(), "hi": hi.copy(), "c": c.copy()}
            x[arr][3, 1] = bad
            with pytest.raises(ValueError):
                build_bvh(x["lo"], x["hi"], x["c"])
    with pytest.raises(ValueError, match="lo > hi"):
        build_bvh(hi, lo, c)
    with pytest.raises(ValueError, match="shape"):
        build_bvh(lo[:, :2], hi, c)
    with pytest.raises(ValueError, match="same length"):
        build_bvh(lo[:5], hi, c)
    with pytest.raises(ValueError, match="strategy"):
        build_bvh(lo, hi, c, strategy="lbvh")
    with pytest.raises(ValueError, match="max_leaf_size"):
        build_bvh(lo, hi, c, max_leaf_size=0)
    with pytest.raises(ValueError, match="bins"):
        build_bvh(lo, hi, c, bins=1)
    with pytest.raises(ValueError, match="float32"):
        build_bvh(lo * 1e39, hi * 1e39, c)
