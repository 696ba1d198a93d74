"""`python app.py info MODEL`: materials, textures, extensions, instances, device memory."""
from __future__ import annotations

import warnings
from dataclasses import replace
from pathlib import Path

import pytest

import app
from renderer.scene.catalog import load_any
from renderer.mesh_world import prepare_mesh_scene
from renderer.scene.model_report import BVH_NODE_BYTES, BVH_SLOT_BYTES, device_lines, model_lines
from renderer.scene.textures import pack_atlas

DATA = Path(__file__).resolve().parents[1] / "data"


def info(capsys, path) -> list[str]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert app.main(["info", str(path)]) == 0
    return capsys.readouterr().out.splitlines()


def test_info_on_an_instanced_model(capsys):
    out = info(capsys, DATA / "instancing.gltf")
    assert "model:       instancing.gltf" in out
    assert "  triangles  9 unique, 21 drawn (20 by instances)" in out
    assert "  instances  5 of 2 meshes: 'shared box/0' x2, 'crowd box/0' x3" in out
    assert "  extensions EXT_mesh_gpu_instancing" in out
    assert "  triangles  0.0 MB (9 triangles as uploaded)" in out  # instanced meshes once


def test_info_lists_layers_textures_and_ignored_extensions(capsys):
    out = info(capsys, DATA / "layers.gltf")
    assert "    'coated'                 metallic-roughness; clearcoat; KHR_materials_clearcoat" in out
    assert ("    'absorbing'              metallic-roughness; transmission + volume; "
            "KHR_materials_transmission, KHR_materials_volume") in out
    assert "    'thin'                   metallic-roughness; transmission (thin-walled); " \
           "KHR_materials_transmission" in out
    assert "  textures   3 entries, 2 stored" in out  # layer.png read as data and as colour
    assert ("    [2] 2x2 half  sRGB colour images[1] 'rgb16.png'; used by tinted specular_color"
            in out)
    out = info(capsys, DATA / "imperfect.gltf")
    assert ("  extensions KHR_lights_punctual (ignored), KHR_materials_unlit (ignored), "
            "KHR_texture_transform") in out
    assert ("    'painted'                unlit (ignored: shaded as metallic-roughness); "
            "KHR_materials_unlit (ignored)") in out


def test_device_memory_lines_add_up():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_any(DATA / "textured_quad.gltf")
    mesh = prepare_mesh_scene(scene)
    asset = scene.model_files.load(DATA / "textured_quad.gltf")
    lines = device_lines(mesh)
    # textures are mip-mapped by default (render.texture_filter): their levels are on the device too
    assert lines[1] == (f"  textures   {pack_atlas(asset.images, mipmaps=True).nbytes / 1e6:.1f} MB"
                        " (with their mip levels: render.texture_filter)")
    unfiltered = replace(scene, render=replace(scene.render, texture_filter="none"))
    assert device_lines(prepare_mesh_scene(unfiltered))[1] == f"  textures   {pack_atlas(asset.images).nbytes / 1e6:.1f} MB"
    n = mesh.data.primitive_count
    assert f"at most {((2 * n - 1) * BVH_NODE_BYTES + n * BVH_SLOT_BYTES) / 1e6:.1f} MB" in lines[3]
    assert model_lines(asset, "q")[0] == "model:       q"


@pytest.mark.parametrize("scene", ["showcase", "textured"])
def test_info_on_scene_files_keeps_working(capsys, scene):
    out = info(capsys, scene)
    assert out[0].startswith(f"scene:       {scene}")
    assert ("device memory:" in out) == (scene == "textured")  # mesh scenes only
