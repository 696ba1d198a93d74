"""The shipped environment maps load without a warning, and scripts/clamp_envmaps.py, which
cleaned them, keeps everything of a map but its negative values."""
import os
import warnings
from pathlib import Path

import numpy as np
import OpenEXR
import pytest

from renderer.output.image_io import read_environment, read_exr
from scripts.clamp_envmaps import clamp_map

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = sorted((ROOT / "assets" / "envmaps").iterdir())


def test_the_maps_are_there():
    assert {p.name for p in SHIPPED} >= {"park.exr", "park.hdr", "sky.exr", "studio.exr", "sunset.exr", "venice.exr"}


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.name)
def test_every_shipped_map_loads_without_a_warning(path):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a NegativePixelsWarning (or any other) fails the test
        image = read_environment(path)
    assert image.ndim == 3 and image.shape[2] == 3 and np.isfinite(image).all() and (image >= 0).all()


def write_map(path: Path, channels: dict[str, np.ndarray], compression) -> None:
    header = {"compression": compression, "type": OpenEXR.scanlineimage, "owner": "a test"}
    with OpenEXR.File(header, dict(channels)) as exr:
        exr.write(os.fspath(path))


def read_map(path: Path):
    with OpenEXR.File(os.fspath(path), separate_channels=True) as exr:
        return dict(exr.header()), {name: np.array(c.pixels) for name, c in exr.channels().items()}


def test_the_script_clamps_only_the_negative_values_and_keeps_the_rest(tmp_path):
    """A map with ringing, stored lossy as the Poly Haven maps were: afterwards it holds exactly
    what the reader made of it (negative values and -0 as +0), in half floats, losslessly; its
    header is the same but for the compression; a second run changes nothing."""
    rng = np.random.default_rng(1)
    planes = {name: rng.normal(1.0, 0.6, (16, 32)).astype(np.float16) for name in "RGB"}
    planes["G"][0, :4] = np.array([-0.0, -1e-3, 0.0, 2.0], np.float16)
    path = tmp_path / "ringing.exr"
    write_map(path, planes, OpenEXR.DWAB_COMPRESSION)
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        expected = read_environment(path)  # what renders saw: clamped, with a warning
    assert len(said) == 1 and "negative values" in str(said[0].message)
    header_before, before = read_map(path)

    line = clamp_map(path)
    assert "clamped" in line and "DWAB_COMPRESSION -> PIZ_COMPRESSION (lossless)" in line
    header_after, after = read_map(path)
    assert header_after["compression"] == OpenEXR.PIZ_COMPRESSION
    assert {k: v for k, v in header_after.items() if k not in ("compression", "channels", "dataWindow",
                                                              "displayWindow", "screenWindowCenter")} == \
        {k: v for k, v in header_before.items() if k not in ("compression", "channels", "dataWindow",
                                                            "displayWindow", "screenWindowCenter")}
    for key in ("dataWindow", "displayWindow"):
        assert all(np.array_equal(a, b) for a, b in zip(header_after[key], header_before[key]))
    assert sorted(after) == sorted(before) and all(after[n].dtype == np.float16 for n in after)
    for name in after:
        kept = ~np.signbit(before[name])
        np.testing.assert_array_equal(after[name][kept], before[name][kept])  # untouched, bit for bit
        assert (after[name][~kept].view(np.uint16) == 0).all()  # +0, as the reader made them
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        np.testing.assert_array_equal(read_environment(path).view(np.uint32), expected.view(np.uint32))

    content = path.read_bytes()
    assert clamp_map(path).endswith("no negative values, unchanged") and path.read_bytes() == content


def test_a_map_without_negative_values_is_left_alone(tmp_path):
    path = tmp_path / "clean.exr"
    write_map(path, {name: np.full((4, 8), 0.5, np.float16) for name in "RGB"}, OpenEXR.DWAB_COMPRESSION)
    content = path.read_bytes()
    assert clamp_map(path).endswith("no negative values, unchanged") and path.read_bytes() == content
    assert (read_exr(path) >= 0).all()
