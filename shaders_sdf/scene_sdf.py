"""Turns a scene's SDF tree into Taichi funcs: kinds compiled in, instances kept as data.

Top-level primitives are grouped by kind and evaluated by a runtime loop over a field range per
kind, so a scene with 50 spheres compiles one sphere evaluation. Operator subtrees (smooth unions,
subtractions, repetitions...) are unrolled at compile time, their parameters and transforms still
read from the node table, so editing a value never recompiles. Only the primitive and operator
kinds a scene uses are ever referenced, hence compiled.
"""
import numpy as np
import taichi as ti

from renderer.geometry.interface import INF
from renderer.upload import upload_fields
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


class SdfProgram:
    """The node table (fields) of one SDF scene and the distance funcs generated over it."""

    def __init__(self, objects, material_index):
        """objects: the scene's top-level SdfNodes; material_index: name -> material id."""
        order = self._table_order(objects)
        self.node_count = len(order)
        self.inv_rotation = ti.Matrix.field(3, 3, ti.f32, shape=self.node_count)
        self.translation = ti.Vector.field(3, ti.f32, shape=self.node_count)
        self.scale = ti.field(ti.f32, shape=self.node_count)
        self.params = ti.Vector.field(4, ti.f32, shape=self.node_count)
        self.limit = ti.Vector.field(3, ti.f32, shape=self.node_count)
        self.material = ti.field(ti.i32, shape=self.node_count)
        index_of = {id(node): i for i, node in enumerate(order)}
        self._upload(order, material_index)

        # Top-level primitives, batched by kind: [start, end) ranges into the node table.
        self.batched_kinds = []
        ranges = []
        i = 0
        tops = sorted((n for n in objects if n.is_primitive), key=lambda n: n.kind)  # as in the table
        while i < len(tops):
            kind = tops[i].kind
            j = i
            while j < len(tops) and tops[j].kind == kind:
                j += 1
            self.batched_kinds.append(kind)
            ranges.append((index_of[id(tops[i])], index_of[id(tops[i])] + (j - i)))
            i = j
        self.ranges = ti.Vector.field(2, ti.i32, shape=max(1, len(ranges)))
        if ranges:
            self.ranges.from_numpy(np.array(ranges, np.int32))
        compounds = [n for n in objects if not n.is_primitive]
        self.compound_funcs = [self._node_func(n, index_of) for n in compounds]
        self.compound_index = [index_of[id(n)] for n in compounds]
        self.distance = self._scene_func(with_material=False)  # p -> d
        self.distance_material = self._scene_func(with_material=True)  # p -> (d, material id, node id)
        self.order = order  # node table order: node id -> SdfNode

    @staticmethod
    def _table_order(objects):
        """Top-level primitives first, sorted by kind (stable), then every compound subtree."""
        tops = sorted((n for n in objects if n.is_primitive), key=lambda n: n.kind)
        order = list(tops)
        for n in objects:
            if not n.is_primitive:
                order.extend(n.walk())
        return order

    def _upload(self, order, material_index):
        limits = [dict(n.params).get("limit") or (0, 0, 0) for n in order]
        # kept on the host too: emitter_info reads it without a download
        self.material_ids = np.array([material_index(n.material) if n.material is not None else -1 for n in order],
                                     np.int32)
        upload_fields([(self.inv_rotation, np.stack([n.transform.rotation_matrix().T for n in order])),
                       (self.translation, np.array([n.transform.translate for n in order])),
                       (self.scale, np.array([n.transform.scale for n in order])),
                       (self.params, np.stack([pack_parameters(n) for n in order])),
                       (self.limit, np.array(limits)), (self.material, self.material_ids)])

    # --- generated funcs ---------------------------------------------------------------------
    def _node_func(self, node, index_of):
        """A ti.func p -> distance for one node, its subtree unrolled."""
        idx = index_of[id(node)]
        identity = node.transform.is_identity
        body = self._body_func(node, idx, index_of)
        table = self

        @ti.func
        def node_distance(p):
            d = 0.0
            if ti.static(identity):
                d = body(p)
            else:
                d = body(_rotate(table.inv_rotation[idx], p - table.translation[idx]) / table.scale[idx]) * table.scale[idx]
            return d

        return node_distance

    def _body_func(self, node, idx, index_of):
        table = self
        if node.is_primitive:
            prim = PRIMITIVE_FUNCS[node.kind]

            @ti.func
            def primitive(q):
                return prim(q, table.params[idx])

            return primitive
        children = [self._node_func(c, index_of) for c in node.children]
        kind = node.kind
        if kind == "repeat":
            child = children[0]
            finite = dict(node.params).get("limit") is not None

            @ti.func
            def repeat(q):
                period = table.params[idx].xyz
                safe = ti.select(period > 0.0, period, 1.0)
                cell = ti.round(q / safe)
                if ti.static(finite):
                    cell = ti.math.clamp(cell, -table.limit[idx], table.limit[idx])
                return child(q - ti.select(period > 0.0, period * cell, 0.0))

            return repeat

        first, rest = children[0], children[1:]

        @ti.func
        def combine(q):
            d = first(q)
            for c in ti.static(rest):
                e = c(q)
                if ti.static(kind == "union"):
                    d = ti.min(d, e)
                elif ti.static(kind == "intersection"):
                    d = ti.max(d, e)
                elif ti.static(kind == "subtraction"):
                    d = ti.max(d, -e)
                else:  # smooth_union
                    d = smooth_min(d, e, table.params[idx].x)
            return d

        return combine

    def _scene_func(self, with_material):
        table = self
        kinds = [PRIMITIVE_FUNCS[k] for k in self.batched_kinds]
        compounds = self.compound_funcs
        compound_index = self.compound_index

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
            for c in ti.static(range(len(compounds))):
                d = compounds[c](p)
                if d < best:
                    best = d
                    if ti.static(with_material):
                        mat = table.material[compound_index[c]]
                        node = compound_index[c]
            return ti.math.vec3(best, ti.cast(mat, ti.f32), ti.cast(node, ti.f32))

        if with_material:
            return scene_distance

        @ti.func
        def distance_only(p):
            return scene_distance(p).x

        return distance_only
