"""Rough conductors in lane arithmetic: isotropic GGX with height-correlated Smith masking, visible
normals sampled as Heitz (2018) does, and the material's Fresnel, as lobes.conductor_eval and
conductor_sample have them without energy compensation (pbrt's and Mitsuba's scenes render
without it). Lanes on other conductors (a delta mirror, another microfacet model, compensated
lobes) stay with the scalar BSDF (renderer/packets/path.py decides).

An isotropic lobe depends only on angles to its normal, so the value and density are computed
from world-space dot products; sin^2 comes from a cross product, not 1 - cos^2, which would cancel
for the narrow lobes of nearly smooth metals. Only sampling needs a frame (lanes.basis).
"""
import taichi as ti

from renderer.materials import lobes
from renderer.materials import microfacet as mf
from renderer.materials.table import alpha_of
from renderer.packets.lanes import basis, dot, normalized, sincos_2pi
from renderer.packets.shading_normals import sides_agree

PI = 3.141592653589793


@ti.func
def gather(table: ti.template(), material, like):
    """Per lane, the GGX width of its material row (Bsdf.shade's alpha: 0 for a smooth one);
    `like`: float lanes for the width."""
    alpha = like * 0.0
    for k in ti.static(range(like.n)):
        alpha[k] = alpha_of(table[material[k]].roughness)
    return alpha


@ti.func
def fresnel(table: ti.template(), material, cos_i):
    """lobes.conductor_reflectance of each lane's material row at cos_i: (r, g, b) lanes."""
    fr, fg, fb = cos_i * 0.0, cos_i * 0.0, cos_i * 0.0
    for k in ti.static(range(cos_i.n)):
        row = table[material[k]]
        f = ti.math.vec3(0.0)
        if row.complex_ior == 1:
            f = mf.fresnel_conductor(cos_i[k], row.eta, row.k)
        else:
            f = lobes.conductor_fresnel(cos_i[k], row.base_color, row.edge_tint)
        f *= row.specular_color
        fr[k], fg[k], fb[k] = f.x, f.y, f.z
    return fr, fg, fb


@ti.func
def _sin2(wx, wy, wz, nx, ny, nz):
    """|w x n|^2: sin^2 of the angle between unit w and n, without cancellation near 0."""
    cx = wy * nz - wz * ny
    cy = wz * nx - wx * nz
    cz = wx * ny - wy * nx
    return cx * cx + cy * cy + cz * cz


@ti.func
def _smith_lambda(cos_w, sin2_w, alpha):
    return 0.5 * (ti.sqrt(1.0 + alpha * alpha * sin2_w / ti.max(cos_w * cos_w, 1e-20)) - 1.0)


@ti.func
def _ggx_d(cos_h, sin2_h, alpha):
    a2 = alpha * alpha
    t = sin2_h / a2 + cos_h * cos_h
    return 1.0 / (PI * a2 * t * t)


@ti.func
def toward(table: ti.template(), material, alpha, wx, wy, wz, fx, fy, fz, snx, sny, snz, nx, ny, nz, ox, oy, oz):
    """f cos (rgb lanes) and the density of `sample` toward the directions w; o: toward the
    viewer; f: the lobe's normal (the shading normal on o's side); n: the geometric normal."""
    cos_o = dot(ox, oy, oz, fx, fy, fz)
    cos_i = dot(wx, wy, wz, fx, fy, fz)
    hx, hy, hz = normalized(ox + wx, oy + wy, oz + wz)
    cos_oh = dot(ox, oy, oz, hx, hy, hz)
    cos_h = dot(hx, hy, hz, fx, fy, fz)
    safe_alpha = ti.max(alpha, 1e-30)
    d = _ggx_d(cos_h, _sin2(hx, hy, hz, fx, fy, fz), safe_alpha)
    lambda_o = _smith_lambda(cos_o, _sin2(ox, oy, oz, fx, fy, fz), safe_alpha)
    lambda_i = _smith_lambda(cos_i, _sin2(wx, wy, wz, fx, fy, fz), safe_alpha)
    reflects = (cos_i > 0.0) & (alpha > 0.0) & (cos_oh > 0.0) & (cos_o > 0.0)
    lit = reflects & (sides_agree(snx, sny, snz, nx, ny, nz, ox, oy, oz, wx, wy, wz) == 1)
    fr, fg, fb = fresnel(table, material, cos_oh)
    scale = ti.select(lit, d / ((1.0 + lambda_o + lambda_i) * 4.0 * cos_o), 0.0)
    pdf = ti.select(reflects, d / ((1.0 + lambda_o) * 4.0 * cos_o), 0.0)
    return fr * scale, fg * scale, fb * scale, pdf


@ti.func
def sample(table: ti.template(), material, alpha, v1, v2, fx, fy, fz, snx, sny, snz, nx, ny, nz, ox, oy, oz):
    """A direction per lane from (v1, v2): (x, y, z, weight rgb, density, valid mask)."""
    tx, ty, tz, bx, by, bz = basis(fx, fy, fz)
    lx, ly, lz = dot(ox, oy, oz, tx, ty, tz), dot(ox, oy, oz, bx, by, bz), dot(ox, oy, oz, fx, fy, fz)
    # Heitz 2018 in the lobe's frame: the hemisphere of the stretched view direction vh
    vx, vy, vz = normalized(alpha * lx, alpha * ly, lz)
    lensq = vx * vx + vy * vy
    inv = 1.0 / ti.sqrt(ti.select(lensq > 0.0, lensq, 1.0))
    t1x = ti.select(lensq > 0.0, -vy * inv, 1.0)
    t1y = ti.select(lensq > 0.0, vx * inv, 0.0)
    t2x, t2y, t2z = vy * 0.0 - vz * t1y, vz * t1x, vx * t1y - vy * t1x  # vh x t1 (t1.z = 0)
    r = ti.sqrt(v1)
    s, c = sincos_2pi(v2)
    p1 = r * c
    p2 = r * s
    w = 0.5 * (1.0 + vz)
    p2 = (1.0 - w) * ti.sqrt(ti.max(0.0, 1.0 - p1 * p1)) + w * p2
    up = ti.sqrt(ti.max(0.0, 1.0 - p1 * p1 - p2 * p2))
    mx = p1 * t1x + p2 * t2x + up * vx
    my = p1 * t1y + p2 * t2y + up * vy
    mz = p2 * t2z + up * vz
    hlx, hly, hlz = normalized(alpha * mx, alpha * my, ti.max(1e-6, mz))
    hx = hlx * tx + hly * bx + hlz * fx
    hy = hlx * ty + hly * by + hlz * fy
    hz = hlx * tz + hly * bz + hlz * fz
    cos_oh = dot(ox, oy, oz, hx, hy, hz)
    wx, wy, wz = 2.0 * cos_oh * hx - ox, 2.0 * cos_oh * hy - oy, 2.0 * cos_oh * hz - oz
    cos_i = dot(wx, wy, wz, fx, fy, fz)
    safe_alpha = ti.max(alpha, 1e-30)
    lambda_o = _smith_lambda(lz, _sin2(ox, oy, oz, fx, fy, fz), safe_alpha)
    lambda_i = _smith_lambda(cos_i, _sin2(wx, wy, wz, fx, fy, fz), safe_alpha)
    d = _ggx_d(hlz, hlx * hlx + hly * hly, safe_alpha)
    valid = (cos_i > 0.0) & (cos_oh > 0.0) & (alpha > 0.0) & (lz > 0.0)
    valid &= sides_agree(snx, sny, snz, nx, ny, nz, ox, oy, oz, wx, wy, wz) == 1
    fr, fg, fb = fresnel(table, material, cos_oh)
    g = (1.0 + lambda_o) / (1.0 + lambda_o + lambda_i)  # G2 / G1(wo)
    pdf = d / ((1.0 + lambda_o) * 4.0 * ti.max(lz, 1e-30))
    return wx, wy, wz, fr * g, fg * g, fb * g, pdf, ti.select(valid, 1, 0)
