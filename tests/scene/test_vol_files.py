"""Mitsuba's .vol grids (renderer/scene/vol_files.py): a grid written here reads back exactly, in
Mitsuba's layout (x fastest), and every malformed file is one line naming it."""
import struct

import numpy as np
import pytest

from renderer.scene.errors import SceneError
from renderer.scene.limits import MemoryBudget, MemoryLedger
from renderer.scene.vol_files import read_vol, write_vol


@pytest.mark.parametrize("channels", [1, 3])
def test_a_written_grid_reads_back(tmp_path, channels):
    values = np.random.default_rng(channels).random((2, 3, 4, channels)).astype(np.float32)
    path = tmp_path / "g.vol"
    write_vol(path, values, bounds=((-1.0, 0.0, 0.5), (1.0, 2.0, 3.5)))
    grid = read_vol(path)
    np.testing.assert_array_equal(grid.values, values)
    assert grid.resolution == (4, 3, 2)
    assert grid.bounds == ((-1.0, 0.0, 0.5), (1.0, 2.0, 3.5))


def test_the_layout_is_mitsubas(tmp_path):
    """The header as Mitsuba's writers lay it out, then the voxels x fastest: value = x + 10 y + 100 z."""
    xres, yres, zres = 3, 2, 2
    data = [float(x + 10 * y + 100 * z) for z in range(zres) for y in range(yres) for x in range(xres)]
    path = tmp_path / "hand.vol"
    path.write_bytes(b"VOL" + bytes([3]) + struct.pack("<5i", 1, xres, yres, zres, 1)
                     + struct.pack("<6f", 0, 0, 0, 1, 1, 1) + struct.pack(f"<{len(data)}f", *data))
    values = read_vol(path).values
    assert values.shape == (zres, yres, xres, 1)
    assert values[1, 0, 2, 0] == 102.0 and values[0, 1, 1, 0] == 11.0


def _header(magic=b"VOL", version=3, encoding=1, res=(2, 2, 2), channels=1):
    return magic + bytes([version]) + struct.pack("<5i", encoding, *res, channels) + struct.pack("<6f", 0, 0, 0, 1, 1, 1)


@pytest.mark.parametrize("content,problem", [
    (b"VOL", "shorter than its 48-byte header"),
    (_header(magic=b"VOX") + bytes(32), "not a Mitsuba volume file"),
    (_header(version=2) + bytes(32), "version 2 is not supported"),
    (_header(encoding=2) + bytes(16), "encoding 2 is not supported"),
    (_header(res=(2, 0, 2)), "has no voxels"),
    (_header(channels=2) + bytes(64), "2 channels per voxel"),
    (_header() + bytes(31), "takes 80 bytes, the file has 79"),
    (_header(res=(1 << 20, 1 << 20, 1 << 20)) + bytes(32), "the file has 80"),  # a short file asking for petabytes
    (_header() + struct.pack("<8f", *([1.0] * 7 + [float("nan")])), "not finite"),
])
def test_malformed_files_are_one_line_naming_them(tmp_path, content, problem):
    path = tmp_path / "bad.vol"
    path.write_bytes(content)
    with pytest.raises(SceneError) as error:
        read_vol(path)
    text = str(error.value)
    assert text.startswith(str(path)) and problem in text and "\n" not in text


def test_a_missing_file_is_one_line(tmp_path):
    with pytest.raises(SceneError, match="cannot read the volume file"):
        read_vol(tmp_path / "nowhere.vol")


def test_grids_are_charged_to_the_memory_budget(tmp_path):
    path = tmp_path / "g.vol"
    write_vol(path, np.zeros((4, 4, 4), np.float32))
    ledger = MemoryLedger(MemoryBudget(200, "a test's"))  # the voxels take 256 bytes
    with pytest.raises(SceneError, match="more than the memory limit"):
        read_vol(path, ledger)
    ledger = MemoryLedger(MemoryBudget(1 << 20, "a test's"))
    read_vol(path, ledger)
    assert ledger.spent == 4 * 64
