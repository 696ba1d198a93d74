"""Point, spot and directional lights (renderer/lights/delta_lights.py) rendered against their
analytic images, and `nee` against `mis` where they light a scene with every other kind of light.

Analytic images (direct light only, max_depth 2, black environment, diffuse albedo rho; every pixel
mean is the box-filtered average of the exact radiance over the pixel, computed here by a 48 x 48
midpoint rule per pixel through the renderer's own pinhole model):
  - a plane under a point light:            L = rho / pi * I cos(theta) / r^2;
  - a plane under a tilted spot:             the same times Mitsuba 3's falloff (1 within the
                                             beam, linear in angle to 0 at the cutoff): the profile
                                             crosses the image, beam edge and cutoff included;
  - a sphere under a directional light:      L = rho / pi * E cos(theta), the sphere filling the
                                             view (a pixel on its silhouette, or on the terminator,
                                             would have a mean of rare events, not near-normal),
                                             cos(theta) from 0.1 to 0.87 across it.
Each is tested by the per-pixel rule (a z-test of every pixel and channel against the analytic
value with the film's variance of the mean, Sidak-corrected to ALPHA = 0.01 over the image;
99.75 % of the pixel channels must pass, as Mitsuba's render tests ask) and by a z-test of the
image mean (green) against the analytic image's mean at ALPHA, two-sided. The only randomness is
the pixel jitter, so the pixel tests are sharp: a directional irradiance 1 % too high fails them,
as do 1 / r rather than 1 / r^2, and a smoothstep in cos(theta) in place of Mitsuba's ramp.

Selection: a scene with two point lights, a spot, a directional light, an emissive sphere and a
constant sky renders, by `mis`, the sum of the renders of each of them alone (image means and per-
pixel rule on the difference, variances added), with the delta lights chosen by power and
uniformly: the choice's probability divides each sample, so any selection is unbiased (leaving the
light's probability, or the emissive sphere's share, out of a sample's density fails it).
`nee` and `mis` agree on that scene (assert_agree, different seeds; a glossy and a diffuse ball on
a floor, max depth 4: indirect light included) and in a scattering medium (light samples at
scattering points, weighed against the phase function), and `path` renders a scene lit only by delta
lights black: no BSDF sample can find them (as in pbrt).
Seeds are fixed.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

from renderer.camera import CameraFrame
from renderer.lights.delta_lights import spot_falloff, spot_solid_angle
from renderer.renderer import Renderer
from renderer.scene.description import LightSpec
from tests.scene_builder import scene_from_toml
from tests.stats.image_tests import assert_agree, describe, mean_z, pixel_z_test

ALPHA = 0.01
SUB = 48  # midpoint rule per pixel side for the analytic images
RHO = (0.8, 0.5, 0.3)

PLANE = """
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
[materials.floor]
base_color = [0.8, 0.5, 0.3]
[[objects]]
type = "quad"
size = [40.0, 40.0]
material = "floor"
{lights}
"""

BALL = """
[scene]
geometry = "mesh"
[camera]
position = [0.0, 0.0, 1.6]
look_at = [0.0, 0.0, 0.0]
fov = 50
[render]
width = 36
height = 32
max_depth = 2
[environment]
type = "constant"
color = [0.0, 0.0, 0.0]
[materials.clay]
base_color = [0.8, 0.5, 0.3]
[[objects]]
type = "sphere"
radius = 1.0
material = "clay"
[[lights]]
type = "directional"
direction = [-0.79, -0.21, -0.57]
irradiance = [2.0, 1.5, 1.0]
"""

POINT = """
[[lights]]
type = "point"
position = [0.7, 1.0, 0.3]
intensity = [3.0, 2.0, 1.0]
"""

SPOT = """
[[lights]]
type = "spot"
position = [0.2, 1.2, -0.1]
direction = [0.3, -1.0, 0.2]
intensity = [4.0, 3.0, 2.0]
cutoff_angle = 35
beam_width = 20
"""


def render(scene, integrator, spp, seed, renderer=None):
    """(mean image, variance of the mean) as float64, row 0 at the top."""
    r = renderer or Renderer(scene)
    r.reset()
    r.render(CameraFrame.from_spec(scene.camera), spp, integrator, seed=seed)
    assert r.film.stats()["rejected"] == 0, "non-finite samples"
    return r.film.mean_image().astype(np.float64), r.film.variance_of_mean_image().astype(np.float64)


def camera_rays(scene):
    """(origin, unit directions (H, W, SUB * SUB, 3)) through a SUB x SUB midpoint grid of every
    pixel, as renderer/camera.py generate_ray makes them (y up; returned with row 0 at the top)."""
    cam = CameraFrame.from_spec(scene.camera)
    w, h = scene.render.width, scene.render.height
    t = math.tan(math.radians(cam.fov) / 2.0)
    j = (np.arange(SUB) + 0.5) / SUB
    x = (np.arange(w)[:, None] + j[None, :]).reshape(-1)  # (W * SUB,)
    y = (np.arange(h)[:, None] + j[None, :]).reshape(-1)
    sx = (2.0 * x / w - 1.0) * t * (w / h)
    sy = (2.0 * y / h - 1.0) * t
    f, r, u = (np.asarray(v, np.float64) for v in (cam.forward, cam.right, cam.up))
    d = f + sx[None, :, None] * r + sy[:, None, None] * u  # (H * SUB, W * SUB, 3), y up
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    d = d.reshape(h, SUB, w, SUB, 3).transpose(0, 2, 1, 3, 4).reshape(h, w, SUB * SUB, 3)
    return np.asarray(cam.position, np.float64), d[::-1]


def plane_image(scene, radiance_at):
    """The box-filtered image of the plane y = 0: radiance_at(points (..., 3)) -> (..., 3)."""
    o, d = camera_rays(scene)
    t = -o[1] / d[..., 1]
    assert np.all(t > 0), "every ray must meet the plane"
    return radiance_at(o + t[..., None] * d).mean(axis=2)


def point_radiance(position, intensity, falloff=None):
    def radiance_at(p):
        to = np.asarray(position) - p
        r2 = (to ** 2).sum(-1)
        cos = np.maximum(to[..., 1], 0.0) / np.sqrt(r2)  # the plane's normal is +y
        value = cos / r2
        if falloff is not None:
            value = value * falloff(-to / np.sqrt(r2)[..., None])
        return np.asarray(RHO) / math.pi * np.asarray(intensity) * value[..., None]
    return radiance_at


def assert_analytic(rendered, expected, names):
    mean, var = rendered
    passed, fraction, _, p_value, level = pixel_z_test(mean, var, expected, np.zeros_like(expected))
    assert passed, (f"{names}: {fraction:.2%} of the pixel channels pass at the Sidak level {level:.1e}\n"
                    + describe((mean, var), (expected, np.zeros_like(expected)), p_value, ("rendered", "analytic")))
    z = mean_z(mean, var, expected[..., 1].mean())
    assert abs(z) < stats.norm.isf(ALPHA / 2), f"{names}: image mean (green) z = {z:.2f}"


@pytest.mark.parametrize("integrator", ["nee", "mis"])
def test_point_light_on_a_plane(tmp_path, integrator):
    scene = scene_from_toml(tmp_path, PLANE.format(lights=POINT))
    expected = plane_image(scene, point_radiance((0.7, 1.0, 0.3), (3.0, 2.0, 1.0)))
    assert_analytic(render(scene, integrator, 64, seed=11), expected, f"point light, {integrator}")


def test_spot_falloff_on_a_plane(tmp_path):
    scene = scene_from_toml(tmp_path, PLANE.format(lights=SPOT))
    axis = np.array([0.3, -1.0, 0.2]) / np.linalg.norm([0.3, -1.0, 0.2])

    def falloff(w):
        return spot_falloff(np.arccos(np.clip(w @ axis, -1.0, 1.0)), 35.0, 20.0)

    expected = plane_image(scene, point_radiance((0.2, 1.2, -0.1), (4.0, 3.0, 2.0), falloff))
    # The image holds the whole profile: dark corners beyond the cutoff, the ramp, the full beam.
    assert expected[..., 1].min() == 0.0 and (expected[..., 1] > 0.0).mean() < 0.9
    assert_analytic(render(scene, "mis", 64, seed=12), expected, "spot light")


def test_directional_light_on_a_sphere(tmp_path):
    scene = scene_from_toml(tmp_path, BALL)
    o, d = camera_rays(scene)
    b = (o * d).sum(-1)
    disc = b * b - (o @ o - 1.0)
    hit = disc > 0.0
    t = -b - np.sqrt(np.where(hit, disc, 0.0))
    n = o + t[..., None] * d
    assert hit.all(), "the sphere fills the view (a silhouette pixel's mean is not near-normal)"
    towards = np.array([0.79, 0.21, 0.57]) / np.linalg.norm([0.79, 0.21, 0.57])
    cos = n @ towards
    assert 0.0 < cos.min() < 0.15 and cos.max() > 0.85  # lit everywhere, from grazing to nearly head-on
    expected = (np.asarray(RHO) / math.pi * np.array([2.0, 1.5, 1.0]) * cos[..., None]).mean(axis=2)
    assert_analytic(render(scene, "mis", 64, seed=13), expected, "directional light")


def test_spot_solid_angle_integrates_the_falloff():
    """The spot's power factor (used to choose among lights) is its falloff over the sphere."""
    theta = np.linspace(0.0, math.pi, 200_001)
    for cutoff, beam in ((20.0, 15.0), (35.0, 20.0), (90.0, 0.0), (30.0, 30.0)):
        numeric = 2 * math.pi * np.trapezoid(spot_falloff(theta, cutoff, beam) * np.sin(theta), theta)
        assert spot_solid_angle(cutoff, beam) == pytest.approx(numeric, rel=1e-4), (cutoff, beam)


# --- selection among lights, and nee against mis ------------------------------------------------

MIXED = """
[scene]
geometry = "mesh"
[camera]
position = [0.0, 1.3, 3.0]
look_at = [0.0, 0.4, 0.0]
fov = 45
[render]
width = 24
height = 18
max_depth = {max_depth}
[environment]
type = "constant"
color = [{sky}, {sky}, {sky}]
[materials.floor]
base_color = [0.6, 0.6, 0.6]
[materials.clay]
base_color = [0.7, 0.5, 0.4]
[materials.metal]
type = "conductor"
base_color = [0.9, 0.8, 0.6]
roughness = 0.4
[materials.lamp]
emission = [{lamp}, {lamp}, {lamp}]
[[objects]]
type = "quad"
size = [6.0, 6.0]
material = "floor"
[[objects]]
type = "sphere"
material = "clay"
radius = 0.4
translate = [-0.5, 0.4, 0.0]
[[objects]]
type = "sphere"
material = "metal"
radius = 0.4
translate = [0.5, 0.4, 0.0]
[[objects]]
type = "sphere"
material = "lamp"
radius = 0.15
translate = [0.0, 1.6, -0.6]
"""

# The emissive sphere's radiance: bright enough that the share of light samples it gets (about a
# third here, by power) matters to the image.
LAMP = 40.0

DELTA_LIGHTS = (
    LightSpec("point", position=(-1.0, 1.5, 1.0), intensity=(2.0, 1.8, 1.5)),
    LightSpec("point", position=(1.2, 0.9, 0.8), intensity=(0.3, 0.4, 0.6)),
    LightSpec("spot", position=(0.6, 2.0, 0.6), direction=(-0.3, -1.0, -0.3), intensity=(6.0, 5.0, 4.0),
              cutoff_angle=30.0, beam_width=18.0),
    LightSpec("directional", direction=(0.4, -1.0, -0.5), irradiance=(0.8, 0.7, 0.6)),
)


def mixed_scene(tmp_path, lights, lamp=LAMP, sky=0.2, max_depth=3):
    body = MIXED.format(lamp=lamp, sky=sky, max_depth=max_depth)
    return replace(scene_from_toml(tmp_path, body), lights=tuple(lights))


def uniform_renderer(scene):
    """A Renderer whose delta lights are chosen uniformly rather than by power."""
    from renderer.lights.delta_lights import DeltaLights
    from renderer.lights.lights import Lights, emitter_table

    r = Renderer(scene)
    delta = DeltaLights(scene.lights, r.scene_radius(), selector_kind="uniform")
    r._lights = Lights(r.geometry, emitter_table(r.geometry, r.materials.arrays), r.environment, scene.environment,
                       None, delta=delta)
    return r


@pytest.mark.parametrize("selection", ["power", "uniform"])
def test_all_lights_render_the_sum_of_each_alone(tmp_path, selection):
    parts = [mixed_scene(tmp_path, [light], lamp=0.0, sky=0.0) for light in DELTA_LIGHTS]
    parts.append(mixed_scene(tmp_path, [], lamp=LAMP, sky=0.0))
    parts.append(mixed_scene(tmp_path, [], lamp=0.0, sky=0.2))
    alone = [render(s, "mis", 256, seed=40 + i) for i, s in enumerate(parts)]
    total = (sum(a[0] for a in alone), sum(a[1] for a in alone))
    scene = mixed_scene(tmp_path, DELTA_LIGHTS)
    renderer = uniform_renderer(scene) if selection == "uniform" else None
    together = render(scene, "mis", 2048, seed=50, renderer=renderer)
    assert_agree(together, total, (f"all lights ({selection})", "sum of each alone"))


def test_nee_and_mis_agree(tmp_path):
    scene = mixed_scene(tmp_path, DELTA_LIGHTS, max_depth=4)
    r = Renderer(scene)
    assert_agree(render(scene, "nee", 1024, seed=60, renderer=r), render(scene, "mis", 1024, seed=61, renderer=r),
                 ("nee", "mis"))


FOGGY = """
[scene]
geometry = "sdf"
[camera]
position = [0.0, 1.0, 3.0]
look_at = [0.0, 0.5, 0.0]
[render]
width = 24
height = 18
max_depth = 4
[environment]
type = "constant"
color = [0.0, 0.0, 0.0]
[media.haze]
sigma_a = [0.05, 0.05, 0.05]
sigma_s = [0.3, 0.25, 0.2]
g = 0.3
[fog]
type = "medium"
medium = "haze"
[materials.white]
base_color = [0.7, 0.7, 0.7]
[[objects]]
type = "plane"
material = "white"
[[objects]]
type = "sphere"
material = "white"
radius = 0.5
translate = [0.0, 0.5, 0.0]
"""


def test_nee_and_mis_agree_in_a_medium(tmp_path):
    """Light samples taken at scattering points in a medium weigh delta lights by 1 as well."""
    scene = replace(scene_from_toml(tmp_path, FOGGY), lights=DELTA_LIGHTS[:3])
    r = Renderer(scene)
    assert_agree(render(scene, "nee", 512, seed=80, renderer=r), render(scene, "mis", 512, seed=81, renderer=r),
                 ("nee in a medium", "mis in a medium"))


def test_path_never_sees_delta_lights(tmp_path):
    scene = mixed_scene(tmp_path, DELTA_LIGHTS, lamp=0.0, sky=0.0)
    mean, _ = render(scene, "path", 16, seed=70)
    assert not mean.any()
    lit, _ = render(scene, "mis", 16, seed=70)
    assert lit[..., 1].mean() > 0.01  # the same scene under light sampling is lit
