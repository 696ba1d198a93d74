"""A large ground, seen near its middle, reflects exactly its albedo, whatever primitive it is.

Under a constant sky of radiance 1 a diffuse convex or flat surface of albedo a has radiance a
everywhere: every ray leaving it escapes to the sky. A ground's points near the camera are much
smaller than the coordinates they are computed from (a sphere's centre and radius, a quad's corner
and edges, a triangle's corners), and rays leaving them used to start inside the ground and hit
it again: the weekend scene's ground (a sphere of radius 1000 about (0, -1000, 0)) came out at
0.38 for an albedo of 0.5 and the whole weekend image 8 % dark; tilted quads and triangle pairs 2
km across at 0.47 (tests/geometry/test_large_primitive_spawn.py has the geometric tests). Here
the whole renderer sees each ground under each integrator.

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
from tests.geometry.mesh_helpers import TILT_DEGREES, tilted_square_corners
from tests.scene_builder import scene_from_toml
from tests.stats.chi2 import sidak_alpha
from tests.stats.image_tests import mean_z

ALPHA = 0.01
ALBEDO = 0.5
SPP = 64
SIZE = (48, 27)


def ground_object(kind: str, fields: str) -> str:
    return f'[[objects]]\ntype = "{kind}"\nmaterial = "ground"\n{fields}\n'


TILTED = f"rotate = {list(TILT_DEGREES)}"
GROUNDS = {
    "sphere_r1000": ground_object("sphere", "radius = 1000\ntranslate = [0.0, -1000.0, 0.0]"),
    "sphere_r10000": ground_object("sphere", "radius = 10000\ntranslate = [0.0, -10000.0, 0.0]"),
    "quad_2km_tilted": ground_object("quad", f"size = [2000, 2000]\n{TILTED}"),
    "disc_2km_tilted": ground_object("disc", f"radius = 1000\n{TILTED}"),
    "triangles_2km_tilted": ground_object("mesh", 'file = "ground.obj"'),
}
INTEGRATORS = ("path", "nee", "mis")
LEVEL = sidak_alpha(ALPHA, len(GROUNDS) * len(INTEGRATORS))

SCENE = f"""
[scene]
geometry = "mesh"
[camera]
position = [3.0, 2.0, 8.0]
look_at = [0.0, 0.0, 0.0]
fov = 40
[render]
width = {SIZE[0]}
height = {SIZE[1]}
max_depth = -1
[environment]
type = "constant"
color = [1.0, 1.0, 1.0]
[materials.ground]
type = "diffuse"
base_color = [{ALBEDO}, {ALBEDO}, {ALBEDO}]
"""


def write_tilted_square(path, size):
    """Two triangles `size` across about the origin, tilted as the quad."""
    corners = tilted_square_corners(size)
    path.write_text("".join(f"v {x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in corners) + "f 1 3 2\nf 1 4 3\n")


@pytest.fixture(scope="module", params=list(GROUNDS))
def ground(request, tmp_path_factory):
    folder = tmp_path_factory.mktemp("ground")
    write_tilted_square(folder / "ground.obj", 2000.0)
    scene = scene_from_toml(folder, SCENE + GROUNDS[request.param], name=request.param)
    return Renderer(scene, SIZE)


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_a_ground_reflects_its_albedo(ground, integrator):
    ground.reset()
    ground.render(CameraFrame.from_spec(ground.scene.camera), SPP, integrator=integrator, seed=5)
    mean, variance = ground.film.mean_image(), ground.film.variance_of_mean_image()
    assert np.isfinite(mean).all()
    # The camera looks 13 degrees down with a 40 degree field: the lower half of the image is ground.
    rows = slice(mean.shape[0] // 2, None)
    m, v = mean[rows], variance[rows]
    if v[..., 1].sum() == 0.0:  # zero-variance estimator: exact but for float32 accumulation
        assert np.abs(m[..., 1] - ALBEDO).max() <= SPP * 2.0**-24 * ALBEDO
        return
    z = mean_z(m, v, ALBEDO)
    critical = stats.norm.isf(LEVEL / 2)
    assert abs(z) < critical, f"ground mean {m[..., 1].mean():.5f} against {ALBEDO}: z = {z:.2f}"
