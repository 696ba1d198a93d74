"""glTF KHR_materials_volume: a transmissive solid absorbs by Beer's law inside.

A unit cube of smooth glass (ior 1.5) with attenuationColor c at attenuationDistance d = 1, seen
head-on through its centre in a white furnace (constant environment of radiance 1), from a camera
with a 1-degree field of view (paths through the cube differ in length by < 1e-4 relative).
Light that crosses it is attenuated by tau = c per unit length; the slab's reflections add up in
closed form at normal incidence (F = ((n - 1) / (n + 1))^2): what the camera sees is the slab's
total reflectance plus its total transmittance, both of the white environment,

    R = F + (1 - F)^2 F tau^2 / (1 - F^2 tau^2),   T = (1 - F)^2 tau / (1 - F^2 tau^2).

(The side faces are never reached by these near-axial paths: a head-on ray stays on the axis.)
Decision: the image mean against R + T by a z-test at ALPHA = 0.01 (per-pixel variance, pixels
independent); without the volume (the same cube, no extension) it must be R + T at tau = 1, i.e. 1.
"""
import json
import math

import numpy as np
import pytest
from scipy import stats

from renderer.camera import CameraFrame
from renderer.renderer import Renderer
from tests.data import make_test_models as mtm
from tests.scene_builder import scene_from_toml
from tests.stats.image_tests import mean_z

ALPHA = 0.01
IOR = 1.5
COLOUR = (0.5, 0.25, 0.8)


def cube_document(volume: bool) -> dict:
    b = mtm.BufferBuilder()
    positions, normals, indices = mtm.cube_arrays()
    extensions = {"KHR_materials_transmission": {"transmissionFactor": 1.0}, "KHR_materials_ior": {"ior": IOR}}
    if volume:
        extensions["KHR_materials_volume"] = {"thicknessFactor": 1.0, "attenuationDistance": 1.0,
                                              "attenuationColor": list(COLOUR)}
    material = {"name": "glass", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0.0,
                                                           "roughnessFactor": 0.0}, "extensions": extensions}
    return {"asset": {"version": "2.0"}, "extensionsUsed": sorted(extensions),
            "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": b.accessor(positions),
                                                       "NORMAL": b.accessor(normals)},
                                        "indices": b.accessor(indices), "material": 0}]}],
            "materials": [material], "accessors": b.accessors, "bufferViews": b.views,
            "buffers": mtm.data_uri_buffer(b)}


def expected(tau):
    f = ((IOR - 1.0) / (IOR + 1.0)) ** 2
    denominator = 1.0 - f * f * tau * tau
    return f + (1.0 - f) ** 2 * f * tau * tau / denominator + (1.0 - f) ** 2 * tau / denominator


@pytest.mark.parametrize("volume", [True, False], ids=["volume", "no volume"])
def test_beer_lambert_through_a_glass_cube(tmp_path, volume):
    (tmp_path / "cube.gltf").write_text(json.dumps(cube_document(volume)))
    scene = scene_from_toml(tmp_path, """
        [scene]
        geometry = "mesh"
        [camera]
        position = [0.0, 0.0, 4.0]
        look_at = [0.0, 0.0, 0.0]
        fov = 1.0
        [render]
        width = 8
        height = 8
        max_depth = -1
        [environment]
        type = "constant"
        color = [1.0, 1.0, 1.0]
        [[objects]]
        type = "mesh"
        file = "cube.gltf"
        """)
    r = Renderer(scene)
    assert r.features().has_media == volume  # the volume is an absorbing medium, only where one is declared
    r.render(CameraFrame.from_spec(scene.camera), 256, integrator="path")
    mean, var = r.film.mean_image(), r.film.variance_of_mean_image()
    for channel, c in enumerate(COLOUR):
        target = expected(c if volume else 1.0)
        # Rounding of the path weights is added (a nearly deterministic estimate: see test_glass_furnace).
        z = mean_z(mean, var + (1e-5 * target) ** 2, target, channel=channel)
        assert 2.0 * stats.norm.sf(abs(z)) >= ALPHA, (channel, mean[..., channel].mean(), target, z)
    if volume:
        assert not math.isclose(expected(COLOUR[1]), 1.0, abs_tol=0.1)  # the test can tell absorption apart
