"""The pixel (reconstruction) filter: where in and around its pixel a camera sample lands, and its
weight. A film setting of every scene (render.pixel_filter), honoured by `render` and the viewer.

box       the sample lands uniformly in its pixel, weight 1 (Lantern's default; Mitsuba's `box`).
tent      f(x) = max(0, 1 - |x| / radius) per axis (Mitsuba's `tent`, radius 1 by default).
gaussian  f(x) = max(0, exp(-x^2 / 2 s^2) - exp(-R^2 / 2 s^2)) with R = 4 s (Mitsuba's default
          filter, s = 0.5 pixel).

Filter importance sampling: the offset from the pixel's centre is drawn with a density p and the
sample weighted by f / (p * integral of f), so each pixel's mean estimates the filtered image
integral(f L) / integral(f) exactly, the per-pixel running mean and variance of the film stay what
they are, and pixels stay independent (Mitsuba splats each sample over its neighbours, a ratio
estimator with the same limit). Both filters are sampled exactly, so every sample weighs 1 (away
from the image's edges): a flat image stays exactly flat, as under Mitsuba's splatting. The tent by
its inverse CDF; the Gaussian by rejection: normals of deviation s (Box-Muller), each axis accepted
with probability (g(x) - bias) / g(x) inside R (over 0.997 within 2 s; a pair is rejected about
once in 440), a redraw taking its uniforms from a hash of the sample's own.
"""
import taichi as ti

from renderer.sampling.rng import pcg_hash, uniform

GAUSSIAN_TRIES = 16  # redraws of a rejected Gaussian offset (all rejected: about once in 10^45)


@ti.func
def _tent_offset(u, radius):
    """The inverse of the tent's CDF on [-radius, radius]."""
    x = 0.0
    if u < 0.5:
        x = radius * (ti.sqrt(2.0 * u) - 1.0)
    else:
        x = radius * (1.0 - ti.sqrt(2.0 - 2.0 * u))
    return x


@ti.func
def _gaussian_acceptance(x, key: ti.template()):
    """f(x) / g(x) for one axis: the windowed Gaussian over the untruncated one (0 beyond R)."""
    s, r, bias = ti.static(key[1], key[2], key[3])
    a = 0.0
    if ti.abs(x) < r:
        a = 1.0 - bias / ti.exp(-x * x / (2.0 * s * s))
    return a


@ti.func
def _normal_pair(u, s):
    """Two independent normals of deviation s from one 2D sample (Box-Muller)."""
    radius = s * ti.sqrt(-2.0 * ti.log(ti.max(1.0 - u.x, 1e-12)))
    angle = 2.0 * 3.141592653589793 * u.y
    return ti.math.vec2(radius * ti.cos(angle), radius * ti.sin(angle))


@ti.func
def _gaussian_offset(u, key: ti.template()):
    """(an offset distributed as the windowed Gaussian on both axes, 1; or 0, 0 if every redraw was
    rejected)."""
    offset = _normal_pair(u, ti.static(key[1]))
    h = pcg_hash(ti.bit_cast(u.x, ti.u32) ^ pcg_hash(ti.bit_cast(u.y, ti.u32)))
    found = 0.0
    for attempt in range(GAUSSIAN_TRIES + 1):
        if uniform(h, 3 * attempt) < _gaussian_acceptance(offset.x, key) * _gaussian_acceptance(offset.y, key):
            found = 1.0
            break
        offset = _normal_pair(ti.math.vec2(uniform(h, 3 * attempt + 1), uniform(h, 3 * attempt + 2)),
                              ti.static(key[1]))
    return offset, found


@ti.func
def _edge_factor(offset, i, n, tails: ti.template()):
    """For pixel i of n along an axis: 0 where the sample lands outside the image, else the factor
    that renormalises the filter cut at the image's edges (1 away from them, and for a pixel outside
    the image, which only a viewer showing a crop window beyond the image has: it has no edge)."""
    factor = 1.0
    if i < 0 or i >= n:
        factor = 1.0
    elif offset < -(i + 0.5) or offset > (n - i) - 0.5:
        factor = 0.0
    else:
        cut = 0.0
        for d in ti.static(range(len(tails))):
            if i == d:
                cut += tails[d]
            if n - 1 - i == d:
                cut += tails[d]
        factor = 1.0 / (1.0 - cut)
    return factor


@ti.func
def pixel_sample(u, x, y, width, height, key: ti.template()):
    """(position in pixel (x, y)'s own [0, 1)^2 frame, which may lie outside it; the sample's weight)
    from a uniform 2D sample `u`, for an image of width x height pixels."""
    position = u
    weight = 1.0
    if ti.static(key[0] == "tent"):
        offset = ti.math.vec2(_tent_offset(u.x, key[1]), _tent_offset(u.y, key[1]))
        position = 0.5 + offset
        weight = _edge_factor(offset.x, x, width, key[2]) * _edge_factor(offset.y, y, height, key[2])
    elif ti.static(key[0] == "gaussian"):
        offset, found = _gaussian_offset(u, key)
        position = 0.5 + offset
        weight = found * _edge_factor(offset.x, x, width, key[4]) * _edge_factor(offset.y, y, height, key[4])
    return position, weight
