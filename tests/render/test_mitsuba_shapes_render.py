"""Mitsuba shapes in whole renders: flip_normals turns a mesh's emitting side over (Mitsuba's area
emitters shine from the front only), on a serialized file and on an instance of a shape group.

The answers do not depend on the random samples: with a box filter and the emitter seen directly,
a pixel wholly on the square shows its radiance exactly, and its back shows black."""
from __future__ import annotations

import numpy as np
import pytest

from renderer.camera import CameraFrame
from renderer.renderer import Renderer
from renderer.scene.mitsuba import load_mitsuba_scene
from tests.scene.serialized_writer import square, write_serialized

SIZE = 16
# An orthographic view of [-1, 1]^2 from z = -5 looking along +z: the square ([0, 1]^2 in z = 0,
# facing +z) fills the pixels of its quarter of the image, seen from behind.
SCENE = """<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="1"/></integrator>
    <sensor type="orthographic">
        <transform name="to_world"><lookat origin="0, 0, -5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><rfilter type="box"/><integer name="width" value="16"/>
            <integer name="height" value="16"/></film>
    </sensor>
    {shapes}
</scene>"""
EMITTER = '<emitter type="area"><rgb name="radiance" value="2, 3, 4"/></emitter>'


def render(tmp_path, shapes: str) -> np.ndarray:
    write_serialized(tmp_path / "square.serialized", [square()])
    path = tmp_path / "scene.xml"
    path.write_text(SCENE.format(shapes=shapes))
    scene = load_mitsuba_scene(path)
    renderer = Renderer(scene)
    renderer.render(CameraFrame.from_spec(scene.camera), 4)
    return renderer.film.mean_image()


def serialized(flip: str) -> str:
    return (f'<shape type="serialized"><string name="filename" value="square.serialized"/>'
            f'<boolean name="flip_normals" value="{flip}"/>{EMITTER}</shape>')


def group_instance(flip: str) -> str:
    return ('<shape type="shapegroup" id="g">' + serialized(flip) + '</shape>'
            '<shape type="instance"><ref id="g"/></shape>')


@pytest.mark.parametrize("shapes", [serialized, group_instance], ids=["serialized", "instance"])
def test_flip_normals_turns_the_emitting_side_to_the_camera(tmp_path, shapes):
    covered = np.zeros((SIZE, SIZE), bool)
    covered[:8, :8] = True  # rows from the top; world +x is the image's left seen from -z
    front = render(tmp_path, shapes("true"))
    np.testing.assert_allclose(front[covered], np.tile((2.0, 3.0, 4.0), (covered.sum(), 1)), rtol=1e-6)
    assert np.all(front[~covered] == 0.0)
    assert np.all(render(tmp_path, shapes("false")) == 0.0)  # its back: nothing
