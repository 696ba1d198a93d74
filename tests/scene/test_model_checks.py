"""What every model format shares (renderer/scene/model_formats/builder.py and load.py): the test
models themselves, the shipped models, one-line errors naming the file, and the repairs of
degenerate triangles and bad normals."""
from __future__ import annotations

import json
import shutil
import warnings

import numpy as np
import pytest

from renderer.scene.errors import SceneError
from renderer.scene.model_formats import DegenerateTrianglesWarning, MeshWarning, load_mesh_asset
from renderer.scene.pbr_approximation import approximate_spec
from tests.data import make_test_models as mtm
from tests.scene.model_file_helpers import DATA, MODELS, TRIANGLE, one_line_error, write_gltf


# ---------------------------------------------------------------------------------------------
# test data


def test_generated_files_are_up_to_date(tmp_path):
    """The committed models are what the generator writes (PNG bytes may differ by zlib version)."""
    import cv2

    mtm.main(tmp_path)
    for name in ("textured_quad.gltf", "textured_quad.bin", "two_nodes.gltf", "materials.obj",
                 "materials.mtl", "pyramid.ply", "alpha_colors.gltf", "instancing.gltf",
                 "layers.gltf", "imperfect.gltf"):
        assert (tmp_path / name).read_bytes() == (DATA / name).read_bytes(), name
    for name in ("checker.png", "mr.png", "normal.png", "alpha.png", "layer.png", "rgb16.png"):
        new, committed = (cv2.imread(str(d / name), cv2.IMREAD_UNCHANGED) for d in (tmp_path, DATA))
        assert new.dtype == committed.dtype and np.array_equal(new, committed), name


def test_test_models_are_tiny():
    model_suffixes = {".gltf", ".glb", ".bin", ".obj", ".mtl", ".ply", ".png"}
    for path in DATA.iterdir():
        if path.suffix in model_suffixes:
            assert path.stat().st_size < 8192, path


# ---------------------------------------------------------------------------------------------
# shipped models


@pytest.mark.parametrize("name, triangles", [("bunny.glb", 5648), ("suzanne.glb", 14842)])
def test_shipped_models(name, triangles):
    import trimesh

    asset = load_mesh_asset(MODELS / name)
    assert asset.triangle_count == triangles
    assert len(asset.materials) == 1 and len(asset.meshes) == 1
    # same world-space geometry as trimesh's own glTF importer
    reference = trimesh.load(MODELS / name, force="mesh", process=False)
    np.testing.assert_allclose(asset.meshes[0].positions[asset.meshes[0].indices],
                               np.asarray(reference.vertices)[np.asarray(reference.faces)], atol=1e-6)
    np.testing.assert_allclose(asset.bounds, reference.bounds, atol=1e-6)


def test_bunny_material():
    m = load_mesh_asset(MODELS / "bunny.glb").materials[0]
    assert m.base_color_factor == pytest.approx((0.8, 0.8, 0.8, 1.0))
    assert (m.metallic_factor, m.roughness_factor) == (0.0, 0.5)
    assert approximate_spec(m).kind == "diffuse"


# ---------------------------------------------------------------------------------------------
# bad input: one line each, naming the file


def test_missing_file(tmp_path):
    path = tmp_path / "nothing.glb"
    with pytest.raises(SceneError) as e:
        load_mesh_asset(path)
    assert "not found" in one_line_error(e, path)


def test_unsupported_extension(tmp_path):
    path = tmp_path / "model.fbx"
    path.write_bytes(b"Kaydara")
    with pytest.raises(SceneError) as e:
        load_mesh_asset(path)
    assert "unsupported model format '.fbx'" in one_line_error(e, path)


@pytest.mark.parametrize("kind", ["gltf_no_mesh", "obj_points_only", "ply_points_only"])
def test_no_triangles(tmp_path, kind):
    if kind == "gltf_no_mesh":
        path = tmp_path / "empty.gltf"
        path.write_text(json.dumps({"asset": {"version": "2.0"}, "scenes": [{"nodes": []}]}))
    elif kind == "obj_points_only":
        path = tmp_path / "points.obj"
        path.write_text("v 0 0 0\nv 1 0 0\n")
    else:
        path = tmp_path / "points.ply"
        path.write_text("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                        "property float y\nproperty float z\nend_header\n0 0 0\n")
    with pytest.raises(SceneError) as e:
        load_mesh_asset(path)
    assert "contains no triangles" in one_line_error(e, path)


@pytest.mark.parametrize("value", ["nan", "inf"])
def test_non_finite_vertices(tmp_path, value):
    obj = tmp_path / "bad.obj"
    obj.write_text(f"v 0 0 0\nv {value} 0 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(SceneError) as e:
        load_mesh_asset(obj)
    assert "1 vertex positions are not finite" in one_line_error(e, obj)
    gltf = write_gltf(tmp_path / "bad.gltf", [[0, 0, 0], [float(value), 0, 0], [0, 1, 0]], [0, 1, 2])
    with pytest.raises(SceneError) as e:
        load_mesh_asset(gltf)
    message = one_line_error(e, gltf)
    assert "mesh 'm' primitive 0" in message and "not finite" in message


def test_index_out_of_range(tmp_path):
    gltf = write_gltf(tmp_path / "bad.gltf", TRIANGLE, [0, 1, 7])
    with pytest.raises(SceneError) as e:
        load_mesh_asset(gltf)
    assert "vertex index 7 is out of range (the mesh has 3 vertices)" in one_line_error(e, gltf)
    obj = tmp_path / "bad.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    with pytest.raises(SceneError) as e:
        load_mesh_asset(obj)
    assert "out of range" in one_line_error(e, obj)
    ply = tmp_path / "bad.ply"
    ply.write_text((DATA / "pyramid.ply").read_text().replace("3 3 4 0\n", "3 3 40 0\n"))
    with pytest.raises(SceneError) as e:
        load_mesh_asset(ply)
    assert "vertex index 40 is out of range" in one_line_error(e, ply)


def test_missing_texture_and_buffer_files(tmp_path):
    shutil.copy(DATA / "textured_quad.gltf", tmp_path)
    shutil.copy(DATA / "mr.png", tmp_path)
    shutil.copy(DATA / "normal.png", tmp_path)
    path = tmp_path / "textured_quad.gltf"
    # A missing texture is a warning naming the file and its users (contract change: it was an
    # error), a missing buffer is still an error: geometry cannot be guessed.
    with pytest.raises(SceneError) as e:
        load_mesh_asset(path)
    assert "buffers[0] file 'textured_quad.bin' not found" in one_line_error(e, path)
    shutil.copy(DATA / "textured_quad.bin", tmp_path)
    with pytest.warns(MeshWarning) as caught:
        asset = load_mesh_asset(path)
    assert [str(w.message) for w in caught] == [
        f"{path}: texture file 'checker.png' not found; drawn without it (factors alone): "
        "material 'quad' base colour, material 'quad' emissive"]
    quad = asset.materials[0]
    assert quad.base_color_texture is None and quad.emissive_texture is None
    assert quad.metallic_roughness_texture is not None and quad.normal_texture is not None
    # A file that is there but is no image is treated as a missing one: one warning naming it and
    # why (no library object's repr), and the model renders without the texture.
    (tmp_path / "checker.png").write_bytes(b"not a png")
    with pytest.warns(MeshWarning) as caught:
        asset = load_mesh_asset(path)
    assert [str(w.message) for w in caught] == [
        f"{path}: texture images[0] 'checker.png' cannot be decoded (not an image format the decoders read); "
        "drawn without it (factors alone): material 'quad' base colour, material 'quad' emissive"]
    assert asset.materials[0].base_color_texture is None and " at 0x" not in str(caught[0].message)
    shutil.copy(DATA / "checker.png", tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert load_mesh_asset(path).triangle_count == 2


# ---------------------------------------------------------------------------------------------
# repairs: degenerate triangles, bad normals


def test_degenerate_triangles_are_removed_with_a_count(tmp_path):
    path = tmp_path / "degenerate.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nv 1 1 0\n"
                    "f 1 2 3\n"        # fine
                    "f 2 5 3\n"        # fine
                    "f 1 1 3\n"        # repeated index
                    "f 1 2 4\n")       # collinear: zero area
    with pytest.warns(DegenerateTrianglesWarning, match=r"skipped 2 degenerate triangles of 4"):
        asset = load_mesh_asset(path)
    assert asset.triangle_count == 2


def test_all_degenerate_is_an_error(tmp_path):
    path = write_gltf(tmp_path / "flat.gltf", [[0, 0, 0], [1, 1, 1], [2, 2, 2]], [0, 1, 2, 0, 0, 1])
    with pytest.raises(SceneError) as e:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            load_mesh_asset(path)
    assert "all 2 triangles are degenerate" in one_line_error(e, path)


def test_zero_normals_are_replaced(tmp_path):
    path = tmp_path / "zero_normal.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 0\nvn 0 0 1\nf 1//1 2//2 3//2\n")
    with pytest.warns(MeshWarning, match="replaced 1 zero-length"):
        mesh = load_mesh_asset(path).meshes[0]
    np.testing.assert_allclose(mesh.normals, [[0, 0, 1]] * 3, atol=1e-7)
