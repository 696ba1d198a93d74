"""Triangles wound against their vertex normals are rewound to them (and only those)."""
import numpy as np
import trimesh

from renderer.scene.orientation import rewind_to_normals


def test_the_normals_decide():
    ball = trimesh.creation.icosphere(subdivisions=2)
    outward = ball.vertex_normals
    same, count = rewind_to_normals(ball.vertices, ball.faces, outward)
    assert count == 0 and same is ball.faces
    flipped = ball.faces[:, ::-1]
    turned, count = rewind_to_normals(ball.vertices, flipped, outward)
    assert count == len(flipped)
    np.testing.assert_array_equal(np.sort(turned, axis=1), np.sort(ball.faces, axis=1))
    # Each rewound triangle faces outwards again: its normal agrees with the vertex normals.
    p = ball.vertices
    face = np.cross(p[turned[:, 1]] - p[turned[:, 0]], p[turned[:, 2]] - p[turned[:, 0]])
    assert (np.einsum("ij,ij->i", face, outward[turned].sum(axis=1)) > 0).all()


def test_a_room_wound_inwards_with_inward_normals_stays_a_room():
    ball = trimesh.creation.icosphere(subdivisions=2)
    room, count = rewind_to_normals(ball.vertices, ball.faces[:, ::-1], -ball.vertex_normals)
    assert count == 0


def test_only_the_disagreeing_triangles_turn_and_no_normals_change_nothing():
    ball = trimesh.creation.icosphere(subdivisions=1)
    mixed = ball.faces.copy()
    mixed[::3] = mixed[::3, ::-1]
    _, count = rewind_to_normals(ball.vertices, mixed, ball.vertex_normals)
    assert count == len(mixed[::3])
    same, count = rewind_to_normals(ball.vertices, mixed, None)
    assert count == 0 and same is mixed
