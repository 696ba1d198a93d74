"""A Mitsuba 3 scene whose envmap has a rotation off +y (renderer/lights/environment.py's full
rotation) renders as it should: as the same scene with the map unturned seen by the camera turned
the other way (a rigid turn of everything changes no image), and as Mitsuba 3 renders the file
(when Mitsuba is installed). A diffuse sphere lit by a bright patch of the map tests the importance
sampler and its pdf under MIS; the background tests the lookup.

Statistics: the suite's image rule (tests/stats/image_tests.py: the per-pixel z-test at the 1%
level, Sidak-corrected over the pixels, and the image mean's z-test), fixed seeds. Mitsuba's
variance of the mean comes from the spread of MITSUBA_PASSES independent renders.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from renderer.camera import CameraFrame
from renderer.output.image_io import write_exr
from renderer.renderer import Renderer
from renderer.scene.catalog import load_any
from renderer.scene.description import EnvironmentSpec
from tests.stats.image_tests import assert_agree

SIZE = 16
SPP = 128
MITSUBA_PASSES, MITSUBA_PASS_SPP = 32, 8
TURN = '<rotate x="1" angle="70"/><rotate z="1" angle="30"/>'  # composed as written: Rz(30) Rx(70)
R = (EnvironmentSpec(rotation=30.0, rotation_axis=(0, 0, 1)).rotation_matrix()
     @ EnvironmentSpec(rotation=70.0, rotation_axis=(1, 0, 0)).rotation_matrix())
EYE, TARGET, UP = np.array([0.0, 0.0, 4.0]), np.zeros(3), np.array([0.0, 1.0, 0.0])
PATCH = np.array([0.5, 0.6, 0.8]) / np.linalg.norm([0.5, 0.6, 0.8])  # where the bright patch shines from


def envmap_image(height=32, width=64) -> np.ndarray:
    """A smooth, lopsided gradient plus a bright 3x3 patch of texels placed so that, turned by R,
    it lights the sphere's side that faces the camera from PATCH."""
    v = np.arange(height)[:, None] / (height - 1)
    u = (np.arange(width)[None, :] + 0.5) / width
    image = np.stack([0.3 + 0.5 * v + 0.2 * np.sin(2 * math.pi * u), 0.4 + 0.3 * np.cos(2 * math.pi * u) * (1 - v),
                      0.6 - 0.4 * v + 0 * u], axis=-1)
    local = R.T @ PATCH  # the patch's direction in the map's frame, as Mitsuba's uv
    row = round(math.acos(local[1]) / math.pi * (height - 1))
    col = int(math.atan2(local[0], -local[2]) / (2 * math.pi) % 1.0 * width)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            image[row + dr, (col + dc) % width] = (40.0, 30.0, 20.0)
    return image.astype(np.float32)


def write_scene(folder: Path, name: str, turn: str, eye, target, up) -> Path:
    path = folder / name
    lookat = ", ".join
    path.write_text(f'''<scene version="3.0.0">
        <integrator type="path"><integer name="max_depth" value="3"/></integrator>
        <sensor type="perspective"><float name="fov" value="40"/>
            <transform name="to_world"><lookat origin="{lookat(map(str, eye))}" target="{lookat(map(str, target))}"
                up="{lookat(map(str, up))}"/></transform>
            <sampler type="independent"/>
            <film type="hdrfilm"><rfilter type="box"/><integer name="width" value="{SIZE}"/>
                <integer name="height" value="{SIZE}"/></film></sensor>
        <emitter type="envmap"><string name="filename" value="map.exr"/>
            <transform name="to_world">{turn}</transform></emitter>
        <shape type="sphere"><bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.6, 0.5"/></bsdf></shape>
    </scene>''')
    return path


def lantern(path: Path, seed: int):
    scene = load_any(path)
    renderer = Renderer(scene, (SIZE, SIZE))
    assert renderer.features().environment_rotated == scene.environment.needs_matrix
    renderer.render(CameraFrame.from_spec(scene.camera), SPP, "mis", max_depth=scene.render.max_depth, seed=seed)
    return scene, (renderer.film.mean_image(), renderer.film.variance_of_mean_image())


@pytest.fixture(scope="module")
def turned(taichi_runtime, tmp_path_factory):
    """The scene with the turned map, parsed (no warning) and rendered."""
    folder = tmp_path_factory.mktemp("rotated_envmap")
    write_exr(folder / "map.exr", envmap_image())
    path = write_scene(folder, "turned.xml", TURN, EYE, TARGET, UP)
    scene, image = lantern(path, seed=1)
    assert scene.environment.needs_matrix
    np.testing.assert_allclose(scene.environment.rotation_matrix(), R, atol=1e-12)
    return folder, path, image


def test_a_turned_map_renders_as_the_camera_turned_the_other_way(turned):
    folder, _, image = turned
    mean = image[0]
    # the patch shines from the upper right (+x, +y): that side of the sphere is the brighter
    assert mean[5, 10, 0] > 1.5 * mean[10, 5, 0], (mean[5, 10], mean[10, 5])
    # everything turned by R^T: the map unturned (its to_world the identity), the camera turned back
    back = write_scene(folder, "camera_turned.xml", "", R.T @ EYE, R.T @ TARGET, R.T @ UP)
    scene, other = lantern(back, seed=2)
    assert scene.environment.to_world is None and not scene.environment.needs_matrix
    assert_agree(image, other, ("map turned", "camera turned back"))


def test_a_turned_map_renders_as_in_mitsuba(turned):
    mi = pytest.importorskip("mitsuba", reason="Mitsuba is the project's optional `reference` extra")
    mi.set_variant("scalar_rgb")
    _, path, image = turned
    scene = mi.load_file(str(path))
    passes = np.stack([np.array(mi.render(scene, spp=MITSUBA_PASS_SPP, seed=100 + k), np.float64)[..., :3]
                       for k in range(MITSUBA_PASSES)])
    theirs = (passes.mean(axis=0), passes.var(axis=0, ddof=1) / MITSUBA_PASSES)
    assert_agree(image, theirs, ("Lantern", "Mitsuba"))
