"""Mitsuba 3's mesh_attribute texture (renderer/scene/mitsuba/mesh_attribute_textures.py): on a
BSDF's base colour and as a blend of two diffuse BSDFs, read into the material's
MeshAttributeColor, assembled into per-corner colours, and rendered.

Renders (direct light only: a directional light straight down, irradiance E, on a diffuse PLY
square of two triangles filling the view, seen from above):
  - face colours: every pixel wholly inside one triangle is exactly c / pi * E (every sample the
    same), the two triangles different in every channel; the image mean is z-tested at ALPHA;
  - vertex colours: L = rho(p) / pi * E with rho interpolated barycentrically, against the
    midpoint-rule image of tests/lights/test_delta_lights.py by Mitsuba's per-pixel rule and the
    image mean's z-test (Sidak-corrected ALPHA = 0.01; fixed seeds).
"""
from __future__ import annotations

import math
import warnings
from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

from renderer.scene.description import MeshAttributeColor
from renderer.scene.errors import SceneError
from renderer.scene.mesh_assembly import assemble
from renderer.scene.mitsuba import MitsubaSceneWarning, load_mitsuba_scene
from tests.lights.test_delta_lights import ALPHA, assert_analytic, plane_image, render
from tests.scene_builder import scene_from_toml
from tests.stats.image_tests import mean_z

HALF = 4.0  # the square's half size: wider than the view of the plane below
CORNERS = np.array([[-HALF, 0.0, -HALF], [HALF, 0.0, -HALF], [HALF, 0.0, HALF], [-HALF, 0.0, HALF]])
TRIANGLES = ((0, 2, 1), (0, 3, 2))  # facing +y
VERTEX_COLOR = np.array([[0.9, 0.2, 0.1], [0.1, 0.8, 0.3], [0.2, 0.3, 0.9], [0.7, 0.7, 0.2]])
FACE_COLOR = np.array([[0.8, 0.3, 0.1], [0.2, 0.6, 0.9]])
FACE_WEIGHT = (0.25, 0.75)


def write_square(path):
    head = ["ply", "format ascii 1.0", "element vertex 4"] + [f"property float {p}" for p in (
        "x", "y", "z", "color_0", "color_1", "color_2")]
    head += ["element face 2", "property list uchar int vertex_indices"] + [
        f"property float {p}" for p in ("color_0", "color_1", "color_2", "weight_0")] + ["end_header"]
    rows = [" ".join(f"{v:g}" for v in (*p, *c)) for p, c in zip(CORNERS, VERTEX_COLOR)]
    rows += [f"3 {' '.join(map(str, t))} {' '.join(f'{v:g}' for v in c)} {w}"
             for t, c, w in zip(TRIANGLES, FACE_COLOR, FACE_WEIGHT)]
    path.write_text("\n".join(head + rows) + "\n")
    return path


def load(tmp_path, bsdf: str, expect_warnings: int = 0):
    write_square(tmp_path / "square.ply")
    path = tmp_path / "s.xml"
    path.write_text(f'<scene version="3.0.0"><shape type="ply"><string name="filename" value="square.ply"/>'
                    f'{bsdf}</shape></scene>')
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = load_mitsuba_scene(path)
    messages = [str(w.message) for w in caught if issubclass(w.category, MitsubaSceneWarning)]
    assert len(messages) == expect_warnings, messages
    return scene, messages


def attribute(name, scale=None):
    extra = f'<float name="scale" value="{scale}"/>' if scale is not None else ""
    return f'<texture type="mesh_attribute" name="{{}}"><string name="name" value="{name}"/>{extra}</texture>'


def test_a_base_colour_from_a_vertex_attribute(tmp_path):
    scene, _ = load(tmp_path, f'<bsdf type="diffuse">{attribute("vertex_color").format("reflectance")}</bsdf>')
    (material,) = scene.materials
    assert material.base_color == (1.0, 1.0, 1.0)
    assert material.base_color_attribute == MeshAttributeColor("vertex_color")
    colours = assemble(scene).data.tri_colors  # per corner, the file's vertices in each triangle
    np.testing.assert_allclose(colours[..., :3], VERTEX_COLOR[list(TRIANGLES)], rtol=1e-6)


def test_inside_twosided_with_the_textures_scale(tmp_path):
    inner = f'<bsdf type="diffuse">{attribute("face_color", 0.5).format("reflectance")}</bsdf>'
    scene, _ = load(tmp_path, f'<bsdf type="twosided">{inner}</bsdf>')
    assert scene.materials[0].base_color_attribute == MeshAttributeColor("face_color", scale=(0.5, 0.5, 0.5))
    colours = assemble(scene).data.tri_colors
    np.testing.assert_allclose(colours[..., :3], np.repeat(0.5 * FACE_COLOR[:, None], 3, axis=1), rtol=1e-6)


def test_a_blend_of_two_diffuse_colours_by_a_face_attribute(tmp_path):
    scene, _ = load(tmp_path, f'<bsdf type="blendbsdf">{attribute("face_weight").format("weight")}'
                              '<bsdf type="diffuse"><rgb name="reflectance" value="0, 0.5, 0.5"/></bsdf>'
                              '<bsdf type="diffuse"><rgb name="reflectance" value="1, 1, 0"/></bsdf></bsdf>')
    (material,) = scene.materials
    assert material.kind == "diffuse" and material.base_color == (1.0, 1.0, 1.0)
    assert material.base_color_attribute == MeshAttributeColor("face_weight", offset=(0.0, 0.5, 0.5),
                                                               scale=(1.0, 0.5, -0.5))
    colours = assemble(scene).data.tri_colors[:, 0, :3]
    expected = [(1 - w) * np.array([0.0, 0.5, 0.5]) + w * np.array([1.0, 1.0, 0.0]) for w in FACE_WEIGHT]
    np.testing.assert_allclose(colours, expected, rtol=1e-6)


def test_a_blend_by_a_number_and_a_general_blend(tmp_path):
    scene, _ = load(tmp_path, '<bsdf type="blendbsdf"><float name="weight" value="0.25"/>'
                              '<bsdf type="diffuse"><rgb name="reflectance" value="0.8"/></bsdf>'
                              '<bsdf type="diffuse"><rgb name="reflectance" value="0, 0.4, 0"/></bsdf></bsdf>')
    assert scene.materials[0].base_color == pytest.approx((0.6, 0.7, 0.6))
    scene, _ = load(tmp_path, '<bsdf type="blendbsdf"><float name="weight" value="0.25"/>'
                              '<bsdf type="diffuse"/><bsdf type="conductor"/></bsdf>')
    mix = scene.materials[0]
    assert mix.mix_weight == 0.25 and [part.kind for part in mix.mix] == ["diffuse", "conductor"]


@pytest.mark.parametrize("texture, message", [
    ('<texture type="mesh_attribute" name="reflectance"/>', "needs the name of a mesh attribute"),
    (attribute("color").format("reflectance"), "mesh attribute 'color' is neither vertex_... nor face_..."),
])
def test_bad_mesh_attributes_are_one_line_errors(tmp_path, texture, message):
    with pytest.raises(SceneError) as error:
        load(tmp_path, f'<bsdf type="diffuse">{texture}</bsdf>')
    assert message in str(error.value) and "\n" not in str(error.value)


# --- renders ------------------------------------------------------------------------------------

SQUARE_SCENE = """
[scene]
geometry = "mesh"
[camera]
position = [0.0, 3.0, 0.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
fov = 70
[render]
width = 40
height = 32
max_depth = 2
[environment]
type = "constant"
color = [0.0, 0.0, 0.0]
[materials.white]
base_color = [1.0, 1.0, 1.0]
[[objects]]
type = "mesh"
file = "square.ply"
material = "white"
[[lights]]
type = "directional"
direction = [0.0, -1.0, 0.0]
irradiance = [2.0, 2.0, 2.0]
"""
E = 2.0


def square_scene(tmp_path, name: str):
    write_square(tmp_path / "square.ply")
    scene = scene_from_toml(tmp_path, SQUARE_SCENE)
    (white,) = scene.materials
    return replace(scene, materials=(replace(white, base_color_attribute=MeshAttributeColor(name)),))


def test_face_colours_render_exactly(tmp_path):
    scene = square_scene(tmp_path, "face_color")

    def radiance_at(p):  # the second triangle (0, 3, 2) is where z > x
        second = (p[..., 2] > p[..., 0])[..., None]
        return np.where(second, FACE_COLOR[1], FACE_COLOR[0]) / math.pi * E

    expected = plane_image(scene, radiance_at)
    whole = np.zeros(expected.shape[:2], bool)  # pixels wholly inside one triangle
    for colour in FACE_COLOR:
        whole |= np.all(np.isclose(expected, colour / math.pi * E, rtol=1e-12, atol=0.0), axis=-1)
    assert whole.mean() > 0.8
    mean, var = render(scene, "mis", 16, seed=31)
    np.testing.assert_allclose(mean[whole], expected[whole], rtol=1e-5)
    z = mean_z(mean, var, expected[..., 1].mean())
    assert abs(z) < stats.norm.isf(ALPHA / 2), f"face colours: image mean (green) z = {z:.2f}"


def test_vertex_colours_render_interpolated(tmp_path):
    scene = square_scene(tmp_path, "vertex_color")

    def radiance_at(p):
        u = (p[..., 0] + HALF) / (2 * HALF)  # along corner 0 -> 1
        v = (p[..., 2] + HALF) / (2 * HALF)  # along corner 0 -> 3
        first = (v <= u)[..., None]  # triangle (0, 2, 1): weights 1 - u, v, u - v
        c0, c1, c2, c3 = VERTEX_COLOR
        a = (1 - u)[..., None] * c0 + v[..., None] * c2 + (u - v)[..., None] * c1
        b = (1 - v)[..., None] * c0 + u[..., None] * c2 + (v - u)[..., None] * c3
        return np.where(first, a, b) / math.pi * E

    expected = plane_image(scene, radiance_at)
    assert_analytic(render(scene, "mis", 64, seed=32), expected, "vertex colours")


def test_an_analytic_shape_has_no_attributes_to_read(tmp_path):
    """A sphere or rectangle has no file to take a mesh attribute from: one line naming the shape
    (it rendered white before)."""
    path = tmp_path / "s.xml"
    bsdf = f'<bsdf type="diffuse">{attribute("vertex_color").format("reflectance")}</bsdf>'
    path.write_text(f'<scene version="3.0.0"><shape type="sphere">{bsdf}</shape></scene>')
    with pytest.raises(SceneError, match=r"line 1: <shape type=\"sphere\">: a mesh_attribute texture needs a mesh"):
        load_mitsuba_scene(path)
