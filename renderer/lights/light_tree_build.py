"""The light tree's build (numpy): emitter bounds in, the depth-first node table out.

The tree (Conty Estevez and Kulla 2018) chooses one of many emitters in proportion to its
estimated contribution; ``renderer.lights.light_tree.LightTree`` uploads it and walks it on the
device, and documents the importance a node gets there.

Emitters
--------
The tree sees an emitter as a box ``lo``/``hi``, a power (flux; for a one-sided Lambertian emitter
radiance x area x pi, computed by the caller) and an orientation cone: a unit ``axis``, the spread
``theta_o`` of the normals about it (0 for a flat one-sided emitter, pi for a two-sided one or a
point light) and the emission spread ``theta_e`` beyond the normal (pi/2 for Lambertian). The
emitter lights no point p whose direction from it is more than ``theta_e`` away from its normal.
``triangle_emitters`` computes these for one-sided Lambertian triangles.

Build (numpy)
-------------
Level by level, like ``renderer.geometry.bvh_build``: every node of a depth is split at once
with whole-array operations (scatters by ``np.minimum.at`` / ``np.bincount``). Measured here in
CPU time (``tests/lights/test_light_tree.py::test_build_time_100k`` prints the wall time, which
grows with whatever else the machine runs): the 20,000 triangles of the default ``light_panels``
in 0.07-0.1 s, 100,000 random emitters in 0.5-0.7 s.

* Split rule: the paper's SAOH over ``bins`` (12) bins of the centroid bounds per axis (fewer,
  down to 2, on deep levels whose nodes hold fewer emitters on average). A split into L and R costs
  ``K_r * (E_L * M_A(L) * M_O(L) + E_R * M_A(R) * M_O(R))`` with E the power, M_A the half
  surface area of the box plus ``AREA_EPS * (ex + ey + ez)^2`` (so that a set of lights on a
  line or at one height still has a measure that grows with its extent), M_O the paper's
  orientation measure of the cone (theta_o, theta_e) and ``K_r = max extent / extent on the
  axis`` (which keeps nodes from becoming long and thin). A bin's orientation cone is a bound
  computed in one pass (its axis is the mean of its emitters' axes, its spread the largest
  angle from that axis plus the emitter's theta_o); bins are merged by the exact cone union.
  The per-node cone data (used for sampling) is the exact union of the children's cones.
* The cheapest candidate always splits: nodes are split until they hold ``max_leaf_size``
  emitters (default 1, the best sampling; a leaf with several emitters chooses among them by
  power). A node whose centroids all coincide cannot be split by a plane, and a node deeper than
  ``COUNT_SPLIT_DEPTH`` (only reached by very skewed inputs) is split by count into halves, which
  bounds the depth by ``COUNT_SPLIT_DEPTH + log2(N)``.
* Nodes of at most ``small_node`` (``SMALL_NODE`` = 8) emitters are finished in one go, without
  the SAOH: their emitters are ordered along a Morton curve (63-bit codes of the centroids in the
  scene's box) and the order is halved by count down to the leaves. Binning such small nodes would
  cost as much per level as the large ones for little gain (a few neighbouring emitters); this
  takes the last 3 levels off the level loop.

Layout
------
Depth first: the left child of interior node i is i + 1, ``node_right[i]`` the right one (-1 for
a leaf). Emitters are listed in leaf order in ``order``; every node covers the contiguous range
``order[node_first : node_first + node_count]``. ``rank`` is the inverse of ``order``: the
position of an emitter in leaf order. That position encodes the emitter's trail from the root
(the left/right decisions): at interior node i the emitter lies to the left exactly when
``rank < node_first[node_right[i]]``. This is used instead of a bit mask so that no tree depth
is too deep to store (``LightTreeData.trail`` gives the bits on the host). ``emitter_leaf`` is
each emitter's leaf.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from renderer.geometry.box_rounding import round_out_f32

__all__ = ["EmitterBounds", "LightTreeData", "build_light_tree", "triangle_emitters", "cone_union",
           "orientation_measure", "SMALL_NODE"]

PI = math.pi

# Build constants.
AREA_EPS = 1e-3  # weight of the squared extent in the area measure (only matters for flat boxes)
SMALL_NODE = 8  # nodes of at most this many emitters are finished by Morton order
COUNT_SPLIT_DEPTH = 64  # beyond this depth nodes split by count (bounds the depth)
CONE_SLACK = 1e-6  # rad added to stored cone spreads: covers f64 -> f32 rounding of the axes


# ------------------------------------------------------------------------------------------------
# emitter input


@dataclass
class EmitterBounds:
    """Per-emitter input of the light selectors (N emitters).

    lo, hi: (N, 3) box; power: (N,) flux (>= 0); axis: (N, 3) orientation cone axis (need not be
    unit; a zero axis means "any direction", theta_o = pi); theta_o: (N,) spread of the normals
    about the axis; theta_e: (N,) emission spread beyond the normal (pi/2 for Lambertian).
    """

    lo: np.ndarray
    hi: np.ndarray
    power: np.ndarray
    axis: np.ndarray
    theta_o: np.ndarray
    theta_e: np.ndarray

    def __len__(self) -> int:
        return int(np.asarray(self.power).shape[0])


def triangle_emitters(v0, v1, v2, radiance) -> EmitterBounds:
    """Bounds of one-sided Lambertian triangles (front: counter-clockwise, normal
    (v1 - v0) x (v2 - v0)) emitting `radiance` (T,) (a scalar per triangle, e.g. the luminance
    of the emitted RGB radiance): power = radiance * area * pi, cone axis = the normal,
    theta_o = 0, theta_e = pi / 2. Boxes are rounded outwards to f32 (f32 vertices stay exact).
    Degenerate triangles get power 0 and a full cone."""
    v0, v1, v2 = (np.asarray(v, np.float64) for v in (v0, v1, v2))
    cross = np.cross(v1 - v0, v2 - v0)
    twice_area = np.linalg.norm(cross, axis=1)
    ok = twice_area > 0
    axis = np.zeros_like(cross)
    axis[ok] = cross[ok] / twice_area[ok, None]
    axis[~ok] = (0.0, 0.0, 1.0)
    radiance = np.broadcast_to(np.asarray(radiance, np.float64), twice_area.shape)
    lo, hi = round_out_f32(np.minimum(np.minimum(v0, v1), v2), np.maximum(np.maximum(v0, v1), v2))
    return EmitterBounds(
        lo=lo,
        hi=hi,
        power=(radiance * 0.5 * twice_area * PI).astype(np.float32),
        axis=axis.astype(np.float32),
        theta_o=np.where(ok, 0.0, PI).astype(np.float32),
        theta_e=np.full(twice_area.shape, 0.5 * PI, np.float32),
    )


def _validate(e: EmitterBounds):
    lo = np.asarray(e.lo)
    hi = np.asarray(e.hi)
    power = np.asarray(e.power, np.float64)
    axis = np.asarray(e.axis, np.float64)
    theta_o = np.asarray(e.theta_o, np.float64)
    theta_e = np.asarray(e.theta_e, np.float64)
    n = power.shape[0] if power.ndim == 1 else -1
    if n <= 0:
        raise ValueError("a light tree needs at least one emitter (power must have shape (N,))")
    for name, a, shape in (("lo", lo, (n, 3)), ("hi", hi, (n, 3)), ("axis", axis, (n, 3)),
                           ("theta_o", theta_o, (n,)), ("theta_e", theta_e, (n,))):
        if a.shape != shape:
            raise ValueError(f"{name} must have shape {shape}, got {a.shape}")
    for name, a in (("lo", lo), ("hi", hi), ("power", power), ("axis", axis),
                    ("theta_o", theta_o), ("theta_e", theta_e)):
        if not np.all(np.isfinite(np.asarray(a, np.float64))):
            raise ValueError(f"{name} contains NaN or infinite values")
    if np.any(lo > hi):
        raise ValueError("some emitter boxes have lo > hi")
    if np.any(power < 0):
        raise ValueError("emitter power must be >= 0")
    if not power.sum() > 0:
        raise ValueError("the emitters' total power is 0: nothing to sample")
    length = np.linalg.norm(axis, axis=1)
    ok = length > 0
    unit = np.zeros_like(axis)
    unit[ok] = axis[ok] / length[ok, None]
    unit[~ok] = (0.0, 0.0, 1.0)
    theta_o = np.where(ok, np.clip(theta_o, 0.0, PI), PI)
    lo32, hi32 = round_out_f32(lo, hi)
    return lo32, hi32, power, unit, theta_o, np.clip(theta_e, 0.0, PI)


# ------------------------------------------------------------------------------------------------
# cones


def cone_union(wa, ta, wb, tb):
    """The smallest cone holding both cones (Conty Estevez and Kulla, Listing 1), vectorised.

    wa, wb (..., 3) unit axes; ta, tb (...) spreads in [0, pi], or negative for an empty cone.
    Returns (w (..., 3), t (...)) as f64 arrays.
    """
    wa, wb = np.asarray(wa, np.float64), np.asarray(wb, np.float64)
    ta, tb = np.asarray(ta, np.float64), np.asarray(tb, np.float64)
    shape = np.broadcast_shapes(wa.shape[:-1], wb.shape[:-1], ta.shape, tb.shape)
    wa, wb = (np.broadcast_to(w, shape + (3,)).reshape(-1, 3) for w in (wa, wb))
    ta, tb = (np.broadcast_to(t, shape).reshape(-1) for t in (ta, tb))
    x, y, z, t = _cone_union_soa(wa[:, 0], wa[:, 1], wa[:, 2], ta, wb[:, 0], wb[:, 1], wb[:, 2], tb)
    return np.stack([x, y, z], -1).reshape(shape + (3,)), t.reshape(shape)


def _cone_union_soa(ax, ay, az, ta, bx, by, bz, tb):
    """cone_union on axes given as separate x, y, z arrays (the builder's layout)."""
    # the angle between the axes as atan2(|a x b|, a . b): accurate near 0 and pi, where
    # arccos(a . b) loses half the digits
    cx = ay * bz - az * by
    cy = az * bx - ax * bz
    cz = ax * by - ay * bx
    td = np.arctan2(np.sqrt(cx * cx + cy * cy + cz * cz), ax * bx + ay * by + az * bz)
    b_in_a = (tb < 0) | (np.minimum(td + tb, PI) <= ta)
    a_in_b = ~b_in_a & ((ta < 0) | (np.minimum(td + ta, PI) <= tb))
    x = np.where(a_in_b, bx, ax)
    y = np.where(a_in_b, by, ay)
    z = np.where(a_in_b, bz, az)
    t = np.where(a_in_b, tb, ta)
    mix = ~(b_in_a | a_in_b)
    if mix.any():
        to = 0.5 * (ta + td + tb)
        t[mix] = PI  # a full cone unless the rotation below applies
        idx = np.nonzero(mix & (to < PI))
        # rotate wa towards wb by theta_r = theta_o - theta_a about k = wa x wb (Rodrigues, with
        # k . wa = 0): w = wa cos(theta_r) + (k x wa) sin(theta_r)
        a = np.stack([ax[idx], ay[idx], az[idx]], 1)
        b = np.stack([bx[idx], by[idx], bz[idx]], 1)
        k = np.cross(a, b)
        k_len = np.sqrt(np.einsum("ij,ij->i", k, k))
        ok = k_len > 1e-12  # antiparallel axes: no unique rotation, keep the full cone
        k = k[ok] / k_len[ok, None]
        a = a[ok]
        tr = (to[idx] - ta[idx])[ok, None]
        r = a * np.cos(tr) + np.cross(k, a) * np.sin(tr)
        r /= np.sqrt(np.einsum("ij,ij->i", r, r))[:, None]
        sel = tuple(i[ok] for i in idx)
        x[sel], y[sel], z[sel] = r[:, 0], r[:, 1], r[:, 2]
        t[sel] = to[idx][ok]
    return x, y, z, t


def orientation_measure(theta_o, theta_e):
    """The paper's M_Omega: the solid-angle-like measure of a cone of normals (theta_o) that emit
    up to theta_e beyond the normal."""
    to = np.asarray(theta_o, np.float64)
    tw = np.minimum(to + np.asarray(theta_e, np.float64), PI)
    cos_o = np.cos(to)
    sin_o = np.sin(to)
    return 2.0 * PI * (1.0 - cos_o) + 0.5 * PI * (
        2.0 * (tw - to) * sin_o - np.cos(to - 2.0 * tw) + cos_o)


def _accumulate(op, x):
    """op.accumulate along axis 1 of x, one whole slice per step (faster than ufunc.accumulate
    along an inner axis)."""
    out = np.empty_like(x)
    out[:, 0] = x[:, 0]
    for j in range(1, x.shape[1]):
        op(out[:, j - 1], x[:, j], out=out[:, j])
    return out


def _area_measure(ext):
    """ext (..., 3) extents -> half surface area + AREA_EPS * (ex + ey + ez)^2."""
    ex, ey, ez = ext[..., 0], ext[..., 1], ext[..., 2]
    s = ex + ey + ez
    return ex * ey + ey * ez + ez * ex + AREA_EPS * s * s


# ------------------------------------------------------------------------------------------------
# the tree on the host


@dataclass
class LightTreeData:
    """A light tree flattened depth first (M nodes over N emitters); see the module docstring.

    node_lo, node_hi, node_axis: (M, 3) f32; node_power, node_theta_o, node_theta_e: (M,) f32;
    node_right: (M,) i32 (-1 for leaves); node_first, node_count: (M,) i32 (the node's range in
    ``order``); order: (N,) i32 emitters in leaf order; rank: (N,) i32 its inverse;
    emitter_leaf: (N,) i32; emitter_power: (N,) f32 (input order).
    """

    node_lo: np.ndarray
    node_hi: np.ndarray
    node_axis: np.ndarray
    node_power: np.ndarray
    node_theta_o: np.ndarray
    node_theta_e: np.ndarray
    node_right: np.ndarray
    node_first: np.ndarray
    node_count: np.ndarray
    order: np.ndarray
    rank: np.ndarray
    emitter_leaf: np.ndarray
    emitter_power: np.ndarray

    @property
    def num_nodes(self) -> int:
        return int(self.node_right.shape[0])

    @property
    def num_emitters(self) -> int:
        return int(self.order.shape[0])

    def depth(self) -> int:
        """Levels from the root to the deepest leaf (1 for a single leaf)."""
        level = np.zeros(1, np.int64)
        depth = 0
        while level.shape[0]:
            depth += 1
            inner = level[self.node_right[level] >= 0]
            level = np.concatenate((inner + 1, self.node_right[inner]))
        return depth

    def trail(self, emitter: int) -> list[int]:
        """The left (0) / right (1) decisions from the root to the emitter's leaf."""
        r = int(self.rank[emitter])
        node, bits = 0, []
        while self.node_right[node] >= 0:
            right = int(self.node_right[node])
            go_right = r >= self.node_first[right]
            bits.append(int(go_right))
            node = right if go_right else node + 1
        assert node == self.emitter_leaf[emitter]
        return bits


def build_light_tree(emitters: EmitterBounds, *, max_leaf_size: int = 1, bins: int = 12,
                     small_node: int = SMALL_NODE) -> LightTreeData:
    """Build the light tree (see the module docstring for the split rule and layout)."""
    if max_leaf_size < 1:
        raise ValueError("max_leaf_size must be >= 1")
    if bins < 2:
        raise ValueError("bins must be >= 2")
    lo, hi, power, axis, theta_o, theta_e = _validate(emitters)
    n = power.shape[0]
    centroid = 0.5 * (lo.astype(np.float64) + hi.astype(np.float64))
    table = _Table(n)
    leaf_of = np.zeros(n, np.int64)
    if n > max_leaf_size:
        morton = _morton(centroid)
        act = np.arange(n, dtype=np.int64)
        node_of = np.zeros(n, np.int64)
        gids = np.zeros(1, np.int64)
        depth = 0
        while act.shape[0]:
            cnt = np.bincount(node_of, minlength=gids.shape[0])
            small = cnt <= small_node
            if small.any():
                # small nodes: whole subtrees at once, by halving their Morton order
                mine = small[node_of]
                small_index = np.cumsum(small) - 1
                _build_small(table, gids[small], act[mine], small_index[node_of[mine]], morton,
                             leaf_of, max_leaf_size)
                big = np.flatnonzero(~small)
                remap = np.full(gids.shape[0], -1, np.int64)
                remap[big] = np.arange(big.shape[0])
                act = act[~mine]
                node_of = remap[node_of[~mine]]
                gids = gids[big]
                cnt = cnt[big]
                if not act.shape[0]:
                    break
            k = gids.shape[0]
            go_left = _split_level(act, node_of, cnt, depth, centroid, lo, hi, power, axis,
                                   theta_o, theta_e, bins)
            left_cnt = np.bincount(node_of, weights=go_left, minlength=k).astype(np.int64)
            base = table.add_children(gids, left_cnt, cnt - left_cnt)
            child_cnt = table.count[base:base + 2 * k]
            child = 2 * node_of + (~go_left)
            child_leaf = child_cnt <= max_leaf_size
            done = child_leaf[child]
            leaf_of[act[done]] = base + child[done]
            inner = np.flatnonzero(~child_leaf)
            remap = np.full(2 * k, -1, np.int64)
            remap[inner] = np.arange(inner.shape[0])
            keep = ~done
            act = act[keep]
            node_of = remap[child[keep]]
            gids = base + inner
            depth += 1
    return _finish(lo, hi, power, axis, theta_o, theta_e, table.left[:table.size],
                   table.count[:table.size], table.level_ranges, leaf_of)


class _Table:
    """The breadth-first node table under construction: children are allocated in pairs
    (right = left + 1), one contiguous range of pairs per call, so that every node's children
    lie in a later range than the node (``level_ranges``)."""

    def __init__(self, n: int):
        self.left = np.full(2 * n + 1, -1, np.int64)
        self.count = np.zeros(2 * n + 1, np.int64)
        self.count[0] = n
        self.level_ranges = [(0, 1)]
        self.size = 1

    def add_children(self, parents, left_count, right_count) -> int:
        """Give each parent two children; returns the gid of the first left child."""
        k = parents.shape[0]
        base = self.size
        self.left[parents] = base + 2 * np.arange(k)
        self.count[base:base + 2 * k:2] = left_count
        self.count[base + 1:base + 2 * k:2] = right_count
        self.level_ranges.append((base, base + 2 * k))
        self.size += 2 * k
        return base


def _morton(points) -> np.ndarray:
    """63-bit Morton codes (21 bits per axis) of points in their bounding box."""
    lo = points.min(axis=0)
    ext = points.max(axis=0) - lo
    q = np.where(ext > 0, (points - lo) / np.where(ext > 0, ext, 1.0), 0.0)
    q = np.minimum((q * (1 << 21)).astype(np.uint64), np.uint64((1 << 21) - 1))
    code = np.zeros(points.shape[0], np.uint64)
    for a in range(3):
        x = q[:, a]
        x = (x | (x << np.uint64(32))) & np.uint64(0x1F00000000FFFF)
        x = (x | (x << np.uint64(16))) & np.uint64(0x1F0000FF0000FF)
        x = (x | (x << np.uint64(8))) & np.uint64(0x100F00F00F00F00F)
        x = (x | (x << np.uint64(4))) & np.uint64(0x10C30C30C30C30C3)
        x = (x | (x << np.uint64(2))) & np.uint64(0x1249249249249249)
        code |= x << np.uint64(2 - a)
    return code


def _build_small(table: _Table, gids, emitters, node_of, morton, leaf_of, max_leaf_size):
    """Subtrees of the nodes ``gids`` (each of at most SMALL_NODE emitters; ``emitters`` with
    their ``node_of`` index into gids): the emitters of a node are ordered along the Morton
    curve and the order is halved by count down to leaves of at most max_leaf_size."""
    srt = np.lexsort((morton[emitters], node_of))
    em = emitters[srt]
    count = np.bincount(node_of, minlength=gids.shape[0])
    start = np.zeros_like(count)
    np.cumsum(count[:-1], out=start[1:])
    gid = gids
    while gid.shape[0]:
        leaf = count <= max_leaf_size
        if leaf.any():
            c = count[leaf]
            first = np.repeat(start[leaf] - np.cumsum(c) + c, c)
            leaf_of[em[first + np.arange(first.shape[0])]] = np.repeat(gid[leaf], c)
        inner = ~leaf
        gid, start, count = gid[inner], start[inner], count[inner]
        if not gid.shape[0]:
            break
        lc = count // 2
        base = table.add_children(gid, lc, count - lc)
        k = gid.shape[0]
        gid = base + np.arange(2 * k)
        start = np.stack([start, start + lc], 1).ravel()
        count = np.stack([lc, count - lc], 1).ravel()


def _split_level(act, node_of, cnt, depth, centroid, lo, hi, power, axis, theta_o, theta_e,
                 bins) -> np.ndarray:
    """Split every node of one level; returns go_left per active emitter."""
    k = cnt.shape[0]
    n_act = act.shape[0]
    c = centroid[act]
    cmin = np.full((3, k), np.inf)
    cmax = np.full((3, k), -np.inf)
    for a in range(3):
        np.minimum.at(cmin[a], node_of, c[:, a])
        np.maximum.at(cmax[a], node_of, c[:, a])
    ext = cmax - cmin
    # Bins per axis: `bins`, but no more than the level's mean node size (deep levels of small
    # nodes would otherwise spend their time on empty bins).
    nb = int(np.clip(n_act // k, 2, bins))
    splittable = ext > 0  # (3, k)
    scale = np.where(splittable, nb * (1.0 - 1e-9) / np.where(splittable, ext, 1.0), 0.0)
    binv = np.empty((3, n_act), np.int64)
    for a in range(3):
        binv[a] = np.clip(((c[:, a] - cmin[a][node_of]) * scale[a][node_of]).astype(np.int64),
                          0, nb - 1)

    go_left = np.zeros(n_act, bool)
    count_split = np.ones(k, bool)
    if depth < COUNT_SPLIT_DEPTH and splittable.any():
        # Per (bin, split axis, node) statistics in one flat array, bin-major so that the
        # sweeps over bins below run along whole rows: key = (bin * 3 + axis) * k + node,
        # for the 3 * n_act (emitter, split axis) pairs at once.
        g = nb * 3 * k
        key = ((binv * 3 + np.arange(3)[:, None]) * k + node_of).ravel()

        def t3(x):  # a per-emitter value for each of the 3 (emitter, split axis) pairs
            return np.concatenate((x, x, x))
        wa = axis[act].T.copy()
        shape = (nb, 3, k)
        b_cnt = np.bincount(key, minlength=g).reshape(shape)
        b_pow = np.bincount(key, weights=t3(power[act]), minlength=g).reshape(shape)
        b_lo = np.full((3, g), np.inf, np.float32)
        b_hi = np.full((3, g), -np.inf, np.float32)
        la = lo[act].T.copy()
        ha = hi[act].T.copy()
        for r in range(3):
            np.minimum.at(b_lo[r], key, t3(la[r]))
            np.maximum.at(b_hi[r], key, t3(ha[r]))
        # A bin's cone, bounded in one pass: the mean axis, and the largest angle from it plus
        # the emitter's spread. A bin whose axes (nearly) cancel gets a full cone.
        wa3 = [t3(wa[r]) for r in range(3)]
        b_w = [np.bincount(key, weights=wa3[r], minlength=g) for r in range(3)]
        length = np.sqrt(b_w[0] ** 2 + b_w[1] ** 2 + b_w[2] ** 2)
        spread_ok = length > 1e-6 * np.maximum(b_cnt.ravel(), 1)
        inv = np.where(spread_ok, 1.0 / np.where(spread_ok, length, 1.0), 0.0)
        b_w = [w * inv for w in b_w]
        b_w[2][~spread_ok] = 1.0
        cos_dev = wa3[0] * b_w[0][key]
        cos_dev += wa3[1] * b_w[1][key]
        cos_dev += wa3[2] * b_w[2][key]
        dev = np.arccos(np.clip(cos_dev, -1.0, 1.0, out=cos_dev))
        dev += t3(theta_o[act])
        b_to = np.full(g, -1.0, np.float32)
        np.maximum.at(b_to, key, dev.astype(np.float32))
        b_to = np.where(spread_ok, np.minimum(b_to.astype(np.float64), PI), PI)
        b_to[b_cnt.ravel() == 0] = -1.0  # empty bins hold empty cones
        b_te = np.zeros(g, np.float32)
        np.maximum.at(b_te, key, t3(theta_e[act]).astype(np.float32))
        b_lo = b_lo.reshape((3,) + shape)
        b_hi = b_hi.reshape((3,) + shape)
        b_w = [w.reshape(shape) for w in b_w]
        b_to = b_to.reshape(shape)
        b_te = b_te.reshape(shape)

        def sweep(flip):
            """Merged statistics of bins 0..j (flip: of bins j..nb-1) for every j:
            (count, power * M_A * M_O, box extents), each (nb, 3, k)."""
            f = (lambda x, ax=0: np.flip(x, ax)) if flip else (lambda x, ax=0: x)
            c_acc = np.cumsum(f(b_cnt), 0)
            p_acc = np.cumsum(f(b_pow), 0)
            lo_acc = _accumulate(np.minimum, f(b_lo, 1))
            hi_acc = _accumulate(np.maximum, f(b_hi, 1))
            te_acc = _accumulate(np.maximum, f(b_te)[None])[0]
            w_in = [f(w) for w in b_w]
            to_in = f(b_to)
            w_acc = [np.empty(shape) for _ in range(3)]
            to_acc = np.empty(shape)
            for r in range(3):
                w_acc[r][0] = w_in[r][0]
            to_acc[0] = to_in[0]
            for j in range(1, nb):
                w_acc[0][j], w_acc[1][j], w_acc[2][j], to_acc[j] = _cone_union_soa(
                    w_acc[0][j - 1], w_acc[1][j - 1], w_acc[2][j - 1], to_acc[j - 1],
                    w_in[0][j], w_in[1][j], w_in[2][j], to_in[j])
            ext_acc = np.maximum(hi_acc.astype(np.float64) - lo_acc, 0.0)  # (3, nb, 3, k)
            measure = (_area_measure(np.moveaxis(ext_acc, 0, -1))
                       * orientation_measure(np.maximum(to_acc, 0.0), te_acc))
            return f(c_acc), f(p_acc * measure), f(ext_acc, 1)

        c_pre, m_pre, e_pre = sweep(False)
        c_suf, m_suf, _ = sweep(True)
        node_ext = e_pre[:, nb - 1, 0]  # (3, k): the node's box extents
        with np.errstate(divide="ignore", invalid="ignore"):
            k_r = np.where(node_ext > 0, node_ext.max(axis=0) / node_ext, np.inf)
        # split after bin j: bins 0..j left, j+1..nb-1 right
        ok = (c_pre[:-1] > 0) & (c_suf[1:] > 0) & splittable
        with np.errstate(invalid="ignore"):
            cost = np.where(ok, k_r * (m_pre[:-1] + m_suf[1:]), np.inf)  # (nb - 1, 3, k)
        flat = cost.reshape(-1, k)
        best = np.argmin(flat, axis=0)
        count_split = ~np.isfinite(flat[best, np.arange(k)])
        best_bin = best // 3
        best_axis = best % 3
        go_left = binv[best_axis[node_of], np.arange(n_act)] <= best_bin[node_of]

    if count_split.any():
        # the first floor(count / 2) emitters (in working order) of each such node go left
        sub = np.flatnonzero(count_split[node_of])
        nd = node_of[sub]
        srt = np.argsort(nd, kind="stable")
        sub, nd = sub[srt], nd[srt]
        start = np.zeros(k, np.int64)
        np.cumsum(np.bincount(nd, minlength=k)[:-1], out=start[1:])
        rank = np.arange(sub.shape[0]) - start[nd]
        go_left[sub] = rank < (cnt // 2)[nd]
    return go_left


def _finish(lo, hi, power, axis, theta_o, theta_e, t_left, t_count, level_ranges,
            leaf_of) -> LightTreeData:
    """Node data bottom-up, then the breadth-first table -> depth-first arrays."""
    m = t_left.shape[0]
    n = power.shape[0]
    interior = t_left >= 0
    levels = [g0 + np.flatnonzero(interior[g0:g1]) for g0, g1 in level_ranges]

    # leaves from their emitters
    b_lo = np.full((m, 3), np.inf, np.float32)
    b_hi = np.full((m, 3), -np.inf, np.float32)
    for r in range(3):
        np.minimum.at(b_lo[:, r], leaf_of, lo[:, r])
        np.maximum.at(b_hi[:, r], leaf_of, hi[:, r])
    b_pow = np.bincount(leaf_of, weights=power, minlength=m)
    b_te = np.full(m, -1.0)
    np.maximum.at(b_te, leaf_of, theta_e)
    b_w = np.zeros((m, 3))
    b_w[:, 2] = 1.0
    b_to = np.full(m, -1.0)
    by_leaf = np.argsort(leaf_of, kind="stable")
    leaves_sorted = leaf_of[by_leaf]
    first_of = np.searchsorted(leaves_sorted, leaves_sorted, side="left")
    slot = np.arange(n) - first_of
    for s in range(int(slot.max()) + 1):
        e = by_leaf[slot == s]
        lf = leaf_of[e]
        b_w[lf], b_to[lf] = cone_union(b_w[lf], b_to[lf], axis[e], theta_o[e])
    # interior nodes from their children, deepest level first
    for it in reversed(levels):
        if it.shape[0]:
            left = t_left[it]
            right = left + 1
            b_lo[it] = np.minimum(b_lo[left], b_lo[right])
            b_hi[it] = np.maximum(b_hi[left], b_hi[right])
            b_pow[it] = b_pow[left] + b_pow[right]
            b_te[it] = np.maximum(b_te[left], b_te[right])
            b_w[it], b_to[it] = cone_union(b_w[left], b_to[left], b_w[right], b_to[right])

    # depth-first numbering: subtree sizes bottom-up, indices top-down
    size = np.ones(m, np.int64)
    for it in reversed(levels):
        if it.shape[0]:
            left = t_left[it]
            size[it] = 1 + size[left] + size[left + 1]
    dfs = np.zeros(m, np.int64)
    first = np.zeros(m, np.int64)
    for it in levels:
        if it.shape[0]:
            left = t_left[it]
            dfs[left] = dfs[it] + 1
            dfs[left + 1] = dfs[it] + 1 + size[left]
            first[left] = first[it]
            first[left + 1] = first[it] + t_count[left]
    # emitters in leaf order: by the leaf's first position, stable within a leaf
    order = np.argsort(first[leaf_of], kind="stable")
    rank = np.empty(n, np.int64)
    rank[order] = np.arange(n)

    def place(x, dtype):
        out = np.empty((m,) + x.shape[1:], dtype)
        out[dfs] = x
        return out

    right = np.where(interior, dfs[np.where(interior, t_left + 1, 0)], -1)
    return LightTreeData(
        node_lo=place(b_lo, np.float32),
        node_hi=place(b_hi, np.float32),
        node_axis=place(b_w, np.float32),
        node_power=place(b_pow, np.float32),
        node_theta_o=place(np.minimum(b_to + CONE_SLACK, PI), np.float32),
        node_theta_e=place(b_te, np.float32),
        node_right=place(right, np.int32),
        node_first=place(first, np.int32),
        node_count=place(t_count, np.int32),
        order=order.astype(np.int32),
        rank=rank.astype(np.int32),
        emitter_leaf=dfs[leaf_of].astype(np.int32),
        emitter_power=power.astype(np.float32),
    )
