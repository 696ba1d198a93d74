"""The device texture sampler agrees with the numpy reference of the atlas layout."""
import numpy as np
import pytest
import taichi as ti

from renderer.materials.texture_sampler import TextureTable
from renderer.scene.mesh_model import uv_transform_matrix
from renderer.scene.textures import WRAP_CODES, pack_atlas, sample_bilinear


@ti.kernel
def _sample(table: ti.template(), slot: ti.i32, uv: ti.types.ndarray(), out: ti.types.ndarray()):
    for i in range(uv.shape[0]):
        v = table.sample(slot, ti.math.vec2(uv[i, 0], uv[i, 1]), ti.math.vec2(0.0))
        for c in ti.static(range(4)):
            out[i, c] = v[c]


@pytest.mark.parametrize("wrap_s, wrap_t", [("repeat", "repeat"), ("clamp", "mirror"), ("mirror", "clamp")])
def test_sampler_matches_reference(wrap_s, wrap_t):
    rng = np.random.default_rng(4)
    images = [rng.uniform(0, 1, (5, 7, 4)).astype(np.float32), rng.uniform(0, 1, (16, 9, 4)).astype(np.float32),
              rng.uniform(0, 1, (3, 3, 4)).astype(np.float32)]
    atlas = pack_atlas(images)
    matrix = uv_transform_matrix(offset=(0.3, -0.2), rotation=0.4, scale=(1.7, 0.6))
    slots = [(atlas.rects[i], WRAP_CODES[wrap_s], WRAP_CODES[wrap_t], 0, matrix) for i in range(3)]
    table = TextureTable(atlas.atlas, slots)
    uv = rng.uniform(-2.5, 3.5, (4000, 2)).astype(np.float32)
    for slot in range(3):
        out = np.zeros((len(uv), 4), np.float32)
        _sample(table, slot, uv, out)
        ref = sample_bilinear(atlas, slot, uv, wrap_s, wrap_t, matrix)
        # f32 UV arithmetic on the device against f64 in the reference: texel positions agree to
        # ~1e-5 texel, so values agree to that times the largest texel difference (< 1).
        np.testing.assert_allclose(out, ref, atol=2e-4)
