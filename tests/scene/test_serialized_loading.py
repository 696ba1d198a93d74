"""Mitsuba's serialized meshes read (renderer/scene/model_formats/serialized.py): versions 3 and 4,
single and double precision, the optional arrays, several shapes in one file, and one-line errors
for bad headers, damaged or truncated data."""
from __future__ import annotations

import struct
import zlib

import numpy as np
import pytest

from renderer.scene.errors import SceneError
from renderer.scene.model_formats import load_mesh_asset
from renderer.scene.model_formats.serialized import shape_name
from tests.scene.model_file_helpers import one_line_error
from tests.scene.serialized_writer import (SQUARE_INDICES, SQUARE_POSITIONS, SQUARE_UVS, SerializedMesh,
                                           TRIANGLE_SHAPE, mesh_stream, serialized_bytes, square,
                                           write_serialized)

TRIANGLE = TRIANGLE_SHAPE


@pytest.mark.parametrize("version, double", [(4, False), (3, True), (4, True), (3, False)])
def test_meshes_read_back_as_written(tmp_path, version, double):
    colors = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [0.5, 0.5, 0.5]])
    path = write_serialized(tmp_path / "two.serialized", [square(colors=colors), TRIANGLE], version, double)
    asset = load_mesh_asset(path)
    first, second = asset.meshes
    assert (first.name, second.name) == (shape_name(0), shape_name(1))
    np.testing.assert_array_equal(first.positions, SQUARE_POSITIONS)
    np.testing.assert_array_equal(first.indices, SQUARE_INDICES)
    np.testing.assert_array_equal(first.normals, np.tile([0.0, 0.0, 1.0], (4, 1)))
    np.testing.assert_array_equal(first.uv0, SQUARE_UVS)  # as stored: Mitsuba reads them so
    np.testing.assert_array_equal(first.colors, np.concatenate([colors, np.ones((4, 1))], axis=1))
    np.testing.assert_array_equal(second.positions, TRIANGLE.positions)
    assert second.normals is None and second.uv0 is None and second.colors is None
    np.testing.assert_array_equal(asset.bounds, [[0, 0, -2], [2, 1, 0]])


def test_the_face_normals_flag_is_ignored_as_mitsuba_ignores_it(tmp_path):
    """Mitsuba 3.9.1 keeps a file's normals under the flag (its shapes' face_normals asks for flat
    shading instead)."""
    asset = load_mesh_asset(write_serialized(tmp_path / "flat.serialized", [square(face_normals=True)]))
    np.testing.assert_array_equal(asset.meshes[0].normals, np.tile([0.0, 0.0, 1.0], (4, 1)))


def test_a_file_without_its_dictionary_is_one_mesh(tmp_path):
    path = tmp_path / "bare.serialized"
    path.write_bytes(mesh_stream(TRIANGLE))  # Mitsuba reads shape 0 without the dictionary
    assert [m.name for m in load_mesh_asset(path).meshes] == [shape_name(0)]


def _damaged(data: bytes) -> bytes:
    return data[:20] + bytes(b ^ 0x5A for b in data[20:40]) + data[40:]


BAD_FILES = {
    "format id": (lambda: b"\x1d\x04" + serialized_bytes([TRIANGLE])[2:], r"not a Mitsuba serialized mesh"),
    "version": (lambda: struct.pack("<HH", 0x041C, 5) + serialized_bytes([TRIANGLE])[4:],
                r"serialized version 5 is not supported \(3 or 4\)"),
    "empty": (lambda: b"", r"truncated \(no header\)"),
    "truncated": (lambda: mesh_stream(square())[:-30], r"shape 0: truncated"),
    "damaged": (lambda: _damaged(mesh_stream(square())), r"shape 0: the compressed data is damaged"),
    "precision": (lambda: struct.pack("<HH", 0x041C, 3) + zlib.compress(struct.pack("<IQQ", 0x3000, 3, 1)),
                  r"shape 0: flags 0x3000 give both single and double precision"),
    "index": (lambda: mesh_stream(SerializedMesh(TRIANGLE.positions, np.array([[0, 1, 7]]))),
              r"vertex index 7 is out of range"),
}


@pytest.mark.parametrize("case", sorted(BAD_FILES))
def test_bad_files_are_one_line_errors(tmp_path, case):
    make, pattern = BAD_FILES[case]
    path = tmp_path / "bad.serialized"
    path.write_bytes(make())
    with pytest.raises(SceneError, match=pattern) as excinfo:
        load_mesh_asset(path)
    one_line_error(excinfo, path)


def test_counts_are_checked_against_the_budget_before_inflating(tmp_path):
    from renderer.scene.load_options import LoadOptions

    path = tmp_path / "huge.serialized"
    path.write_bytes(struct.pack("<HH", 0x041C, 3) + zlib.compress(struct.pack("<IQQ", 0x1000, 10**12, 10**12)))
    with pytest.raises(SceneError, match=r"shape 0 \(1000000000000 vertices") as excinfo:
        load_mesh_asset(path, LoadOptions())
    one_line_error(excinfo, path)
