"""Tabulates the energy a single-scattering rough dielectric interface reflects and transmits, for
the multiple-scattering compensation of renderer/materials/dielectric_energy.py.

For an interface with relative index eta (n on the far side / n on wo's side) and GGX roughness r,
R(mu) and T(mu) are the expected weights of the renderer's own sampler (lobes.dielectric_sample,
tint 1) for reflection and for transmission, the latter counted in energy units: the sampler's
transmission weight carries the radiance scaling 1 / eta^2, so T sums weight * eta^2. What a white
interface loses by single scattering is then 1 - R(mu) - T(mu).

Both sides of one interface share a row: side 0 is wo outside (eta = ior), side 1 wo inside
(eta = 1 / ior). Nodes are uniform in sqrt(mu), in sqrt(roughness) and in x = (ior - 1) / (ior + 1)
(the square root of the reflectance at normal incidence) over ior in [1, 4], the range scene files
allow. Roughness 0 is the smooth interface (R = F, T = 1 - F, nothing lost).

The expectation runs over a midpoint grid of the sampler's three uniforms (the lobe choice and the
visible normal); Taichi does the sums (f32 partial sums over rows, added in float64 here), which
keeps the table's own error near 1e-5, below the error of interpolating it (tests/materials check
both against an independent quadrature).

Usage: python scripts/make_dielectric_albedo_table.py  (writes renderer/materials/data/dielectric_albedo.npz)
"""
import sys
import time
from pathlib import Path

import numpy as np
import taichi as ti

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from renderer.materials import lobes  # noqa: E402
from renderer.materials import microfacet as mf  # noqa: E402

MU_NODES = 32
ROUGHNESS_NODES = 32
IOR_NODES = 16
MAX_IOR = 4.0
GRID = 384  # midpoints per visible-normal uniform; the lobe choice uses the Fresnel weight exactly
OUT = Path(__file__).resolve().parent.parent / "renderer" / "materials" / "data" / "dielectric_albedo.npz"


def nodes():
    mu = np.linspace(0.0, 1.0, MU_NODES) ** 2
    roughness = np.linspace(0.0, 1.0, ROUGHNESS_NODES) ** 2
    x_max = (MAX_IOR - 1.0) / (MAX_IOR + 1.0)
    x = np.linspace(0.0, x_max, IOR_NODES)
    ior = (1.0 + x) / (1.0 - x)
    return mu, roughness, x, ior


@ti.kernel
def tabulate(mu: ti.types.ndarray(), alpha: ti.types.ndarray(), eta: ti.types.ndarray(),
             out_r: ti.types.ndarray(), out_t: ti.types.ndarray()):
    """out_[cell, row] = sum over one row of the uniform grid; cells are (mu, alpha, eta) triples."""
    for cell, row in ti.ndrange(mu.shape[0], GRID):
        m = mu[cell]
        wo = ti.math.vec3(ti.sqrt(ti.max(0.0, 1.0 - m * m)), 0.0, m)
        a = alpha[cell]
        e = eta[cell]
        sum_r = 0.0
        sum_t = 0.0
        u1 = (row + 0.5) / GRID
        for col in range(GRID):
            u2 = (col + 0.5) / GRID
            h = mf.sample_visible_normal(wo, a, ti.math.vec2(u1, u2))
            # Both lobes at once: the sampler picks reflection with probability F, so its expected
            # weight is F * w_reflect + (1 - F) * w_transmit; evaluate both branches here.
            cos_oh = wo.dot(h)
            f, cos_t = mf.fresnel_dielectric(cos_oh, e)
            s_r = lobes.dielectric_sample(ti.math.vec3(1.0), a, e, wo, 0.0, ti.math.vec2(u1, u2))
            s_t = lobes.dielectric_sample(ti.math.vec3(1.0), a, e, wo, 1.0, ti.math.vec2(u1, u2))
            if s_r.valid == 1 and f > 0.0:
                sum_r += f * s_r.weight.x
            if s_t.valid == 1 and f < 1.0:
                sum_t += (1.0 - f) * s_t.weight.x * e * e
        out_r[cell, row] = sum_r / GRID
        out_t[cell, row] = sum_t / GRID


def main():
    ti.init(arch=ti.cpu, default_fp=ti.f32, offline_cache=False)
    mu, roughness, x, ior = nodes()
    r_table = np.zeros((2, ROUGHNESS_NODES, IOR_NODES, MU_NODES))
    t_table = np.zeros_like(r_table)
    # Roughness 0: the smooth interface, exact Fresnel, nothing lost.
    for side in range(2):
        for k, n in enumerate(ior):
            e = n if side == 0 else 1.0 / n
            for j, m in enumerate(mu):
                f = fresnel_np(max(m, 1e-4), e)
                r_table[side, 0, k, j] = f
                t_table[side, 0, k, j] = 1.0 - f
    cells = [(side, i, k, j) for side in range(2) for i in range(1, ROUGHNESS_NODES)
             for k in range(IOR_NODES) for j in range(MU_NODES)]
    mu_a = np.array([max(mu[j], 1e-4) for _, _, _, j in cells], np.float32)
    alpha_a = np.array([max(roughness[i] ** 2, 1e-4) for _, i, _, _ in cells], np.float32)
    eta_a = np.array([max(ior[k], 1.0001) ** (1 if side == 0 else -1) for side, _, k, _ in cells], np.float32)
    start = time.perf_counter()
    batch = 2048
    for b in range(0, len(cells), batch):
        sl = slice(b, b + batch)
        n = len(mu_a[sl])
        out_r = np.zeros((n, GRID), np.float32)
        out_t = np.zeros((n, GRID), np.float32)
        tabulate(mu_a[sl], alpha_a[sl], eta_a[sl], out_r, out_t)
        sums_r = out_r.astype(np.float64).sum(axis=1) / GRID
        sums_t = out_t.astype(np.float64).sum(axis=1) / GRID
        for c, (side, i, k, j) in enumerate(cells[sl]):
            r_table[side, i, k, j] = sums_r[c]
            t_table[side, i, k, j] = sums_t[c]
        print(f"{min(b + batch, len(cells))}/{len(cells)} cells, {time.perf_counter() - start:.0f} s", flush=True)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(OUT, reflect=r_table.astype(np.float32), transmit=t_table.astype(np.float32),
                        mu=mu.astype(np.float32), roughness=roughness.astype(np.float32),
                        x=x.astype(np.float32), grid=np.int32(GRID))
    print(f"wrote {OUT}")


def fresnel_np(cos_i, eta):
    sin2_t = (1.0 - cos_i * cos_i) / (eta * eta)
    if sin2_t >= 1.0:
        return 1.0
    cos_t = np.sqrt(1.0 - sin2_t)
    rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return 0.5 * (rs * rs + rp * rp)


if __name__ == "__main__":
    main()
