"""The generators with texture coordinates (renderer/scene/shape_meshes.py): the cylinder's and the
disc fan's vertices lie on the round shape with its exact normals and (u, v), every triangle faces
outwards, the counts are what triangle_count says. (How they sit on Mitsuba's shapes, against
Mitsuba's own hits: tests/scene/mitsuba/test_shapes.py.)"""
from __future__ import annotations

import numpy as np
import pytest

from renderer.scene.generators import generate, generated_mesh, triangle_count


def face_normals(mesh):
    p = mesh.positions.astype(np.float64)
    t = mesh.indices
    n = np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]])
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def angle(x, minus_z):
    """The angle from +x towards -z, in turns in [0, 1)."""
    return np.mod(np.arctan2(minus_z, x) / (2 * np.pi), 1.0)


def test_cylinder_vertices_lie_on_the_tube_with_its_normals_and_coordinates():
    mesh = generated_mesh("cylinder", {"radius": 0.5, "height": 3.0, "sectors": 12})
    p = mesh.positions.astype(np.float64)
    np.testing.assert_allclose(np.hypot(p[:, 0], p[:, 2]), 0.5, rtol=1e-6)
    np.testing.assert_allclose(mesh.normals, np.stack([p[:, 0], 0 * p[:, 1], p[:, 2]], 1) / 0.5, atol=1e-6)
    np.testing.assert_allclose(mesh.uv0[:, 1], p[:, 1] / 3.0, atol=1e-6)
    seam = mesh.uv0[:, 0] == 1.0  # the seam's second column closes the tube at u = 1
    np.testing.assert_allclose(mesh.uv0[~seam, 0], angle(p[~seam, 0], -p[~seam, 2]), atol=1e-6)
    np.testing.assert_allclose(p[seam], p[mesh.uv0[:, 0] == 0.0])
    centres = p[mesh.indices].mean(axis=1)
    assert (np.einsum("ij,ij->i", face_normals(mesh), centres * [1, 0, 1]) > 0).all()  # outwards
    assert len(mesh.indices) == triangle_count("cylinder", {"sectors": 12}) == 24


def test_disc_fan_lies_in_its_plane_facing_up_with_radial_coordinates():
    mesh = generated_mesh("disc_fan", {"radius": 2.0, "sectors": 16})
    p = mesh.positions.astype(np.float64)
    assert (p[:, 1] == 0).all() and (face_normals(mesh)[:, 1] > 0.999999).all()
    r = np.hypot(p[:, 0], p[:, 2])
    np.testing.assert_allclose(mesh.uv0[:, 0], r / 2.0, atol=1e-6)
    rim = (r > 1.0) & (mesh.uv0[:, 1] < 1.0)
    np.testing.assert_allclose(mesh.uv0[rim, 1], angle(p[rim, 0], -p[rim, 2]), atol=1e-6)
    # Each triangle's centre vertex takes the angle of the triangle's middle.
    middle = p[mesh.indices[:, 1:]].mean(axis=1)
    np.testing.assert_allclose(mesh.uv0[mesh.indices[:, 0], 1], angle(middle[:, 0], -middle[:, 2]), atol=1e-6)
    assert len(mesh.indices) == triangle_count("disc_fan", {"sectors": 16}) == 16


def test_cube_faces_look_out_and_span_the_texture():
    mesh = generated_mesh("cube", {"size": 3.0})
    p = mesh.positions.astype(np.float64)
    assert np.abs(p).max() == 1.5 and len(mesh.indices) == triangle_count("cube") == 12
    n = face_normals(mesh)
    np.testing.assert_allclose(mesh.normals[mesh.indices[:, 0]], n, atol=1e-7)
    assert (np.einsum("ij,ij->i", n, p[mesh.indices].mean(axis=1)) > 0).all()
    for face in range(6):  # each face's four corners take the texture's four corners
        assert sorted(map(tuple, mesh.uv0[4 * face:4 * face + 4])) == [(0, 0), (0, 1), (1, 0), (1, 1)]


@pytest.mark.parametrize("generator", ["cylinder", "disc_fan", "cube"])
def test_generate_gives_the_same_three_arrays(generator):
    positions, indices, normals = generate(generator)
    mesh = generated_mesh(generator)
    np.testing.assert_array_equal(positions, mesh.positions)
    np.testing.assert_array_equal(indices, mesh.indices)
    np.testing.assert_array_equal(normals, mesh.normals)
    assert generated_mesh("icosphere").uv0 is None
