"""PLY and STL files read (renderer/scene/model_formats/ply_stl.py): texture files, vertex colours,
quads, binary STL."""
from __future__ import annotations

import shutil

import numpy as np
import pytest

from renderer.scene.model_formats import MeshWarning, load_mesh_asset
from renderer.scene.srgb import srgb_to_linear
from tests.data import make_test_models as mtm
from tests.scene.model_file_helpers import DATA, geometric_normals, rgba


def test_ply_texture_file(tmp_path):
    shutil.copy(DATA / "checker.png", tmp_path)
    path = tmp_path / "textured.ply"
    path.write_text("ply\nformat ascii 1.0\ncomment TextureFile checker.png\nelement vertex 4\n"
                    "property float x\nproperty float y\nproperty float z\nelement face 2\n"
                    "property list uchar int vertex_indices\nproperty list uchar float texcoord\n"
                    "end_header\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n"
                    "3 0 1 2 6 0 0 1 0 0 1\n3 1 3 2 6 1 0 1 1 0 1\n")
    asset = load_mesh_asset(path)
    mesh = asset.meshes[0]
    ref = asset.materials[0].base_color_texture
    np.testing.assert_allclose(asset.images[ref.texture].linear(), rgba(mtm.CHECKER, True), atol=1e-6)
    # the vertex at y = 1 had t = 1 (v-up): top of the image, stored v = 0
    top = np.flatnonzero(mesh.positions[:, 1] == 1)
    np.testing.assert_array_equal(mesh.uv0[top, 1], 0.0)
    (tmp_path / "checker.png").unlink()
    with pytest.warns(MeshWarning, match=r"textured.ply: texture file 'checker.png' not found; "
                                         r"drawn without it \(factors alone\): base colour$"):
        asset = load_mesh_asset(path)
    assert asset.materials[0].base_color_texture is None
    assert asset.materials[0].base_color_factor == (0.8, 0.8, 0.8, 1.0)


def test_ply_vertex_colours_normals_and_quads():
    asset = load_mesh_asset(DATA / "pyramid.ply")
    mesh = asset.meshes[0]
    assert asset.triangle_count == 6
    assert mesh.normals[4].tolist() == [0, 1, 0]
    expected = srgb_to_linear(np.array([128 / 255.0] * 3))
    np.testing.assert_allclose(mesh.colors[3], [*expected, 1.0], atol=1e-6)
    np.testing.assert_allclose(mesh.colors[0], [1, 0, 0, 1])
    assert asset.materials[0].base_color_factor == (1.0, 1.0, 1.0, 1.0)
    # every face points outwards of the pyramid
    centre = mesh.positions.mean(axis=0)
    n = geometric_normals(mesh.positions, mesh.indices)
    face_centres = mesh.positions[mesh.indices].mean(axis=1)
    assert (np.einsum("ij,ij->i", n, face_centres - centre) > 0).all()


def test_a_hard_edge_keeps_its_normals_beside_per_vertex_texture_coordinates(tmp_path):
    """Two faces meeting at a crease store their shared corners twice, with the same position and
    texture coordinate but each face's normal: every vertex keeps its own normal (a parser that
    merges such vertices lost the crease and left the normals out of step with the positions)."""
    rows = [(0, 0, 0, 0, 0, 1, 0, 0), (1, 0, 0, 0, 0, 1, 1, 0), (0, 1, 0, 0, 0, 1, 0, 1),
            (0, 0, 0, 0, 1, 0, 0, 0), (1, 0, 0, 0, 1, 0, 1, 0), (0, 0, 1, 0, 1, 0, 0, 1)]
    header = ("ply\nformat ascii 1.0\nelement vertex 6\n" + "".join(f"property float {p}\n" for p in
              ("x", "y", "z", "nx", "ny", "nz", "u", "v")) + "element face 2\nproperty list uchar int vertex_indices\n"
              "end_header\n")
    body = "".join(" ".join(str(v) for v in r) + "\n" for r in rows) + "3 0 1 2\n3 3 5 4\n"
    (tmp_path / "crease.ply").write_text(header + body)
    mesh = load_mesh_asset(tmp_path / "crease.ply").meshes[0]
    assert len(mesh.positions) == len(mesh.normals) == 6
    assert mesh.normals[0].tolist() == [0, 0, 1] and mesh.normals[3].tolist() == [0, 1, 0]


def test_stl_loads(tmp_path):
    import trimesh

    trimesh.creation.box(extents=(1, 2, 3)).export(tmp_path / "box.stl")
    asset = load_mesh_asset(tmp_path / "box.stl")
    assert asset.triangle_count == 12
    np.testing.assert_allclose(asset.bounds, [[-0.5, -1, -1.5], [0.5, 1, 1.5]])
