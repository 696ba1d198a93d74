"""Bounding volume hierarchy construction in pure, vectorised numpy.

The builder works on axis-aligned primitive bounds and centroids only, so triangles, spheres,
quads and discs all go through the same code. It splits the tree level by level: all nodes of a
depth are processed together with segmented numpy operations (the primitives of each node are
kept contiguous in one array), so the Python overhead is per level, not per node. A million
triangles build in about a second with binned SAH.

Strategies
----------
``"sah"``
    Binned surface area heuristic in the style of Wald (2007): the centroid bounds of every node
    are cut into ``bins`` equal bins on each of the three axes, the primitive boxes are binned,
    and every boundary between bins is a candidate split plane. Nodes with few primitives use
    fewer bins (the largest power of two not above their count, at least 2), which costs little
    quality and saves most of the sweep work deep in the tree. A node becomes a leaf when its
    count is at most ``max_leaf_size``, or when no candidate split is cheaper than the leaf and
    its count is at most ``max_leaf_hard``. Costs (see ``C_TRAV`` and ``C_ISECT``)::

        leaf  = C_ISECT * n
        split = C_TRAV + C_ISECT * (n_L * A_L + n_R * A_R) / A

    where ``A`` is the surface area of the node box and ``A_L``, ``A_R`` those of the boxes of
    the two sides.
``"midpoint"``
    Split at the middle of the centroid bounds along their largest axis.
``"equal_count"``
    Median split along the largest axis of the centroid bounds (``np.argpartition`` for the few
    large nodes at the top of the tree, one segmented sort per level further down).

Degenerate input
----------------
* When all centroids of a node coincide (no plane can separate them) the node is split by
  count, in its current order, into halves: SAH makes a leaf instead while the count is at most
  ``max_leaf_hard`` (splitting identical boxes only adds traversal cost).
* Leaves therefore never hold more than ``max_leaf_size`` primitives, except SAH leaves, which
  hold at most ``max(max_leaf_size, max_leaf_hard)``.
* ``N == 0`` raises ``ValueError`` (a tree with no primitive has no valid root box, and callers
  refuse empty meshes earlier); ``N == 1`` gives a single leaf.
* NaN or infinite bounds or centroids, and boxes with ``lo > hi``, raise ``ValueError``.

Layout
------
Nodes are stored in depth-first order, so the left child of an interior node ``i`` is ``i + 1``.
Per node (37 bytes in separate arrays): ``node_lo``/``node_hi`` (3 x f32 each), ``node_a``,
``node_count``, ``node_skip`` (i32) and ``node_axis`` (i8); plus one i32 per primitive in
``prim_order``. Node boxes are conservative in f32: f64 input is rounded outwards.
"""
from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

__all__ = ["FlatBVH", "build_bvh", "sah_cost", "C_TRAV", "C_ISECT", "STRATEGIES"]

# SAH cost constants. A node visit is one ray/box slab test; a primitive test (ray/triangle,
# sphere, ...) costs about twice as much, counting the extra indirection through prim_order.
C_TRAV = 1.0
C_ISECT = 2.0

STRATEGIES = ("sah", "midpoint", "equal_count")

# Above this many nodes per level the per-node centroid bounds use ufunc.at, below it reduceat
# (reduceat is fast for few long segments, ufunc.at for many short ones).
_REDUCEAT_MAX_SEGMENTS_FRACTION = 1.0 / 32.0
# Equal-count splits use a Python loop of np.argpartition while a level has at most this many
# nodes, and a single segmented sort per level beyond.
_ARGPARTITION_MAX_NODES = 64
# Builds over fewer primitives stay on the calling thread.
_THREADS_MIN_PRIMS = 100_000


@dataclass
class FlatBVH:
    """A BVH flattened in depth-first order (M nodes over N primitives).

    node_lo, node_hi: (M, 3) f32 node bounds.
    node_a:     (M,) i32, interior: index of the right child (the left child is node + 1);
                leaf: index of its first primitive in ``prim_order``.
    node_count: (M,) i32, 0 for interior nodes, the number of primitives (>= 1) for leaves.
    node_skip:  (M,) i32, the next node in depth-first order after this node's subtree (M at the
                end): where stackless traversal goes on a miss or after a leaf.
    node_axis:  (M,) i8, split axis of interior nodes, -1 for leaves.
    prim_order: (N,) i32, primitive indices in leaf order; a leaf covers
                ``prim_order[a : a + count]``.
    """

    node_lo: np.ndarray
    node_hi: np.ndarray
    node_a: np.ndarray
    node_count: np.ndarray
    node_skip: np.ndarray
    node_axis: np.ndarray
    prim_order: np.ndarray

    @property
    def num_nodes(self) -> int:
        return int(self.node_a.shape[0])

    @property
    def num_prims(self) -> int:
        return int(self.prim_order.shape[0])

    @property
    def nbytes(self) -> int:
        return sum(getattr(self, f).nbytes for f in ("node_lo", "node_hi", "node_a", "node_count",
                                                     "node_skip", "node_axis", "prim_order"))

    def depth(self) -> int:
        """Number of levels (1 for a single leaf)."""
        m = self.num_nodes
        d = np.zeros(m, np.int32)
        interior = np.flatnonzero(self.node_count == 0)
        for i in interior:  # parents precede children in depth-first order
            d[i + 1] = d[i] + 1
            d[self.node_a[i]] = d[i] + 1
        return int(d.max()) + 1


# ------------------------------------------------------------------------------------------------
# input preparation


def _to_f32_down(x: np.ndarray) -> np.ndarray:
    """Round to f32 towards -inf (exact for f32 input)."""
    if x.dtype == np.float32:
        return np.ascontiguousarray(x)
    x64 = x.astype(np.float64)
    y = x64.astype(np.float32)
    bad = y.astype(np.float64) > x64
    if bad.any():
        y[bad] = np.nextafter(y[bad], np.float32(-np.inf))
    return y


def _to_f32_up(x: np.ndarray) -> np.ndarray:
    """Round to f32 towards +inf (exact for f32 input)."""
    if x.dtype == np.float32:
        return np.ascontiguousarray(x)
    x64 = x.astype(np.float64)
    y = x64.astype(np.float32)
    bad = y.astype(np.float64) < x64
    if bad.any():
        y[bad] = np.nextafter(y[bad], np.float32(np.inf))
    return y


def _prepare(lo, hi, centroids) -> np.ndarray:
    """Validate the input and return X (9, N) f32: rows lo xyz, -hi xyz, centroid xyz.

    The upper bounds are stored negated so that every box reduction is a minimum.
    """
    arrays = []
    for name, a in (("lo", lo), ("hi", hi), ("centroids", centroids)):
        a = np.asarray(a)
        if a.ndim != 2 or a.shape[1] != 3:
            raise ValueError(f"{name} must have shape (N, 3), got {a.shape}")
        if not np.issubdtype(a.dtype, np.number) or np.issubdtype(a.dtype, np.complexfloating):
            raise ValueError(f"{name} must be a real numeric array, got {a.dtype}")
        arrays.append(a)
    lo, hi, c = arrays
    if not (lo.shape[0] == hi.shape[0] == c.shape[0]):
        raise ValueError(f"lo, hi and centroids must have the same length, "
                         f"got {lo.shape[0]}, {hi.shape[0]}, {c.shape[0]}")
    n = lo.shape[0]
    if n == 0:
        raise ValueError("cannot build a BVH over zero primitives")
    for name, a in (("lo", lo), ("hi", hi), ("centroids", c)):
        if np.issubdtype(a.dtype, np.floating) and not np.isfinite(a).all():
            raise ValueError(f"{name} contains NaN or infinite values")
    if (lo > hi).any():
        raise ValueError("some primitive boxes have lo > hi")
    lo32 = _to_f32_down(lo)
    hi32 = _to_f32_up(hi)
    c32 = c.astype(np.float32)
    if not np.isfinite(c32).all() or not np.isfinite(lo32).all() or not np.isfinite(hi32).all():
        raise ValueError("input values overflow float32")
    x = np.empty((9, n), np.float32)
    x[0:3] = lo32.T
    np.negative(hi32.T, out=x[3:6])
    x[6:9] = c32.T
    return x


# ------------------------------------------------------------------------------------------------
# per-level helpers


class _Work:
    """Per-element buffers reused by every level.

    Fresh multi-megabyte temporaries on every level cost more in page faults than in arithmetic,
    so the large per-element arrays live here and numpy writes into them with ``out=``.
    """

    def __init__(self, n: int, threads: int):
        self.n = n
        self.ar = np.arange(n, dtype=np.int64)
        self.x = (np.empty(9 * n, np.float32), np.empty(9 * n, np.float32))
        self.pid = (np.empty(n, np.int64), np.empty(n, np.int64))
        self.nodeof = np.empty(n, np.int64)
        self.f = np.empty(n, np.float32)
        self.f6 = np.empty(6 * n, np.float32)
        self.i = tuple(np.empty(n, np.int64) for _ in range(4))
        self.keys = np.empty(3 * n, np.int64)
        self.bins = np.empty(3 * n, np.int16)
        self.side = np.empty(n, np.bool_)
        self._box = np.empty(0, np.float32)
        self.pool = None
        if threads > 1 and n >= _THREADS_MIN_PRIMS:
            from concurrent.futures import ThreadPoolExecutor
            self.pool = ThreadPoolExecutor(max_workers=threads)

    def box(self, g: int) -> np.ndarray:
        """(6, g) f32 bin boxes, filled with +inf."""
        if self._box.shape[0] < 6 * g:
            self._box = np.empty(max(6 * g, self._box.shape[0] * 3 // 2), np.float32)
        b = self._box[:6 * g].reshape(6, g)
        b.fill(np.inf)
        return b

    def close(self):
        if self.pool is not None:
            self.pool.shutdown()
            self.pool = None


def _bcast(w: _Work, per_node: np.ndarray, nodeof: np.ndarray, out: np.ndarray) -> np.ndarray:
    """Per-node values -> per-element values (rows of a 2-D array at once)."""
    if per_node.ndim == 1:
        return np.take(per_node, nodeof, out=out)
    return np.take(per_node, nodeof, axis=1, out=out)


def _centroid_bounds(w: _Work, x, st, nodeof):
    """Per-node centroid bounds (3, n) of the contiguous, nonempty node segments."""
    n = st.shape[0]
    c = x[6:9]
    if n <= x.shape[1] * _REDUCEAT_MAX_SEGMENTS_FRACTION:
        return np.minimum.reduceat(c, st, axis=1), np.maximum.reduceat(c, st, axis=1)
    cmin = np.full((3, n), np.inf, np.float32)
    cmax = np.full((3, n), -np.inf, np.float32)
    for a in range(3):
        np.minimum.at(cmin[a], nodeof, c[a])
        np.maximum.at(cmax[a], nodeof, c[a])
    return cmin, cmax


def _half_area(b: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """Half surface area of boxes stored as (6, ...) = lo xyz, -hi xyz (empty boxes -> inf).

    With s = lo - hi = -extent the signs cancel: ex*ey + ey*ez + ez*ex = sx*(sy + sz) + sy*sz.
    """
    sx = b[3] + b[0]
    sy = b[4] + b[1]
    sz = b[5] + b[2]
    area = np.add(sy, sz, out=out)
    area *= sx
    sy *= sz
    area += sy
    return area


def _positional_side(w: _Work, n_act, st, cnt, nodeof, out):
    """Side for a split by count in the current order: the first floor(n/2) go right... left."""
    pos = np.subtract(w.ar[:n_act], _bcast(w, st, nodeof, w.i[3][:n_act]), out=w.i[3][:n_act])
    half = _bcast(w, cnt // 2, nodeof, w.i[2][:n_act])
    return np.greater_equal(pos, half, out=out)


def _bins_for_count(cnt: np.ndarray, bins: int) -> np.ndarray:
    """Bin count per node: half the largest power of two <= count, at least 2, at most ``bins``."""
    p = np.left_shift(1, np.floor(np.log2(np.maximum(cnt, 4))).astype(np.int64) - 1)
    return np.minimum(p, bins)


def _run(w: _Work, tasks):
    """Run callables, on the thread pool when there is one (ufunc.at releases the GIL)."""
    if w.pool is None:
        for t in tasks:
            t()
    else:
        for f in [w.pool.submit(t) for t in tasks]:
            f.result()


def _sah_level(w: _Work, x, st, cnt, nodeof, nbins, max_leaf_hard, c_trav, c_isect):
    """Binned SAH for all nodes of a level.

    Nodes must be sorted by descending ``nbins`` (each bin count forms one block).
    Returns (leaf mask, side per element, split axis per node).
    """
    n = cnt.shape[0]
    n_act = x.shape[1]
    cmin, cmax = _centroid_bounds(w, x, st, nodeof)
    ext = cmax - cmin
    # (c - cmin) * scale < nbins always: each f32 rounding gains at most 2**-24 relative
    nb_f = nbins.astype(np.float32) * np.float32(1.0 - 1e-6)
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        scale = np.where(ext > np.float32(1e-30), nb_f / ext, np.float32(0.0)).astype(np.float32)

    # Bin blocks: nodes with the same bin count b are contiguous; their bins are laid out
    # (b, 3, n_block) so that the sweeps over bins run along long vector rows.
    change = np.flatnonzero(nbins[1:] != nbins[:-1]) + 1
    blk_start = np.concatenate(([0], change)).astype(np.int64)
    blk_end = np.concatenate((change, [n])).astype(np.int64)
    blk_b = nbins[blk_start].astype(np.int64)
    blk_n = blk_end - blk_start
    blk_off = np.zeros(blk_start.shape[0] + 1, np.int64)
    np.cumsum(blk_b * 3 * blk_n, out=blk_off[1:])
    g_total = int(blk_off[-1])
    blk_of_node = np.repeat(np.arange(blk_start.shape[0]), blk_n)
    # bin (a, q) of node i sits at kbase + kaxis * (a + 3 q)
    kbase = blk_off[blk_of_node] + (np.arange(n) - blk_start[blk_of_node])
    kaxis = blk_n[blk_of_node]

    fe = _bcast(w, np.concatenate((cmin, scale)), nodeof, w.f6[:6 * n_act].reshape(6, n_act))
    kbase_e = _bcast(w, kbase, nodeof, w.i[0][:n_act])
    kaxis_e = _bcast(w, kaxis, nodeof, w.i[1][:n_act])
    keys = w.keys[:3 * n_act].reshape(3, n_act)
    node_bins = w.bins[:3 * n_act].reshape(3, n_act)
    f = w.f[:n_act]
    for a in range(3):
        np.subtract(x[6 + a], fe[a], out=f)
        f *= fe[3 + a]
        b = node_bins[a]
        np.copyto(b, f, casting="unsafe")  # truncation = floor, f >= 0
        k = keys[a]
        np.multiply(b, 3, out=k)
        k += a
        k *= kaxis_e
        k += kbase_e

    box = w.box(g_total)
    tasks = []
    for a in range(3):
        for rows in ((0, 1, 2), (3, 4, 5)):
            def task(a=a, rows=rows):
                for r in rows:
                    np.minimum.at(box[r], keys[a], x[r])
            tasks.append(task)
    if w.pool is not None:
        futures = [w.pool.submit(t) for t in tasks]
        counts = np.bincount(keys.reshape(-1), minlength=g_total)
        for fu in futures:
            fu.result()
    else:
        counts = np.bincount(keys.reshape(-1), minlength=g_total)
        for t in tasks:
            t()

    best_cost = np.empty(n, np.float32)
    best_axis = np.empty(n, np.int64)
    best_bin = np.empty(n, np.int64)
    node_area = np.empty(n, np.float32)
    with np.errstate(invalid="ignore", over="ignore"):
        for i in range(blk_start.shape[0]):
            b = int(blk_b[i])
            nn = int(blk_n[i])
            m = 3 * nn
            s0, s1 = int(blk_off[i]), int(blk_off[i + 1])
            t = box[:, s0:s1].reshape(6, b, m)
            k = counts[s0:s1].reshape(b, m).astype(np.float32)
            # suffix areas: a_r[q] = area of bins q+1 .. b-1
            a_r = np.empty((b - 1, m), np.float32)
            acc = t[:, b - 1].copy()
            for q in range(b - 2, -1, -1):
                _half_area(acc, out=a_r[q])
                np.minimum(acc, t[:, q], out=acc)
            node_area[blk_start[i]:blk_end[i]] = _half_area(acc[:, :nn])
            n_tot = k.sum(axis=0)
            # prefix sweep; an empty side has an infinite area, so its cost is 0 * inf = NaN,
            # which never compares below the running best
            acc = t[:, 0].copy()
            n_l = k[0].copy()
            best = np.full(m, np.inf, np.float32)
            best_q = np.zeros(m, np.int64)
            cost = np.empty(m, np.float32)
            tmp = np.empty(m, np.float32)
            for q in range(b - 1):
                if q > 0:
                    np.minimum(acc, t[:, q], out=acc)
                    n_l += k[q]
                _half_area(acc, out=cost)
                cost *= n_l
                np.subtract(n_tot, n_l, out=tmp)
                tmp *= a_r[q]
                cost += tmp
                better = cost < best
                np.copyto(best, cost, where=better)
                np.copyto(best_q, q, where=better)
            best = best.reshape(3, nn)
            j = np.argmin(best, axis=0)
            ar = np.arange(nn)
            sl = slice(int(blk_start[i]), int(blk_end[i]))
            best_cost[sl] = best[j, ar]
            best_axis[sl] = j
            best_bin[sl] = best_q.reshape(3, nn)[j, ar]

    valid = np.isfinite(best_cost)
    # split cost < leaf cost, multiplied through by the node area (robust for flat nodes)
    split_better = valid & (c_trav * node_area + c_isect * best_cost < c_isect * cnt * node_area)
    leaf = ~split_better & (cnt <= max_leaf_hard)

    # side per element: right iff its bin on the split axis is above the split bin
    idx = _bcast(w, np.where(valid, best_axis, 0) * n_act, nodeof, w.i[0][:n_act])
    idx += w.ar[:n_act]
    sel = np.take(w.bins[:3 * n_act], idx, out=w.i[1].view(np.int16)[:n_act])
    side = np.greater(sel, _bcast(w, best_bin, nodeof, w.i[2][:n_act]), out=w.side[:n_act])
    if not valid.all():
        # no plane separates the centroids: split by count
        need = np.repeat(~valid, cnt)
        pos = _positional_side(w, n_act, st, cnt, nodeof, np.empty(n_act, np.bool_))
        np.copyto(side, pos, where=need)
    axis = np.where(valid, best_axis, np.argmax(ext, axis=0))
    return leaf, side, axis


def _midpoint_level(w: _Work, x, st, cnt, nodeof):
    n_act = x.shape[1]
    cmin, cmax = _centroid_bounds(w, x, st, nodeof)
    ext = cmax - cmin
    axis = np.argmax(ext, axis=0)
    ar = np.arange(cnt.shape[0])
    idx = _bcast(w, axis * n_act, nodeof, w.i[0][:n_act])
    idx += w.ar[:n_act]
    c = np.take(x[6:9].reshape(-1), idx, out=w.f[:n_act])
    c -= _bcast(w, cmin[axis, ar], nodeof, w.f6[:n_act])
    half = ext[axis, ar] * np.float32(0.5)
    # right iff (c - cmin) > extent / 2: the extreme centroids always land on different sides
    # when the extent is nonzero, whatever the rounding
    side = np.greater(c, _bcast(w, half, nodeof, w.f6[n_act:2 * n_act]), out=w.side[:n_act])
    flat = ext[axis, ar] <= 0
    if flat.any():  # all centroids identical: split by count
        pos = _positional_side(w, n_act, st, cnt, nodeof, np.empty(n_act, np.bool_))
        np.copyto(side, pos, where=np.repeat(flat, cnt))
    return side, axis


def _equal_count_order(w: _Work, x, st, cnt, nodeof):
    """Median split: the element order that puts each node's lower half (on the largest
    centroid axis) first, and the split axes."""
    n = cnt.shape[0]
    n_act = x.shape[1]
    cmin, cmax = _centroid_bounds(w, x, st, nodeof)
    ext = cmax - cmin
    axis = np.argmax(ext, axis=0)
    if n <= _ARGPARTITION_MAX_NODES:
        order = np.arange(n_act)
        for i in range(n):
            s, c = int(st[i]), int(cnt[i])
            order[s:s + c] = s + np.argpartition(x[6 + axis[i], s:s + c], c // 2)
    else:
        ar = np.arange(n)
        idx = np.repeat(axis * n_act, cnt)
        idx += w.ar[:n_act]
        c = x[6:9].reshape(-1)[idx].astype(np.float64)
        e = ext[axis, ar].astype(np.float64)
        inv = np.where(e > 0, 0.5 / np.where(e > 0, e, 1.0), 0.0)
        # the keys of node i lie in [i, i + 0.5]: one sort orders the nodes and their centroids
        c -= np.repeat(cmin[axis, ar], cnt)
        c *= np.repeat(inv, cnt)
        c += nodeof
        order = np.argsort(c)
    return order, axis


# ------------------------------------------------------------------------------------------------
# the builder


def build_bvh(lo, hi, centroids, strategy: str = "sah", max_leaf_size: int = 4, bins: int = 16,
              *, max_leaf_hard: int = 16, c_trav: float = C_TRAV, c_isect: float = C_ISECT,
              threads: int | None = None) -> FlatBVH:
    """Build a BVH over N primitive boxes ``[lo, hi]`` (N, 3) with split keys ``centroids``.

    strategy: "sah" (binned SAH), "midpoint" or "equal_count" (see the module docstring).
    max_leaf_size: nodes with at most this many primitives always become leaves; the other
        strategies never make larger leaves.
    bins: SAH bins per axis for large nodes (2..256).
    max_leaf_hard: SAH may keep up to this many primitives (or max_leaf_size if larger) in a
        leaf when no split is cheaper or no plane separates the centroids.
    c_trav, c_isect: SAH traversal and intersection costs.
    threads: worker threads for the binning of large builds (numpy releases the GIL there);
        default min(2, cpu count). The result does not depend on it.
    """
    if strategy not in STRATEGIES:
        raise ValueError(f"unknown strategy {strategy!r}; expected one of {STRATEGIES}")
    max_leaf_size = int(max_leaf_size)
    if max_leaf_size < 1:
        raise ValueError("max_leaf_size must be >= 1")
    bins = int(bins)
    if not 2 <= bins <= 256:
        raise ValueError("bins must be in [2, 256]")
    max_leaf_hard = max(int(max_leaf_hard), max_leaf_size)
    if threads is None:
        threads = min(2, os.cpu_count() or 1)

    x_all = _prepare(lo, hi, centroids)
    n_prims = x_all.shape[1]
    w = _Work(n_prims, threads)
    try:
        return _build(w, x_all, strategy, max_leaf_size, bins, max_leaf_hard, c_trav, c_isect)
    finally:
        w.close()


def _build(w: _Work, x_all, strategy, max_leaf_size, bins, max_leaf_hard, c_trav, c_isect):
    n_prims = x_all.shape[1]
    cap = 2 * n_prims - 1

    # node table in breadth-first creation order (gid)
    t_left = np.full(cap, -1, np.int64)  # gid of the left child (right = left + 1), -1: leaf
    t_count = np.zeros(cap, np.int64)  # leaf primitive count
    t_first = np.zeros(cap, np.int64)  # leaf start in out_pid
    t_axis = np.full(cap, -1, np.int8)
    level_ranges = [(0, 1)]  # gid range of each depth

    out_pid = np.empty(n_prims, np.int64)
    out_cursor = 0
    next_gid = 1
    buf = 0  # which of the double buffers holds the current level

    if n_prims <= max_leaf_size:
        t_count[0] = n_prims
        out_pid[:] = np.arange(n_prims)
        out_cursor = n_prims
        gids = np.zeros(0, np.int64)
        cnt = np.zeros(0, np.int64)
    else:
        gids = np.zeros(1, np.int64)
        cnt = np.array([n_prims], np.int64)
        x = w.x[0][:9 * n_prims].reshape(9, n_prims)
        x[:] = x_all
        pid = w.pid[0][:n_prims]
        pid[:] = w.ar

    while cnt.shape[0] > 0:
        n = cnt.shape[0]
        n_act = x.shape[1]
        st = np.zeros(n, np.int64)
        np.cumsum(cnt[:-1], out=st[1:])
        nodeof = w.nodeof[:n_act]
        nodeof.fill(0)
        nodeof[st[1:]] = 1
        np.cumsum(nodeof, out=nodeof)

        if strategy == "sah":
            nbins = _bins_for_count(cnt, bins)
            leaf, side, axis = _sah_level(w, x, st, cnt, nodeof, nbins, max_leaf_hard, c_trav,
                                          c_isect)
            if leaf.any():  # leaves made here keep all their elements on the left
                np.copyto(side, False, where=np.repeat(leaf, cnt))
        else:
            if strategy == "midpoint":
                side, axis = _midpoint_level(w, x, st, cnt, nodeof)
            else:
                order, axis = _equal_count_order(w, x, st, cnt, nodeof)
                other = 1 - buf
                x = np.take(x, order, axis=1, out=w.x[other][:9 * n_act].reshape(9, n_act))
                pid = np.take(pid, order, out=w.pid[other][:n_act])
                buf = other
                side = _positional_side(w, n_act, st, cnt, nodeof, w.side[:n_act])
            leaf = np.zeros(n, bool)
        split = ~leaf

        # children counts
        side_i = side.view(np.int8)
        cs = np.cumsum(side_i, dtype=np.int64, out=w.i[0][:n_act])
        r_before = cs[st] - side_i[st]
        n_r = cs[st + cnt - 1] - r_before
        n_l = cnt - n_r

        sp = np.flatnonzero(split)
        ns = sp.shape[0]
        sp_gid = gids[sp]
        t_left[sp_gid] = next_gid + 2 * np.arange(ns)
        t_axis[sp_gid] = axis[sp]
        child_cnt = np.empty(2 * ns, np.int64)
        child_cnt[0::2] = n_l[sp]
        child_cnt[1::2] = n_r[sp]
        child_gid = next_gid + np.arange(2 * ns)
        level_ranges.append((next_gid, next_gid + 2 * ns))
        next_gid += 2 * ns

        child_leaf = child_cnt <= max_leaf_size
        act = np.flatnonzero(~child_leaf)
        if strategy == "sah" and act.shape[0] > 0:
            # the next level in descending bin count (one block per bin count)
            act = act[np.argsort(-_bins_for_count(child_cnt[act], bins), kind="stable")]
        act_cnt = child_cnt[act]
        n_next = int(act_cnt.sum())

        # destinations: [0, n_next) the next level (in `act` order), then the leaves made at
        # this level (leaf nodes first, then leaf children), which go on to out_pid
        dest_child = np.empty(2 * ns, np.int64)
        act_start = np.zeros(act.shape[0], np.int64)
        np.cumsum(act_cnt[:-1], out=act_start[1:])
        dest_child[act] = act_start
        lf_nodes = np.flatnonzero(leaf)
        lf_child = np.flatnonzero(child_leaf)
        lf_cnt = np.concatenate((cnt[lf_nodes], child_cnt[lf_child]))
        lf_start = np.zeros(lf_cnt.shape[0], np.int64)
        np.cumsum(lf_cnt[:-1], out=lf_start[1:])
        n_lf_nodes = lf_nodes.shape[0]
        dest_child[lf_child] = n_next + lf_start[n_lf_nodes:]
        dest_l = np.empty(n, np.int64)
        dest_r = np.zeros(n, np.int64)
        dest_l[lf_nodes] = n_next + lf_start[:n_lf_nodes]
        dest_l[sp] = dest_child[0::2]
        dest_r[sp] = dest_child[1::2]

        lf_gid = np.concatenate((gids[lf_nodes], child_gid[lf_child]))
        t_count[lf_gid] = lf_cnt
        t_first[lf_gid] = out_cursor + lf_start

        # stable partition of every node by side. With e the element index and E the number of
        # right elements before e: right -> dest_r + E - r_before, left -> dest_l + (e - st) -
        # (E - r_before)
        e_r = np.subtract(cs, side_i, out=cs)
        d_r = _bcast(w, dest_r - r_before, nodeof, w.i[1][:n_act])
        d_r += e_r
        d_l = np.subtract(w.ar[:n_act], e_r, out=w.i[2][:n_act])
        d_l += _bcast(w, dest_l - st + r_before, nodeof, w.i[3][:n_act])
        np.copyto(d_l, d_r, where=side)
        inv = w.i[0][:n_act]  # cs is no longer needed
        inv[d_l] = w.ar[:n_act]

        n_out = n_act - n_next
        np.take(pid, inv[n_next:], out=out_pid[out_cursor:out_cursor + n_out])
        out_cursor += n_out
        if n_next:
            keep = inv[:n_next]
            other = 1 - buf
            x_next = w.x[other][:9 * n_next].reshape(9, n_next)
            if w.pool is not None and n_next >= _THREADS_MIN_PRIMS:
                _run(w, [lambda: np.take(x[0:5], keep, axis=1, out=x_next[0:5]),
                         lambda: np.take(x[5:9], keep, axis=1, out=x_next[5:9])])
            else:
                np.take(x, keep, axis=1, out=x_next)
            x = x_next
            pid = np.take(pid, keep, out=w.pid[other][:n_next])
            buf = other
        gids = child_gid[act]
        cnt = act_cnt

    assert out_cursor == n_prims
    return _flatten(x_all, t_left[:next_gid], t_count[:next_gid], t_first[:next_gid],
                    t_axis[:next_gid], level_ranges, out_pid)


def _flatten(x_all, t_left, t_count, t_first, t_axis, level_ranges, out_pid) -> FlatBVH:
    """Breadth-first node table -> depth-first FlatBVH with boxes and skip links."""
    m = t_left.shape[0]
    n_prims = out_pid.shape[0]
    interior = t_left >= 0

    # subtree sizes bottom-up, depth-first indices top-down, one vector step per level
    size = np.ones(m, np.int64)
    for g0, g1 in reversed(level_ranges):
        it = g0 + np.flatnonzero(interior[g0:g1])
        if it.shape[0]:
            left = t_left[it]
            size[it] = 1 + size[left] + size[left + 1]
    dfs = np.zeros(m, np.int64)
    for g0, g1 in level_ranges:
        it = g0 + np.flatnonzero(interior[g0:g1])
        if it.shape[0]:
            left = t_left[it]
            dfs[left] = dfs[it] + 1
            dfs[left + 1] = dfs[it] + 1 + size[left]

    # primitives in depth-first leaf order
    leaves = np.flatnonzero(~interior)
    leaves = leaves[np.argsort(dfs[leaves])]
    lcnt = t_count[leaves]
    lstart = np.zeros(leaves.shape[0], np.int64)
    np.cumsum(lcnt[:-1], out=lstart[1:])
    src = np.repeat(t_first[leaves] - lstart, lcnt)
    src += np.arange(n_prims)
    prim_order = out_pid[src]

    # boxes: leaves from their primitives, interior nodes as the union of their children
    box = np.empty((6, m), np.float32)
    box[:, leaves] = np.minimum.reduceat(np.take(x_all[0:6], prim_order, axis=1), lstart, axis=1)
    for g0, g1 in reversed(level_ranges):
        it = g0 + np.flatnonzero(interior[g0:g1])
        if it.shape[0]:
            left = t_left[it]
            box[:, it] = np.minimum(box[:, left], box[:, left + 1])

    node_lo = np.empty((m, 3), np.float32)
    node_hi = np.empty((m, 3), np.float32)
    node_lo[dfs] = box[0:3].T
    node_hi[dfs] = -box[3:6].T
    node_a = np.empty(m, np.int32)
    it = np.flatnonzero(interior)
    node_a[dfs[it]] = dfs[t_left[it] + 1]
    node_a[dfs[leaves]] = lstart
    node_count = np.zeros(m, np.int32)
    node_count[dfs[leaves]] = lcnt
    node_skip = np.empty(m, np.int32)
    node_skip[dfs] = dfs + size
    node_axis = np.empty(m, np.int8)
    node_axis[dfs] = t_axis
    return FlatBVH(node_lo=node_lo, node_hi=node_hi, node_a=node_a, node_count=node_count,
                   node_skip=node_skip, node_axis=node_axis,
                   prim_order=prim_order.astype(np.int32))


def sah_cost(bvh: FlatBVH, c_trav: float = C_TRAV, c_isect: float = C_ISECT) -> float:
    """SAH cost of a tree: sum over nodes of area(node) / area(root) times c_trav for interior
    nodes and c_isect * count for leaves. A root of zero area counts every node with ratio 1."""
    lo = bvh.node_lo.astype(np.float64)
    hi = bvh.node_hi.astype(np.float64)
    e = hi - lo
    area = e[:, 0] * e[:, 1] + e[:, 1] * e[:, 2] + e[:, 2] * e[:, 0]
    ratio = area / area[0] if area[0] > 0 else np.ones_like(area)
    cnt = bvh.node_count.astype(np.float64)
    per_node = np.where(cnt > 0, c_isect * cnt, c_trav)
    return float(np.sum(ratio * per_node))
