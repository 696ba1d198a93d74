"""Shapes (renderer/scene/pbrt/shapes.py, inline_meshes.py): inline meshes as parts of the scene
file, PLY files (gzip too), spheres, disks, cylinders, and what warns."""
from __future__ import annotations

import gzip

import numpy as np
import trimesh

from renderer.scene.mesh_assembly import assemble

from tests.scene.pbrt.pbrt_helpers import load

QUAD = ('Shape "trianglemesh" "point3 P" [-1 0 -1  1 0 -1  1 0 1  -1 0 1] "integer indices" [0 2 1 0 3 2] '
        '"point2 uv" [0 0 1 0 1 1 0 1] "normal N" [0 1 0 0 1 0 0 1 0 0 1 0]\n')


def asset_mesh(scene, obj):
    asset = scene.model_files.load(obj.file)
    return next(m for m in asset.meshes if m.name == obj.part)


def test_trianglemesh_is_a_part_of_the_scene_file_with_v_turned_over(tmp_path):
    scene, _ = load(tmp_path, QUAD + "ReverseOrientation\n" + QUAD)
    first, second = scene.mesh_objects
    assert first.file == scene.path and (first.part, second.part) == ("mesh 0", "mesh 1")
    assert (first.flip_normals, second.flip_normals) == (False, True)
    mesh = asset_mesh(scene, first)
    assert len(mesh.indices) == 2
    assert sorted(mesh.uv0[:, 1].tolist()) == [0.0, 0.0, 1.0, 1.0]
    uv_of = {tuple(np.round(p, 3)): tuple(uv) for p, uv in zip(mesh.positions, mesh.uv0)}
    assert uv_of[(-1.0, 0.0, -1.0)] == (0.0, 1.0)  # pbrt's v = 0 is Lantern's 1


def test_bilinear_patch_is_two_triangles_facing_dpdu_x_dpdv(tmp_path):
    scene, _ = load(tmp_path, 'Shape "bilinearmesh" "point3 P" [0 0 0  1 0 0  0 1 0  1 1 0]\n')
    mesh = asset_mesh(scene, scene.mesh_objects[0])
    p = mesh.positions[mesh.indices[0]]
    assert len(mesh.indices) == 2 and np.cross(p[1] - p[0], p[2] - p[0])[2] > 0


def test_plymesh_plain_and_gzipped(tmp_path):
    box = trimesh.creation.box()
    (tmp_path / "box.ply").write_bytes(trimesh.exchange.ply.export_ply(box))
    (tmp_path / "box.ply.gz").write_bytes(gzip.compress(trimesh.exchange.ply.export_ply(box)))
    scene, _ = load(tmp_path, 'Shape "plymesh" "string filename" "box.ply"\nShape "plymesh" "string filename" '
                              '"box.ply.gz"\n')
    plain, packed = scene.mesh_objects
    assert plain.file == tmp_path / "box.ply" and packed.file == scene.path
    assert len(asset_mesh(scene, packed).indices) == 12
    assert assemble(scene) is not None  # both files assemble


def test_missing_ply_warns_and_the_rest_renders(tmp_path):
    scene, messages = load(tmp_path, 'Shape "plymesh" "string filename" "gone.ply"\nShape "sphere"\n',
                           expect_warnings=1)
    assert [o.kind for o in scene.mesh_objects] == ["sphere"]
    assert 'line 5: Shape "plymesh": gone.ply: ' in messages[0] and "left out" in messages[0]


def test_an_unreadable_ply_is_left_out_with_a_warning_and_the_rest_renders(tmp_path):
    """One malformed mesh of many (here: every triangle degenerate) leaves its shape out, with a
    warning naming the file, where a model file given alone stops with an error."""
    import warnings

    flat = trimesh.Trimesh(vertices=[[0, 0, 0], [1, 0, 0], [2, 0, 0]], faces=[[0, 1, 2]], process=False)
    (tmp_path / "flat.ply").write_bytes(trimesh.exchange.ply.export_ply(flat))
    scene, _ = load(tmp_path, 'Shape "plymesh" "string filename" "flat.ply"\nShape "sphere"\n')
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assembly = assemble(scene)
    messages = [str(w.message) for w in caught]
    assert any("flat.ply" in m and "the shape is left out" in m for m in messages), messages
    assert len(assembly.data.spheres) == 1  # the sphere is there


def test_sphere_disk_cylinder(tmp_path):
    scene, messages = load(tmp_path, 'Shape "sphere" "float radius" 2 "float zmax" 1\n'
                                     'Scale 1 2 1\nShape "sphere"\nShape "disk" "float radius" 3 "float height" 1\n'
                                     'Shape "cylinder" "float zmin" 0 "float zmax" 2\n', expect_warnings=1)
    sphere, ellipsoid, disk, cylinder = scene.mesh_objects
    assert (sphere.kind, sphere.radius) == ("sphere", 2.0) and "zmin, zmax and phimax" in messages[0]
    assert (ellipsoid.kind, ellipsoid.generator) == ("generated", "icosphere")
    assert disk.generator == "disc_fan" and dict(disk.params)["radius"] == 3.0
    assert np.allclose(disk.matrix() @ [0, 0, 0, 1], [0, 0, 1, 1])  # at its height on z
    assert np.allclose(disk.matrix()[:3, :3] @ [0, 1, 0], [0, 0, 1])  # the fan's normal (+y) is pbrt's +z
    assert cylinder.generator == "cylinder"


def test_mirroring_transform_turns_a_sphere_inwards_as_pbrt_does(tmp_path):
    scene, _ = load(tmp_path, 'Scale -1 1 1\nShape "sphere"\nReverseOrientation\nShape "sphere"\n')
    assert [o.flip_normals for o in scene.mesh_objects] == [True, False]


def test_unsupported_shape_warns_once_and_is_left_out(tmp_path):
    scene, messages = load(tmp_path, 'Shape "curve" "point3 P" [0 0 0 1 1 1 2 2 2 3 3 3]\nShape "sphere"\n',
                           expect_warnings=1)
    assert len(scene.mesh_objects) == 1
    assert messages[0].endswith('line 5: Shape "curve": the curve shape is not supported: left out')
