"""The tree a BVH build gives: FlatBVH, the flattening of the builder's breadth-first node table
into it, and the SAH cost of a tree.

Layout
------
Nodes are stored in depth-first order, so the left child of interior node ``i`` is ``i + 1``;
leaves list their primitives contiguously in ``prim_order``, also in depth-first order. A node
takes 37 bytes in the separate arrays: ``node_lo``, ``node_hi`` (3 x f32 each), ``node_a``,
``node_count``, ``node_skip`` (i32) and ``node_axis`` (i8); ``prim_order`` adds 4 bytes per
primitive. Node boxes are conservative in f32: f64 input is rounded outwards, f32 input is
used exactly.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# SAH cost constants. A node visit is one ray/box slab test; a primitive test (ray/triangle,
# ray/sphere, ...) costs about twice as much, counting the indirection through prim_order.
C_TRAV = 1.0
C_ISECT = 2.0


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


def flatten(x_box, leaf_of_box, t_left, t_count, t_axis, level_ranges, leaf_of_prim) -> FlatBVH:
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
