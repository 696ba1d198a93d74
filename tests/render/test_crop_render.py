"""Crop windows rendered (Mitsuba's hdrfilm crop_*, a scene file's render.crop): only the window is
rendered, with the whole image's projection.

Each pixel's rays, pixel-filter weights (the filter cut at the whole image's edges, not the
window's) and random numbers (seeded by its number in the whole image) are the whole render's, so
a crop equals the same window of the whole render bit for bit, with every filter, inside the image
and along its edges. A film of another size (the viewer's, `render --size`) shows the window
scaled: at twice the crop's size it is the crop of the image rendered at twice its size, bit for
bit. Against Mitsuba 3 where it is installed (box filter: Mitsuba's crop leaves out the filter's
reach beyond the window, which a box filter does not have), by its render-test rule at ALPHA =
0.01 (fixed seeds)."""
from __future__ import annotations

import numpy as np
import pytest

from renderer.camera import CameraFrame
from renderer.renderer import Renderer
from renderer.scene.mitsuba import load_mitsuba_scene
from tests.render.mitsuba_xml_compare import lantern_image, mitsuba_image, mitsuba_or_skip
from tests.stats.image_tests import assert_agree

ALPHA = 0.01
WIDTH, HEIGHT = 24, 16
SCENE = """<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="3"/></integrator>
    <sensor type="perspective"><float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 1, 4" target="0, 0.5, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><rfilter type="{rfilter}"/><integer name="width" value="{width}"/>
            <integer name="height" value="{height}"/>{crop}</film>
    </sensor>
    <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="3"/></transform>
        <bsdf type="diffuse"/></shape>
    <shape type="sphere"><point name="center" x="0" y="0.5" z="0"/><float name="radius" value="0.5"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.2, 0.2"/></bsdf></shape>
    <shape type="sphere"><point name="center" x="1" y="2" z="1"/><float name="radius" value="0.3"/>
        <emitter type="area"><rgb name="radiance" value="10, 10, 10"/></emitter></shape>
</scene>"""


def scene_path(tmp_path, rfilter="gaussian", crop=None, scale=1, name="s"):
    """The scene at `scale` times its size, cropped to `crop` (x, y, width, height) times `scale`."""
    text = ""
    if crop is not None:
        text = "".join(f'<integer name="crop_{key}" value="{value * scale}"/>'
                       for key, value in zip(("offset_x", "offset_y", "width", "height"), crop))
    path = tmp_path / f"{name}.xml"
    path.write_text(SCENE.format(rfilter=rfilter, width=WIDTH * scale, height=HEIGHT * scale, crop=text))
    return path


def film(path, spp=3, size=None, integrator=None):
    scene = load_mitsuba_scene(path)
    renderer = Renderer(scene, size)
    renderer.render(CameraFrame.from_spec(scene.camera), spp, integrator, seed=5)
    f = renderer.film
    return f.mean_image(), f.variance_of_mean_image(), f.sample_counts()


@pytest.mark.parametrize("rfilter", ["box", "tent", "gaussian"])
def test_a_crop_is_the_same_window_of_the_whole_render_bit_for_bit(tmp_path, rfilter):
    whole = film(scene_path(tmp_path, rfilter))
    # the top-left and bottom-right corners: each window has two edges on the image's, two inside it
    for x, y, w, h in ((0, 0, 10, 7), (14, 9, 10, 7)):
        crop = film(scene_path(tmp_path, rfilter, (x, y, w, h)))
        assert crop[0].shape == (h, w, 3)
        for cropped, full in zip(crop, whole):
            np.testing.assert_array_equal(cropped, full[y:y + h, x:x + w])


def test_a_film_twice_the_crops_size_is_the_crop_of_the_image_at_twice_its_size(tmp_path):
    window = (5, 3, 10, 7)
    scaled = film(scene_path(tmp_path, crop=window), size=(20, 14))  # as the viewer's film or --size
    doubled = film(scene_path(tmp_path, crop=window, scale=2, name="doubled"))
    for a, b in zip(scaled, doubled):
        np.testing.assert_array_equal(a, b)


def test_focus_probes_the_cropped_films_point_of_the_whole_image(tmp_path):
    camera = CameraFrame.from_spec(load_mitsuba_scene(scene_path(tmp_path)).camera)
    whole = Renderer(load_mitsuba_scene(scene_path(tmp_path)))
    crop = Renderer(load_mitsuba_scene(scene_path(tmp_path, crop=(5, 3, 10, 7), name="crop")))
    # the crop's point (0.5, 0.25) (y up) is the image's (5 + 5) / 24, (16 - 3 - 7 + 1.75) / 16
    near = crop.focus_distance_at(camera, 0.5, 0.25)
    assert near is not None
    assert near == pytest.approx(whole.focus_distance_at(camera, 10 / WIDTH, 7.75 / HEIGHT), rel=1e-5)


def test_a_crop_renders_as_mitsubas(tmp_path):
    mitsuba_or_skip()
    path = scene_path(tmp_path, "box", (5, 3, 12, 9))
    lantern, mitsuba = lantern_image(path, 256), mitsuba_image(path, 64, 8)
    assert lantern[0].shape == mitsuba[0].shape == (9, 12, 3)
    assert_agree(lantern, mitsuba, ("lantern", "mitsuba"), alpha=ALPHA)
