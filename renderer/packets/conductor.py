"""Rough conductors in lane arithmetic: isotropic GGX with height-correlated Smith masking, visible
normals sampled as Heitz (2018) does, and the material's Fresnel, as the scalar conductor kind has
them (materials/conductor.py); where the scene compensates energy, Kulla and Conty's
multiple-scattering lobe as Bsdf.metal_eval adds it (its tables read lane by lane), sampled with
the same share of cosine-weighted directions. Lanes on other conductors (a delta mirror, another
microfacet model, anisotropic widths) stay with the scalar BSDF (renderer/packets/path.py decides).

An isotropic lobe depends only on angles to its normal, so the value and density are computed
from world-space dot products; sin^2 comes from a cross product, not 1 - cos^2, which would cancel
for the narrow lobes of nearly smooth metals. Only sampling needs a frame (lanes.basis).
"""
import taichi as ti

from renderer.materials import lobes
from renderer.materials import microfacet as mf
from renderer.materials.energy import MIN_LOSS
from renderer.packets.lanes import PI, basis, cosine_hemisphere, dot, mask, normalized, sincos_2pi
from renderer.packets.shading_normals import sides_agree
from renderer.sampling.warps import INV_PI


@ti.func
def _reflectance(table: ti.template(), material, cos_i, average: ti.template()):
    """Per lane, lobes.conductor_reflectance of its material row at cos_i or (average) its
    cosine-weighted mean, lobes.conductor_reflectance_average: (r, g, b) lanes."""
    fr, fg, fb = cos_i * 0.0, cos_i * 0.0, cos_i * 0.0
    for k in ti.static(range(cos_i.n)):
        row = table[material[k]]
        f = ti.math.vec3(0.0)
        if ti.static(average):
            if row.complex_ior == 1:
                f = row.fresnel_avg
            else:
                f = lobes.conductor_fresnel_average(row.base_color, row.edge_tint)
        else:
            if row.complex_ior == 1:
                f = mf.fresnel_conductor(cos_i[k], row.eta, row.k)
            else:
                f = lobes.conductor_fresnel(cos_i[k], row.base_color, row.edge_tint)
        f *= row.specular_color
        fr[k], fg[k], fb[k] = f.x, f.y, f.z
    return fr, fg, fb


@ti.func
def fresnel(table: ti.template(), material, cos_i):
    """lobes.conductor_reflectance of each lane's material row at cos_i: (r, g, b) lanes."""
    return _reflectance(table, material, cos_i, False)


@ti.func
def fresnel_average(table: ti.template(), material, like):
    """lobes.conductor_reflectance_average of each lane's material row: (r, g, b) lanes."""
    return _reflectance(table, material, like, True)


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


def compensates(energy) -> bool:
    """Whether the lanes add the multiple-scattering lobe: energy is the scene's GgxAlbedo tables,
    or None (a compile-time choice)."""
    return energy is not None


@ti.func
def _albedo(energy: ti.template(), mu, roughness):
    """E(mu, roughness) of the GGX table, lane by lane."""
    e = mu * 0.0
    for k in ti.static(range(mu.n)):
        e[k] = energy.albedo(mu[k], roughness[k])
    return e


@ti.func
def sampling_share(energy: ti.template(), alpha, cos_o):
    """The chance of a cosine-weighted direction (the multiple-scattering lobe's energy when F = 1),
    energy.sampling_share lane by lane; 0 without compensation (energy None)."""
    share = cos_o * 0.0
    if ti.static(compensates(energy)):
        share = ti.math.clamp(1.0 - _albedo(energy, cos_o, ti.sqrt(alpha)), 0.0, 1.0)
    return share


@ti.func
def _evaluate(table: ti.template(), energy: ti.template(), material, alpha, wx, wy, wz, fx, fy, fz, ox, oy, oz):
    """The kind's f cos (rgb) and density toward w, before the sides rule: single scattering, plus
    the multiple-scattering lobe where energy (a GgxAlbedo) is given."""
    cos_o = dot(ox, oy, oz, fx, fy, fz)
    cos_i = dot(wx, wy, wz, fx, fy, fz)
    hx, hy, hz = normalized(ox + wx, oy + wy, oz + wz)
    cos_oh = dot(ox, oy, oz, hx, hy, hz)
    cos_h = dot(hx, hy, hz, fx, fy, fz)
    safe_alpha = ti.max(alpha, 1e-30)
    d = _ggx_d(cos_h, _sin2(hx, hy, hz, fx, fy, fz), safe_alpha)
    lambda_o = _smith_lambda(cos_o, _sin2(ox, oy, oz, fx, fy, fz), safe_alpha)
    lambda_i = _smith_lambda(cos_i, _sin2(wx, wy, wz, fx, fy, fz), safe_alpha)
    seen = (cos_o > 0.0) & (cos_i > 0.0)
    reflects = seen & (alpha > 0.0) & (cos_oh > 0.0)
    fr, fg, fb = fresnel(table, material, cos_oh)
    scale = ti.select(reflects, d / ((1.0 + lambda_o + lambda_i) * 4.0 * cos_o), 0.0)
    pdf = ti.select(reflects, d / ((1.0 + lambda_o) * 4.0 * cos_o), 0.0)
    vr, vg, vb = fr * scale, fg * scale, fb * scale
    if ti.static(compensates(energy)):
        roughness = ti.sqrt(alpha)
        loss_o = ti.math.clamp(1.0 - _albedo(energy, cos_o, roughness), 0.0, 1.0)
        loss_i = 1.0 - _albedo(energy, cos_i, roughness)
        e_avg = cos_o * 0.0
        for k in ti.static(range(cos_o.n)):
            e_avg[k] = energy.average(roughness[k])
        ar, ag, ab = fresnel_average(table, material, cos_o)
        ms = ti.select(seen, loss_o * loss_i / ti.max(1.0 - e_avg, MIN_LOSS) * INV_PI * cos_i, 0.0)
        vr += ar * ar * e_avg / (1.0 - ar * (1.0 - e_avg)) * ms
        vg += ag * ag * e_avg / (1.0 - ag * (1.0 - e_avg)) * ms
        vb += ab * ab * e_avg / (1.0 - ab * (1.0 - e_avg)) * ms
        pdf = (1.0 - loss_o) * pdf + loss_o * ti.select(seen, cos_i * INV_PI, 0.0)
    return vr, vg, vb, pdf


@ti.func
def toward(table: ti.template(), energy: ti.template(), material, alpha, wx, wy, wz, fx, fy, fz, snx, sny, snz, nx,
           ny, nz, ox, oy, oz):
    """f cos (rgb lanes) and the density of `sample` toward the directions w; o: toward the
    viewer; f: the lobe's normal (the shading normal on o's side); n: the geometric normal;
    energy: the GGX albedo tables where the scene compensates energy, else None."""
    vr, vg, vb, pdf = _evaluate(table, energy, material, alpha, wx, wy, wz, fx, fy, fz, ox, oy, oz)
    lit = sides_agree(snx, sny, snz, nx, ny, nz, ox, oy, oz, wx, wy, wz) == 1
    return ti.select(lit, vr, 0.0), ti.select(lit, vg, 0.0), ti.select(lit, vb, 0.0), pdf


@ti.func
def _visible_normal_reflection(alpha, v1, v2, fx, fy, fz, ox, oy, oz):
    """wo reflected about a visible normal drawn from (v1, v2), Heitz 2018 in the lobe's frame:
    (wi xyz, the normal's cosine to f, its sin^2, cos(wo, h), cos(wo, f))."""
    tx, ty, tz, bx, by, bz = basis(fx, fy, fz)
    lx, ly, lz = dot(ox, oy, oz, tx, ty, tz), dot(ox, oy, oz, bx, by, bz), dot(ox, oy, oz, fx, fy, fz)
    # the hemisphere of the stretched view direction vh
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
    return wx, wy, wz, hlz, hlx * hlx + hly * hly, cos_oh, lz


@ti.func
def sample(table: ti.template(), energy: ti.template(), material, alpha, lobe, v1, v2, fx, fy, fz, snx, sny, snz, nx,
           ny, nz, ox, oy, oz):
    """A direction per lane from the lobe choice `lobe` and (v1, v2): (x, y, z, weight rgb,
    density, valid mask). Without compensation (energy None) a visible normal's reflection, whose
    weight F G2 / G1(wo) needs no evaluation; with it, a cosine-weighted direction with the
    multiple-scattering lobe's share, and the weight f cos / pdf of the whole lobe (as the scalar
    conductor kind samples)."""
    wx, wy, wz, cos_h, sin2_h, cos_oh, cos_o = _visible_normal_reflection(alpha, v1, v2, fx, fy, fz, ox, oy, oz)
    cos_i = dot(wx, wy, wz, fx, fy, fz)
    wr, wg, wb, pdf = cos_o * 0.0, cos_o * 0.0, cos_o * 0.0, cos_o * 0.0
    valid = (cos_i > 0.0) & (alpha > 0.0) & (cos_o > 0.0)
    if ti.static(compensates(energy)):
        share = sampling_share(energy, alpha, cos_o)
        cx, cy, cz, cos_t = cosine_hemisphere(v1, v2, fx, fy, fz)
        diffuse = lobe < share
        wx, wy, wz = ti.select(diffuse, cx, wx), ti.select(diffuse, cy, wy), ti.select(diffuse, cz, wz)
        cos_i = ti.select(diffuse, cos_t, cos_i)
        vr, vg, vb, pdf = _evaluate(table, energy, material, alpha, wx, wy, wz, fx, fy, fz, ox, oy, oz)
        inv = 1.0 / ti.select(pdf > 0.0, pdf, 1.0)
        wr, wg, wb = vr * inv, vg * inv, vb * inv
        broken = mask(pdf < 0.0)  # a numerically broken weight ends the path (Bsdf.sample's bit test)
        for k in ti.static(range(cos_o.n)):
            br, bg, bb = ti.bit_cast(wr[k], ti.i32), ti.bit_cast(wg[k], ti.i32), ti.bit_cast(wb[k], ti.i32)
            if (br & 0x7F800000) == 0x7F800000 or (bg & 0x7F800000) == 0x7F800000 or \
                    (bb & 0x7F800000) == 0x7F800000:
                broken[k] = 1
        valid = (cos_i > 0.0) & (alpha > 0.0) & (cos_o > 0.0) & (pdf > 0.0) & (broken == 0)
    else:
        safe_alpha = ti.max(alpha, 1e-30)
        lambda_o = _smith_lambda(cos_o, _sin2(ox, oy, oz, fx, fy, fz), safe_alpha)
        lambda_i = _smith_lambda(cos_i, _sin2(wx, wy, wz, fx, fy, fz), safe_alpha)
        d = _ggx_d(cos_h, sin2_h, safe_alpha)
        valid &= cos_oh > 0.0
        fr, fg, fb = fresnel(table, material, cos_oh)
        g = (1.0 + lambda_o) / (1.0 + lambda_o + lambda_i)  # G2 / G1(wo)
        wr, wg, wb = fr * g, fg * g, fb * g
        pdf = d / ((1.0 + lambda_o) * 4.0 * ti.max(cos_o, 1e-30))
    valid &= sides_agree(snx, sny, snz, nx, ny, nz, ox, oy, oz, wx, wy, wz) == 1
    return wx, wy, wz, wr, wg, wb, pdf, ti.select(valid, 1, 0)
