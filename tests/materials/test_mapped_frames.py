"""Mitsuba's normal-map frame on the device (renderer/materials/mapped_frames.py), case by case: the
map's normal in the frame (dp/du made orthogonal to n, n x that, n); mirrored where the viewer is
behind it (flip_invalid_normals); seen from behind, in the frame mirrored through the tangent
plane; and the weight: zero where the light is on different sides of the two normals, else the
shadow-terminator term."""
import math

import numpy as np
import pytest
import taichi as ti

from renderer.geometry.interface import Surface
from renderer.materials.kinds import SHADING_FRAME_MAP
from renderer.materials.mapped_frames import mapped_frame, scattering_weight
from renderer.materials.texture_sampler import TextureTable
from renderer.scene.mesh_model import TextureImage
from renderer.scene.textures import WRAP_CODES, pack_atlas

vec3 = ti.math.vec3


def table_of(normal):
    texel = (np.asarray(normal, np.float32) + 1) / 2
    atlas = pack_atlas([TextureImage(np.tile(np.append(texel, 1.0).astype(np.float32), (2, 2, 1)), srgb=False)])
    return TextureTable(atlas, [(atlas.rects[0], WRAP_CODES["repeat"], WRAP_CODES["repeat"], 0, np.eye(3))])


@ti.kernel
def _frame(table: ti.template(), n0: ti.types.ndarray(), dp_du: ti.types.ndarray(), wo: ti.types.ndarray(),
           out: ti.types.ndarray()):
    for _ in range(1):
        n = vec3(n0[0], n0[1], n0[2])
        surface = Surface(n_geo=n, n_shading=n, dp_du=vec3(dp_du[0], dp_du[1], dp_du[2]))
        mapped, tangent, front = mapped_frame(table, 0, SHADING_FRAME_MAP, 1.0, surface, vec3(wo[0], wo[1], wo[2]),
                                              False)
        for c in ti.static(range(3)):
            out[0, c] = mapped[c]
            out[1, c] = tangent[c]
            out[2, c] = front[c]


@ti.kernel
def _weight(n_front: ti.types.ndarray(), n: ti.types.ndarray(), wo: ti.types.ndarray(), wi: ti.types.ndarray(),
            one_sided: ti.i32) -> ti.f32:
    return scattering_weight(vec3(n_front[0], n_front[1], n_front[2]), vec3(n[0], n[1], n[2]),
                             vec3(wo[0], wo[1], wo[2]), vec3(wi[0], wi[1], wi[2]), one_sided != 0)


def frame(normal, wo, n0=(0.0, 0.0, 1.0), dp_du=(2.0, 0.0, 0.5)):
    out = np.zeros((3, 3), np.float32)
    _frame(table_of(normal), np.array(n0, np.float32), np.array(dp_du, np.float32),
           np.array(wo, np.float32) / np.linalg.norm(wo), out)
    return out


S, C = math.sin(0.6), math.cos(0.6)


@pytest.mark.parametrize("wo, expected", [
    ((0.3, 0.2, 1.0), (S, 0.0, C)),  # seen from in front of both normals: the map's normal, x along dp/du
    ((-1.0, 0.0, 0.2), (-S, 0.0, C)),  # behind the mapped normal: its tangential part mirrored
    ((0.3, 0.2, -1.0), (S, 0.0, -C)),  # from behind the surface: the frame mirrored through its plane
])
def test_the_mapped_normal_and_its_flips(wo, expected):
    out = frame((S, 0.0, C), wo)
    np.testing.assert_allclose(out[0], expected, atol=2e-6)
    np.testing.assert_allclose(out[2], (0.0, 0.0, 1.0 if wo[2] > 0 else -1.0), atol=0)
    # the tangent: s0 = dp/du made orthogonal to n0 (+x here), made orthogonal to the mapped normal
    tangent = np.array([1.0, 0.0, 0.0]) - out[0] * out[0, 0]
    np.testing.assert_allclose(out[1], tangent / np.linalg.norm(tangent), atol=2e-6)


def test_y_of_the_map_runs_along_n_cross_dp_du():
    out = frame((0.0, S, C), (0.0, 0.1, 1.0), dp_du=(1.0, 0.0, 0.0))
    np.testing.assert_allclose(out[0], (0.0, S, C), atol=2e-6)  # n x (+x) = +y


def test_the_weight_is_mitsubas_shadowing_term_where_both_sides_agree():
    n = np.array([S, 0.0, C], np.float32)
    up, wo = np.array([0.0, 0.0, 1.0], np.float32), np.array([0.0, 0.0, 1.0], np.float32)
    wi = np.array([math.sin(1.0), 0.0, math.cos(1.0)], np.float32)
    alpha2 = 0.125 * math.tan(0.6) ** 2
    expected = 2.0 / (1.0 + math.sqrt(1.0 + alpha2 * math.tan(1.0) ** 2))
    assert _weight(up, n, wo, wi, 0) == pytest.approx(expected, rel=1e-6)
    below_mapped = np.array([-0.95, 0.0, math.sqrt(1 - 0.95 ** 2)], np.float32)  # above n0, below n
    assert below_mapped @ n < 0 and _weight(up, n, wo, below_mapped, 0) == 0.0
    behind = np.array([-0.9, 0.0, 0.1], np.float32) / np.linalg.norm([-0.9, 0.0, 0.1])
    assert _weight(up, n, behind, wi, 1) == 0.0  # a one-sided material seen from behind its mapped normal
    assert _weight(up, n, behind, wi, 0) > 0.0
