"""A pbrt-v4 scene rendered: an area light over a diffuse floor, the floor's radiance against the
form factor of the emitter (a z-test on the image mean at the 1% level, fixed seed)."""
from __future__ import annotations

import math

import numpy as np
import pytest
from PIL import Image
from scipy import stats

from renderer.camera import CameraFrame
from renderer.renderer import Renderer

from tests.scene.pbrt.pbrt_helpers import load

ALPHA = 0.01  # two-sided significance level
HALF, HEIGHT, ALBEDO, RADIANCE = 10.0, 1.0, 0.5, 2.0

SCENE_OPTIONS = """LookAt 0 0.5 0  0 0 0  0 0 1
Camera "perspective" "float fov" 2
Film "rgb" "integer xresolution" 8 "integer yresolution" 8
Sampler "independent" "integer pixelsamples" 32 "integer seed" 5
Integrator "path" "integer maxdepth" 1
PixelFilter "box"
"""
# the emitter faces down (its triangles wind clockwise seen from above); the floor faces up
WORLD = f"""AttributeBegin
AreaLightSource "diffuse" "rgb L" [{RADIANCE} {RADIANCE} {RADIANCE}]
Shape "trianglemesh" "point3 P" [-{HALF} {HEIGHT} -{HALF}  {HALF} {HEIGHT} -{HALF}  {HALF} {HEIGHT} {HALF}  -{HALF} {HEIGHT} {HALF}]
  "integer indices" [0 1 2 0 2 3]
AttributeEnd
Material "diffuse" "rgb reflectance" [{ALBEDO} {ALBEDO} {ALBEDO}]
Shape "bilinearmesh" "point3 P" [-{HALF} 0 -{HALF}  -{HALF} 0 {HALF}  {HALF} 0 -{HALF}  {HALF} 0 {HALF}]
"""


def corner_form_factor(a: float, b: float, c: float) -> float:
    """From a point to a parallel a x b rectangle at distance c whose corner is above it."""
    x, y = a / c, b / c
    return (x / math.sqrt(1 + x * x) * math.atan(y / math.sqrt(1 + x * x))
            + y / math.sqrt(1 + y * y) * math.atan(x / math.sqrt(1 + y * y))) / (2 * math.pi)


def rendered(scene, integrator: str | None = None):
    """(mean, variance of the mean) of the green channel of the scene rendered at its spp."""
    renderer = Renderer(scene)
    renderer.render(CameraFrame.from_spec(scene.camera), scene.render.spp, *([integrator] if integrator else []))
    return renderer.film.mean_image()[..., 1], renderer.film.variance_of_mean_image()[..., 1]


def assert_image_mean(mean, var, expected, level=ALPHA, precision=0.02):
    """A z-test of the image mean at `level` (two-sided), and a run precise enough to tell a
    3 x `precision` error apart."""
    z = (mean.mean() - expected) / np.sqrt(var.sum() / mean.size ** 2)
    assert abs(z) < stats.norm.ppf(1 - level / 2), (mean.mean(), expected, z)
    assert np.sqrt(var.sum()) / mean.size < precision * expected


def assert_binomial_mean(mean, spp, expected):
    """Each sample 0 or 1 (absorbed or not, blocked or not): a z-test on the binomial mean at ALPHA."""
    n = mean.size * spp
    z = (mean.mean() - expected) / math.sqrt(expected * (1 - expected) / n)
    assert abs(z) < stats.norm.ppf(1 - ALPHA / 2), (mean.mean(), expected, z)


def test_area_light_lights_a_diffuse_floor(tmp_path):
    scene, _ = load(tmp_path, WORLD, options=SCENE_OPTIONS)
    assert scene.render.max_depth == 2 and scene.render.seed == 5
    # radiance = albedo / pi * irradiance, irradiance = pi L (4 corner form factors)
    assert_image_mean(*rendered(scene), ALBEDO * RADIANCE * 4.0 * corner_form_factor(HALF, HALF, HEIGHT))


@pytest.mark.parametrize("scale, side", [("Scale -1 1 1\n", "right"), ("", "left")])
def test_marked_object_lands_on_pbrts_side_of_the_image(tmp_path, scale, side):
    """An emitter at world +x: on the right under `Scale -1 1 1`, on the left under a bare LookAt
    (pbrt's camera x is up x direction)."""
    options = (scale + 'LookAt 0 0 5  0 0 0  0 1 0\nCamera "perspective" "float fov" 60\n'
               'Film "rgb" "integer xresolution" 16 "integer yresolution" 8\n'
               'Sampler "independent" "integer pixelsamples" 4\nIntegrator "path" "integer maxdepth" 0\n'
               'PixelFilter "box"\n')  # samples stay in their pixel: the halves are apart
    world = ('AreaLightSource "diffuse" "rgb L" [1 1 1]\n'
             'Shape "trianglemesh" "point3 P" [0.5 -1.5 0  3 -1.5 0  3 1.5 0  0.5 1.5 0] "integer indices" [0 1 2 0 2 3]\n')
    scene, _ = load(tmp_path, world, options=options)
    renderer = Renderer(scene)
    renderer.render(CameraFrame.from_spec(scene.camera), scene.render.spp)
    image = renderer.film.mean_image()[..., 1]
    left, right = image[:, :8].sum(), image[:, 8:].sum()
    assert (right > 0 and left == 0) if side == "right" else (left > 0 and right == 0), (left, right)


# A glass sphere of index 1 (no bend, no reflection) whose outside is the absorbing gas it stands in,
# inside a boundary that holds the gas: a ray through the centre crosses 2 x (1 - 0.5) of gas.
NESTED_OPTIONS = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 1
Film "rgb" "integer xresolution" 4 "integer yresolution" 4
Sampler "independent" "integer pixelsamples" 256 "integer seed" 3
Integrator "volpath" "integer maxdepth" 10
PixelFilter "box"
"""
NESTED_WORLD = """LightSource "infinite" "rgb L" [1 1 1]
MakeNamedMedium "gas" "string type" "homogeneous" "rgb sigma_a" [1 1 1] "rgb sigma_s" [0 0 0]
AttributeBegin
MediumInterface "gas" ""
Material "interface"
Shape "sphere" "float radius" 1
AttributeEnd
AttributeBegin
MediumInterface "" "gas"
Material "dielectric" "float eta" 1
Shape "sphere" "float radius" 0.5
AttributeEnd
"""


def test_a_ray_leaving_a_sphere_enters_the_medium_outside_it(tmp_path):
    scene, _ = load(tmp_path, NESTED_WORLD, options=NESTED_OPTIONS)
    # (the scene's empty space after the inner sphere would give exp(-0.5))
    assert_binomial_mean(rendered(scene)[0], scene.render.spp, math.exp(-1.0))


def test_light_through_a_diffuse_transmitter(tmp_path):
    """The floor of the first test as pbrt's diffusetransmission, seen from below: its radiance
    there is transmittance / pi times the irradiance on its top (light sampled through the sheet)."""
    transmittance = 0.3
    world = WORLD.replace(f'Material "diffuse" "rgb reflectance" [{ALBEDO} {ALBEDO} {ALBEDO}]',
                          f'Material "diffusetransmission" "rgb reflectance" [0.2 0.2 0.2] '
                          f'"rgb transmittance" [{transmittance} {transmittance} {transmittance}]')
    options = SCENE_OPTIONS.replace("LookAt 0 0.5 0  0 0 0  0 0 1", "LookAt 0 -0.5 0  0 0 0  0 0 1")
    scene, _ = load(tmp_path, world, options=options)
    assert_image_mean(*rendered(scene), transmittance * RADIANCE * 4.0 * corner_form_factor(HALF, HALF, HEIGHT))


def test_a_mix_of_images_colours_the_floor(tmp_path):
    """The floor of the first test textured by pbrt's mix of two grey images by a third: its
    albedo is (1 - a) v1 + a v2 everywhere (with the amount turned round it would be 0.65)."""
    values = {"v1.png": 51, "v2.png": 204, "a.png": 64}
    for name, value in values.items():
        Image.new("RGB", (2, 2), (value,) * 3).save(tmp_path / name)
    v1, v2, a = (values[n] / 255 for n in ("v1.png", "v2.png", "a.png"))
    textures = "".join(f'Texture "{n[:2]}" "spectrum" "imagemap" "string filename" "{n}" "string encoding" "linear"\n'
                       for n in values)
    textures += 'Texture "m" "spectrum" "mix" "texture tex1" "v1" "texture tex2" "v2" "texture amount" "a."\n'
    world = textures + WORLD.replace(f'"rgb reflectance" [{ALBEDO} {ALBEDO} {ALBEDO}]', '"texture reflectance" "m"')
    scene, _ = load(tmp_path, world, options=SCENE_OPTIONS)
    albedo = (1 - a) * v1 + a * v2
    assert_image_mean(*rendered(scene), albedo * RADIANCE * 4.0 * corner_form_factor(HALF, HALF, HEIGHT))


def test_a_shapes_alpha_lets_that_share_of_the_light_through(tmp_path):
    """A black sphere of alpha 0.3 before an emitter of radiance 1 fills the view: each camera
    sample passes with probability 0.7 (a binomial z-test at the 1% level)."""
    options = NESTED_OPTIONS.replace("Integrator \"volpath\" \"integer maxdepth\" 10", "Integrator \"path\" \"integer maxdepth\" 1")
    world = ('AttributeBegin\nAreaLightSource "diffuse" "rgb L" [1 1 1]\n'
             'Shape "trianglemesh" "point3 P" [-5 -5 -3  5 -5 -3  5 5 -3  -5 5 -3] "integer indices" [0 1 2 0 2 3]\n'
             'AttributeEnd\nMaterial "diffuse" "rgb reflectance" [0 0 0]\n'
             'Shape "sphere" "float radius" 1 "float alpha" 0.3\n')
    scene, _ = load(tmp_path, world, options=options)
    assert_binomial_mean(rendered(scene)[0], scene.render.spp, 0.7)


@pytest.mark.parametrize("integrator", ["mis", "path"])
def test_a_two_sided_light_facing_away_lights_the_floor_from_its_back(tmp_path, integrator):
    """The first test's emitter turned to face up (away from the floor) and made two-sided: the floor
    receives the same irradiance, by light sampling through its back face (mis) and by paths that
    hit it (path); one-sided, it would be dark."""
    world = WORLD.replace('AreaLightSource "diffuse" "rgb L" [{0} {0} {0}]'.format(RADIANCE),
                          'AreaLightSource "diffuse" "rgb L" [{0} {0} {0}] "bool twosided" true'.format(RADIANCE))
    world = world.replace("[0 1 2 0 2 3]", "[0 2 1 0 3 2]", 1)  # the emitter's winding turned over
    scene, _ = load(tmp_path, world, options=SCENE_OPTIONS.replace('"integer pixelsamples" 32',
                                                                    '"integer pixelsamples" 128'))
    assert_image_mean(*rendered(scene, integrator), ALBEDO * RADIANCE * 4.0 * corner_form_factor(HALF, HALF, HEIGHT),
                      level=ALPHA / 2, precision=0.05)  # (about Sidak's level over the two)


def test_light_through_a_uniform_grid_medium(tmp_path):
    """pbrt's uniformgrid (two cells: density 0 and 2 at their centres x = -0.5 and 0.5, clamped
    beyond) inside an interface sphere of radius 1, absorbing only: the rays at x = 0.75 cross a
    chord of 2 sqrt(1 - 0.75^2) at density 2 (a binomial z-test at the 1% level)."""
    options = NESTED_OPTIONS.replace("LookAt 0 0 5  0 0 0  0 1 0", "LookAt 0.75 0 5  0.75 0 0  0 1 0")
    world = ('LightSource "infinite" "rgb L" [1 1 1]\n'
             'MakeNamedMedium "smoke" "string type" "uniformgrid" "integer nx" 2 "integer ny" 1 "integer nz" 1 '
             '"float density" [0 2] "point3 p0" [-1 -1 -1] "point3 p1" [1 1 1] "rgb sigma_a" [1 1 1] '
             '"rgb sigma_s" [0 0 0]\n'
             'AttributeBegin\nMediumInterface "smoke" ""\nMaterial "interface"\nShape "sphere" "float radius" 1\n'
             'AttributeEnd\n')
    scene, _ = load(tmp_path, world, options=options)
    assert_binomial_mean(rendered(scene)[0], scene.render.spp, math.exp(-2.0 * 2.0 * math.sqrt(1 - 0.75 ** 2)))
