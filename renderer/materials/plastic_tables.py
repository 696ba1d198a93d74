"""The host-side numbers of the `plastic` kind (numpy, no Taichi): what Mitsuba 3's plastic and
roughplastic precompute per material, so that a plastic renders as Mitsuba's does.

A plastic is a diffuse base under a dielectric coating of relative index eta. Light reaches the
base through the coating, bounces between base and coating, and leaves through the coating:
  diffuse(wo, wi) = rho / (1 - k) * (T(wo) T(wi) / eta^2) * cos(wi) / pi,
k = Fdr_int (linear, Mitsuba's default) or rho Fdr_int (`nonlinear`: the base's colour deepens,
as in wet or saturated paint), where Fdr_int is the coating's mean internal reflectance and T the
coating's transmittance from outside. Smooth coating: T = 1 - F (the Fresnel reflectance), Fdr_int
from the published fits of Egan and Hilgeman (1973) and d'Eon and Irving (2011), as Mitsuba has
them. Rough coating: T(mu) and the internal reflectance integrate the rough interface (its
microfacet model's transmission with Smith's masking G1 of the outgoing direction), tabulated at
TABLE_SIZE cosines from 0 to 1 and interpolated linearly, like Mitsuba's; the internal reflectance
is Mitsuba's estimate, twice the mean of mu r(mu) over that grid (about 1.5% under the exact
cosine-weighted integral: kept so that Mitsuba scenes render alike).
"""
from __future__ import annotations

import math

import numpy as np

from renderer.materials.kinds import MICROFACET_MODELS as MODELS
from renderer.materials.kinds import alpha_from_roughness

BECKMANN = MODELS["beckmann"]

TABLE_SIZE = 64
_U_NODES = 96  # Gauss-Legendre nodes over the distribution's CDF of tan(theta_m)
_PHI_NODES = 192  # uniform nodes in azimuth (periodic)
_VNDF_NODES = 48  # Gauss-Legendre nodes per axis of GGX's visible-normal square


def fresnel_dielectric(cos_i: np.ndarray, eta: float) -> tuple[np.ndarray, np.ndarray]:
    """Unpolarised Fresnel reflectance for cos_i > 0 and relative index eta (far / near side);
    returns (F, cos_t), F = 1 and cos_t = 0 under total internal reflection."""
    cos_i = np.clip(cos_i, 0.0, 1.0)
    sin2_t = (1.0 - cos_i * cos_i) / (eta * eta)
    cos_t = np.sqrt(np.clip(1.0 - sin2_t, 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):  # cos_i = cos_t = 0 at grazing: F = 1 there
        rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
        rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    f = np.where((sin2_t < 1.0) & (cos_i > 0.0), 0.5 * (rs * rs + rp * rp), 1.0)
    return f, np.where(sin2_t < 1.0, cos_t, 0.0)


def diffuse_fresnel_reflectance(eta: float) -> float:
    """The cosine-weighted mean Fresnel reflectance of an interface of relative index eta, by the
    fits of Egan and Hilgeman 1973 (eta < 1) and d'Eon and Irving 2011 (eta >= 1)."""
    if eta < 1.0:
        return 0.0636 / eta + eta * (eta * -1.4399 + 0.7099) + 0.6681
    x = 1.0 / eta
    return 0.919317 + x * (-3.4793 + x * (6.75335 + x * (-7.80989 + x * (4.98554 - 1.36881 * x))))


def _g1(v: np.ndarray, alpha: float, model: int) -> np.ndarray:
    """Smith's G1 of direction v (..., 3) as the model's masking has it (Beckmann: the rational fit)."""
    xy = np.maximum(v[..., 0] ** 2 + v[..., 1] ** 2, 1e-30)
    tan_alpha2 = alpha * alpha * xy / np.maximum(v[..., 2] ** 2, 1e-30)
    if model == BECKMANN:
        a = 1.0 / np.sqrt(tan_alpha2)
        return np.where(a >= 1.6, 1.0, (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a))
    return 2.0 / (1.0 + np.sqrt(1.0 + tan_alpha2))


def _exact_g1(mu: np.ndarray, alpha: float, model: int) -> np.ndarray:
    """The exact Smith G1 at cos(theta) = mu: what normalises the distribution of visible normals."""
    tan = np.sqrt(np.maximum(1.0 - mu * mu, 0.0)) / mu
    if model != BECKMANN:
        return 2.0 / (1.0 + np.sqrt(1.0 + (alpha * tan) ** 2))
    a = 1.0 / np.maximum(alpha * tan, 1e-30)
    erf = np.vectorize(math.erf)(a)
    lam = np.where(a > 30.0, 0.0, 0.5 * (erf - 1.0) + np.exp(-np.minimum(a * a, 700.0)) / (2.0 * a * math.sqrt(math.pi)))
    return 1.0 / (1.0 + lam)


def _normals(alpha: float, model: int):
    """Microfacet normals at quadrature nodes of the measure D(m) cos(theta_m) dm, and their weights."""
    x, w = np.polynomial.legendre.leggauss(_U_NODES)
    u, wu = 0.5 * (x + 1.0), 0.5 * w
    tan2 = -alpha * alpha * np.log1p(-u) if model == BECKMANN else alpha * alpha * u / (1.0 - u)
    cos_t = 1.0 / np.sqrt(1.0 + tan2)
    sin_t = np.sqrt(np.maximum(0.0, 1.0 - cos_t * cos_t))
    phi = (np.arange(_PHI_NODES) + 0.5) * (2.0 * math.pi / _PHI_NODES)
    m = np.stack([np.outer(sin_t, np.cos(phi)), np.outer(sin_t, np.sin(phi)),
                  np.repeat(cos_t[:, None], _PHI_NODES, axis=1)], axis=-1).reshape(-1, 3)
    weights = np.repeat(wu, _PHI_NODES) / _PHI_NODES
    return m, weights


def _ggx_visible_normals(wi: np.ndarray, alpha: float) -> tuple[np.ndarray, np.ndarray]:
    """GGX's visible normals for direction wi (Heitz 2018) at Gauss-Legendre nodes of the unit
    square, with the nodes' weights: the quadrature of Mitsuba's tables, whose integrand is smooth
    in the square."""
    x, w = np.polynomial.legendre.leggauss(_VNDF_NODES)
    u1, u2 = np.meshgrid(0.5 * (x + 1.0), 0.5 * (x + 1.0), indexing="ij")
    weights = np.outer(0.5 * w, 0.5 * w).ravel()
    vh = np.array([alpha * wi[0], alpha * wi[1], wi[2]])
    vh /= np.linalg.norm(vh)
    lensq = vh[0] ** 2 + vh[1] ** 2
    t1 = np.array([-vh[1], vh[0], 0.0]) / math.sqrt(lensq) if lensq > 0 else np.array([1.0, 0.0, 0.0])
    t2 = np.cross(vh, t1)
    r, phi = np.sqrt(u1.ravel()), 2.0 * math.pi * u2.ravel()
    p1, p2 = r * np.cos(phi), r * np.sin(phi)
    s = 0.5 * (1.0 + vh[2])
    p2 = (1.0 - s) * np.sqrt(np.maximum(0.0, 1.0 - p1 * p1)) + s * p2
    nh = p1[:, None] * t1 + p2[:, None] * t2 + np.sqrt(np.maximum(0.0, 1.0 - p1 * p1 - p2 * p2))[:, None] * vh
    m = np.stack([alpha * nh[:, 0], alpha * nh[:, 1], np.maximum(1e-7, nh[:, 2])], axis=-1)
    return m / np.linalg.norm(m, axis=-1, keepdims=True), weights


def _interface_albedo(mu: np.ndarray, alpha: float, eta: float, model: int, transmitted: bool) -> np.ndarray:
    """For incident cosines mu: the share of light the rough interface transmits (transmitted) or
    reflects, each direction weighted by Smith's G1 of the outgoing direction (Mitsuba's
    eval_transmittance / eval_reflectance, integrated over the visible normals)."""
    out = np.zeros_like(mu)
    if model == BECKMANN:  # the same nodes for every incident cosine
        m_beckmann, w_beckmann = _normals(alpha, model)
    for i, c in enumerate(mu):
        wi = np.array([math.sqrt(max(0.0, 1.0 - c * c)), 0.0, c])
        if model == BECKMANN:
            m, weights = m_beckmann, w_beckmann
            cos_im = m @ wi
            # D_wi(m) / (D(m) cos(theta_m)): the visible normals' density over the quadrature's
            visible = _exact_g1(np.array([c]), alpha, model)[0] * np.maximum(cos_im, 0.0) / (c * m[:, 2])
        else:
            m, weights = _ggx_visible_normals(wi, alpha)
            cos_im = m @ wi
            visible = np.ones_like(cos_im)
        f, cos_t = fresnel_dielectric(cos_im, eta)
        if transmitted:
            wo = -wi / eta + (cos_im / eta - cos_t)[:, None] * m
            keep = (wo[:, 2] < 0.0) & (cos_t > 0.0)
            share = 1.0 - f
        else:
            wo = 2.0 * cos_im[:, None] * m - wi
            keep = wo[:, 2] > 0.0
            share = f
        value = np.where(keep & (cos_im > 0.0), share * _g1(wo, alpha, model), 0.0)
        out[i] = np.sum(weights * visible * value)
    return out


def table_cosines() -> np.ndarray:
    return np.maximum(1e-6, np.linspace(0.0, 1.0, TABLE_SIZE))


def rough_transmittance(alpha: float, eta: float, model: int) -> np.ndarray:
    """T(mu) at table_cosines(): the rough coating's transmittance from outside."""
    return _interface_albedo(table_cosines(), alpha, eta, model, transmitted=True)


def rough_internal_reflectance(alpha: float, eta: float, model: int) -> float:
    """Mitsuba's mean internal reflectance of the rough coating: 2 mean(mu r(mu)) over the table's
    cosines, r the reflectance from inside (relative index 1 / eta)."""
    mu = table_cosines()
    return float(2.0 * np.mean(_interface_albedo(mu, alpha, 1.0 / eta, model, transmitted=False) * mu))


def plastic_row(spec, tables: list) -> dict:
    """The plastic columns of a material row; a rough plastic's transmittance table is appended to
    `tables` and the row names its index."""
    eta = float(spec.ior)
    d_mean = float(np.mean(spec.base_color))
    s_mean = float(np.mean(spec.specular_color))
    row = {"nonlinear": int(spec.nonlinear), "specular_weight": s_mean / max(d_mean + s_mean, 1e-6)}
    if spec.roughness <= 0.0:
        return {**row, "internal_reflectance": diffuse_fresnel_reflectance(1.0 / eta)}
    alpha, model = alpha_from_roughness(spec.roughness), MODELS[spec.microfacet]
    tables.append(rough_transmittance(alpha, eta, model))
    return {**row, "internal_reflectance": rough_internal_reflectance(alpha, eta, model),
            "plastic_table": len(tables) - 1}
