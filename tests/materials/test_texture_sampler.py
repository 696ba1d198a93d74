"""The device texture sampler agrees with the numpy reference of the atlas layout, for every
storage kind (8-bit, half, float) and both decodings (linear data, sRGB colour)."""
import numpy as np
import pytest
import taichi as ti

from renderer.materials.texture_sampler import TextureTable
from renderer.scene.mesh_model import TextureImage, uv_transform_matrix
from renderer.scene.textures import WRAP_CODES, pack_atlas, sample_bilinear, wrap_index


@ti.kernel
def _sample(table: ti.template(), slot: ti.i32, uv: ti.types.ndarray(), out: ti.types.ndarray()):
    for i in range(uv.shape[0]):
        v = table.sample(slot, ti.math.vec2(uv[i, 0], uv[i, 1]), ti.math.vec2(0.0))
        for c in ti.static(range(4)):
            out[i, c] = v[c]


def entries(rng):
    """Images of every storage kind, each read as data and as colour (one pixel array each)."""
    bytes_ = rng.integers(0, 256, (5, 7, 4), dtype=np.uint8)
    half = rng.uniform(0, 1.2, (16, 9, 4)).astype(np.float16)  # > 1 too: an HDR-ish half texture
    half[0, 0, 0] = np.float16(3e-6)  # a subnormal half
    full = rng.uniform(0, 1, (3, 3, 4)).astype(np.float32)
    images = []
    for pixels in (bytes_, half, full):
        images += [TextureImage(pixels, srgb=False), TextureImage(pixels, srgb=True)]
    return images


@pytest.mark.parametrize("wrap_s, wrap_t", [("repeat", "repeat"), ("clamp", "mirror"), ("mirror", "clamp")])
def test_sampler_matches_reference(wrap_s, wrap_t):
    rng = np.random.default_rng(4)
    images = entries(rng)
    atlas = pack_atlas(images)
    assert atlas.storages == {0, 1, 2}
    matrix = uv_transform_matrix(offset=(0.3, -0.2), rotation=0.4, scale=(1.7, 0.6))
    slots = [(atlas.rects[i], WRAP_CODES[wrap_s], WRAP_CODES[wrap_t], 0, matrix) for i in range(len(images))]
    table = TextureTable(atlas, slots)
    uv = rng.uniform(-2.5, 3.5, (4000, 2)).astype(np.float32)
    for slot in range(len(images)):
        out = np.zeros((len(uv), 4), np.float32)
        _sample(table, slot, uv, out)
        ref = sample_bilinear(atlas, slot, uv, wrap_s, wrap_t, matrix)
        # f32 UV arithmetic on the device against f64 in the reference: texel positions agree to
        # ~1e-5 texel, so values agree to that times the largest texel difference (< 2 here).
        np.testing.assert_allclose(out, ref, atol=3e-4, err_msg=repr(images[slot]))


def test_sampler_reads_texel_centres_exactly():
    """At texel centres the device returns each decoded texel: bytes through the sRGB table,
    halves bit-exactly converted (subnormals included)."""
    rng = np.random.default_rng(5)
    images = entries(rng)
    atlas = pack_atlas(images)
    slots = [(atlas.rects[i], WRAP_CODES["clamp"], WRAP_CODES["clamp"], 0, np.eye(3)) for i in range(len(images))]
    table = TextureTable(atlas, slots)
    for slot, image in enumerate(images):
        h, w = image.shape
        j, i = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
        uv = np.stack([(i + 0.5) / w, (j + 0.5) / h], -1).reshape(-1, 2).astype(np.float32)
        out = np.zeros((len(uv), 4), np.float32)
        _sample(table, slot, uv, out)
        np.testing.assert_allclose(out.reshape(h, w, 4), image.linear(), rtol=2e-6, atol=1e-7,
                                   err_msg=repr(image))


def test_only_used_storage_kinds_are_uploaded():
    rng = np.random.default_rng(6)
    only_bytes = TextureImage(rng.integers(0, 256, (4, 4, 4), dtype=np.uint8), srgb=True)
    atlas = pack_atlas([only_bytes])
    table = TextureTable(atlas, [(atlas.rects[0], 0, 0, 0, np.eye(3))])
    assert table.storages == {0}
    assert table.half.shape == (1, 1) and table.full.shape == (1, 1)
    assert table.rgba8.shape == atlas.pages[0].shape[:2]


@pytest.mark.parametrize("wrap", ["repeat", "clamp", "mirror"])
def test_nearest_slots_read_the_texel_under_the_point(wrap):
    """A slot with nearest filtering returns the texel whose cell holds the (transformed, wrapped)
    point, exactly; a bilinear slot of the same table still blends."""
    rng = np.random.default_rng(8)
    pixels = rng.uniform(0, 1, (3, 5, 4)).astype(np.float32)
    atlas = pack_atlas([TextureImage(pixels)])
    matrix = uv_transform_matrix(offset=(0.1, 0.2), rotation=0.3, scale=(2.0, 1.5))
    code = WRAP_CODES[wrap]
    table = TextureTable(atlas, [(atlas.rects[0], code, code, 0, matrix, True),
                                 (atlas.rects[0], code, code, 0, matrix, False)])
    uv = rng.uniform(-2.0, 3.0, (3000, 2)).astype(np.float32)
    out = np.zeros((len(uv), 4), np.float32)
    _sample(table, 0, uv, out)
    moved = np.c_[uv, np.ones(len(uv))] @ np.asarray(matrix, np.float64).T
    i = wrap_index(np.floor(moved[:, 0] * 5).astype(np.int64), 5, wrap)
    j = wrap_index(np.floor(moved[:, 1] * 3).astype(np.int64), 3, wrap)
    # f32 against f64 UVs: a point within ~1e-5 of a cell edge may land in the neighbour.
    edge = np.minimum(np.abs(moved[:, 0] * 5 - np.round(moved[:, 0] * 5)),
                      np.abs(moved[:, 1] * 3 - np.round(moved[:, 1] * 3))) < 1e-4
    np.testing.assert_array_equal(out[~edge], pixels[j, i][~edge])
    blended = np.zeros_like(out)
    _sample(table, 1, uv, blended)
    assert np.abs(blended - out).max() > 0.05
