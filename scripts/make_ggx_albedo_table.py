"""Tabulates the directional albedo E(mu, roughness) of a GGX reflector with Fresnel 1 and the
height-correlated Smith term, and its cosine-weighted average E_avg(roughness), for the multiple-
scattering energy compensation of renderer/materials/energy.py (Kulla and Conty 2017).

E(mu) is the expected weight G2(wo, wi) / G1(wo) of a reflection off a visible normal (Heitz 2018)
that stays above the surface. The expectation runs over a midpoint grid of the sampler's two
uniforms (the integrand is smooth in them except at the horizon cut), fine enough that the table
is accurate to about 1e-4, far below the error of interpolating it (tests/materials check both).

Usage: python scripts/make_ggx_albedo_table.py  (writes renderer/materials/data/ggx_albedo.npz)
"""
from pathlib import Path

import numpy as np

SIZE = 32  # nodes in sqrt(mu) and in sqrt(roughness); bilinear lookups between them
GRID = 1024  # midpoints per uniform


def smith_lambda(cos, alpha):
    c2 = np.maximum(cos * cos, 1e-20)
    return 0.5 * (np.sqrt(1.0 + alpha * alpha * (1.0 - c2) / c2) - 1.0)


def albedo(mu, alpha):
    """E(mu) for F = 1 by the midpoint rule over the visible-normal sampler's uniforms."""
    u = (np.arange(GRID) + 0.5) / GRID
    u1, u2 = np.meshgrid(u, u, indexing="ij")
    wo = np.array([np.sqrt(max(0.0, 1.0 - mu * mu)), 0.0, mu])
    # Heitz 2018: stretch, sample the projected disc, unstretch.
    vh = np.array([alpha * wo[0], alpha * wo[1], wo[2]])
    vh /= np.linalg.norm(vh)
    lensq = vh[0] ** 2 + vh[1] ** 2
    t1 = np.array([-vh[1], vh[0], 0.0]) / np.sqrt(lensq) if lensq > 0 else np.array([1.0, 0.0, 0.0])
    t2 = np.cross(vh, t1)
    r = np.sqrt(u1)
    phi = 2.0 * np.pi * u2
    p1 = r * np.cos(phi)
    p2 = r * np.sin(phi)
    s = 0.5 * (1.0 + vh[2])
    p2 = (1.0 - s) * np.sqrt(np.maximum(0.0, 1.0 - p1 * p1)) + s * p2
    p3 = np.sqrt(np.maximum(0.0, 1.0 - p1 * p1 - p2 * p2))
    nh = p1[..., None] * t1 + p2[..., None] * t2 + p3[..., None] * vh
    h = np.stack([alpha * nh[..., 0], alpha * nh[..., 1], np.maximum(1e-9, nh[..., 2])], axis=-1)
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    cos_oh = h @ wo
    wi_z = 2.0 * cos_oh * h[..., 2] - wo[2]
    lam_o = smith_lambda(mu, alpha)
    weight = (1.0 + lam_o) / (1.0 + lam_o + smith_lambda(wi_z, alpha))  # G2 / G1
    return float(np.where(wi_z > 0.0, weight, 0.0).mean())


def main():
    # Nodes uniform in sqrt(mu): E changes fastest near grazing, where the nodes crowd.
    mu_nodes = np.linspace(0.0, 1.0, SIZE) ** 2
    # Also uniform in sqrt(roughness): the grazing dip of a smooth lobe moves fast with roughness.
    roughness_nodes = np.linspace(0.0, 1.0, SIZE) ** 2
    table = np.ones((SIZE, SIZE))  # [roughness, mu]; roughness 0 is a mirror: E = 1
    for i, roughness in enumerate(roughness_nodes[1:], start=1):
        alpha = max(roughness * roughness, 1e-4)
        for j, mu in enumerate(mu_nodes):
            table[i, j] = albedo(max(mu, 1e-4), alpha)  # mu = 0 taken as its limit
        print(f"roughness {roughness:.3f}: E(1) = {table[i, -1]:.5f}, E(0) = {table[i, 0]:.5f}", flush=True)
    out = Path(__file__).resolve().parent.parent / "renderer" / "materials" / "data" / "ggx_albedo.npz"
    np.savez_compressed(out, albedo=table.astype(np.float32), mu=mu_nodes.astype(np.float32),
                        roughness=roughness_nodes.astype(np.float32))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
