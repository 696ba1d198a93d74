"""An object's options on the meshes it draws (renderer/scene/mesh_adjustments.py): which of a file's
meshes, flat or computed normals, the front side turned over, v flipped; the defaults change nothing."""
from __future__ import annotations

import numpy as np

from renderer.scene.description import MeshObject
from renderer.scene.mesh_adjustments import adjusted, angle_weighted_normals, selected_meshes
from renderer.scene.mesh_model import TriangleMesh

# A triangle in z = 0 and a square in x = 0 sharing the origin, each with a right angle there; the
# square's area (1) is twice the triangle's, so area weights would lean the shared normal to +x.
POSITIONS = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 1, 1]], np.float32)
INDICES = np.array([[0, 1, 2], [0, 2, 4], [0, 4, 3]], np.int32)
UVS = np.array([[0, 0], [1, 0], [0, 1], [0.5, 0.25], [1, 1]], np.float32)


def mesh(**changes) -> TriangleMesh:
    return TriangleMesh(**{"positions": POSITIONS, "indices": INDICES, "uv0": UVS, "name": "a", **changes})


def obj(**changes) -> MeshObject:
    return MeshObject(kind="mesh", **changes)


def test_the_defaults_change_nothing():
    plain = mesh(normals=np.tile(np.float32([0, 0, 1]), (5, 1)))
    assert adjusted(plain, obj()) is plain


def test_angle_weighted_normals():
    n = angle_weighted_normals(POSITIONS, INDICES)
    np.testing.assert_allclose(n[0], np.array([1.0, 0.0, 1.0]) / np.sqrt(2.0), atol=1e-6)
    np.testing.assert_allclose(n[1], [0, 0, 1], atol=1e-7)
    np.testing.assert_allclose(n[3], [1, 0, 0], atol=1e-7)
    lone = angle_weighted_normals(np.zeros((3, 3), np.float32), np.array([[0, 1, 2]]))  # no area at all
    np.testing.assert_array_equal(lone, np.tile([0, 0, 1], (3, 1)))


def test_smooth_computes_only_missing_normals_and_flat_drops_them():
    smooth = adjusted(mesh(), obj(normals="smooth"))
    np.testing.assert_allclose(smooth.normals, angle_weighted_normals(POSITIONS, INDICES))
    given = np.tile(np.float32([0, 1, 0]), (5, 1))
    assert adjusted(mesh(normals=given), obj(normals="smooth")).normals is given
    flat = adjusted(mesh(normals=given, tangents=np.ones((5, 4), np.float32)), obj(normals="flat"))
    assert flat.normals is None and flat.tangents is None


def test_flip_normals_turns_winding_and_normals_over():
    given = angle_weighted_normals(POSITIONS, INDICES)
    flipped = adjusted(mesh(normals=given), obj(flip_normals=True))
    p = POSITIONS.astype(np.float64)
    before = np.cross(p[INDICES[:, 1]] - p[INDICES[:, 0]], p[INDICES[:, 2]] - p[INDICES[:, 0]])
    t = flipped.indices
    after = np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]])
    np.testing.assert_allclose(after, -before)
    np.testing.assert_array_equal(flipped.normals, -given)
    assert flipped.uv0 is UVS


def test_flip_v_and_parts():
    flipped = adjusted(mesh(), obj(flip_v=True))
    np.testing.assert_array_equal(flipped.uv0, np.stack([UVS[:, 0], 1 - UVS[:, 1]], 1))
    assert UVS[3, 1] == np.float32(0.25)  # the file's mesh (shared by other objects) is left alone
    meshes = [mesh(name="shape 0"), mesh(name="shape 1")]
    assert selected_meshes(meshes, obj(part="shape 1")) == [meshes[1]]
    assert selected_meshes(meshes, obj()) == meshes and selected_meshes(meshes, obj(part="shape 2")) == []


def test_vertex_colours_can_be_dropped():
    """Mitsuba's meshes shade with their vertex colours only through a mesh_attribute texture."""
    coloured = mesh(colors=np.tile(np.float32([1, 0, 0, 1]), (5, 1)))
    assert adjusted(coloured, obj()).colors is coloured.colors
    assert adjusted(coloured, obj(vertex_colors=False)).colors is None
