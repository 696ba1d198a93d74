"""Mip-mapped lookups on the device: trilinear and anisotropic filtering agree with the numpy
reference at the level the footprint asks for, and the footprint of a ray cone on a surface is the
ellipse it cuts, in texture coordinates (renderer/geometry/texture_footprint.py)."""
import math

import numpy as np
import pytest
import taichi as ti

from renderer.geometry.texture_footprint import MAX_STRETCH, footprint_shrink, uv_footprint
from renderer.materials.texture_sampler import MAX_ANISOTROPY, TextureTable
from renderer.scene.mesh_model import TextureImage, uv_transform_matrix
from renderer.scene.textures import WRAP_CODES, pack_atlas, sample_trilinear

vec3 = ti.math.vec3


@ti.kernel
def _filtered(table: ti.template(), slot: ti.i32, uv: ti.types.ndarray(), fp: ti.types.ndarray(),
              out: ti.types.ndarray()):
    for i in range(uv.shape[0]):
        v = table.filtered(slot, ti.math.vec2(uv[i, 0], uv[i, 1]), ti.math.vec4(fp[i, 0], fp[i, 1], fp[i, 2], fp[i, 3]))
        for c in ti.static(range(4)):
            out[i, c] = v[c]


def table_of(images, filtering, wrap=("repeat", "repeat"), matrix=np.eye(3)):
    atlas = pack_atlas(images, mipmaps=True)
    slots = [((*atlas.rects[i], *atlas.level_span[i]), WRAP_CODES[wrap[0]], WRAP_CODES[wrap[1]], 0, matrix)
             for i in range(len(images))]
    return atlas, TextureTable(atlas, slots, filtering)


def images(rng):
    return [TextureImage(rng.integers(0, 256, (32, 16, 4), dtype=np.uint8), srgb=True),
            TextureImage(rng.uniform(0, 2, (9, 24, 4)).astype(np.float16)),
            TextureImage(rng.random((16, 16, 4)).astype(np.float32))]


@pytest.mark.parametrize("wrap", [("repeat", "repeat"), ("clamp", "mirror")])
def test_trilinear_matches_the_reference_at_the_footprints_level(wrap):
    rng = np.random.default_rng(7)
    matrix = uv_transform_matrix(offset=(0.1, 0.3), rotation=0.0, scale=(1.5, 0.75))
    atlas, table = table_of(images(rng), "trilinear", wrap, matrix)
    assert table.filters
    n = 3000
    uv = rng.uniform(-1.5, 2.5, (n, 2)).astype(np.float32)
    for slot, image in enumerate(images(rng)):
        h, w = image.shape
        # the footprint's longer axis along u is `width` level-0 texels (through the matrix's 1.5)
        width = 2.0 ** rng.uniform(-1.0, 7.0, n)
        shorter = width * rng.uniform(0.0, 1.0, n)
        fp = np.stack([width / (w * 1.5), np.zeros(n), np.zeros(n), shorter / (h * 0.75)], -1).astype(np.float32)
        out = np.zeros((n, 4), np.float32)
        _filtered(table, slot, uv, fp, out)
        lods = np.log2(np.maximum(np.maximum(width, shorter), 1.0))
        ref = np.stack([sample_trilinear(atlas, slot, uv[i], lods[i], *wrap, matrix) for i in range(n)])
        np.testing.assert_allclose(out, ref, atol=2e-3, err_msg=repr(image))


def test_anisotropic_probes_along_the_longer_axis_at_the_shorter_ones_level():
    rng = np.random.default_rng(8)
    image = TextureImage(rng.random((64, 64, 4)).astype(np.float32))
    atlas, table = table_of([image], "anisotropic")
    cases = [(16.0, 4.0), (40.0, 2.0), (3.0, 3.0), (0.5, 0.25), (64.0, 0.0)]
    uv = rng.random((len(cases), 2)).astype(np.float32)
    direction = np.array([0.6, 0.8])
    fp = np.array([[*(direction * major / 64), *(np.array([-0.8, 0.6]) * minor / 64)] for major, minor in cases],
                  np.float32)
    out = np.zeros((len(cases), 4), np.float32)
    _filtered(table, 0, uv, fp, out)
    for i, (major, minor) in enumerate(cases):
        minor = max(minor, major / MAX_ANISOTROPY)
        probes = min(math.ceil(major / minor - 1e-3), MAX_ANISOTROPY) if major > 1.0 else 1  # within a texel: one
        lod = math.log2(max(minor, 1.0)) if major > 1.0 else 0.0
        offsets = [(p - 0.5 * (probes - 1)) / probes for p in range(probes)]
        ref = np.mean([sample_trilinear(atlas, 0, uv[i] + o * fp[i, :2], lod) for o in offsets], axis=0)
        np.testing.assert_allclose(out[i], ref, atol=2e-4, err_msg=f"major {major}, minor {minor}")


def test_filtering_needs_levels_and_a_known_name():
    image = TextureImage(np.ones((4, 4, 4), np.float32))
    plain = pack_atlas([image])
    assert not TextureTable(plain, [(plain.rects[0], 0, 0, 0, np.eye(3))], "trilinear").filters
    assert not TextureTable(None, [], "anisotropic").filters
    with pytest.raises(ValueError, match="unknown texture filter 'bicubic'"):
        TextureTable(plain, [(plain.rects[0], 0, 0, 0, np.eye(3))], "bicubic")


@ti.kernel
def _footprints(rows: ti.types.ndarray(), out: ti.types.ndarray()):
    for i in range(rows.shape[0]):
        d = vec3(rows[i, 0], rows[i, 1], rows[i, 2])
        n = vec3(rows[i, 3], rows[i, 4], rows[i, 5])
        du = vec3(rows[i, 7], rows[i, 8], rows[i, 9])
        dv = vec3(rows[i, 10], rows[i, 11], rows[i, 12])
        f = uv_footprint(d, n, rows[i, 6], du, dv)
        for c in ti.static(range(4)):
            out[i, c] = f[c]


def footprints(*rows):
    rows = np.array(rows, np.float32)
    out = np.zeros((len(rows), 4), np.float32)
    _footprints(rows, out)
    return out


def test_a_cone_head_on_covers_its_width_in_both_directions():
    # a plane z = 0 with u along x at 2 m per unit and v along y at 4 m per unit, a cone 0.1 m wide
    out = footprints([0, 0, -1, 0, 0, 1, 0.1, 2, 0, 0, 0, 4, 0])[0]
    a, b = out[:2], out[2:]
    np.testing.assert_allclose(sorted(np.abs(a) + np.abs(b)), [0.025, 0.05], rtol=1e-5)
    assert abs(a @ b) < 1e-9  # the two axes stay perpendicular in uv here


def test_a_grazing_cone_stretches_along_the_ray():
    theta = math.radians(75.0)  # from the normal
    d = [math.sin(theta), 0.0, -math.cos(theta)]
    out = footprints([*d, 0, 0, 1, 0.1, 1, 0, 0, 0, 1, 0])[0]
    np.testing.assert_allclose(out[:2], [0.0, 0.1], atol=1e-6)  # across the ray: its width, along v
    np.testing.assert_allclose(out[2:], [0.1 / math.cos(theta), 0.0], rtol=1e-5)  # along it: width / cos
    parallel = footprints([1, 0, 0, 0, 0, 1, 0.1, 1, 0, 0, 0, 1, 0])[0]  # exactly in the plane
    assert np.isfinite(parallel).all() and abs(parallel[2]) == pytest.approx(0.1 * MAX_STRETCH, rel=1e-5)


def test_no_cone_or_a_degenerate_parametrisation_has_no_footprint():
    out = footprints([0, 0, -1, 0, 0, 1, 0.0, 1, 0, 0, 0, 1, 0],  # no cone
                     [0, 0, -1, 0, 0, 1, 0.1, 1, 0, 0, 2, 0, 0],  # dp/du parallel to dp/dv
                     [0, 0, -1, 0, 0, 1, 0.1, 0, 0, 0, 0, 0, 0])  # no partials at all
    np.testing.assert_array_equal(out, 0.0)


@ti.kernel
def _shrinks(out: ti.types.ndarray()):
    for i in range(out.shape[0]):
        out[i] = footprint_shrink(i)


def test_the_cone_narrows_as_the_spacing_of_a_pixels_samples():
    out = np.zeros(64, np.float32)
    _shrinks(out)
    np.testing.assert_allclose(out, 1.0 / np.sqrt(np.arange(64) + 1.0), rtol=1e-6)
