"""Orthographic cameras in whole renders: parallel rays from the view's plane, in mesh and SDF scenes,
and the viewer's focus probe along them.

The answers here do not depend on the random samples: each pixel's footprint lies wholly on or off the
quad, and a plane facing the camera lies at one distance along every parallel ray."""
import numpy as np

from renderer.camera import CameraFrame
from renderer.renderer import Renderer
from renderer.scene.toml_loader import load_scene

CAMERA = """
[camera]
position = [0.0, 0.0, 5.0]
look_at = [0.0, 0.0, 0.0]
projection = "orthographic"
ortho_height = 2.0
[render]
width = 16
height = 16
[environment]
type = "constant"
color = [0.0, 0.0, 0.0]
[materials.grey]
type = "diffuse"
"""

# A 1 m quad facing the camera over x, y in [0, 1]: the view's top-right quarter.
QUAD_SCENE = '[scene]\ngeometry = "mesh"\n' + CAMERA + """
[[objects]]
type = "quad"
material = "grey"
size = [1.0, 1.0]
rotate = [90.0, 0.0, 0.0]
translate = [0.5, 0.5, 0.0]
"""

PLANE_SCENE = '[scene]\ngeometry = "sdf"\n' + CAMERA + """
[[objects]]
type = "plane"
material = "grey"
normal = [0.0, 0.0, 1.0]
offset = 0.0
"""


def load(tmp_path, text):
    path = tmp_path / "scene.toml"
    path.write_text(text)
    return load_scene(path)


def depth_image(scene, spp=4):
    renderer = Renderer(scene)
    renderer.render(CameraFrame.from_spec(scene.camera), spp, integrator="depth")
    return renderer, renderer.film.mean_image()[..., 0]


def test_orthographic_view_covers_its_height_with_parallel_rays(tmp_path):
    scene = load(tmp_path, QUAD_SCENE)
    assert scene.camera.projection == "orthographic"
    renderer, depth = depth_image(scene)
    quarter = np.zeros((16, 16), bool)
    quarter[:8, 8:] = True  # rows from the top: the top-right quarter
    assert np.allclose(depth[quarter], 5.0, atol=1e-4)  # every ray meets the quad 5 m along
    assert np.all(depth[~quarter] == 0.0)  # a perspective camera would see the quad in fewer pixels
    camera = CameraFrame.from_spec(scene.camera)
    assert abs(renderer.focus_distance_at(camera, 0.9, 0.9) - 5.0) < 1e-4  # the probe's ray is parallel too
    assert renderer.focus_distance_at(camera, 0.1, 0.1) is None


def test_sdf_scenes_march_parallel_rays(tmp_path):
    _, depth = depth_image(load(tmp_path, PLANE_SCENE))
    # The marcher stops within its hit threshold (a pixel's footprint, 1/8 m) of the plane; a
    # perspective camera's corner rays would travel 5 / cos(angle) > 5.2 m.
    assert np.all(depth <= 5.0 + 1e-4) and np.all(depth >= 5.0 - 2.0 / 16)
    assert np.ptp(depth) < 2.0 / 16
