"""Leaves tested four primitives at a time: the BVH's primitive order in packets of four slots,
triangles stored structure-of-arrays (numpy build, device fields and the 4-lane tests).

A leaf covers slots [first, first + count) of the BVH's primitive order (bvh_build's layout, kept
by the wide collapse). Here slot j lives in packet j // 4, lane j % 4, and a packet holds, per
lane, the primitive id and (for a triangle) its three corners as nine rows of four floats:
row 3 i + a is corner i's coordinate a in the four lanes. A leaf tests the packets its slots
touch with a lane mask for its own slots, so the slots stay dense (one packet per four
primitives; the last one padded) and a leaf may share a packet with its neighbours without
testing their primitives. (Leaves aligned to packet starts would save a packet test where a leaf
straddles two, but the builder's leaves hold two or three primitives more often than four, so
the padding would cost 10-25 % more packets: 47-50 instead of 40 bytes a triangle, past the 64
bytes a triangle the BVH and intersection data may take.)

The four triangles are tested with 4-lane arithmetic, written so that LLVM's SLP vectoriser on
the CPU keeps it 4 lanes wide (every lane's edge functions, determinant and distance computed
unconditionally, the hit mask folded before any branch; docs/findings.md has the evidence):
the watertight test of Woop, Benthin and Wald 2013 with the per-ray axis permutation choosing
the rows (so the test is the scalar intersect.triangle_watertight's, lane by lane), or Moller-
Trumbore. Lanes holding other primitives (spheres, quads, discs, Bezier patches) have zero
corners, a degenerate triangle no ray hits, and are tested one by one by the scalar tests;
scenes without them compile none of that.

Shading and emitter sampling read a triangle's corners back from its packet through the slot of
each triangle (4 bytes a triangle): the packets replace the per-triangle corner array.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import taichi as ti

from renderer.geometry.wide_traversal import MISS_KEY  # a lane's key where it has no hit

LANES = 4
ROWS = 9  # three corners x three coordinates
NO_PRIM = -1  # the primitive id of a padding lane

vec3 = ti.math.vec3
vec4 = ti.math.vec4
ivec4 = ti.math.ivec4
LANE = ivec4(0, 1, 2, 3)


@dataclass
class PacketArrays:
    """rows: (P, ROWS, LANES) f32 corners; prims: (P, LANES) i32 ids (NO_PRIM: padding);
    tri_slot: (T,) i32, each triangle's slot (packet * LANES + lane)."""

    rows: np.ndarray
    prims: np.ndarray
    tri_slot: np.ndarray

    @property
    def num_packets(self) -> int:
        return int(self.prims.shape[0])


def build_packets(prim_order: np.ndarray, tri_vertices: np.ndarray) -> PacketArrays:
    """Packets of the slots of `prim_order` (primitive ids in leaf order; ids below
    len(tri_vertices) are triangles, whose (T, 3, 3) corners are given)."""
    order = np.asarray(prim_order, np.int64)
    n = len(order)
    t = len(tri_vertices)
    packets = max(1, -(-n // LANES))
    prims = np.full(packets * LANES, NO_PRIM, np.int64)
    prims[:n] = order
    is_triangle = (prims >= 0) & (prims < t)
    corners = np.zeros((packets * LANES, 3, 3), np.float32)
    corners[is_triangle] = np.asarray(tri_vertices, np.float32)[prims[is_triangle]]
    # (slot, corner, axis) -> (packet, corner * 3 + axis, lane)
    rows = corners.reshape(packets, LANES, ROWS).transpose(0, 2, 1)
    tri_slot = np.full(t, -1, np.int64)
    tri_slot[prims[is_triangle]] = np.flatnonzero(is_triangle)
    if t and (tri_slot < 0).any():
        raise ValueError("the BVH's primitive order leaves out triangles")
    return PacketArrays(rows=np.ascontiguousarray(rows, np.float32), prims=prims.reshape(packets, LANES).astype(np.int32),
                        tri_slot=tri_slot.astype(np.int32))


@ti.func
def _kept(x, zero):
    """x unchanged, but opaque to floating-point reassociation and contraction: its bits pass an
    integer OR with `zero` (0 at run time, not known to be at compile time)."""
    out = x
    for c in ti.static(range(LANES)):
        out[c] = ti.bit_cast(ti.bit_cast(x[c], ti.i32) | zero, ti.f32)
    return out


@ti.func
def _pick(k, v):
    """v[k] for k in 0..2 without indexing a local vector dynamically (which spills it)."""
    return ti.select(k == 0, v.x, ti.select(k == 1, v.y, v.z))


@ti.data_oriented
class TrianglePackets:
    """The packets on the device (module docs)."""

    BYTES_PER_PACKET = ROWS * LANES * 4 + LANES * 4

    def __init__(self, arrays: PacketArrays, uploads: list):
        """Appends its (field, array) pairs to `uploads` (one launch for the whole mesh)."""
        self.count = arrays.num_packets
        self.rows = ti.Vector.field(LANES, ti.f32, shape=(self.count, ROWS))
        self.prims = ti.Vector.field(LANES, ti.i32, shape=self.count)
        self.tri_slot = ti.field(ti.i32, shape=max(1, len(arrays.tri_slot)))
        uploads += [(self.rows, arrays.rows), (self.prims, arrays.prims)]
        if len(arrays.tri_slot):
            uploads.append((self.tri_slot, arrays.tri_slot))

    def device_bytes(self) -> dict:
        """{"ids": the primitive ids (what the BVH's slot array was), "triangles": the corners
        and each triangle's slot}."""
        return {"ids": self.count * LANES * 4,
                "triangles": self.count * ROWS * LANES * 4 + self.tri_slot.shape[0] * 4}

    @ti.func
    def corners(self, g):
        """Triangle g's three corners, read from its packet's lane."""
        slot = self.tri_slot[g]
        p = slot >> 2
        lane = slot & 3
        rows = ti.static(self.rows)
        return (vec3(rows[p, 0][lane], rows[p, 1][lane], rows[p, 2][lane]),
                vec3(rows[p, 3][lane], rows[p, 4][lane], rows[p, 5][lane]),
                vec3(rows[p, 6][lane], rows[p, 7][lane], rows[p, 8][lane]))

    @ti.func
    def lane_mask(self, p, first, end):
        """1 in the lanes of packet p whose slots lie in [first, end)."""
        slot = p * LANES + LANE
        return ti.cast(slot >= first, ti.i32) & ti.cast(slot < end, ti.i32)

    @ti.func
    def watertight(self, p, ok, k, s, t_max):
        """Woop et al.'s test of packet p's four triangles: (hit mask, t, b1, b2), 4 lanes each.
        ok = the origin permuted as k (ok.x = o[k.x] ...), k and s from watertight_setup."""
        # The corners relative to the origin, each difference kept as computed (_kept): fast math
        # lets LLVM reassociate (v - o) - s (w - o') into v - s w + (s o' - o), hoisting the ray's
        # part, which cancels catastrophically far from the origin (measured: hits 1.5e-3 in
        # barycentrics off on a triangle 0.25 across at 1e4, and rays through the gaps).
        zero = ti.cast(t_max < 0.0, ti.i32)  # 0 at run time, unknown to the compiler
        ax = _kept(self.rows[p, k.x] - ok.x, zero)
        ay = _kept(self.rows[p, k.y] - ok.y, zero)
        az = _kept(self.rows[p, k.z] - ok.z, zero)
        bx = _kept(self.rows[p, 3 + k.x] - ok.x, zero)
        by = _kept(self.rows[p, 3 + k.y] - ok.y, zero)
        bz = _kept(self.rows[p, 3 + k.z] - ok.z, zero)
        cx = _kept(self.rows[p, 6 + k.x] - ok.x, zero)
        cy = _kept(self.rows[p, 6 + k.y] - ok.y, zero)
        cz = _kept(self.rows[p, 6 + k.z] - ok.z, zero)
        ax, ay = ax - s.x * az, ay - s.y * az
        bx, by = bx - s.x * bz, by - s.y * bz
        cx, cy = cx - s.x * cz, cy - s.y * cz
        # Each edge function's products rounded on their own (_kept): the backend fuses one product
        # of a difference into an FMA in this vector code, and the two triangles of an edge, which
        # take its corners in opposite orders, would then round it differently (not to exactly
        # opposite values), letting rays through the edge.
        u = _kept(cx * by, zero) - _kept(cy * bx, zero)
        v = _kept(ax * cy, zero) - _kept(ay * cx, zero)
        w = _kept(bx * ay, zero) - _kept(by * ax, zero)
        # Inside unless the edge functions have mixed signs (zero counts as inside, as in the
        # scalar test); a back face has u, v, w, tt all of det's sign.
        neg = ti.cast(u < 0.0, ti.i32) | ti.cast(v < 0.0, ti.i32) | ti.cast(w < 0.0, ti.i32)
        pos = ti.cast(u > 0.0, ti.i32) | ti.cast(v > 0.0, ti.i32) | ti.cast(w > 0.0, ti.i32)
        det = u + v + w
        tt = u * (s.z * az) + v * (s.z * bz) + w * (s.z * cz)
        sign = ti.select(det > 0.0, 1.0, -1.0)
        hit = ((neg & pos) ^ 1) & ti.cast(det != 0.0, ti.i32) & ti.cast(tt * sign > 0.0, ti.i32) \
            & ti.cast(tt * sign < t_max * det * sign, ti.i32)
        inv = 1.0 / ti.select(det != 0.0, det, 1.0)
        return hit, tt * inv, v * inv, w * inv

    @ti.func
    def moller_trumbore(self, p, o, d, t_max):
        """Moller-Trumbore on packet p's four triangles: (hit mask, t, b1, b2), 4 lanes each."""
        v0x, v0y, v0z = self.rows[p, 0], self.rows[p, 1], self.rows[p, 2]
        e1x, e1y, e1z = self.rows[p, 3] - v0x, self.rows[p, 4] - v0y, self.rows[p, 5] - v0z
        e2x, e2y, e2z = self.rows[p, 6] - v0x, self.rows[p, 7] - v0y, self.rows[p, 8] - v0z
        px = d.y * e2z - d.z * e2y
        py = d.z * e2x - d.x * e2z
        pz = d.x * e2y - d.y * e2x
        det = e1x * px + e1y * py + e1z * pz
        inv = 1.0 / ti.select(det != 0.0, det, 1.0)
        tx, ty, tz = o.x - v0x, o.y - v0y, o.z - v0z
        u = (tx * px + ty * py + tz * pz) * inv
        qx = ty * e1z - tz * e1y
        qy = tz * e1x - tx * e1z
        qz = tx * e1y - ty * e1x
        v = (d.x * qx + d.y * qy + d.z * qz) * inv
        tt = (e2x * qx + e2y * qy + e2z * qz) * inv
        hit = ti.cast(det != 0.0, ti.i32) & ti.cast(u >= 0.0, ti.i32) & ti.cast(v >= 0.0, ti.i32) \
            & ti.cast(u + v <= 1.0, ti.i32) & ti.cast(tt > 0.0, ti.i32) & ti.cast(tt < t_max, ti.i32)
        return hit, tt, u, v


@ti.func
def nearest_lane(found, t, b1, b2):
    """(t, lane, b1, b2) of the nearest lane whose `found` is 1 (the lowest such lane on a tie);
    t = MISS_KEY where none is. The lanes' keys and barycentrics go to local arrays that the
    chosen lane's dynamic index reads: their four stores each become one 4-lane store, which is
    where LLVM's SLP vectoriser starts, and it then vectorises the test that computes them (with
    the values consumed lane by lane instead, by branches, the test stayed scalar)."""
    key = ti.select(found == 1, t, MISS_KEY)
    keys = vec4(MISS_KEY)
    bu = vec4(0.0)
    bv = vec4(0.0)
    for c in ti.static(range(LANES)):
        keys[c] = key[c]
        bu[c] = b1[c]
        bv[c] = b2[c]
    low = ti.select(key[1] < key[0], 1, 0)
    high = ti.select(key[3] < key[2], 3, 2)
    best = ti.select(ti.min(key[2], key[3]) < ti.min(key[0], key[1]), high, low)
    return keys[best], best, bu[best], bv[best]


@ti.func
def permuted_origin(o, k):
    """(o[k.x], o[k.y], o[k.z]) for the packet watertight test, once per leaf."""
    return vec3(_pick(k.x, o), _pick(k.y, o), _pick(k.z, o))
