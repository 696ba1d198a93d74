"""The device texture sampler's gradient (bump maps' dh/du, dh/dv) against central differences of
the numpy reference lookup, with a uv transform, every storage kind and both decodings; nearest
filtering has none."""
import numpy as np
import taichi as ti

from renderer.materials.texture_sampler import TextureTable
from renderer.scene.mesh_model import TextureImage, uv_transform_matrix
from renderer.scene.textures import WRAP_CODES, pack_atlas, sample_bilinear


@ti.kernel
def _gradient(table: ti.template(), slot: ti.i32, uv: ti.types.ndarray(), out: ti.types.ndarray()):
    for i in range(uv.shape[0]):
        d_du, d_dv = table.gradient(slot, ti.math.vec2(uv[i, 0], uv[i, 1]), ti.math.vec2(0.0))
        for c in ti.static(range(4)):
            out[i, 0, c] = d_du[c]
            out[i, 1, c] = d_dv[c]


def _images(rng):
    pixels8 = rng.integers(0, 256, (6, 5, 4), dtype=np.uint8)
    half = rng.uniform(0, 1.5, (7, 9, 4)).astype(np.float16)
    full = rng.uniform(0, 1, (4, 4, 4)).astype(np.float32)
    return [TextureImage(p, srgb=s) for p in (pixels8, half, full) for s in (False, True)]


def _inside_cells(uv, matrix, shape, margin):
    """The uvs whose texel-space position is at least `margin` from a cell edge (the bilinear
    lookup's derivative jumps across them)."""
    h, w = shape[:2]
    st = uv @ matrix[:2, :2].T + matrix[:2, 2]
    s, t = st[:, 0] * w - 0.5, st[:, 1] * h - 0.5
    fs, ft = s - np.floor(s), t - np.floor(t)
    return (fs > margin) & (fs < 1 - margin) & (ft > margin) & (ft < 1 - margin)


def test_gradient_matches_central_differences_of_the_bilinear_lookup():
    rng = np.random.default_rng(11)
    images = _images(rng)
    atlas = pack_atlas(images)
    matrix = uv_transform_matrix(offset=(0.2, -0.1), rotation=0.5, scale=(1.3, 0.7))
    slots = [(atlas.rects[i], WRAP_CODES["repeat"], WRAP_CODES["mirror"], 0, matrix) for i in range(len(images))]
    table = TextureTable(atlas, slots)
    uv = rng.uniform(-1.5, 2.5, (3000, 2))
    step = 1e-5
    for slot, image in enumerate(images):
        keep = _inside_cells(uv, matrix, image.shape, margin=0.01)
        points = uv[keep]
        out = np.zeros((len(points), 2, 4), np.float32)
        _gradient(table, slot, points.astype(np.float32), out)
        for axis in range(2):
            offset = np.zeros(2)
            offset[axis] = step
            # Along any uv direction the bilinear lookup is quadratic inside a cell: the central
            # difference is its derivative exactly (to f64 rounding).
            expected = (sample_bilinear(atlas, slot, points + offset, "repeat", "mirror", matrix).astype(np.float64)
                        - sample_bilinear(atlas, slot, points - offset, "repeat", "mirror", matrix)) / (2 * step)
            scale = np.abs(expected).max()
            # f32 uvs on the device: the cell fractions agree to ~1e-6, the derivative to that
            # times its own rate of change (a few texel differences per texel).
            np.testing.assert_allclose(out[:, axis], expected, atol=2e-3 * scale, err_msg=f"slot {slot}, axis {axis}")
        assert np.abs(out).max() > 0.1  # a real gradient was measured


def test_a_nearest_texture_has_no_gradient():
    rng = np.random.default_rng(12)
    image = TextureImage(rng.uniform(0, 1, (4, 4, 4)).astype(np.float32), srgb=False)
    atlas = pack_atlas([image])
    table = TextureTable(atlas, [(atlas.rects[0], WRAP_CODES["repeat"], WRAP_CODES["repeat"], 0, np.eye(3), True)])
    out = np.ones((50, 2, 4), np.float32)
    _gradient(table, 0, rng.uniform(0, 1, (50, 2)).astype(np.float32), out)
    assert (out == 0.0).all()
