"""Smooth thin dielectric walls in the path tracer (renderer/integrators/tracer.py), as Mitsuba's
thindielectric: passing straight through one is no bounce, shadow rays pass it with its
transmittance (MIS keeping the vertex before it), and a wall that bounds a medium is entered.

- An emitter behind a pane at max_depth = 1 (emitters seen directly) shows through it at the
  pane's transmittance 1 - 2F / (1 + F): a z-test of the image mean against that value.
- A floor lit through a pane: `path` (no shadow rays) and `mis` (shadow rays through the pane)
  agree by the pixel rule of Mitsuba's render tests (tests/stats/image_tests.py).
- A thin wall of index 1.0001 (reflectance 2.5e-9) around a medium renders as a `null` boundary
  around it, at a depth limit the wall's crossings would otherwise use up.

ALPHA = 0.01 family-wise over the module's NUM_TESTS tests (Sidak-corrected); fixed seeds.
"""
import numpy as np
from scipy import stats

from renderer.camera import CameraFrame
from renderer.renderer import Renderer
from tests.scene_builder import scene_from_toml
from tests.stats.chi2 import sidak_alpha
from tests.stats.image_tests import assert_agree, mean_z

ALPHA = 0.01
NUM_TESTS = 3 + 1 + 1  # the pane's three channels, two image agreements
LEVEL = sidak_alpha(ALPHA, NUM_TESTS)

PANE = """
[scene]
geometry = "mesh"
[camera]
position = [0.0, 0.0, 5.0]
look_at = [0.0, 0.0, 0.0]
fov = 2.0
[render]
width = 16
height = 16
max_depth = 1
[environment]
type = "constant"
color = [0.0, 0.0, 0.0]
[materials.glass]
type = "dielectric"
thin = true
ior = 1.5
base_color = [1.0, 1.0, 1.0]
[materials.lamp]
type = "diffuse"
base_color = [0.0, 0.0, 0.0]
emission = [1.0, 1.0, 1.0]
[[objects]]
type = "quad"
material = "glass"
size = [2.0, 2.0]
rotate = [90.0, 0.0, 0.0]
translate = [0.0, 0.0, 1.0]
[[objects]]
type = "quad"
material = "lamp"
size = [2.0, 2.0]
rotate = [90.0, 0.0, 0.0]
"""

LIT_THROUGH_A_PANE = """
[scene]
geometry = "mesh"
[camera]
position = [0.0, 1.2, 4.0]
look_at = [0.0, 0.0, 0.0]
fov = 40
[render]
width = 20
height = 20
max_depth = 3
[environment]
type = "constant"
color = [0.0, 0.0, 0.0]
[materials.glass]
type = "dielectric"
thin = true
ior = 1.5
base_color = [0.9, 0.7, 0.5]
[materials.floor]
type = "diffuse"
base_color = [0.8, 0.8, 0.8]
[materials.lamp]
type = "diffuse"
base_color = [0.0, 0.0, 0.0]
emission = [2.0, 2.0, 2.0]
[[objects]]
type = "quad"
material = "floor"
size = [4.0, 4.0]
[[objects]]
type = "quad"
material = "glass"
size = [1.6, 1.6]
translate = [0.3, 1.0, 0.0]
[[objects]]
type = "quad"
material = "lamp"
size = [2.5, 2.5]
rotate = [180.0, 0.0, 0.0]
translate = [0.0, 2.0, 0.0]
"""

MEDIUM_IN_A_WALL = """
[scene]
geometry = "mesh"
[camera]
position = [0.0, 0.8, 3.0]
look_at = [0.0, 0.2, 0.0]
fov = 40
[render]
width = 20
height = 20
max_depth = 4
[environment]
type = "sky"
[media.cloud]
sigma_a = [0.5, 1.0, 1.5]
sigma_s = [2.0, 1.5, 1.0]
g = 0.2
[materials.wall]
{wall}
medium = "cloud"
[materials.floor]
type = "diffuse"
base_color = [0.6, 0.6, 0.6]
[[objects]]
type = "sphere"
material = "wall"
radius = 0.6
translate = [0.0, 0.4, 0.0]
[[objects]]
type = "quad"
material = "floor"
size = [4.0, 4.0]
translate = [0.0, -0.2, 0.0]
"""


def render(scene, integrator, spp, seed):
    renderer = Renderer(scene)
    renderer.render(CameraFrame.from_spec(scene.camera), spp, integrator=integrator, seed=seed)
    assert renderer.film.stats()["rejected"] == 0
    return renderer.image().astype(np.float64), renderer.film.variance_of_mean_image().astype(np.float64)


def test_an_emitter_shows_through_a_pane_at_depth_one(tmp_path):
    image, variance = render(scene_from_toml(tmp_path, PANE), "mis", 64, seed=3)
    f = ((1.5 - 1.0) / (1.5 + 1.0)) ** 2  # normal incidence (within 1.4 degrees: 3e-6 relative)
    expected = 1.0 - 2.0 * f / (1.0 + f)
    for c in range(3):
        z = mean_z(image, variance, expected, channel=c)
        assert 2.0 * stats.norm.sf(abs(z)) >= LEVEL, f"channel {c}: {image[..., c].mean():.5f} vs {expected:.5f}"


def test_light_through_a_pane_agrees_with_and_without_shadow_rays(tmp_path):
    scene = scene_from_toml(tmp_path, LIT_THROUGH_A_PANE)
    a = render(scene, "path", 1024, seed=5)
    b = render(scene, "mis", 64, seed=6)
    assert b[0].mean() > 0.05  # the floor is lit
    assert_agree(a, b, ("path", "mis"), alpha=LEVEL)


def test_a_clear_thin_wall_around_a_medium_is_a_null_boundary(tmp_path):
    wall = scene_from_toml(tmp_path, MEDIUM_IN_A_WALL.format(wall='type = "dielectric"\nthin = true\nior = 1.0001\nbase_color = [1.0, 1.0, 1.0]'),
                           name="wall")
    null = scene_from_toml(tmp_path, MEDIUM_IN_A_WALL.format(wall='type = "null"'), name="null")
    assert_agree(render(wall, "mis", 64, seed=7), render(null, "mis", 64, seed=8), ("thin wall", "null"), alpha=LEVEL)
