"""OBJ files and their MTL libraries read (renderer/scene/model_formats/obj_mtl.py): the MTL mapping
onto metallic-roughness, UVs and texture options, missing pieces, bump maps."""
from __future__ import annotations

import math
import shutil

import numpy as np
import pytest

from renderer.scene.errors import SceneError
from renderer.scene.model_formats import MeshWarning, load_mesh_asset
from renderer.scene.pbr_approximation import approximate_spec
from tests.data import make_test_models as mtm
from tests.scene.model_file_helpers import DATA, one_line_error, rgba


@pytest.fixture(scope="module")
def obj():
    return load_mesh_asset(DATA / "materials.obj")


def test_obj_materials_from_mtl(obj):
    by_name = {m.name: m for m in obj.materials}
    assert list(by_name) == ["textured", "glass", "lamp", "mirror"]
    textured = by_name["textured"]
    assert textured.base_color_factor == (0.5, 0.6, 0.7, 1.0)
    assert textured.metallic_factor == 0.0
    assert textured.roughness_factor == pytest.approx(math.sqrt(math.sqrt(2 / (98 + 2))))
    glass = by_name["glass"]
    assert glass.transmission_factor == pytest.approx(0.9) and glass.ior == pytest.approx(1.45)
    assert glass.base_color_factor[3] == 1.0 and glass.alpha_mode == "OPAQUE"
    assert glass.roughness_factor == pytest.approx((2 / 1002) ** 0.25)
    lamp = by_name["lamp"]
    assert lamp.emissive_factor == (3.0, 2.0, 1.0) and lamp.roughness_factor == 1.0
    mirror = by_name["mirror"]
    assert mirror.metallic_factor == 1.0 and mirror.base_color_factor[:3] == (0.9, 0.8, 0.7)
    assert mirror.roughness_factor == pytest.approx(0.05)
    assert [approximate_spec(s).kind for s in obj.materials] == [
        "diffuse", "dielectric", "diffuse", "conductor"]


def test_obj_geometry_uvs_and_texture(obj):
    assert obj.triangle_count == 5  # the quad is split in two
    textured = next(m for m in obj.meshes if obj.materials[m.material].name == "textured")
    assert textured.triangle_count == 2
    np.testing.assert_array_equal(textured.positions, mtm.QUAD_POSITIONS)
    np.testing.assert_array_equal(textured.uv0, mtm.QUAD_UV0)  # v flipped to the glTF frame
    np.testing.assert_array_equal(textured.normals, mtm.QUAD_NORMALS)
    ref = obj.materials[textured.material].base_color_texture
    np.testing.assert_allclose(obj.images[ref.texture].linear(), rgba(mtm.CHECKER, True), atol=1e-6)
    # -o 0.25 0.5 -s 2 2 in OBJ's v-up frame, expressed on our v-down UVs
    for u_up, v_up in [(0.1, 0.2), (0.7, 0.9)]:
        obj_lookup = np.array([2 * u_up + 0.25, 2 * v_up + 0.5])  # v-up image coordinates
        ours = ref.matrix @ [u_up, 1 - v_up, 1]
        np.testing.assert_allclose(ours[:2], [obj_lookup[0], 1 - obj_lookup[1]], atol=1e-6)


def test_obj_missing_pieces(tmp_path):
    (tmp_path / "a.obj").write_text("mtllib nowhere.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(SceneError) as e:
        load_mesh_asset(tmp_path / "a.obj")
    assert "material library 'nowhere.mtl' not found" in one_line_error(e, tmp_path / "a.obj")
    # A missing texture is a warning (contract change: it was an error); the material keeps Kd.
    shutil.copy(DATA / "materials.obj", tmp_path / "b.obj")
    shutil.copy(DATA / "materials.mtl", tmp_path / "materials.mtl")
    with pytest.warns(MeshWarning) as caught:
        asset = load_mesh_asset(tmp_path / "b.obj")
    assert [str(w.message) for w in caught] == [
        f"{tmp_path / 'b.obj'}: texture file 'checker.png' not found; drawn without it "
        "(factors alone): material 'textured' map_kd"]
    textured = asset.materials[0]
    assert textured.base_color_texture is None and textured.base_color_factor == (0.5, 0.6, 0.7, 1.0)


def test_obj_without_materials_gets_default_grey(tmp_path):
    path = tmp_path / "plain.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")
    asset = load_mesh_asset(path)
    assert asset.triangle_count == 2
    assert asset.materials[0].base_color_factor == (0.8, 0.8, 0.8, 1.0)
    assert asset.meshes[0].normals is None and asset.meshes[0].uv0 is None


def test_obj_bump_maps(tmp_path):
    """map_Bump holding a tangent-space normal map is used; a height map is skipped with a warning."""
    shutil.copy(DATA / "normal.png", tmp_path)
    from PIL import Image

    Image.fromarray(np.full((4, 4), 90, np.uint8)).save(tmp_path / "height.png")
    (tmp_path / "m.mtl").write_text("newmtl n\nmap_Bump -bm 0.5 normal.png\nnewmtl h\nbump height.png\n")
    (tmp_path / "a.obj").write_text("mtllib m.mtl\nv -1 1 0\nv 1 1 0\nv 1 -1 0\nv -1 -1 0\n"
                                    "vt 0 1\nvt 1 1\nvt 1 0\nvt 0 0\n"
                                    "usemtl n\nf 1/1 4/4 3/3\nusemtl h\nf 1/1 3/3 2/2\n")
    with pytest.warns(MeshWarning, match="height-map bump 'height.png' ignored"):
        asset = load_mesh_asset(tmp_path / "a.obj")
    n, h = asset.materials
    assert n.normal_texture is not None and n.normal_scale == 0.5 and h.normal_texture is None
    np.testing.assert_allclose(asset.images[n.normal_texture.texture].linear(), rgba(mtm.NORMAL, False),
                               atol=1e-7)
    mapped = next(m for m in asset.meshes if m.material == 0)
    # no normals in the file: flat normals, and tangents along +u = +x
    np.testing.assert_allclose(mapped.normals, [[0, 0, 1]] * 3, atol=1e-7)
    np.testing.assert_allclose(mapped.tangents, [[1, 0, 0, 1]] * 3, atol=1e-6)
