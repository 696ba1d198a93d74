"""Mitsuba's binary grid volume files (`.vol`, read by its `gridvolume`): read and write.

The layout (little-endian): the bytes 'VOL', a version byte (3), an int32 encoding (1 = float32,
the only one Mitsuba 3 reads), int32 xres, yres, zres, int32 channels (1 or 3 here), six float32
of a bounding box (min xyz, max xyz), then xres * yres * zres * channels float32 values, x
fastest, then y, then z, a voxel's channels together.

Bad input is one SceneError line naming the file; the declared size is checked against the file's
own length before anything is allocated, so a short file cannot ask for gigabytes.
"""
from __future__ import annotations

import os
import struct
from dataclasses import dataclass

import numpy as np

from renderer.scene.errors import PathLike, SceneError
from renderer.scene.limits import MemoryLedger

MAGIC = b"VOL"
VERSION = 3
FLOAT32_ENCODING = 1
CHANNEL_COUNTS = (1, 3)
_HEADER = struct.Struct("<3sBiiiii6f")  # magic, version, encoding, xres, yres, zres, channels, bbox


@dataclass(frozen=True)
class VolumeGrid:
    values: np.ndarray  # (zres, yres, xres, channels) float32
    bounds: tuple[tuple[float, float, float], tuple[float, float, float]]  # the file's box: min, max

    @property
    def resolution(self) -> tuple[int, int, int]:
        """(xres, yres, zres)."""
        z, y, x, _ = self.values.shape
        return x, y, z


def read_vol(path: PathLike, ledger: MemoryLedger | None = None) -> VolumeGrid:
    """The grid of a .vol file; SceneError (one line, naming the file) for anything else."""
    try:
        size = os.path.getsize(path)
        with open(path, "rb") as f:
            header = f.read(_HEADER.size)
            if len(header) < _HEADER.size:
                raise SceneError(path, f"not a Mitsuba volume file: {len(header)} bytes, shorter than its "
                                       f"{_HEADER.size}-byte header")
            magic, version, encoding, xres, yres, zres, channels, *box = _HEADER.unpack(header)
            if magic != MAGIC:
                raise SceneError(path, f"not a Mitsuba volume file: it starts with {magic!r}, not b'VOL'")
            if version != VERSION:
                raise SceneError(path, f"volume file version {version} is not supported (only {VERSION})")
            if encoding != FLOAT32_ENCODING:
                raise SceneError(path, f"volume encoding {encoding} is not supported (only 1, float32)")
            if min(xres, yres, zres) < 1:
                raise SceneError(path, f"volume resolution {xres}x{yres}x{zres} has no voxels")
            if channels not in CHANNEL_COUNTS:
                raise SceneError(path, f"{channels} channels per voxel (Lantern reads 1 or 3)")
            count = xres * yres * zres * channels
            expected = _HEADER.size + 4 * count
            if size != expected:
                raise SceneError(path, f"a {xres}x{yres}x{zres} volume of {channels} channel(s) takes {expected} "
                                       f"bytes, the file has {size}")
            if ledger is not None:
                ledger.charge(path, f"a {xres}x{yres}x{zres} volume", 4 * count)
            values = np.frombuffer(f.read(4 * count), dtype="<f4").astype(np.float32)
    except OSError as error:
        raise SceneError(path, f"cannot read the volume file: {error.strerror or error}") from None
    if not np.all(np.isfinite(values)):
        raise SceneError(path, "the volume holds values that are not finite numbers")
    lo, hi = tuple(float(v) for v in box[:3]), tuple(float(v) for v in box[3:])
    return VolumeGrid(values.reshape(zres, yres, xres, channels), (lo, hi))


def write_vol(path: PathLike, values, bounds=((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))) -> None:
    """Write `values` (zres, yres, xres) or (zres, yres, xres, channels) as a .vol file."""
    grid = np.asarray(values, np.float32)
    if grid.ndim == 3:
        grid = grid[..., None]
    zres, yres, xres, channels = grid.shape
    header = _HEADER.pack(MAGIC, VERSION, FLOAT32_ENCODING, xres, yres, zres, channels,
                          *(float(v) for v in (*bounds[0], *bounds[1])))
    with open(path, "wb") as f:
        f.write(header)
        f.write(grid.astype("<f4").tobytes())
