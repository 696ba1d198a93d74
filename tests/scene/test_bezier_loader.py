"""The `bezier` object type in scene files: values as written, defaults equal to the model's, and a
one-line error naming the file and the place for every bad profile."""
from pathlib import Path

import numpy as np
import pytest

from renderer.scene import SceneError, load_scene, schema
from renderer.scene.mesh_assembly import assemble
from renderer.scene.description import CameraSpec, EnvironmentSpec, MaterialSpec, MeshObject, RenderSettings, Scene

HEADER = '[scene]\ngeometry = "mesh"\n\n[materials.m]\n\n'
BEZIER = '[[objects]]\ntype = "bezier"\nmaterial = "m"\n'
CUP = "profile = [[0, 0], [0.5, 0], [0.6, 0.2], [0.6, 1]]\n"


def write(tmp_path: Path, objects: str) -> Path:
    path = tmp_path / "scene.toml"
    path.write_text(HEADER + objects, encoding="utf-8")
    return path


def load_error(path) -> str:
    with pytest.raises(SceneError) as info:
        load_scene(path)
    message = str(info.value)
    assert "\n" not in message and message.startswith(f"{path}: ")
    return message


def test_bezier_object_as_written(tmp_path):
    text = (BEZIER + 'profile = [[0, 0], [1, 0.5], [0.5, 1]]\ndegree = 2\nspans = 3\nsectors = 24\n'
            'translate = [1, 0, 0]\nrotate = [0, 0, 90]\nscale = [1, 2, 1]\n')
    obj = load_scene(write(tmp_path, text)).mesh_objects[0]
    assert obj == MeshObject("bezier", material="m", profile=((0.0, 0.0), (1.0, 0.5), (0.5, 1.0)), degree=2,
                             spans=3, sectors=24, translate=(1.0, 0.0, 0.0), rotate=(0.0, 0.0, 90.0),
                             scale=(1.0, 2.0, 1.0))
    assert all(type(c) is float for point in obj.profile for c in point)


def test_bezier_defaults_equal_model_defaults(tmp_path):
    obj = load_scene(write(tmp_path, BEZIER + CUP)).mesh_objects[0]
    model = MeshObject("bezier")
    kind = schema.MESH_KINDS_BY_NAME["bezier"]
    for name in ("degree", "spans", "sectors"):
        assert getattr(obj, name) == getattr(model, name) == kind.params[[f.name for f in kind.params].index(name)].default
    assert kind.params[0].required and model.profile == ()


BAD = {
    "no profile": (BEZIER, "objects[0]: missing required field 'profile'"),
    "no material": ('[[objects]]\ntype = "bezier"\n' + CUP, "objects[0]: missing required field 'material'"),
    "profile a number": (BEZIER + "profile = 3\n", "objects[0].profile: expected an array of [number, number] pairs, got integer 3"),
    "point of 3": (BEZIER + "profile = [[0, 0], [1, 1, 1]]\ndegree = 1\n", "objects[0].profile[1]: expected 2 numbers, got 3"),
    "point a number": (BEZIER + "profile = [[0, 0], 1]\ndegree = 1\n",
                       "objects[0].profile[1]: expected an array of 2 numbers, got integer 1"),
    "nan": (BEZIER + "profile = [[0, 0], [nan, 1]]\ndegree = 1\n", "objects[0].profile[1][0]: nan is not a finite number"),
    "inf": (BEZIER + "profile = [[0, 0], [1, inf]]\ndegree = 1\n", "objects[0].profile[1][1]: inf is not a finite number"),
    "bool": (BEZIER + "profile = [[0, 0], [true, 1]]\ndegree = 1\n", "objects[0].profile[1][0]: expected a number, got boolean true"),
    "one point": (BEZIER + "profile = [[1, 0]]\n", "objects[0]: profile needs at least 2 points, got 1"),
    "empty": (BEZIER + "profile = []\n", "objects[0]: profile needs at least 2 points, got 0"),
    "count": (BEZIER + "profile = [[0, 0], [1, 0], [1, 1], [1, 2], [0, 3]]\n",
              "objects[0]: profile has 5 points; a degree-3 profile needs 3k + 1 points (4, 7, 10, ...)"),
    "negative radius": (BEZIER + "profile = [[0, 0], [-0.5, 1]]\ndegree = 1\n",
                        "objects[0]: profile[1] has a negative radius -0.5 (radii must be >= 0)"),
    "collapsed segment": (BEZIER + "profile = [[0, 0], [1, 1], [1, 1]]\ndegree = 1\n",
                          "objects[0]: profile segment 1 (points 1 to 2) is a single point"),
    "on the axis": (BEZIER + "profile = [[0, 0], [0, 1]]\ndegree = 1\n",
                    "objects[0]: profile segment 0 lies on the axis (radius 0 throughout), which is no surface"),
    "degree 4": (BEZIER + CUP + "degree = 4\n", "objects[0].degree: 4 is out of range (allowed: [1, 3])"),
    "degree 0": (BEZIER + CUP + "degree = 0\n", "objects[0].degree: 0 is out of range (allowed: [1, 3])"),
    "sectors 3": (BEZIER + CUP + "sectors = 3\n", "objects[0].sectors: 3 is out of range (allowed: [4, 256])"),
    "spans 0": (BEZIER + CUP + "spans = 0\n", "objects[0].spans: 0 is out of range (allowed: [1, 64])"),
    "spans float": (BEZIER + CUP + "spans = 2.0\n", "objects[0].spans: expected an integer, got float 2.0"),
    "radius on bezier": (BEZIER + CUP + "radius = 1\n",
                         "objects[0]: unknown field 'radius' (allowed: type, material, translate, rotate, scale, "
                         "profile, degree, spans, sectors)"),
    "profile on sphere": ('[[objects]]\ntype = "sphere"\nmaterial = "m"\n' + CUP, "objects[0]: unknown field 'profile'"),
}


@pytest.mark.parametrize("text, expected", BAD.values(), ids=BAD.keys())
def test_bad_bezier_gives_one_line_error(tmp_path, text, expected):
    assert expected in load_error(write(tmp_path, text))


def test_sdf_scene_refuses_bezier(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text('[scene]\ngeometry = "sdf"\n[materials.m]\n' + BEZIER + CUP, encoding="utf-8")
    assert "type 'bezier' is only allowed in scenes with geometry 'mesh', not 'sdf'" in load_error(path)


def test_scene_built_in_code_is_checked_too():
    scene = Scene(name="x", path=Path("x.toml"), geometry="mesh", camera=CameraSpec(), render=RenderSettings(),
                  environment=EnvironmentSpec(), materials=(MaterialSpec("m"),),
                  mesh_objects=(MeshObject("bezier", material="m", profile=((0.0, 0.0), (-1.0, 1.0)), degree=1),))
    with pytest.raises(SceneError, match=r"x.toml: objects\[0\]: profile\[1\] has a negative radius"):
        assemble(scene)


def test_assembled_patches_follow_the_transform(tmp_path):
    """A cylinder of radius 1 and height 1, scaled by 2 along x and moved up: its patch boxes
    cover exactly x in [-2, 2], y in [3, 4], z in [-1, 1] (up to the boxes' padding)."""
    text = BEZIER + "profile = [[1, 0], [1, 1]]\ndegree = 1\nscale = [2, 1, 1]\ntranslate = [0, 3, 0]\n"
    data = assemble(load_scene(write(tmp_path, text))).data
    lo, hi = data.scene_bounds()
    assert np.allclose(lo, [-2, 3, -1], atol=1e-4) and np.allclose(hi, [2, 4, 1], atol=1e-4)
    assert data.counts["bezier"] == 4 * 16 and data.kinds() == frozenset({"bezier"})
