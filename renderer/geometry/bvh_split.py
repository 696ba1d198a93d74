"""The splits of one level of the BVH build: every node of a depth at once, with whole-array numpy
operations, by binned SAH, midpoint or median (equal count), and the per-primitive buffers and
threads the levels share (renderer/geometry/bvh_build.py describes the strategies and why the
work is laid out so).

The primitive data never moves: every level works on the same (9, n) array of active
primitives, and each primitive carries the index of its node at the current level (`node_of`).
Primitives that already reached a leaf point at a dummy node `n` (one past the real nodes),
whose per-node values are chosen so that it bins into a dummy slot and never affects a result.
"""
from __future__ import annotations

import numpy as np

# Equal-count splits use np.argpartition while a level has at most this many nodes, a full
# sort beyond.
_ARGPARTITION_MAX_NODES = 64
# Builds over fewer primitives stay on the calling thread.
_THREADS_MIN_PRIMS = 100_000
# SAH levels of one bin count b bin through b**3 cells per node while cells <= ratio * prims.
_CELLS_MAX_RATIO = 1.0


class LevelWork:
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


def _node_min_max(w: LevelWork, vals: np.ndarray, node_of: np.ndarray, n: int):
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


def bins_for_count(cnt: np.ndarray, bins: int) -> np.ndarray:
    """Bin count per node: half the largest power of two <= count, at least 2, at most ``bins``."""
    p = np.left_shift(1, np.floor(np.log2(np.maximum(cnt, 4))).astype(np.int64) - 1)
    return np.minimum(p, bins)


def _select_axis(w: LevelWork, rows: np.ndarray, axis_e: np.ndarray, out: np.ndarray) -> np.ndarray:
    """rows (3, n_act) -> rows[axis_e[i], i]."""
    n_act = rows.shape[1]
    idx = np.multiply(axis_e, n_act, out=w.i[1][:n_act])
    idx += w.ar[:n_act]
    return np.take(rows.reshape(-1), idx, out=out)


def rank_split(w: LevelWork, side, node_of, cnt, nodes):
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


def _bin_by_cells(w: LevelWork, x, node_of, node_bins, n, b):
    """Bin boxes and counts for a level of n nodes that all use b bins, through a b x b x b
    grid of cells per node: 6 scatter passes over the primitives instead of 18, then cheap
    reductions over the cells. Worth it while there are fewer cells than primitives.

    Returns (box, counts) in the layout of sah_level (bin q of axis a of node i at
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


def sah_level(w: LevelWork, x, node_of, cnt, nbins, max_leaf_hard, c_trav, c_isect, k_area):
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


def midpoint_level(w: LevelWork, x, node_of, cnt):
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


def equal_count_level(w: LevelWork, x, node_of, cnt):
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

