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
  ``ValueError`` (renderer/geometry/bvh_input.py checks the input).

The tree comes out as a FlatBVH (renderer/geometry/bvh_tree.py describes its layout); each
level's nodes are split by renderer/geometry/bvh_split.py.

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

import numpy as np

from renderer.geometry.bvh_input import prepare_boxes
from renderer.geometry.bvh_split import (LevelWork, bins_for_count, equal_count_level, midpoint_level, rank_split,
                                         sah_level)
from renderer.geometry.bvh_tree import C_ISECT, C_TRAV, FlatBVH, flatten

STRATEGIES = ("sah", "midpoint", "equal_count")

# The active primitives are compacted once fewer than this fraction remain.
_COMPACT_FRACTION = 0.6


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

    x, order = prepare_boxes(lo, hi, centroids)
    w = LevelWork(x.shape[1], threads)
    try:
        return _build(w, x, order, strategy, max_leaf_size, bins, max_leaf_hard, c_trav, c_isect)
    finally:
        w.close()


def _build(w: LevelWork, x, order, strategy, max_leaf_size, bins, max_leaf_hard, c_trav, c_isect):
    """x (9, N): the primitives order[0], order[1], ... (see prepare_boxes)."""
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
        return flatten(x, leaf_of_prim, t_left[:1], t_count[:1], t_axis[:1], level_ranges,
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
            nbins = bins_for_count(cnt, bins)
            leaf, side, axis, by_count = sah_level(w, x, node_of, cnt, nbins, max_leaf_hard,
                                                    c_trav, c_isect, k_area)
        elif strategy == "midpoint":
            side, axis, by_count = midpoint_level(w, x, node_of, cnt)
            leaf = np.zeros(n, bool)
        else:
            side, axis = equal_count_level(w, x, node_of, cnt)
            by_count = np.zeros(0, np.int64)
            leaf = np.zeros(n, bool)
        if by_count.shape[0]:
            rank_split(w, side, node_of, cnt, by_count)

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
            act = act[np.argsort(-bins_for_count(child_cnt[act], bins), kind="stable")]
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
    return flatten(x_all, leaf_of_prim[order], t_left[:next_gid], t_count[:next_gid],
                    t_axis[:next_gid], level_ranges, leaf_of_prim)
