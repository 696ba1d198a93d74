"""glTF and GLB files read (renderer/scene/model_formats/gltf.py): a textured quad with every texture
slot, a node hierarchy with instancing, mirroring and flattening transforms, broken containers.

The small models under tests/data are written by tests/data/make_test_models.py; the expected
values below come from the same constants, so a test failure means the loader disagrees with the
file, not with a copy of its numbers.
"""
from __future__ import annotations

import json
import math
import shutil

import numpy as np
import pytest

from renderer.scene.errors import SceneError
from renderer.scene.mesh_model import IDENTITY_UV_TRANSFORM, uv_transform_matrix
from renderer.scene.model_formats import MeshWarning, load_mesh_asset
from tests.data import make_test_models as mtm
from tests.scene.model_file_helpers import DATA, TRIANGLE, geometric_normals, one_line_error, rgba, trs, write_gltf


# ---------------------------------------------------------------------------------------------
# textured quad


@pytest.fixture(scope="module")
def quad():
    return load_mesh_asset(DATA / "textured_quad.gltf")


def test_quad_geometry_exact(quad):
    assert len(quad.meshes) == 1
    mesh = quad.meshes[0]
    np.testing.assert_array_equal(mesh.positions, mtm.QUAD_POSITIONS + np.float32(mtm.QUAD_TRANSLATION))
    np.testing.assert_array_equal(mesh.indices, mtm.QUAD_INDICES.reshape(-1, 3))
    np.testing.assert_array_equal(mesh.normals, mtm.QUAD_NORMALS)
    np.testing.assert_array_equal(mesh.uv0, mtm.QUAD_UV0)
    np.testing.assert_array_equal(mesh.uv1, mtm.QUAD_UV1)
    assert mesh.uv(0) is mesh.uv0 and mesh.uv(1) is mesh.uv1
    assert mesh.colors is None
    assert mesh.positions.dtype == np.float32 and mesh.indices.dtype == np.int32
    np.testing.assert_array_equal(quad.bounds, [[-0.5, -1, 0], [1.5, 1, 0]])


def test_quad_material_factors_and_extensions(quad):
    m = quad.materials[0]
    src = mtm.QUAD_MATERIAL
    assert m.name == "quad"
    assert m.base_color_factor == pytest.approx(src["pbrMetallicRoughness"]["baseColorFactor"])
    assert m.metallic_factor == 0.25 and m.roughness_factor == 0.625
    # emissive factor times KHR_materials_emissive_strength (4)
    assert m.emissive_factor == pytest.approx((4.0, 2.0, 1.0))
    assert m.transmission_factor == 0.375
    assert m.ior == pytest.approx(1.33)
    assert m.normal_scale == 0.75
    assert (m.alpha_mode, m.alpha_cutoff, m.double_sided) == ("MASK", 0.25, True)
    assert m.is_emissive
    # occlusion is ignored by design: no slot for it
    assert set(m.texture_slots) == {"base_color", "metallic_roughness", "normal", "emissive"}


def test_quad_texture_slots(quad):
    m = quad.materials[0]
    base = m.base_color_texture
    assert (base.uv_set, base.wrap_s, base.wrap_t) == (0, "repeat", "mirror")
    assert (base.mag_filter, base.min_filter) == ("nearest", "linear_mipmap_linear")
    expected = uv_transform_matrix((0.25, 0.5), 0.5, (2.0, 3.0))
    np.testing.assert_allclose(base.matrix, expected, rtol=1e-6)
    # T * R * S written out: (1, 0) -> offset + 2 * (cos, -sin)
    np.testing.assert_allclose(base.matrix @ [1, 0, 1],
                               [0.25 + 2 * math.cos(0.5), 0.5 - 2 * math.sin(0.5), 1], rtol=1e-6)
    assert base.has_transform

    mr = m.metallic_roughness_texture
    assert (mr.uv_set, mr.wrap_s, mr.wrap_t, mr.transform) == (1, "clamp", "clamp",
                                                               IDENTITY_UV_TRANSFORM)
    normal = m.normal_texture
    assert (normal.uv_set, normal.wrap_s, normal.wrap_t) == (0, "repeat", "repeat")
    assert normal.mag_filter is None and not normal.has_transform
    emissive = m.emissive_texture
    assert emissive.texture == base.texture  # same image, same (sRGB) encoding: one copy
    assert not emissive.has_transform


def test_quad_images_colour_spaces(quad):
    m, second = quad.materials
    images = quad.images
    assert len(images) == 4
    for image in images:  # 8-bit files stay 8-bit, RGBA
        assert image.pixels.dtype == np.uint8 and image.pixels.shape[2] == 4
    base, mr = images[m.base_color_texture.texture], images[m.metallic_roughness_texture.texture]
    assert base.srgb and not mr.srgb and not images[m.normal_texture.texture].srgb
    np.testing.assert_array_equal(base.pixels[..., :3], mtm.CHECKER)
    np.testing.assert_allclose(base.linear(), rgba(mtm.CHECKER, True), atol=1e-6)
    np.testing.assert_allclose(mr.linear(), rgba(mtm.MR, False), atol=1e-7)
    np.testing.assert_allclose(images[m.normal_texture.texture].linear(), rgba(mtm.NORMAL, False),
                               atol=1e-7)
    # mr.png is also a base colour: a second entry that decodes sRGB, sharing the same pixels
    other = images[second.base_color_texture.texture]
    assert other is not mr and other.pixels is mr.pixels
    np.testing.assert_allclose(other.linear(), rgba(mtm.MR, True), atol=1e-6)
    assert other.label == mr.label == "images[1] 'mr.png'"


def test_glb_matches_gltf(quad):
    glb = load_mesh_asset(DATA / "textured_quad.glb")
    assert glb.materials == quad.materials
    assert glb.images == quad.images  # same pixels, same decoding
    for field in ("positions", "indices", "normals", "uv0", "uv1", "tangents"):
        np.testing.assert_array_equal(getattr(glb.meshes[0], field), getattr(quad.meshes[0], field))


def test_quad_tangents_follow_uv_directions(quad):
    mesh = quad.meshes[0]
    assert mesh.tangents is not None  # generated: the material has a normal map, the file no TANGENT
    t, w = mesh.tangents[:, :3], mesh.tangents[:, 3]
    # u grows along +x; stored v grows down the image, i.e. along -y, so "image up" is +y
    np.testing.assert_allclose(t, [[1, 0, 0]] * 4, atol=1e-6)
    np.testing.assert_array_equal(w, [1, 1, 1, 1])
    bitangent = w[:, None] * np.cross(mesh.normals, t)
    np.testing.assert_allclose(bitangent, [[0, 1, 0]] * 4, atol=1e-6)


# ---------------------------------------------------------------------------------------------
# node hierarchy


@pytest.fixture(scope="module")
def nodes():
    return load_mesh_asset(DATA / "two_nodes.gltf")


def node_matrices():
    parent = trs(mtm.PARENT["translation"], 90.0, mtm.PARENT["scale"])
    child_a = np.array(mtm.CHILD_A_MATRIX, dtype=np.float64).reshape(4, 4).T
    child_b = trs(mtm.CHILD_B["translation"])
    mirror = trs(mtm.MIRROR["translation"], 0.0, mtm.MIRROR["scale"])
    return {"child_a": parent @ child_a, "child_b": parent @ child_b, "mirror": mirror}


def apply(m: np.ndarray, p: np.ndarray) -> np.ndarray:
    return p.astype(np.float64) @ m[:3, :3].T + m[:3, 3]


def placed(asset, name: str, k: int):
    """Instance k of the instanced mesh called `name`, in world space."""
    return next(i for i in asset.instanced if i.mesh.name == name).placed(k)


def test_mesh_used_by_two_nodes_is_stored_once(nodes):
    """Contract: a mesh placed by two nodes is one local-space mesh with two matrices (it used to
    be two world-space copies); a mesh placed once stays in world space."""
    assert [m.name for m in nodes.meshes] == ["mirror/pair/0", "mirror/pair/1"]
    assert [i.mesh.name for i in nodes.instanced] == ["tri/0"]
    tri = nodes.instanced[0]
    matrices = node_matrices()
    np.testing.assert_allclose(tri.matrices, [matrices["child_a"], matrices["child_b"]], atol=1e-12)
    assert tri.matrices.dtype == np.float64 and tri.matrices.shape == (2, 4, 4)
    np.testing.assert_array_equal(tri.mesh.positions, mtm.TRI_POSITIONS)  # local: as in the file
    np.testing.assert_array_equal(tri.mesh.normals, mtm.TRI_NORMALS)
    assert nodes.triangle_count == 1 + 3 + 2  # unique
    assert nodes.instanced_triangle_count == 2 and nodes.drawn_triangle_count == 2 + 3 + 2


def test_node_transforms_applied_to_positions(nodes):
    matrices = node_matrices()
    for k, node in enumerate(("child_a", "child_b")):
        np.testing.assert_allclose(placed(nodes, "tri/0", k).positions,
                                   apply(matrices[node], mtm.TRI_POSITIONS), atol=1e-6)
    by_name = {m.name: m for m in nodes.meshes}
    np.testing.assert_allclose(by_name["mirror/pair/0"].positions,
                               apply(matrices["mirror"], mtm.STRIP_POSITIONS), atol=1e-6)
    everything = np.concatenate([m.positions for m in nodes.meshes]
                                + [placed(nodes, "tri/0", k).positions for k in range(2)])
    np.testing.assert_allclose(nodes.bounds, [everything.min(0), everything.max(0)], atol=1e-6)


def test_normals_use_inverse_transpose_under_nonuniform_scale(nodes):
    matrices = node_matrices()
    for k, node in enumerate(("child_a", "child_b")):
        mesh = placed(nodes, "tri/0", k)
        m3 = matrices[node][:3, :3]
        expected = mtm.TRI_NORMALS[0] @ np.linalg.inv(m3)
        expected /= np.linalg.norm(expected)
        np.testing.assert_allclose(mesh.normals, [expected] * 3, atol=1e-6)
        np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-6)
        # The file's normal is its plane normal, so the transformed one must be the world
        # triangle's plane normal...
        np.testing.assert_allclose(geometric_normals(mesh.positions, mesh.indices)[0], expected,
                                   atol=1e-6)
        # ...which transforming with M itself would get wrong (the scale is not uniform).
        naive = m3 @ mtm.TRI_NORMALS[0]
        assert not np.allclose(naive / np.linalg.norm(naive), expected, atol=1e-3)


def test_flattening_node_transform_keeps_normals_defined(tmp_path):
    """A zero scale has no inverse; normals still follow the flattened triangle (cofactor matrix)."""
    doc = json.loads((DATA / "two_nodes.gltf").read_text())
    doc["nodes"][0]["scale"] = [0.0, 1.0, 1.0]
    path = tmp_path / "flat.gltf"
    path.write_text(json.dumps(doc))
    asset = load_mesh_asset(path)
    for mesh in (placed(asset, "tri/0", k) for k in range(2)):
        assert np.isfinite(mesh.normals).all()
        np.testing.assert_allclose(mesh.normals, np.repeat(
            geometric_normals(mesh.positions, mesh.indices), 3, axis=0), atol=1e-6)


def test_file_tangents_are_transformed(nodes):
    matrices = node_matrices()
    np.testing.assert_array_equal(nodes.instanced[0].mesh.tangents, mtm.TRI_TANGENTS)  # local
    mesh = placed(nodes, "tri/0", 0)
    t = matrices["child_a"][:3, :3] @ mtm.TRI_TANGENTS[0, :3]
    np.testing.assert_allclose(mesh.tangents[:, :3], [t / np.linalg.norm(t)] * 3, atol=1e-6)
    np.testing.assert_array_equal(mesh.tangents[:, 3], [-1, -1, -1])
    assert np.abs(np.einsum("ij,ij->i", mesh.tangents[:, :3], mesh.normals)).max() < 1e-6


def test_mirroring_node_keeps_front_faces(nodes):
    """det(M) < 0: the winding is reversed so the geometric normal still transforms like a normal."""
    mirror = node_matrices()["mirror"][:3, :3]
    mesh = next(m for m in nodes.meshes if m.name == "mirror/pair/0")
    strip = np.array([[0, 1, 2], [1, 3, 2], [2, 3, 4]])  # glTF strip order, before mirroring
    local = geometric_normals(mtm.STRIP_POSITIONS, strip)
    expected = local @ np.linalg.inv(mirror)
    np.testing.assert_allclose(geometric_normals(mesh.positions, mesh.indices), expected, atol=1e-6)
    np.testing.assert_array_equal(mesh.indices, strip[:, [0, 2, 1]])


def test_mirrored_tangent_handedness_flips(tmp_path):
    doc = json.loads((DATA / "two_nodes.gltf").read_text())
    doc["nodes"][3]["mesh"] = 0  # the mirror node now shows the triangle with TANGENT
    path = tmp_path / "mirrored.gltf"
    path.write_text(json.dumps(doc))
    asset = load_mesh_asset(path)
    assert asset.instanced[0].instance_count == 3  # child_a, child_b, mirror
    mesh = placed(asset, "tri/0", 2)
    m3 = node_matrices()["mirror"][:3, :3]
    np.testing.assert_array_equal(mesh.tangents[:, 3], [1, 1, 1])  # -1 in the file
    # The bitangent must still be the transformed file bitangent B = w * cross(N, T).
    n, t = mtm.TRI_NORMALS[0].astype(np.float64), mtm.TRI_TANGENTS[0, :3].astype(np.float64)
    b_local = mtm.TRI_TANGENTS[0, 3] * np.cross(n, t)
    b_world = m3 @ b_local
    b_loaded = mesh.tangents[0, 3] * np.cross(mesh.normals[0], mesh.tangents[0, :3])
    assert np.dot(b_loaded, b_world) > 0.99 * np.linalg.norm(b_world)


def test_instance_placement_matches_world_placement(tmp_path):
    """`InstancedMesh.placed` gives what the loader gives for the same mesh placed once."""
    doc = json.loads((DATA / "two_nodes.gltf").read_text())
    doc["nodes"][3]["mesh"] = 0
    (tmp_path / "all.gltf").write_text(json.dumps(doc))
    instanced = load_mesh_asset(tmp_path / "all.gltf").instanced[0]
    for k, node in enumerate((1, 2, 3)):  # child_a, child_b, mirror (depth-first order)
        once = json.loads(json.dumps(doc))
        for other in {1, 2, 3} - {node}:
            once["nodes"][other].pop("mesh")
        (tmp_path / f"once{k}.gltf").write_text(json.dumps(once))
        world = next(m for m in load_mesh_asset(tmp_path / f"once{k}.gltf").meshes
                     if m.name.endswith("/tri/0"))
        mesh = instanced.placed(k)
        np.testing.assert_array_equal(mesh.indices, world.indices)  # winding reversed if mirrored
        for field in ("positions", "normals", "tangents"):
            np.testing.assert_allclose(getattr(mesh, field), getattr(world, field), atol=1e-6)


def test_strip_colors_sparse_and_default_material(nodes):
    strip, no_material = nodes.meshes[0], nodes.meshes[1]
    expected = np.concatenate([mtm.STRIP_COLORS / 255.0, np.ones((5, 1))], axis=1)
    np.testing.assert_allclose(strip.colors, expected, atol=1e-7)  # COLOR_0 is linear in glTF
    assert strip.material == 0 and nodes.materials[0].name == "pair"
    sparse_vertex = apply(node_matrices()["mirror"], mtm.SPARSE_VALUE)[0]
    np.testing.assert_allclose(no_material.positions[mtm.SPARSE_INDEX], sparse_vertex)
    np.testing.assert_allclose(no_material.positions[:4], strip.positions[:4])
    default = nodes.materials[no_material.material]
    assert no_material.material == 1 and len(nodes.materials) == 2
    assert (default.name, default.base_color_factor, default.metallic_factor,
            default.roughness_factor) == ("default", (1, 1, 1, 1), 1.0, 1.0)


def test_normal_map_without_normals_gets_flat_normals_and_tangents(tmp_path):
    doc, binary = mtm.quad_document(embed_images=False)
    del doc["meshes"][0]["primitives"][0]["attributes"]["NORMAL"]
    (tmp_path / "quad.bin").write_bytes(binary)
    doc["buffers"][0]["uri"] = "quad.bin"
    for name in ("checker.png", "mr.png", "normal.png"):
        shutil.copy(DATA / name, tmp_path / name)
    (tmp_path / "quad.gltf").write_text(json.dumps(doc))
    mesh = load_mesh_asset(tmp_path / "quad.gltf").meshes[0]
    assert mesh.vertex_count == 6  # split per triangle: flat shading, as glTF prescribes
    np.testing.assert_allclose(mesh.normals, [[0, 0, 1]] * 6, atol=1e-7)
    np.testing.assert_allclose(mesh.tangents, [[1, 0, 0, 1]] * 6, atol=1e-6)


# ---------------------------------------------------------------------------------------------
# bad containers and primitives: one line each, naming the file


def test_broken_containers(tmp_path):
    cases = {
        "truncated.glb": (DATA / "textured_quad.glb").read_bytes()[:100],
        "garbage.glb": b"\0" * 64,
        "bad.gltf": b"{ not json",
        "old.gltf": json.dumps({"asset": {"version": "1.0"}}).encode(),
        "draco.gltf": json.dumps({"asset": {"version": "2.0"},
                                  "extensionsRequired": ["KHR_draco_mesh_compression"]}).encode(),
    }
    expected = {"truncated.glb": "truncated", "garbage.glb": "not a GLB file",
                "bad.gltf": "invalid glTF JSON", "old.gltf": "glTF version '1.0' is not supported",
                "draco.gltf": "requires unsupported glTF extension(s) KHR_draco_mesh_compression"}
    for name, data in cases.items():
        path = tmp_path / name
        path.write_bytes(data)
        with pytest.raises(SceneError) as e:
            load_mesh_asset(path)
        assert expected[name] in one_line_error(e, path), name


def test_accessor_past_end_of_buffer(tmp_path):
    path = write_gltf(tmp_path / "short.gltf", TRIANGLE, [0, 1, 2])
    doc = json.loads(path.read_text())
    doc["accessors"][0]["count"] = 1000
    path.write_text(json.dumps(doc))
    with pytest.raises(SceneError) as e:
        load_mesh_asset(path)
    assert "accessors[0] reads past the end of bufferViews[0]" in one_line_error(e, path)


def test_points_and_lines_are_skipped_with_a_warning(tmp_path):
    path = write_gltf(tmp_path / "lines.gltf", TRIANGLE, [0, 1, 2])
    doc = json.loads(path.read_text())
    doc["meshes"][0]["primitives"].append(dict(doc["meshes"][0]["primitives"][0], mode=1))
    path.write_text(json.dumps(doc))
    with pytest.warns(MeshWarning, match="skipped 1 point or line primitives"):
        asset = load_mesh_asset(path)
    assert asset.triangle_count == 1
