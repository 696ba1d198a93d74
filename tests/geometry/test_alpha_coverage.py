"""Stochastic coverage's uniform: deterministic per (ray, primitive, instance), uniform, and
independent between primitives and between neighbouring rays (chi-square tests at a fixed seed);
scenes without alpha materials compile no coverage code."""
import numpy as np
import pytest
import taichi as ti
from scipy import stats

from renderer.geometry import coverage
from renderer.geometry.mesh_data import MeshData
from renderer.materials.table import MaterialRows, MaterialTable
from renderer.scene.mesh_model import PbrMaterial
from tests.geometry.mesh_helpers import RayShooter, geometry_from

LEVEL = 1e-3  # each chi-square test's significance


@ti.kernel
def _uniforms(o: ti.types.ndarray(), d: ti.types.ndarray(), g: ti.types.ndarray(), instance: ti.types.ndarray(),
              out: ti.types.ndarray()):
    for i in range(o.shape[0]):
        out[i] = coverage.ray_primitive_uniform(ti.math.vec3(o[i, 0], o[i, 1], o[i, 2]),
                                                ti.math.vec3(d[i, 0], d[i, 1], d[i, 2]), g[i], instance[i])


def uniforms(o, d, g, instance):
    out = np.zeros(len(o), np.float32)
    _uniforms(np.ascontiguousarray(o, np.float32), np.ascontiguousarray(d, np.float32),
              np.ascontiguousarray(g, np.int32), np.ascontiguousarray(instance, np.int32), out)
    return out


def camera_rays(n, jitter_seed):
    """The rays of one pixel's samples: one origin, directions a pixel's width apart at most."""
    rng = np.random.default_rng(jitter_seed)
    d = np.array([0.0, 0.0, -1.0]) + rng.uniform(-1e-3, 1e-3, (n, 3)) * [1.0, 1.0, 0.0]
    return np.tile([0.5, 1.0, 4.0], (n, 1)), d / np.linalg.norm(d, axis=1, keepdims=True)


def test_uniform_is_deterministic_uniform_and_independent():
    n = 64000
    o, d = camera_rays(n, 11)
    zero = np.zeros(n, np.int32)
    u = uniforms(o, d, zero + 7, zero - 1)
    np.testing.assert_array_equal(u, uniforms(o, d, zero + 7, zero - 1))
    assert ((u >= 0.0) & (u < 1.0)).all()
    counts = np.histogram(u, bins=64, range=(0.0, 1.0))[0]
    assert stats.chisquare(counts).pvalue > LEVEL
    # The next primitive, and the same primitive in another instance, decide independently.
    for other in (uniforms(o, d, zero + 8, zero - 1), uniforms(o, d, zero + 7, zero + 3)):
        joint = np.histogram2d(u, other, bins=8, range=((0, 1), (0, 1)))[0]
        assert stats.chisquare(joint.ravel()).pvalue > LEVEL


def blend_row(alpha_mode="BLEND", base_alpha=0.3):
    rows = MaterialRows()
    rows.add_pbr(PbrMaterial(name="veil", base_color_factor=(0.0, 0.0, 0.0, base_alpha), alpha_mode=alpha_mode),
                 texture_id=None)
    return MaterialTable(rows)


def test_blend_triangle_stops_a_share_alpha_of_the_rays():
    """One BLEND triangle of alpha 0.3 under 40,000 rays through it: each ray stops with
    probability 0.3 (binomial z-test) and the same ray always decides alike."""
    tri = np.array([[[-1.0, -1.0, 0.0], [3.0, -1.0, 0.0], [-1.0, 3.0, 0.0]]], np.float32)
    data = MeshData(tri_vertices=tri, tri_material=np.zeros(1, np.int32))
    shooter = RayShooter(geometry_from(data, materials=blend_row()))
    rng = np.random.default_rng(4)
    n = 40000
    o = np.concatenate([rng.uniform(-0.5, 0.5, (n, 2)), np.full((n, 1), 2.0)], axis=1)
    d = np.tile([0.0, 0.0, -1.0], (n, 1))
    hits = shooter.closest(o, d)[1] >= 0
    z = (hits.mean() - 0.3) / np.sqrt(0.3 * 0.7 / n)
    assert abs(z) < stats.norm.isf(LEVEL / 2), z
    np.testing.assert_array_equal(shooter.closest(o, d)[1] >= 0, hits)
    np.testing.assert_array_equal(shooter.occluded(o, d) == 1, hits)  # shadow rays agree
    opaque = RayShooter(geometry_from(data, materials=blend_row("OPAQUE")))
    assert (opaque.closest(o, d)[1] >= 0).all()


@pytest.mark.filterwarnings("ignore:.*non-taichi function")  # the trap is plain Python on purpose
def test_scene_without_alpha_compiles_no_coverage_code(monkeypatch):
    def trap(*args):
        raise RuntimeError("coverage code compiled")

    monkeypatch.setattr(coverage, "covered", trap)
    tri = np.array([[[-1.0, -1.0, 0.0], [3.0, -1.0, 0.0], [-1.0, 3.0, 0.0]]], np.float32)
    data = MeshData(tri_vertices=tri, tri_material=np.zeros(1, np.int32))
    o, d = np.array([[0.0, 0.0, 2.0]]), np.array([[0.0, 0.0, -1.0]])
    plain = geometry_from(data, materials=blend_row("OPAQUE"))
    assert not plain.has_alpha and RayShooter(plain).closest(o, d)[1][0] == 0
    with pytest.raises(Exception, match="coverage code compiled"):
        RayShooter(geometry_from(data, materials=blend_row())).closest(o, d)
