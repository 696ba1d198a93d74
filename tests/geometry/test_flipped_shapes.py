"""Spheres and quads with their normals turned over (MeshData.sphere_flipped / quad_flipped, Mitsuba's
flip_normals): hits see the other side as the front, with the same points and texture coordinates;
emitter samples carry the normal their hits have, with the same densities; light selection's cone
axis of a quad turns with it; back-face culling culls the other side; and geometry without a
flipped shape compiles none of it."""
import numpy as np
import pytest
import taichi as ti

from renderer.geometry.mesh_data import MeshData
from tests.geometry.mesh_helpers import SurfaceProbe, geometry_from

vec3 = ti.math.vec3
# Two spheres and two quads side by side along x; the second of each is turned over.
SPHERES = np.array([[0.0, 0.0, 0.0, 1.0], [3.0, 0.0, 0.0, 1.0]], np.float32)
QUADS = np.array([[[-0.5, 3.0, -0.5], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]],  # faces +y (edge u x edge v)
                  [[2.5, 3.0, -0.5], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]], np.float32)


def data(flipped=True) -> MeshData:
    return MeshData(spheres=SPHERES, sphere_material=np.zeros(2, np.int32), quads=QUADS,
                    quad_material=np.zeros(2, np.int32), sphere_flipped=np.array([False, flipped]),
                    quad_flipped=np.array([False, flipped]))


def test_hits_turn_their_front_over_and_keep_points_and_texture_coordinates(taichi_runtime):
    # From above (+y, onto the quads' +y faces and the spheres' tops) and from below.
    origins = np.array([[0.2, 5.0, 0.1], [3.2, 5.0, 0.1], [0.2, -5.0, 0.1], [3.2, -5.0, 0.1],
                        [0.1, 5.0, 0.2], [3.1, 5.0, 0.2]], np.float32)
    directions = np.array([[0, -1, 0], [0, -1, 0], [0, 1, 0], [0, 1, 0], [0, -1, 0], [0, -1, 0]], np.float32)
    # (the quads at y = 3 lie above the spheres: rays from above meet them first)
    out = SurfaceProbe(geometry_from(data())).shoot(origins, directions)
    plain = SurfaceProbe(geometry_from(data(flipped=False))).shoot(origins, directions)
    assert (out[:, SurfaceProbe.HIT] == 1).all()
    np.testing.assert_array_equal(out[:, SurfaceProbe.P], plain[:, SurfaceProbe.P])
    np.testing.assert_array_equal(out[:, SurfaceProbe.UV], plain[:, SurfaceProbe.UV])
    flipped = np.array([1, 3, 5])  # rows whose hit is on a turned-over shape
    same = np.array([0, 2, 4])
    np.testing.assert_array_equal(out[same], plain[same])
    np.testing.assert_array_equal(out[flipped][:, SurfaceProbe.N_GEO], -plain[flipped][:, SurfaceProbe.N_GEO])
    np.testing.assert_array_equal(out[flipped][:, SurfaceProbe.N_SHADING], -plain[flipped][:, SurfaceProbe.N_SHADING])
    assert (plain[:, SurfaceProbe.FRONT] == 1).all() and (out[flipped, SurfaceProbe.FRONT] == 0).all()
    # the rays from below meet the spheres' bottoms: the quads are above them
    assert (out[[2, 3], SurfaceProbe.PRIM] == [0, 1]).all() and (out[[0, 1], SurfaceProbe.PRIM] == [2, 3]).all()


@ti.kernel
def _emitter_samples(geometry: ti.template(), g: ti.i32, ref: vec3, u: ti.types.ndarray(dtype=ti.math.vec2, ndim=1),
                     p: ti.types.ndarray(dtype=vec3, ndim=1), n: ti.types.ndarray(dtype=vec3, ndim=1),
                     pdf: ti.types.ndarray(dtype=ti.f32, ndim=2)):
    for i in range(u.shape[0]):
        e = geometry.sample_emitter(g, ref, u[i])
        p[i] = e.p
        n[i] = e.n
        pdf[i, 0] = e.pdf
        pdf[i, 1] = geometry.emitter_pdf(g, ref, e.p, e.n)


def emitter_samples(geometry, g, ref, count=256, seed=1):
    u = np.random.default_rng(seed).random((count, 2)).astype(np.float32)
    p, n, pdf = np.zeros((count, 3), np.float32), np.zeros((count, 3), np.float32), np.zeros((count, 2), np.float32)
    _emitter_samples(geometry, g, ti.Vector(ref), u, p, n, pdf)
    return p, n, pdf


@pytest.mark.parametrize("g, ref", [(0, (0.2, 0.1, -0.3)), (1, (3.2, 0.1, -0.3)), (1, (6.0, 0.2, 0.1)),
                                    (2, (0.1, 5.0, 0.2)), (3, (3.1, 5.0, 0.2)), (3, (3.1, 2.0, 0.2))],
                         ids=["sphere-inside", "flipped-sphere-inside", "flipped-sphere-outside", "quad",
                              "flipped-quad-above", "flipped-quad-below"])
def test_emitter_samples_carry_their_hits_normal_and_the_same_density(taichi_runtime, g, ref):
    flipped, plain = geometry_from(data()), geometry_from(data(flipped=False))
    p, n, pdf = emitter_samples(flipped, g, ref)
    p0, n0, pdf0 = emitter_samples(plain, g, ref)
    np.testing.assert_array_equal(p, p0)
    np.testing.assert_array_equal(pdf, pdf0)  # densities do not depend on the normal's sign
    np.testing.assert_allclose(pdf[:, 0], pdf[:, 1], rtol=1e-5)
    np.testing.assert_array_equal(n, -n0 if g in (1, 3) else n0)
    # the sample's normal is the normal a ray from ref meets there
    directions = p - np.asarray(ref, np.float32)
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    hits = SurfaceProbe(flipped).shoot(np.tile(np.asarray(ref, np.float32), (len(p), 1)), directions)
    sure = (hits[:, SurfaceProbe.HIT] == 1) & (hits[:, SurfaceProbe.PRIM] == g)
    assert sure.mean() > 0.9
    np.testing.assert_allclose(hits[sure][:, SurfaceProbe.N_GEO], n[sure], atol=1e-4)
    if g == 1:  # inside the turned-over sphere every point emits towards ref; outside, none does
        inside = np.linalg.norm(np.subtract(ref, SPHERES[1, :3])) < SPHERES[1, 3]
        assert (np.einsum("ij,ij->i", n, directions) < 0).all() == inside
        assert (np.einsum("ij,ij->i", n, directions) > 0).all() != inside


def test_light_selection_sees_a_flipped_quad_emit_the_other_way(taichi_runtime):
    axis = geometry_from(data()).emitter_info()["axis"]
    np.testing.assert_allclose(axis[2:], [[0.0, 1.0, 0.0], [0.0, -1.0, 0.0]])  # spheres first, then quads


def test_geometry_without_flipped_shapes_compiles_no_sign(taichi_runtime):
    plain = geometry_from(data(flipped=False))
    assert not plain.has_flipped and not hasattr(plain, "flipped")
    assert geometry_from(data()).has_flipped
    assert not MeshData(spheres=SPHERES, sphere_material=np.zeros(2, np.int32)).has_flipped
