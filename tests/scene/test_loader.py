"""Tests for the TOML scene loader, its schema and the generated format documentation."""
from __future__ import annotations

import dataclasses
import math
import pickle
from pathlib import Path

import numpy as np
import pytest

from renderer.scene import (
    ENVIRONMENT_KINDS,
    GEOMETRY_KINDS,
    MATERIAL_KINDS,
    SDF_OPERATORS,
    SDF_PRIMITIVES,
    CameraSpec,
    EnvironmentSpec,
    MarchSettings,
    MaterialSpec,
    RenderSettings,
    Scene,
    SceneError,
    SdfNode,
    Transform,
    load_scene,
)
from renderer.scene import schema
from renderer.scene.model_formats import MESH_EXTENSIONS
from renderer.scene.description import MESH_GENERATORS, MESH_OBJECT_KINDS, MeshObject

REPO = Path(__file__).resolve().parents[2]

HEADER = '[scene]\ngeometry = "sdf"\n'
MATERIAL = "[materials.m]\n"
SPHERE = '[[objects]]\ntype = "sphere"\nmaterial = "m"\n'


def scene_text(extra: str = "", objects: str = SPHERE, materials: str = MATERIAL,
               header: str = HEADER) -> str:
    """A valid minimal scene with `extra` sections inserted (TOML forbids redefining tables)."""
    return header + extra + "\n" + materials + "\n" + objects


def write(tmp_path: Path, text: str, name: str = "scene.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def load_error(path) -> str:
    """Load a bad scene and check the message contract: one line, starting with the path."""
    with pytest.raises(SceneError) as info:
        load_scene(path)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{path}: ")
    return message


def node(kind: str, params=(), children=(), material=None, transform=Transform()) -> SdfNode:
    return SdfNode(kind=kind, params=tuple(sorted(params)), children=tuple(children),
                   transform=transform, material=material)


# --- valid scenes ----------------------------------------------------------------------------

FULL_SCENE = """
[scene]
name = "full"
description = "every section"
geometry = "sdf"

[camera]
position = [1, 2, 3]
look_at = [0, 0.5, 0]
up = [0, 1, 0]
fov = 30
aperture = 0.05
focus_distance = 3.5

[render]
width = 320
height = 200
spp = 16
max_depth = -1
integrator = "direct"
seed = 42

[render.march]
hit_threshold = 0.5
min_threshold = 1e-5
max_steps = 512
max_distance = 50
over_relaxation = 1.2

[environment]
type = "map"
file = "../envmaps/park.hdr"
intensity = 2
rotation = -90

[materials.gold]
type = "conductor"
base_color = [1.0, 0.78, 0.34]
roughness = 0.2

[materials.glass]
type = "dielectric"
base_color = [1, 1, 1]
roughness = 0
ior = 1.33

[materials.lamp]
emission = [1, 0.5, 0.25]
emission_strength = 4

[materials.unused]

[[objects]]
type = "sphere"
material = "gold"
radius = 0.75
translate = [0, 0.5, 0]
rotate = [0, 45, 0]
scale = [2, 2, 2]

[[objects]]
type = "smooth_union"
material = "glass"
k = 0.2
[[objects.children]]
type = "box"
size = [1, 2, 3]
[[objects.children]]
type = "subtraction"
scale = 0.5
[[objects.children.children]]
type = "rounded_box"
[[objects.children.children]]
type = "cylinder"
height = 2
[[objects.children.children]]
type = "capsule"
radius = 0.1

[[objects]]
type = "repeat"
material = "lamp"
period = [2, 0, 2]
limit = [3, 0, 1]
[[objects.children]]
type = "union"
[[objects.children.children]]
type = "torus"
[[objects.children.children]]
type = "cone"
translate = [0, 1, 0]

[[objects]]
type = "intersection"
material = "gold"
[[objects.children]]
type = "repeat"
[[objects.children.children]]
type = "sphere"
[[objects.children]]
type = "plane"
normal = [0, 0, 2]
offset = -1.5
"""


def test_full_scene_round_trips(tmp_path):
    (tmp_path / "envmaps").mkdir()
    (tmp_path / "envmaps" / "park.hdr").write_bytes(b"")
    (tmp_path / "scenes").mkdir()
    path = write(tmp_path / "scenes", FULL_SCENE, "full.toml")

    scene = load_scene(path)

    unit = Transform()
    expected = Scene(
        name="full",
        path=path,
        geometry="sdf",
        description="every section",
        camera=CameraSpec((1.0, 2.0, 3.0), (0.0, 0.5, 0.0), (0.0, 1.0, 0.0), 30.0, 0.05, 3.5),
        render=RenderSettings(320, 200, 16, -1, "direct", 42,
                              MarchSettings(0.5, 1e-5, 512, 50.0, 1.2)),
        environment=EnvironmentSpec(kind="map", file=(tmp_path / "envmaps" / "park.hdr").resolve(),
                                    intensity=2.0, rotation=-90.0),
        materials=(
            MaterialSpec("gold", "conductor", (1.0, 0.78, 0.34), 0.2),
            MaterialSpec("glass", "dielectric", (1.0, 1.0, 1.0), 0.0, 1.33),
            MaterialSpec("lamp", emission=(4.0, 2.0, 1.0)),
            MaterialSpec("unused"),
        ),
        sdf_objects=(
            node("sphere", [("radius", 0.75)], material="gold",
                 transform=Transform((0.0, 0.5, 0.0), (0.0, 45.0, 0.0), 2.0)),
            node("smooth_union", [("k", 0.2)], material="glass", children=[
                node("box", [("size", (1.0, 2.0, 3.0))]),
                node("subtraction", transform=Transform(scale=0.5), children=[
                    node("rounded_box", [("size", (1.0, 1.0, 1.0)), ("radius", 0.1)]),
                    node("cylinder", [("height", 2.0), ("radius", 0.5)]),
                    node("capsule", [("height", 1.0), ("radius", 0.1)]),
                ]),
            ]),
            node("repeat", [("period", (2.0, 0.0, 2.0)), ("limit", (3, 0, 1))], material="lamp",
                 children=[node("union", children=[
                     node("torus", [("major_radius", 0.5), ("minor_radius", 0.15)]),
                     node("cone", [("height", 1.0), ("radius", 0.5)],
                          transform=Transform(translate=(0.0, 1.0, 0.0))),
                 ])]),
            node("intersection", material="gold", children=[
                node("repeat", [("period", (1.0, 1.0, 1.0)), ("limit", None)],
                     children=[node("sphere", [("radius", 0.5)])]),
                node("plane", [("normal", (0.0, 0.0, 1.0)), ("offset", -1.5)]),
            ]),
        ),
    )
    assert scene == expected
    assert scene.sdf_objects[0].transform != unit
    # Types matter to the renderer: ints stay ints, everything else is float.
    assert isinstance(scene.render.march.max_steps, int)
    assert all(type(c) is float for c in scene.camera.position)
    assert all(type(c) is int for c in scene.sdf_objects[2].param("limit"))


def test_minimal_scene_gets_model_defaults(tmp_path):
    path = write(tmp_path, scene_text(), "my_scene.toml")
    scene = load_scene(path)
    assert scene.name == "my_scene"
    assert scene.description == ""
    assert scene.path == path
    assert scene.camera == CameraSpec()
    assert scene.render == RenderSettings()
    assert scene.environment == EnvironmentSpec()
    assert scene.materials == (MaterialSpec("m"),)
    assert scene.sdf_objects == (node("sphere", [("radius", 0.5)], material="m"),)


def test_accepts_str_path_and_relative_path(tmp_path, monkeypatch):
    write(tmp_path, scene_text())
    monkeypatch.chdir(tmp_path)
    assert load_scene("scene.toml").name == "scene"
    assert load_scene(str(tmp_path / "scene.toml")).name == "scene"


def test_env_map_relative_to_scene_folder_not_cwd(tmp_path, monkeypatch):
    (tmp_path / "scenes").mkdir()
    (tmp_path / "scenes" / "sky.exr").write_bytes(b"")
    path = write(tmp_path / "scenes", scene_text('[environment]\ntype = "map"\nfile = "sky.exr"\n'))
    monkeypatch.chdir(tmp_path)  # the map is not in the working directory
    scene = load_scene(Path("scenes") / "scene.toml")
    assert scene.environment.file == (tmp_path / "scenes" / "sky.exr").resolve()
    assert scene.environment.file.is_absolute()


def test_env_map_absolute_path_and_upper_case_extension(tmp_path):
    env = tmp_path / "maps" / "Studio.EXR"
    env.parent.mkdir()
    env.write_bytes(b"")
    path = write(tmp_path, scene_text(f'[environment]\ntype = "map"\nfile = "{env}"\n'))
    assert load_scene(path).environment.file == env.resolve()


def test_constant_and_sky_environments(tmp_path):
    constant = write(tmp_path, scene_text('[environment]\ntype = "constant"\ncolor = [2, 1, 0]\n'), "a.toml")
    env = load_scene(constant).environment
    assert (env.kind, env.color, env.file) == ("constant", (2.0, 1.0, 0.0), None)

    sky = write(tmp_path, scene_text("[environment]\nzenith = [0, 0, 1]\nground = [0.1, 0.1, 0.1]\n"), "b.toml")
    env = load_scene(sky).environment
    assert (env.kind, env.zenith, env.ground, env.horizon) == (
        "sky", (0.0, 0.0, 1.0), (0.1, 0.1, 0.1), EnvironmentSpec().horizon)


def test_plane_normal_is_normalised(tmp_path):
    objects = '[[objects]]\ntype = "plane"\nmaterial = "m"\nnormal = [1, 1, 0]\n'
    normal = load_scene(write(tmp_path, scene_text(objects=objects))).sdf_objects[0].param("normal")
    assert normal == pytest.approx((math.sqrt(0.5), math.sqrt(0.5), 0.0))


def test_emission_strength_is_folded_into_emission(tmp_path):
    materials = "[materials.m]\nemission = [1, 2, 3]\nemission_strength = 0.5\n"
    material = load_scene(write(tmp_path, scene_text(materials=materials))).materials[0]
    assert material.emission == (0.5, 1.0, 1.5)
    assert material.is_emissive


def test_byte_order_mark_is_tolerated(tmp_path):
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + scene_text().encode())
    assert load_scene(path).geometry == "sdf"


def test_documented_example_loads(tmp_path):
    (tmp_path / "envmaps").mkdir()
    (tmp_path / "envmaps" / "park.exr").write_bytes(b"")
    (tmp_path / "scenes").mkdir()
    scene = load_scene(write(tmp_path / "scenes", schema.EXAMPLE))
    assert scene.name == "showcase"
    assert {n.kind for o in scene.sdf_objects for n in o.walk()} >= {"sphere", "repeat", "plane"}


# --- file-level errors -----------------------------------------------------------------------


def test_missing_file(tmp_path):
    assert load_error(tmp_path / "nope.toml").endswith(": file not found")


def test_directory_instead_of_file(tmp_path):
    folder = tmp_path / "scene.toml"
    folder.mkdir()
    assert "is a directory" in load_error(folder)


@pytest.mark.parametrize("name, expected", [
    ("scene.json", "unsupported scene extension '.json' (expected .toml)"),
    ("scene", "unsupported scene file without an extension"),
])
def test_unsupported_scene_extension(tmp_path, name, expected):
    assert expected in load_error(write(tmp_path, scene_text(), name))


def test_malformed_toml_reports_line(tmp_path):
    message = load_error(write(tmp_path, '[scene]\ngeometry = "sdf"\nname = \n'))
    assert "invalid TOML" in message
    assert "line 3" in message


def test_duplicate_table_is_malformed(tmp_path):
    assert "invalid TOML" in load_error(write(tmp_path, scene_text(extra="[scene]\n")))


def test_not_utf8(tmp_path):
    path = tmp_path / "latin1.toml"
    path.write_bytes(scene_text().encode() + b'\n# caf\xe9\n')
    assert "not UTF-8" in load_error(path)


def test_error_shows_the_path_as_given(tmp_path, monkeypatch):
    write(tmp_path, scene_text(extra="[camera]\nfov = 0\n"))
    monkeypatch.chdir(tmp_path)
    assert load_error("scene.toml").startswith("scene.toml: camera.fov: ")


# --- validation errors -----------------------------------------------------------------------

OBJ = '[[objects]]\nmaterial = "m"\n'

BAD_SCENES = {
    # sections and the [scene] header
    "unknown section": (scene_text(extra="[camra]\nfov = 3\n"),
                        "unknown section 'camra' (allowed: scene, camera, render, environment, materials, media, fog, objects)"),
    "no scene section": ("[materials.m]\n" + SPHERE, "missing [scene] section"),
    "scene not a table": ("scene = 3\n" + MATERIAL + SPHERE, "scene: expected a table, got integer 3"),
    "no geometry": (scene_text(header='[scene]\nname = "x"\n'), "scene: missing required field 'geometry'"),
    "unknown geometry": (scene_text(header='[scene]\ngeometry = "voxels"\n'),
                         "scene.geometry: unknown value 'voxels' (allowed: sdf, mesh)"),
    "unknown scene field": (scene_text(header='[scene]\ngeometry = "sdf"\ntitle = "x"\n'),
                            "scene: unknown field 'title' (allowed: name, description, geometry)"),
    "name not a string": (scene_text(header='[scene]\ngeometry = "sdf"\nname = 3\n'),
                          "scene.name: expected a string, got integer 3"),
    # camera: types, vectors, ranges, non-finite numbers
    "fov too small": (scene_text(extra="[camera]\nfov = 0.5\n"), "camera.fov: 0.5 is out of range (allowed: [1, 179])"),
    "fov too large": (scene_text(extra="[camera]\nfov = 180\n"), "camera.fov: 180 is out of range"),
    "fov bool": (scene_text(extra="[camera]\nfov = true\n"), "camera.fov: expected a number, got boolean true"),
    "fov string": (scene_text(extra='[camera]\nfov = "wide"\n'), "camera.fov: expected a number, got string 'wide'"),
    "fov nan": (scene_text(extra="[camera]\nfov = nan\n"), "camera.fov: nan is not a finite number"),
    "aperture negative": (scene_text(extra="[camera]\naperture = -0.1\n"), "camera.aperture: -0.1 is out of range (allowed: >= 0)"),
    "focus zero": (scene_text(extra="[camera]\nfocus_distance = 0\n"), "camera.focus_distance: 0 is out of range (allowed: > 0)"),
    "vector too short": (scene_text(extra="[camera]\nposition = [0, 1]\n"), "camera.position: expected 3 numbers, got 2"),
    "vector too long": (scene_text(extra="[camera]\nup = [0, 1, 0, 0]\n"), "camera.up: expected 3 numbers, got 4"),
    "vector not array": (scene_text(extra="[camera]\nup = 1\n"), "camera.up: expected an array of 3 numbers, got integer 1"),
    "vector inf": (scene_text(extra="[camera]\nposition = [0, inf, 5]\n"), "camera.position[1]: inf is not a finite number"),
    "vector -inf": (scene_text(extra="[camera]\nlook_at = [-inf, 0, 0]\n"), "camera.look_at[0]: -inf is not a finite number"),
    "vector bool": (scene_text(extra="[camera]\nposition = [0, false, 5]\n"), "camera.position[1]: expected a number, got boolean false"),
    "vector nested": (scene_text(extra="[camera]\nposition = [0, [1], 5]\n"), "camera.position[1]: expected a number, got array"),
    "camera degenerate": (scene_text(extra="[camera]\nposition = [1, 1, 1]\nlook_at = [1, 1, 1]\n"),
                          "camera: position and look_at are the same point"),
    "camera up parallel": (scene_text(extra="[camera]\nposition = [0, 5, 0]\nlook_at = [0, 0, 0]\n"),
                           "camera: up is zero or parallel to the view direction"),
    "camera unknown field": (scene_text(extra="[camera]\nfovy = 30\n"),
                             "camera: unknown field 'fovy' (allowed: position, look_at, up, fov, aperture, focus_distance)"),
    "date instead of number": (scene_text(extra="[camera]\nfov = 1979-05-27\n"), "camera.fov: expected a number, got date/time"),
    # render
    "width zero": (scene_text(extra="[render]\nwidth = 0\n"), "render.width: 0 is out of range (allowed: [1, 16384])"),
    "width float": (scene_text(extra="[render]\nwidth = 640.0\n"), "render.width: expected an integer, got float 640.0"),
    "spp bool": (scene_text(extra="[render]\nspp = true\n"), "render.spp: expected an integer, got boolean true"),
    "max_depth zero": (scene_text(extra="[render]\nmax_depth = 0\n"), "render.max_depth: 0 is out of range (allowed: -1 or >= 1)"),
    "max_depth -2": (scene_text(extra="[render]\nmax_depth = -2\n"), "render.max_depth: -2 is out of range"),
    "seed negative": (scene_text(extra="[render]\nseed = -1\n"), "render.seed: -1 is out of range"),
    "integrator number": (scene_text(extra="[render]\nintegrator = 3\n"), "render.integrator: expected a string, got integer 3"),
    "render unknown field": (scene_text(extra="[render]\nsamples = 3\n"), "render: unknown field 'samples' (allowed: width, height, spp, max_depth, integrator, seed, sampler, energy_compensation, march)"),
    "march not table": (scene_text(extra="[render]\nmarch = 3\n"), "render.march: expected a table, got integer 3"),
    "over_relaxation 4": (scene_text(extra="[render.march]\nover_relaxation = 4.0\n"), "render.march.over_relaxation: 4 is out of range (allowed: [1, 4))"),
    "fixed over_relaxation 2": (scene_text(extra="[render.march]\nover_relaxation = 2.0\nadaptive = false\n"),
                                "render.march: over_relaxation 2 needs adaptive = true"),
    "over_relaxation below 1": (scene_text(extra="[render.march]\nover_relaxation = 0.9\n"), "render.march.over_relaxation: 0.9 is out of range"),
    "max_steps zero": (scene_text(extra="[render.march]\nmax_steps = 0\n"), "render.march.max_steps: 0 is out of range"),
    "hit_threshold zero": (scene_text(extra="[render.march]\nhit_threshold = 0\n"), "render.march.hit_threshold: 0 is out of range (allowed: > 0)"),
    "min_threshold negative": (scene_text(extra="[render.march]\nmin_threshold = -1e-4\n"), "render.march.min_threshold: -0.0001 is out of range"),
    "max_distance inf": (scene_text(extra="[render.march]\nmax_distance = inf\n"), "render.march.max_distance: inf is not a finite number"),
    "march unknown field": (scene_text(extra="[render.march]\nepsilon = 1\n"), "render.march: unknown field 'epsilon' (allowed: hit_threshold,"),
    # environment
    "env unknown type": (scene_text(extra='[environment]\ntype = "hdri"\n'), "environment.type: unknown value 'hdri' (allowed: map, sky, constant)"),
    "env file on sky": (scene_text(extra='[environment]\ntype = "sky"\nfile = "a.exr"\n'), "environment.file: only allowed with type 'map', not 'sky'"),
    "env file on default sky": (scene_text(extra='[environment]\nfile = "a.exr"\n'), "environment.file: only allowed with type 'map', not 'sky'"),
    "env color on sky": (scene_text(extra="[environment]\ncolor = [1, 1, 1]\n"), "environment.color: only allowed with type 'constant', not 'sky'"),
    "env zenith on map": (scene_text(extra='[environment]\ntype = "map"\nfile = "a.exr"\nzenith = [1, 1, 1]\n'),
                          "environment.zenith: only allowed with type 'sky', not 'map'"),
    "env map without file": (scene_text(extra='[environment]\ntype = "map"\n'), "environment: missing required field 'file'"),
    "env map png": (scene_text(extra='[environment]\ntype = "map"\nfile = "sky.png"\n'),
                    "environment.file: unsupported environment map extension '.png' (expected .exr or .hdr)"),
    "env map no extension": (scene_text(extra='[environment]\ntype = "map"\nfile = "sky"\n'),
                             "environment.file: unsupported environment map file without an extension"),
    "env map missing": (scene_text(extra='[environment]\ntype = "map"\nfile = "../envmaps/nope.exr"\n'),
                        "environment: missing map file ../envmaps/nope.exr"),
    "env intensity negative": (scene_text(extra="[environment]\nintensity = -1\n"), "environment.intensity: -1 is out of range (allowed: >= 0)"),
    "env colour negative": (scene_text(extra="[environment]\nhorizon = [1, -0.5, 1]\n"), "environment.horizon[1]: -0.5 is out of range (allowed: >= 0)"),
    "env unknown field": (scene_text(extra="[environment]\nstrength = 1\n"),
                          "environment: unknown field 'strength' (allowed: type, intensity, rotation, zenith, horizon, ground)"),
    # materials
    "material unknown field": (scene_text(materials="[materials.glass]\ntype = \"dielectric\"\niorr = 1.5\n"),
                               "materials.glass: unknown field 'iorr' (allowed: type, base_color, roughness, ior, thin, emission, emission_strength, abbe, glass, medium)"),
    "material unknown type": (scene_text(materials='[materials.m]\ntype = "metal"\n'),
                              "materials.m.type: unknown value 'metal' (allowed: diffuse, conductor, dielectric, principled, null)"),
    "ior on conductor": (scene_text(materials='[materials.m]\ntype = "conductor"\nior = 1.5\n'),
                         "materials.m.ior: only allowed with type 'dielectric' or 'principled', not 'conductor'"),
    "ior on default diffuse": (scene_text(materials="[materials.m]\nior = 1.5\n"),
                               "materials.m.ior: only allowed with type 'dielectric' or 'principled', not 'diffuse'"),
    "metallic on diffuse": (scene_text(materials="[materials.m]\nmetallic = 1\n"),
                            "materials.m.metallic: only allowed with type 'principled', not 'diffuse'"),
    "transmission on dielectric": (scene_text(materials='[materials.m]\ntype = "dielectric"\ntransmission = 1\n'),
                                   "materials.m.transmission: only allowed with type 'principled', not 'dielectric'"),
    "metallic above 1": (scene_text(materials='[materials.m]\ntype = "principled"\nmetallic = 1.5\n'),
                         "materials.m.metallic: 1.5 is out of range (allowed: [0, 1])"),
    "transmission negative": (scene_text(materials='[materials.m]\ntype = "principled"\ntransmission = -0.1\n'),
                              "materials.m.transmission: -0.1 is out of range (allowed: [0, 1])"),
    "principled unknown field": (scene_text(materials='[materials.m]\ntype = "principled"\nspeculr = 0.5\n'),
                                 "materials.m: unknown field 'speculr' (allowed: type, base_color, metallic, roughness, transmission, ior,"),
    "ior 1": (scene_text(materials='[materials.m]\ntype = "dielectric"\nior = 1.0\n'), "materials.m.ior: 1 is out of range (allowed: (1, 4])"),
    "ior 5": (scene_text(materials='[materials.m]\ntype = "dielectric"\nior = 5\n'), "materials.m.ior: 5 is out of range"),
    "base_color above 1": (scene_text(materials="[materials.m]\nbase_color = [0.5, 0.5, 1.2]\n"),
                           "materials.m.base_color[2]: 1.2 is out of range (allowed: [0, 1])"),
    "roughness above 1": (scene_text(materials="[materials.m]\nroughness = 2\n"), "materials.m.roughness: 2 is out of range"),
    "emission negative": (scene_text(materials="[materials.m]\nemission = [-1, 0, 0]\n"), "materials.m.emission[0]: -1 is out of range (allowed: >= 0)"),
    "emission strength negative": (scene_text(materials="[materials.m]\nemission_strength = -2\n"), "materials.m.emission_strength: -2 is out of range"),
    "emission overflow": (scene_text(materials="[materials.m]\nemission = [1e300, 0, 0]\nemission_strength = 1e300\n"),
                          "materials.m.emission[0]: 1e+300 is beyond the 32-bit float range"),
    "emission strength beyond f32": (scene_text(materials="[materials.m]\nemission = [1, 1, 1]\nemission_strength = 1e39\n"),
                                     "materials.m.emission_strength: 1e+39 is beyond the 32-bit float range"),
    "folded emission beyond f32": (scene_text(materials="[materials.m]\nemission = [1e20, 0, 0]\nemission_strength = 1e20\n"),
                                   "materials.m: emission * emission_strength = 1e+40 is beyond the 32-bit float range"),
    "radius beyond f32": (scene_text(objects=OBJ + 'type = "sphere"\nradius = 1e39\n'),
                          "objects[0].radius: 1e+39 is beyond the 32-bit float range"),
    "width beyond the film limit": (scene_text(extra="[render]\nwidth = 100000\n"),
                                    "render.width: 100000 is out of range (allowed: [1, 16384])"),
    "material not a table": (scene_text(materials="[materials]\nm = 3\n"), "materials.m: expected a table, got integer 3"),
    "materials not a table": ("materials = 3\n" + HEADER + SPHERE, "materials: expected a table, got integer 3"),
    # objects: structure
    "no objects": (scene_text(objects=""), "objects: the scene has no objects"),
    "empty objects array": ("objects = []\n" + HEADER + MATERIAL, "objects: the scene has no objects"),
    "objects as table": (scene_text(objects='[objects]\ntype = "sphere"\n'), "objects: expected an array of tables, got table"),
    "object not a table": ("objects = [1]\n" + HEADER + MATERIAL, "objects[0]: expected a table, got integer 1"),
    "object without type": (scene_text(objects=OBJ), "objects[0]: missing required field 'type'"),
    "object type not string": (scene_text(objects=OBJ + "type = 1\n"), "objects[0].type: expected a string, got integer 1"),
    "unknown primitive in child": (
        scene_text(objects=SPHERE + OBJ + 'type = "union"\n[[objects.children]]\ntype = "box"\n[[objects.children]]\ntype = "sphre"\n'),
        "objects[1].children[1]: unknown primitive 'sphre' (known: sphere, box, rounded_box, torus, capsule, cylinder, cone, plane; operators: union,"),
    "unknown object field": (scene_text(objects=SPHERE + "radius = 1\ncolour = 3\n"),
                             "objects[0]: unknown field 'colour' (allowed: type, material, translate, rotate, scale, radius)"),
    "param of another primitive": (scene_text(objects=SPHERE + "size = [1, 1, 1]\n"), "objects[0]: unknown field 'size'"),
    "unknown material": (scene_text(materials="[materials.gold]\n[materials.floor]\n",
                                    objects=('[[objects]]\ntype = "sphere"\nmaterial = "gold"\n' * 2)
                                    + '[[objects]]\ntype = "sphere"\nmaterial = "golde"\n'),
                         "unknown material 'golde' in objects[2] (known: gold, floor)"),
    "no materials defined": (scene_text(materials=""), "unknown material 'm' in objects[0] (no materials are defined)"),
    "missing material": (scene_text(objects='[[objects]]\ntype = "sphere"\n'), "objects[0]: missing required field 'material'"),
    "material on child": (
        scene_text(objects=OBJ + 'type = "repeat"\n[[objects.children]]\ntype = "box"\nmaterial = "m"\n'),
        "objects[0].children[0]: 'material' is only allowed on top-level objects"),
    "children on primitive": (scene_text(objects=SPHERE + '[[objects.children]]\ntype = "box"\n'),
                              "objects[0]: primitive 'sphere' cannot have children"),
    "children not tables": (scene_text(objects=OBJ + 'type = "union"\nchildren = 3\n'),
                            "objects[0].children: expected an array of tables, got integer 3"),
    "union with one child": (scene_text(objects=OBJ + 'type = "union"\n[[objects.children]]\ntype = "box"\n'),
                             "objects[0]: 'union' needs at least 2 children, got 1"),
    "subtraction without children": (scene_text(objects=OBJ + 'type = "subtraction"\n'),
                                     "objects[0]: 'subtraction' needs at least 2 children, got 0"),
    "repeat with two children": (
        scene_text(objects=OBJ + 'type = "repeat"\n[[objects.children]]\ntype = "box"\n[[objects.children]]\ntype = "box"\n'),
        "objects[0]: 'repeat' needs exactly 1 child, got 2"),
    "deep nested error": (
        scene_text(objects=OBJ + 'type = "union"\n[[objects.children]]\ntype = "box"\n[[objects.children]]\ntype = "union"\n'
                   '[[objects.children.children]]\ntype = "box"\n[[objects.children.children]]\ntype = "box"\ntranslate = [1, 2]\n'),
        "objects[0].children[1].children[1].translate: expected 3 numbers, got 2"),
    # objects: parameters
    "radius zero": (scene_text(objects=SPHERE + "radius = 0\n"), "objects[0].radius: 0 is out of range (allowed: > 0)"),
    "radius bool": (scene_text(objects=SPHERE + "radius = true\n"), "objects[0].radius: expected a number, got boolean true"),
    "box size negative": (scene_text(objects=OBJ + 'type = "box"\nsize = [1, -1, 1]\n'), "objects[0].size[1]: -1 is out of range"),
    "rounded box radius too big": (scene_text(objects=OBJ + 'type = "rounded_box"\nsize = [1, 0.4, 1]\nradius = 0.3\n'),
                                   "objects[0]: radius 0.3 is larger than half the smallest size component (0.2)"),
    "torus minor not smaller": (scene_text(objects=OBJ + 'type = "torus"\nmajor_radius = 0.2\nminor_radius = 0.2\n'),
                                "objects[0]: minor_radius 0.2 must be smaller than major_radius 0.2"),
    "capsule height zero": (scene_text(objects=OBJ + 'type = "capsule"\nheight = 0\n'), "objects[0].height: 0 is out of range"),
    "cone radius negative": (scene_text(objects=OBJ + 'type = "cone"\nradius = -1\n'), "objects[0].radius: -1 is out of range"),
    "cylinder height nan": (scene_text(objects=OBJ + 'type = "cylinder"\nheight = nan\n'), "objects[0].height: nan is not a finite number"),
    "plane zero normal": (scene_text(objects=OBJ + 'type = "plane"\nnormal = [0, 0, 0]\n'), "objects[0].normal: must not be the zero vector"),
    "smooth_union k zero": (
        scene_text(objects=OBJ + 'type = "smooth_union"\nk = 0\n[[objects.children]]\ntype = "box"\n[[objects.children]]\ntype = "box"\n'),
        "objects[0].k: 0 is out of range (allowed: > 0)"),
    "repeat period negative": (scene_text(objects=OBJ + 'type = "repeat"\nperiod = [1, -1, 0]\n[[objects.children]]\ntype = "box"\n'),
                               "objects[0].period[1]: -1 is out of range (allowed: >= 0)"),
    "repeat limit float": (scene_text(objects=OBJ + 'type = "repeat"\nlimit = [1, 1.5, 1]\n[[objects.children]]\ntype = "box"\n'),
                           "objects[0].limit[1]: expected an integer, got float 1.5"),
    "repeat limit negative": (scene_text(objects=OBJ + 'type = "repeat"\nlimit = [-1, 0, 0]\n[[objects.children]]\ntype = "box"\n'),
                              "objects[0].limit[0]: -1 is out of range (allowed: >= 0)"),
    "repeat limit length": (scene_text(objects=OBJ + 'type = "repeat"\nlimit = [1, 1]\n[[objects.children]]\ntype = "box"\n'),
                            "objects[0].limit: expected 3 numbers, got 2"),
    # objects: transforms
    "non-uniform scale": (scene_text(objects=SPHERE + "scale = [1, 2, 1]\n"),
                          "objects[0].scale: non-uniform scale [1, 2, 1] breaks the SDF distance bound; use a uniform scale"),
    "scale zero": (scene_text(objects=SPHERE + "scale = 0\n"), "objects[0].scale: 0 is out of range (allowed: > 0)"),
    "scale list negative": (scene_text(objects=SPHERE + "scale = [-1, -1, -1]\n"), "objects[0].scale: -1 is out of range"),
    "rotate wrong length": (scene_text(objects=SPHERE + "rotate = [0, 45]\n"), "objects[0].rotate: expected 3 numbers, got 2"),
    "translate string": (scene_text(objects=SPHERE + 'translate = "up"\n'), "objects[0].translate: expected an array of 3 numbers, got string 'up'"),
    # objects of the other geometry kind
    "quad in sdf scene": (scene_text(objects=OBJ + 'type = "quad"\n'),
                          "objects[0]: type 'quad' is only allowed in scenes with geometry 'mesh', not 'sdf' (sdf primitives: sphere, box,"),
    "mesh in sdf child": (scene_text(objects=OBJ + 'type = "union"\n[[objects.children]]\ntype = "box"\n[[objects.children]]\ntype = "mesh"\n'),
                          "objects[0].children[1]: type 'mesh' is only allowed in scenes with geometry 'mesh', not 'sdf'"),
}


@pytest.mark.parametrize("text, expected", BAD_SCENES.values(), ids=BAD_SCENES.keys())
def test_bad_scene_gives_one_line_error(tmp_path, text, expected):
    path = write(tmp_path, text)
    message = load_error(path)
    assert expected in message


def test_map_directory_is_rejected(tmp_path):
    (tmp_path / "dir.exr").mkdir()
    path = write(tmp_path, scene_text(extra='[environment]\ntype = "map"\nfile = "dir.exr"\n'))
    assert "environment: map file dir.exr is not a file" in load_error(path)


def test_missing_map_names_scene_file_and_map(tmp_path):
    (tmp_path / "scenes").mkdir()
    path = write(tmp_path / "scenes", scene_text(extra='[environment]\ntype = "map"\nfile = "../envmaps/nope.exr"\n'))
    message = load_error(path)
    assert message.startswith(f"{path}: environment: missing map file ../envmaps/nope.exr")
    assert str(tmp_path / "envmaps" / "nope.exr") in message


# --- mesh scenes -----------------------------------------------------------------------------

MESH_HEADER = '[scene]\ngeometry = "mesh"\n'
MESH_SPHERE = '[[objects]]\ntype = "sphere"\nmaterial = "m"\n'


def mesh_text(objects: str = MESH_SPHERE, extra: str = "", materials: str = MATERIAL) -> str:
    return scene_text(extra=extra, objects=objects, materials=materials, header=MESH_HEADER)


def touch(path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(b"")  # the scene loader checks that model files exist, it does not read them
    return path


FULL_MESH_SCENE = """
[scene]
name = "full mesh"
geometry = "mesh"

[camera]
position = [0, 2, 6]

[render]
width = 64
height = 32
max_depth = 5

[environment]
type = "constant"
color = [0, 0, 0]

[materials.copper]
type = "conductor"
base_color = [0.955, 0.638, 0.538]
roughness = 0.25

[materials.car_paint]
type = "principled"
base_color = [0.6, 0.05, 0.05]
metallic = 0.3
roughness = 0.2
transmission = 0.1
ior = 1.45

[materials.glass]
type = "dielectric"
roughness = 0
ior = 1.5

[materials.lamp]
emission = [10, 9, 8]

[[objects]]
type = "mesh"
file = "../models/bunny.glb"
material = "copper"
translate = [0, 0.5, 0]
rotate = [0, 90, 0]
scale = [1, 2, 3]

[[objects]]
type = "mesh"
file = "../models/Chair.OBJ"

[[objects]]
type = "sphere"
material = "glass"
radius = 0.25
scale = [2, 2, 2]

[[objects]]
type = "disc"
material = "lamp"
radius = 0.75
rotate = [180, 0, 0]
translate = [0, 3, 0]
scale = 2

[[objects]]
type = "quad"
material = "car_paint"
size = [4, 2.5]
scale = [1, 1, 0.5]

[[objects]]
type = "generated"
generator = "terrain"
material = "copper"
resolution = 32
size = 20
height = 0.5
seed = 11
translate = [0, -1, 0]

[[objects]]
type = "generated"
generator = "icosphere"
material = "glass"
"""


def test_full_mesh_scene_round_trips(tmp_path):
    bunny = touch(tmp_path / "models" / "bunny.glb")
    chair = touch(tmp_path / "models" / "Chair.OBJ")
    (tmp_path / "scenes").mkdir()
    path = write(tmp_path / "scenes", FULL_MESH_SCENE, "full_mesh.toml")

    scene = load_scene(path)

    expected = Scene(
        name="full mesh",
        path=path,
        geometry="mesh",
        camera=CameraSpec(position=(0.0, 2.0, 6.0)),
        render=RenderSettings(width=64, height=32, max_depth=5),
        environment=EnvironmentSpec(kind="constant", color=(0.0, 0.0, 0.0)),
        materials=(
            MaterialSpec("copper", "conductor", (0.955, 0.638, 0.538), 0.25),
            MaterialSpec("car_paint", "principled", (0.6, 0.05, 0.05), 0.2, 1.45,
                         metallic=0.3, transmission=0.1),
            MaterialSpec("glass", "dielectric", roughness=0.0, ior=1.5),
            MaterialSpec("lamp", emission=(10.0, 9.0, 8.0)),
        ),
        mesh_objects=(
            MeshObject("mesh", file=bunny.resolve(), material="copper", translate=(0.0, 0.5, 0.0),
                       rotate=(0.0, 90.0, 0.0), scale=(1.0, 2.0, 3.0)),
            MeshObject("mesh", file=chair.resolve()),
            MeshObject("sphere", material="glass", radius=0.25, scale=(2.0, 2.0, 2.0)),
            MeshObject("disc", material="lamp", radius=0.75, rotate=(180.0, 0.0, 0.0),
                       translate=(0.0, 3.0, 0.0), scale=(2.0, 2.0, 2.0)),
            MeshObject("quad", material="car_paint", size=(4.0, 2.5), scale=(1.0, 1.0, 0.5)),
            MeshObject("generated", material="copper", generator="terrain",
                       params=(("height", 0.5), ("resolution", 32), ("seed", 11), ("size", 20.0)),
                       translate=(0.0, -1.0, 0.0)),
            MeshObject("generated", material="glass", generator="icosphere",
                       params=(("radius", 1.0), ("subdivisions", 3))),
        ),
    )
    assert scene == expected
    assert scene.sdf_objects == ()
    assert scene.render.march == MarchSettings()  # unused by mesh scenes, but always present
    # Types matter to the generators and the renderer: ints stay ints, the rest is float.
    params = dict(scene.mesh_objects[5].params)
    assert type(params["resolution"]) is int and type(params["seed"]) is int
    assert type(params["size"]) is float and type(params["height"]) is float
    assert all(type(c) is float for o in scene.mesh_objects for c in o.scale + o.size)
    assert scene.mesh_objects[0].file.is_absolute()


def test_mesh_object_defaults_equal_model_defaults(tmp_path):
    touch(tmp_path / "m.glb")
    objects = ('[[objects]]\ntype = "mesh"\nfile = "m.glb"\n'
               + "".join(f'[[objects]]\ntype = "{k}"\nmaterial = "m"\n' for k in ("sphere", "quad", "disc"))
               + '[[objects]]\ntype = "generated"\nmaterial = "m"\ngenerator = "terrain"\n'
               + '[[objects]]\ntype = "generated"\nmaterial = "m"\ngenerator = "icosphere"\n')
    scene = load_scene(write(tmp_path, mesh_text(objects=objects)))
    assert scene.geometry == "mesh"
    mesh, sphere, quad, disc, terrain, icosphere = scene.mesh_objects
    assert mesh == MeshObject("mesh", file=(tmp_path / "m.glb").resolve())
    assert sphere == MeshObject("sphere", material="m")
    assert quad == MeshObject("quad", material="m")
    assert disc == MeshObject("disc", material="m")
    assert terrain == MeshObject("generated", material="m", generator="terrain", params=(
        ("height", 1.0), ("resolution", 708), ("seed", 0), ("size", 10.0)))
    assert icosphere == MeshObject("generated", material="m", generator="icosphere",
                                   params=(("radius", 1.0), ("subdivisions", 3)))
    assert 2 * dict(terrain.params)["resolution"] ** 2 >= 1_000_000  # the default is the 1M case


def test_model_file_relative_to_scene_folder_not_cwd(tmp_path, monkeypatch):
    touch(tmp_path / "scenes" / "models" / "a.ply")
    path = write(tmp_path / "scenes", mesh_text(objects='[[objects]]\ntype = "mesh"\nfile = "models/a.ply"\n'))
    monkeypatch.chdir(tmp_path)
    scene = load_scene(Path("scenes") / "scene.toml")
    assert scene.mesh_objects[0].file == (tmp_path / "scenes" / "models" / "a.ply").resolve()


@pytest.mark.parametrize("extension", MESH_EXTENSIONS + (".GLB", ".Obj"))
def test_every_model_extension_is_accepted(tmp_path, extension):
    touch(tmp_path / f"model{extension}")
    text = mesh_text(objects=f'[[objects]]\ntype = "mesh"\nfile = "model{extension}"\n')
    assert load_scene(write(tmp_path, text)).mesh_objects[0].file.name == f"model{extension}"


def test_principled_material_with_ior(tmp_path):
    materials = '[materials.m]\ntype = "principled"\nmetallic = 1\nroughness = 0.1\nior = 1.3\n'
    material = load_scene(write(tmp_path, mesh_text(materials=materials))).materials[0]
    assert material == MaterialSpec("m", "principled", roughness=0.1, ior=1.3, metallic=1.0)


def test_documented_mesh_example_loads(tmp_path):
    touch(tmp_path / "envmaps" / "sky.exr")
    touch(tmp_path / "models" / "bunny.glb")
    (tmp_path / "scenes").mkdir()
    scene = load_scene(write(tmp_path / "scenes", schema.MESH_EXAMPLE))
    assert scene.geometry == "mesh"
    assert tuple(o.kind for o in scene.mesh_objects) == ("mesh", "sphere", "quad", "disc", "generated")
    assert {m.kind for m in scene.materials} == {"conductor", "principled", "diffuse"}


MESH_OBJ = '[[objects]]\nmaterial = "m"\n'
GEN = MESH_OBJ + 'type = "generated"\n'

BAD_MESH_SCENES = {
    # structure and types
    "no objects": (mesh_text(objects=""), "objects: the scene has no objects"),
    "no type": (mesh_text(objects=MESH_OBJ), "objects[0]: missing required field 'type'"),
    "type not a string": (mesh_text(objects=MESH_OBJ + "type = 3\n"), "objects[0].type: expected a string, got integer 3"),
    "unknown type": (mesh_text(objects=MESH_OBJ + 'type = "cube"\n'),
                     "objects[0]: unknown object type 'cube' (known: mesh, sphere, quad, disc, generated, bezier)"),
    "sdf primitive": (mesh_text(objects=MESH_SPHERE + MESH_OBJ + 'type = "box"\n'),
                      "objects[1]: type 'box' is an sdf primitive, only allowed in scenes with geometry 'sdf', not 'mesh' "
                      "(mesh scenes allow: mesh, sphere, quad, disc, generated, bezier)"),
    "sdf operator": (mesh_text(objects=MESH_OBJ + 'type = "union"\n'),
                     "objects[0]: type 'union' is an sdf operator, only allowed in scenes with geometry 'sdf', not 'mesh'"),
    "sdf plane": (mesh_text(objects=MESH_OBJ + 'type = "plane"\n'), "objects[0]: type 'plane' is an sdf primitive"),
    "children": (mesh_text(objects=MESH_SPHERE + '[[objects.children]]\ntype = "sphere"\n'),
                 "objects[0]: unknown field 'children' (allowed: type, material, translate, rotate, scale, radius)"),
    "march in mesh scene": (mesh_text(extra="[render.march]\nmax_steps = 10\n"),
                            "render.march: only allowed in scenes with geometry 'sdf', not 'mesh'"),
    "march empty table": (mesh_text(extra="[render]\nspp = 4\n[render.march]\n"),
                          "render.march: only allowed in scenes with geometry 'sdf', not 'mesh'"),
    "render still validated": (mesh_text(extra="[render]\nspp = 0\n"), "render.spp: 0 is out of range"),
    # materials
    "sphere without material": (mesh_text(objects='[[objects]]\ntype = "sphere"\n'), "objects[0]: missing required field 'material'"),
    "quad without material": (mesh_text(objects='[[objects]]\ntype = "quad"\n'), "objects[0]: missing required field 'material'"),
    "disc without material": (mesh_text(objects='[[objects]]\ntype = "disc"\n'), "objects[0]: missing required field 'material'"),
    "generated without material": (mesh_text(objects='[[objects]]\ntype = "generated"\ngenerator = "icosphere"\n'),
                                   "objects[0]: missing required field 'material'"),
    "unknown material": (mesh_text(objects=MESH_SPHERE + '[[objects]]\ntype = "quad"\nmaterial = "gold"\n'),
                         "unknown material 'gold' in objects[1] (known: m)"),
    "material not a string": (mesh_text(objects='[[objects]]\ntype = "sphere"\nmaterial = 1\n'),
                              "objects[0].material: expected a string, got integer 1"),
    # model files
    "mesh without file": (mesh_text(objects='[[objects]]\ntype = "mesh"\n'), "objects[0]: missing required field 'file'"),
    "file not a string": (mesh_text(objects='[[objects]]\ntype = "mesh"\nfile = 3\n'), "objects[0].file: expected a string, got integer 3"),
    "file fbx": (mesh_text(objects='[[objects]]\ntype = "mesh"\nfile = "car.fbx"\n'),
                 "objects[0].file: unsupported model extension '.fbx' (expected .gltf, .glb, .obj, .ply or .stl)"),
    "file no extension": (mesh_text(objects='[[objects]]\ntype = "mesh"\nfile = "car"\n'),
                          "objects[0].file: unsupported model file without an extension"),
    "file missing": (mesh_text(objects=MESH_SPHERE + '[[objects]]\ntype = "mesh"\nfile = "../models/nope.glb"\n'),
                     "objects[1]: missing model file ../models/nope.glb (looked for "),
    "file on sphere": (mesh_text(objects=MESH_SPHERE + 'file = "a.glb"\n'),
                       "objects[0]: unknown field 'file' (allowed: type, material, translate, rotate, scale, radius)"),
    # shape parameters
    "sphere radius zero": (mesh_text(objects=MESH_SPHERE + "radius = 0\n"), "objects[0].radius: 0 is out of range (allowed: > 0)"),
    "disc radius negative": (mesh_text(objects=MESH_OBJ + 'type = "disc"\nradius = -1\n'), "objects[0].radius: -1 is out of range"),
    "disc radius string": (mesh_text(objects=MESH_OBJ + 'type = "disc"\nradius = "big"\n'),
                           "objects[0].radius: expected a number, got string 'big'"),
    "quad size one number": (mesh_text(objects=MESH_OBJ + 'type = "quad"\nsize = 2\n'),
                             "objects[0].size: expected an array of 2 numbers, got integer 2"),
    "quad size three numbers": (mesh_text(objects=MESH_OBJ + 'type = "quad"\nsize = [1, 1, 1]\n'),
                                "objects[0].size: expected 2 numbers, got 3"),
    "quad size zero": (mesh_text(objects=MESH_OBJ + 'type = "quad"\nsize = [1, 0]\n'),
                       "objects[0].size[1]: 0 is out of range (allowed: > 0)"),
    "quad size nan": (mesh_text(objects=MESH_OBJ + 'type = "quad"\nsize = [nan, 1]\n'), "objects[0].size[0]: nan is not a finite number"),
    "radius on quad": (mesh_text(objects=MESH_OBJ + 'type = "quad"\nradius = 1\n'),
                       "objects[0]: unknown field 'radius' (allowed: type, material, translate, rotate, scale, size)"),
    "size on sphere": (mesh_text(objects=MESH_SPHERE + "size = [1, 1]\n"), "objects[0]: unknown field 'size'"),
    # transforms
    "non-uniform sphere": (mesh_text(objects=MESH_SPHERE + "scale = [1, 2, 1]\n"),
                           "objects[0].scale: non-uniform scale [1, 2, 1] is not allowed for type 'sphere' "
                           "(an ellipsoid is not a sphere); use a uniform scale"),
    "non-uniform disc": (mesh_text(objects=MESH_OBJ + 'type = "disc"\nscale = [2, 2, 1.5]\n'),
                         "objects[0].scale: non-uniform scale [2, 2, 1.5] is not allowed for type 'disc' (an ellipse is not a disc)"),
    "scale zero": (mesh_text(objects=MESH_OBJ + 'type = "quad"\nscale = 0\n'), "objects[0].scale: 0 is out of range (allowed: > 0)"),
    "scale component negative": (mesh_text(objects=MESH_OBJ + 'type = "quad"\nscale = [1, 1, -1]\n'),
                                 "objects[0].scale[2]: -1 is out of range (allowed: > 0)"),
    "scale component zero on sphere": (mesh_text(objects=MESH_SPHERE + "scale = [0, 0, 0]\n"),
                                       "objects[0].scale[0]: 0 is out of range (allowed: > 0)"),
    "scale two numbers": (mesh_text(objects=MESH_OBJ + 'type = "quad"\nscale = [1, 2]\n'), "objects[0].scale: expected 3 numbers, got 2"),
    "scale bool": (mesh_text(objects=MESH_OBJ + 'type = "quad"\nscale = true\n'), "objects[0].scale: expected a number, got boolean true"),
    "rotate short": (mesh_text(objects=MESH_SPHERE + "rotate = [0, 1]\n"), "objects[0].rotate: expected 3 numbers, got 2"),
    "translate inf": (mesh_text(objects=MESH_SPHERE + "translate = [0, inf, 0]\n"), "objects[0].translate[1]: inf is not a finite number"),
    # generators
    "no generator": (mesh_text(objects=GEN), "objects[0]: missing required field 'generator'"),
    "unknown generator": (mesh_text(objects=GEN + 'generator = "noise"\n'),
                          "objects[0].generator: unknown value 'noise' (allowed: terrain, icosphere, light_panels, water)"),
    "generator not a string": (mesh_text(objects=GEN + "generator = 1\n"), "objects[0].generator: expected a string, got integer 1"),
    "generator on sphere": (mesh_text(objects=MESH_SPHERE + 'generator = "terrain"\n'), "objects[0]: unknown field 'generator'"),
    "param of other generator": (mesh_text(objects=GEN + 'generator = "terrain"\nsubdivisions = 2\n'),
                                 "objects[0].subdivisions: only allowed with generator 'icosphere', not 'terrain'"),
    "terrain param on icosphere": (mesh_text(objects=GEN + 'generator = "icosphere"\nseed = 2\n'),
                                   "objects[0].seed: only allowed with generator 'terrain' or 'light_panels' or 'water', not 'icosphere'"),
    "unknown generator param": (mesh_text(objects=GEN + 'generator = "terrain"\noctaves = 2\n'),
                                "objects[0]: unknown field 'octaves' (allowed: type, material, translate, rotate, scale, generator, "
                                "resolution, size, height, seed)"),
    "terrain param on sphere": (mesh_text(objects=MESH_SPHERE + "resolution = 10\n"), "objects[0]: unknown field 'resolution'"),
    "resolution 1": (mesh_text(objects=GEN + 'generator = "terrain"\nresolution = 1\n'),
                     "objects[0].resolution: 1 is out of range (allowed: [2, 4096])"),
    "resolution huge": (mesh_text(objects=GEN + 'generator = "terrain"\nresolution = 5000\n'), "objects[0].resolution: 5000 is out of range"),
    "resolution float": (mesh_text(objects=GEN + 'generator = "terrain"\nresolution = 10.0\n'),
                         "objects[0].resolution: expected an integer, got float 10.0"),
    "terrain size zero": (mesh_text(objects=GEN + 'generator = "terrain"\nsize = 0\n'), "objects[0].size: 0 is out of range (allowed: > 0)"),
    "terrain height negative": (mesh_text(objects=GEN + 'generator = "terrain"\nheight = -1\n'),
                                "objects[0].height: -1 is out of range (allowed: >= 0)"),
    "terrain seed negative": (mesh_text(objects=GEN + 'generator = "terrain"\nseed = -1\n'), "objects[0].seed: -1 is out of range"),
    "subdivisions 9": (mesh_text(objects=GEN + 'generator = "icosphere"\nsubdivisions = 9\n'),
                       "objects[0].subdivisions: 9 is out of range (allowed: [0, 8])"),
    "subdivisions negative": (mesh_text(objects=GEN + 'generator = "icosphere"\nsubdivisions = -1\n'),
                              "objects[0].subdivisions: -1 is out of range"),
    "icosphere radius zero": (mesh_text(objects=GEN + 'generator = "icosphere"\nradius = 0\n'), "objects[0].radius: 0 is out of range"),
}


@pytest.mark.parametrize("text, expected", BAD_MESH_SCENES.values(), ids=BAD_MESH_SCENES.keys())
def test_bad_mesh_scene_gives_one_line_error(tmp_path, text, expected):
    assert expected in load_error(write(tmp_path, text))


def test_model_directory_is_rejected(tmp_path):
    (tmp_path / "dir.glb").mkdir()
    path = write(tmp_path, mesh_text(objects='[[objects]]\ntype = "mesh"\nfile = "dir.glb"\n'))
    assert "objects[0]: model file dir.glb is not a file" in load_error(path)


def test_missing_model_names_scene_file_and_model(tmp_path):
    (tmp_path / "scenes").mkdir()
    path = write(tmp_path / "scenes", mesh_text(objects='[[objects]]\ntype = "mesh"\nfile = "../models/nope.obj"\n'))
    message = load_error(path)
    assert message.startswith(f"{path}: objects[0]: missing model file ../models/nope.obj")
    assert str(tmp_path / "models" / "nope.obj") in message


def test_model_file_is_not_read_by_the_scene_loader(tmp_path):
    (tmp_path / "broken.glb").write_bytes(b"not a glb at all")
    text = mesh_text(objects='[[objects]]\ntype = "mesh"\nfile = "broken.glb"\n')
    assert load_scene(write(tmp_path, text)).mesh_objects[0].file == (tmp_path / "broken.glb").resolve()


# --- the scenes that ship --------------------------------------------------------------------

SHIPPED = sorted((REPO / "assets" / "scenes").glob("*.toml"))
MESH_SCENES = ("cornell_box", "bunnies", "weekend", "textured", "stress", "many_lights", "studio", "pool", "goblet")


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_shipped_scene_loads(path):
    scene = load_scene(path)
    assert scene.geometry == ("mesh" if path.stem in MESH_SCENES else "sdf")
    if scene.geometry == "mesh":
        for obj in scene.mesh_objects:
            assert obj.file is None or obj.file.is_file()


def test_mesh_scenes_ship():
    assert set(MESH_SCENES) <= {p.stem for p in SHIPPED}


def test_cornell_box_matches_mitsuba_dictionary():
    """The values of Mitsuba 3's `mi.cornell_box()` (mitsuba/python/util.py)."""
    scene = load_scene(REPO / "assets" / "scenes" / "cornell_box.toml")
    assert (scene.render.width, scene.render.height, scene.render.spp, scene.render.max_depth) == (256, 256, 64, 8)
    assert scene.camera == CameraSpec(position=(0.0, 0.0, 3.9), look_at=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0),
                                      fov=39.3077, aperture=0.0, focus_distance=scene.camera.focus_distance)
    assert (scene.environment.kind, scene.environment.color) == ("constant", (0.0, 0.0, 0.0))
    colours = {m.name: m.base_color for m in scene.materials}
    assert colours["white"] == (0.885809, 0.698859, 0.666422)
    assert colours["green"] == (0.105421, 0.37798, 0.076425)
    assert colours["red"] == (0.570068, 0.0430135, 0.0443706)
    assert all(m.kind == "diffuse" for m in scene.materials)
    emissive = [m for m in scene.materials if m.is_emissive]
    assert [m.emission for m in emissive] == [(18.387, 13.9873, 6.75357)]
    assert emissive[0].base_color == colours["white"]  # Mitsuba's light rectangle has the white BSDF
    assert all(o.kind == "quad" for o in scene.mesh_objects)
    assert len(scene.mesh_objects) == 5 + 1 + 2 * 6

    def corners(obj):
        hx, hz = obj.size[0] / 2, obj.size[1] / 2
        local = [(-hx, 0, -hz, 1), (hx, 0, -hz, 1), (hx, 0, hz, 1), (-hx, 0, hz, 1)]
        return [tuple(obj.matrix() @ c)[:3] for c in local]

    def normal(obj):
        return tuple(obj.matrix()[:3, :3] @ (0.0, 1.0, 0.0))

    # The room: five 2 x 2 quads on the faces of [-1, 1]^3 facing inwards, the light facing down.
    by_material = {}
    for obj in scene.mesh_objects:
        by_material.setdefault(obj.material, []).append(obj)
    light = by_material[emissive[0].name][0]
    xs, ys, zs = zip(*corners(light))
    assert (min(xs), max(xs), min(zs), max(zs)) == pytest.approx((-0.23, 0.23, -0.18, 0.20))
    assert ys == pytest.approx((0.99,) * 4)
    assert normal(light) == pytest.approx((0, -1, 0), abs=1e-12)
    (red,), (green,) = by_material["red"], by_material["green"]
    assert np.asarray(corners(red))[:, 0] == pytest.approx(-1.0) and normal(red) == pytest.approx((1, 0, 0), abs=1e-12)
    assert np.asarray(corners(green))[:, 0] == pytest.approx(1.0) and normal(green) == pytest.approx((-1, 0, 0), abs=1e-12)
    walls = [o for o in by_material["white"] if o.size == (2.0, 2.0)]
    assert sorted(tuple(np.round(normal(o), 9)) for o in walls) == sorted(
        [(0.0, 1.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, 1.0)])

    # The boxes: Mitsuba's unit cube [-1, 1]^3 under T(t) Ry(angle) S(s); each face of ours must
    # map to a face of that box, facing out.
    boxes = {"small": ((0.335, -0.7, 0.38), -17.0, (0.3, 0.3, 0.3)),
             "large": ((-0.33, -0.4, -0.28), 18.25, (0.3, 0.61, 0.3))}
    faces = [o for o in by_material["white"] if o.size != (2.0, 2.0)]
    assert len(faces) == 12
    for name, (t, angle, s) in boxes.items():
        box = MeshObject("quad", translate=t, rotate=(0.0, angle, 0.0), scale=s).matrix()
        inverse = np.linalg.inv(box)
        mine = [o for o in faces if np.all(np.abs((inverse @ (*o.translate, 1.0))[:3]) <= 1 + 1e-6)]
        assert len(mine) == 6, name
        seen = set()
        for obj in mine:
            local = np.array([inverse @ (*c, 1.0) for c in corners(obj)])[:, :3]
            axis = int(np.argmin(np.ptp(local, axis=0)))  # the coordinate all four corners share
            side = float(np.sign(local[0, axis]))
            assert local[:, axis] == pytest.approx(side, abs=1e-6), name
            others = [a for a in range(3) if a != axis]
            assert np.abs(local[:, others]) == pytest.approx(1.0, abs=1e-6), name  # the whole face
            n_local = box[:3, :3].T @ np.asarray(normal(obj))  # world -> local normal: M^T n
            assert np.sign(n_local[axis]) == side, name  # facing out
            seen.add((axis, side))
        assert len(seen) == 6, name


# --- SceneError ------------------------------------------------------------------------------


def test_scene_error_format_and_pickle():
    err = SceneError("assets/scenes/x.toml", "first\n   second")
    assert str(err) == "assets/scenes/x.toml: first second"
    assert (err.path, err.message) == ("assets/scenes/x.toml", "first second")
    again = pickle.loads(pickle.dumps(err))
    assert str(again) == str(err)
    assert str(SceneError(Path("a") / "b.exr", "bad")) == f"{Path('a') / 'b.exr'}: bad"


# --- schema, model and documentation ---------------------------------------------------------


def _model_defaults(model) -> dict:
    out = {}
    for f in dataclasses.fields(model):
        if f.default is not dataclasses.MISSING:
            out[f.name] = f.default
        elif f.default_factory is not dataclasses.MISSING:
            out[f.name] = f.default_factory()
    return out


SECTION_MODELS = [
    (schema.CAMERA, CameraSpec, set()),
    (schema.RENDER, RenderSettings, {"march"}),
    (schema.MARCH, MarchSettings, set()),
    (schema.ENVIRONMENT, EnvironmentSpec, set()),
    (schema.MATERIAL, MaterialSpec, {"name"}),  # the name is the table key
]


@pytest.mark.parametrize("section, model, not_fields", SECTION_MODELS, ids=lambda x: getattr(x, "name", None))
def test_schema_defaults_equal_model_defaults(section, model, not_fields):
    defaults = _model_defaults(model)
    covered = set()
    for field in section.fields:
        if not field.in_model:
            continue
        covered.add(field.model_attr)
        if not field.required:
            assert field.default == defaults[field.model_attr], f"{section.name}.{field.name}"
    # Every model field is described by the schema, and nothing else is.
    assert covered | not_fields == {f.name for f in dataclasses.fields(model)}


def test_required_env_file_matches_model_absent_value():
    assert schema.ENVIRONMENT.field("file").required
    assert EnvironmentSpec().file is None


def test_schema_scene_and_transform_defaults_equal_model():
    assert schema.SCENE.field("description").default == _model_defaults(Scene)["description"]
    transform = Transform()
    for name in ("translate", "rotate", "scale"):
        assert schema.NODE.field(name).default == getattr(transform, name)


def test_schema_kinds_equal_model_kinds():
    assert schema.SCENE.field("geometry").choices == GEOMETRY_KINDS
    assert schema.ENVIRONMENT.field("type").choices == ENVIRONMENT_KINDS
    assert schema.MATERIAL.field("type").choices == MATERIAL_KINDS
    assert tuple(k.name for k in schema.PRIMITIVES) == SDF_PRIMITIVES
    assert tuple(k.name for k in schema.OPERATORS) == SDF_OPERATORS
    assert not any(k.is_operator for k in schema.PRIMITIVES)
    assert all(k.is_operator for k in schema.OPERATORS)
    assert tuple(k.name for k in schema.MESH_KINDS) == MESH_OBJECT_KINDS
    assert schema.MESH_OBJECT.field("type").choices == MESH_OBJECT_KINDS
    assert tuple(g.name for g in schema.GENERATORS) == MESH_GENERATORS
    assert schema.MESH_KINDS_BY_NAME["generated"].params[0].choices == MESH_GENERATORS
    assert schema.MESH_FILE_EXTENSIONS == MESH_EXTENSIONS  # what the mesh loader reads


def test_mesh_schema_defaults_equal_model_defaults():
    model = MeshObject(kind="sphere")
    for name in ("translate", "rotate"):
        assert schema.MESH_OBJECT.field(name).default == getattr(model, name)
    assert (schema.MESH_OBJECT.field("scale").default,) * 3 == model.scale
    assert schema.MESH_OBJECT.field("material").default == model.material
    kinds = schema.MESH_KINDS_BY_NAME
    assert kinds["sphere"].params[0].default == model.radius
    assert kinds["disc"].params[0].default == model.radius
    assert kinds["quad"].params[0].default == model.size
    assert kinds["mesh"].params[0].required and model.file is None
    assert kinds["generated"].params[0].required and model.generator is None and model.params == ()
    # Which kinds need a material and a uniform scale, as the model documents.
    assert [k.name for k in schema.MESH_KINDS if not k.needs_material] == ["mesh"]
    assert [k.name for k in schema.MESH_KINDS if k.uniform_scale_reason] == ["sphere", "disc"]


def test_every_field_has_a_description_and_known_kind():
    fields = [f for s in schema.SECTIONS + (schema.NODE, schema.MESH_OBJECT) for f in s.fields]
    fields += [f for k in schema.NODE_KINDS.values() for f in k.params]
    fields += [f for k in schema.MESH_KINDS + schema.GENERATORS for f in k.params]
    for f in fields:
        assert f.description.strip(), f.name
        assert f.kind in schema.VALUE_KINDS, f.name


def test_docs_equal_generated_text():
    doc = REPO / "docs" / "scene-format.md"
    assert doc.read_text(encoding="utf-8") == schema.render_markdown(), (
        "docs/scene-format.md is stale; regenerate it with "
        "python -c \"from renderer.scene.schema import write_markdown; write_markdown()\"")


def test_docs_mention_every_section_field_and_kind():
    text = schema.render_markdown()
    for section in schema.SECTIONS:
        assert section.name in text
        for f in section.fields:
            assert f"`{f.name}`" in text
    for kind in schema.NODE_KINDS:
        assert f"#### `{kind}`" in text
    for kind in schema.MESH_KINDS + schema.GENERATORS:
        assert f"#### `{kind.name}`" in text
        for f in kind.params:
            assert f"`{f.name}`" in text
    assert "## `[[objects]]` in `sdf` scenes" in text
    assert "## `[[objects]]` in `mesh` scenes" in text
    assert 'geometry = "mesh"' in text  # the mesh example


@pytest.mark.parametrize("value, text", [
    (schema.Range(1.0, 179.0), "[1, 179]"),
    (schema.Range(1.0, 2.0, hi_open=True), "[1, 2)"),
    (schema.Range(1.0, 4.0, lo_open=True), "(1, 4]"),
    (schema.POSITIVE, "> 0"),
    (schema.NON_NEGATIVE, ">= 0"),
    (schema.Range(1, also=(-1,)), "-1 or >= 1"),
])
def test_range_text(value, text):
    assert str(value) == text


def test_range_membership():
    depth = schema.Range(1, also=(-1,))
    assert -1 in depth and 1 in depth and 100 in depth
    assert 0 not in depth and -2 not in depth
    relax = schema.Range(1.0, 2.0, hi_open=True)
    assert 1.0 in relax and 1.999 in relax and 2.0 not in relax
