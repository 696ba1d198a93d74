"""Participating media in the path tracers (renderer/integrators/tracer.py) and the scene format.

- An absorbing slab between the camera and a white sky transmits exp(-sigma_t d) per channel.
- A medium of albedo 1 inside an invisible (`null`) sphere under a uniform sky of radiance 1
  conserves energy: every pixel's expectation is exactly 1 (the white furnace), for every
  integrator, on SDF and mesh scenes.
- Fog filling the scene (`[fog] type = "medium"`) attenuates an emitter by exp(-sigma_a D).
- The analytic fog blends to its colour by exp(-density t).
- Scenes without media compile no medium code (Features), and bad media are one-line errors.

Each statistical check is a z-test of the image mean (per channel) against its exact value with
the standard error from the per-pixel sample variance; ALPHA = 0.01 family-wise over the module,
Sidak-corrected; fixed seeds.
"""
import math

import numpy as np
import pytest
from scipy import stats

from renderer.camera import CameraFrame
from renderer.renderer import Renderer
from renderer.scene.errors import SceneError
from renderer.scene.features import scene_features
from tests.scene_builder import scene_from_toml
from tests.stats.chi2 import sidak_alpha
from tests.stats.image_tests import mean_z

ALPHA = 0.01
SLAB_CASES = ("path", "mis")
FURNACE_CASES = [("sdf", "path"), ("sdf", "nee"), ("sdf", "mis"), ("mesh", "mis")]
NUM_TESTS = 3 * (len(SLAB_CASES) + len(FURNACE_CASES) + 1)  # three channels each

SIGMA_A = (0.5, 1.0, 2.0)

SLAB = """
[scene]
geometry = "sdf"
[camera]
position = [0.0, 0.0, 5.0]
look_at = [0.0, 0.0, 0.0]
fov = 1.0
[render]
width = 16
height = 16
max_depth = -1
[environment]
type = "constant"
color = [1.0, 1.0, 1.0]
[media.ink]
sigma_a = [0.5, 1.0, 2.0]
sigma_s = [0.0, 0.0, 0.0]
[materials.boundary]
type = "null"
medium = "ink"
[[objects]]
type = "box"
material = "boundary"
size = [4.0, 4.0, 1.0]
"""

SDF_FURNACE = """
[scene]
geometry = "sdf"
[camera]
position = [0.0, 0.0, 3.0]
look_at = [0.0, 0.0, 0.0]
fov = 30
[render]
width = 16
height = 16
max_depth = -1
[environment]
type = "constant"
color = [1.0, 1.0, 1.0]
[media.cloud]
sigma_s = [2.0, 3.0, 4.0]
g = 0.5
[materials.boundary]
type = "null"
medium = "cloud"
[[objects]]
type = "sphere"
material = "boundary"
radius = 0.6
"""

# The same furnace in the mesh world (an analytic sphere), with backward scattering for variety.
MESH_FURNACE = SDF_FURNACE.replace('geometry = "sdf"', 'geometry = "mesh"').replace("g = 0.5", "g = -0.3")

FOGGY_EMITTER = """
[scene]
geometry = "sdf"
[camera]
position = [0.0, 0.0, 4.0]
look_at = [0.0, 0.0, 0.0]
fov = 1.0
[render]
width = 16
height = 16
max_depth = 2
[environment]
type = "constant"
color = [0.0, 0.0, 0.0]
[media.haze]
sigma_a = [0.1, 0.2, 0.4]
sigma_s = [0.0, 0.0, 0.0]
[fog]
type = "{fog}"
{fog_fields}
[materials.lamp]
type = "diffuse"
base_color = [0.0, 0.0, 0.0]
emission = [1.0, 1.0, 1.0]
[[objects]]
type = "box"
material = "lamp"
size = [2.0, 2.0, 2.0]
"""


def render(scene, integrator, spp, seed=7):
    renderer = Renderer(scene)
    camera = CameraFrame.from_spec(scene.camera)
    renderer.render(camera, spp, integrator=integrator, seed=seed)
    image = renderer.image().astype(np.float64)
    variance = renderer.film.variance_of_mean_image().astype(np.float64)
    assert renderer.film.stats()["rejected"] == 0
    return image, variance


def z_test_mean(image, variance, expected, what):
    """Image mean per channel against `expected` (3,), se from the per-pixel variances of the
    means (pixels are independent)."""
    n = image.shape[0] * image.shape[1]
    mean = image.reshape(-1, 3).mean(axis=0)
    se = np.sqrt(variance.reshape(-1, 3).sum(axis=0)) / n
    for c in range(3):
        if se[c] == 0.0:
            assert abs(mean[c] - expected[c]) < 1e-5, f"{what} channel {c}: {mean[c]} vs {expected[c]}"
            continue
        z = mean_z(image, variance, expected[c], channel=c)
        p = 2.0 * stats.norm.sf(abs(z))
        assert p >= sidak_alpha(ALPHA, NUM_TESTS), f"{what} channel {c}: {mean[c]:.5f} vs {expected[c]:.5f}, z {z:.2f}"
    return mean, se


@pytest.mark.parametrize("integrator", SLAB_CASES)
def test_absorbing_slab_transmits_exp_minus_sigma_d(tmp_path, integrator):
    """Rays cross 1 m of ink within 0.7 degrees of the normal: the path is longer than 1 m by at
    most 1 / cos(0.7 deg) - 1 = 7.5e-5, a bias of at most 1.5e-4 relative, below the test's
    resolution (se ~ 1e-3)."""
    scene = scene_from_toml(tmp_path, SLAB)
    image, variance = render(scene, integrator, 64)
    expected = np.exp(-np.array(SIGMA_A) * 1.0)
    z_test_mean(image, variance, expected, f"slab, {integrator}")


@pytest.mark.parametrize("geometry,integrator", FURNACE_CASES)
def test_albedo_one_medium_conserves_energy_in_a_white_furnace(tmp_path, geometry, integrator):
    scene = scene_from_toml(tmp_path, SDF_FURNACE if geometry == "sdf" else MESH_FURNACE)
    # Either world compiles its medium code for the cloud inside a null boundary (else the furnace
    # would be a plain sky of radiance 1 and pass whatever the medium code does).
    features = scene_features(scene)
    assert scene.geometry == geometry
    assert features.has_media and features.has_kind("null") and not features.analytic_fog
    image, variance = render(scene, integrator, 96)
    z_test_mean(image, variance, np.ones(3), f"furnace, {geometry}, {integrator}")


def test_fog_filling_the_scene_attenuates_an_emitter(tmp_path):
    """Camera 3 m from the lamp's face, in an absorbing fog: exp(-sigma_a 3) of its radiance
    (within 7.5e-5 relative path length, as for the slab)."""
    scene = scene_from_toml(tmp_path, FOGGY_EMITTER.format(fog="medium", fog_fields='medium = "haze"'))
    features = scene_features(scene)
    assert features.has_media and not features.analytic_fog
    image, variance = render(scene, "mis", 64)
    z_test_mean(image, variance, np.exp(-np.array((0.1, 0.2, 0.4)) * 3.0), "fog medium")


def test_analytic_fog_blends_to_its_colour(tmp_path):
    """Deterministic: the lamp's radiance 1 at 3 m blended towards the fog colour by
    exp(-0.25 * 3); the per-pixel spread of distances is below 1e-4 relative."""
    fields = "density = 0.25\ncolor = [0.2, 0.4, 0.8]"
    scene = scene_from_toml(tmp_path, FOGGY_EMITTER.format(fog="analytic", fog_fields=fields))
    features = scene_features(scene)
    assert features.analytic_fog and not features.has_media
    image, _ = render(scene, "mis", 4)
    keep = math.exp(-0.25 * 3.0)
    expected = np.array([0.2, 0.4, 0.8]) * (1.0 - keep) + keep
    np.testing.assert_allclose(image.reshape(-1, 3).mean(axis=0), expected, rtol=2e-4)


def test_scenes_without_media_compile_no_medium_code(tmp_path):
    scene = scene_from_toml(tmp_path, FOGGY_EMITTER.format(fog="none", fog_fields=""))
    features = scene_features(scene)
    assert not (features.has_media or features.analytic_fog or features.has_kind("null"))


@pytest.mark.parametrize("edit,message", [
    (('medium = "ink"', 'medium = "inc"'), "materials.boundary.medium: unknown medium 'inc' (known: ink)"),
    (("sigma_s = [0.0, 0.0, 0.0]", "sigma_s = [0.0, -1.0, 0.0]"), "media.ink.sigma_s"),
    (("[media.ink]", "[media.ink]\ng = 1.0"), "media.ink.g"),
])
def test_bad_media_are_one_line_errors(tmp_path, edit, message):
    with pytest.raises(SceneError) as error:
        scene_from_toml(tmp_path, SLAB.replace(*edit))
    text = str(error.value)
    assert message in text and "\n" not in text


def test_fog_needs_a_known_medium(tmp_path):
    body = FOGGY_EMITTER.format(fog="medium", fog_fields='medium = "smog"')
    with pytest.raises(SceneError) as error:
        scene_from_toml(tmp_path, body)
    assert "fog.medium: unknown medium 'smog' (known: haze)" in str(error.value)
