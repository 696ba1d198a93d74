"""renderer/bench/mitsuba_scene_dict.py's environment, through which `compare` gives a TOML scene to
Mitsuba: a map keeps its orientation as the envmap's to_world, a turn about +y and any other."""
from types import SimpleNamespace

import numpy as np
import pytest

from renderer.bench.mitsuba_scene_dict import _environment
from renderer.scene.description import EnvironmentSpec

mi = pytest.importorskip("mitsuba", reason="Mitsuba is the project's optional `reference` extra")


def pbrt_to_mitsuba(tmp_path, world: str) -> tuple[dict, list, object]:
    """(Mitsuba's scene dictionary, the conversion's notes, Lantern's scene) of a small pbrt world."""
    from renderer.bench.mitsuba_scene_dict import scene_dict
    from tests.scene.pbrt.pbrt_helpers import load

    mi.set_variant("scalar_rgb")
    scene, _ = load(tmp_path, world)
    result, notes = scene_dict(scene, tmp_path)
    return result, notes, scene


def first_mesh(result: dict) -> dict:
    return next(v for k, v in result.items() if k.startswith("mesh_"))


TRIANGLE_WITH_UVS = ('Shape "trianglemesh" "point3 P" [-1 -1 -2  1 -1 -2  1 1 -2] "point2 uv" [0 0 1 0 1 1] '
                     '"integer indices" [0 1 2]\n')


@pytest.mark.parametrize("spec", [
    EnvironmentSpec(kind="map", file="sky.exr", rotation=30.0),
    EnvironmentSpec(kind="map", file="sky.exr", rotation=30.0, rotation_axis=(0.0, -1.0, 0.0)),
    EnvironmentSpec(kind="map", file="sky.exr", rotation=50.0, rotation_axis=(0.6, 0.0, 0.8)),
], ids=["about +y", "about -y", "tilted"])
def test_a_map_keeps_its_orientation(spec):
    mi.set_variant("scalar_rgb")
    envmap = _environment(SimpleNamespace(environment=spec), mi.ScalarTransform4f)
    assert envmap["type"] == "envmap" and envmap["filename"] == "sky.exr"
    np.testing.assert_allclose(np.array(envmap["to_world"].matrix)[:3, :3], spec.rotation_matrix(), atol=1e-6)


def test_two_sided_walls_and_media_on_both_sides_reach_mitsuba(tmp_path):
    """pbrt's walls shade both faces (Mitsuba's twosided), and a sphere standing in a gas names it as
    its exterior, with Mitsuba's volumetric path tracer (its `path` ignores media)."""
    world = ('MakeNamedMedium "gas" "string type" "homogeneous" "rgb sigma_a" [1 1 1] "rgb sigma_s" [0.5 0.5 0.5]\n'
             'Material "diffuse"\nShape "trianglemesh" "point3 P" [-1 -1 -2  1 -1 -2  1 1 -2] "integer indices" [0 1 2]\n'
             'AttributeBegin\nMediumInterface "gas" ""\nMaterial "interface"\nShape "sphere" "float radius" 1.5\n'
             'AttributeEnd\nAttributeBegin\nMediumInterface "" "gas"\nMaterial "dielectric"\n'
             'Shape "sphere" "float radius" 0.5\nAttributeEnd\n')
    result, _, _ = pbrt_to_mitsuba(tmp_path, world)
    assert result["integrator"]["type"] == "volpath"
    wall = first_mesh(result)
    assert wall["bsdf"]["type"] == "twosided" and wall["bsdf"]["bsdf"]["type"] == "diffuse"
    boundary, glass = (result[k] for k in sorted(k for k in result if k.startswith("sphere_")))
    if boundary["bsdf"]["type"] != "null":
        boundary, glass = glass, boundary
    assert "interior" in boundary and "exterior" not in boundary
    assert glass["bsdf"]["type"] == "dielectric" and "exterior" in glass and "interior" not in glass
    assert glass["exterior"]["sigma_t"]["value"] == [1.5, 1.5, 1.5]


def test_a_textured_diffuse_reaches_mitsuba_with_its_uv_transform(tmp_path):
    """A pbrt checkerboard on a diffuse reflectance becomes Mitsuba's checkerboard with the same
    to_uv (Lantern's TextureSpec is Mitsuba's), and the mesh keeps its texture coordinates."""
    world = ('Texture "c" "spectrum" "checkerboard" "rgb tex1" [1 0 0] "rgb tex2" [0 0 1] "float uscale" 4\n'
             'Material "diffuse" "texture reflectance" "c"\n' + TRIANGLE_WITH_UVS)
    result, notes, scene = pbrt_to_mitsuba(tmp_path, world)
    bsdf = first_mesh(result)["bsdf"]["bsdf"]
    texture = bsdf["reflectance"]
    spec = scene.materials[0].base_color_texture
    assert texture["type"] == "checkerboard" and texture["color0"]["value"] == list(spec.color0)
    np.testing.assert_allclose(np.array(texture["to_uv"].matrix), np.array(spec.transform), atol=1e-7)
    assert not any("texture" in n for n in notes)
    mesh = mi.load_dict({"type": "ply", "filename": first_mesh(result)["filename"]})
    assert mesh.has_vertex_texcoords()


def test_a_mixed_texture_reaches_mitsuba_as_the_image_lantern_bakes(tmp_path):
    """Mitsuba has no mix texture: the bitmap it gets holds Lantern's baked texels, and it loads."""
    from PIL import Image

    Image.new("RGB", (2, 2), (255, 0, 0)).save(tmp_path / "red.png")
    world = ('Texture "r" "spectrum" "imagemap" "string filename" "red.png" "string encoding" "linear"\n'
             'Texture "m" "spectrum" "mix" "texture tex1" "r" "rgb tex2" [0 0 1] "float amount" 0.25\n'
             'Material "diffuse" "texture reflectance" "m"\n' + TRIANGLE_WITH_UVS)
    result, _, _ = pbrt_to_mitsuba(tmp_path, world)
    texture = first_mesh(result)["bsdf"]["bsdf"]["reflectance"]
    assert texture["type"] == "bitmap" and texture["raw"]
    np.testing.assert_allclose(np.array(texture["bitmap"])[0, 0], [0.75, 0.0, 0.25], atol=1e-6)
    mi.load_dict(texture)
