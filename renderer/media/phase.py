"""The Henyey-Greenstein phase function.

Convention (pbrt's): both directions point *away* from the scattering point. `wo` points back
toward where the light is going (the camera side, i.e. the reverse of the incoming ray's
direction) and `wi` is the direction the path continues in. cos_theta = dot(wo, wi), so forward
scattering (g > 0) favours wi = -wo, cos_theta = -1:

    p(cos_theta) = (1 - g^2) / (4 pi (1 + g^2 + 2 g cos_theta)^(3/2))

normalised over the sphere (1 / (4 pi) at g = 0). The phase function is its own sampling pdf, so
a sample's weight p / pdf is 1.

Numerics (f32):
* g is clamped to [-G_MAX, G_MAX], G_MAX = 0.9999: at |g| = 1 HG is a delta; at 0.9999 the peak
  (1 + g) / (4 pi (1 - g)^2) = 1.6e7 is still far from overflow.
* The denominator 1 + g^2 + 2 g cos_theta is written as a sum of non-negative terms,
  (1 - |g|)^2 + 2 |g| (1 +- cos_theta), so it does not cancel catastrophically at the peak.
  `hg_phase(g, wo, wi)` goes further and computes 1 +- cos_theta as |wo +- wi|^2 / 2, which is
  accurate even for nearly (anti)parallel unit vectors, where 1 + dot(wo, wi) has lost its digits.
* Sampling inverts the CDF exactly. With t = 1 + g (1 - 2 u) and s = (1 - g^2) / t, the textbook
  inverse gives the propagation cosine mu = dot(-wo, wi) = (1 + g^2 - s^2) / (2 g), which divides
  by g (cancellation as g -> 0) and loses 1 - mu, the quantity that sets the direction near the
  peak, to rounding (absolute error 1e-7: all of it when 1 - mu ~ 1e-6, as for g = 0.99).
  Factoring s^2 - (1 - g)^2 and (1 + g)^2 - s^2 instead gives, with no division by g,
      1 - mu = (1 - g) u (s + 1 - g) / t,      1 + mu = (1 + g) (1 - u) (s + 1 + g) / t,
  products of positive numbers (|g| < 1, t > 0, s > 0) with relative error ~1e-7 for every g,
  g = 0 included (1 - mu = 2 u). t itself is formed as a sum of non-negative terms, and 1 - g^2
  as (1 - g)(1 + g). The sampler
  takes mu from the smaller of the two and sin(theta) from their product. The pdf of the sample
  is t^3 / (4 pi (1 - g^2)^2), which follows from s^2 = 1 + g^2 - 2 g mu without cancellation
  (1 / (4 pi) at g = 0).
"""
from __future__ import annotations

import math

import numpy as np
import taichi as ti

from renderer.sampling.warps import orthonormal_basis

vec3 = ti.math.vec3
INV_4PI = 1.0 / (4.0 * math.pi)
G_MAX = 0.9999


@ti.func
def _clamp_g(g):
    return ti.min(ti.max(g, -G_MAX), G_MAX)


@ti.func
def _hg(g, one_plus, one_minus):
    """HG from 1 + cos_theta and 1 - cos_theta (cos_theta between wo and wi, pbrt convention)."""
    a = 1.0 - ti.abs(g)
    denom = a * a + 2.0 * g * one_plus  # g >= 0: (1 - g)^2 + 2 g (1 + cos)
    if g < 0.0:
        denom = a * a - 2.0 * g * one_minus  # g < 0: (1 + g)^2 + 2 |g| (1 - cos)
    return INV_4PI * (1.0 - g) * (1.0 + g) / (denom * ti.sqrt(denom))


@ti.func
def hg_eval(g, cos_theta):
    """Phase function value = pdf (solid angle) at cos_theta = dot(wo, wi)."""
    c = ti.min(ti.max(cos_theta, -1.0), 1.0)
    return _hg(_clamp_g(g), 1.0 + c, 1.0 - c)


@ti.func
def hg_phase(g, wo, wi):
    """hg_eval for unit directions, accurate at the forward peak (see the module doc)."""
    s = wo + wi
    d = wo - wi
    return _hg(_clamp_g(g), 0.5 * s.dot(s), 0.5 * d.dot(d))


@ti.func
def hg_sample(g, wo, u):
    """(wi, pdf) for unit wo and u in [0, 1)^2. The weight p / pdf is 1."""
    gc = _clamp_g(g)
    # t = 1 + gc v as a sum of non-negative terms: (1 - gc) + 2 gc (1 - u) or (1 + gc) - 2 gc u.
    t = (1.0 - gc) + 2.0 * gc * (1.0 - u[0])
    if gc < 0.0:
        t = (1.0 + gc) - 2.0 * gc * u[0]
    one_minus_g2 = (1.0 - gc) * (1.0 + gc)  # not 1 - gc^2: that loses digits as |g| -> 1
    s = one_minus_g2 / t
    one_minus_mu = (1.0 - gc) * u[0] * (s + 1.0 - gc) / t
    one_plus_mu = (1.0 + gc) * (1.0 - u[0]) * (s + 1.0 + gc) / t
    mu = 1.0 - one_minus_mu
    if one_minus_mu > 1.0:
        mu = one_plus_mu - 1.0
    mu = ti.min(ti.max(mu, -1.0), 1.0)
    sin_t = ti.sqrt(ti.max(0.0, one_minus_mu * one_plus_mu))
    phi = 2.0 * math.pi * u[1]
    forward = -wo
    tx, ty = orthonormal_basis(forward)
    wi = (sin_t * ti.cos(phi)) * tx + (sin_t * ti.sin(phi)) * ty + mu * forward
    pdf = INV_4PI * t * t * t / (one_minus_g2 * one_minus_g2)
    return wi, pdf


# --- numpy references (float64) ---------------------------------------------------------------


def hg_eval_np(g, cos_theta):
    """HG in pbrt's convention, cos_theta = dot(wo, wi)."""
    g = float(np.clip(g, -G_MAX, G_MAX))
    c = np.clip(np.asarray(cos_theta, np.float64), -1.0, 1.0)
    return INV_4PI * (1.0 - g * g) / (1.0 + g * g + 2.0 * g * c) ** 1.5


def hg_sample_np(g, wo, u):
    """(wi (N, 3), pdf (N,)) for unit wo (3,) and u (N, 2): the classic inverse (pbrt-v3), a
    reference for the Taichi version's rearranged arithmetic."""
    g = float(np.clip(g, -G_MAX, G_MAX))
    u = np.asarray(u, np.float64).reshape(-1, 2)
    if abs(g) < 1e-3:
        mu = 1.0 - 2.0 * u[:, 0]
    else:
        s = (1.0 - g * g) / (1.0 + g - 2.0 * g * u[:, 0])
        mu = (1.0 + g * g - s * s) / (2.0 * g)
    mu = np.clip(mu, -1.0, 1.0)
    forward = -np.asarray(wo, np.float64)
    helper = np.array([1.0, 0.0, 0.0]) if abs(forward[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    tx = np.cross(helper, forward)
    tx /= np.linalg.norm(tx)
    ty = np.cross(forward, tx)
    sin_t = np.sqrt(np.maximum(0.0, 1.0 - mu * mu))
    phi = 2.0 * np.pi * u[:, 1]
    wi = (sin_t * np.cos(phi))[:, None] * tx + (sin_t * np.sin(phi))[:, None] * ty + mu[:, None] * forward
    return wi, hg_eval_np(g, -mu)
