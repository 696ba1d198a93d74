"""Tabulates the directional albedo E(mu, roughness) of a white sheen lobe (renderer/materials/sheen.py):
E(mu_o) = integral over the upper hemisphere of D(h) V(mu_o, mu_i) mu_i d wi, by Gauss-Legendre
quadrature in (cos theta_i, phi) in float64 (the integrand is smooth; the narrowest lobe, at the
smallest roughness, peaks at grazing half vectors and is resolved by refining until two rules
agree to 1e-6). Nodes: uniform in sqrt(mu) and in roughness on [MIN_ROUGHNESS, 1].

Usage: python scripts/make_sheen_albedo_table.py  (writes renderer/materials/data/sheen_albedo.npz)
"""
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from renderer.materials.sheen import MIN_ROUGHNESS, TABLE_FILE, charlie_np, visibility_np  # noqa: E402

SIZE = 32


def albedo(mu_o, roughness, n_mu=256, n_phi=128):
    x, w = np.polynomial.legendre.leggauss(n_mu)
    mu_i = 0.5 * (x + 1.0)
    w_mu = 0.5 * w
    xp, wp = np.polynomial.legendre.leggauss(n_phi)
    phi = 0.5 * np.pi * (xp + 1.0)  # [0, pi], doubled by symmetry
    w_phi = 0.5 * np.pi * wp
    s_o = np.sqrt(max(0.0, 1.0 - mu_o * mu_o))
    s_i = np.sqrt(np.maximum(0.0, 1.0 - mu_i * mu_i))
    # |wo + wi| and (wo + wi).z for every (mu_i, phi)
    hz = mu_o + mu_i[:, None]
    hx = s_o + s_i[:, None] * np.cos(phi)[None, :]
    hy = s_i[:, None] * np.sin(phi)[None, :]
    cos_h = hz / np.sqrt(hx * hx + hy * hy + hz * hz)
    f = charlie_np(cos_h, roughness) * visibility_np(mu_o, mu_i[:, None]) * mu_i[:, None]
    return 2.0 * np.sum(w_mu[:, None] * w_phi[None, :] * f)


def converged_albedo(mu_o, roughness):
    coarse = albedo(mu_o, roughness)
    n = 256
    while True:
        fine = albedo(mu_o, roughness, 2 * n, n)
        if abs(fine - coarse) < 1e-6 or n >= 2048:
            return fine
        coarse, n = fine, 2 * n


def main():
    mu = np.linspace(0.0, 1.0, SIZE) ** 2
    roughness = np.linspace(MIN_ROUGHNESS, 1.0, SIZE)
    table = np.zeros((SIZE, SIZE))
    for i, r in enumerate(roughness):
        for j, m in enumerate(mu):
            table[i, j] = converged_albedo(max(m, 1e-4), r)
        print(f"roughness {r:.3f}: E(1) = {table[i, -1]:.5f}, E(0) = {table[i, 0]:.5f}", flush=True)
    np.savez_compressed(TABLE_FILE, albedo=table.astype(np.float32), mu=mu.astype(np.float32),
                        roughness=roughness.astype(np.float32))
    print(f"wrote {TABLE_FILE}")


if __name__ == "__main__":
    main()
