"""The primitives of a mesh scene as flat numpy arrays, world space, ready for the BVH and upload.

Global primitive ids run over triangles first, then spheres, quads, discs and Bezier patches, in
that order.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

KINDS = ("triangle", "sphere", "quad", "disc", "bezier")


def _f32(shape):
    return np.zeros(shape, np.float32)


def _i32(n=0):
    return np.zeros(n, np.int32)


@dataclass
class MeshData:
    tri_vertices: np.ndarray = field(default_factory=lambda: _f32((0, 3, 3)))  # (T, 3 corners, xyz)
    tri_normals: np.ndarray | None = None  # (T, 3, 3) per-corner shading normals, or None
    tri_uvs: np.ndarray | None = None  # (T, 3, 2) per-corner texture coordinates (set 0), or None
    tri_uvs1: np.ndarray | None = None  # (T, 3, 2) texture coordinate set 1, or None
    tri_tangents: np.ndarray | None = None  # (T, 3, 4) per-corner tangent xyz + handedness, or None
    tri_material: np.ndarray = field(default_factory=_i32)
    spheres: np.ndarray = field(default_factory=lambda: _f32((0, 4)))  # centre xyz, radius
    sphere_material: np.ndarray = field(default_factory=_i32)
    quads: np.ndarray = field(default_factory=lambda: _f32((0, 3, 3)))  # corner, edge u, edge v
    quad_material: np.ndarray = field(default_factory=_i32)
    discs: np.ndarray = field(default_factory=lambda: _f32((0, 7)))  # centre xyz, normal xyz, radius
    disc_material: np.ndarray = field(default_factory=_i32)
    # Surfaces of revolution (renderer/geometry/bezier.py): curves are cubic profile segments in
    # their object's frame; each patch (a u-span times an angular sector) is one primitive.
    bezier_curves: np.ndarray = field(default_factory=lambda: _f32((0, 4, 2)))  # (C, 4, 2) radius, height
    bezier_curve_object: np.ndarray = field(default_factory=_i32)  # (C,) row of bezier_objects
    bezier_curve_u: np.ndarray = field(default_factory=lambda: _f32((0, 2)))  # texture u = a + b * u
    bezier_objects: np.ndarray = field(default_factory=lambda: _f32((0, 3, 4)))  # object-to-world rows
    bezier_patches: np.ndarray = field(default_factory=lambda: _f32((0, 4)))  # u0, u1, phi0, phi1
    bezier_patch_curve: np.ndarray = field(default_factory=_i32)
    bezier_patch_box: np.ndarray = field(default_factory=lambda: _f32((0, 2, 3)))  # object-space lo, hi
    bezier_material: np.ndarray = field(default_factory=_i32)

    @property
    def counts(self) -> dict[str, int]:
        return {"triangle": len(self.tri_vertices), "sphere": len(self.spheres),
                "quad": len(self.quads), "disc": len(self.discs), "bezier": len(self.bezier_patches)}

    @property
    def primitive_count(self) -> int:
        return sum(self.counts.values())

    def kinds(self) -> frozenset:
        return frozenset(k for k, n in self.counts.items() if n)

    def range_ends(self) -> np.ndarray:
        """Exclusive end of each kind's global id range, in KINDS order."""
        return np.cumsum([self.counts[k] for k in KINDS]).astype(np.int32)

    def materials(self) -> np.ndarray:
        return np.concatenate([self.tri_material, self.sphere_material, self.quad_material,
                               self.disc_material, self.bezier_material]).astype(np.int32)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Per-primitive boxes (N, 3) lo and hi, in global id order (float64)."""
        los, his = [], []
        tv = self.tri_vertices.astype(np.float64)
        los.append(tv.min(axis=1))
        his.append(tv.max(axis=1))
        s = self.spheres.astype(np.float64)
        los.append(s[:, :3] - s[:, 3:4])
        his.append(s[:, :3] + s[:, 3:4])
        q = self.quads.astype(np.float64)
        corners = np.stack([q[:, 0], q[:, 0] + q[:, 1], q[:, 0] + q[:, 2], q[:, 0] + q[:, 1] + q[:, 2]], axis=1)
        los.append(corners.min(axis=1))
        his.append(corners.max(axis=1))
        d = self.discs.astype(np.float64)
        # A disc of radius r with unit normal n extends r * sqrt(1 - n_i^2) along axis i.
        extent = d[:, 6:7] * np.sqrt(np.clip(1.0 - d[:, 3:6] ** 2, 0.0, 1.0))
        los.append(d[:, :3] - extent)
        his.append(d[:, :3] + extent)
        lo, hi = self.bezier_bounds()
        los.append(lo)
        his.append(hi)
        return np.concatenate(los).reshape(-1, 3), np.concatenate(his).reshape(-1, 3)

    def bezier_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """World boxes of the Bezier patches: their object-space boxes' corners, transformed."""
        from renderer.geometry.bezier import world_boxes

        lo, hi = np.zeros((0, 3)), np.zeros((0, 3))
        if len(self.bezier_patches):
            obj = self.bezier_curve_object[self.bezier_patch_curve]
            box = self.bezier_patch_box.astype(np.float64)
            lo, hi = np.empty((len(box), 3)), np.empty((len(box), 3))
            for o in np.unique(obj):
                rows = obj == o
                lo[rows], hi[rows] = world_boxes(box[rows], self.bezier_objects[o].astype(np.float64))
        return lo, hi

    def scene_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        lo, hi = self.bounds()
        if len(lo) == 0:
            return np.zeros(3), np.zeros(3)
        return lo.min(axis=0), hi.max(axis=0)
