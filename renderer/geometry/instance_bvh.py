"""The BVH of a mesh scene with instances: one node array for the world and every instanced mesh.

A mesh drawn many times keeps one copy of its triangles and one tree over them, built once in
the mesh's own frame; the world level holds one box per instance. All of it is one `FlatBVH`
(so one traversal loop walks it), laid out as:

  root          only when the scene has both world primitives and instances: an interior node
                whose left child is the world tree and whose right child the instance tree
  world tree    over the primitives placed in world space, exactly as a scene without instances
  instance tree over the instances' world boxes, one instance per leaf; such a leaf is an
                instance node: node_count INSTANCE_NODE, node_a the instance id
  mesh trees    one per instanced mesh (`mesh_root`), over its object-space triangles

Skip links that leave the world part or a mesh tree point at the end (`num_nodes`): a stackless
walk that gets there inside an instance resumes at the instance node's own skip link.
Scenes without instances get `build_bvh`'s tree over their primitives, as they always did.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from renderer.geometry.bvh_build import build_bvh
from renderer.geometry.bvh_tree import FlatBVH
from renderer.geometry.mesh_data import MeshData

INSTANCE_NODE = -1  # node_count of an instance node


@dataclass
class InstancedBVH:
    """nodes: the whole node array (module docs); mesh_root: (K,) the root node of each instanced
    mesh's tree; stack_depth: the most entries an ordered traversal's stack can hold (the world
    part's depth plus the deepest mesh tree's, plus the entry that marks the way back)."""

    nodes: FlatBVH
    mesh_root: np.ndarray
    stack_depth: int


def build_scene_bvh(data: MeshData, strategy: str = "sah", max_leaf_size: int = 4):
    """The BVH MeshGeometry takes for `data`: a FlatBVH without instances, else an InstancedBVH."""
    lo, hi = data.bounds()

    def tree(box_lo, box_hi, **options):
        options.setdefault("max_leaf_size", max_leaf_size)
        return build_bvh(box_lo, box_hi, 0.5 * (box_lo + box_hi), strategy=strategy, **options)

    if not data.has_instances:
        return tree(lo, hi)
    world = data.world_prims()
    # One instance per leaf: a leaf is where the ray changes frames.
    parts = [(tree(*data.instance_bounds(), max_leaf_size=1, max_leaf_hard=1), None)]
    if len(world):
        parts.insert(0, (tree(lo[world], hi[world]), world))
    meshes = [(tree(lo[first:first + count], hi[first:first + count]), np.arange(first, first + count))
              for first, count in data.instanced_meshes]
    return _concatenate(parts, meshes)


def _concatenate(world_parts, meshes) -> InstancedBVH:
    """world_parts: [(world tree, its primitive ids)], then (instance tree, None); meshes:
    [(mesh tree, its primitive ids)]. Returns the layout of the module docs."""
    joined = len(world_parts) == 2
    total = int(joined) + sum(t.num_nodes for t, _ in world_parts) + sum(t.num_nodes for t, _ in meshes)
    pieces = []
    base = int(joined)
    slots = 0
    for i, (tree, ids) in enumerate(world_parts):
        last = i == len(world_parts) - 1
        # The world tree's walk ends where the instance tree starts: only the last part ends the world.
        pieces.append(_shifted(tree, base, slots, ids, total if last else None))
        base += tree.num_nodes
        slots += tree.num_prims if ids is not None else 0
    world_depth = max(tree.depth() for tree, _ in world_parts) + int(joined)
    mesh_root = []
    mesh_depth = 0
    for tree, ids in meshes:
        mesh_root.append(base)
        mesh_depth = max(mesh_depth, tree.depth())
        pieces.append(_shifted(tree, base, slots, ids, total))
        base += tree.num_nodes
        slots += tree.num_prims
    if joined:
        (w, _), (t, _) = world_parts
        root = FlatBVH(node_lo=np.minimum(w.node_lo[:1], t.node_lo[:1]),
                       node_hi=np.maximum(w.node_hi[:1], t.node_hi[:1]),
                       node_a=np.array([1 + w.num_nodes], np.int32), node_count=np.zeros(1, np.int32),
                       node_skip=np.array([total], np.int32), node_axis=np.zeros(1, np.int8),
                       prim_order=np.zeros(0, np.int32))
        pieces.insert(0, root)
    nodes = FlatBVH(**{name: np.concatenate([getattr(p, name) for p in pieces])
                       for name in ("node_lo", "node_hi", "node_a", "node_count", "node_skip", "node_axis",
                                    "prim_order")})
    return InstancedBVH(nodes=nodes, mesh_root=np.array(mesh_root, np.int32),
                        stack_depth=world_depth + mesh_depth + 1)


def _shifted(tree: FlatBVH, base: int, slot_base: int, ids, end) -> FlatBVH:
    """`tree` placed at node `base` (its primitives at slot `slot_base`, renamed by `ids`), its
    walk's end redirected to `end` (None: kept). ids None: an instance tree, whose single-instance
    leaves become instance nodes."""
    interior = tree.node_count == 0
    skip = tree.node_skip.astype(np.int64) + base
    if end is not None:
        skip[skip == base + tree.num_nodes] = end
    if ids is None:
        a = np.where(interior, tree.node_a + base, tree.prim_order[np.where(interior, 0, tree.node_a)])
        count = np.where(interior, 0, INSTANCE_NODE)
        order = np.zeros(0, np.int32)
    else:
        a = np.where(interior, tree.node_a + base, tree.node_a + slot_base)
        count = tree.node_count
        order = ids[tree.prim_order]
    return FlatBVH(node_lo=tree.node_lo, node_hi=tree.node_hi, node_a=a.astype(np.int32),
                   node_count=count.astype(np.int32), node_skip=skip.astype(np.int32), node_axis=tree.node_axis,
                   prim_order=order.astype(np.int32))
