"""The directional albedo of a white GGX reflector by quadrature (numpy, float64): the reference
the furnace tests hold the sampler and the energy-compensation table to, written independently
of both."""
import math

import numpy as np


def ggx_albedo_reference(alpha, cos_o, n_u=2048, n_phi=48):
    """Directional albedo E(mu) of a GGX reflector with F = 1 and height-correlated Smith G2, by
    quadrature (numpy, float64), independent of the renderer.

    Half vectors are distributed as D(h) cos(theta_h): tan^2(theta_h) = alpha^2 u / (1 - u) with u
    and phi uniform, so E = E[G2(wo, wi) (wo.h) / (cos_o cos theta_h) ; wi.z > 0]. With wo in the xz
    plane, wi.z = 2 (wo.h) h.z - cos_o > 0 (which implies wo.h > 0) holds exactly for
    cos(phi) > T(theta_h) = -cos_o cos(2 theta_h) / (sin_o sin(2 theta_h)): every phi below
    theta_h = pi/4 - theta_o/2, none above pi/4 + theta_o/2, and |phi| < acos(T) between. So phi
    runs over [0, phi_max] (doubled by symmetry) and u is split at those two angles, where phi_max
    has square-root ends that a cosine substitution smooths; Gauss-Legendre everywhere."""
    theta_o = math.acos(cos_o)
    s_o = math.sin(theta_o)
    u_of = lambda th: math.tan(th) ** 2 / (alpha * alpha + math.tan(th) ** 2)
    u_lo, u_hi = u_of(math.pi / 4 - theta_o / 2), u_of(math.pi / 4 + theta_o / 2)
    x, w = np.polynomial.legendre.leggauss(16)
    pieces = np.linspace(0.0, 1.0, n_u // 16 + 1)
    t = (pieces[:-1, None] + 0.5 * (x[None, :] + 1.0) * np.diff(pieces)[:, None]).ravel()
    wt = (0.5 * w[None, :] * np.diff(pieces)[:, None]).ravel()
    # [0, u_lo]: all phi; [u_lo, u_hi]: u = u_lo + (u_hi - u_lo) (1 - cos(pi t)) / 2
    u = np.concatenate([u_lo * t, u_lo + (u_hi - u_lo) * 0.5 * (1.0 - np.cos(np.pi * t))])
    wu = np.concatenate([u_lo * wt, (u_hi - u_lo) * 0.5 * np.pi * np.sin(np.pi * t) * wt])
    tan2 = alpha * alpha * u / (1.0 - u)
    c_h = 1.0 / np.sqrt(1.0 + tan2)
    s_h = np.sqrt(tan2) * c_h
    with np.errstate(divide="ignore", invalid="ignore"):
        threshold = (cos_o / (2.0 * c_h) - cos_o * c_h) / (s_o * s_h)
    phi_max = np.where(np.arange(len(u)) < len(t), np.pi, np.arccos(np.clip(threshold, -1.0, 1.0)))
    xp, wp = np.polynomial.legendre.leggauss(n_phi)
    phi = phi_max[:, None] * 0.5 * (xp[None, :] + 1.0)
    w_phi = phi_max[:, None] * 0.5 * wp[None, :]
    d = s_o * s_h[:, None] * np.cos(phi) + cos_o * c_h[:, None]  # wo . h
    cos_i = 2.0 * d * c_h[:, None] - cos_o

    def smith_lambda(c):
        c2 = c * c
        return 0.5 * (np.sqrt(1.0 + alpha * alpha * (1.0 - c2) / c2) - 1.0)

    with np.errstate(divide="ignore", invalid="ignore"):
        g = 1.0 / (1.0 + smith_lambda(cos_o) + smith_lambda(cos_i)) * d / (cos_o * c_h[:, None])
    g = np.where(cos_i > 0.0, g, 0.0)
    return float(np.sum(wu * np.sum(w_phi * g, axis=1)) / math.pi)
