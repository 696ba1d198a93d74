"""The TOML scene loader on SDF scenes: every section read into the model, defaults, paths
relative to the scene file, file-level errors and one-line validation errors (SceneError)."""
from __future__ import annotations

import math
import pickle
from pathlib import Path

import pytest

from renderer.scene import (
    CameraSpec,
    EnvironmentSpec,
    MarchSettings,
    MaterialSpec,
    RenderSettings,
    Scene,
    SceneError,
    Transform,
    load_scene,
)
from renderer.scene import schema_docs
from renderer.scene.features import scene_features
from tests.scene.scene_file_helpers import HEADER, MATERIAL, SPHERE, load_error, node, scene_text, write


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


def test_a_scenes_exposure_is_read(tmp_path):
    scene = load_scene(write(tmp_path, scene_text(extra="[render]\nexposure = -1.5\n")))
    assert scene.render.exposure == -1.5
    assert "render.exposure: 200 is out of range" in load_error(write(tmp_path, scene_text(extra="[render]\nexposure = 200\n")))


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


def test_environment_rotation_axis(tmp_path):
    """`rotation` alone turns about +y (no matrix compiled); `rotation_axis` (normalised) makes it
    any rotation, Mitsuba's rotate(axis, angle); -y is a turn about +y the other way."""
    def env(text, name):
        return load_scene(write(tmp_path, scene_text(f"[environment]\n{text}\n"), name)).environment

    about_y = env("rotation = 30", "a.toml")
    assert about_y.rotation_axis == (0.0, 1.0, 0.0) and about_y.y_rotation() == 30.0 and not about_y.needs_matrix
    assert not scene_features(load_scene(tmp_path / "a.toml")).environment_rotated
    assert env("rotation = 30\nrotation_axis = [0, -2, 0]", "b.toml").y_rotation() == -30.0
    tilted = env("rotation = 90\nrotation_axis = [2, 0, 0]", "c.toml")
    assert tilted.rotation_axis == (1.0, 0.0, 0.0) and tilted.y_rotation() is None and tilted.needs_matrix
    assert scene_features(load_scene(tmp_path / "c.toml")).environment_rotated  # the sky turns too
    # a quarter turn about +x (right-handed) takes +y to +z: the map's zenith is seen along +z
    assert tuple(tilted.rotation_matrix() @ (0.0, 1.0, 0.0)) == pytest.approx((0.0, 0.0, 1.0), abs=1e-15)
    assert not env('type = "constant"\nrotation = 90\nrotation_axis = [1, 0, 0]', "d.toml").needs_matrix
    assert "must not be the zero vector" in load_error(write(tmp_path, scene_text(
        "[environment]\nrotation_axis = [0, 0, 0]\n"), "e.toml"))


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
    scene = load_scene(write(tmp_path / "scenes", schema_docs.EXAMPLE))
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
                        "unknown section 'camra' (allowed: scene, camera, render, environment, lights, materials, model_materials, media, fog, objects)"),
    "no scene section": ("[materials.m]\n" + SPHERE, "missing [scene] section"),
    "scene not a table": ("scene = 3\n" + MATERIAL + SPHERE, "scene: expected a table, got integer 3"),
    "no geometry": (scene_text(header='[scene]\nname = "x"\n'), "scene: missing required field 'geometry'"),
    "unknown geometry": (scene_text(header='[scene]\ngeometry = "voxels"\n'),
                         "scene.geometry: unknown value 'voxels' (allowed: sdf, mesh)"),
    "unknown scene field": (scene_text(header='[scene]\ngeometry = "sdf"\ntitle = "x"\n'),
                            "scene: unknown field 'title' (allowed: name, description, geometry, edits)"),
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
                             "camera: unknown field 'fovy' (allowed: position, look_at, up, fov, aperture, focus_distance, projection, ortho_height, keyframes)"),
    "date instead of number": (scene_text(extra="[camera]\nfov = 1979-05-27\n"), "camera.fov: expected a number, got date/time"),
    # render
    "width zero": (scene_text(extra="[render]\nwidth = 0\n"), "render.width: 0 is out of range (allowed: [1, 16384])"),
    "width float": (scene_text(extra="[render]\nwidth = 640.0\n"), "render.width: expected an integer, got float 640.0"),
    "spp bool": (scene_text(extra="[render]\nspp = true\n"), "render.spp: expected an integer, got boolean true"),
    "max_depth zero": (scene_text(extra="[render]\nmax_depth = 0\n"), "render.max_depth: 0 is out of range (allowed: -1 or >= 1)"),
    "max_depth -2": (scene_text(extra="[render]\nmax_depth = -2\n"), "render.max_depth: -2 is out of range"),
    "seed negative": (scene_text(extra="[render]\nseed = -1\n"), "render.seed: -1 is out of range"),
    "integrator number": (scene_text(extra="[render]\nintegrator = 3\n"), "render.integrator: expected a string, got integer 3"),
    "render unknown field": (scene_text(extra="[render]\nsamples = 3\n"), "render: unknown field 'samples' (allowed: width, height, spp, max_depth, integrator, seed, sampler, pixel_filter, filter_radius, filter_stddev, crop, exposure, energy_compensation, texture_filter, march)"),
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
                          "environment: unknown field 'strength' (allowed: type, intensity, rotation, rotation_axis, zenith, horizon, "
                          "ground)"),
    # materials
    "material unknown field": (scene_text(materials="[materials.glass]\ntype = \"dielectric\"\niorr = 1.5\n"),
                               "materials.glass: unknown field 'iorr' (allowed: type, base_color, roughness, ior, thin, "
                               "specular_color, microfacet, roughness_v, sidedness, "
                               "opacity, emission, emission_strength, two_sided_emission, abbe, glass, medium, outside_medium, normal_map, "
                               "bump_map, bump_scale)"),
    "material unknown type": (scene_text(materials='[materials.m]\ntype = "metal"\n'),
                              "materials.m.type: unknown value 'metal' (allowed: diffuse, conductor, dielectric, principled, null, plastic, disney, coated, diffuse_transmission)"),
    "ior on conductor": (scene_text(materials='[materials.m]\ntype = "conductor"\nior = 1.5\n'),
                         "materials.m.ior: only allowed with type 'dielectric' or 'principled' or 'plastic' or 'disney' or 'coated', not 'conductor'"),
    "ior on default diffuse": (scene_text(materials="[materials.m]\nior = 1.5\n"),
                               "materials.m.ior: only allowed with type 'dielectric' or 'principled' or 'plastic' or 'disney' or 'coated', not 'diffuse'"),
    "metallic on diffuse": (scene_text(materials="[materials.m]\nmetallic = 1\n"),
                            "materials.m.metallic: only allowed with type 'principled' or 'disney', not 'diffuse'"),
    "transmission on dielectric": (scene_text(materials='[materials.m]\ntype = "dielectric"\ntransmission = 1\n'),
                                   "materials.m.transmission: only allowed with type 'principled' or 'disney', not 'dielectric'"),
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


# --- SceneError ------------------------------------------------------------------------------


def test_scene_error_format_and_pickle():
    err = SceneError("assets/scenes/x.toml", "first\n   second")
    assert str(err) == "assets/scenes/x.toml: first second"
    assert (err.path, err.message) == ("assets/scenes/x.toml", "first second")
    again = pickle.loads(pickle.dumps(err))
    assert str(again) == str(err)
    assert str(SceneError(Path("a") / "b.exr", "bad")) == f"{Path('a') / 'b.exr'}: bad"
