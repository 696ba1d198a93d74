"""Direct light at a path vertex, shared by the path tracers (nee, mis) and SPPM's camera pass.

Two strategies find the light arriving at a vertex: a light sample (`sample_direct`) and the
continuation ray the BSDF samples, which may land on an emitter or leave the scene. With `mis`
both count, weighted by the power heuristic (Veach 1997); without it, only the light sample
counts for lights the light sampler can reach, and BSDF-sampled rays count only after the camera
or a delta bounce, which light sampling cannot follow (`emission_weight`, `environment_weight`).
Point, spot and directional lights are found by light samples alone: theirs take weight 1.
"""
import taichi as ti

vec3 = ti.math.vec3


@ti.func
def power_heuristic(a, b):
    """a^2 / (a^2 + b^2), written through the ratio of the smaller to the larger density so that
    an infinite or overflowing density (a light seen exactly edge-on) gives 1 or 0, never inf/inf."""
    w = 0.0
    if a >= b and a > 0.0:
        r = b / a
        w = 1.0 / (1.0 + r * r)
    elif b > a:
        r = a / b
        w = r * r / (1.0 + r * r)
    return w


@ti.func
def emission_weight(lights: ti.template(), mis: ti.template(), prev_delta, prev_pdf, prev_p, prev_n, s):
    """The weight of emission that a BSDF-sampled ray from (prev_p, prev_n) finds at surface s."""
    weight = 1.0
    if prev_delta == 0 and lights.is_sampled(s.prim):
        if ti.static(mis):
            weight = power_heuristic(prev_pdf, lights.pdf_hit(prev_p, prev_n, s.prim, s.p, s.n_geo))
        else:
            weight = 0.0
    return weight


@ti.func
def environment_weight(lights: ti.template(), mis: ti.template(), prev_delta, prev_pdf, d):
    """The weight of the environment that a BSDF-sampled ray leaving the scene along d sees."""
    weight = 1.0
    if ti.static(lights.has_env):
        if prev_delta == 0:
            if ti.static(mis):
                weight = power_heuristic(prev_pdf, lights.pdf_env(d))
            else:
                weight = 0.0
    return weight


@ti.func
def light_weight(lights: ti.template(), ls, pdf_other):
    """The MIS weight of light sample ls against the other strategy's density pdf_other: 1 for a
    light without a surface, which no BSDF or phase sample can find."""
    weight = 0.0
    if ti.static(lights.has_delta):
        weight = 1.0
        if ls.delta == 0:
            weight = power_heuristic(ls.pdf, pdf_other)
    else:
        weight = power_heuristic(ls.pdf, pdf_other)
    return weight


@ti.func
def sample_direct(ctx: ti.template(), mis: ti.template(), mat, n, s, wo, u_select, u_point):
    """A light sample for the vertex s (material mat, shading normal n) seen from wo:
    (found, the light sample, f, weight / pdf). found is False when it carries nothing (no
    density, no radiance, or f = 0); else its contribution, before visibility, is
    throughput * f * radiance * (weight / pdf)."""
    ls = ctx.lights.sample(ctx, s.p, n, u_select, u_point)
    found = False
    f = vec3(0.0)
    scale = 0.0
    if ls.pdf > 0.0 and ls.radiance.max() > 0.0:
        f, pdf_bsdf = ctx.bsdf.eval_at(mat, n, s.n_geo, wo, ls.wi)
        if f.max() > 0.0:
            found = True
            weight = 1.0
            if ti.static(mis):
                weight = light_weight(ctx.lights, ls, pdf_bsdf)
            scale = weight / ls.pdf
    return found, ls, f, scale
