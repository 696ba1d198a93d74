"""The environment map's direction convention is Mitsuba 3's (renderer/lights/environment.py).

A map with one bright texel: the direction it lights, with and without `rotation`. The expected
directions are written two ways: from Mitsuba's formulas (src/emitters/envmap.cpp: u = atan2(x, -z)
/ 2pi with column centres at (j + 1/2) / W; v = theta / pi with row centres at i / (H - 1)), and as
measured in Mitsuba 3.9.1 itself (scalar_rgb: an 8 x 16 map with one red texel at row 1, column 3,
`envmap` `eval` scanned over directions; its peak at theta / pi = 1/7, u = 0.21875, and with
to_world = rotate([0, 1, 0], 90) at u = 0.96875). Everything here is deterministic.
"""
import math

import numpy as np
import pytest

from renderer.lights.env_sampling import FLOOR, EnvironmentSampler
from renderer.lights.environment import Environment
from renderer.scene.description import EnvironmentSpec

H, W = 8, 16
ROW, COL = 1, 3
MITSUBA_PEAK = {0.0: (1.0 / 7.0, 0.21875), 90.0: (1.0 / 7.0, 0.96875)}  # rotation: (theta / pi, u)


def direction(theta, u):
    """Mitsuba's uv_to_direction: phi = 2 pi u, d = (sin phi sin theta, cos theta, -cos phi sin theta)."""
    phi = 2.0 * math.pi * np.asarray(u, np.float64)
    theta = np.asarray(theta, np.float64)
    return np.stack([np.sin(phi) * np.sin(theta), np.cos(theta) + 0.0 * phi, -np.cos(phi) * np.sin(theta)], axis=-1)


def sampler(rotation=0.0):
    image = np.zeros((H, W, 3), np.float32)
    image[ROW, COL, 0] = 1.0
    return EnvironmentSampler(image, Environment(EnvironmentSpec(kind="map", rotation=rotation), image))


@pytest.mark.parametrize("rotation", sorted(MITSUBA_PEAK))
def test_one_bright_texel_lights_the_direction_mitsuba_gives_it(rotation):
    env = sampler(rotation)
    theta_c = math.pi * ROW / (H - 1)
    u_c = (COL + 0.5) / W - rotation / 360.0  # the map turns by +rotation about +y: azimuth - rotation
    assert (theta_c / math.pi, u_c % 1.0) == pytest.approx(MITSUBA_PEAK[rotation])
    centre = env.radiance_batch(direction([theta_c], [u_c]))[0]
    assert centre[0] == pytest.approx(1.0, abs=1e-5) and centre[1] == centre[2] == 0.0
    # half a texel away in u, and half a row away in theta, the bilinear lookup gives half
    du, dtheta = 0.5 / W, 0.5 * math.pi / (H - 1)
    around = env.radiance_batch(direction([theta_c, theta_c, theta_c - dtheta, theta_c + dtheta],
                                          [u_c - du, u_c + du, u_c, u_c]))[:, 0]
    np.testing.assert_allclose(around, 0.5, atol=1e-4)
    # a fine scan of the sphere peaks at that direction (the old half-texel-shifted rows would
    # put the peak at theta / pi = (ROW + 1/2) / H = 0.1875 instead of 1/7)
    thetas, us = np.meshgrid(np.linspace(0.0, math.pi, 8 * 28 + 1), np.arange(16 * 16) / (16 * 16), indexing="ij")
    values = env.radiance_batch(direction(thetas.ravel(), us.ravel()).astype(np.float32))[:, 0]
    best = np.argmax(values)
    assert thetas.ravel()[best] / math.pi == pytest.approx(MITSUBA_PEAK[rotation][0], abs=1e-9)
    assert us.ravel()[best] == pytest.approx(MITSUBA_PEAK[rotation][1], abs=1e-9)


def test_first_and_last_rows_are_the_poles():
    """Row 0 is the zenith itself and the last row the nadir: straight up sees row 0 only."""
    image = np.zeros((H, W, 3), np.float32)
    image[0] = (1.0, 0.0, 0.0)
    image[-1] = (0.0, 0.0, 2.0)
    env = Environment(EnvironmentSpec(kind="map"), image)
    s = EnvironmentSampler(image, env)
    poles = s.radiance_batch(np.array([[0.0, 1.0, 0.0], [0.0, -1.0, 0.0]], np.float32))
    np.testing.assert_allclose(poles, [[1.0, 0.0, 0.0], [0.0, 0.0, 2.0]], atol=1e-6)


@pytest.mark.parametrize("rotation", [0.0, 90.0, -33.0])
def test_sampler_draws_the_bright_texel_where_it_shines(rotation):
    """The importance sampler draws from the texel's 3 x 3 cells around the same direction (all but
    the floor's share, < 2 FLOOR), and every sample that sees light lies within the bilinear
    footprint: a texel and a row of the centre."""
    env = sampler(rotation)
    d, _, radiance = env.sample_batch(np.random.default_rng(5).random((20_000, 2), dtype=np.float32))
    theta = np.arccos(np.clip(d[:, 1].astype(np.float64), -1, 1))
    u = np.mod(np.arctan2(d[:, 0], -d[:, 2]).astype(np.float64) / (2 * math.pi), 1.0)
    theta_c, u_c = math.pi * ROW / (H - 1), ((COL + 0.5) / W - rotation / 360.0) % 1.0
    dtheta = np.abs(theta - theta_c) / (math.pi / (H - 1))  # in rows
    du = np.abs(np.mod(u - u_c + 0.5, 1.0) - 0.5) * W  # in texels
    assert ((dtheta <= 1.5 + 1e-5) & (du <= 1.5 + 1e-5)).mean() > 1.0 - 2.0 * FLOOR
    lit = radiance[:, 0] > 0
    assert lit.mean() > 0.2 and (dtheta[lit] <= 1.0 + 1e-5).all() and (du[lit] <= 1.0 + 1e-5).all()
