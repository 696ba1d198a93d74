"""A camera framed on a model's bounds (renderer/scene/framing.py)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from renderer.scene.framing import frame_camera
from renderer.scene.model_formats import load_mesh_asset
from tests.scene.model_file_helpers import MODELS


def test_frame_camera_fits_the_bounding_sphere():
    bounds = np.array([[-1.0, 0.0, -2.0], [3.0, 2.0, 0.0]])
    position, look_at = frame_camera(bounds, 45.0)
    centre = bounds.mean(axis=0)
    np.testing.assert_allclose(look_at, centre)
    radius = 0.5 * np.linalg.norm(bounds[1] - bounds[0])
    distance = np.linalg.norm(np.subtract(position, centre))
    assert radius / distance == pytest.approx(math.sin(math.radians(22.5)) / 1.1)
    direction = np.subtract(position, centre) / distance
    assert direction[2] > 0.9 and direction[1] > 0  # in front (+z), slightly above
    # a portrait viewport is limited by its horizontal field of view: back off further
    narrow, _ = frame_camera(bounds, 45.0, aspect=0.5)
    assert np.linalg.norm(np.subtract(narrow, centre)) > distance
    # a single point still gives a usable camera
    p, a = frame_camera([[1, 1, 1], [1, 1, 1]], 60.0)
    assert np.linalg.norm(np.subtract(p, a)) > 0


def test_frame_camera_on_bunny():
    asset = load_mesh_asset(MODELS / "bunny.glb")
    position, look_at = frame_camera(asset.bounds, 40.0, aspect=16 / 9)
    assert all(math.isfinite(v) for v in position + look_at)
