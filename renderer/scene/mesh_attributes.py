"""Per-vertex and per-face attributes of PLY files, and the colours a `MeshAttributeColor` makes of
them (numpy, no Taichi).

Names follow Mitsuba 3's PLY loader: properties that are not positions, normals or texture
coordinates, named <prefix>_0, <prefix>_1, ..., form the attribute vertex_<prefix> or
face_<prefix> (one or three channels; other counts are not attributes), and red, green, blue (or
r, g, b) form vertex_color (integers as fractions of their type's maximum; Mitsuba reads them as
they are, and warns). Properties without such a postfix are not attributes either, as in Mitsuba.

A mesh model (renderer/scene/mesh_model.py) keeps the file's vertices in order but may drop
degenerate triangles, rewind others and triangulate polygons, so a vertex attribute is read by
vertex index and a face attribute by matching each triangle's three vertices to the face they
come from. Per-face colours need each triangle's corners to itself: such a mesh is split into
three vertices per triangle (the device interpolates colours per corner).
"""
from __future__ import annotations

import re
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from renderer.scene.description import MeshAttributeColor
from renderer.scene.errors import SceneError
from renderer.scene.limits import MemoryLedger
from renderer.scene.mesh_model import TriangleMesh
from renderer.scene.model_formats.builder import TRIMESH_PARSE_BYTES_PER_BYTE

# Vertex properties a mesh model reads itself (never attributes).
GEOMETRY_PROPERTIES = frozenset(("x", "y", "z", "nx", "ny", "nz", "u", "v", "s", "t", "texture_u", "texture_v",
                                 "texture_s", "texture_t", "vertex_indices", "vertex_index"))
COLOR_PROPERTIES = (("red", "green", "blue"), ("r", "g", "b"))
POSTFIX = re.compile(r"^(.+)_(\d+)$")


@dataclass(frozen=True)
class PlyAttributes:
    """A PLY file's attributes by Mitsuba's name ((count, channels) float64 arrays), its vertex
    count, and its faces as polygons (vertex index arrays)."""

    vertex_count: int
    faces: tuple
    attributes: dict

    def names(self) -> list[str]:
        return sorted(self.attributes)


def read_ply_attributes(path: Path, ledger: MemoryLedger) -> PlyAttributes:
    from trimesh.exchange.ply import load_ply

    ledger.check_peak(path, "reading the PLY file's attributes", path.stat().st_size * TRIMESH_PARSE_BYTES_PER_BYTE)
    try:
        with open(path, "rb") as f:
            raw = load_ply(f, fix_texture=False, skip_materials=True)["metadata"]["_ply_raw"]
    except SceneError:
        raise
    except Exception as error:  # noqa: BLE001 - trimesh raises many types for a damaged file
        raise SceneError(path, f"cannot be read for its attributes ({type(error).__name__}: {error})") from None
    vertex, face = raw.get("vertex", {}).get("data"), raw.get("face", {}).get("data")
    if vertex is None or face is None:
        raise SceneError(path, "has no vertex or face element")
    attributes = {}
    for element, data in (("vertex", vertex), ("face", face)):
        attributes.update({f"{element}_{name}": values for name, values in _grouped(data).items()})
    return PlyAttributes(len(_column(vertex, _names(vertex)[0])), _polygons(face), attributes)


def _names(data) -> list[str]:
    return list(data.dtype.names) if hasattr(data, "dtype") and data.dtype.names else list(data.keys())


def _column(data, name: str) -> np.ndarray:
    return np.asarray(data[name]).reshape(len(data[name]), -1)


def _grouped(data) -> dict[str, np.ndarray]:
    """Mitsuba's attributes of one element: <prefix>_<k> properties by prefix (1 or 3 of them),
    and red / green / blue as "color"."""
    names = _names(data)
    groups: dict[str, dict[int, str]] = {}
    for name in names:
        match = POSTFIX.match(name)
        if match and name not in GEOMETRY_PROPERTIES:
            groups.setdefault(match.group(1), {})[int(match.group(2))] = name
    out = {}
    for prefix, members in groups.items():
        if sorted(members) in ([0], [0, 1, 2]):
            out[prefix] = np.concatenate([_fraction(_column(data, members[k])) for k in sorted(members)], axis=1)
    for colour in COLOR_PROPERTIES:
        if "color" not in out and all(c in names for c in colour):
            out["color"] = np.concatenate([_fraction(_column(data, c)) for c in colour], axis=1)
    return out


def _fraction(values: np.ndarray) -> np.ndarray:
    if np.issubdtype(values.dtype, np.integer):
        return values.astype(np.float64) / float(np.iinfo(values.dtype).max)
    return values.astype(np.float64)


def _polygons(face) -> tuple:
    name = "vertex_indices" if "vertex_indices" in _names(face) else "vertex_index"
    indices = face[name]
    if getattr(indices, "dtype", None) is not None and indices.dtype.names:  # binary lists: (count, indices)
        indices = indices[indices.dtype.names[-1]]
    return tuple(np.asarray(p, np.int64).reshape(-1) for p in indices)


def face_of_triangles(polygons, triangles: np.ndarray) -> np.ndarray:
    """The index of the polygon each triangle (T, 3) was cut from (by its set of vertices, the
    polygons fanned from their first vertex), -1 where none matches."""
    fans, owner = [], []
    for i, polygon in enumerate(polygons):
        for k in range(1, len(polygon) - 1):
            fans.append((polygon[0], polygon[k], polygon[k + 1]))
            owner.append(i)
    if not fans:
        return np.full(len(triangles), -1, np.int64)
    keys = np.sort(np.concatenate([np.asarray(fans, np.int64), np.asarray(triangles, np.int64)]), axis=1)
    _, key_id = np.unique(keys, axis=0, return_inverse=True)
    key_id = key_id.reshape(-1)
    first_owner = np.full(key_id.max() + 1, -1, np.int64)
    first_owner[key_id[:len(fans)][::-1]] = np.asarray(owner, np.int64)[::-1]  # the first polygon with those vertices
    return first_owner[key_id[len(fans):]]


class AttributeColoring:
    """Gives meshes the colours of a material's `MeshAttributeColor`, each PLY file read once."""

    def __init__(self, ledger: MemoryLedger):
        self.ledger = ledger
        self.files: dict[Path, PlyAttributes] = {}

    def attributes(self, file: Path) -> PlyAttributes:
        if file not in self.files:
            if file.suffix.lower() != ".ply":
                raise SceneError(file, "mesh attributes are read from PLY files only")
            self.files[file] = read_ply_attributes(file, self.ledger)
        return self.files[file]

    def colored(self, mesh: TriangleMesh, file: Path, spec: MeshAttributeColor) -> TriangleMesh:
        """`mesh` (drawn from `file`) with per-vertex colours offset + scale * the attribute."""
        found = self.attributes(file)
        if spec.name not in found.attributes:
            known = ", ".join(found.names()) or "none"
            raise SceneError(file, f"has no mesh attribute '{spec.name}' (its attributes: {known})")
        values = found.attributes[spec.name]
        colour = np.maximum(np.asarray(spec.offset) + np.asarray(spec.scale) * values, 0.0)  # grey from one channel
        rgba = np.concatenate([colour, np.ones((len(colour), 1))], axis=1).astype(np.float32)
        if spec.name.startswith("vertex_"):
            if len(mesh.positions) != found.vertex_count:
                raise SceneError(file, f"its mesh was rebuilt ({len(mesh.positions)} vertices of "
                                       f"{found.vertex_count}): vertex attributes cannot follow")
            return replace(mesh, colors=rgba)
        face = face_of_triangles(found.faces, mesh.indices)
        if np.any(face < 0):
            raise SceneError(file, f"{int(np.count_nonzero(face < 0))} triangles match no face of the file: "
                                   f"'{spec.name}' cannot follow them")
        return split_per_triangle(mesh, np.repeat(rgba[face], 3, axis=0))


def split_per_triangle(mesh: TriangleMesh, corner_colors: np.ndarray) -> TriangleMesh:
    """The mesh with three vertices of its own per triangle, coloured corner by corner
    ((3 T, 4), triangle by triangle)."""
    corners = mesh.indices.reshape(-1)

    def per_corner(values):
        return None if values is None else np.ascontiguousarray(values[corners])

    return replace(mesh, positions=per_corner(mesh.positions), normals=per_corner(mesh.normals),
                   uv0=per_corner(mesh.uv0), uv1=per_corner(mesh.uv1), tangents=per_corner(mesh.tangents),
                   colors=np.ascontiguousarray(corner_colors, np.float32),
                   indices=np.arange(len(corners), dtype=np.int32).reshape(-1, 3))
