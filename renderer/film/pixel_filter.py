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
estimator with the same limit). The tent is sampled exactly (weight 1); the Gaussian from an
untruncated normal of deviation s (Box-Muller), weighted by (1 - bias / g(x)) * s sqrt(2 pi) / F per
axis inside R and 0 outside (F the integral of the windowed filter).
"""
import taichi as ti


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
def _gaussian_weight(x, key: ti.template()):
    """f(x) / (p(x) * F) for one axis: p the untruncated normal, f the windowed Gaussian."""
    s, r, bias, norm = ti.static(key[1], key[2], key[3], key[4])
    w = 0.0
    if ti.abs(x) < r:
        g = ti.exp(-x * x / (2.0 * s * s))
        w = (1.0 - bias / g) * norm
    return w


@ti.func
def _edge_factor(offset, i, n, tails: ti.template()):
    """For pixel i of n along an axis: 0 where the sample lands outside the image, else the factor
    that renormalises the filter cut at the image's edges (1 away from them)."""
    factor = 1.0
    if offset < -(i + 0.5) or offset > (n - i) - 0.5:
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
        # Box-Muller: two independent normals of deviation s from one 2D sample.
        radius = ti.static(key[1]) * ti.sqrt(-2.0 * ti.log(ti.max(1.0 - u.x, 1e-12)))
        angle = 2.0 * 3.141592653589793 * u.y
        offset = ti.math.vec2(radius * ti.cos(angle), radius * ti.sin(angle))
        position = 0.5 + offset
        weight = (_gaussian_weight(offset.x, key) * _gaussian_weight(offset.y, key)
                  * _edge_factor(offset.x, x, width, key[5]) * _edge_factor(offset.y, y, height, key[5]))
    return position, weight
