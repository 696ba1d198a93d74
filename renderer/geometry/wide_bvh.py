"""A binary BVH collapsed into 4-wide (or 8-wide) nodes whose child boxes sit side by side (numpy
only).

One wide node holds up to four (eight) children. Their boxes are stored structure-of-arrays: six rows
(lo x, lo y, lo z, hi x, hi y, hi z) of four floats each, so the device tests the four children
with one set of 4-lane operations (renderer/geometry/wide_traversal.py). Per child slot:

  child_count 0              an inner child: child_a is its wide node
  child_count > 0            a leaf: child_a is its first slot in `prim_order`, count primitives
  child_count INSTANCE_NODE  an instance (two-level BVH): child_a is the instance id
  child_count EMPTY_CHILD    no child: its box is lo = +F32_MAX, hi = -F32_MAX, whose far planes
                             lie behind every ray origin, so the slab test can never enter it

The collapse (as Embree's and Wald et al. 2008's): a wide node starts from a binary node's two
children and repeatedly opens the inner child of the largest surface area (replacing it by its
two children) while a slot is free. The inner children left become the wide nodes of the next
level. Leaves and `prim_order` are the binary tree's own, so every primitive is referenced once,
and every child box is the binary node's box (conservative in f32 already). Each level of the
tree is collapsed at once with whole-array numpy operations.

Several roots can be collapsed together (the two-level BVH: the world's root and each instanced
mesh's root); root i becomes wide node i. A root that is itself a leaf becomes a wide node with
that leaf as its only child, so a traversal always starts at a wide node.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from renderer.geometry.bvh_tree import FlatBVH
from renderer.geometry.instance_bvh import INSTANCE_NODE

WIDTH = 4  # the default width; collapse(..., width=8) makes 8-wide nodes
WIDTHS = (4, 8)
EMPTY_CHILD = -2  # child_count of an unused slot
F32_MAX = float(np.finfo(np.float32).max)


@dataclass
class WideBVH:
    """M wide nodes of W (4 or 8) children each (module docs).

    bounds:      (M, 6, W) f32, rows lo x, lo y, lo z, hi x, hi y, hi z of the children.
    child_a:     (M, W) i32, child_count: (M, W) i32 (module docs).
    prim_order:  (N,) i32, the binary tree's primitive order (leaves cover ranges of it).
    roots:       (R,) i32, the wide node of each collapsed root (root i is node i).
    depth:       (R,) i32, levels of wide nodes below each root (1: the root alone).
    """

    bounds: np.ndarray
    child_a: np.ndarray
    child_count: np.ndarray
    prim_order: np.ndarray
    roots: np.ndarray
    depth: np.ndarray

    @property
    def width(self) -> int:
        return int(self.bounds.shape[2])

    @property
    def num_nodes(self) -> int:
        return int(self.child_a.shape[0])

    @property
    def nbytes(self) -> int:
        return self.bounds.nbytes + self.child_a.nbytes + self.child_count.nbytes + self.prim_order.nbytes

    def packed_refs(self) -> tuple[np.ndarray, int]:
        """(refs (M, W) i32, bits): each child in one i32, as the device stacks it. An inner
        child is its node (>= 0); a leaf is ~(first << bits | count), an instance
        ~(instance << bits), so count 0 there (the empty slot's ~0 reads so too, but no ray
        enters an empty slot). bits holds the largest leaf count."""
        leaf = self.child_count > 0
        bits = max(1, int(self.child_count.max(initial=0)).bit_length())
        inner, empty = self.child_count == 0, self.child_count == EMPTY_CHILD
        first = np.where(inner | empty, 0, self.child_a).astype(np.int64)
        if first.max(initial=0) >= 2 ** (31 - bits):
            raise ValueError(f"too many primitives for the wide BVH's packed leaves (at most {2 ** (31 - bits):,})")
        packed = ~((first << bits) | np.where(leaf, self.child_count, 0))
        refs = np.where(inner, self.child_a, packed)
        return refs.astype(np.int32), bits


def _surface_area(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    e = (hi - lo).astype(np.float64)
    return e[:, 0] * e[:, 1] + e[:, 1] * e[:, 2] + e[:, 2] * e[:, 0]


def collapse(bvh: FlatBVH, roots=(0,), width: int = WIDTH) -> WideBVH:
    """The `width`-wide BVH (4 or 8) of the binary `bvh`'s subtrees below `roots` (node indices;
    the first is usually 0, the world's root)."""
    if width not in WIDTHS:
        raise ValueError(f"wide BVH width {width} (choose from {', '.join(map(str, WIDTHS))})")
    roots = np.asarray(roots, np.int64)
    if roots.ndim != 1 or len(roots) == 0:
        raise ValueError("collapse needs at least one root")
    if bvh.num_nodes == 0 or roots.min() < 0 or roots.max() >= bvh.num_nodes:
        raise ValueError(f"roots must be node indices of the BVH (it has {bvh.num_nodes} nodes)")
    inner = bvh.node_count == 0
    area = _surface_area(bvh.node_lo, bvh.node_hi)
    right = bvh.node_a.astype(np.int64)

    # level 0: each root's two children, or the root itself where it is a leaf
    slots = np.full((len(roots), width), -1, np.int64)
    slots[:, 0] = np.where(inner[roots], roots + 1, roots)
    slots[:, 1] = np.where(inner[roots], right[roots], -1)
    owner = np.arange(len(roots))  # the root each wide node descends from
    levels, owners = [], []
    while len(slots):
        _open_largest(slots, inner, area, right)
        levels.append(slots)
        owners.append(owner)
        is_inner = (slots >= 0) & inner[np.maximum(slots, 0)]
        row, _ = np.nonzero(is_inner)
        nxt = slots[is_inner]
        slots = np.full((len(nxt), width), -1, np.int64)
        slots[:, 0] = nxt + 1
        slots[:, 1] = right[nxt]
        owner = owner[row]
    return _encode(bvh, levels, owners, len(roots), inner)


def _open_largest(slots: np.ndarray, inner: np.ndarray, area: np.ndarray, right: np.ndarray) -> None:
    """Fill the free slots of every row (in place): open the largest inner child while one is
    there. Rows hold binary node indices, -1 for a free slot, filled from the left."""
    rows = np.arange(len(slots))
    width = slots.shape[1]
    for _ in range(width - 2):
        filled = (slots >= 0).sum(axis=1)
        node = np.maximum(slots, 0)
        score = np.where((slots >= 0) & inner[node], area[node], -1.0)
        pick = np.argmax(score, axis=1)
        opened = (score[rows, pick] >= 0.0) & (filled < width)
        r = rows[opened]
        c = slots[r, pick[opened]]
        slots[r, pick[opened]] = c + 1
        slots[r, filled[opened]] = right[c]


def _encode(bvh: FlatBVH, levels, owners, n_roots: int, inner: np.ndarray) -> WideBVH:
    """Wide node rows in level order: children as (a, count), boxes structure-of-arrays."""
    slots = np.concatenate(levels)
    m = len(slots)
    used = slots >= 0
    node = np.maximum(slots, 0)
    is_inner = used & inner[node]
    # the wide index of each inner child: the rows of the next levels, in the order they came
    child_a = np.where(used, bvh.node_a[node], 0).astype(np.int64)
    child_a[is_inner] = n_roots + np.arange(int(is_inner.sum()))
    child_count = np.where(used, bvh.node_count[node], EMPTY_CHILD).astype(np.int32)
    child_count[is_inner] = 0
    lo = np.where(used[..., None], bvh.node_lo[node], np.float32(F32_MAX))
    hi = np.where(used[..., None], bvh.node_hi[node], np.float32(-F32_MAX))
    bounds = np.concatenate([lo.transpose(0, 2, 1), hi.transpose(0, 2, 1)], axis=1).astype(np.float32)
    depth = np.zeros(n_roots, np.int32)
    for level, owner in enumerate(owners):
        depth[np.unique(owner)] = level + 1
    if child_a.max(initial=0) >= 2**31:
        raise ValueError("the wide BVH has more nodes than an i32 index reaches")
    return WideBVH(bounds=np.ascontiguousarray(bounds), child_a=child_a.astype(np.int32), child_count=child_count,
                   prim_order=bvh.prim_order.astype(np.int32), roots=np.arange(n_roots, dtype=np.int32),
                   depth=depth)


def empty_wide_bvh(width: int = WIDTH) -> WideBVH:
    """One wide node without children: no ray enters anything (a mesh without primitives)."""
    bounds = np.concatenate([np.full((1, 3, width), F32_MAX, np.float32),
                             np.full((1, 3, width), -F32_MAX, np.float32)], axis=1)
    return WideBVH(bounds=bounds, child_a=np.zeros((1, width), np.int32),
                   child_count=np.full((1, width), EMPTY_CHILD, np.int32), prim_order=np.zeros(0, np.int32),
                   roots=np.zeros(1, np.int32), depth=np.ones(1, np.int32))
