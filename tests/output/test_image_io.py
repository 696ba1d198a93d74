import shutil
import warnings
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import OpenEXR
import pytest

from renderer.output.image_io import (
    NegativePixelsWarning,
    read_environment,
    read_exr,
    write_exr,
    write_png,
)
from renderer.scene.errors import SceneError

ENVMAPS = Path(__file__).resolve().parents[2] / "assets" / "envmaps"


def test_park_exr_and_hdr_agree_within_rgbe_precision():
    exr = read_environment(ENVMAPS / "park.exr")  # (scripts/clamp_envmaps.py removed its negatives)
    hdr = read_environment(ENVMAPS / "park.hdr")
    assert exr.dtype == hdr.dtype == np.float32
    assert exr.shape == hdr.shape == (256, 512, 3)
    # RGBE stores an 8-bit mantissa per channel under the exponent of the brightest channel, whose
    # mantissa is >= 128: each channel is off by less than one step, max(rgb) / 128.
    step = np.maximum(exr.max(axis=2, keepdims=True), hdr.max(axis=2, keepdims=True)) / 128.0
    assert np.all(np.abs(exr - hdr) <= step + 1e-30)
    # Row 0 is the zenith in both: the top of the sky is brighter than the ground.
    assert exr[:32].mean() > exr[-32:].mean()


@pytest.mark.parametrize("name", ["sky.exr", "sunset.exr", "venice.exr"])
def test_shipped_maps_load_finite_and_non_negative(name):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NegativePixelsWarning)
        image = read_environment(ENVMAPS / name)
    assert image.dtype == np.float32 and image.shape == (256, 512, 3)
    assert image.flags.c_contiguous
    assert np.isfinite(image).all() and image.min() >= 0.0 and image.max() > 0.0


def test_negative_pixels_are_clamped_with_a_one_line_warning(tmp_path):
    """A map with lossy-compression undershoot (the shipped ones had it until they were cleaned)."""
    rng = np.random.default_rng(3)
    written = rng.uniform(0.0, 2.0, (16, 32, 3)).astype(np.float32)
    written[rng.uniform(size=written.shape) < 0.1] *= -0.01
    write_exr(tmp_path / "undershoot.exr", written)
    raw = read_exr(tmp_path / "undershoot.exr")
    negative_values = int((raw < 0).sum())
    negative_pixels = int((raw < 0).any(axis=2).sum())
    assert negative_values > 100
    with pytest.warns(NegativePixelsWarning) as caught:
        image = read_environment(tmp_path / "undershoot.exr")
    message = str(caught[0].message)
    assert "undershoot.exr" in message and "\n" not in message
    assert f"{negative_values} negative values" in message and f"{negative_pixels} pixels" in message
    assert image.min() == 0.0
    np.testing.assert_array_equal(image, np.maximum(raw, 0.0))


def test_missing_file(tmp_path):
    with pytest.raises(SceneError, match="not found") as error:
        read_environment(tmp_path / "nowhere.exr")
    assert "nowhere.exr" in str(error.value)


def test_unsupported_extension_is_named(tmp_path):
    path = tmp_path / "map.png"
    path.write_bytes(b"\x89PNG")
    with pytest.raises(SceneError, match=r"\.png"):
        read_environment(path)


@pytest.mark.parametrize("suffix", [".exr", ".hdr"])
def test_corrupt_file(tmp_path, suffix):
    path = tmp_path / f"broken{suffix}"
    path.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4 +X 4\n" + b"junk")
    with pytest.raises(SceneError, match="cannot read") as error:
        read_environment(path)
    assert "\n" not in str(error.value) and str(path) in str(error.value)


def test_truncated_exr(tmp_path):
    path = tmp_path / "truncated.exr"
    data = (ENVMAPS / "sky.exr").read_bytes()
    path.write_bytes(data[: len(data) // 3])
    with pytest.raises(SceneError):
        read_environment(path)


def test_non_finite_pixels_are_an_error_naming_the_count(tmp_path):
    image = np.ones((4, 6, 3), dtype=np.float32)
    image[0, 0, 0] = np.nan
    image[1, 2, 1] = np.inf
    image[3, 5] = -np.inf
    path = tmp_path / "bad.exr"
    write_exr(path, image)
    with pytest.raises(SceneError, match="3 pixels have non-finite"):
        read_environment(path)


def test_exr_channel_layouts_rgba_and_half(tmp_path):
    rgb = np.random.default_rng(1).random((5, 7, 3)).astype(np.float32)
    layouts = {
        "rgba_half.exr": {"RGBA": np.concatenate([rgb, np.ones((5, 7, 1), np.float32)], axis=2).astype(np.float16)},
        "separate_float.exr": {"R": rgb[..., 0].copy(), "G": rgb[..., 1].copy(), "B": rgb[..., 2].copy()},
    }
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    for name, channels in layouts.items():
        with OpenEXR.File(header, channels) as exr:
            exr.write(str(tmp_path / name))
        image = read_environment(tmp_path / name)
        assert image.dtype == np.float32 and image.shape == (5, 7, 3)
        tolerance = 1e-3 if "half" in name else 0.0
        np.testing.assert_allclose(image, rgb, atol=tolerance)


def test_exr_without_rgb_channels_is_refused(tmp_path):
    path = tmp_path / "depth.exr"
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, {"Z": np.ones((2, 2), np.float32)}) as exr:
        exr.write(str(path))
    with pytest.raises(SceneError, match="found: Z"):
        read_environment(path)


def test_exr_round_trip_is_exact_float32(tmp_path):
    image = (np.random.default_rng(2).random((9, 13, 3)) * 1000.0).astype(np.float32)
    image[0, 0] = [1.0, 0.0, 0.0]  # marks the top-left corner
    path = tmp_path / "nested" / "dir" / "out.exr"
    write_exr(path, image)
    back = read_exr(path)
    assert back.dtype == np.float32
    np.testing.assert_array_equal(back, image)


def test_png_from_uint8_and_float(tmp_path):
    bytes_image = np.arange(4 * 5 * 3, dtype=np.uint8).reshape(4, 5, 3)
    write_png(tmp_path / "a" / "bytes.png", bytes_image)
    np.testing.assert_array_equal(iio.imread(tmp_path / "a" / "bytes.png"), bytes_image)

    floats = np.array([[[0.0, 0.5, 1.0], [-1.0, 2.0, np.nan]]], dtype=np.float32)
    write_png(tmp_path / "floats.png", floats)
    np.testing.assert_array_equal(iio.imread(tmp_path / "floats.png"), [[[0, 128, 255], [0, 255, 0]]])


def test_write_rejects_wrong_shapes(tmp_path):
    with pytest.raises(ValueError):
        write_png(tmp_path / "x.png", np.zeros((4, 4), np.uint8))
    with pytest.raises(ValueError):
        write_exr(tmp_path / "x.exr", np.zeros((4, 4, 4), np.float32))


def test_path_is_reported_as_given(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    shutil.copy(ENVMAPS / "park.hdr", tmp_path / "copy.hdr")
    assert read_environment("copy.hdr").shape == (256, 512, 3)
    with pytest.raises(SceneError) as error:
        read_environment("missing.hdr")
    assert str(error.value).startswith("missing.hdr: ")


@pytest.mark.parametrize("kind, channels", [(b"PF", 3), (b"Pf", 1)])
def test_a_pfm_map_reads_top_row_first(tmp_path, kind, channels):
    """A portable float map (its rows stored bottom to top, little-endian for a negative scale)
    reads as the image itself, a grey one as three equal channels; a file without its header is
    one error naming it."""
    image = np.random.default_rng(2).random((3, 5, channels)).astype(np.float32)
    path = tmp_path / "map.pfm"
    path.write_bytes(kind + b"\n5 3\n-1.0\n" + image[::-1].astype("<f4").tobytes())
    assert np.array_equal(read_environment(path), np.repeat(image, 3 // channels, axis=2))
    (tmp_path / "bad.pfm").write_bytes(b"P6\n1 1\n255\n\0\0\0")
    with pytest.raises(SceneError, match="bad.pfm: cannot read PFM file"):
        read_environment(tmp_path / "bad.pfm")
