"""The primitives of a mesh scene as flat numpy arrays, ready for the BVH and upload.

Global primitive ids run over triangles first, then spheres, quads, discs and Bezier patches, in
that order. Everything is in world space except the triangles of instanced meshes: a mesh drawn
many times is stored once in its own frame, as the LAST triangles of the triangle range (mesh by
mesh, `instanced_meshes` says where each lies), and `instance_mesh` / `instance_to_world` place
it; the world-level BVH holds the other primitives and one box per instance.
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
    tri_colors: np.ndarray | None = None  # (T, 3, 4) per-corner linear RGBA vertex colours, or None
    tri_material: np.ndarray = field(default_factory=_i32)
    spheres: np.ndarray = field(default_factory=lambda: _f32((0, 4)))  # centre xyz, radius
    sphere_material: np.ndarray = field(default_factory=_i32)
    # (S, 3, 3) per sphere the unit x, y, z axes of its own frame (rows), in which its texture
    # coordinates are Mitsuba's: u = the angle about z from x (towards y) / 2 pi, v = the angle from
    # z / pi. Empty: every sphere in the world's axes.
    sphere_frames: np.ndarray = field(default_factory=lambda: _f32((0, 3, 3)))
    quads: np.ndarray = field(default_factory=lambda: _f32((0, 3, 3)))  # corner, edge u, edge v
    quad_material: np.ndarray = field(default_factory=_i32)
    # Per sphere and per quad: whether its normal is turned over (Mitsuba's flip_normals): a sphere's
    # then points inwards, a quad's against edge u x edge v, keeping its texture coordinates, as
    # Mitsuba's do. Empty: none is. (A disc's normal is data: turning it over needs no flag.)
    sphere_flipped: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    quad_flipped: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
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
    # Instancing: (K, 2) first triangle and triangle count of each mesh stored once in its own
    # frame (the object-space triangles, contiguous at the end of the triangle range); per
    # instance the mesh it draws (I,) and its object-to-world matrix (I, 3, 4), float64 (rows of
    # a matrix acting on column vectors; never singular: assembly flattens those).
    instanced_meshes: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int32))
    instance_mesh: np.ndarray = field(default_factory=_i32)
    instance_to_world: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 4)))
    # Host only (picking): the scene object each primitive came from, an index into
    # Scene.mesh_objects, in global id order (an instanced mesh's triangles: its object's); empty
    # where the data was not assembled from a scene.
    prim_object: np.ndarray = field(default_factory=_i32)

    @property
    def counts(self) -> dict[str, int]:
        return {"triangle": len(self.tri_vertices), "sphere": len(self.spheres),
                "quad": len(self.quads), "disc": len(self.discs), "bezier": len(self.bezier_patches)}

    def sphere_axes(self) -> np.ndarray:
        """(S, 3, 3) the spheres' frames, the world's axes where none are given."""
        if len(self.sphere_frames) == len(self.spheres):
            return self.sphere_frames.astype(np.float32)
        return np.tile(np.eye(3, dtype=np.float32), (len(self.spheres), 1, 1))

    @property
    def has_flipped(self) -> bool:
        """Whether a sphere or quad has its normal turned over."""
        return bool(np.any(self.sphere_flipped) or np.any(self.quad_flipped))

    def analytic_flipped(self) -> np.ndarray:
        """(spheres + quads,) int32: 1 where the normal is turned over, spheres then quads (their
        global ids in order, from the first sphere's)."""
        flags = [np.asarray(f, bool) if len(f) == n else np.zeros(n, bool)
                 for f, n in ((self.sphere_flipped, len(self.spheres)), (self.quad_flipped, len(self.quads)))]
        return np.concatenate(flags).astype(np.int32)

    @property
    def primitive_count(self) -> int:
        return sum(self.counts.values())

    @property
    def has_instances(self) -> bool:
        return len(self.instance_mesh) > 0

    @property
    def world_triangle_count(self) -> int:
        """Triangles placed in world space (the first ones; the object-space ones follow)."""
        return len(self.tri_vertices) - int(self.instanced_meshes[:, 1].sum())

    def world_prims(self) -> np.ndarray:
        """Global ids of the primitives placed in world space (all but the instanced meshes')."""
        return np.concatenate([np.arange(self.world_triangle_count),
                               np.arange(len(self.tri_vertices), self.primitive_count)]).astype(np.int64)

    def kinds(self) -> frozenset:
        return frozenset(k for k, n in self.counts.items() if n)

    def range_ends(self) -> np.ndarray:
        """Exclusive end of each kind's global id range, in KINDS order."""
        return np.cumsum([self.counts[k] for k in KINDS]).astype(np.int32)

    def materials(self) -> np.ndarray:
        return np.concatenate([self.tri_material, self.sphere_material, self.quad_material,
                               self.disc_material, self.bezier_material]).astype(np.int32)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Per-primitive boxes (N, 3) lo and hi, in global id order (float64); the triangles of
        instanced meshes in their mesh's own frame."""
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

    def instance_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """World boxes (I, 3) lo and hi of the instances: their mesh's box, transformed."""
        lo, hi = self.bounds()
        mesh_lo = np.array([lo[a:a + n].min(axis=0) for a, n in self.instanced_meshes]).reshape(-1, 3)
        mesh_hi = np.array([hi[a:a + n].max(axis=0) for a, n in self.instanced_meshes]).reshape(-1, 3)
        return transformed_boxes(mesh_lo[self.instance_mesh], mesh_hi[self.instance_mesh], self.instance_to_world)

    def scene_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        lo, hi = self.bounds()
        world = self.world_prims()
        lo, hi = lo[world], hi[world]
        if self.has_instances:
            inst_lo, inst_hi = self.instance_bounds()
            lo, hi = np.concatenate([lo, inst_lo]), np.concatenate([hi, inst_hi])
        if len(lo) == 0:
            return np.zeros(3), np.zeros(3)
        return lo.min(axis=0), hi.max(axis=0)


def transformed_boxes(lo: np.ndarray, hi: np.ndarray, matrices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World boxes of object boxes (N, 3) under matrices (N, 3, 4): their eight corners
    transformed, padded by a few f32 ulps of their size and place (a ray transformed into the
    object's frame in f32 may find a point just outside the exact box)."""
    corners = np.stack(np.meshgrid([0, 1], [0, 1], [0, 1], indexing="ij"), axis=-1).reshape(8, 3)
    pts = np.where(corners[None] == 1, hi[:, None, :], lo[:, None, :])  # (N, 8, 3)
    world = np.einsum("nij,nkj->nki", matrices[:, :, :3], pts) + matrices[:, None, :, 3]
    w_lo, w_hi = world.min(axis=1), world.max(axis=1)
    pad = 4e-6 * (np.maximum(np.abs(w_lo), np.abs(w_hi)).max(axis=1, keepdims=True)
                  + (w_hi - w_lo).max(axis=1, keepdims=True))
    return w_lo - pad, w_hi + pad
