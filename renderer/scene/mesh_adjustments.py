"""A triangle mesh as one scene object asks for it (`MeshObject.normals`, `flip_normals`, `flip_v`,
`part`, `vertex_colors`): formats whose shapes take a model file with options (Mitsuba's face_normals, flip_normals,
flip_tex_coords, shape_index) set them; TOML objects keep the defaults, which change nothing.

Numpy only. The meshes are in their source's frame, before the object's placement; what is
adjusted is a copy (a model file's meshes are shared by every object that draws them).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from renderer.scene.description import MeshObject
from renderer.scene.mesh_model import TriangleMesh


def selected_meshes(meshes, obj: MeshObject) -> list[TriangleMesh]:
    """The meshes of a file the object draws: all, or those named `obj.part`."""
    if obj.part is None:
        return list(meshes)
    return [mesh for mesh in meshes if mesh.name == obj.part]


def adjusted(mesh: TriangleMesh, obj: MeshObject) -> TriangleMesh:
    """`mesh` with the object's normals, side and texture coordinates."""
    if obj.normals == "flat":
        mesh = replace(mesh, normals=None, tangents=None)  # the device shades with the geometric normal
    elif obj.normals == "smooth" and mesh.normals is None:
        mesh = replace(mesh, normals=angle_weighted_normals(mesh.positions, mesh.indices))
    if obj.flip_normals:
        # Reversed winding turns the geometric normal over (the side that emits, the inside of a
        # medium); the shading normals go with it.
        mesh = replace(mesh, indices=np.ascontiguousarray(mesh.indices[:, ::-1]),
                       normals=None if mesh.normals is None else -mesh.normals)
    if obj.flip_v:
        mesh = replace(mesh, uv0=_flipped(mesh.uv0), uv1=_flipped(mesh.uv1))
    if not obj.vertex_colors:
        mesh = replace(mesh, colors=None)
    return mesh


def _flipped(uv):
    if uv is None:
        return None
    out = np.array(uv, np.float32)
    out[:, 1] = 1.0 - out[:, 1]
    return out


def angle_weighted_normals(positions: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """Unit vertex normals: the sum of the adjacent faces' unit normals, each weighted by the face's
    angle at the vertex (Thuermer and Wuethrich 1998, as Mitsuba computes the normals a mesh file
    lacks); a vertex of degenerate faces only gets +z. (V, 3) float32."""
    p = positions.astype(np.float64)
    tri = indices.astype(np.int64)
    corners = p[tri]  # (T, 3 corners, 3)
    face = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(face, axis=1)
    good = length > 0.0
    face = face[good] / length[good, None]
    corners, tri = corners[good], tri[good]
    normals = np.zeros_like(p)
    for k in range(3):
        a = corners[:, (k + 1) % 3] - corners[:, k]
        b = corners[:, (k + 2) % 3] - corners[:, k]
        cosine = np.einsum("ij,ij->i", a, b) / np.maximum(np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1),
                                                          1e-300)
        angle = np.arccos(np.clip(cosine, -1.0, 1.0))
        np.add.at(normals, tri[:, k], face * angle[:, None])
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    unit = np.where(length > 0.0, normals / np.where(length > 0.0, length, 1.0), [0.0, 0.0, 1.0])
    return unit.astype(np.float32)
