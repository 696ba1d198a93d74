"""Picking: the camera ray through a pixel names the scene object and material it meets first, in
the Cornell box (a mesh scene of quads) and in an SDF scene (a union under a transform)."""
from __future__ import annotations

import math
from pathlib import Path

import pytest

from renderer.camera import CameraFrame
from renderer.picking import pick
from renderer.renderer import Renderer
from renderer.scene import load_scene

REPO = Path(__file__).resolve().parents[2]


def sdf_scene(size: int, environment: str, objects: str) -> str:
    """A small SDF scene's TOML, its camera 5 m out on +z looking at the origin."""
    return (f'[scene]\ngeometry = "sdf"\n\n[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov = 40\n\n'
            f"[render]\nwidth = {size}\nheight = {size}\n\n[environment]\n{environment}\n\n{objects}")


BALL = '[materials.ball]\n\n[[objects]]\ntype = "sphere"\nmaterial = "ball"\nradius = 0.5\n'
SDF_SCENE = sdf_scene(32, 'type = "constant"\ncolor = [0, 0, 0]', BALL + """
[materials.block]
type = "conductor"

[[objects]]
type = "union"
material = "block"
translate = [1.2, 0, 0]
[[objects.children]]
type = "box"
size = [0.3, 0.3, 0.3]
[[objects.children]]
type = "sphere"
radius = 0.2
translate = [0, 0.4, 0]
""")


def screen_uv(scene, point):
    """(u, v) in [0,1]^2 (y up) where the camera sees a world point (the camera looks down -z)."""
    cam = scene.camera
    depth = cam.position[2] - point[2]
    half = math.tan(math.radians(cam.fov) / 2) * depth
    aspect = scene.render.width / scene.render.height
    return 0.5 + (point[0] - cam.position[0]) / (2 * half * aspect), 0.5 + (point[1] - cam.position[1]) / (2 * half)


@pytest.fixture(scope="module")
def cornell():
    scene = load_scene(REPO / "assets" / "scenes" / "cornell_box.toml")
    renderer = Renderer(scene, max_size=(32, 32))
    return scene, renderer, CameraFrame.from_spec(scene.camera)


def test_the_tall_box_and_the_red_wall_of_the_cornell_box(cornell):
    scene, renderer, camera = cornell
    # the tall box's front face (z = -0.28 + 0.3 at its centre, turned 18 degrees)
    got = pick(renderer, camera, *screen_uv(scene, (-0.33, -0.4, 0.0)))
    assert (got.material_name, got.material_kind) == ("tall_box", "diffuse") and got.editable
    obj = scene.mesh_objects[got.object_index]
    assert obj.kind == "quad" and obj.material == "tall_box" and got.object_label.endswith("(quad)")
    assert 3.7 < got.hit.distance < 4.3 and got.hit.front_face
    wall = pick(renderer, camera, 0.03, 0.5)
    assert wall.material_name == "red" and wall.hit.normal[0] > 0.99  # facing +x into the room
    assert math.isclose(wall.hit.point[0], -1.0, abs_tol=1e-4)
    assert "objects[" in wall.describe() and "'red' (diffuse)" in wall.describe()


def test_an_sdf_object_is_its_top_level_tree(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(SDF_SCENE)
    scene = load_scene(path)
    renderer = Renderer(scene)
    camera = CameraFrame.from_spec(scene.camera)
    ball = pick(renderer, camera, 0.5, 0.5)
    assert (ball.object_index, ball.material_name) == (0, "ball")
    assert math.isclose(ball.hit.distance, 4.5, abs_tol=2e-3) and ball.hit.normal[2] > 0.99
    # the union's second child, a sphere on top of the box: still the union, object 1
    top = pick(renderer, camera, *screen_uv(scene, (1.2, 0.55, 0.0)))
    assert (top.object_index, top.material_name, top.material_kind) == (1, "block", "conductor")
    assert top.object_label == "objects[1] (union)"
    assert pick(renderer, camera, 0.02, 0.98) is None  # nothing but the black sky
