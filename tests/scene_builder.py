"""Small scene files for tests, written next to the test's tmp_path."""
from pathlib import Path
from textwrap import dedent

from renderer.scene import load_scene


def scene_from_toml(tmp_path: Path, body: str, name: str = "test_scene"):
    path = tmp_path / f"{name}.toml"
    path.write_text(dedent(body))
    return load_scene(path)


FURNACE = """
[scene]
geometry = "sdf"
[camera]
position = [0.0, 1.5, 3.0]
look_at = [0.0, 0.4, 0.0]
fov = 50
[render]
width = 24
height = 16
max_depth = {max_depth}
[environment]
type = "constant"
color = [{env}, {env}, {env}]
[materials.white]
type = "diffuse"
base_color = [{albedo}, {albedo}, {albedo}]
[materials.ball]
type = "{ball_kind}"
base_color = [1.0, 1.0, 1.0]
roughness = 0.0
ior = 1.5
{floor}[[objects]]
type = "sphere"
material = "ball"
radius = 0.5
translate = [0.0, 0.5, 0.0]
"""


FLOOR = """[[objects]]
type = "plane"
material = "white"
"""


def furnace_toml(env=0.5, albedo=1.0, max_depth=-1, ball_kind="diffuse", floor=True):
    """A ball (optionally on a floor) under a constant sky. Without the floor, the ball alone is
    convex: no path is ever trapped, so no estimate depends on rare, heavy Russian-roulette
    survivors (whose weights make small-sample variance estimates unreliable)."""
    body = FURNACE.format(env=env, albedo=albedo, max_depth=max_depth, ball_kind=ball_kind,
                          floor=FLOOR if floor else "")
    if ball_kind != "dielectric":
        body = body.replace("ior = 1.5\n", "")
    return body


CAVITY_HEADER = """
[scene]
geometry = "{geometry}"
[camera]
position = [0.2, 0.1, 0.3]
look_at = [0.0, 0.0, -1.0]
fov = 70
[render]
width = 16
height = 12
max_depth = -1
[environment]
type = "constant"
color = [0.0, 0.0, 0.0]
[materials.wall]
type = "diffuse"
base_color = [{albedo}, {albedo}, {albedo}]
emission = [{emission}, {emission}, {emission}]
"""

CAVITY = CAVITY_HEADER.replace("{geometry}", "sdf") + """[[objects]]
type = "subtraction"
material = "wall"
[[objects.children]]
type = "box"
size = [4.0, 4.0, 4.0]
[[objects.children]]
type = "sphere"
radius = 1.0
"""

MESH_CAVITY = CAVITY_HEADER.replace("{geometry}", "mesh") + """[[objects]]
type = "mesh"
file = "{obj}"
material = "wall"
"""


def cavity_toml(albedo=0.5, emission=0.5):
    """pbrt's analytic test: inside a closed diffuse sphere of albedo a emitting Le, the radiance
    is Le / (1 - a) everywhere (the series Le (1 + a + a^2 + ...)). The cavity is a box minus a
    sphere, so the wall's outward normal faces the inside and its emission is seen."""
    return CAVITY.format(albedo=albedo, emission=emission)


TINY_BENCH = """
[scene]
name = "{name}"
geometry = "sdf"
[camera]
position = [0.0, 1.0, 3.0]
look_at = [0.0, 0.4, 0.0]
fov = 50
[render]
width = {width}
height = {height}
max_depth = 3
[environment]
type = "sky"
[materials.white]
type = "diffuse"
{extra_materials}[[objects]]
type = "plane"
material = "white"
[[objects]]
type = "sphere"
material = "{ball}"
radius = 0.5
translate = [0.0, 0.5, 0.0]
"""


def tiny_bench_toml(name: str, width: int = 32, height: int = 18, glass_ball: bool = False) -> str:
    """A white ball on a white plane under a sky (the ball glass if asked): the benchmarks' smoke
    tests render it in a fraction of a second."""
    extra = '[materials.glass]\ntype = "dielectric"\nroughness = 0.0\n' if glass_ball else ""
    return TINY_BENCH.format(name=name, width=width, height=height, extra_materials=extra,
                             ball="glass" if glass_ball else "white")
