"""Turns a scene's SDF tree into Taichi funcs: shapes compiled in, nodes kept as data.

Every node is a row of the node table (transform, parameters, material, the rows of its
children, its shape). Top-level primitives are grouped by kind and evaluated by a runtime loop
over a field range per kind, so a scene with 50 spheres compiles one sphere evaluation.

Operators work the same way. A node's *shape* is what its code depends on: its kind, whether its
transform is the identity, whether a repetition is finite, and the set of its children's shapes.
An operator evaluates its children in a runtime loop over their rows (contiguous, in file order)
and evaluates each child with the func of the child's shape, picked at run time among the few
shapes that occur under that operator. So code grows with the number of distinct shapes, not
of nodes: a union of 10,000 spheres compiles one sphere, as 10,000 top-level spheres do, and
top-level operator trees are looped over in the same way. Parameters and transforms are read
from the node table, so editing a value never recompiles. Children are combined in file order,
as written (smooth unions depend on it).
"""
import numpy as np
import taichi as ti

from renderer.geometry.interface import INF
from renderer.runtime.upload import upload_fields
from shaders_sdf.primitives import PRIMITIVE_FUNCS, pack_parameters

vec3 = ti.math.vec3


@ti.func
def smooth_min(a, b, k):
    """Polynomial smooth minimum (quadratic); never above min(a, b) by more than k/4."""
    h = ti.max(k - ti.abs(a - b), 0.0) / k
    return ti.min(a, b) - h * h * k * 0.25


@ti.func
def _rotate(m, v):
    """m @ v for a 3x3 matrix, written out: Taichi's generic matrix product costs ~6 ms of
    kernel building (Python-side) at every place the SDF is inlined, the written-out one a tenth."""
    return ti.math.vec3(m[0, 0] * v[0] + m[0, 1] * v[1] + m[0, 2] * v[2],
                        m[1, 0] * v[0] + m[1, 1] * v[1] + m[1, 2] * v[2],
                        m[2, 0] * v[0] + m[2, 1] * v[1] + m[2, 2] * v[2])


def node_shape_key(node, child_shapes: tuple[int, ...]) -> tuple:
    """What a node's generated code depends on; `child_shapes`: the sorted distinct shape ids of
    its children."""
    finite = node.kind == "repeat" and dict(node.params).get("limit") is not None
    return node.kind, node.transform.is_identity, finite, child_shapes


class NodeTable:
    """The rows of an SDF scene (host side): order, children's row ranges and shape ids.

    Rows: top-level primitives sorted by kind (stable), then the top-level operator trees in
    file order, then, breadth first, the children of every operator row as one contiguous block.
    """

    def __init__(self, objects):
        tops = sorted((n for n in objects if n.is_primitive), key=lambda n: n.kind)
        self.compounds = [n for n in objects if not n.is_primitive]
        self.order = list(tops) + list(self.compounds)
        self.children = []  # (first row, end row) per row; (0, 0) for primitives
        row = 0
        while row < len(self.order):
            node = self.order[row]
            first = len(self.order)
            self.order.extend(node.children)
            self.children.append((first, len(self.order)) if node.children else (0, 0))
            row += 1
        self.primitive_kinds = []  # kind of each top-level batch, with its [start, end) rows
        self.primitive_ranges = []
        for i, node in enumerate(tops):
            if not self.primitive_kinds or self.primitive_kinds[-1] != node.kind:
                self.primitive_kinds.append(node.kind)
                self.primitive_ranges.append([i, i])
            self.primitive_ranges[-1][1] = i + 1
        self.compound_range = (len(tops), len(tops) + len(self.compounds))
        self.shape_keys: list[tuple] = []  # shape id -> key (node_shape_key)
        ids: dict[tuple, int] = {}
        self.shape = [0] * len(self.order)
        for row in reversed(range(len(self.order))):  # children sit below their parents
            first, end = self.children[row]
            key = node_shape_key(self.order[row], tuple(sorted({self.shape[c] for c in range(first, end)})))
            if key not in ids:
                ids[key] = len(self.shape_keys)
                self.shape_keys.append(key)
            self.shape[row] = ids[key]

    def node_objects(self, objects) -> np.ndarray:
        """Per row, the index in `objects` (the scene's top-level nodes) of the tree it belongs to."""
        top = {id(node): i for i, node in enumerate(objects)}
        out = np.full(len(self.order), -1, np.int32)
        for row, node in enumerate(self.order):  # parents come before their children
            if out[row] < 0:
                out[row] = top.get(id(node), -1)
            first, end = self.children[row]
            out[first:end] = out[row]
        return out

    def shapes_of(self, rows) -> tuple[int, ...]:
        return tuple(sorted({self.shape[r] for r in rows}))


class SdfProgram:
    """The node table (fields) of one SDF scene and the distance funcs generated over it."""

    def __init__(self, objects, material_index):
        """objects: the scene's top-level SdfNodes; material_index: name -> material id."""
        table = NodeTable(objects)
        order = table.order
        self.node_count = len(order)
        self.shape_count = len(table.shape_keys)
        self.inv_rotation = ti.Matrix.field(3, 3, ti.f32, shape=self.node_count)
        self.translation = ti.Vector.field(3, ti.f32, shape=self.node_count)
        self.scale = ti.field(ti.f32, shape=self.node_count)
        self.params = ti.Vector.field(4, ti.f32, shape=self.node_count)
        self.limit = ti.Vector.field(3, ti.f32, shape=self.node_count)
        self.material = ti.field(ti.i32, shape=self.node_count)
        self.children = ti.Vector.field(2, ti.i32, shape=self.node_count)  # rows [first, end)
        self.shape = ti.field(ti.i32, shape=self.node_count)
        self.batched_kinds = table.primitive_kinds
        self.ranges = ti.Vector.field(2, ti.i32, shape=max(1, len(table.primitive_ranges)))
        self.compound_range = ti.Vector.field(2, ti.i32, shape=1)
        self._upload(table, material_index)
        self._table = table
        self._funcs: dict[int, object] = {}
        self.distance = self._scene_func(with_material=False)  # p -> d
        self.distance_material = self._scene_func(with_material=True)  # p -> (d, material id, node id)
        self.order = order  # node table order: node id -> SdfNode

    def node_objects(self, objects) -> np.ndarray:
        return self._table.node_objects(objects)

    def _upload(self, table: NodeTable, material_index):
        order = table.order
        limits = [dict(n.params).get("limit") or (0, 0, 0) for n in order]
        # kept on the host too: emitter_info reads it without a download
        self.material_ids = np.array([material_index(n.material) if n.material is not None else -1 for n in order],
                                     np.int32)
        ranges = np.array(table.primitive_ranges or [[0, 0]], np.int32)
        upload_fields([(self.inv_rotation, np.stack([n.transform.rotation_matrix().T for n in order])),
                       (self.translation, np.array([n.transform.translate for n in order])),
                       (self.scale, np.array([n.transform.scale for n in order])),
                       (self.params, np.stack([pack_parameters(n) for n in order])),
                       (self.limit, np.array(limits)), (self.material, self.material_ids),
                       (self.children, np.array(table.children, np.int32)),
                       (self.shape, np.array(table.shape, np.int32)),
                       (self.ranges, ranges), (self.compound_range, np.array([table.compound_range], np.int32))])

    # --- generated funcs: one per shape ------------------------------------------------------
    def _shape_func(self, shape: int):
        """A ti.func (row, p) -> distance for the nodes of one shape. One func per level of the
        tree: Taichi inlines funcs recursively in Python, so each extra func per level would cut
        the depth that compiles."""
        if shape not in self._funcs:
            kind, identity, finite, child_shapes = self._table.shape_keys[shape]
            prim = PRIMITIVE_FUNCS.get(kind)
            children = [self._shape_func(s) for s in child_shapes]
            dispatched = len(children) > 1
            is_primitive = prim is not None
            table = self

            @ti.func
            def node_distance(i, p):
                q = p
                if ti.static(not identity):
                    q = _rotate(table.inv_rotation[i], p - table.translation[i]) / table.scale[i]
                d = 0.0
                if ti.static(is_primitive):
                    d = prim(q, table.params[i])
                else:
                    span = table.children[i]
                    if ti.static(kind == "repeat"):
                        period = table.params[i].xyz
                        safe = ti.select(period > 0.0, period, 1.0)
                        cell = ti.round(q / safe)
                        if ti.static(finite):
                            cell = ti.math.clamp(cell, -table.limit[i], table.limit[i])
                        q = q - ti.select(period > 0.0, period * cell, 0.0)
                    # Children in file order, each by the func of its shape (every row of one
                    # loop takes the same branch, so threads do not diverge); one call site per
                    # shape keeps the code linear in the number of shapes.
                    for c in range(span[0], span[1]):
                        e = 0.0
                        if ti.static(not dispatched):
                            e = children[0](c, q)
                        else:
                            child_shape = table.shape[c]
                            for k in ti.static(range(len(children))):
                                if child_shape == child_shapes[k]:
                                    e = children[k](c, q)
                        if ti.static(kind == "repeat"):
                            d = e  # its one child
                        elif c == span[0]:
                            d = e
                        elif ti.static(kind == "union"):
                            d = ti.min(d, e)
                        elif ti.static(kind == "intersection"):
                            d = ti.max(d, e)
                        elif ti.static(kind == "subtraction"):
                            d = ti.max(d, -e)
                        else:  # smooth_union
                            d = smooth_min(d, e, table.params[i].x)
                if ti.static(not identity):
                    d = d * table.scale[i]
                return d

            self._funcs[shape] = node_distance
        return self._funcs[shape]

    def _dispatch_func(self, shapes: tuple[int, ...]):
        """A ti.func (row, p) -> distance for rows of any of `shapes` (the top-level operator
        trees): the row's shape picks the func at run time."""
        funcs = [self._shape_func(s) for s in shapes]
        if len(funcs) == 1:
            return funcs[0]
        table = self

        @ti.func
        def dispatch(i, p):
            d = 0.0
            shape = table.shape[i]
            for k in ti.static(range(len(funcs))):
                if shape == shapes[k]:
                    d = funcs[k](i, p)
            return d

        return dispatch

    def _scene_func(self, with_material):
        table = self
        kinds = [PRIMITIVE_FUNCS[k] for k in self.batched_kinds]
        compound_shapes = self._table.shapes_of(range(*self._table.compound_range))
        has_compounds = bool(compound_shapes)
        compound = self._dispatch_func(compound_shapes) if has_compounds else None

        @ti.func
        def scene_distance(p):
            best = INF
            mat = -1
            node = -1
            for r in ti.static(range(len(kinds))):
                lo_hi = table.ranges[r]
                for i in range(lo_hi[0], lo_hi[1]):
                    q = _rotate(table.inv_rotation[i], p - table.translation[i]) / table.scale[i]
                    d = kinds[r](q, table.params[i]) * table.scale[i]
                    if d < best:
                        best = d
                        if ti.static(with_material):
                            mat = table.material[i]
                            node = i
            if ti.static(has_compounds):
                span = table.compound_range[0]
                for c in range(span[0], span[1]):
                    d = compound(c, p)
                    if d < best:
                        best = d
                        if ti.static(with_material):
                            mat = table.material[c]
                            node = c
            return ti.math.vec3(best, ti.cast(mat, ti.f32), ti.cast(node, ti.f32))

        if with_material:
            return scene_distance

        @ti.func
        def distance_only(p):
            return scene_distance(p).x

        return distance_only
