"""Lights that project an image (renderer/lights/delta_lights.py with light_projection.py): a spot's
texture and Mitsuba 3's projector, rendered against their analytic images, and the choice among
delta lights by their contribution at the shading point.

Analytic images (direct light only, max_depth 2, black environment, a diffuse plane y = 0 of albedo
rho, through tests/lights/test_delta_lights.py's midpoint rule per pixel):
  - a tilted spot with an image:  L = rho / pi * I falloff(theta) T(uv) cos / r^2, uv where the
                                  direction meets the image (the cutoff circle inscribed in it),
                                  beam and ramp in view, the cutoff beyond it;
  - a tilted projector:           L = rho / pi * E T(uv) pi r / z^3 * cos inside its image, 0 out
                                  of it, z the depth along its axis; its image is 5 x 3 texels
                                  (aspect 5/3, fov along y) so a swapped axis or aspect fails;
  - the constant projector:       a plane at distance 1 facing it receives pi E (Mitsuba's
                                  definition) everywhere in its square image: the pixels wholly
                                  inside or outside it are exact (every sample the same value),
                                  the image mean (green) is z-tested.
T is the image through the numpy reference sampler (renderer/scene/textures.py, bilinear, texel
centres at half-integers). Every decision is Mitsuba's render-test rule: a per-pixel z-test against
the analytic value (Sidak-corrected to ALPHA = 0.01, 99.75 % of the channels must pass) and a
z-test of the image mean (green) at ALPHA, two-sided; seeds are fixed. The images have distinct
texel colours in every channel, so a mirrored or flipped image, or a wrong aspect, fails both.

Selection: a scene with a textured spot, a projector, a point and a directional light renders, by
`mis`, the sum of the renders of each light alone (assert_agree), with lights chosen by their
contribution at each point (the default) and uniformly: each sample is divided by its choice's
probability, so either is unbiased (a probability left out of the division fails it).
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from PIL import Image
from scipy import stats

from renderer.lights.delta_lights import spot_falloff
from renderer.lights.light_projection import image_uv, light_frame, projection_scale, projector_value
from renderer.scene.features import scene_features
from renderer.scene.limits import MemoryBudget, MemoryLedger
from renderer.scene.texture_images import texture_image
from renderer.scene.textures import pack_atlas, sample_bilinear
from tests.lights.test_delta_lights import (ALPHA, PLANE, RHO, assert_analytic, mixed_scene, plane_image,
                                            render, uniform_renderer)
from tests.scene_builder import scene_from_toml
from tests.stats.image_tests import assert_agree, mean_z

# sRGB texels (row 0 on top): every channel differs from texel to texel.
SLIDE = np.array([[[250, 30, 30], [30, 250, 30], [30, 30, 250], [250, 250, 30], [160, 90, 200]],
                  [[90, 200, 160], [250, 250, 250], [60, 60, 60], [200, 120, 40], [40, 120, 200]],
                  [[120, 40, 200], [200, 40, 120], [10, 200, 10], [220, 180, 140], [100, 100, 250]]], np.uint8)

TEXTURED_SPOT = """
[[lights]]
type = "spot"
position = [0.1, 1.0, 0.0]
direction = [0.1, -1.0, 0.1]
up = [1.0, 0.0, 0.4]
intensity = [4.0, 3.0, 2.0]
cutoff_angle = 72
beam_width = 55
texture = "slide.png"
"""

PROJECTOR = """
[[lights]]
type = "projector"
position = [-0.2, 1.4, 0.1]
direction = [-0.25, -1.0, 0.15]
up = [0.0, 0.3, -1.0]
irradiance = [1.5, 1.2, 1.0]
texture = "slide.png"
fov = 70
fov_axis = "y"
"""

CONSTANT_PROJECTOR = """
[[lights]]
type = "projector"
position = [0.0, 1.0, 0.0]
direction = [0.0, -1.0, 0.0]
up = [0.0, 0.0, -1.0]
irradiance = [0.5, 0.4, 0.3]
fov = 60
"""


def textured_plane(tmp_path, lights: str):
    Image.fromarray(SLIDE).save(tmp_path / "slide.png")
    return scene_from_toml(tmp_path, PLANE.format(lights=lights))


def image_at(light, local):
    """The light's image (linear RGB) where light-frame points or directions `local` meet it."""
    image = texture_image(light.texture, MemoryLedger(MemoryBudget.from_settings()))
    height, width = image.pixels.shape[:2]
    uv = image_uv(projection_scale(light, width / height), local)
    return sample_bilinear(pack_atlas([image]), 0, uv)[..., :3], uv


def local_points(light, p):
    return (p - np.asarray(light.position)) @ light_frame(light).T


def cos_at_plane(light, p):
    to = np.asarray(light.position) - p
    r = np.sqrt((to ** 2).sum(-1))
    return np.maximum(to[..., 1], 0.0) / r, r


def test_a_spot_projects_its_texture(tmp_path):
    # The cone's edge outside the view (its profile is tests/lights/test_delta_lights.py's): an edge
    # pixel lit by a sliver of the cone has a mean of rare events, not a near-normal one.
    scene = textured_plane(tmp_path, TEXTURED_SPOT)
    scene = replace(scene, camera=replace(scene.camera, fov=40.0))
    (light,) = scene.lights
    assert scene_features(scene).has_light_textures

    def radiance_at(p):
        cos, r = cos_at_plane(light, p)
        local = local_points(light, p)
        theta = np.arccos(np.clip(local[..., 2] / r, -1.0, 1.0))
        texel, _ = image_at(light, local)
        value = spot_falloff(theta, light.cutoff_angle, light.beam)[..., None] * np.where(
            local[..., 2:3] > 0.0, texel, 0.0)
        return np.asarray(RHO) / math.pi * np.asarray(light.intensity) * value * (cos / r ** 2)[..., None]

    expected = plane_image(scene, radiance_at)
    corners = np.array([[x, 0.0, z] for x in (-1.37, 1.37) for z in (-1.1, 1.1)])  # of the view on the plane
    _, uv = image_at(light, local_points(light, corners))
    assert np.all((uv > 0.0) & (uv < 1.0)) and np.ptp(uv, axis=0).min() > 0.45  # inside the cone, across texels
    assert_analytic(render(scene, "mis", 64, seed=21), expected, "textured spot")


def test_a_projector_projects_its_image(tmp_path):
    scene = textured_plane(tmp_path, PROJECTOR)
    (light,) = scene.lights

    def radiance_at(p):
        cos, r = cos_at_plane(light, p)
        local = local_points(light, p)
        texel, uv = image_at(light, local)
        value = projector_value(uv, local[..., 2], r)[..., None] * texel
        return np.asarray(RHO) / math.pi * np.asarray(light.irradiance) * value * cos[..., None]

    expected = plane_image(scene, radiance_at)
    lit = (expected[..., 1] > 0.0).mean()
    assert 0.2 < lit < 0.8, lit  # the image's edges cross the view
    assert_analytic(render(scene, "nee", 64, seed=22), expected, "projector")


def test_a_constant_projector_gives_pi_times_its_irradiance_at_distance_one(tmp_path):
    """Mitsuba's definition: a white diffuse plane at distance 1 facing the projector shows its
    irradiance E as radiance (it receives pi E); out to the edges of its square image."""
    scene = scene_from_toml(tmp_path, PLANE.format(lights=CONSTANT_PROJECTOR))
    assert not scene_features(scene).has_light_textures  # no image: no lookups compiled in
    half = math.tan(math.radians(30.0))

    def radiance_at(p):
        inside = (np.abs(p[..., 0]) <= half) & (np.abs(p[..., 2]) <= half)
        return np.asarray(RHO) * np.asarray((0.5, 0.4, 0.3)) * inside[..., None]

    expected = plane_image(scene, radiance_at)
    full, empty = expected[..., 1] == expected[..., 1].max(), expected[..., 1] == 0.0
    assert full.mean() > 0.03 and empty.mean() > 0.5
    mean, var = render(scene, "mis", 64, seed=23)
    # Every sample of a pixel wholly inside (or outside) the image has the same value: those pixels
    # are exact (to float rounding); the pixels its edges cross are decided by the image mean.
    np.testing.assert_allclose(mean[full | empty], expected[full | empty], rtol=1e-5, atol=1e-9)
    z = mean_z(mean, var, expected[..., 1].mean())
    assert abs(z) < stats.norm.isf(ALPHA / 2), f"constant projector: image mean (green) z = {z:.2f}"


def test_the_choice_among_lights_is_unbiased(tmp_path):
    Image.fromarray(SLIDE).save(tmp_path / "slide.png")
    base = textured_plane(tmp_path, TEXTURED_SPOT + PROJECTOR)
    spot, projector = base.lights
    lights = (replace(spot, position=(0.4, 1.6, 0.3), direction=(-0.2, -1.0, -0.4)),
              replace(projector, position=(-0.5, 1.8, 0.2), irradiance=(3.0, 2.5, 2.0)),
              replace(spot, kind="point", texture=None, position=(1.0, 1.2, 0.8), intensity=(0.8, 0.7, 0.6)),
              replace(spot, kind="directional", texture=None, direction=(0.3, -1.0, -0.4), irradiance=(0.3, 0.3, 0.3)))
    alone = [render(mixed_scene(tmp_path, [light], lamp=0.0, sky=0.0), "mis", 256, seed=90 + i)
             for i, light in enumerate(lights)]
    total = (sum(a[0] for a in alone), sum(a[1] for a in alone))
    scene = mixed_scene(tmp_path, lights, lamp=0.0, sky=0.0)
    assert_agree(render(scene, "mis", 1024, seed=95), total, ("all lights, chosen at each point", "sum of each alone"))
    assert_agree(render(scene, "mis", 1024, seed=96, renderer=uniform_renderer(scene)), total,
                 ("all lights, chosen uniformly", "sum of each alone"))
