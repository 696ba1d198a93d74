"""Mitsuba 3 plugins made into Lantern's scene description: the Cornell box written as Mitsuba XML
is the catalog's Cornell box, sensors' fields of view convert by axis, shapes face where Mitsuba's
do, BSDFs and media map onto Lantern's kinds, and what is left out is one warning each."""
from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
import pytest

from renderer.scene.catalog import load_any, resolve_scene
from renderer.scene.errors import SceneError
from renderer.scene.mesh_assembly import assemble
from renderer.scene.mitsuba import MitsubaSceneWarning, load_mitsuba_scene
from renderer.spectral.mitsuba_rgb import spectrum_to_rgb

DATA = Path(__file__).resolve().parents[2] / "data" / "mitsuba"
SHAPE = '<shape type="sphere"><bsdf type="diffuse"/></shape>'


def load(tmp_path, body: str, expect_warnings: int | None = 0):
    path = tmp_path / "s.xml"
    path.write_text(f'<scene version="3.0.0">\n{body}\n</scene>\n')
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = load_mitsuba_scene(path)
    messages = [str(w.message) for w in caught if issubclass(w.category, MitsubaSceneWarning)]
    if expect_warnings is not None:
        assert len(messages) == expect_warnings, messages
    return scene, messages


def quad_set(scene):
    """Each flat face (a quad, or one of a cube mesh's faces: two triangles in a row) as (its corners,
    its facing, its material's colour and emission), rounded."""
    assembly = assemble(scene)
    faces = [((corner, corner + u, corner + v, corner + u + v), np.cross(u, v), index)
             for (corner, u, v), index in zip(assembly.data.quads, assembly.data.quad_material)]
    tris = assembly.data.tri_vertices.reshape(-1, 2, 3, 3)
    faces += [(pair.reshape(-1, 3), np.cross(pair[0, 1] - pair[0, 0], pair[0, 2] - pair[0, 0]), index)
              for pair, index in zip(tris, assembly.data.tri_material[::2])]
    out = []
    for points, normal, index in faces:
        material = assembly.materials[index]
        corners = tuple(sorted({tuple(np.round(p, 5)) for p in points}))
        out.append((corners, tuple(np.round(normal / np.linalg.norm(normal), 5)),
                    tuple(np.round(material.base_color, 6)), tuple(np.round(material.emission, 5))))
    return sorted(out)


def test_the_cornell_box_in_mitsuba_xml_is_the_catalogs():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        xml = load_any(DATA / "cornell_box.xml")
    assert [str(w.message) for w in caught] == []  # nothing left out
    # Mitsuba's film filters with a Gaussian unless told otherwise, and so does Lantern's for it.
    assert (xml.render.pixel_filter, xml.render.filter_stddev) == ("gaussian", 0.5)
    toml = load_any(resolve_scene("cornell_box"))
    assert quad_set(xml) == quad_set(toml) and len(quad_set(xml)) == 18
    assert xml.camera.position == toml.camera.position and xml.camera.up == toml.camera.up
    forward = np.subtract(xml.camera.look_at, xml.camera.position)
    np.testing.assert_allclose(forward / np.linalg.norm(forward), (0, 0, -1))
    assert xml.camera.fov == pytest.approx(toml.camera.fov, abs=1e-9)
    r = xml.render
    assert (r.width, r.height, r.spp, r.max_depth, r.integrator) == (256, 256, 64, 8, "mis")


@pytest.mark.parametrize("axis, size, expected", [
    ("x", (200, 100), 2 * math.atan(math.tan(math.radians(30)) * 100 / 200)),
    ("y", (200, 100), math.radians(60)),
    ("diagonal", (200, 100), 2 * math.atan(math.tan(math.radians(30)) * 100 / math.hypot(200, 100))),
    ("smaller", (100, 200), 2 * math.atan(math.tan(math.radians(30)) * 200 / 100)),
    ("larger", (100, 200), math.radians(60)),
])
def test_field_of_view_by_axis(tmp_path, axis, size, expected):
    scene, _ = load(tmp_path, f'''<sensor type="perspective"><float name="fov" value="60"/>
        <string name="fov_axis" value="{axis}"/><film type="hdrfilm"><rfilter type="box"/>
        <integer name="width" value="{size[0]}"/><integer name="height" value="{size[1]}"/></film></sensor>''' + SHAPE)
    assert scene.camera.fov == pytest.approx(math.degrees(expected), rel=1e-12)


@pytest.mark.parametrize("lens, mm", [('<string name="focal_length" value="35mm"/>', 35.0), ("", 50.0)])
def test_focal_length_is_against_35mm_films_diagonal(tmp_path, lens, mm):
    """A focal length, or Mitsuba's default of 50 mm when the sensor gives neither it nor a fov."""
    scene, _ = load(tmp_path, f'''<sensor type="perspective">{lens}
        <film type="hdrfilm"><rfilter type="box"/><integer name="width" value="100"/>
        <integer name="height" value="100"/></film></sensor>''' + SHAPE)
    diagonal = 2 * math.atan(math.hypot(36, 24) / (2 * mm))
    expected = 2 * math.atan(math.tan(diagonal / 2) * 100 / math.hypot(100, 100))
    assert scene.camera.fov == pytest.approx(math.degrees(expected), rel=1e-12)


def test_rectangle_disk_and_cube_face_as_mitsubas(tmp_path):
    scene, _ = load(tmp_path, '''<shape type="rectangle"/><shape type="disk"/>
        <shape type="cube"><transform name="to_world"><scale value="0.5"/><translate x="3"/></transform></shape>''')
    data = assemble(scene).data
    corner, u, v = data.quads[0]
    np.testing.assert_allclose(np.cross(u, v) / np.linalg.norm(np.cross(u, v)), (0, 0, 1), atol=1e-7)
    np.testing.assert_allclose(sorted(map(tuple, (corner, corner + u, corner + v, corner + u + v))),
                               [(-1, -1, 0), (-1, 1, 0), (1, -1, 0), (1, 1, 0)], atol=1e-7)
    # The disk and the cube are triangle meshes (tests/scene/mitsuba/test_shapes.py has their texture
    # coordinates): the disk's in z = 0 facing +z out to radius 1, the cube's looking out of it.
    tris = data.tri_vertices.astype(np.float64)
    normals = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    disk = np.abs(tris[:, :, 0] - 3).max(axis=1) > 1.0
    assert len(tris) - disk.sum() == 12
    np.testing.assert_allclose(tris[disk][..., 2], 0.0, atol=1e-7)
    np.testing.assert_allclose(normals[disk], np.tile((0, 0, 1), (disk.sum(), 1)), atol=1e-6)
    assert np.linalg.norm(tris[disk][..., :2], axis=-1).max() == pytest.approx(1.0, abs=1e-6)
    centres = tris[~disk].mean(axis=1) - (3, 0, 0)
    assert (np.einsum("ij,ij->i", normals[~disk], centres) > 0).all()  # every face looks out of the cube
    np.testing.assert_allclose(np.abs(tris[~disk] - (3, 0, 0)).max(), 0.5, atol=1e-6)


def test_sphere_centre_radius_and_a_non_uniform_scale(tmp_path):
    scene, _ = load(tmp_path, '''<shape type="sphere"><point name="center" x="1" y="0" z="0"/>
        <float name="radius" value="0.5"/><transform name="to_world"><scale value="2"/>
        <translate y="1"/></transform></shape>''')
    np.testing.assert_allclose(assemble(scene).data.spheres[0], (2, 1, 0, 1), atol=1e-6)
    with pytest.raises(SceneError, match="a sphere's to_world must scale uniformly"):
        load(tmp_path, '<shape type="sphere"><transform name="to_world"><scale x="2"/></transform></shape>')


def materials(tmp_path, bsdf: str, expect_warnings=0):
    scene, messages = load(tmp_path, f'<shape type="sphere">{bsdf}</shape>', expect_warnings)
    return scene.materials[0], messages


def test_conductors(tmp_path):
    gold, _ = materials(tmp_path, '''<bsdf type="roughconductor"><string name="material" value="Au"/>
        <string name="distribution" value="ggx"/><float name="alpha" value="0.09"/></bsdf>''')
    assert (gold.kind, gold.metal, gold.roughness) == ("conductor", "Au", pytest.approx(0.3))
    mirror, _ = materials(tmp_path, '<bsdf type="conductor"/>')
    assert (mirror.kind, mirror.roughness, mirror.base_color, mirror.eta) == ("conductor", 0.0, (1, 1, 1), None)
    beckmann, _ = materials(tmp_path, '<bsdf type="roughconductor"/>')  # Mitsuba's defaults: Beckmann, 0.1
    assert beckmann.roughness == pytest.approx(math.sqrt(0.1)) and beckmann.microfacet == "beckmann"
    assert gold.microfacet == "ggx_separable" and mirror.sidedness == gold.sidedness == "back_black"
    tinted, _ = materials(tmp_path, '<bsdf type="conductor"><rgb name="specular_reflectance" value="0.9, 0.5, 0.2"/></bsdf>')
    assert (tinted.base_color, tinted.edge_tint, tinted.specular_color) == ((1, 1, 1), (1, 1, 1), (0.9, 0.5, 0.2))
    textured, _ = materials(tmp_path, '''<bsdf type="roughconductor"><string name="material" value="Cu"/>
        <texture name="specular_reflectance" type="checkerboard"/></bsdf>''')
    (role, checker), = textured.parameter_textures
    assert role == "specular_color" and checker.color0 == (0.4,) * 3  # a colour: Mitsuba's own parity
    assert textured.specular_color == (1, 1, 1) and textured.metal == "Cu"
    with pytest.raises(SceneError, match="distribution 'phong'"):
        materials(tmp_path, '<bsdf type="roughconductor"><string name="distribution" value="phong"/></bsdf>')
    with pytest.raises(SceneError, match="unknown conductor material 'Unobtainium'"):
        materials(tmp_path, '<bsdf type="conductor"><string name="material" value="Unobtainium"/></bsdf>')


def test_plastics_masks_and_sides(tmp_path):
    smooth, _ = materials(tmp_path, '<bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.1, 0.2, 0.3"/>'
                                    '<boolean name="nonlinear" value="true"/></bsdf>')
    assert (smooth.kind, smooth.roughness, smooth.nonlinear, smooth.base_color) == ("plastic", 0.0, True, (0.1, 0.2, 0.3))
    assert smooth.ior == pytest.approx(1.49 / 1.00028) and smooth.sidedness == "back_black"  # polypropylene in air
    rough, _ = materials(tmp_path, '<bsdf type="roughplastic"><string name="distribution" value="ggx"/>'
                                   '<float name="alpha" value="0.04"/><float name="int_ior" value="1.9"/>'
                                   '<rgb name="specular_reflectance" value="0.5"/></bsdf>')
    assert (rough.roughness, rough.microfacet, rough.specular_color) == (pytest.approx(0.2), "ggx_separable",
                                                                         (0.5, 0.5, 0.5))
    assert (rough.base_color, rough.nonlinear) == ((0.5, 0.5, 0.5), False)  # Mitsuba's defaults
    with pytest.raises(SceneError, match="int_ior and ext_ior are equal"):
        materials(tmp_path, '<bsdf type="plastic"><float name="int_ior" value="1"/><float name="ext_ior" value="1"/></bsdf>')
    both, _ = materials(tmp_path, '<bsdf type="twosided"><bsdf type="diffuse"/></bsdf>')
    assert both.sidedness == "two_sided"
    glass, _ = materials(tmp_path, '<bsdf type="dielectric"/>')
    assert glass.sidedness == "two_sided"  # transmitters shade both sides in Mitsuba too
    masked, _ = materials(tmp_path, '<bsdf type="mask"><float name="opacity" value="0.3"/><bsdf type="diffuse"/></bsdf>')
    assert (masked.kind, masked.opacity, masked.sidedness) == ("diffuse", 0.3, "back_black")
    with pytest.raises(SceneError, match="opacity 2 is not between 0 and 1"):
        materials(tmp_path, '<bsdf type="mask"><float name="opacity" value="2"/><bsdf type="diffuse"/></bsdf>')


def test_anisotropic_and_textured_widths(tmp_path):
    aniso, _ = materials(tmp_path, '<bsdf type="roughconductor"><float name="alpha_u" value="0.04"/>'
                                   '<float name="alpha_v" value="0.25"/></bsdf>')
    assert (aniso.roughness, aniso.roughness_v) == (pytest.approx(0.2), pytest.approx(0.5))
    same, _ = materials(tmp_path, '<bsdf type="roughconductor"><float name="alpha_u" value="0.09"/>'
                                  '<float name="alpha_v" value="0.09"/></bsdf>')
    assert same.roughness_v is None  # equal widths: isotropic
    textured, _ = materials(tmp_path, '<bsdf type="roughconductor"><texture name="alpha" type="checkerboard">'
                                      '<float name="color0" value="0.05"/><float name="color1" value="0.3"/>'
                                      '</texture></bsdf>')
    # Read as a number, Mitsuba's checkerboard puts color0 in the other squares: swapped here.
    assert (textured.alpha_texture.color0, textured.alpha_texture.color1) == ((0.3,) * 3, (0.05,) * 3)
    assert textured.alpha_v_texture is None
    with pytest.raises(SceneError, match="roughplastic takes one alpha"):
        materials(tmp_path, '<bsdf type="roughplastic"><float name="alpha_u" value="0.1"/>'
                            '<float name="alpha_v" value="0.2"/></bsdf>')


def test_principled_and_principledthin_are_the_disney_kind(tmp_path):
    thick, _ = materials(tmp_path, '''<bsdf type="principled"><rgb name="base_color" value="0.2, 0.8, 0.1"/>
        <float name="roughness" value="0.15"/><float name="specular" value="0.7"/><float name="sheen" value="0.3"/>
        <texture name="metallic" type="checkerboard"><float name="color0" value="0.7"/>
        <float name="color1" value="0.1"/></texture><float name="clearcoat_gloss" value="0.4"/></bsdf>''')
    assert (thick.kind, thick.thin, thick.roughness, thick.sheen, thick.clearcoat_gloss, thick.metallic) == (
        "disney", False, 0.15, 0.3, 0.4, 1.0)
    assert thick.ior == pytest.approx(2.0 / (1.0 - math.sqrt(0.08 * 0.7)) - 1.0)  # Mitsuba's specular -> eta
    (role, checker), = thick.parameter_textures
    assert role == "metallic" and (checker.color0, checker.color1) == ((0.1,) * 3, (0.7,) * 3)  # read as a number
    assert thick.sidedness == "two_sided" and not thick.front_both_sides
    wrapped, _ = materials(tmp_path, '<bsdf type="twosided"><bsdf type="principled"/></bsdf>')
    assert wrapped.front_both_sides and wrapped.ior == pytest.approx(1.5) and wrapped.roughness == 0.5
    thin, _ = materials(tmp_path, '''<bsdf type="principledthin"><float name="eta" value="1.33"/>
        <float name="spec_trans" value="0.4"/><float name="diff_trans" value="1.4"/></bsdf>''')
    assert (thin.kind, thin.thin, thin.ior, thin.transmission, thin.diff_trans) == ("disney", True, 1.33, 0.4, 1.4)
    with pytest.raises(SceneError, match="give eta or specular, not both"):
        materials(tmp_path, '<bsdf type="principled"><float name="eta" value="1.4"/><float name="specular" value="0.5"/>'
                            '</bsdf>')
    transmits, _ = materials(tmp_path, '<bsdf type="principled"><float name="spec_trans" value="0.5"/>'
                                       '<float name="eta" value="1"/></bsdf>')
    assert transmits.ior == pytest.approx(1.001)  # as Mitsuba: an index of 1 cannot refract


def test_blendbsdf_is_a_mix_of_its_two_bsdfs(tmp_path):
    blend, _ = materials(tmp_path, '''<bsdf type="twosided"><bsdf type="blendbsdf"><float name="weight" value="0.3"/>
        <bsdf type="roughconductor"/><bsdf type="blendbsdf"><texture name="weight" type="checkerboard"/>
        <bsdf type="plastic"/><bsdf type="diffuse"/></bsdf></bsdf></bsdf>''')
    metal, inner = blend.mix
    assert (blend.mix_weight, metal.kind, inner.mix_weight) == (0.3, "conductor", 1.0)
    assert [part.kind for part in inner.mix] == ["plastic", "diffuse"]
    (role, checker), = inner.parameter_textures
    assert role == "mix_weight" and checker.color0 == (0.2,) * 3  # read as a number: parities swapped
    # twosided reaches every material of the mix; the mix's textures carry their part's prefix
    assert {metal.sidedness, *(p.sidedness for p in inner.mix)} == {"two_sided"}
    assert set(blend.textures) == {"mix1.mix_weight"}
    two_diffuse, _ = materials(tmp_path, '<bsdf type="blendbsdf"><bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf>')
    assert two_diffuse.mix is None and two_diffuse.kind == "diffuse"  # plain colours: one diffuse, exactly
    with pytest.raises(SceneError, match="needs two nested BSDFs, not 1"):
        materials(tmp_path, '<bsdf type="blendbsdf"><bsdf type="diffuse"/><float name="weight" value="0.1"/></bsdf>'
                            .replace('<float name="weight" value="0.1"/>', '<bsdf type="conductor"/>', 0))


def test_dielectrics_and_named_indices(tmp_path):
    glass, _ = materials(tmp_path, '''<bsdf type="dielectric"><string name="int_ior" value="diamond"/>
        <string name="ext_ior" value="water"/></bsdf>''')
    assert (glass.kind, glass.roughness, glass.thin) == ("dielectric", 0.0, False)
    assert glass.ior == pytest.approx(2.419 / 1.333)
    thin, _ = materials(tmp_path, '<bsdf type="thindielectric"><float name="int_ior" value="1.33"/></bsdf>')
    assert thin.thin and thin.ior == pytest.approx(1.33 / 1.00028)
    with pytest.raises(SceneError, match="unknown int_ior 'unobtainium'"):
        materials(tmp_path, '<bsdf type="dielectric"><string name="int_ior" value="unobtainium"/></bsdf>')


def test_twosided_wraps_and_spectra_become_mitsubas_rgb(tmp_path):
    spectrum = "400:0.2, 500:0.4, 600:0.6, 700:0.8"
    diffuse, _ = materials(tmp_path, f'''<bsdf type="twosided"><bsdf type="diffuse">
        <spectrum name="reflectance" value="{spectrum}"/></bsdf></bsdf>''')
    expected = spectrum_to_rgb([400, 500, 600, 700], [0.2, 0.4, 0.6, 0.8], bounded=True, d65=True)
    assert diffuse.kind == "diffuse" and diffuse.base_color == pytest.approx(expected)
    scene, _ = load(tmp_path, f'''<shape type="sphere"><emitter type="area">
        <spectrum name="radiance" value="{spectrum}"/></emitter></shape>''')
    emission = spectrum_to_rgb([400, 500, 600, 700], [0.2, 0.4, 0.6, 0.8], bounded=False, d65=False)
    assert scene.materials[-1].emission == pytest.approx(emission)
    assert emission != pytest.approx(expected)  # emission is integrated without D65


def test_homogeneous_medium_inside_a_shape(tmp_path):
    scene, _ = load(tmp_path, '''<medium type="homogeneous" id="fog"><float name="scale" value="2"/>
        <rgb name="sigma_t" value="1, 2, 3"/><rgb name="albedo" value="0.5, 0.25, 1"/>
        <phase type="hg"><float name="g" value="0.3"/></phase></medium>
        <shape type="sphere"><bsdf type="null"/><ref name="interior" id="fog"/></shape>''')
    (medium,) = scene.media
    assert medium.name == "fog" and medium.g == 0.3
    np.testing.assert_allclose(medium.sigma_s, (1.0, 1.0, 6.0))
    np.testing.assert_allclose(medium.sigma_a, (1.0, 3.0, 0.0))
    material = scene.materials[scene.material_index(scene.mesh_objects[0].material)]
    assert (material.kind, material.medium) == ("null", "fog")


def test_unsupported_plugins_are_one_warning_each(tmp_path):
    scene, messages = load(tmp_path, '''<emitter type="sunsky"><float name="turbidity" value="3"/>
        <float name="albedo" value="0.2"/></emitter>
        <shape type="hair"><string name="filename" value="x.hair"/></shape>''' + SHAPE, expect_warnings=2)
    assert "line 2: <emitter type=\"sunsky\">: this emitter type is not supported yet and is left out" in messages[0]
    assert "line 4: <shape type=\"hair\">: this shape type is not supported yet" in messages[1]
    assert len(scene.mesh_objects) == 1


def test_an_unread_parameter_is_a_warning(tmp_path):
    _, messages = load(tmp_path, '<shape type="sphere"><bsdf type="diffuse"><float name="sparkle" value="1"/>'
                                 '</bsdf></shape>', expect_warnings=1)
    assert "<bsdf type=\"diffuse\">: parameter 'sparkle' is not supported and was ignored" in messages[0]


def test_nothing_left_to_render_is_one_error(tmp_path):
    with pytest.raises(SceneError, match="nothing Lantern can render"):
        load(tmp_path, '<shape type="hair"/>', expect_warnings=None)


def test_bitmap_and_checkerboard_textures_become_texture_specs(tmp_path):
    from renderer.scene.description import TextureSpec

    (tmp_path / "wood.png").write_bytes(b"")  # read when the scene is assembled, not here
    scene, _ = load(tmp_path, '''<shape type="sphere"><bsdf type="diffuse"><texture name="reflectance" type="bitmap">
            <string name="filename" value="wood.png"/><string name="filter_type" value="nearest"/>
            <string name="wrap_mode" value="mirror"/><boolean name="raw" value="true"/>
            <transform name="to_uv"><scale x="2" y="3"/><translate x="0.5"/></transform></texture></bsdf></shape>
        <shape type="sphere"><bsdf type="principled"><texture name="base_color" type="checkerboard">
            <rgb name="color0" value="0.9"/></texture></bsdf></shape>''')
    wood, checker = scene.materials
    assert wood.base_color == (1.0, 1.0, 1.0)
    assert wood.base_color_texture == TextureSpec("bitmap", file=tmp_path / "wood.png", srgb=False, wrap="mirror",
                                                  nearest=True, transform=((2.0, 0.0, 0.5), (0.0, 3.0, 0.0),
                                                                           (0.0, 0.0, 1.0)))
    assert checker.base_color_texture == TextureSpec("checkerboard", nearest=True, color0=(0.9, 0.9, 0.9),
                                                     color1=(0.2, 0.2, 0.2))
    with pytest.raises(SceneError, match="wrap_mode 'tile'"):
        load(tmp_path, '''<shape type="sphere"><bsdf type="diffuse"><texture name="reflectance" type="bitmap">
            <string name="filename" value="wood.png"/><string name="wrap_mode" value="tile"/></texture></bsdf></shape>''')


@pytest.mark.parametrize("rfilter, expected, warned", [
    ("", ("gaussian", 0.5, 1.0), False),
    ('<rfilter type="box"/>', ("box", 0.5, 1.0), False),
    ('<rfilter type="tent"><float name="radius" value="1.5"/></rfilter>', ("tent", 0.5, 1.5), False),
    ('<rfilter type="gaussian"><float name="stddev" value="0.25"/></rfilter>', ("gaussian", 0.25, 1.0), False),
    ('<rfilter type="mitchell"/>', ("box", 0.5, 1.0), True),
])
def test_reconstruction_filters(tmp_path, rfilter, expected, warned):
    scene, messages = load(tmp_path, f'''<sensor type="perspective"><film type="hdrfilm">{rfilter}
        <integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>''' + SHAPE,
                           expect_warnings=int(warned))
    r = scene.render
    assert (r.pixel_filter, r.filter_stddev, r.filter_radius) == expected


def film(crop: str) -> str:
    return (f'<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="40"/>'
            f'<integer name="height" value="30"/>{crop}</film></sensor>' + SHAPE)


def crop_values(**values) -> str:
    return "".join(f'<integer name="crop_{name}" value="{value}"/>' for name, value in values.items())


def test_the_films_crop_window_is_read_as_mitsubas(tmp_path):
    scene, _ = load(tmp_path, film(crop_values(offset_x=5, offset_y=4, width=10, height=6)))
    r = scene.render
    assert (r.width, r.height, r.crop, r.image_size) == (40, 30, (5, 4, 10, 6), (10, 6))
    # Mitsuba's defaults: offset 0, size the image's (so an offset alone must come with a size)
    assert load(tmp_path, film(crop_values(height=6)))[0].render.crop == (0, 0, 40, 6)
    assert load(tmp_path, film(crop_values(offset_x=0, width=40)))[0].render.crop is None  # the whole image


@pytest.mark.parametrize("values", [dict(offset_x=35, width=10), dict(offset_y=1), dict(width=0),
                                    dict(offset_x=-1, width=10), dict(height=31)])
def test_a_crop_window_outside_the_image_is_one_line_naming_file_and_line(tmp_path, values):
    with pytest.raises(SceneError, match="is not a window of the 40x30 image") as excinfo:
        load(tmp_path, film(crop_values(**values)))
    message = str(excinfo.value)
    assert "\n" not in message and message.startswith(f"{tmp_path / 's.xml'}: line 2: <film type=\"hdrfilm\">")
