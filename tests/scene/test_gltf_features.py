"""glTF as real assets use it: alpha, vertex colours, instancing (shared meshes and
EXT_mesh_gpu_instancing), material layer extensions, 16-bit textures, missing textures, unknown
extensions, and one parse per model file per run.

The files under tests/data are written by tests/data/make_test_models.py; expected values come
from its constants.
"""
from __future__ import annotations

import json
import math
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

from renderer.scene.errors import SceneError
from renderer.scene.model_formats import MeshWarning, load_mesh_asset
from renderer.scene.srgb import srgb_to_linear
from renderer.scene.textures import STORE_HALF, STORE_RGBA8, pack_atlas
from tests.data import make_test_models as mtm

DATA = Path(__file__).resolve().parents[1] / "data"


def quiet_load(path):
    """Load a file that must not warn."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return load_mesh_asset(path)


def geometric_normals(positions, indices):
    p = positions.astype(np.float64)
    n = np.cross(p[indices[:, 1]] - p[indices[:, 0]], p[indices[:, 2]] - p[indices[:, 0]])
    return n / np.linalg.norm(n, axis=1, keepdims=True)


# ---------------------------------------------------------------------------------------------
# alpha and vertex colours


@pytest.fixture(scope="module")
def alpha_colors():
    return quiet_load(DATA / "alpha_colors.gltf")


def test_alpha_modes_and_cutoff(alpha_colors):
    masked, blended = alpha_colors.materials
    assert (masked.alpha_mode, masked.alpha_cutoff, masked.base_color_factor[3]) == ("MASK", 0.3, 0.9)
    assert (blended.alpha_mode, blended.alpha_cutoff, blended.double_sided) == ("BLEND", 0.5, True)


def test_base_colour_alpha_stays_in_the_texture(alpha_colors):
    masked, blended = alpha_colors.materials
    assert masked.base_color_texture.texture == blended.base_color_texture.texture  # one entry
    image = alpha_colors.images[masked.base_color_texture.texture]
    assert image.srgb and image.pixels.dtype == np.uint8
    np.testing.assert_array_equal(image.pixels, mtm.ALPHA)
    linear = image.linear()
    np.testing.assert_allclose(linear[..., 3], mtm.ALPHA[..., 3] / 255.0, atol=1e-7)  # alpha: linear
    np.testing.assert_allclose(linear[..., :3], srgb_to_linear(mtm.ALPHA[..., :3] / 255.0), atol=1e-7)


def test_vertex_colours_float_and_normalized(alpha_colors):
    """glTF COLOR_0 is linear: floats as written, normalized u8 / u16 as k / 255 and k / 65535;
    a VEC3 colour gets alpha 1."""
    float3, u8, u16 = (m.colors for m in alpha_colors.meshes)
    np.testing.assert_array_equal(float3, np.concatenate([mtm.COLORS_FLOAT3, np.ones((3, 1))], 1))
    np.testing.assert_allclose(u8, mtm.COLORS_U8 / 255.0, rtol=1e-7)
    np.testing.assert_allclose(u16, mtm.COLORS_U16 / 65535.0, rtol=1e-7)
    assert float3.dtype == np.float32 and u16[2, 0] == np.float32(300 / 65535.0)


def test_integer_colours_without_the_normalized_flag_still_mean_unit_range(tmp_path):
    doc = json.loads((DATA / "alpha_colors.gltf").read_text())
    u8_accessor = doc["meshes"][0]["primitives"][1]["attributes"]["COLOR_0"]
    del doc["accessors"][u8_accessor]["normalized"]
    shutil.copy(DATA / "alpha.png", tmp_path)
    (tmp_path / "a.gltf").write_text(json.dumps(doc))
    colors = load_mesh_asset(tmp_path / "a.gltf").meshes[1].colors
    np.testing.assert_allclose(colors, mtm.COLORS_U8 / 255.0, rtol=1e-7)


# ---------------------------------------------------------------------------------------------
# instancing


def trs(translation, quaternion, scale) -> np.ndarray:
    """An independent glTF TRS matrix (quaternion x, y, z, w)."""
    x, y, z, w = np.asarray(quaternion, dtype=np.float64) / np.linalg.norm(quaternion)
    r = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                  [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                  [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
    m = np.eye(4)
    m[:3, :3] = r @ np.diag(scale)
    m[:3, 3] = translation
    return m


def node_matrix(node: dict) -> np.ndarray:
    return trs(node.get("translation", (0, 0, 0)), node.get("rotation", (0, 0, 0, 1)),
               node.get("scale", (1, 1, 1)))


@pytest.fixture(scope="module")
def instancing():
    return quiet_load(DATA / "instancing.gltf")


def test_mesh_placed_by_two_nodes_is_stored_once(instancing):
    shared = next(i for i in instancing.instanced if i.mesh.name == "shared box/0")
    np.testing.assert_array_equal(shared.mesh.positions, mtm.BOX_POSITIONS)  # local, as in the file
    np.testing.assert_array_equal(shared.mesh.indices, mtm.BOX_INDICES.reshape(-1, 3))  # file winding
    np.testing.assert_allclose(shared.matrices, [node_matrix(n) for n in mtm.SHARED_NODES], atol=1e-12)


def test_gpu_instancing_composes_instance_trs_with_the_node_world_matrix(instancing):
    crowd = next(i for i in instancing.instanced if i.mesh.name == "crowd box/0")
    world = node_matrix(mtm.INSTANCING_PARENT) @ node_matrix(mtm.INSTANCING_NODE)
    rotations = mtm.INSTANCE_ROTATIONS / 32767.0  # normalized shorts
    expected = [world @ trs(t, q, s) for t, q, s in
                zip(mtm.INSTANCE_TRANSLATIONS, rotations, mtm.INSTANCE_SCALES)]
    np.testing.assert_allclose(crowd.matrices, expected, atol=1e-4)  # short quantisation
    assert crowd.matrices.dtype == np.float64 and crowd.instance_count == 3
    np.testing.assert_allclose(crowd.matrices[:, 3], [[0, 0, 0, 1]] * 3)


def test_mesh_placed_once_stays_in_world_space(instancing):
    assert [m.name for m in instancing.meshes] == ["single/single/0"]
    np.testing.assert_allclose(instancing.meshes[0].positions,
                               mtm.TRI_POSITIONS + np.float32(mtm.SINGLE_NODE["translation"]))


def test_instanced_counts_and_bounds(instancing):
    box = len(mtm.BOX_INDICES) // 3
    assert instancing.triangle_count == 1 + 2 * box  # unique: each instanced mesh once
    assert instancing.instanced_triangle_count == 2 * box + 3 * box  # what the instances draw
    assert instancing.drawn_triangle_count == 1 + 5 * box
    assert instancing.vertex_count == 3 + 2 * len(mtm.BOX_POSITIONS)
    points = [instancing.meshes[0].positions] + [
        inst.placed(k).positions for inst in instancing.instanced for k in range(inst.instance_count)]
    everything = np.concatenate(points)
    np.testing.assert_allclose(instancing.bounds, [everything.min(0), everything.max(0)], atol=1e-5)


def test_mirrored_instances_flip_the_front_side(instancing):
    """det < 0: placed() reverses the winding, so the geometric normal of the placed triangles is
    the transformed (cofactor) normal, as for a world mesh under a mirroring node."""
    mirrored = 0
    for inst in instancing.instanced:
        local_n = geometric_normals(inst.mesh.positions, inst.mesh.indices)
        for k, m in enumerate(inst.matrices):
            mesh = inst.placed(k)
            det = np.linalg.det(m[:3, :3])
            mirrored += det < 0
            expected = local_n @ np.linalg.inv(m[:3, :3])  # (inverse transpose @ n) as rows
            expected /= np.linalg.norm(expected, axis=1, keepdims=True)
            np.testing.assert_allclose(geometric_normals(mesh.positions, mesh.indices), expected, atol=1e-6)
            vertex_n = inst.mesh.normals @ np.linalg.inv(m[:3, :3])
            vertex_n /= np.linalg.norm(vertex_n, axis=1, keepdims=True)
            np.testing.assert_allclose(mesh.normals, vertex_n, atol=1e-5)
            flipped = det < 0
            np.testing.assert_array_equal(
                mesh.indices, inst.mesh.indices[:, [0, 2, 1]] if flipped else inst.mesh.indices)
    assert mirrored == 2  # the "mirrored" node and the crowd's last instance


def test_gpu_instancing_errors_are_one_line(tmp_path):
    doc = json.loads((DATA / "instancing.gltf").read_text())
    attributes = doc["nodes"][3]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]
    attributes["SCALE"] = attributes["ROTATION"]  # VEC4 where VEC3 belongs
    path = tmp_path / "bad.gltf"
    path.write_text(json.dumps(doc))
    with pytest.raises(SceneError) as e:
        load_mesh_asset(path)
    assert str(e.value) == f"{path}: nodes[3] EXT_mesh_gpu_instancing: SCALE has 4 components, not 3"
    # SCALE: a copy of the TRANSLATION accessor that reads 2 values where the others have 3
    doc["accessors"].append(dict(doc["accessors"][attributes["TRANSLATION"]], count=2))
    attributes["SCALE"] = len(doc["accessors"]) - 1
    path.write_text(json.dumps(doc))
    with pytest.raises(SceneError) as e:
        load_mesh_asset(path)
    assert "TRANSLATION, ROTATION and SCALE have different counts" in str(e.value)
    assert "\n" not in str(e.value)


def test_assembly_keeps_each_instanced_mesh_once():
    """mesh_assembly stores an instanced mesh once in its own frame with one matrix per placement;
    placing those triangles gives the loader's world-space instances."""
    from renderer.scene.catalog import load_any
    from renderer.scene.mesh_assembly import assemble

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the default environment map may warn
        scene = load_any(DATA / "instancing.gltf")
    asset = scene.model_files.load(DATA / "instancing.gltf")
    data = assemble(scene).data
    assert len(data.tri_vertices) == asset.triangle_count  # unique triangles only
    assert len(data.instance_mesh) == sum(i.instance_count for i in asset.instanced)
    drawn = [data.tri_vertices[:data.world_triangle_count].astype(np.float64)]
    for mesh, m in zip(data.instance_mesh, data.instance_to_world):
        first, count = data.instanced_meshes[mesh]
        drawn.append(data.tri_vertices[first:first + count].astype(np.float64) @ m[:, :3].T + m[:, 3])
    placed = [asset.meshes[0]] + [i.placed(k) for i in asset.instanced for k in range(i.instance_count)]
    expected = np.concatenate([m.positions[m.indices] for m in placed])
    np.testing.assert_allclose(triangle_set(np.concatenate(drawn)), triangle_set(expected), atol=1e-5)


def triangle_set(tris):
    """(T, 9) triangles with their corners in lexicographic order, rows sorted: a mirrored
    placement reverses the winding of placed() only, so compare corners as sets."""
    t = np.round(np.asarray(tris, np.float64), 4) + 0.0
    corners = np.take_along_axis(t, np.lexsort((t[..., 2], t[..., 1], t[..., 0]), axis=1)[..., None], axis=1)
    rows = corners.reshape(-1, 9)
    return rows[np.lexsort(rows.T[::-1])]


# ---------------------------------------------------------------------------------------------
# material layers


@pytest.fixture(scope="module")
def layers():
    return quiet_load(DATA / "layers.gltf")


def by_name(asset):
    return {m.name: m for m in asset.materials}


def test_clearcoat(layers):
    m = by_name(layers)["coated"]
    src = mtm.LAYER_MATERIALS[0]["extensions"]["KHR_materials_clearcoat"]
    assert (m.clearcoat_factor, m.clearcoat_roughness_factor, m.clearcoat_normal_scale) == (
        src["clearcoatFactor"], src["clearcoatRoughnessFactor"], 0.5)
    for ref in (m.clearcoat_texture, m.clearcoat_roughness_texture, m.clearcoat_normal_texture):
        assert not layers.images[ref.texture].srgb  # data slots
    assert m.extensions == ("KHR_materials_clearcoat",)
    # a clearcoat normal map needs tangents even without a base normal map
    mesh = next(x for x in layers.meshes if layers.materials[x.material].name == "coated")
    assert mesh.tangents is not None and m.normal_texture is None


def test_sheen(layers):
    m = by_name(layers)["velvet"]
    assert m.sheen_color_factor == (0.5, 0.25, 1.0) and m.sheen_roughness_factor == 0.625
    colour = layers.images[m.sheen_color_texture.texture]
    roughness = layers.images[m.sheen_roughness_texture.texture]
    assert colour.srgb and not roughness.srgb
    assert colour.pixels is roughness.pixels  # layer.png: one array, read two ways
    np.testing.assert_allclose(roughness.linear()[..., 3], mtm.LAYER[..., 3] / 255.0, atol=1e-7)  # A


def test_specular_with_a_16_bit_colour_texture(layers):
    m = by_name(layers)["tinted"]
    assert (m.specular_factor, m.specular_color_factor) == (0.5, (1.0, 0.5, 0.25))
    assert not layers.images[m.specular_texture.texture].srgb
    colour = layers.images[m.specular_color_texture.texture]
    assert colour.srgb and colour.storage == "half"  # 16 bits per channel survive as half floats
    np.testing.assert_allclose(colour.pixels[..., :3].astype(np.float64), mtm.RGB16 / 65535.0,
                               rtol=2 ** -11, atol=2 ** -24)
    assert np.all(colour.pixels[..., 3] == 1)
    # 1 / 65535 is not 0: a value that 8 bits cannot hold
    assert 0 < colour.pixels[0, 0, 1] < 1 / 255


def test_volume_and_thin_walled(layers):
    m = by_name(layers)
    absorbing = m["absorbing"]
    assert absorbing.has_volume and not absorbing.thin_walled
    assert (absorbing.thickness_factor, absorbing.attenuation_color, absorbing.attenuation_distance) == (
        0.2, (0.9, 0.5, 0.1), 0.05)
    assert absorbing.transmission_factor == 1.0
    assert m["thin"].thin_walled and not m["thin"].has_volume  # transmission without a volume
    defaults = m["volume defaults"]
    assert defaults.has_volume and defaults.thin_walled  # thickness 0 means thin-walled
    assert defaults.attenuation_distance == math.inf and defaults.attenuation_color == (1.0, 1.0, 1.0)
    plain = load_mesh_asset(DATA / "textured_quad.gltf").materials[0]
    assert (plain.clearcoat_factor, plain.sheen_color_factor, plain.specular_factor,
            plain.attenuation_distance) == (0.0, (0.0, 0.0, 0.0), 1.0, math.inf)


def test_layer_textures_pack_with_their_precision(layers):
    tex = pack_atlas(layers.images)
    kinds = sorted({int(r[4]) for r in tex.rects})
    assert kinds == [STORE_RGBA8, STORE_HALF]
    rgba8 = [i for i, r in enumerate(tex.rects) if r[4] == STORE_RGBA8]
    assert len(rgba8) == 2 and np.array_equal(tex.rects[rgba8[0], :5], tex.rects[rgba8[1], :5])


# ---------------------------------------------------------------------------------------------
# an imperfect file: missing texture, unknown extensions


def test_missing_texture_and_unknown_extensions_warn_and_load():
    path = DATA / "imperfect.gltf"
    with pytest.warns(MeshWarning) as caught:
        asset = load_mesh_asset(path)
    assert [str(w.message) for w in caught] == [
        f"{path}: ignoring glTF extension(s) this loader does not implement: "
        "KHR_lights_punctual, KHR_materials_unlit",
        f"{path}: texture file 'missing.png' not found; drawn without it (factors alone): "
        "material 'painted' base colour, material 'painted' metallic-roughness",
    ]
    painted = asset.materials[0]
    assert painted.base_color_texture is None and painted.metallic_roughness_texture is None
    assert painted.base_color_factor == (0.5, 0.25, 0.125, 1.0)
    assert painted.extensions == ("KHR_materials_unlit",)
    assert asset.extensions_used == (*mtm.IGNORED_EXTENSIONS, "KHR_texture_transform")  # file order
    assert asset.extensions_ignored == tuple(mtm.IGNORED_EXTENSIONS)
    assert asset.images == [] and asset.triangle_count == 1


def test_required_unknown_extension_is_still_an_error(tmp_path):
    doc = json.loads((DATA / "imperfect.gltf").read_text())
    doc["extensionsRequired"] = ["KHR_materials_unlit"]
    path = tmp_path / "required.gltf"
    path.write_text(json.dumps(doc))
    with pytest.raises(SceneError) as e:
        load_mesh_asset(path)
    assert str(e.value) == f"{path}: requires unsupported glTF extension(s) KHR_materials_unlit"


def test_supported_extensions_do_not_warn():
    for name in ("layers.gltf", "instancing.gltf", "textured_quad.gltf"):
        asset = quiet_load(DATA / name)
        assert asset.extensions_ignored == ()


# ---------------------------------------------------------------------------------------------
# one parse per model file per run


def test_a_model_scene_is_parsed_once(monkeypatch):
    import renderer.scene.model_files as model_files
    from renderer.scene.catalog import load_any
    from renderer.scene.mesh_assembly import assemble

    calls = []
    real = model_files.load_mesh_asset

    def counting(path, *options):
        calls.append(Path(path))
        return real(path, *options)

    monkeypatch.setattr(model_files, "load_mesh_asset", counting)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_any(DATA / "textured_quad.gltf")  # frames the camera on the parsed asset
        assemble(scene)  # builds the device arrays from the same asset
        assemble(scene)
    assert calls == [DATA / "textured_quad.gltf"]
    assert len(scene.model_files) == 1


def test_model_files_belong_to_their_scene():
    from renderer.scene.model_files import ModelFiles

    a, b = ModelFiles(), ModelFiles()
    first = a.load(DATA / "two_nodes.gltf")
    assert a.load(DATA / ".." / "data" / "two_nodes.gltf") is first  # keyed by resolved path
    assert b.load(DATA / "two_nodes.gltf") is not first  # no cache shared between scenes
    with pytest.raises(SceneError):
        a.load(DATA / "nothing.glb")
