"""Bounding volume hierarchy construction in pure, vectorised numpy.

The builder sees primitives only as axis-aligned boxes plus a centroid each (the split key), so
triangles, spheres, quads and discs all go through the same code.

Strategies
----------
``"sah"``
    Binned surface area heuristic in the style of Wald (2007): the centroid bounds of every node
    are cut into equal bins on each of the three axes, the primitive boxes are binned, and every
    boundary between two bins is a candidate split plane. Large nodes use ``bins`` bins; a node
    of n < 2 * bins primitives uses half the largest power of two <= n (at least 2), which costs
    little quality and keeps the per-level bin work below the primitive count. A node becomes a
    leaf when n <= ``max_leaf_size``, or when no candidate split is cheaper than the leaf and
    n <= ``max_leaf_hard``. Costs, with ``A`` the surface area of the node's box and ``A_L``,
    ``A_R`` those of the two sides' boxes::

        leaf  = C_ISECT * n
        split = C_TRAV + C_ISECT * (n_L * A_L + n_R * A_R) / A

    ``C_TRAV = 1`` and ``C_ISECT = 2``: a node visit is one ray/box slab test, a primitive test
    (ray/triangle, ray/sphere, ...) costs about twice that, indirection included.
``"midpoint"``
    Split at the middle of the centroid bounds, on their largest axis.
``"equal_count"``
    Median split on the largest axis of the centroid bounds: ``np.argpartition`` at the node
    boundaries and medians while a level has at most 64 nodes, one sort per level beyond.

Degenerate input
----------------
* A node whose centroids all coincide cannot be split by a plane. SAH keeps it as a leaf while
  n <= ``max_leaf_hard`` (splitting identical boxes only adds traversal cost); beyond that, and
  always for the other strategies, it is split by count into halves.
* So leaves never hold more than ``max_leaf_size`` primitives, except SAH leaves, which hold at
  most ``max(max_leaf_size, max_leaf_hard)`` (default 16).
* ``N == 0`` raises ``ValueError``: a tree without primitives has no root box (callers refuse
  empty meshes earlier). ``N == 1`` (or any ``N <= max_leaf_size``) gives a single leaf.
* NaN or infinite values, values beyond the float32 range and boxes with ``lo > hi`` raise
  ``ValueError``.

Layout
------
Nodes are stored in depth-first order, so the left child of interior node ``i`` is ``i + 1``;
leaves list their primitives contiguously in ``prim_order``, also in depth-first order. A node
takes 37 bytes in the separate arrays: ``node_lo``, ``node_hi`` (3 x f32 each), ``node_a``,
``node_count``, ``node_skip`` (i32) and ``node_axis`` (i8); ``prim_order`` adds 4 bytes per
primitive. Node boxes are conservative in f32: f64 input is rounded outwards, f32 input is
used exactly.

How it is fast
--------------
A per-node Python loop would cost seconds for a million primitives, so the tree is built level
by level: every node of a depth is split at once with whole-array numpy operations.

* The primitive data never moves. Each primitive carries the index of its node at the current
  level; primitives that reached a leaf point at a dummy node past the last one. The active set
  is compacted once fewer than 60 % of the primitives remain in it.
* Per-node reductions (centroid bounds, bin boxes) are ``ufunc.at`` scatters, about 1.2 ns per
  element. They serialise on repeated updates of one address, so the primitives are processed
  in a scattered order (neighbours in a mesh share nodes and bins), and the few nodes at the top
  of the tree spread their updates over 16 lanes.
* Binned SAH needs the box of every (node, axis, bin): 18 scatter passes per level. While a
  level has fewer than N / b**3 nodes, it bins into b x b x b cells instead (6 passes) and
  reduces the cells to per-axis bins.
* Prefix and suffix sweeps run over all nodes with the same bin count together, bin by bin.
* Large per-primitive arrays live in buffers reused by every level (fresh temporaries would
  cost more in page faults than in arithmetic).
* A second thread takes half of the scatter passes when a core is free (numpy releases the GIL
  there); the tree does not depend on it.

Binned SAH over a million triangles takes about 1.2 s on one core, midpoint 0.5 s.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from renderer.geometry.box_rounding import round_out_f32

__all__ = ["FlatBVH", "build_bvh", "sah_cost", "C_TRAV", "C_ISECT", "STRATEGIES"]

# SAH cost constants. A node visit is one ray/box slab test; a primitive test (ray/triangle,
# ray/sphere, ...) costs about twice as much, counting the indirection through prim_order.
C_TRAV = 1.0
C_ISECT = 2.0

STRATEGIES = ("sah", "midpoint", "equal_count")

# Equal-count splits use np.argpartition while a level has at most this many nodes, a full
# sort beyond.
_ARGPARTITION_MAX_NODES = 64
# Builds over fewer primitives stay on the calling thread.
_THREADS_MIN_PRIMS = 100_000
# The active primitives are compacted once fewer than this fraction remain.
_COMPACT_FRACTION = 0.6
# SAH levels of one bin count b bin through b**3 cells per node while cells <= ratio * prims.
_CELLS_MAX_RATIO = 1.0


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
        level = np.zeros(1, np.int64)
        depth = 0
        while level.shape[0]:
            depth += 1
            inner = level[self.node_count[level] == 0]
            level = np.concatenate((inner + 1, self.node_a[inner]))
        return depth


# ------------------------------------------------------------------------------------------------
# input preparation


def _scattered_order(n: int) -> np.ndarray:
    """A fixed permutation of range(n) that sends neighbours far apart: i -> i * s mod n with a
    stride s near n / golden ratio, coprime to n."""
    s = max(1, int(n * 0.6180339887498949))
    while math.gcd(s, n) != 1:
        s += 1
    return (np.arange(n, dtype=np.int64) * s) % n


def _prepare(lo, hi, centroids):
    """Validate the input and return (X, order): X (9, N) f32 holds rows lo xyz, -hi xyz,
    centroid xyz of the primitives order[0], order[1], ... (a scattered order, see
    _scattered_order).

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
    lo32, hi32 = round_out_f32(lo, hi)
    with np.errstate(over="ignore"):
        c32 = c.astype(np.float32)
    if not np.isfinite(c32).all() or not np.isfinite(lo32).all() or not np.isfinite(hi32).all():
        raise ValueError("input values overflow float32")
    order = _scattered_order(n)
    x = np.empty((9, n), np.float32)
    x[0:3] = np.take(lo32, order, axis=0).T
    np.negative(np.take(hi32, order, axis=0).T, out=x[3:6])
    x[6:9] = np.take(c32, order, axis=0).T
    return x, order


# ------------------------------------------------------------------------------------------------
# per-level helpers
#
# The primitive data never moves: every level works on the same (9, n) array of active
# primitives, and each primitive carries the index of its node at the current level (`node_of`).
# Primitives that already reached a leaf point at a dummy node `n` (one past the real nodes),
# whose per-node values are chosen so that it bins into a dummy slot and never affects a result.
# Once most primitives are finished the active set is compacted.


class _Work:
    """Per-primitive buffers reused by every level.

    Fresh multi-megabyte temporaries on every level cost more in page faults than in arithmetic,
    so the large per-primitive arrays live here and numpy writes into them with ``out=``.
    """

    def __init__(self, n: int, threads: int):
        self.ar = np.arange(n, dtype=np.int64)
        self.node_of = (np.empty(n, np.int64), np.empty(n, np.int64))
        self.leaf_of = np.empty(n, np.int32)
        self.f = (np.empty(n, np.float32), np.empty(n, np.float32))
        self.i = (np.empty(n, np.int64), np.empty(n, np.int64))  # index scratch
        self.j = (np.empty(n, np.int32), np.empty(n, np.int32))  # value scratch
        self.bins = np.empty(3 * n, np.int16)
        self.side = np.empty(n, np.bool_)
        self._box = np.empty(0, np.float32)
        self.pool = None
        self.threads = 1
        if threads > 1 and n >= _THREADS_MIN_PRIMS:
            from concurrent.futures import ThreadPoolExecutor
            self.threads = threads
            self.pool = ThreadPoolExecutor(max_workers=threads - 1)

    def box(self, g: int) -> np.ndarray:
        """(6, g) f32 bin boxes, filled with +inf."""
        if self._box.shape[0] < 6 * g:
            self._box = np.empty(max(6 * g, self._box.shape[0] * 3 // 2), np.float32)
        b = self._box[:6 * g].reshape(6, g)
        b.fill(np.inf)
        return b

    def run(self, tasks, also=None):
        """Run callables and return the result of ``also()``. With a pool, the calling thread
        takes its share of the tasks instead of waiting, so a busy machine loses little."""
        if self.pool is None:
            for t in tasks:
                t()
            return also() if also is not None else None
        k = self.threads
        futures = [self.pool.submit(_run_all, tasks[i::k]) for i in range(1, k)]
        result = also() if also is not None else None
        _run_all(tasks[0::k])
        for f in futures:
            f.result()
        return result

    def close(self):
        if self.pool is not None:
            self.pool.shutdown()
            self.pool = None


def _run_all(tasks):
    for t in tasks:
        t()


def _pad(a: np.ndarray, value) -> np.ndarray:
    """Append the dummy node's value (along the last axis)."""
    pad = np.full(a.shape[:-1] + (1,), value, a.dtype)
    return np.concatenate((a, pad), axis=-1)


def _node_min_max(w: _Work, vals: np.ndarray, node_of: np.ndarray, n: int):
    """Per-node minimum and maximum (k, n) of the rows of vals (k, n_act) by node_of.

    With few nodes every update would hit the same few addresses and ufunc.at would serialise
    on them, so each node gets 16 lanes, reduced afterwards.
    """
    k = vals.shape[0]
    n_act = vals.shape[1]
    lanes = 16 if n < 1024 else 1
    if lanes > 1:
        idx = np.bitwise_and(w.ar[:n_act], lanes - 1, out=w.i[0][:n_act])
        idx += node_of * lanes
    else:
        idx = node_of
    lo = np.full((k, (n + 1) * lanes), np.inf, np.float32)
    hi = np.full((k, (n + 1) * lanes), -np.inf, np.float32)

    def rows(rr):
        def task():
            for r in rr:
                np.minimum.at(lo[r], idx, vals[r])
                np.maximum.at(hi[r], idx, vals[r])
        return task
    w.run([rows(range(0, k, 2)), rows(range(1, k, 2))])
    lo = lo.reshape(k, n + 1, lanes).min(axis=2)[:, :n]
    hi = hi.reshape(k, n + 1, lanes).max(axis=2)[:, :n]
    return lo, hi


def _half_area(b: np.ndarray, k: float, out: np.ndarray | None = None) -> np.ndarray:
    """Half surface area of boxes stored as (6, ...) = lo xyz, -hi xyz (empty boxes -> inf),
    with the extents scaled by k (a power of two that brings the scene to unit size, so that
    areas times counts neither overflow nor underflow f32).

    With s = lo - hi = -extent the signs cancel: ex*ey + ey*ez + ez*ex = sx*(sy + sz) + sy*sz.
    """
    k = np.float32(k)
    sx = b[3] + b[0]
    sx *= k
    sy = b[4] + b[1]
    sy *= k
    sz = b[5] + b[2]
    sz *= k
    area = np.add(sy, sz, out=out)
    area *= sx
    sy *= sz
    area += sy
    return area


def _bins_for_count(cnt: np.ndarray, bins: int) -> np.ndarray:
    """Bin count per node: half the largest power of two <= count, at least 2, at most ``bins``."""
    p = np.left_shift(1, np.floor(np.log2(np.maximum(cnt, 4))).astype(np.int64) - 1)
    return np.minimum(p, bins)


def _select_axis(w: _Work, rows: np.ndarray, axis_e: np.ndarray, out: np.ndarray) -> np.ndarray:
    """rows (3, n_act) -> rows[axis_e[i], i]."""
    n_act = rows.shape[1]
    idx = np.multiply(axis_e, n_act, out=w.i[1][:n_act])
    idx += w.ar[:n_act]
    return np.take(rows.reshape(-1), idx, out=out)


def _rank_split(w: _Work, side, node_of, cnt, nodes):
    """Split the given nodes by count: in each, the first floor(count / 2) primitives in the
    builder's working order go left. Used when no plane separates the centroids."""
    n = cnt.shape[0]
    flag = np.zeros(n + 1, bool)
    flag[nodes] = True
    sub = np.flatnonzero(flag[node_of])
    if sub.shape[0] == 0:
        return
    nd = node_of[sub]
    order = np.argsort(nd, kind="stable")
    sub = sub[order]
    nd = nd[order]
    start = np.zeros(n + 1, np.int64)
    np.cumsum(np.bincount(nd, minlength=n + 1)[:-1], out=start[1:])
    rank = np.arange(sub.shape[0]) - start[nd]
    side[sub] = rank >= (cnt // 2)[nd]


def _bin_by_cells(w: _Work, x, node_of, node_bins, n, b):
    """Bin boxes and counts for a level of n nodes that all use b bins, through a b x b x b
    grid of cells per node: 6 scatter passes over the primitives instead of 18, then cheap
    reductions over the cells. Worth it while there are fewer cells than primitives.

    Returns (box, counts) in the layout of _sah_level (bin q of axis a of node i at
    (3 q + a) n + i) plus one dummy slot at the end.
    """
    n_act = x.shape[1]
    nc = (n + 1) * b ** 3
    cell = np.multiply(node_of, b ** 3, out=w.i[1][:n_act])
    # (in int64: the bins are int16, and bin * b * b passes 32767 from 46 bins up)
    for a, stride in ((0, b * b), (1, b), (2, 1)):
        cell += node_bins[a].astype(np.int64) * stride
    cbox = np.full((6, nc), np.inf, np.float32)

    def rows(rr):
        def task():
            for r in rr:
                np.minimum.at(cbox[r], cell, x[r])
        return task
    ccount = w.run([rows((0, 1, 2)), rows((3, 4, 5))],
                   also=lambda: np.bincount(cell, minlength=nc))
    g = 3 * b * n
    cb = cbox[:, :n * b ** 3].reshape(6, n, b, b, b)
    cc = ccount[:n * b ** 3].reshape(n, b, b, b)
    box = np.full((6, g + 1), np.inf, np.float32)
    counts = np.zeros(g + 1, np.int64)
    bv = box[:, :g].reshape(6, b, 3, n)
    cv = counts[:g].reshape(b, 3, n)
    for a, other in enumerate(((3, 4), (2, 4), (2, 3))):
        bv[:, :, a, :] = cb.min(axis=other).transpose(0, 2, 1)
        cv[:, a, :] = cc.sum(axis=(other[0] - 1, other[1] - 1)).T
    return box, counts


def _sah_level(w: _Work, x, node_of, cnt, nbins, max_leaf_hard, c_trav, c_isect, k_area):
    """Binned SAH for all nodes of a level.

    Nodes must be sorted by descending ``nbins`` (each bin count forms one block).
    Returns (leaf mask, side per primitive, split axis per node, nodes to split by count).
    """
    n = cnt.shape[0]
    n_act = x.shape[1]
    cmin, cmax = _node_min_max(w, x[6:9], node_of, n)
    ext = cmax - cmin
    # (c - cmin) * scale < nbins always: each f32 rounding gains at most 2**-24 relative
    nb_f = nbins.astype(np.float32) * np.float32(1.0 - 1e-6)
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        scale = (nb_f / ext).astype(np.float32)
    # zero (or so tiny that the scale overflows) extent: everything in bin 0, no split
    scale[~np.isfinite(scale) | (ext <= 0)] = 0.0

    # Bin blocks: nodes with the same bin count b are contiguous; their bins are laid out
    # (b, 3, n_block) so that the sweeps over bins run along long vector rows. Slot g_total is
    # the dummy node's.
    change = np.flatnonzero(nbins[1:] != nbins[:-1]) + 1
    blk_start = np.concatenate(([0], change)).astype(np.int64)
    blk_end = np.concatenate((change, [n])).astype(np.int64)
    blk_b = nbins[blk_start].astype(np.int64)
    blk_n = blk_end - blk_start
    blk_off = np.zeros(blk_start.shape[0] + 1, np.int64)
    np.cumsum(blk_b * 3 * blk_n, out=blk_off[1:])
    g_total = int(blk_off[-1])
    blk_of_node = np.repeat(np.arange(blk_start.shape[0]), blk_n)
    # bin q on axis a of node i sits at kbase + kaxis * (a + 3 q)
    kbase = blk_off[blk_of_node] + (np.arange(n) - blk_start[blk_of_node])
    kaxis = blk_n[blk_of_node]

    cmin_p = _pad(cmin, 0.0)
    scale_p = _pad(scale, 0.0)
    node_bins = w.bins[:3 * n_act].reshape(3, n_act)
    f = w.f[0][:n_act]
    g = w.f[1][:n_act]
    for a in range(3):
        np.take(cmin_p[a], node_of, out=f)
        np.subtract(x[6 + a], f, out=f)
        f *= np.take(scale_p[a], node_of, out=g)
        np.copyto(node_bins[a], f, casting="unsafe")  # truncation = floor, as f >= 0

    b0 = int(blk_b[0])
    if blk_start.shape[0] == 1 and n * b0 ** 3 <= n_act * _CELLS_MAX_RATIO:
        box, counts = _bin_by_cells(w, x, node_of, node_bins, n, b0)
    else:
        kbase_e = np.take(_pad(kbase, g_total).astype(np.int32), node_of, out=w.j[0][:n_act])
        kaxis_e = np.take(_pad(kaxis, 0).astype(np.int32), node_of, out=w.j[1][:n_act])
        key = w.i[0][:n_act]
        box = w.box(g_total + 1)
        counts = np.zeros(g_total + 1, np.int64)

        def rows(rr):
            def task():
                for r in rr:
                    np.minimum.at(box[r], key, x[r])
            return task
        for a in range(3):
            np.multiply(node_bins[a], 3, out=key)
            key += a
            key *= kaxis_e
            key += kbase_e
            counts += w.run([rows((0, 1, 2)), rows((3, 4, 5))],
                            also=lambda: np.bincount(key, minlength=g_total + 1))

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
                _half_area(acc, k_area, out=a_r[q])
                np.minimum(acc, t[:, q], out=acc)
            node_area[blk_start[i]:blk_end[i]] = _half_area(acc[:, :nn], k_area)
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
                _half_area(acc, k_area, out=cost)
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

    # side per primitive: right iff its bin on the split axis is above the split bin
    axis_e = np.take(_pad(np.where(valid, best_axis, 0), 0), node_of, out=w.i[0][:n_act])
    sel = _select_axis(w, node_bins, axis_e, w.j[1].view(np.int16)[:n_act])
    bin_e = np.take(_pad(best_bin, 0).astype(np.int16), node_of,
                    out=w.i[0].view(np.int16)[:n_act])
    side = np.greater(sel, bin_e, out=w.side[:n_act])
    by_count = np.flatnonzero(~valid & ~leaf)
    axis = np.where(valid, best_axis, np.argmax(ext, axis=0))
    return leaf, side, axis, by_count


def _midpoint_level(w: _Work, x, node_of, cnt):
    n = cnt.shape[0]
    n_act = x.shape[1]
    cmin, cmax = _node_min_max(w, x[6:9], node_of, n)
    ext = cmax - cmin
    axis = np.argmax(ext, axis=0)
    ar = np.arange(n)
    axis_e = np.take(_pad(axis, 0), node_of, out=w.i[0][:n_act])
    c = _select_axis(w, x[6:9], axis_e, w.f[0][:n_act])
    c -= np.take(_pad(cmin[axis, ar], 0.0), node_of, out=w.f[1][:n_act])
    half = ext[axis, ar] * np.float32(0.5)
    # right iff (c - cmin) > extent / 2: the extreme centroids always land on different sides
    # when the extent is nonzero, whatever the rounding
    side = np.greater(c, np.take(_pad(half, 0.0), node_of, out=w.f[1][:n_act]),
                      out=w.side[:n_act])
    return side, axis, np.flatnonzero(ext[axis, ar] <= 0)


def _equal_count_level(w: _Work, x, node_of, cnt):
    """Median split along the largest axis of the centroid bounds."""
    n = cnt.shape[0]
    n_act = x.shape[1]
    cmin, cmax = _node_min_max(w, x[6:9], node_of, n)
    ext = cmax - cmin
    axis = np.argmax(ext, axis=0)
    ar = np.arange(n)
    axis_e = np.take(_pad(axis, 0), node_of, out=w.i[0][:n_act])
    c = _select_axis(w, x[6:9], axis_e, w.f[0][:n_act]).astype(np.float64)
    e = ext[axis, ar].astype(np.float64)
    inv = np.where(e > 0, 0.5 / np.where(e > 0, e, 1.0), 0.0)
    # The keys of node i lie in [i, i + 0.5] (finished primitives: n), so ordering the keys
    # groups the nodes in index order and sorts each by centroid.
    c -= _pad(cmin[axis, ar], 0.0)[node_of]
    c *= _pad(inv, 0.0)[node_of]
    c += node_of
    start = np.zeros(n + 1, np.int64)
    np.cumsum(cnt, out=start[1:])
    mid = start[:-1] + cnt // 2
    if n <= _ARGPARTITION_MAX_NODES:
        # partitioning at the node boundaries and the medians is enough
        kth = np.unique(np.concatenate((start[1:], mid)))
        order = np.argpartition(c, kth[kth < n_act])
    else:
        order = np.argsort(c)
    pos = np.empty(n_act, np.int64)
    pos[order] = w.ar[:n_act]
    side = np.greater_equal(pos, _pad(mid, n_act)[node_of], out=w.side[:n_act])
    return side, axis


# ------------------------------------------------------------------------------------------------
# the builder


def _default_threads() -> int:
    """Two threads when the machine has a core to spare (by its load average), else one.

    On a busy machine a second thread only waits for a core and slows the build down."""
    cpus = os.cpu_count() or 1
    try:
        load = os.getloadavg()[0]
    except (AttributeError, OSError):
        return 1
    return 2 if cpus >= 2 and load <= cpus - 1 else 1


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
    threads: threads for the scatter reductions of large builds (numpy releases the GIL there);
        default 2 when a core looks idle, else 1. The result does not depend on it.
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
        threads = _default_threads()

    x, order = _prepare(lo, hi, centroids)
    w = _Work(x.shape[1], threads)
    try:
        return _build(w, x, order, strategy, max_leaf_size, bins, max_leaf_hard, c_trav, c_isect)
    finally:
        w.close()


def _build(w: _Work, x, order, strategy, max_leaf_size, bins, max_leaf_hard, c_trav, c_isect):
    """x (9, N): the primitives order[0], order[1], ... (see _prepare)."""
    n_prims = x.shape[1]
    cap = 2 * n_prims - 1

    # node table in breadth-first creation order (gid)
    t_left = np.full(cap, -1, np.int32)  # gid of the left child (right = left + 1), -1: leaf
    t_count = np.zeros(cap, np.int32)  # leaf primitive count
    t_axis = np.full(cap, -1, np.int8)
    level_ranges = [(0, 1)]  # gid range of each depth
    next_gid = 1
    leaf_of_prim = np.zeros(n_prims, np.int64)  # gid of each primitive's leaf

    if n_prims <= max_leaf_size:
        t_count[0] = n_prims
        return _flatten(x, leaf_of_prim, t_left[:1], t_count[:1], t_axis[:1], level_ranges,
                        leaf_of_prim)
    cnt = np.array([n_prims], np.int64)
    gids = np.zeros(1, np.int64)
    x_all = x
    pid = order  # primitive index of each active primitive
    # SAH areas are computed for the scene scaled to unit size by a power of two
    extent = float(np.max(-x[3:6].min(axis=1).astype(np.float64) - x[0:3].min(axis=1)))
    k_area = 2.0 ** -math.ceil(math.log2(extent)) if extent > 0 else 1.0
    buf = 0
    node_of = w.node_of[buf][:n_prims]
    node_of.fill(0)
    leaf_of = w.leaf_of[:n_prims]
    leaf_of.fill(-1)

    while cnt.shape[0] > 0:
        n = cnt.shape[0]
        n_act = x.shape[1]
        if strategy == "sah":
            nbins = _bins_for_count(cnt, bins)
            leaf, side, axis, by_count = _sah_level(w, x, node_of, cnt, nbins, max_leaf_hard,
                                                    c_trav, c_isect, k_area)
        elif strategy == "midpoint":
            side, axis, by_count = _midpoint_level(w, x, node_of, cnt)
            leaf = np.zeros(n, bool)
        else:
            side, axis = _equal_count_level(w, x, node_of, cnt)
            by_count = np.zeros(0, np.int64)
            leaf = np.zeros(n, bool)
        if by_count.shape[0]:
            _rank_split(w, side, node_of, cnt, by_count)

        # slot = 2 * node + side; child counts per slot
        slot = np.multiply(node_of, 2, out=w.i[0][:n_act])
        slot += side
        n_slot = np.bincount(slot, minlength=2 * n + 2)
        n_l = n_slot[0:2 * n:2]
        n_r = n_slot[1:2 * n:2]
        split = ~leaf
        if not ((n_l > 0) & (n_r > 0) | leaf).all():
            raise AssertionError("BVH builder produced an empty child")

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
        n_next = act.shape[0]
        lf_nodes = np.flatnonzero(leaf)
        t_count[gids[lf_nodes]] = cnt[lf_nodes]
        t_count[child_gid[child_leaf]] = child_cnt[child_leaf]

        # slot -> next-level node (n_next: finished) and slot -> leaf gid (-1: not a leaf)
        child_new = np.full(2 * ns, n_next, np.int64)
        child_new[act] = np.arange(n_next)
        child_leafgid = np.where(child_leaf, child_gid, -1)
        slot_new = np.full(2 * n + 2, n_next, np.int64)
        slot_leaf = np.full(2 * n + 2, -1, np.int64)
        slot_new[2 * sp] = child_new[0::2]
        slot_new[2 * sp + 1] = child_new[1::2]
        slot_leaf[2 * sp] = child_leafgid[0::2]
        slot_leaf[2 * sp + 1] = child_leafgid[1::2]
        slot_leaf[2 * lf_nodes] = gids[lf_nodes]
        slot_leaf[2 * lf_nodes + 1] = gids[lf_nodes]

        buf = 1 - buf
        node_of = np.take(slot_new, slot, out=w.node_of[buf][:n_act])
        np.maximum(leaf_of, np.take(slot_leaf.astype(np.int32), slot, out=w.j[0][:n_act]),
                   out=leaf_of)

        gids = child_gid[act]
        cnt = child_cnt[act]
        n_keep = int(cnt.sum())
        if n_keep < _COMPACT_FRACTION * n_act:
            # compact the active set
            keep = np.flatnonzero(node_of < n_next)
            done = np.flatnonzero(node_of == n_next)
            leaf_of_prim[pid[done]] = leaf_of[done]
            pid = pid[keep]
            x = np.take(x, keep, axis=1)
            buf = 1 - buf
            node_of = np.take(node_of, keep, out=w.node_of[buf][:n_keep])
            leaf_of = w.leaf_of[:n_keep]
            leaf_of.fill(-1)

    leaf_of_prim[pid] = leaf_of
    return _flatten(x_all, leaf_of_prim[order], t_left[:next_gid], t_count[:next_gid],
                    t_axis[:next_gid], level_ranges, leaf_of_prim)


def _flatten(x_box, leaf_of_box, t_left, t_count, t_axis, level_ranges,
             leaf_of_prim) -> FlatBVH:
    """Breadth-first node table -> depth-first FlatBVH with boxes and skip links.

    x_box (rows 0..5: lo, -hi) and leaf_of_box give the primitive boxes and their leaves in any
    order (a scattered one is faster); leaf_of_prim gives the leaf of each primitive index.
    """
    m = t_left.shape[0]
    interior = t_left >= 0
    ranges = [(g0, g0 + np.flatnonzero(interior[g0:g1])) for g0, g1 in level_ranges]

    # subtree sizes bottom-up, depth-first indices top-down, one vector step per level
    size = np.ones(m, np.int64)
    for g0, it in reversed(ranges):
        if it.shape[0]:
            left = t_left[it]
            size[it] = 1 + size[left] + size[left + 1]
    dfs = np.zeros(m, np.int64)
    for g0, it in ranges:
        if it.shape[0]:
            left = t_left[it]
            dfs[left] = dfs[it] + 1
            dfs[left + 1] = dfs[it] + 1 + size[left]

    # primitives sorted by the depth-first index of their leaf
    leaves = np.flatnonzero(~interior)
    leaves = leaves[np.argsort(dfs[leaves])]
    lcnt = t_count[leaves]
    lstart = np.zeros(leaves.shape[0], np.int64)
    np.cumsum(lcnt[:-1], out=lstart[1:])
    prim_order = np.argsort(dfs[leaf_of_prim])

    # boxes: leaves from their primitives, interior nodes as the union of their children
    box = np.full((6, m), np.inf, np.float32)
    for r in range(6):
        np.minimum.at(box[r], leaf_of_box, x_box[r])
    for g0, it in reversed(ranges):
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
