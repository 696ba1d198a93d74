"""The texture atlas and its numpy reference sampler (renderer/scene/textures.py), and the
KHR_texture_transform matrix (renderer/scene/mesh_model.py)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from renderer.scene.mesh_model import TextureImage, uv_transform_matrix
from renderer.scene.model_formats import load_mesh_asset
from renderer.scene.srgb import srgb_to_linear
from renderer.scene.textures import STORE_FLOAT, STORE_HALF, STORE_RGBA8, as_rgba, pack_atlas, sample_bilinear, wrap_index
from tests.scene.model_file_helpers import DATA


def random_images(seed=3):
    rng = np.random.default_rng(seed)
    shapes = [(5, 7, 3), (16, 4, 4), (1, 1, 1), (9, 9), (3, 12, 2), (30, 2, 3), (2, 30, 4)]
    return [rng.random(s).astype(np.float32) for s in shapes]


def mixed_images(seed=4):
    """8-bit, half and float images, one 8-bit array used twice (as data and as colour)."""
    rng = np.random.default_rng(seed)
    shared = rng.integers(0, 256, (6, 5, 4), dtype=np.uint8)
    return [TextureImage(shared), TextureImage(rng.integers(0, 256, (3, 9, 4), dtype=np.uint8)),
            TextureImage(shared, srgb=True),
            TextureImage(rng.random((4, 4, 4)).astype(np.float16), srgb=True),
            TextureImage(rng.random((2, 7, 4)).astype(np.float32))]


def test_atlas_no_overlap_and_exact_recovery():
    images = random_images()
    pad = 2
    tex = pack_atlas(images, padding=pad)
    page = tex.pages[STORE_FLOAT]
    assert page.dtype == np.float32 and page.shape[2] == 4 and tex.rects.dtype == np.int32
    owner = np.full(page.shape[:2], -1)
    for i, (x, y, w, h, storage, srgb) in enumerate(tex.rects):
        assert (storage, srgb) == (STORE_FLOAT, 0)
        assert x >= pad and y >= pad and x + w + pad <= page.shape[1] and y + h + pad <= page.shape[0]
        region = owner[y - pad:y + h + pad, x - pad:x + w + pad]
        assert (region == -1).all(), f"image {i} overlaps another (padding included)"
        region[:] = i
        np.testing.assert_array_equal(tex.texels(i), as_rgba(images[i]))
        assert (w, h) == (images[i].shape[1], images[i].shape[0])


def test_atlas_keeps_each_storage_and_stores_shared_pixels_once():
    images = mixed_images()
    tex = pack_atlas(images, padding=1)
    assert [int(r[4]) for r in tex.rects] == [STORE_RGBA8, STORE_RGBA8, STORE_RGBA8, STORE_HALF, STORE_FLOAT]
    assert [int(r[5]) for r in tex.rects] == [0, 0, 1, 1, 0]
    np.testing.assert_array_equal(tex.rects[0, :5], tex.rects[2, :5])  # one rectangle, two decodings
    for i, image in enumerate(images):
        assert tex.texels(i).dtype == image.pixels.dtype
        np.testing.assert_array_equal(tex.texels(i), image.pixels)
    # the 8-bit page holds the two distinct 8-bit images only: (6+2)x(5+2) and (3+2)x(9+2) texels
    assert tex.pages[STORE_RGBA8].dtype == np.uint8
    assert np.count_nonzero(tex.pages[STORE_RGBA8].any(axis=2)) <= 8 * 7 + 5 * 11
    assert tex.nbytes == sum(tex.pages[s].nbytes for s in (STORE_RGBA8, STORE_HALF, STORE_FLOAT))
    only_bytes = pack_atlas(images[:3])
    assert only_bytes.storages == {STORE_RGBA8}
    assert only_bytes.nbytes == only_bytes.pages[STORE_RGBA8].nbytes  # unused pages cost nothing
    for storage in (STORE_HALF, STORE_FLOAT):
        assert only_bytes.pages[storage].shape == (1, 1, 4)


def test_atlas_padding_replicates_edges():
    images = random_images()
    pad = 3
    tex = pack_atlas(images, padding=pad)
    for i, (x, y, w, h, storage, _) in enumerate(tex.rects):
        padded = tex.pages[storage][y - pad:y + h + pad, x - pad:x + w + pad]
        image = as_rgba(images[i])
        np.testing.assert_array_equal(padded, np.pad(image, ((pad, pad), (pad, pad), (0, 0)), mode="edge"))
        np.testing.assert_array_equal(padded[0, 0], image[0, 0])  # corners replicate the corner


def test_atlas_is_roughly_square_and_handles_empty():
    tex = pack_atlas(random_images())
    width, height = tex.page_size(STORE_FLOAT)
    assert 0.25 < width / height < 4
    empty = pack_atlas([])
    assert all(page.shape == (1, 1, 4) for page in empty.pages.values())
    assert empty.rects.shape == (0, 6) and empty.nbytes == 0
    with pytest.raises(ValueError):
        pack_atlas(random_images(), width=4)


def test_reference_sampler_texel_centres_and_wrapping():
    images = random_images()
    tex = pack_atlas(images, padding=1)
    index = 0
    image = as_rgba(images[index])
    h, w = image.shape[:2]
    j, i = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
    centres = np.stack([(i + 0.5) / w, (j + 0.5) / h], -1)
    np.testing.assert_allclose(sample_bilinear(tex, index, centres), image, atol=1e-6)
    # repeat: shifting by whole periods changes nothing; across the seam texels w-1 and 0 blend
    np.testing.assert_allclose(sample_bilinear(tex, index, centres + [3.0, -2.0]), image, atol=1e-5)
    seam = sample_bilinear(tex, index, np.array([1.0, (0.5) / h]))
    np.testing.assert_allclose(seam, 0.5 * (image[0, w - 1] + image[0, 0]), atol=1e-6)
    # clamp: beyond the edge is the edge texel
    np.testing.assert_allclose(sample_bilinear(tex, index, np.array([-5.0, 0.5 / h]), "clamp", "clamp"),
                               image[0, 0], atol=1e-6)
    # mirror: u in (1, 2) reads the image backwards
    mirrored = sample_bilinear(tex, index, centres + [1.0, 0.0], "mirror", "repeat")
    np.testing.assert_allclose(mirrored, image[:, ::-1], atol=1e-6)
    np.testing.assert_array_equal(wrap_index(np.arange(-3, 7), 3, "mirror"),
                                  [2, 1, 0, 0, 1, 2, 2, 1, 0, 0])
    np.testing.assert_array_equal(wrap_index(np.arange(-3, 4), 3, "repeat"), [0, 1, 2, 0, 1, 2, 0])


def test_reference_sampler_decodes_each_tap_before_blending():
    """Half-way between a black and a white sRGB texel the lookup reads 0.5 (the mean of the
    decoded values), not the decoded mean of the codes (0.214); alpha is never decoded."""
    pixels = np.array([[[0, 0, 0, 0], [255, 255, 255, 255]]], dtype=np.uint8)
    tex = pack_atlas([TextureImage(pixels, srgb=True), TextureImage(pixels)])
    for index in (0, 1):
        middle = sample_bilinear(tex, index, np.array([0.5, 0.5]), "clamp", "clamp")
        np.testing.assert_allclose(middle, [0.5, 0.5, 0.5, 0.5], atol=1e-6)
    grey = np.full((1, 1, 4), 128, dtype=np.uint8)
    tex = pack_atlas([TextureImage(grey, srgb=True)])
    value = sample_bilinear(tex, 0, np.array([0.3, 0.7]))
    np.testing.assert_allclose(value, [*srgb_to_linear([128 / 255.0] * 3), 128 / 255.0], atol=1e-7)
    for image in mixed_images():  # at texel centres: exactly TextureImage.linear()
        tex = pack_atlas([image])
        h, w = image.shape
        j, i = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
        centres = np.stack([(i + 0.5) / w, (j + 0.5) / h], -1)
        np.testing.assert_allclose(sample_bilinear(tex, 0, centres), image.linear(), atol=1e-6)


def test_texture_transform_spec_example():
    """KHR_texture_transform: offset (0, 1), rotation 90 deg, scale 0.5 = lower-left quadrant."""
    m = uv_transform_matrix((0.0, 1.0), math.pi / 2, (0.5, 0.5))
    corners = np.array([[0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], dtype=np.float64)
    uv = corners @ m.T
    assert (uv[:, 0] > -1e-9).all() and (uv[:, 0] < 0.5 + 1e-9).all()
    assert (uv[:, 1] > 0.5 - 1e-9).all() and (uv[:, 1] < 1.0 + 1e-9).all()


def test_atlas_from_a_loaded_asset():
    quad = load_mesh_asset(DATA / "textured_quad.gltf")
    tex = pack_atlas(quad.images)
    m = quad.materials[0]
    ref = m.base_color_texture
    np.testing.assert_array_equal(tex.texels(ref.texture), quad.images[ref.texture].pixels)
    assert tex.rects[ref.texture, 5] == 1  # base colour: decoded as sRGB in the lookup
    # the sampler contract: slot matrix, then wrap modes, then bilinear inside the rectangle
    value = sample_bilinear(tex, ref.texture, np.array([0.3, 0.6]), ref.wrap_s, ref.wrap_t, ref.matrix)
    assert value.shape == (4,) and np.isfinite(value).all()
