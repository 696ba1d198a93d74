"""Tests for mesh import (glTF/GLB, OBJ+MTL, PLY, STL), tangent generation and the texture atlas.

The small models under tests/data are written by tests/data/make_test_models.py; the expected
values below come from the same constants, so a test failure means the loader disagrees with the
file, not with a copy of its numbers.
"""
from __future__ import annotations

import base64
import json
import math
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

from renderer.scene.errors import SceneError
from renderer.scene.mesh_loader import (
    DegenerateTrianglesWarning,
    MeshWarning,
    frame_camera,
    generate_tangents,
    load_mesh_asset,
    srgb_to_linear,
)
from renderer.scene.mesh_model import IDENTITY_UV_TRANSFORM, TextureImage, uv_transform_matrix
from renderer.scene.textures import (
    STORE_FLOAT,
    STORE_HALF,
    STORE_RGBA8,
    as_rgba,
    pack_atlas,
    sample_bilinear,
    wrap_index,
)
from tests.data import make_test_models as mtm

REPO = Path(__file__).resolve().parents[2]
DATA = REPO / "tests" / "data"
MODELS = REPO / "assets" / "models"


def rgba(pixels: np.ndarray, srgb: bool) -> np.ndarray:
    """What a lookup should read for 8-bit pixels: k / 255, sRGB-decoded if a colour slot."""
    values = pixels.astype(np.float64) / 255.0
    if srgb:
        values = srgb_to_linear(values)
    return as_rgba(values)


def geometric_normals(positions: np.ndarray, indices: np.ndarray) -> np.ndarray:
    p = positions.astype(np.float64)
    n = np.cross(p[indices[:, 1]] - p[indices[:, 0]], p[indices[:, 2]] - p[indices[:, 0]])
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def trs(translation=(0, 0, 0), rotation_y_deg=0.0, scale=(1, 1, 1)) -> np.ndarray:
    """Independent TRS matrix (rotation about +y only: that is all the test files use)."""
    a = math.radians(rotation_y_deg)
    r = np.array([[math.cos(a), 0, math.sin(a)], [0, 1, 0], [-math.sin(a), 0, math.cos(a)]])
    m = np.eye(4)
    m[:3, :3] = r @ np.diag(scale)
    m[:3, 3] = translation
    return m


def one_line_error(excinfo, path) -> str:
    message = str(excinfo.value)
    assert "\n" not in message
    assert message.startswith(f"{path}: "), message
    return message


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
# glTF: textured quad


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
# glTF: node hierarchy


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
# tangent generation


def test_generated_tangents_on_a_curved_grid_are_orthonormal_and_follow_u():
    rng = np.random.default_rng(7)
    n = 9
    u, v = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    theta, phi = u * 2.0, 0.4 + v * 1.5  # a patch of a sphere, u around, v down from the pole
    positions = np.stack([np.sin(phi) * np.cos(theta), np.cos(phi), np.sin(phi) * np.sin(theta)], -1)
    positions = positions.reshape(-1, 3) + rng.normal(0, 1e-3, (n * n, 3))
    normals = positions / np.linalg.norm(positions, axis=1, keepdims=True)
    uvs = np.stack([u, v], -1).reshape(-1, 2)
    quads = np.array([[r * n + c, r * n + c + 1, (r + 1) * n + c + 1, (r + 1) * n + c]
                      for r in range(n - 1) for c in range(n - 1)])
    tri = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    t = generate_tangents(positions, normals, uvs, tri)
    assert t.shape == (n * n, 4) and t.dtype == np.float32
    np.testing.assert_allclose(np.linalg.norm(t[:, :3], axis=1), 1.0, atol=1e-5)
    assert np.abs(np.einsum("ij,ij->i", t[:, :3], normals)).max() < 1e-5
    # T points along dP/du (increasing theta): compare with the analytic derivative direction
    dpdu = np.stack([-np.sin(theta), np.zeros_like(theta), np.cos(theta)], -1).reshape(-1, 3)
    assert np.einsum("ij,ij->i", t[:, :3], dpdu).min() > 0.95
    # B = w * cross(N, T) points towards decreasing stored v (towards the pole: +y here)
    b = t[:, 3:] * np.cross(normals, t[:, :3])
    dpdv = np.stack([np.cos(phi) * np.cos(theta), -np.sin(phi), np.cos(phi) * np.sin(theta)],
                    -1).reshape(-1, 3)
    assert np.einsum("ij,ij->i", b, -dpdv).min() > 0.95


def test_generated_tangents_mirrored_and_rotated_uvs():
    positions = mtm.QUAD_POSITIONS.astype(np.float64)
    normals = mtm.QUAD_NORMALS
    tri = mtm.QUAD_INDICES.reshape(-1, 3)
    mirrored = mtm.QUAD_UV0 * [-1.0, 1.0]  # u runs along -x
    t = generate_tangents(positions, normals, mirrored, tri)
    np.testing.assert_allclose(t, [[-1, 0, 0, -1]] * 4, atol=1e-6)
    rotated = mtm.QUAD_UV0[:, ::-1]  # u runs down the quad (-y), v along +x
    t = generate_tangents(positions, normals, rotated, tri)
    np.testing.assert_allclose(t[:, :3], [[0, -1, 0]] * 4, atol=1e-6)
    b = t[:, 3:] * np.cross(normals, t[:, :3])
    np.testing.assert_allclose(b, [[-1, 0, 0]] * 4, atol=1e-6)  # towards decreasing v


def test_generated_tangents_survive_degenerate_uvs():
    positions = mtm.QUAD_POSITIONS
    t = generate_tangents(positions, mtm.QUAD_NORMALS, np.zeros((4, 2)), mtm.QUAD_INDICES.reshape(-1, 3))
    assert np.isfinite(t).all()
    np.testing.assert_allclose(np.linalg.norm(t[:, :3], axis=1), 1.0, atol=1e-6)
    assert np.abs(t[:, :3] @ [0, 0, 1]).max() < 1e-6


# ---------------------------------------------------------------------------------------------
# OBJ, PLY, STL


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
    assert [s.approximate_spec().kind for s in obj.materials] == [
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


def test_stl_loads(tmp_path):
    import trimesh

    trimesh.creation.box(extents=(1, 2, 3)).export(tmp_path / "box.stl")
    asset = load_mesh_asset(tmp_path / "box.stl")
    assert asset.triangle_count == 12
    np.testing.assert_allclose(asset.bounds, [[-0.5, -1, -1.5], [0.5, 1, 1.5]])


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
    assert m.approximate_spec().kind == "diffuse"


# ---------------------------------------------------------------------------------------------
# bad input: one line each, naming the file


def write_gltf(path: Path, positions, indices, extra_doc=None) -> Path:
    b = mtm.BufferBuilder()
    position_accessor = b.accessor(np.asarray(positions, dtype=np.float32))
    index_accessor = b.accessor(np.asarray(indices, dtype=np.uint16))
    for accessor in b.accessors:  # min / max would hold NaN for the bad-input cases
        accessor.pop("min", None)
        accessor.pop("max", None)
    doc = {
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"name": "m", "primitives": [
            {"attributes": {"POSITION": position_accessor}, "indices": index_accessor}]}],
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": [{"byteLength": len(b.data), "uri": "data:application/octet-stream;base64,"
                     + base64.b64encode(bytes(b.data)).decode()}],
    }
    doc.update(extra_doc or {})
    path.write_text(json.dumps(doc))
    return path


TRIANGLE = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]


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
    (tmp_path / "checker.png").write_bytes(b"not a png")
    with pytest.raises(SceneError) as e:
        load_mesh_asset(path)
    assert "cannot decode image images[0] 'checker.png'" in one_line_error(e, path)
    shutil.copy(DATA / "checker.png", tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert load_mesh_asset(path).triangle_count == 2


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


def test_points_and_lines_are_skipped_with_a_warning(tmp_path):
    path = write_gltf(tmp_path / "lines.gltf", TRIANGLE, [0, 1, 2])
    doc = json.loads(path.read_text())
    doc["meshes"][0]["primitives"].append(dict(doc["meshes"][0]["primitives"][0], mode=1))
    path.write_text(json.dumps(doc))
    with pytest.warns(MeshWarning, match="skipped 1 point or line primitives"):
        asset = load_mesh_asset(path)
    assert asset.triangle_count == 1


# ---------------------------------------------------------------------------------------------
# framing


def test_frame_camera_fits_the_bounding_sphere():
    bounds = np.array([[-1.0, 0.0, -2.0], [3.0, 2.0, 0.0]])
    position, look_at = frame_camera(bounds, 45.0)
    centre = bounds.mean(axis=0)
    np.testing.assert_allclose(look_at, centre)
    radius = 0.5 * np.linalg.norm(bounds[1] - bounds[0])
    distance = np.linalg.norm(np.subtract(position, centre))
    assert radius / distance == pytest.approx(math.sin(math.radians(22.5)) / 1.1)
    direction = np.subtract(position, centre) / distance
    assert direction[2] > 0.9 and direction[1] > 0  # in front (+z), slightly above
    # a portrait viewport is limited by its horizontal field of view: back off further
    narrow, _ = frame_camera(bounds, 45.0, aspect=0.5)
    assert np.linalg.norm(np.subtract(narrow, centre)) > distance
    # a single point still gives a usable camera
    p, a = frame_camera([[1, 1, 1], [1, 1, 1]], 60.0)
    assert np.linalg.norm(np.subtract(p, a)) > 0


def test_frame_camera_on_bunny():
    asset = load_mesh_asset(MODELS / "bunny.glb")
    position, look_at = frame_camera(asset.bounds, 40.0, aspect=16 / 9)
    assert all(math.isfinite(v) for v in position + look_at)


# ---------------------------------------------------------------------------------------------
# texture atlas


def random_images(seed=3):
    rng = np.random.default_rng(seed)
    shapes = [(5, 7, 3), (16, 4, 4), (1, 1, 1), (9, 9), (3, 12, 2), (30, 2, 3), (2, 30, 4)]
    return [rng.random(s).astype(np.float32) for s in shapes]


def mixed_images(seed=4):
    """8-bit, half and float images, one 8-bit array used twice (as data and as colour)."""
    rng = np.random.default_rng(seed)
    shared = rng.integers(0, 256, (6, 5, 4), dtype=np.uint8)
    return [TextureImage(shared), TextureImage(rng.integers(0, 256, (3, 9, 4), dtype=np.uint8)),
            TextureImage(shared, srgb=True),
            TextureImage(rng.random((4, 4, 4)).astype(np.float16), srgb=True),
            TextureImage(rng.random((2, 7, 4)).astype(np.float32))]


def test_atlas_no_overlap_and_exact_recovery():
    images = random_images()
    pad = 2
    tex = pack_atlas(images, padding=pad)
    page = tex.pages[STORE_FLOAT]
    assert page.dtype == np.float32 and page.shape[2] == 4 and tex.rects.dtype == np.int32
    owner = np.full(page.shape[:2], -1)
    for i, (x, y, w, h, storage, srgb) in enumerate(tex.rects):
        assert (storage, srgb) == (STORE_FLOAT, 0)
        assert x >= pad and y >= pad and x + w + pad <= page.shape[1] and y + h + pad <= page.shape[0]
        region = owner[y - pad:y + h + pad, x - pad:x + w + pad]
        assert (region == -1).all(), f"image {i} overlaps another (padding included)"
        region[:] = i
        np.testing.assert_array_equal(tex.texels(i), as_rgba(images[i]))
        assert (w, h) == (images[i].shape[1], images[i].shape[0])


def test_atlas_keeps_each_storage_and_stores_shared_pixels_once():
    images = mixed_images()
    tex = pack_atlas(images, padding=1)
    assert [int(r[4]) for r in tex.rects] == [STORE_RGBA8, STORE_RGBA8, STORE_RGBA8, STORE_HALF, STORE_FLOAT]
    assert [int(r[5]) for r in tex.rects] == [0, 0, 1, 1, 0]
    np.testing.assert_array_equal(tex.rects[0, :5], tex.rects[2, :5])  # one rectangle, two decodings
    for i, image in enumerate(images):
        assert tex.texels(i).dtype == image.pixels.dtype
        np.testing.assert_array_equal(tex.texels(i), image.pixels)
    # the 8-bit page holds the two distinct 8-bit images only: (6+2)x(5+2) and (3+2)x(9+2) texels
    assert tex.pages[STORE_RGBA8].dtype == np.uint8
    assert np.count_nonzero(tex.pages[STORE_RGBA8].any(axis=2)) <= 8 * 7 + 5 * 11
    assert tex.nbytes == sum(tex.pages[s].nbytes for s in (STORE_RGBA8, STORE_HALF, STORE_FLOAT))
    only_bytes = pack_atlas(images[:3])
    assert only_bytes.storages == {STORE_RGBA8}
    assert only_bytes.nbytes == only_bytes.pages[STORE_RGBA8].nbytes  # unused pages cost nothing
    for storage in (STORE_HALF, STORE_FLOAT):
        assert only_bytes.pages[storage].shape == (1, 1, 4)


def test_atlas_padding_replicates_edges():
    images = random_images()
    pad = 3
    tex = pack_atlas(images, padding=pad)
    for i, (x, y, w, h, storage, _) in enumerate(tex.rects):
        padded = tex.pages[storage][y - pad:y + h + pad, x - pad:x + w + pad]
        image = as_rgba(images[i])
        np.testing.assert_array_equal(padded, np.pad(image, ((pad, pad), (pad, pad), (0, 0)), mode="edge"))
        np.testing.assert_array_equal(padded[0, 0], image[0, 0])  # corners replicate the corner


def test_atlas_is_roughly_square_and_handles_empty():
    tex = pack_atlas(random_images())
    width, height = tex.page_size(STORE_FLOAT)
    assert 0.25 < width / height < 4
    empty = pack_atlas([])
    assert all(page.shape == (1, 1, 4) for page in empty.pages.values())
    assert empty.rects.shape == (0, 6) and empty.nbytes == 0
    with pytest.raises(ValueError):
        pack_atlas(random_images(), width=4)


def test_reference_sampler_texel_centres_and_wrapping():
    images = random_images()
    tex = pack_atlas(images, padding=1)
    index = 0
    image = as_rgba(images[index])
    h, w = image.shape[:2]
    j, i = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
    centres = np.stack([(i + 0.5) / w, (j + 0.5) / h], -1)
    np.testing.assert_allclose(sample_bilinear(tex, index, centres), image, atol=1e-6)
    # repeat: shifting by whole periods changes nothing; across the seam texels w-1 and 0 blend
    np.testing.assert_allclose(sample_bilinear(tex, index, centres + [3.0, -2.0]), image, atol=1e-5)
    seam = sample_bilinear(tex, index, np.array([1.0, (0.5) / h]))
    np.testing.assert_allclose(seam, 0.5 * (image[0, w - 1] + image[0, 0]), atol=1e-6)
    # clamp: beyond the edge is the edge texel
    np.testing.assert_allclose(sample_bilinear(tex, index, np.array([-5.0, 0.5 / h]), "clamp", "clamp"),
                               image[0, 0], atol=1e-6)
    # mirror: u in (1, 2) reads the image backwards
    mirrored = sample_bilinear(tex, index, centres + [1.0, 0.0], "mirror", "repeat")
    np.testing.assert_allclose(mirrored, image[:, ::-1], atol=1e-6)
    np.testing.assert_array_equal(wrap_index(np.arange(-3, 7), 3, "mirror"),
                                  [2, 1, 0, 0, 1, 2, 2, 1, 0, 0])
    np.testing.assert_array_equal(wrap_index(np.arange(-3, 4), 3, "repeat"), [0, 1, 2, 0, 1, 2, 0])


def test_reference_sampler_decodes_each_tap_before_blending():
    """Half-way between a black and a white sRGB texel the lookup reads 0.5 (the mean of the
    decoded values), not the decoded mean of the codes (0.214); alpha is never decoded."""
    pixels = np.array([[[0, 0, 0, 0], [255, 255, 255, 255]]], dtype=np.uint8)
    tex = pack_atlas([TextureImage(pixels, srgb=True), TextureImage(pixels)])
    for index in (0, 1):
        middle = sample_bilinear(tex, index, np.array([0.5, 0.5]), "clamp", "clamp")
        np.testing.assert_allclose(middle, [0.5, 0.5, 0.5, 0.5], atol=1e-6)
    grey = np.full((1, 1, 4), 128, dtype=np.uint8)
    tex = pack_atlas([TextureImage(grey, srgb=True)])
    value = sample_bilinear(tex, 0, np.array([0.3, 0.7]))
    np.testing.assert_allclose(value, [*srgb_to_linear([128 / 255.0] * 3), 128 / 255.0], atol=1e-7)
    for image in mixed_images():  # at texel centres: exactly TextureImage.linear()
        tex = pack_atlas([image])
        h, w = image.shape
        j, i = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
        centres = np.stack([(i + 0.5) / w, (j + 0.5) / h], -1)
        np.testing.assert_allclose(sample_bilinear(tex, 0, centres), image.linear(), atol=1e-6)


def test_texture_transform_spec_example():
    """KHR_texture_transform: offset (0, 1), rotation 90 deg, scale 0.5 = lower-left quadrant."""
    m = uv_transform_matrix((0.0, 1.0), math.pi / 2, (0.5, 0.5))
    corners = np.array([[0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], dtype=np.float64)
    uv = corners @ m.T
    assert (uv[:, 0] > -1e-9).all() and (uv[:, 0] < 0.5 + 1e-9).all()
    assert (uv[:, 1] > 0.5 - 1e-9).all() and (uv[:, 1] < 1.0 + 1e-9).all()


def test_atlas_from_a_loaded_asset(quad):
    tex = pack_atlas(quad.images)
    m = quad.materials[0]
    ref = m.base_color_texture
    np.testing.assert_array_equal(tex.texels(ref.texture), quad.images[ref.texture].pixels)
    assert tex.rects[ref.texture, 5] == 1  # base colour: decoded as sRGB in the lookup
    # the sampler contract: slot matrix, then wrap modes, then bilinear inside the rectangle
    value = sample_bilinear(tex, ref.texture, np.array([0.3, 0.6]), ref.wrap_s, ref.wrap_t, ref.matrix)
    assert value.shape == (4,) and np.isfinite(value).all()
