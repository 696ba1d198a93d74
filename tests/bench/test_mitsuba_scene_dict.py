"""renderer/bench/mitsuba_scene_dict.py's environment, through which `compare` gives a TOML scene to
Mitsuba: a map keeps its orientation as the envmap's to_world, a turn about +y and any other."""
from types import SimpleNamespace

import numpy as np
import pytest

from renderer.bench.mitsuba_scene_dict import _environment
from renderer.scene.description import EnvironmentSpec

mi = pytest.importorskip("mitsuba", reason="Mitsuba is the project's optional `reference` extra")


@pytest.mark.parametrize("spec", [
    EnvironmentSpec(kind="map", file="sky.exr", rotation=30.0),
    EnvironmentSpec(kind="map", file="sky.exr", rotation=30.0, rotation_axis=(0.0, -1.0, 0.0)),
    EnvironmentSpec(kind="map", file="sky.exr", rotation=50.0, rotation_axis=(0.6, 0.0, 0.8)),
], ids=["about +y", "about -y", "tilted"])
def test_a_map_keeps_its_orientation(spec):
    mi.set_variant("scalar_rgb")
    envmap = _environment(SimpleNamespace(environment=spec), mi.ScalarTransform4f)
    assert envmap["type"] == "envmap" and envmap["filename"] == "sky.exr"
    np.testing.assert_allclose(np.array(envmap["to_world"].matrix)[:3, :3], spec.rotation_matrix(), atol=1e-6)
