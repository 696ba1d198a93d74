"""The graphics state and transforms (renderer/scene/pbrt/directives.py), seen through the scene
they build: each shape's placement, orientation, material and instances."""
from __future__ import annotations

import numpy as np
import pytest

from renderer.scene.errors import SceneError
from renderer.scene.pbrt.directives import look_at, parse, rotation

from tests.scene.pbrt.pbrt_helpers import SPHERE, load, write

NO_MIRROR = 'Scale -1 1 1\nLookAt 0 0 5  0 0 0  0 1 0\nCamera "perspective"\n'


def placements(scene):
    return [np.array(o.matrix()) for o in scene.mesh_objects]


def test_transforms_compose_in_pbrt_order(tmp_path):
    path = write(tmp_path, "WorldBegin\nTranslate 1 2 3\nRotate 90 0 0 1\nScale 2 2 2\n" + SPHERE)
    shape = parse(path).shapes[0]
    expected = np.eye(4)
    expected[:3, 3] = (1, 2, 3)
    expected = expected @ rotation(90, (0, 0, 1)) @ np.diag([2.0, 2.0, 2.0, 1.0])
    assert np.allclose(shape.ctm, expected)
    assert np.allclose(shape.ctm @ [1, 0, 0, 1], [1, 4, 3, 1])  # x scaled, turned to +y, moved


def test_transform_and_concat_are_column_major(tmp_path):
    path = write(tmp_path, "WorldBegin\nTransform [1 0 0 0  0 1 0 0  0 0 1 0  5 6 7 1]\n"
                           "ConcatTransform [2 0 0 0 0 2 0 0 0 0 2 0 0 0 0 1]\n" + SPHERE)
    assert np.allclose(parse(path).shapes[0].ctm @ [1, 0, 0, 1], [7, 6, 7, 1])


def test_attributes_coordinate_systems_and_reverse_orientation(tmp_path):
    path = write(tmp_path, "WorldBegin\nTranslate 1 0 0\nCoordinateSystem \"moved\"\nAttributeBegin\n"
                           "ReverseOrientation\nTranslate 0 1 0\n" + SPHERE + "AttributeEnd\n" + SPHERE +
                           "Identity\nCoordSysTransform \"moved\"\n" + SPHERE)
    shapes = parse(path).shapes
    assert [tuple(s.ctm[:3, 3]) for s in shapes] == [(1, 1, 0), (1, 0, 0), (1, 0, 0)]
    assert [s.reverse for s in shapes] == [True, False, False]


def test_camera_coordinate_system_is_the_cameras(tmp_path):
    path = write(tmp_path, "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n"
                           "CoordSysTransform \"camera\"\n" + SPHERE)
    assert np.allclose(parse(path).shapes[0].ctm, np.linalg.inv(look_at((0, 0, 5), (0, 0, 0), (0, 1, 0))))


def test_object_instances_place_the_objects_shapes(tmp_path):
    scene, _ = load(tmp_path, 'ObjectBegin "ball"\nTranslate 0 1 0\n' + SPHERE + 'ObjectEnd\n'
                    'Translate 3 0 0\nObjectInstance "ball"\nTranslate 0 0 -2\nObjectInstance "ball"\n',
                    options=NO_MIRROR)
    assert [tuple(m[:3, 3]) for m in placements(scene)] == [(3, 1, 0), (3, 1, -2)]


def test_instanced_meshes_are_read_once(tmp_path):
    scene, _ = load(tmp_path, 'ObjectBegin "tri"\nShape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0]\nObjectEnd\n'
                    'ObjectInstance "tri"\nTranslate 2 0 0\nObjectInstance "tri"\n', options=NO_MIRROR)
    assert [o.part for o in scene.mesh_objects] == ["mesh 0", "mesh 0"]
    assert len(scene.model_files.load(scene.path).meshes) == 1


def test_named_material_and_medium_interface_follow_the_attribute_stack(tmp_path):
    world = ('MakeNamedMedium "fog" "string type" "homogeneous" "rgb sigma_a" [0.1 0.2 0.3] "rgb sigma_s" [1 1 1] '
             '"float scale" 2 "float g" 0.3\n'
             'MakeNamedMaterial "red" "string type" "diffuse" "rgb reflectance" [0.8 0.1 0.1]\n'
             'AttributeBegin\nNamedMaterial "red"\nMaterial "interface"\nMediumInterface "fog" ""\n' + SPHERE +
             'AttributeEnd\nNamedMaterial "red"\n' + SPHERE)
    scene, _ = load(tmp_path, world)
    first, second = (next(m for m in scene.materials if m.name == o.material) for o in scene.mesh_objects)
    assert first.kind == "null" and first.medium == "fog"
    assert second.name == "red" and second.base_color == (0.8, 0.1, 0.1)
    medium = scene.media[0]
    assert medium.sigma_a == pytest.approx((0.2, 0.4, 0.6)) and medium.sigma_s == (2, 2, 2) and medium.g == 0.3


@pytest.mark.parametrize("world, problem", [
    ("AttributeEnd\n", "line 5: AttributeEnd without a matching AttributeBegin"),
    ("AttributeBegin\n" + SPHERE, "line 5: AttributeBegin without a matching AttributeEnd"),
    ('ObjectInstance "x"\n', "line 5: ObjectInstance: no object named 'x'"),
    ('ObjectBegin "x"\n' + SPHERE, "line 5: ObjectBegin without a matching ObjectEnd"),
    ('NamedMaterial "x"\n' + SPHERE, "line 5: no material named 'x'"),
    ("Translate 1 2\n" + SPHERE, "line 5: Translate: expected 3 numbers, got 2"),
    ('Camera "perspective"\n', "line 5: Camera belongs before WorldBegin"),
    ('"sphere"\n', "line 5: expected a directive, found 'sphere'"),
    ('CoordSysTransform "nowhere"\n', "line 5: CoordSysTransform: no coordinate system 'nowhere'"),
])
def test_errors_are_one_line_with_file_and_line(tmp_path, world, problem):
    with pytest.raises(SceneError) as e:
        load(tmp_path, world)
    assert str(e.value).startswith(str(tmp_path / "s.pbrt")) and problem in str(e.value)


def test_area_lights_on_instances_and_other_colour_spaces_warn_once(tmp_path):
    scene, messages = load(tmp_path, 'ColorSpace "aces2065-1"\nObjectBegin "lamp"\nAreaLightSource "diffuse"\n' + SPHERE +
                           SPHERE + 'ObjectEnd\nObjectInstance "lamp"\nObjectInstance "lamp"\n', expect_warnings=2)
    assert "ColorSpace 'aces2065-1'" in messages[0] and "object instances" in messages[1]
    assert len(scene.mesh_objects) == 4 and all(not m.is_emissive for m in scene.materials)
