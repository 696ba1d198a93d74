"""Per-vertex and per-face attributes of PLY files (renderer/scene/mesh_attributes.py): Mitsuba's
names and grouping, binary and ASCII files, and the colours they give a mesh as the model loader
built it (degenerate triangles dropped, polygons triangulated, faces rewound), with one-line
errors naming the file. PLY files are written by the tests."""
from __future__ import annotations

import numpy as np
import pytest

from renderer.scene.description import MeshAttributeColor
from renderer.scene.errors import SceneError
from renderer.scene.limits import MemoryBudget, MemoryLedger
from renderer.scene.load_options import LoadOptions
from renderer.scene.mesh_attributes import AttributeColoring, face_of_triangles, read_ply_attributes
from renderer.scene.model_files import ModelFiles
from renderer.scene.model_formats.mesh_warnings import DegenerateTrianglesWarning

# A unit square (two triangles), a triangle beside it and a degenerate one (a repeated vertex).
# (trimesh reads binary face lists of one length; polygons are the ASCII test's.)
POSITIONS = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0]], np.float32)
FACES = [(0, 1, 2), (0, 2, 3), (1, 4, 5), (1, 1, 4)]
QUAD_FACES = [(0, 1, 2, 3), (1, 4, 5), (1, 5, 2)]
VERTEX_COLOR = np.linspace(0.0, 1.0, 18).reshape(6, 3)
FACE_COLOR = np.array([[0.9, 0.1, 0.2], [0.3, 0.8, 0.1], [0.2, 0.3, 0.7], [0.5, 0.5, 0.5]])
FACE_WEIGHT = np.array([0.25, 0.5, 0.75, 1.0])


def ledger():
    return MemoryLedger(MemoryBudget.from_settings())


def write_binary_ply(path, faces=FACES):
    """x, y, z, color_0..2 per vertex; vertex_indices, color_0..2, weight_0 per face."""
    lines = ["ply", "format binary_little_endian 1.0", f"element vertex {len(POSITIONS)}"]
    lines += [f"property float {p}" for p in ("x", "y", "z", "color_0", "color_1", "color_2")]
    lines += [f"element face {len(faces)}", "property list uchar int vertex_indices"]
    lines += [f"property float {p}" for p in ("color_0", "color_1", "color_2", "weight_0")] + ["end_header"]
    body = np.concatenate([POSITIONS, VERTEX_COLOR], axis=1).astype("<f4").tobytes()
    for face, colour, weight in zip(faces, FACE_COLOR, FACE_WEIGHT):
        body += bytes([len(face)]) + np.asarray(face, "<i4").tobytes() + np.array([*colour, weight], "<f4").tobytes()
    path.write_bytes(("\n".join(lines) + "\n").encode() + body)
    return path


def test_attributes_are_grouped_and_named_as_mitsuba_does(tmp_path):
    found = read_ply_attributes(write_binary_ply(tmp_path / "m.ply"), ledger())
    assert found.names() == ["face_color", "face_weight", "vertex_color"]
    np.testing.assert_allclose(found.attributes["vertex_color"], VERTEX_COLOR, rtol=1e-6)
    np.testing.assert_allclose(found.attributes["face_color"], FACE_COLOR, rtol=1e-6)
    np.testing.assert_allclose(found.attributes["face_weight"][:, 0], FACE_WEIGHT)
    assert found.vertex_count == 6 and [tuple(f) for f in found.faces] == FACES


def test_ascii_colours_and_what_is_not_an_attribute(tmp_path):
    path = tmp_path / "a.ply"
    path.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                    "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty float foo\n"
                    "property float pair_0\nproperty float pair_1\nelement face 1\n"
                    "property list uchar int vertex_indices\nend_header\n"
                    "0 0 0 255 0 51 1 2 3\n1 0 0 0 255 0 1 2 3\n0 1 0 0 0 255 1 2 3\n3 0 1 2\n")
    found = read_ply_attributes(path, ledger())
    # red / green / blue are vertex_color, as fractions of 255; a property without a _<k> postfix and
    # a two-channel group are not attributes (as in Mitsuba).
    assert found.names() == ["vertex_color"]
    np.testing.assert_allclose(found.attributes["vertex_color"][0], (1.0, 0.0, 0.2))


def test_face_of_triangles_follows_dropped_rewound_and_fanned_faces():
    triangles = np.array([[2, 0, 1], [3, 2, 0], [5, 1, 4], [1, 2, 5]])  # rewound; the quad fanned
    assert face_of_triangles([np.array(f) for f in QUAD_FACES], triangles).tolist() == [0, 0, 1, 2]
    assert face_of_triangles([np.array(f) for f in QUAD_FACES], np.array([[0, 4, 5]])).tolist() == [-1]


def loaded(tmp_path):
    path = write_binary_ply(tmp_path / "m.ply")
    with pytest.warns(DegenerateTrianglesWarning):
        (mesh,) = ModelFiles(LoadOptions()).load(path).meshes
    return path, mesh


def test_vertex_colours_follow_the_vertices(tmp_path):
    path, mesh = loaded(tmp_path)
    spec = MeshAttributeColor("vertex_color", offset=(0.1, 0.0, 0.0), scale=(0.5, 1.0, 2.0))
    coloured = AttributeColoring(ledger()).colored(mesh, path, spec)
    assert coloured.positions is mesh.positions and (coloured.indices == mesh.indices).all()
    np.testing.assert_allclose(coloured.colors[:, :3], (0.1, 0.0, 0.0) + VERTEX_COLOR * (0.5, 1.0, 2.0), rtol=1e-6)
    assert (coloured.colors[:, 3] == 1.0).all()


def test_face_colours_split_the_mesh_per_triangle(tmp_path):
    path, mesh = loaded(tmp_path)
    assert len(mesh.indices) == 3  # the degenerate triangle dropped
    coloured = AttributeColoring(ledger()).colored(mesh, path, MeshAttributeColor("face_color"))
    assert len(coloured.positions) == 9 and coloured.indices.tolist() == np.arange(9).reshape(3, 3).tolist()
    np.testing.assert_array_equal(coloured.positions, mesh.positions[mesh.indices.reshape(-1)])
    faces = face_of_triangles([np.array(f) for f in FACES], mesh.indices)
    assert faces.tolist() == [0, 1, 2]
    corner_colours = coloured.colors[:, :3].reshape(3, 3, 3)
    for k, face in enumerate(faces):
        np.testing.assert_allclose(corner_colours[k], np.repeat(FACE_COLOR[face][None], 3, axis=0), rtol=1e-6)
    weights = AttributeColoring(ledger()).colored(mesh, path, MeshAttributeColor("face_weight"))
    np.testing.assert_allclose(weights.colors[::3, :3], np.repeat(FACE_WEIGHT[faces][:, None], 3, axis=1), rtol=1e-6)


def test_polygons_share_their_face_colour(tmp_path):
    path = tmp_path / "q.ply"
    path.write_text("ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
                    "element face 3\nproperty list uchar int vertex_indices\nproperty float shade_0\nend_header\n"
                    + "".join(" ".join(map(str, p)) + "\n" for p in POSITIONS)
                    + "".join(f"{len(f)} {' '.join(map(str, f))} {0.2 * (k + 1)}\n" for k, f in enumerate(QUAD_FACES)))
    (mesh,) = ModelFiles(LoadOptions()).load(path).meshes
    coloured = AttributeColoring(ledger()).colored(mesh, path, MeshAttributeColor("face_shade"))
    shades = coloured.colors[::3, 0]
    faces = face_of_triangles([np.array(f) for f in QUAD_FACES], mesh.indices)
    assert sorted(faces.tolist()) == [0, 0, 1, 2]  # the quad is two triangles
    np.testing.assert_allclose(shades, 0.2 * (faces + 1), rtol=1e-6)


def test_a_missing_attribute_is_one_line_naming_the_file(tmp_path):
    path, mesh = loaded(tmp_path)
    with pytest.raises(SceneError) as error:
        AttributeColoring(ledger()).colored(mesh, path, MeshAttributeColor("vertex_weight"))
    assert str(error.value) == (f"{path}: has no mesh attribute 'vertex_weight' (its attributes: face_color, "
                                "face_weight, vertex_color)")
    obj = tmp_path / "m.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(SceneError, match=r"m\.obj: mesh attributes are read from PLY files only$"):
        AttributeColoring(ledger()).colored(mesh, obj, MeshAttributeColor("vertex_color"))
