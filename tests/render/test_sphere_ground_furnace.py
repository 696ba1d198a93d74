"""A ground made of a huge analytic sphere, as in the weekend scene, reflects exactly its albedo.

Under a constant sky of radiance 1 a diffuse convex surface of albedo a has radiance a everywhere:
every ray leaving it escapes to the sky. The weekend scene's ground is a sphere of radius 1000
about (0, -1000, 0); its points near y = 0 round at the sphere's scale, not their own, and a
quarter of the rays leaving it used to start inside it and hit it again (the ground, and the whole
image, came out 8 % dark; tests/geometry/test_sphere_spawn.py has the geometric test). Here the
whole renderer sees it: the pixels of the ground, each integrator.

Decision rule: the mean of the green channel over the ground's pixels against a, by a z-test with
the film's per-pixel variance of the mean (pixels independent), at ALPHA = 0.01 Sidak-corrected
over the cases. Under `path` every sample is exactly a (cosine sampling: weight = albedo), so the
variance is zero and the test asks for a to the rounding of the film's float32 sums.
"""
import numpy as np
import pytest
from scipy import stats

from renderer.camera import CameraFrame
from renderer.renderer import Renderer
from tests.scene_builder import scene_from_toml
from tests.stats.chi2 import sidak_alpha
from tests.stats.image_tests import mean_z

ALPHA = 0.01
ALBEDO = 0.5
SPP = 64
RADII = (1000.0, 1e4)
INTEGRATORS = ("path", "nee", "mis")
LEVEL = sidak_alpha(ALPHA, len(RADII) * len(INTEGRATORS))

SCENE = """
[scene]
geometry = "mesh"
[camera]
position = [3.0, 2.0, 8.0]
look_at = [0.0, 0.0, 0.0]
fov = 40
[render]
width = 48
height = 27
max_depth = -1
[environment]
type = "constant"
color = [1.0, 1.0, 1.0]
[materials.ground]
type = "diffuse"
base_color = [{albedo}, {albedo}, {albedo}]
[[objects]]
type = "sphere"
material = "ground"
radius = {radius}
translate = [0.0, {centre_y}, 0.0]
"""


@pytest.fixture(scope="module", params=RADII, ids=lambda r: f"radius{r:g}")
def ground(request, tmp_path_factory):
    radius = request.param
    scene = scene_from_toml(tmp_path_factory.mktemp("ground"),
                            SCENE.format(albedo=ALBEDO, radius=radius, centre_y=-radius), name="sphere_ground")
    return Renderer(scene, (48, 27))


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_a_sphere_ground_reflects_its_albedo(ground, integrator):
    ground.reset()
    ground.render(CameraFrame.from_spec(ground.scene.camera), SPP, integrator=integrator, seed=5)
    mean, variance = ground.film.mean_image(), ground.film.variance_of_mean_image()
    assert np.isfinite(mean).all()
    # The camera looks 14 degrees down with a 40 degree field: the lower half of the image is ground.
    rows = slice(mean.shape[0] // 2, None)
    m, v = mean[rows], variance[rows]
    if v[..., 1].sum() == 0.0:  # zero-variance estimator: exact but for float32 accumulation
        assert np.abs(m[..., 1] - ALBEDO).max() <= SPP * 2.0**-24 * ALBEDO
        return
    z = mean_z(m, v, ALBEDO)
    critical = stats.norm.isf(LEVEL / 2)
    assert abs(z) < critical, f"ground mean {m[..., 1].mean():.5f} against {ALBEDO}: z = {z:.2f}"
