"""The options block and the camera (renderer/scene/pbrt/scene_builder.py): pbrt's left-handed
camera space shown to Lantern's right-handed camera, the fov of the shorter side, film, crop,
sampler, integrator depth and pixel filter."""
from __future__ import annotations

import math

import numpy as np
import pytest

from renderer.scene.errors import SceneError

from tests.scene.pbrt.pbrt_helpers import load

FILM = 'Film "rgb" "integer xresolution" [40] "integer yresolution" [20]\n'
MARKED = "AttributeBegin\nTranslate 1 0 0\nShape \"sphere\" \"float radius\" 0.2\nAttributeEnd\n"


def image_x(scene, point) -> float:
    """Where a world point lands across Lantern's image: > 0 right of centre, < 0 left (Lantern's
    camera's right is forward x up: renderer/camera.py)."""
    camera = np.array(scene.camera.position)
    forward = np.array(scene.camera.look_at) - camera
    right = np.cross(forward, np.array(scene.camera.up))
    return float(np.dot(np.asarray(point) - camera, right / np.linalg.norm(right)))


def marked_x(scene) -> float:
    sphere = next(o for o in scene.mesh_objects if o.kind == "sphere")
    return image_x(scene, sphere.matrix()[:3, 3])


def test_bare_lookat_shows_world_x_on_the_left_as_pbrt_does(tmp_path):
    # pbrt's LookAt takes camera x = up x direction: looking down -z, world +x is the image's left
    scene, _ = load(tmp_path, MARKED, options='LookAt 0 0 5  0 0 0  0 1 0\nCamera "perspective"\n' + FILM)
    assert marked_x(scene) < -0.5


def test_scale_minus_one_first_shows_world_x_on_the_right(tmp_path):
    scene, _ = load(tmp_path, MARKED, options='Scale -1 1 1\nLookAt 0 0 5  0 0 0  0 1 0\nCamera "perspective"\n' + FILM)
    assert marked_x(scene) > 0.5
    assert scene.mesh_objects[0].matrix()[0, 3] == pytest.approx(1.0)  # no mirror was needed
    assert scene.camera.position == pytest.approx((0, 0, 5)) and scene.camera.up == pytest.approx((0, 1, 0))


def test_mirror_moves_lights_too(tmp_path):
    scene, _ = load(tmp_path, MARKED + 'LightSource "point" "point3 from" [2 1 0]\n',
                    options='LookAt 0 0 5  0 0 0  0 1 0\nCamera "perspective"\n' + FILM)
    assert image_x(scene, scene.lights[0].position) == pytest.approx(-2.0)


@pytest.mark.parametrize("width, height, expected", [(40, 20, 30.0), (20, 40, 2 * math.degrees(math.atan(2 * math.tan(math.radians(15)))))])
def test_fov_spans_the_shorter_side(tmp_path, width, height, expected):
    film = f'Film "rgb" "integer xresolution" [{width}] "integer yresolution" [{height}]\n'
    scene, _ = load(tmp_path, MARKED, options='Camera "perspective" "float fov" 30 "float lensradius" 0.1 '
                                              '"float focaldistance" 4\n' + film)
    assert scene.camera.fov == pytest.approx(expected)
    assert (scene.camera.aperture, scene.camera.focus_distance) == (0.1, 4.0)


def test_options(tmp_path):
    options = ('Camera "perspective"\nFilm "rgb" "integer xresolution" 100 "integer yresolution" 50 '
               '"float cropwindow" [0.25 0.75 0 0.5] "string filename" "x.exr"\n'
               'Sampler "independent" "integer pixelsamples" 7 "integer seed" 3\n'
               'Integrator "path" "integer maxdepth" 1\nPixelFilter "gaussian" "float sigma" 0.7\n')
    scene, _ = load(tmp_path, MARKED, options=options)
    r = scene.render
    assert (r.width, r.height, r.crop) == (100, 50, (25, 0, 50, 25))
    assert (r.spp, r.sampler, r.seed) == (7, "independent", 3)
    assert (r.integrator, r.max_depth) == ("mis", 2)  # pbrt's maxdepth 1: direct light, Lantern's 2
    assert (r.pixel_filter, r.filter_stddev) == ("gaussian", 0.7)


def test_defaults_are_pbrts(tmp_path):
    scene, _ = load(tmp_path, MARKED, options="")
    r = scene.render
    assert (r.width, r.height, r.spp, r.max_depth, r.pixel_filter) == (1280, 720, 16, 6, "gaussian")
    assert scene.camera.fov == 90.0 and scene.environment.kind == "constant" and scene.environment.color == (0, 0, 0)


def test_triangle_filter_and_unsupported_filter(tmp_path):
    scene, _ = load(tmp_path, MARKED, options='PixelFilter "triangle" "float xradius" 1.5 "float yradius" 1.5\n')
    assert (scene.render.pixel_filter, scene.render.filter_radius) == ("tent", 1.5)
    scene, messages = load(tmp_path, MARKED, options='PixelFilter "mitchell"\n', expect_warnings=1)
    assert scene.render.pixel_filter == "box" and 'PixelFilter "mitchell"' in messages[0]


def test_unused_option_parameter_warns_once(tmp_path):
    _, messages = load(tmp_path, MARKED, options='Film "rgb" "float maxcomponentvalue" 10\n', expect_warnings=1)
    assert messages[0].endswith("line 1: Film \"rgb\": parameter 'float maxcomponentvalue' is not supported and "
                                "was ignored")


def test_iso_and_shutter_time_are_the_display_exposure(tmp_path):
    """pbrt-v4's imaging ratio, shutter time x iso / 100: 0.5 s at iso 400 is twice the light, 1 EV."""
    options = 'Camera "perspective" "float shutteropen" 0.25 "float shutterclose" 0.75\nFilm "rgb" "float iso" 400\n'
    assert load(tmp_path, MARKED, options=options)[0].render.exposure == pytest.approx(1.0)
    assert load(tmp_path, MARKED, options='Camera "perspective" "float shutterclose" 0.25\n')[0].render.exposure == -2.0
    assert load(tmp_path, MARKED, options="")[0].render.exposure == 0.0
    _, messages = load(tmp_path, MARKED, options='Film "rgb" "float whitebalance" 5000\n', expect_warnings=1)
    assert "not white-balanced" in messages[0]
    _, messages = load(tmp_path, MARKED, options='Film "rgb" "string sensor" "canon_eos_100d"\n', expect_warnings=1)
    assert "canon_eos_100d" in messages[0]
    with pytest.raises(SceneError, match="line 1: .*the film records no light"):
        load(tmp_path, MARKED, options='Film "rgb" "float iso" 0\n')


def test_nothing_to_render_is_one_error(tmp_path):
    with pytest.raises(SceneError) as e:
        load(tmp_path, 'Shape "cone"\n', expect_warnings=1)
    assert str(e.value) == f"{tmp_path / 's.pbrt'}: nothing Lantern can render: the scene has no shape it supports"


def test_sppm_is_lanterns_photon_mapping(tmp_path):
    scene, messages = load(tmp_path, MARKED, options='Integrator "sppm" "integer maxdepth" 9 "float radius" 0.01\n',
                           expect_warnings=1)
    assert (scene.render.integrator, scene.render.max_depth) == ("sppm", 10)
    assert "initial search radius" in messages[0]


@pytest.mark.parametrize("world, why", [
    ('LightSource "point" "rgb I" [1 1 1]\n', "area lights and environments only"),
    ('MakeNamedMedium "gas" "string type" "homogeneous"\n', "does not simulate media"),
])
def test_sppm_falls_back_to_the_path_tracer_where_lanterns_cannot_follow(tmp_path, world, why):
    scene, messages = load(tmp_path, world + MARKED, options='Integrator "sppm"\n', expect_warnings=1)
    assert scene.render.integrator == "mis" and why in messages[0]


@pytest.mark.parametrize("integrator", ["bdpt", "mlt", "lightpath"])
def test_other_estimators_render_with_the_path_tracer_and_one_line(tmp_path, integrator):
    scene, messages = load(tmp_path, MARKED, options=f'Integrator "{integrator}" "integer maxdepth" 3 '
                                                     f'"integer mutationsperpixel" 8\n', expect_warnings=1)
    assert (scene.render.integrator, scene.render.max_depth) == ("mis", 4)
    assert f'Integrator "{integrator}"' in messages[0] and "path tracer (mis)" in messages[0]
