"""The TOML scene loader on mesh scenes: model files, generated meshes and analytic shapes read
into the model, defaults, paths relative to the scene file, and one-line validation errors."""
from __future__ import annotations

from pathlib import Path

import pytest

from renderer.scene import (
    CameraSpec,
    EnvironmentSpec,
    MarchSettings,
    MaterialSpec,
    RenderSettings,
    Scene,
    load_scene,
)
from renderer.scene import schema_docs
from renderer.scene.model_formats import MESH_EXTENSIONS
from renderer.scene.description import MeshObject
from tests.scene.scene_file_helpers import MATERIAL, load_error, scene_text, write


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
    scene = load_scene(write(tmp_path / "scenes", schema_docs.MESH_EXAMPLE))
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
                 "objects[0].file: unsupported model extension '.fbx' (expected .gltf, .glb, .obj, .ply, .stl or "
                 ".serialized)"),
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
                          "objects[0].generator: unknown value 'noise' (allowed: terrain, icosphere, light_panels, water, "
                          "cylinder, disc_fan, cube)"),
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


def test_a_crop_window_is_read_and_sets_the_image_size(tmp_path):
    render = "[render]\nwidth = 40\nheight = 30\ncrop = [5, 4, 10, 6]\n"
    settings = load_scene(write(tmp_path, mesh_text(extra=render))).render
    assert (settings.crop, settings.image_size, settings.width, settings.height) == ((5, 4, 10, 6), (10, 6), 40, 30)
    assert load_scene(write(tmp_path, mesh_text())).render.image_size == (640, 360)  # no crop: the image


@pytest.mark.parametrize("crop, expected", [
    ("[5, 4, 36, 6]", "render: crop [5, 4, 36, 6] reaches outside the 40x30 image"),
    ("[0, 25, 10, 6]", "render: crop [0, 25, 10, 6] reaches outside the 40x30 image"),
    ("[5, 4, 0, 6]", "render: crop [5, 4, 0, 6] has no pixels"),
    ("[-1, 4, 10, 6]", "render.crop[0]: -1 is out of range (allowed: >= 0)"),
    ("[5, 4, 10]", "render.crop: expected 4 numbers, got 3"),
    ("[5, 4, 10, 6.5]", "render.crop[3]: expected an integer, got float 6.5"),
])
def test_a_bad_crop_window_is_one_line_naming_it(tmp_path, crop, expected):
    render = f"[render]\nwidth = 40\nheight = 30\ncrop = {crop}\n"
    assert expected in load_error(write(tmp_path, mesh_text(extra=render)))
