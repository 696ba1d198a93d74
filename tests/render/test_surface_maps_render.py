"""Mitsuba's normalmap and bumpmap, rendered (renderer/materials/mapped_frames.py).

Tilted normals, exactly: a diffuse plane (Mitsuba's rectangle, and an OBJ square of two
triangles) seen head-on, lit only by a directional light, under a constant tilted normal map or a
linear height ramp along u. Every pixel on the plane is then the same deterministic value,
rho / pi * E * cos(mapped normal, light) * G, with G Mitsuba's shadow-terminator term (Estevez et
al. 2019) for the tilt; a ramp of slope dh/du under `scale` on a plane with |dp/du| = L tilts the
normal by atan(scale dh/du / L) away from +u, a normal-map texel (x, y, z) is x along dp/du, y along
n x dp/du. Checked to f32 rounding (no sampling noise enters: one delta light, a black world).

Maps that should change nothing, statistically: a flat normal map (128, 128, 255) and a constant
height under a large scale on a diffuse sphere under a white sky and a directional light render as
the bare sphere does, by Mitsuba's per-pixel z-test rule and the image mean's z-test
(tests/stats/image_tests.py, Sidak-corrected alpha = 0.01; fixed seeds, a different one per image).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from PIL import Image

from renderer.camera import CameraFrame
from renderer.renderer import Renderer
from renderer.scene.catalog import load_any
from tests.stats.image_tests import assert_agree

SIZE = 16
RHO = 0.5
LIGHT_ANGLE = math.radians(30.0)  # the light's angle from the plane's normal
INSIDE = (slice(5, 11), slice(5, 11))  # pixels that see the plane only
RAMP_SCALE = 0.8
RAMP_SLOPE = 16 * 16 / 255  # dh/du of texels 0, 16, ..., 240 (of 255) across 16 texels
TILT = math.radians(20.0)  # of the constant normal maps


def render(scene, spp, seed):
    renderer = Renderer(scene, (SIZE, SIZE))
    renderer.render(CameraFrame.from_spec(scene.camera), spp, "mis", max_depth=scene.render.max_depth, seed=seed)
    assert renderer.film.stats()["rejected"] == 0, "non-finite samples"
    return renderer.film.mean_image().astype(np.float64), renderer.film.variance_of_mean_image().astype(np.float64)


def write_images(folder):
    ramp = np.repeat(np.repeat((16 * np.arange(16)).astype(np.uint8)[None, :, None], 4, axis=0), 3, axis=2)
    Image.fromarray(ramp).save(folder / "ramp.png")
    Image.fromarray(np.full((4, 4, 3), (128, 128, 255), np.uint8)).save(folder / "flat.png")
    Image.fromarray(np.full((4, 4, 3), 150, np.uint8)).save(folder / "level.png")
    (folder / "square.obj").write_text("v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                                       "vn 0 0 1\nf 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n")


def scene_file(tmp_path, name, shape, bsdf, lights, depth=2):
    write_images(tmp_path)
    path = tmp_path / f"{name}.xml"
    path.write_text(f'''<scene version="3.0.0"><integrator type="path"><integer name="max_depth" value="{depth}"/>
        </integrator><sensor type="perspective"><float name="fov" value="30"/>
            <transform name="to_world"><lookat origin="0,0,5" target="0,0,0" up="0,1,0"/></transform>
            <film type="hdrfilm"><rfilter type="box"/><integer name="width" value="{SIZE}"/>
            <integer name="height" value="{SIZE}"/></film></sensor>
        {lights}{shape.format(bsdf=bsdf)}</scene>''')
    return load_any(path)


RECTANGLE = '<shape type="rectangle">{bsdf}</shape>'
SQUARE = '<shape type="obj"><string name="filename" value="square.obj"/>{bsdf}</shape>'
DIFFUSE = f'<bsdf type="diffuse"><rgb name="reflectance" value="{RHO}"/></bsdf>'


def directional(to_light):
    d = -np.asarray(to_light)
    return (f'<emitter type="directional"><vector name="direction" value="{d[0]}, {d[1]}, {d[2]}"/>'
            '<rgb name="irradiance" value="1"/></emitter>')


def constant_normal(n):
    rgb = ", ".join(f"{(c + 1) / 2:.9f}" for c in n)
    return (f'<bsdf type="normalmap"><texture name="normalmap" type="rawconstant"><vector name="value" '
            f'value="{rgb}"/></texture>{DIFFUSE}</bsdf>')


RAMP = (f'<bsdf type="bumpmap"><float name="scale" value="{RAMP_SCALE}"/><texture type="bitmap">'
        '<string name="filename" value="ramp.png"/><boolean name="raw" value="true"/>'
        f'<string name="wrap_mode" value="clamp"/></texture>{DIFFUSE}</bsdf>')


def terminator(tilt, light):
    """Mitsuba's shadowing term for a normal tilted by `tilt` lit from `light` off the plane's normal."""
    alpha2 = min(0.125 * math.tan(tilt) ** 2, 1.0)
    return 2.0 / (1.0 + math.sqrt(1.0 + alpha2 * math.tan(light) ** 2))


def _case(name):
    sin, cos = math.sin(LIGHT_ANGLE), math.cos(LIGHT_ANGLE)
    ramp_tilt = math.atan(RAMP_SCALE * RAMP_SLOPE / 2.0)  # |dp/du| = 2: the plane is 2 wide
    cases = {  # (bsdf, unit direction to the light, mapped normal, its tilt)
        "ramp": (RAMP, (sin, 0.0, cos), (-math.sin(ramp_tilt), 0.0, math.cos(ramp_tilt)), ramp_tilt),
        "normal_along_u": (constant_normal((math.sin(TILT), 0.0, math.cos(TILT))), (sin, 0.0, cos),
                           (math.sin(TILT), 0.0, math.cos(TILT)), TILT),
        # y of the map runs along n x dp/du = +y here
        "normal_along_v": (constant_normal((0.0, math.sin(TILT), math.cos(TILT))), (0.0, -sin, cos),
                           (0.0, math.sin(TILT), math.cos(TILT)), TILT),
    }
    return cases[name]


@pytest.mark.parametrize("shape, case", [(RECTANGLE, "ramp"), (SQUARE, "ramp"), (RECTANGLE, "normal_along_u"),
                                         (SQUARE, "normal_along_v")], ids=["rectangle-ramp", "obj-ramp",
                                                                           "rectangle-normal-u", "obj-normal-v"])
def test_a_mapped_plane_is_lit_by_the_cosine_of_its_tilted_normal(tmp_path, shape, case):
    bsdf, to_light, normal, tilt = _case(case)
    mean, _ = render(scene_file(tmp_path, case, shape, bsdf, directional(to_light)), spp=4, seed=1)
    expected = RHO / math.pi * np.dot(normal, to_light) * terminator(tilt, LIGHT_ANGLE)
    np.testing.assert_allclose(mean[INSIDE], expected, rtol=2e-5)


SPHERE = '<shape type="sphere">{bsdf}</shape>'
SKY = '<emitter type="constant"><rgb name="radiance" value="1"/></emitter>' + directional((0.6, 0.64, 0.48))
FLAT_NORMALS = (f'<bsdf type="normalmap"><texture name="normalmap" type="bitmap"><string name="filename" '
                f'value="flat.png"/><boolean name="raw" value="true"/></texture>{DIFFUSE}</bsdf>')
LEVEL = (f'<bsdf type="bumpmap"><float name="scale" value="5"/><texture type="bitmap"><string name="filename" '
         f'value="level.png"/><boolean name="raw" value="true"/></texture>{DIFFUSE}</bsdf>')


@pytest.mark.parametrize("mapped", [FLAT_NORMALS, LEVEL], ids=["flat-normal-map", "constant-height"])
def test_maps_that_do_not_tilt_render_as_the_bare_surface(tmp_path, mapped):
    bare = render(scene_file(tmp_path, "bare", SPHERE, DIFFUSE, SKY, depth=3), spp=64, seed=5)
    with_map = render(scene_file(tmp_path, "mapped", SPHERE, mapped, SKY, depth=3), spp=64, seed=6)
    assert bare[0][INSIDE].min() > 0.05  # the sphere is lit where the test looks
    assert_agree(with_map, bare, ("mapped", "bare"))


TOML_CARD = """
[scene]
geometry = "mesh"
[camera]
position = [0.0, 5.0, 0.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
fov = 30
[render]
width = {size}
height = {size}
max_depth = 2
[environment]
type = "constant"
color = [0.0, 0.0, 0.0]
[materials.card]
base_color = [{rho}, {rho}, {rho}]
normal_map = "tilt.png"
[[lights]]
type = "directional"
direction = [{d[0]}, {d[1]}, {d[2]}]
irradiance = [1.0, 1.0, 1.0]
[[objects]]
type = "quad"
size = [2.0, 2.0]
material = "card"
"""


def test_a_toml_materials_normal_map_tilts_along_the_quads_u(tmp_path):
    """A quad facing +y has u along +z (its first edge) and n x dp/du along +x: a texel tilted by
    TILT along x leans the normal towards +z."""
    texel = np.round((np.array([math.sin(TILT), 0.0, math.cos(TILT)]) + 1) / 2 * 255).astype(np.uint8)
    Image.fromarray(np.tile(texel, (4, 4, 1))).save(tmp_path / "tilt.png")
    local = texel / 255 * 2 - 1
    local /= np.linalg.norm(local)
    normal = np.array([local[1], local[2], local[0]])  # (n x s, n, s) = (+x, +y, +z)
    to_light = np.array([0.0, math.cos(LIGHT_ANGLE), math.sin(LIGHT_ANGLE)])
    path = tmp_path / "card.toml"
    path.write_text(TOML_CARD.format(size=SIZE, rho=RHO, d=-to_light))
    mean, _ = render(load_any(path), spp=4, seed=1)
    expected = RHO / math.pi * normal.dot(to_light) * terminator(math.acos(local[2]), LIGHT_ANGLE)
    np.testing.assert_allclose(mean[INSIDE], expected, rtol=2e-5)
