"""A writer of Mitsuba's serialized mesh files for the tests, from the format's description (the
reader's module notes): header, zlib stream per mesh, end-of-file dictionary."""
from __future__ import annotations

import struct
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

import numpy as np

# The corners of a unit square in z = 0, two triangles facing +z, with normals and texture coordinates.
SQUARE_POSITIONS = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], np.float64)
SQUARE_INDICES = np.array([[0, 1, 2], [0, 2, 3]], np.uint32)
SQUARE_UVS = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.25], [0.0, 0.25]])


@dataclass
class SerializedMesh:
    positions: np.ndarray
    indices: np.ndarray
    normals: Optional[np.ndarray] = None
    uvs: Optional[np.ndarray] = None
    colors: Optional[np.ndarray] = None
    name: str = "mesh"
    face_normals: bool = False


def square(**changes) -> SerializedMesh:
    mesh = SerializedMesh(SQUARE_POSITIONS, SQUARE_INDICES, normals=np.tile([0.0, 0.0, 1.0], (4, 1)),
                          uvs=SQUARE_UVS)
    for key, value in changes.items():
        setattr(mesh, key, value)
    return mesh


def mesh_stream(mesh: SerializedMesh, version: int = 4, double: bool = False) -> bytes:
    """One mesh: its header and zlib stream."""
    flags = 0x2000 if double else 0x1000
    real = "<f8" if double else "<f4"
    arrays = [np.asarray(mesh.positions, real)]
    for bit, values in ((0x0001, mesh.normals), (0x0002, mesh.uvs), (0x0008, mesh.colors)):
        if values is not None:
            flags |= bit
            arrays.append(np.asarray(values, real))
    if mesh.face_normals:
        flags |= 0x0010
    body = struct.pack("<I", flags)
    if version == 4:
        body += mesh.name.encode() + b"\0"
    body += struct.pack("<QQ", len(mesh.positions), len(mesh.indices))
    body += b"".join(a.tobytes() for a in arrays) + np.asarray(mesh.indices, "<u4").tobytes()
    return struct.pack("<HH", 0x041C, version) + zlib.compress(body)


def serialized_bytes(meshes, version: int = 4, double: bool = False) -> bytes:
    """A whole file: the meshes one after another, then the dictionary of their offsets."""
    out, offsets = b"", []
    for mesh in meshes:
        offsets.append(len(out))
        out += mesh_stream(mesh, version, double)
    entry = "<Q" if version == 4 else "<I"
    return out + b"".join(struct.pack(entry, o) for o in offsets) + struct.pack("<I", len(offsets))


def write_serialized(path: Path, meshes, version: int = 4, double: bool = False) -> Path:
    path.write_bytes(serialized_bytes(meshes, version, double))
    return path


# A second shape for files of several: one triangle in y = 0.
TRIANGLE_SHAPE = SerializedMesh(np.array([[0, 0, 0], [2, 0, 0], [0, 0, -2]], np.float64), np.array([[0, 1, 2]]))
