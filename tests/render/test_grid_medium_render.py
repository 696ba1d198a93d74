"""Grid media in the path tracers (renderer/integrators/tracer.py with renderer/media/grid.py): a grid
of constant density renders the image of the homogeneous medium with the same coefficients.

Delta tracking against a majorant equal to the density, ratio tracking on the shadow rays and the
grid's placement inside the boundary all enter the grid's image, none of the homogeneous one's.
Each pair is judged by the pixel rule of Mitsuba's render tests (tests/stats/image_tests.py) at
ALPHA = 0.01 for the pair, Sidak-corrected over the module's pairs; fixed seeds.
"""
import numpy as np
import pytest

from renderer.camera import CameraFrame
from renderer.renderer import Renderer
from renderer.scene.features import scene_features
from renderer.scene.vol_files import write_vol
from tests.scene_builder import scene_from_toml
from tests.stats.chi2 import sidak_alpha
from tests.stats.image_tests import assert_agree

ALPHA = 0.01
INTEGRATORS = ("path", "mis")
SIGMA_T = (2.0, 3.0, 4.0)
ALBEDO = (0.8, 0.5, 0.3)

SCENE = """
[scene]
geometry = "sdf"
[camera]
position = [0.0, 0.6, 3.0]
look_at = [0.0, 0.0, 0.0]
fov = 35
[render]
width = 20
height = 20
max_depth = -1
[environment]
type = "sky"
[media.cloud]
g = 0.3
{medium}
[materials.boundary]
type = "null"
medium = "cloud"
[materials.floor]
type = "diffuse"
base_color = [0.6, 0.6, 0.6]
[[objects]]
type = "box"
material = "boundary"
size = [1.2, 1.2, 1.2]
[[objects]]
type = "box"
material = "floor"
size = [4.0, 0.2, 4.0]
translate = [0.0, -0.8, 0.0]
"""
HOMOGENEOUS = "sigma_a = [{}, {}, {}]\nsigma_s = [{}, {}, {}]".format(
    *(t * (1.0 - a) for t, a in zip(SIGMA_T, ALBEDO)), *(t * a for t, a in zip(SIGMA_T, ALBEDO)))
# A 2x2x2 grid of the three extinctions, its box beyond the boundary's on every side: the medium
# fills exactly the boundary, as the homogeneous one does.
GRID = ('type = "grid"\nfile = "cloud.vol"\nscale = 2.0\nalbedo = [{}, {}, {}]\n'
        'box_min = [-0.8, -0.8, -0.8]\nbox_max = [0.8, 0.8, 0.8]').format(*ALBEDO)


def render(scene, integrator, seed):
    renderer = Renderer(scene)
    renderer.render(CameraFrame.from_spec(scene.camera), 48, integrator=integrator, seed=seed)
    assert renderer.film.stats()["rejected"] == 0
    return (renderer.image().astype(np.float64), renderer.film.variance_of_mean_image().astype(np.float64))


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_a_constant_grid_renders_as_the_homogeneous_medium(tmp_path, integrator):
    write_vol(tmp_path / "cloud.vol", np.broadcast_to(np.array(SIGMA_T, np.float32) / 2.0, (2, 2, 2, 3)))
    grid = scene_from_toml(tmp_path, SCENE.format(medium=GRID), name="grid")
    homogeneous = scene_from_toml(tmp_path, SCENE.format(medium=HOMOGENEOUS), name="homogeneous")
    assert scene_features(grid).has_grid_media and not scene_features(homogeneous).has_grid_media
    a = render(grid, integrator, seed=11)
    b = render(homogeneous, integrator, seed=12)
    assert_agree(a, b, ("grid", "homogeneous"), alpha=sidak_alpha(ALPHA, len(INTEGRATORS)))
    # The medium shows (an image without it is far from both): the agreement is not that of two skies.
    empty = scene_from_toml(tmp_path, SCENE.format(medium="sigma_s = [0.0, 0.0, 0.0]"), name="empty")
    assert abs(render(empty, integrator, seed=13)[0].mean() - a[0].mean()) > 0.05
