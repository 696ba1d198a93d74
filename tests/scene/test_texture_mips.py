"""Mip-map levels (renderer/scene/texture_mips.py) are exact area averages of the light the level
above shows, in every storage kind, and the atlas packs them beside their images."""
import numpy as np
import pytest

from renderer.scene.mesh_model import TextureImage
from renderer.scene.srgb import SRGB8_TO_LINEAR
from renderer.scene.texture_mips import area_halve, linear_to_srgb, mip_chain, srgb8_codes
from renderer.scene.textures import level_rect, pack_atlas, sample_bilinear, sample_trilinear


def test_levels_halve_down_to_one_texel():
    image = TextureImage(np.random.default_rng(0).random((5, 7, 4)).astype(np.float32))
    assert [level.shape for level in mip_chain(image)] == [(2, 3), (1, 1)]
    assert mip_chain(TextureImage(np.ones((1, 1, 4), np.float32))) == []
    assert [level.shape for level in mip_chain(TextureImage(np.ones((1, 8, 4), np.float32)))] == [(1, 4), (1, 2), (1, 1)]


def test_area_averages_are_exact_for_even_and_odd_sizes():
    rng = np.random.default_rng(1)
    even = rng.random((4, 6, 4))
    halved = area_halve(area_halve(even, 0), 1)
    np.testing.assert_allclose(halved, even.reshape(2, 2, 3, 2, 4).mean(axis=(1, 3)), rtol=1e-12)
    odd = rng.random((5,))
    # width 5 -> 2: texels 0, 1 and half of 2; half of 2, 3 and 4
    expected = [(odd[0] + odd[1] + 0.5 * odd[2]) / 2.5, (0.5 * odd[2] + odd[3] + odd[4]) / 2.5]
    np.testing.assert_allclose(area_halve(odd, 0), expected, rtol=1e-12)


@pytest.mark.parametrize("dtype", [np.uint8, np.float16, np.float32])
def test_constant_images_stay_constant_and_the_top_level_is_the_mean(dtype):
    value = np.array([51, 102, 204, 255]) if dtype == np.uint8 else np.array([0.2, 0.4, 0.8, 1.0])
    image = TextureImage(np.broadcast_to(value, (7, 13, 4)).astype(dtype), srgb=True)
    for level in mip_chain(image):
        np.testing.assert_array_equal(level.pixels, np.broadcast_to(value, level.pixels.shape).astype(dtype))
    rng = np.random.default_rng(2)
    floats = TextureImage(rng.random((8, 8, 4)).astype(np.float32))
    np.testing.assert_allclose(mip_chain(floats)[-1].pixels[0, 0], floats.pixels.mean(axis=(0, 1)), rtol=1e-5)


def test_srgb_colours_are_averaged_in_linear_light():
    black_white = np.zeros((2, 2, 4), np.uint8)
    black_white[0, 0, :3] = black_white[1, 1, :3] = 255
    black_white[..., 3] = 255
    top = mip_chain(TextureImage(black_white, srgb=True))[0].pixels[0, 0]
    # half the light of white, encoded: code 188 (0.5 in linear light), not 128 (the codes' mean)
    assert top[0] == int(np.rint(linear_to_srgb(0.5) * 255)) == 188
    assert abs(SRGB8_TO_LINEAR[top[0]] - 0.5) < 0.005
    assert top[3] == 255  # alpha is never colour-decoded
    data = mip_chain(TextureImage(black_white, srgb=False))[0].pixels[0, 0]
    assert data[0] == 128  # read as data, the same bytes average as numbers


def test_the_atlas_packs_each_chain_once_per_decoding():
    rng = np.random.default_rng(3)
    pixels = rng.integers(0, 256, (6, 10, 4), dtype=np.uint8)
    images = [TextureImage(pixels, srgb=True), TextureImage(pixels, srgb=False), TextureImage(pixels, srgb=True),
              TextureImage(rng.random((4, 4, 4)).astype(np.float32))]
    atlas = pack_atlas(images, mipmaps=True)
    assert atlas.level_span.tolist() == [[0, 3], [3, 3], [0, 3], [6, 2]]
    for index, image in enumerate(images):
        for level, expected in enumerate(mip_chain(image), start=1):
            x, y, w, h, storage, srgb = (int(v) for v in level_rect(atlas, index, level))
            assert (h, w) == expected.shape and srgb == int(image.srgb)
            np.testing.assert_array_equal(atlas.pages[storage][y:y + h, x:x + w], expected.pixels)
    # without mipmaps the atlas is what it was: the images alone
    plain = pack_atlas(images)
    assert len(plain.level_rects) == 0 and len(plain.level_span) == 0
    with pytest.raises(ValueError, match="mip levels 0..3"):
        level_rect(atlas, 0, 4)


def test_trilinear_reference_blends_the_two_levels_around_the_lod():
    rng = np.random.default_rng(4)
    atlas = pack_atlas([TextureImage(rng.random((8, 8, 4)).astype(np.float32))], mipmaps=True)
    uv = rng.random((50, 2))
    level1 = sample_bilinear(atlas, 0, uv, level=1)
    level2 = sample_bilinear(atlas, 0, uv, level=2)
    np.testing.assert_allclose(sample_trilinear(atlas, 0, uv, 1.25), 0.75 * level1 + 0.25 * level2, rtol=1e-6)
    np.testing.assert_array_equal(sample_trilinear(atlas, 0, uv, -3.0), sample_bilinear(atlas, 0, uv))
    top = sample_trilinear(atlas, 0, uv, 99.0)  # clamped to the 1x1 level: the image's mean everywhere
    np.testing.assert_allclose(top, np.broadcast_to(atlas.texels(0).mean(axis=(0, 1)), top.shape), rtol=1e-5)


def test_srgb_codes_are_the_rounded_curve_of_every_linear_value():
    linear = np.concatenate([np.linspace(0.0, 1.0, 200001), SRGB8_TO_LINEAR, [-0.5, 2.0]])
    expected = np.rint(np.clip(linear_to_srgb(linear), 0.0, 1.0) * 255.0)
    codes = srgb8_codes(linear)
    assert np.count_nonzero(codes != expected) <= 4  # values within float32 rounding of an edge may differ
    np.testing.assert_array_equal(srgb8_codes(SRGB8_TO_LINEAR), np.arange(256))  # every code's own value
