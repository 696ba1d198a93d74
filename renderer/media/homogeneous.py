"""A homogeneous participating medium in RGB: transmittance and free-flight sampling, plus the
exponential-fog blend (a named approximation, not a medium).

Coefficients are per metre, one per RGB channel: sigma_a (absorption), sigma_s (scattering),
sigma_t = sigma_a + sigma_s (extinction).

transmittance(sigma_t, d) = exp(-sigma_t d).

sample_distance(sigma_a, sigma_s, t_max, u_channel, u_dist): free-flight sampling with spectral
MIS over the channels, as pbrt-v3's HomogeneousMedium::Sample does it. A channel c is picked
uniformly (u_channel), a distance drawn from its exponential, t = -ln(1 - u_dist) / sigma_t[c],
and the sample is weighted against the *average* of the three channels' densities (the one-sample
balance heuristic), so no channel's estimate blows up where another channel's density is small:

* t < t_max, a scattering event at t: pdf = mean_c(sigma_t[c] Tr_c(t)),
  weight = sigma_s Tr(t) / pdf (the phase function and what lies beyond multiply it later);
* otherwise the ray reaches t_max (the surface): P = mean_c(Tr_c(t_max)),
  weight = Tr(t_max) / P.

For a grey medium the weights are exactly sigma_s / sigma_t (the albedo) and 1. E[weight] over
both cases integrates sigma_s Tr over [0, t_max) plus Tr(t_max): the test checks both parts
against their closed forms. A channel with sigma_t = 0 never scatters (t = t_max). t_max may be
infinite (a ray leaving the scene): it is clamped to 3e38 so that 0 * t_max stays 0 and the
weights stay finite (the surface weight is then 0 wherever sigma_t > 0).

exponential_fog(colour, fog_colour, density, distance) = mix(fog_colour, colour,
exp(-density distance)): the classic "exponential fog" (OpenGL's GL_EXP mode) of real-time
renderers. It is the exact solution of a homogeneous medium of extinction `density` only under a
strong assumption: the radiance scattered toward the eye is the same constant `fog_colour` at
every point of the ray (a uniform ambient in-scattering field, no shadows, no lights, no phase
function, no multiple scattering that depends on geometry). Cheap and stable, but not
energy-consistent with the path-traced media above; use it as a look, not as a measurement.
"""
from __future__ import annotations

import numpy as np
import taichi as ti

vec3 = ti.math.vec3
T_MAX_CLAMP = 3.0e38  # < f32 max (3.4e38): a finite stand-in for an infinite t_max

MediumSample = ti.types.struct(t=ti.f32, scattered=ti.i32, weight=vec3)


@ti.func
def transmittance(sigma_t, distance):
    return ti.exp(-sigma_t * distance)


@ti.func
def sample_distance(sigma_a, sigma_s, t_max, u_channel, u_dist):
    """A MediumSample: the distance t along the ray (t_max if no scattering happened before it),
    whether it scatters, and its weight (see the module doc). u_channel, u_dist in [0, 1)."""
    sigma_t = sigma_a + sigma_s
    tm = ti.min(t_max, T_MAX_CLAMP)
    channel = ti.min(ti.cast(u_channel * 3.0, ti.i32), 2)
    st = sigma_t[channel]
    t = tm
    if st > 0.0:
        t = ti.min(-ti.log(1.0 - u_dist) / st, tm)  # 1 - u_dist in (0, 1]: the log is finite
    scattered = 0
    if t < tm:
        scattered = 1
    tr = ti.exp(-sigma_t * t)
    density = tr
    if scattered:
        density = sigma_t * tr
    pdf = (density[0] + density[1] + density[2]) / 3.0
    weight = vec3(0.0)
    if pdf > 0.0:  # 0 only where every channel's transmittance underflowed: the weight is 0 too
        weight = tr / pdf
        if scattered:
            weight *= sigma_s
    return MediumSample(t=t, scattered=scattered, weight=weight)


@ti.func
def exponential_fog(colour, fog_colour, density, distance):
    """mix(fog_colour, colour, exp(-density distance)): a named approximation, see the module doc."""
    f = ti.exp(-density * distance)
    return fog_colour + (colour - fog_colour) * f


# --- numpy references (float64) -----------------------------------------------------------------


def transmittance_np(sigma_t, distance):
    return np.exp(-np.asarray(sigma_t, np.float64) * np.asarray(distance, np.float64)[..., None])


def sample_distance_np(sigma_a, sigma_s, t_max, u_channel, u_dist):
    """(t (N,), scattered (N,) bool, weight (N, 3)) for u_channel, u_dist (N,)."""
    sigma_s = np.asarray(sigma_s, np.float64)
    sigma_t = np.asarray(sigma_a, np.float64) + sigma_s
    channel = np.minimum((np.asarray(u_channel) * 3).astype(np.int64), 2)
    st = sigma_t[channel]
    with np.errstate(divide="ignore"):
        t = np.where(st > 0.0, np.minimum(-np.log1p(-np.asarray(u_dist, np.float64)) / st, t_max), t_max)
    scattered = t < t_max
    tr = np.exp(-sigma_t[None, :] * t[:, None])
    density = np.where(scattered[:, None], sigma_t[None, :] * tr, tr)
    pdf = density.mean(axis=1)
    weight = np.where(scattered[:, None], sigma_s[None, :] * tr, tr) / np.where(pdf > 0.0, pdf, 1.0)[:, None]
    return t, scattered, weight


def exponential_fog_np(colour, fog_colour, density, distance):
    f = np.exp(-np.asarray(density, np.float64) * np.asarray(distance, np.float64))
    return np.asarray(fog_colour, np.float64) + (np.asarray(colour, np.float64) - fog_colour) * f
