"""Conductors described by a complex index of refraction eta + i k (RGB), written in a scene as
`eta` and `k` or as a named measured `metal`: the columns of their material-table row.

A row with `complex_ior = 1` takes its Fresnel from microfacet.fresnel_conductor (exact, from eta
and k) instead of the colour at normal incidence and edge tint. Energy compensation needs the
Fresnel's cosine-weighted average F_avg = 2 int_0^1 F(mu) mu dmu; for these rows it is computed
here once per material, by quadrature on the host, and stored in the row (`fresnel_avg`).
"""
import numpy as np

from renderer.materials.metals import metal_ior

# Composite Gauss-Legendre over mu in [0, 1]. F is smooth in mu except at a critical angle
# (k = 0, eta < 1: a square-root kink), which is made a panel edge.
_PANELS, _ORDER = 256, 8


def complex_ior(spec):
    """(eta, k) of a conductor spec that has them (written, or from its `metal`), else None."""
    if spec is None or spec.kind not in ("conductor", "coated"):
        return None
    if spec.kind == "coated" and spec.coat_base != "conductor":
        return None
    if spec.metal:
        return metal_ior(spec.metal)
    if spec.eta is not None:
        return tuple(spec.eta), tuple(spec.k)
    if spec.kind == "coated":
        return metal_ior("Cu")  # pbrt-v4's coatedconductor default: copper
    return None


def fresnel_conductor_np(cos_i, eta, k) -> np.ndarray:
    """numpy twin (float64) of microfacet.fresnel_conductor: cos_i (N,), eta and k (3,) -> (N, 3)."""
    c = np.clip(np.asarray(cos_i, np.float64), 0.0, 1.0)[:, None]
    eta = np.asarray(eta, np.float64)[None, :]
    k = np.asarray(k, np.float64)[None, :]
    s2 = 1.0 - c * c
    t = eta * eta - k * k - s2
    y = 2.0 * eta * k
    modulus = np.hypot(t, y)
    with np.errstate(divide="ignore", invalid="ignore"):
        a_pos = np.sqrt(0.5 * (modulus + t))
        b_neg = np.sqrt(0.5 * (modulus - t))
        a = np.where(t >= 0.0, a_pos, y / (2.0 * b_neg))
        b = np.where(t >= 0.0, np.where(a_pos > 0.0, y / (2.0 * a_pos), 0.0), b_neg)
    b2 = b * b
    bc2 = b2 * c * c
    den_s = (a + c) ** 2 + b2
    den_p = (a * c + s2) ** 2 + bc2
    with np.errstate(divide="ignore", invalid="ignore"):
        rs = np.where(den_s > 0.0, ((a - c) ** 2 + b2) / den_s, 1.0)
        ratio = np.where(den_p > 0.0, ((a * c - s2) ** 2 + bc2) / den_p, 1.0)
    return 0.5 * rs * (1.0 + ratio)


def fresnel_average(eta, k) -> np.ndarray:
    """F_avg = 2 int_0^1 F(mu) mu dmu per channel (3,), by composite Gauss-Legendre quadrature."""
    x, w = np.polynomial.legendre.leggauss(_ORDER)
    average = np.zeros(3)
    for c in range(3):
        critical = [np.sqrt(1.0 - eta[c] ** 2)] if k[c] == 0.0 and eta[c] < 1.0 else []
        edges = np.unique(np.concatenate([np.linspace(0.0, 1.0, _PANELS + 1), critical]))
        h = np.diff(edges)[:, None]
        mu = (edges[:-1, None] + 0.5 * h * (x[None, :] + 1.0)).ravel()
        weights = (0.5 * h * w[None, :]).ravel()
        average[c] = 2.0 * np.sum(weights * mu * fresnel_conductor_np(mu, eta, k)[:, c])
    return average


def conductor_ior_row(spec=None) -> dict:
    """The table columns of a material's complex index: the per-row switch, eta, k and F_avg
    (zeros for every row that does not use them)."""
    ior = complex_ior(spec)
    if ior is None:
        return {"complex_ior": 0, "eta": (0.0,) * 3, "k": (0.0,) * 3, "fresnel_avg": (0.0,) * 3}
    eta, k = ior
    return {"complex_ior": 1, "eta": eta, "k": k, "fresnel_avg": tuple(fresnel_average(eta, k))}
