"""Light sources and area lights (renderer/scene/pbrt/lights.py)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from renderer.output.image_io import read_exr, write_exr
from renderer.scene.pbrt.environment_map import CACHE_FOLDER, equal_area_square

from tests.scene.pbrt.pbrt_helpers import SPHERE, load, material

NO_MIRROR = 'Scale -1 1 1\nLookAt 0 0 5  0 0 0  0 1 0\nCamera "perspective"\n'


def lights(tmp_path, text: str, expect_warnings: int = 0):
    return load(tmp_path, text + SPHERE, options=NO_MIRROR, expect_warnings=expect_warnings)


def test_point_spot_distant(tmp_path):
    scene, _ = lights(tmp_path, 'Translate 0 1 0\nLightSource "point" "point3 from" [1 2 3] "rgb I" [1 2 3] '
                                '"float scale" 2\n'
                                'LightSource "spot" "point3 from" [0 0 0] "point3 to" [0 -1 0] "float coneangle" 40 '
                                '"float conedeltaangle" 10 "blackbody I" 3000\n'
                                'LightSource "distant" "point3 from" [0 0 0] "point3 to" [0 0 -1] "rgb L" [3 3 3]\n')
    point, spot, distant = scene.lights
    assert point.position == pytest.approx((1, 3, 3)) and point.intensity == (2, 4, 6)
    assert spot.direction == pytest.approx((0, -1, 0)) and (spot.cutoff_angle, spot.beam) == (40, 30)
    assert spot.intensity[0] > spot.intensity[2]
    assert distant.kind == "directional" and distant.direction == pytest.approx((0, 0, -1))
    assert distant.irradiance == (3, 3, 3)


def test_point_power(tmp_path):
    scene, _ = lights(tmp_path, 'LightSource "point" "float power" 100\n')
    assert scene.lights[0].intensity == pytest.approx((100 / (4 * math.pi),) * 3)


def test_infinite_constant_and_missing_image(tmp_path):
    scene, _ = lights(tmp_path, 'LightSource "infinite" "rgb L" [0.2 0.3 0.4] "float scale" 2\n')
    assert (scene.environment.kind, scene.environment.color) == ("constant", pytest.approx((0.4, 0.6, 0.8)))
    scene, messages = lights(tmp_path, 'LightSource "infinite" "string filename" "sky.exr" "float scale" 3\n',
                             expect_warnings=1)
    env = scene.environment  # a neutral stand-in that keeps the scene visible
    assert (env.kind, env.color, env.intensity) == ("constant", (1.0, 1.0, 1.0), 3.0)
    assert "sky.exr: file not found" in messages[0] and "uniform white environment" in messages[0]
    scene, messages = lights(tmp_path, 'LightSource "infinite" "string filename" "sky.png"\n', expect_warnings=1)
    assert scene.environment.intensity == 0.0 or scene.environment.color == (0, 0, 0)


def test_equal_area_square_points():
    w = np.array([[0, 0, 1.0], [0, 0, -1.0], [1.0, 0, 0], [0, -1.0, 0]])
    assert equal_area_square(w) == pytest.approx(np.array([[0.5, 0.5], [1, 1], [1, 0.5], [0.5, 0]]))


@pytest.mark.parametrize("mirror", [False, True])
def test_image_infinite_light_becomes_a_latlong_map(tmp_path, monkeypatch, mirror):
    """A square lit inside its diamond (pbrt's light-space +z hemisphere) and a light turned so
    that +z is world +y: the map is lit above the horizon; light-space +x lit too is world +x, seen
    where pbrt's camera sees it (on the right under Scale -1 1 1, mirrored into place otherwise)."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    n = 64
    uv = (np.arange(n) + 0.5) / n
    u, v = np.meshgrid(uv, uv)
    square = np.zeros((n, n, 3), np.float32)
    square[np.abs(u - 0.5) + np.abs(v - 0.5) < 0.5] = 1.0
    square[(u > 0.75) & (np.abs(v - 0.5) < 0.1)] = 5.0  # about light-space +x
    write_exr(tmp_path / "sky.exr", square)
    options = ("" if mirror else "Scale -1 1 1\n") + 'LookAt 0 0 5  0 0 0  0 1 0\nCamera "perspective"\n'
    scene, _ = load(tmp_path, 'AttributeBegin\nRotate -90 1 0 0\nLightSource "infinite" "string filename" "sky.exr" '
                              '"float scale" 3\nAttributeEnd\n' + SPHERE, options=options)
    env = scene.environment
    assert env.kind == "map" and env.intensity == 3.0 and env.file.parent == tmp_path / "cache" / "lantern" / CACHE_FOLDER
    image = read_exr(env.file)
    h = image.shape[0]
    assert image[: h // 3].min() >= 1.0 and image[2 * h // 3:].max() == 0.0
    column = int(np.argmax(image[h // 2 - 2, :, 0]))  # just above the horizon
    u_bright = (column + 0.5) / image.shape[1]  # u = atan2(x, -z) / 2pi: 1/4 is +x, 3/4 is -x
    assert u_bright == pytest.approx(0.75 if mirror else 0.25, abs=0.05)


def test_area_light_is_the_shapes_emission(tmp_path):
    scene, _ = lights(tmp_path, 'AttributeBegin\nAreaLightSource "diffuse" "rgb L" [1 2 3] "float scale" 2\n' + SPHERE +
                      SPHERE + 'AttributeEnd\n')
    emissive = [material(scene, o.material) for o in scene.mesh_objects[:2]]
    assert emissive[0] is emissive[1] and emissive[0].emission == (2, 4, 6)
    assert material(scene, scene.mesh_objects[2].material).emission == (0, 0, 0)


def test_area_light_power_divides_by_each_lights_area(tmp_path):
    """pbrt-v4 makes a light of each sphere, each triangle of a mesh and each bilinear patch, each
    given the whole power."""
    scene, messages = lights(tmp_path, 'AttributeBegin\nAreaLightSource "diffuse" "rgb L" [1 1 1] "float power" 100\n'
                             'Scale 2 2 2\nShape "sphere"\n'
                             'Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 1 1 0 0 1 0] "integer indices" [0 1 2 0 2 3]\n'
                             'Shape "bilinearmesh" "point3 P" [0 0 0 1 0 0 0 1 0 1 1 0]\n'
                             'AttributeEnd\nAreaLightSource "diffuse" "bool twosided" true "float power" 100\n'
                             'Shape "sphere" "float radius" 2\n')
    sphere, triangles, patch, both = (material(scene, o.material) for o in scene.mesh_objects[:4])
    assert sphere.emission == pytest.approx((100 / (math.pi * 16 * math.pi),) * 3)  # radius 2: area 16 pi
    assert triangles.emission == pytest.approx((100 / (math.pi * 2),) * 3)  # each triangle: half of 2 x 2
    assert patch.emission == pytest.approx((100 / (math.pi * 4),) * 3)  # one patch of 2 x 2
    assert not sphere.two_sided_emission and both.two_sided_emission
    assert both.emission == pytest.approx((50 / (math.pi * 16 * math.pi),) * 3)  # both faces share the power


def test_unsupported_light_warns(tmp_path):
    scene, messages = lights(tmp_path, 'LightSource "goniometric" "string filename" "g.exr"\n', expect_warnings=1)
    assert scene.lights == () and 'LightSource "goniometric"' in messages[0]
