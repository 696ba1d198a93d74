"""Mitsuba's serialized meshes (.serialized): one or more triangle meshes, each a little-endian header
(uint16 format id 0x041C, uint16 version 3 or 4) followed by a zlib stream, and at the end of the
file a dictionary of where each mesh starts (version 4: uint64 offsets; version 3: uint32) and
their count (uint32).

A mesh's stream holds: uint32 flags (HAS_NORMALS, HAS_TEXCOORDS, HAS_COLORS, 0x0010 face normals and
one of SINGLE / DOUBLE precision), in version 4 a NUL-terminated UTF-8 name, uint64 vertex and triangle
counts, then per vertex positions (x, y, z), normals, texture coordinates (u, v) and colours (r, g,
b) as the flags say, in float32 or float64, and the triangles' vertex indices as uint32 (uint64
where the vertices exceed 2^32).

Every mesh becomes one `TriangleMesh` named "shape k" (k its place in the file, Mitsuba's
`shape_index`; `MeshObject.part` picks one), all with one grey material. Texture coordinates are
kept as stored: Mitsuba reads them so, and its image lookups share glTF's frame (v = 0 at the
image's top row). Colours are linear RGB (alpha 1). The face-normals flag is ignored, as Mitsuba 3
ignores it (a shape asks for flat shading with its own face_normals).
A file whose dictionary does not add up is read as one mesh at its start, as Mitsuba reads shape 0
without looking at the dictionary.
"""
from __future__ import annotations

import mmap
import struct
import zlib
from pathlib import Path

import numpy as np

from renderer.scene.errors import SceneError
from renderer.scene.model_formats.builder import AssetBuilder, default_grey

FORMAT_ID = 0x041C
VERSIONS = (3, 4)
HAS_NORMALS, HAS_TEXCOORDS, HAS_COLORS = 0x0001, 0x0002, 0x0008
SINGLE_PRECISION, DOUBLE_PRECISION = 0x1000, 0x2000
HEADER = struct.Struct("<HH")
MAX_NAME_BYTES = 1 << 16  # a longer name means a damaged stream
# Memory while one mesh is read, per byte of its arrays: the decompressed bytes, the arrays made
# from them and their float64 copies in the mesh build.
READ_BYTES_PER_BYTE = 4


def shape_name(index: int) -> str:
    """The name of the file's mesh number `index` (Mitsuba's shape_index)."""
    return f"shape {index}"


def read_serialized(b: AssetBuilder) -> None:
    data = b.file.read_bytes()
    version = _header(b, data, 0, "the file")
    material = default_grey(b)
    for index, offset in enumerate(mesh_offsets(data, version)):
        _read_mesh(b, data, offset, index, material)


def shape_count(path: Path) -> int:
    """How many meshes a serialized file holds, from its header and dictionary alone (a bad header
    is a one-line SceneError naming the file)."""
    with open(path, "rb") as f:
        if f.seek(0, 2) < HEADER.size:  # (an empty file cannot be mapped)
            raise SceneError(path, "the file: truncated (no header)")
        with mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as data:
            version = _header(None, data, 0, "the file", path)
            return len(mesh_offsets(data, version))


def mesh_offsets(data, version: int) -> list[int]:
    """Where each mesh of the file's bytes `data` starts, from the end-of-file dictionary ([0]
    where it does not add up)."""
    if len(data) < HEADER.size + 4:
        return [0]
    count = struct.unpack_from("<I", data, len(data) - 4)[0]
    entry = "<Q" if version == 4 else "<I"
    size = struct.calcsize(entry)
    start = len(data) - 4 - count * size
    if count == 0 or start < HEADER.size:
        return [0]
    offsets = [struct.unpack_from(entry, data, start + k * size)[0] for k in range(count)]
    if offsets[0] != 0 or any(b_ <= a for a, b_ in zip(offsets, offsets[1:])) or offsets[-1] >= start:
        return [0]
    return offsets


def _header(b: AssetBuilder | None, data, offset: int, what: str, path: Path | None = None) -> int:
    """The version in the header at `offset`; errors name the builder's file, else `path`."""
    def error(message: str) -> SceneError:
        return b.error(f"{what}: {message}") if b is not None else SceneError(path, f"{what}: {message}")

    if len(data) < offset + HEADER.size:
        raise error("truncated (no header)")
    format_id, version = HEADER.unpack_from(data, offset)
    if format_id != FORMAT_ID:
        raise error(f"not a Mitsuba serialized mesh (format id 0x{format_id:04X}, expected 0x{FORMAT_ID:04X})")
    if version not in VERSIONS:
        raise error(f"serialized version {version} is not supported (3 or 4)")
    return version


class _Inflater:
    """Reads a zlib stream piece by piece, so a mesh's counts are checked before its arrays are
    inflated."""

    def __init__(self, b: AssetBuilder, data: bytes, start: int, what: str):
        self.b, self.what = b, what
        self.z = zlib.decompressobj()
        self.pending = memoryview(data)[start:]
        self.buffer = bytearray()

    def read(self, n: int) -> bytes:
        while len(self.buffer) < n:
            if self.z.eof or not self.pending:
                raise self.b.error(f"{self.what}: truncated (its data ends {n - len(self.buffer)} bytes short)")
            try:
                chunk = self.z.decompress(self.pending, n - len(self.buffer))
            except zlib.error as e:
                raise self.b.error(f"{self.what}: the compressed data is damaged ({e})") from None
            self.pending = self.z.unconsumed_tail
            self.buffer += chunk
        out = bytes(self.buffer[:n])
        del self.buffer[:n]
        return out

    def name(self) -> str:
        raw = bytearray()
        while not raw.endswith(b"\0"):
            if len(raw) > MAX_NAME_BYTES:
                raise self.b.error(f"{self.what}: its name has no end (damaged data)")
            raw += self.read(1)
        return raw[:-1].decode("utf-8", errors="replace")

    def array(self, count: int, dtype, width: int) -> np.ndarray:
        dtype = np.dtype(dtype)
        return np.frombuffer(self.read(count * width * dtype.itemsize), dtype).reshape(count, width)


def _read_mesh(b: AssetBuilder, data: bytes, offset: int, index: int, material: int) -> None:
    what = shape_name(index)
    version = _header(b, data, offset, what)
    stream = _Inflater(b, data, offset + HEADER.size, what)
    flags = struct.unpack("<I", stream.read(4))[0]
    if version == 4:
        stream.name()  # the shape's own name; Lantern names shapes by their place in the file
    vertices, triangles = struct.unpack("<QQ", stream.read(16))
    double = bool(flags & DOUBLE_PRECISION)
    if double == bool(flags & SINGLE_PRECISION):
        raise b.error(f"{what}: flags 0x{flags:04X} give {'both' if double else 'neither'} single and double "
                      "precision")
    real = np.dtype("<f8" if double else "<f4")
    index_type = np.dtype("<u8" if vertices > 0xFFFFFFFF else "<u4")
    widths = 3 + 3 * bool(flags & HAS_NORMALS) + 2 * bool(flags & HAS_TEXCOORDS) + 3 * bool(flags & HAS_COLORS)
    nbytes = vertices * widths * real.itemsize + triangles * 3 * index_type.itemsize
    b.check_peak(f"{what} ({vertices} vertices, {triangles} triangles)", nbytes * READ_BYTES_PER_BYTE)
    positions = stream.array(vertices, real, 3)
    normals = stream.array(vertices, real, 3) if flags & HAS_NORMALS else None
    uvs = stream.array(vertices, real, 2) if flags & HAS_TEXCOORDS else None
    colors = stream.array(vertices, real, 3) if flags & HAS_COLORS else None
    indices = stream.array(triangles, index_type, 3)
    if colors is not None:
        colors = np.concatenate([colors, np.ones((vertices, 1))], axis=1)
    if triangles:
        b.add_mesh(what, positions, indices, material=material, normals=normals, uv0=uvs, colors=colors,
                   name=what)
