"""The images of texture specs: a bitmap file decoded as stored (sRGB or raw), a checkerboard as the
2x2 image nearest filtering makes exact, and bad files as one line naming them."""
from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from renderer.output.image_io import write_exr
from renderer.scene.description import TextureSpec
from renderer.scene.errors import SceneError
from renderer.scene.limits import MemoryBudget, MemoryLedger
from renderer.scene.texture_images import checkerboard_image, texture_image


def ledger(limit=1 << 30):
    return MemoryLedger(MemoryBudget(limit, "the test's limit"))


def test_a_png_keeps_its_bytes_and_says_how_to_decode_them(tmp_path):
    pixels = np.arange(2 * 3 * 3, dtype=np.uint8).reshape(2, 3, 3) * 10
    Image.fromarray(pixels).save(tmp_path / "t.png")
    srgb = texture_image(TextureSpec("bitmap", file=tmp_path / "t.png"), ledger())
    raw = texture_image(TextureSpec("bitmap", file=tmp_path / "t.png", srgb=False), ledger())
    np.testing.assert_array_equal(srgb.pixels[..., :3], pixels)
    assert srgb.srgb and not raw.srgb and srgb.pixels[..., 3].min() == 255


def test_an_exr_is_linear(tmp_path):
    rgb = np.random.default_rng(1).uniform(0, 4, (4, 5, 3)).astype(np.float32)
    write_exr(tmp_path / "t.exr", rgb)
    image = texture_image(TextureSpec("bitmap", file=tmp_path / "t.exr"), ledger())
    assert not image.srgb and image.pixels.dtype == np.float32
    np.testing.assert_array_equal(image.pixels[..., :3], rgb)


def test_the_checkerboard():
    image = checkerboard_image((0.9, 0.8, 0.7), (0.1, 0.2, 0.3)).linear()
    np.testing.assert_allclose(image[0, 0, :3], (0.9, 0.8, 0.7))  # u, v < 1/2: color0
    np.testing.assert_allclose(image[0, 1, :3], (0.1, 0.2, 0.3))
    np.testing.assert_allclose(image[1, 1, :3], (0.9, 0.8, 0.7))


def test_bad_files_are_one_line(tmp_path):
    (tmp_path / "bad.png").write_bytes(b"not an image")
    with pytest.raises(SceneError, match=r"bad.png: cannot be decoded as a texture \(not an image format"):
        texture_image(TextureSpec("bitmap", file=tmp_path / "bad.png"), ledger())
    with pytest.raises(SceneError, match="gone.png: texture image file not found"):
        texture_image(TextureSpec("bitmap", file=tmp_path / "gone.png"), ledger())
    Image.fromarray(np.zeros((64, 64, 3), np.uint8)).save(tmp_path / "big.png")
    with pytest.raises(SceneError):
        texture_image(TextureSpec("bitmap", file=tmp_path / "big.png"), ledger(limit=1000))
