"""Materials, textures and media (renderer/scene/pbrt/materials.py)."""
from __future__ import annotations

import math

import numpy as np
import pytest
from PIL import Image

from renderer.scene.errors import SceneError
from tests.scene.pbrt.pbrt_helpers import CAMERA, SPHERE, load, material


def one(tmp_path, material_line: str, expect_warnings: int = 0, extra: str = ""):
    scene, messages = load(tmp_path, extra + material_line + "\n" + SPHERE, expect_warnings=expect_warnings)
    return material(scene, scene.mesh_objects[0].material), messages, scene


def test_diffuse_default_and_colour(tmp_path):
    spec, _, _ = one(tmp_path, 'Material "diffuse"')
    assert (spec.kind, spec.base_color, spec.sidedness) == ("diffuse", (0.5, 0.5, 0.5), "two_sided")
    spec, _, _ = one(tmp_path, 'Material "diffuse" "rgb reflectance" [0.1 0.2 0.3]')
    assert spec.base_color == (0.1, 0.2, 0.3)
    assert one(tmp_path, "")[0].base_color == (0.5, 0.5, 0.5)  # pbrt's default material


@pytest.mark.parametrize("remap, expected_alpha", [("true", math.sqrt(0.09)), ("false", 0.09)])
def test_conductor_named_metal_with_remapped_roughness(tmp_path, remap, expected_alpha):
    spec, _, _ = one(tmp_path, 'Material "conductor" "spectrum eta" "metal-Au-eta" "spectrum k" "metal-Au-k" '
                               f'"float roughness" 0.09 "bool remaproughness" {remap}')
    assert (spec.kind, spec.metal, spec.microfacet) == ("conductor", "Au", "ggx")
    assert spec.roughness ** 2 == pytest.approx(expected_alpha) and spec.roughness_v is None


def test_conductor_defaults_to_copper_and_takes_rgb_eta_k_and_anisotropy(tmp_path):
    assert one(tmp_path, 'Material "conductor"')[0].metal == "Cu"
    spec, _, _ = one(tmp_path, 'Material "conductor" "rgb eta" [0.2 0.9 1.1] "rgb k" [3.9 2.4 2.2] '
                               '"float uroughness" 0.04 "float vroughness" 0.16 "bool remaproughness" false')
    assert spec.eta == (0.2, 0.9, 1.1) and spec.k == (3.9, 2.4, 2.2)
    assert (spec.roughness, spec.roughness_v) == pytest.approx((0.2, 0.4))


def test_conductor_reflectance_and_unknown_metal(tmp_path):
    spec, _, _ = one(tmp_path, 'Material "conductor" "rgb reflectance" [0.9 0.6 0.3]')
    # pbrt's index for a reflectance r: eta 1, k = 2 sqrt(r / (1 - r)), whose normal-incidence Fresnel is r
    assert spec.eta == (1.0, 1.0, 1.0) and spec.metal == ""
    k = np.array(spec.k)
    assert np.allclose(k * k / (4.0 + k * k), (0.9, 0.6, 0.3))
    spec, messages, _ = one(tmp_path, 'Material "conductor" "spectrum eta" "metal-CuZn-eta" "spectrum k" '
                                      '"metal-CuZn-k"', expect_warnings=1)
    assert spec.metal == "Cu" and "metal-CuZn-eta" in messages[0]


def test_dielectrics_and_interface(tmp_path):
    spec, _, _ = one(tmp_path, 'Material "dielectric" "float eta" 1.33 "float roughness" 0.01')
    assert (spec.kind, spec.ior, spec.thin) == ("dielectric", 1.33, False)
    assert spec.roughness == pytest.approx(0.1 ** 0.5)
    spec, _, _ = one(tmp_path, 'Material "thindielectric" "spectrum eta" "glass-BK7"')
    assert spec.thin and spec.ior == pytest.approx(1.5185, abs=1e-3)
    assert one(tmp_path, 'Material "interface"')[0].kind == "null"
    (tmp_path / "water.spd").write_text("400 1.34\n700 1.33\n")
    assert one(tmp_path, 'Material "dielectric" "spectrum eta" "water.spd"')[0].ior == pytest.approx(1.335)


def test_mix_chooses_the_second_with_probability_amount(tmp_path):
    extra = ('MakeNamedMaterial "a" "string type" "diffuse"\n'
             'MakeNamedMaterial "b" "string type" "conductor"\n'
             'MakeNamedMaterial "m" "string type" "mix" "string materials" ["a" "b"] "float amount" 0.25\n')
    spec, _, _ = one(tmp_path, 'NamedMaterial "m"', extra=extra)
    assert [p.kind for p in spec.mix] == ["diffuse", "conductor"] and spec.mix_weight == 0.25
    extra += ('Texture "mask" "float" "checkerboard" "float tex1" 1 "float tex2" 0\n'
              'MakeNamedMaterial "t" "string type" "mix" "string materials" ["a" "b"] "texture amount" "mask"\n')
    spec, _, _ = one(tmp_path, 'NamedMaterial "t"', extra=extra)
    assert spec.mix_weight == 1.0 and dict(spec.parameter_textures)["mix_weight"].kind == "checkerboard"


def test_diffuse_transmission_with_its_scale_and_textures(tmp_path):
    spec, _, _ = one(tmp_path, 'Material "diffusetransmission"')
    assert (spec.kind, spec.base_color, spec.transmittance) == ("diffuse_transmission", (0.25,) * 3, (0.25,) * 3)
    extra = 'Texture "leaf" "spectrum" "checkerboard" "rgb tex1" [0 1 0] "rgb tex2" [0 0.5 0]\n'
    spec, _, _ = one(tmp_path, 'Material "diffusetransmission" "texture reflectance" "leaf" '
                               '"texture transmittance" "leaf" "float scale" 0.5', extra=extra)
    assert spec.base_color == (0.5,) * 3 and spec.transmittance == (0.5,) * 3
    assert spec.base_color_texture.kind == "checkerboard" and dict(spec.parameter_textures)["transmittance"].kind == "checkerboard"


@pytest.mark.parametrize("kind, lantern", [("hair", "diffuse")])
def test_materials_without_a_kind_map_to_the_nearest_with_one_warning(tmp_path, kind, lantern):
    spec, messages, _ = one(tmp_path, f'Material "{kind}"', expect_warnings=1)
    assert spec.kind == lantern and f'Material "{kind}"' in messages[0]


def test_coated_materials_are_the_coated_kind_with_pbrts_parameters(tmp_path):
    spec, _, _ = one(tmp_path, 'Material "coateddiffuse" "rgb reflectance" [0.2 0.4 0.6] "float roughness" 0.01 '
                               '"float thickness" 0.1 "rgb albedo" [0.5 0.5 0.5] "float g" 0.3 "integer maxdepth" 20 '
                               '"integer nsamples" 2 "float eta" 1.33')
    assert (spec.kind, spec.coat_base, spec.base_color, spec.ior) == ("coated", "diffuse", (0.2, 0.4, 0.6), 1.33)
    assert spec.roughness == pytest.approx(0.1 ** 0.5)  # remapped: alpha = sqrt(0.01), roughness = sqrt(alpha)
    assert (spec.coat_thickness, spec.coat_albedo, spec.coat_g, spec.coat_maxdepth, spec.coat_nsamples) == (
        0.1, (0.5, 0.5, 0.5), 0.3, 20, 2)
    spec, _, _ = one(tmp_path, 'Material "coatedconductor" "float interface.roughness" 0 "float interface.eta" 1.5 '
                               '"spectrum conductor.eta" "metal-Au-eta" "spectrum conductor.k" "metal-Au-k" '
                               '"float conductor.roughness" 0.04 "bool remaproughness" false')
    assert (spec.kind, spec.coat_base, spec.metal, spec.roughness) == ("coated", "conductor", "Au", 0.0)
    assert spec.conductor_roughness == pytest.approx(0.2)  # not remapped: alpha = 0.04
    assert one(tmp_path, 'Material "coateddiffuse" "float eta" 0')[0].ior == 1.0  # pbrt: eta 0 means 1
    with pytest.raises(SceneError, match="a coat needs thickness > 0"):
        one(tmp_path, 'Material "coateddiffuse" "float thickness" 0')


def test_imagemap_checkerboard_and_scale_textures(tmp_path):
    Image.new("RGB", (4, 4), (200, 100, 50)).save(tmp_path / "wood.png")
    extra = ('Texture "wood" "spectrum" "imagemap" "string filename" "wood.png" "float uscale" 2 "float scale" 0.5 '
             '"string filter" "point"\n'
             'Texture "lin" "spectrum" "imagemap" "string filename" "wood.png" "string encoding" "linear"\n'
             'Texture "checks" "spectrum" "checkerboard" "rgb tex1" [1 0 0] "rgb tex2" [0 0 1] "float uscale" 4\n'
             'Texture "half" "spectrum" "scale" "texture tex" "checks" "float scale" 0.5\n')
    spec, _, _ = one(tmp_path, 'Material "diffuse" "texture reflectance" "wood"', extra=extra)
    t = spec.base_color_texture
    assert spec.base_color == (0.5, 0.5, 0.5) and t.kind == "bitmap" and t.srgb and t.nearest
    assert t.transform == ((2.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    assert not one(tmp_path, 'Material "diffuse" "texture reflectance" "lin"', extra=extra)[0].base_color_texture.srgb
    spec, _, _ = one(tmp_path, 'Material "diffuse" "texture reflectance" "half"', extra=extra)
    t = spec.base_color_texture
    assert spec.base_color == (0.5, 0.5, 0.5) and (t.kind, t.color0, t.color1) == ("checkerboard", (1, 0, 0), (0, 0, 1))
    assert t.transform[0] == (2.0, 0.0, 0.0)  # pbrt's squares are a unit of st, Lantern's half a period


def test_mix_and_scale_textures(tmp_path):
    Image.new("RGB", (4, 4), (200, 100, 50)).save(tmp_path / "wood.png")
    extra = ('Texture "wood" "spectrum" "imagemap" "string filename" "wood.png"\n'
             'Texture "mask" "float" "imagemap" "string filename" "wood.png"\n'
             'Texture "checks" "spectrum" "checkerboard" "rgb tex1" [1 0 0] "rgb tex2" [0 0 1]\n'
             'Texture "grey" "spectrum" "mix" "rgb tex1" [0 0 1] "rgb tex2" [1 1 0] "float amount" 0.25\n'
             'Texture "dim" "spectrum" "mix" "texture tex1" "checks" "float tex2" 0 "float amount" 0.25\n'
             'Texture "both" "spectrum" "mix" "texture tex1" "wood" "rgb tex2" [0 1 0] "texture amount" "mask"\n'
             'Texture "odd" "spectrum" "mix" "texture tex1" "wood" "texture tex2" "checks"\n'
             'Texture "prod" "spectrum" "scale" "texture tex" "wood" "texture scale" "mask"\n')
    spec = one(tmp_path, 'Material "diffuse" "texture reflectance" "grey"', extra=extra)[0]
    assert spec.base_color == (0.25, 0.25, 0.75) and spec.base_color_texture is None
    spec = one(tmp_path, 'Material "diffuse" "texture reflectance" "dim"', extra=extra)[0]
    assert spec.base_color == (0.75, 0.75, 0.75) and spec.base_color_texture.kind == "checkerboard"
    spec = one(tmp_path, 'Material "diffuse" "texture reflectance" "both"', extra=extra)[0]
    t = spec.base_color_texture
    assert spec.base_color == (1.0, 1.0, 1.0) and t.kind == "mix" and t.amount[1].file.name == "wood.png"
    assert [o[0] for o in t.operands] == [(1.0, 1.0, 1.0), (0.0, 1.0, 0.0)] and t.operands[1][1] is None
    assert t.transform == t.operands[0][1].transform and not t.nearest
    spec, messages, _ = one(tmp_path, 'Material "diffuse" "texture reflectance" "odd"', extra=extra,
                            expect_warnings=1)
    assert spec.base_color_texture.kind == "mix" and "different uv mappings" in messages[0]
    t = one(tmp_path, 'Material "diffuse" "texture reflectance" "prod"', extra=extra)[0].base_color_texture
    assert t.kind == "product" and [o[1].file.name for o in t.operands] == ["wood.png", "wood.png"]


def test_missing_image_warns_and_keeps_the_default(tmp_path):
    extra = 'Texture "gone" "spectrum" "imagemap" "string filename" "gone.png"\n'
    spec, messages, _ = one(tmp_path, 'Material "diffuse" "texture reflectance" "gone"', extra=extra,
                            expect_warnings=1)
    assert spec.base_color_texture is None and spec.base_color == (0.5, 0.5, 0.5) and "gone.png" in messages[0]


def test_unsupported_medium_warns(tmp_path):
    extra = 'MakeNamedMedium "smoke" "string type" "nanovdb" "string filename" "x.nvdb"\n'
    spec, messages, scene = one(tmp_path, 'MediumInterface "smoke" ""', extra=extra, expect_warnings=1)
    assert spec.medium == "" and scene.media == () and "nanovdb" in messages[0]


def test_camera_medium_is_fog(tmp_path):
    options = ('MakeNamedMedium "air" "string type" "homogeneous" "rgb sigma_s" [0.2 0.2 0.2] "rgb sigma_a" [0 0 0]\n'
               'MediumInterface "" "air"\n' + CAMERA)
    scene, _ = load(tmp_path, SPHERE, options=options)
    assert (scene.fog.model, scene.fog.medium) == ("medium", "air")
    assert scene.media[0].sigma_s == (0.2, 0.2, 0.2)


GAS = 'MakeNamedMedium "gas" "string type" "homogeneous" "rgb sigma_a" [1 1 1] "rgb sigma_s" [0 0 0]\n'


@pytest.mark.parametrize("interface, inside, outside", [
    ('"" "gas"', "", "gas"),  # a glass sphere standing in a gas
    ('"gas" ""', "gas", ""),  # a gas behind a boundary, the camera in empty space
    ('"gas" "gas"', "gas", "gas"),  # no transition: a ray stays in the gas
    ('"" ""', "", ""),
])
def test_medium_interface_gives_the_inside_and_the_outside(tmp_path, interface, inside, outside):
    spec, _, scene = one(tmp_path, f'MediumInterface {interface}\nMaterial "dielectric"', extra=GAS)
    assert (spec.medium, spec.outside_medium) == (inside, outside)
    assert [m.name for m in scene.media] == (["gas"] if inside or outside else [])


def test_a_shape_in_the_cameras_medium_keeps_it(tmp_path):
    options = GAS + 'MediumInterface "" "gas"\n' + CAMERA
    scene, _ = load(tmp_path, 'MediumInterface "" ""\nMaterial "dielectric"\n' + SPHERE, options=options)
    spec = material(scene, scene.mesh_objects[0].material)
    assert (scene.fog.medium, spec.medium, spec.outside_medium) == ("gas", "gas", "")  # no transition


def test_empty_space_outside_while_the_camera_is_in_a_medium_warns(tmp_path):
    options = GAS + 'MediumInterface "" "gas"\n' + CAMERA
    scene, messages = load(tmp_path, 'MediumInterface "gas" ""\n' + SPHERE, options=options, expect_warnings=1)
    assert "empty space outside" in messages[0]


def test_a_shapes_alpha_is_its_materials_opacity(tmp_path):
    scene, _ = load(tmp_path, 'Material "diffuse"\nShape "sphere" "float radius" 0.5 "float alpha" 0.25\n' + SPHERE)
    cut, whole = (material(scene, o.material) for o in scene.mesh_objects)
    assert (cut.opacity, cut.opacity_texture, whole.opacity) == (0.25, None, 1.0)
    extra = 'Texture "mask" "float" "checkerboard" "float tex1" 1 "float tex2" 0\n'
    scene, _ = load(tmp_path, extra + 'Shape "sphere" "float radius" 0.5 "texture alpha" "mask"\n')
    spec = material(scene, scene.mesh_objects[0].material)
    assert spec.opacity == 1.0 and spec.opacity_texture.kind == "checkerboard"
    with pytest.raises(SceneError, match="alpha must be one number"):
        load(tmp_path, 'Shape "sphere" "float alpha" 2\n')


GRID = ('AttributeBegin\nTranslate 1 0 0\nMakeNamedMedium "smoke" "string type" "uniformgrid" "integer nx" 2 "integer ny" 1 '
        '"integer nz" 1 "float density" [0 2] "point3 p0" [-1 -1 -1] "point3 p1" [1 1 1] "rgb sigma_a" [1 1 1] '
        '"rgb sigma_s" [1 2 3] "float scale" 0.5\nAttributeEnd\n')


def test_a_uniform_grid_is_a_grid_medium(tmp_path):
    _, _, scene = one(tmp_path, 'MediumInterface "smoke" ""\nMaterial "interface"', extra=GRID)
    m = scene.media[0]
    assert (m.kind, m.scale) == ("grid", 0.5)
    np.testing.assert_allclose(m.density.values[..., 0], [[[0.0, 4.0]]])  # density x (sigma_a + sigma_s): 2 x 2
    np.testing.assert_allclose(m.density.values[0, 0, 1], [4.0, 6.0, 8.0])
    np.testing.assert_allclose(m.albedo.constant, (0.5, 2 / 3, 0.75))
    # the unit cube onto [p0, p1] in the medium's space, then its transform (x + 1)
    np.testing.assert_allclose(np.array(m.density.to_world), [[2, 0, 0, 0], [0, 2, 0, -1], [0, 0, 2, -1], [0, 0, 0, 1]])


def test_a_grid_with_the_wrong_number_of_values_is_an_error(tmp_path):
    with pytest.raises(SceneError, match="3 density values for a grid of 2 x 1 x 1"):
        one(tmp_path, 'MediumInterface "smoke" ""', extra=GRID.replace("[0 2]", "[0 2 3]"))


@pytest.mark.parametrize("remap, expected", [("false", (0.04, 0.36)), ("true", (0.2, 0.6))])
def test_a_checkerboard_of_roughness_is_a_textured_width(tmp_path, remap, expected):
    extra = 'Texture "r" "float" "checkerboard" "float tex1" 0.04 "float tex2" 0.36\n'
    spec, _, _ = one(tmp_path, f'Material "conductor" "texture roughness" "r" "bool remaproughness" {remap}', extra=extra)
    t = spec.alpha_texture
    assert spec.roughness > 0 and t.kind == "checkerboard" and spec.alpha_v_texture is None
    assert (t.color0[0], t.color1[0]) == pytest.approx(expected)  # the widths alpha, remapped as pbrt does


def test_an_image_of_roughness_is_read_as_widths_where_pbrt_does_not_remap(tmp_path):
    Image.new("L", (2, 2), 40).save(tmp_path / "r.png")
    extra = 'Texture "r" "float" "imagemap" "string filename" "r.png" "string encoding" "linear"\n'
    spec, _, _ = one(tmp_path, 'Material "dielectric" "texture uroughness" "r" "float vroughness" 0.09 '
                               '"bool remaproughness" false', extra=extra)
    assert spec.alpha_texture.kind == "bitmap" and spec.alpha_v_texture.color0 == (0.09,) * 3
    spec, messages, _ = one(tmp_path, 'Material "dielectric" "texture roughness" "r"', extra=extra, expect_warnings=1)
    assert "remaproughness false" in messages[0] and spec.alpha_texture.color0 == (math.sqrt(0.5),) * 3


def test_a_textured_coat_roughness_warns_and_takes_the_mean_width(tmp_path):
    extra = 'Texture "r" "float" "checkerboard" "float tex1" 0.04 "float tex2" 0.16\n'
    spec, messages, _ = one(tmp_path, 'Material "coateddiffuse" "texture roughness" "r" "bool remaproughness" false',
                            extra=extra, expect_warnings=1)
    assert spec.kind == "coated" and spec.roughness == pytest.approx(math.sqrt(0.1)) and "mean width 0.1" in messages[0]
