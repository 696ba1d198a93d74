"""Tangents generated from UV derivatives (renderer/scene/model_formats/tangents.py)."""
from __future__ import annotations

import numpy as np

from renderer.scene.model_formats.tangents import generate_tangents
from tests.data import make_test_models as mtm


def test_generated_tangents_on_a_curved_grid_are_orthonormal_and_follow_u():
    rng = np.random.default_rng(7)
    n = 9
    u, v = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    theta, phi = u * 2.0, 0.4 + v * 1.5  # a patch of a sphere, u around, v down from the pole
    positions = np.stack([np.sin(phi) * np.cos(theta), np.cos(phi), np.sin(phi) * np.sin(theta)], -1)
    positions = positions.reshape(-1, 3) + rng.normal(0, 1e-3, (n * n, 3))
    normals = positions / np.linalg.norm(positions, axis=1, keepdims=True)
    uvs = np.stack([u, v], -1).reshape(-1, 2)
    quads = np.array([[r * n + c, r * n + c + 1, (r + 1) * n + c + 1, (r + 1) * n + c]
                      for r in range(n - 1) for c in range(n - 1)])
    tri = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    t = generate_tangents(positions, normals, uvs, tri)
    assert t.shape == (n * n, 4) and t.dtype == np.float32
    np.testing.assert_allclose(np.linalg.norm(t[:, :3], axis=1), 1.0, atol=1e-5)
    assert np.abs(np.einsum("ij,ij->i", t[:, :3], normals)).max() < 1e-5
    # T points along dP/du (increasing theta): compare with the analytic derivative direction
    dpdu = np.stack([-np.sin(theta), np.zeros_like(theta), np.cos(theta)], -1).reshape(-1, 3)
    assert np.einsum("ij,ij->i", t[:, :3], dpdu).min() > 0.95
    # B = w * cross(N, T) points towards decreasing stored v (towards the pole: +y here)
    b = t[:, 3:] * np.cross(normals, t[:, :3])
    dpdv = np.stack([np.cos(phi) * np.cos(theta), -np.sin(phi), np.cos(phi) * np.sin(theta)],
                    -1).reshape(-1, 3)
    assert np.einsum("ij,ij->i", b, -dpdv).min() > 0.95


def test_generated_tangents_mirrored_and_rotated_uvs():
    positions = mtm.QUAD_POSITIONS.astype(np.float64)
    normals = mtm.QUAD_NORMALS
    tri = mtm.QUAD_INDICES.reshape(-1, 3)
    mirrored = mtm.QUAD_UV0 * [-1.0, 1.0]  # u runs along -x
    t = generate_tangents(positions, normals, mirrored, tri)
    np.testing.assert_allclose(t, [[-1, 0, 0, -1]] * 4, atol=1e-6)
    rotated = mtm.QUAD_UV0[:, ::-1]  # u runs down the quad (-y), v along +x
    t = generate_tangents(positions, normals, rotated, tri)
    np.testing.assert_allclose(t[:, :3], [[0, -1, 0]] * 4, atol=1e-6)
    b = t[:, 3:] * np.cross(normals, t[:, :3])
    np.testing.assert_allclose(b, [[-1, 0, 0]] * 4, atol=1e-6)  # towards decreasing v


def test_generated_tangents_survive_degenerate_uvs():
    positions = mtm.QUAD_POSITIONS
    t = generate_tangents(positions, mtm.QUAD_NORMALS, np.zeros((4, 2)), mtm.QUAD_INDICES.reshape(-1, 3))
    assert np.isfinite(t).all()
    np.testing.assert_allclose(np.linalg.norm(t[:, :3], axis=1), 1.0, atol=1e-6)
    assert np.abs(t[:, :3] @ [0, 0, 1]).max() < 1e-6
