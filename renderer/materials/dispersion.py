"""Wavelength-dependent index of refraction of dispersive dielectrics.

A material's dispersion is stored as data: kind (NONE, CAUCHY, SELLMEIER) and two vec4 of
coefficients. Cauchy, n = A + B / lambda^2, is set from the material's `ior` (taken as n at the
helium d line, 587.56 nm) and an Abbe number V = (n_d - 1) / (n_F - n_C); Sellmeier comes from a
real glass's published coefficients (renderer/spectral/ior.py). Only scenes with a dispersive
material compile spectral code (Features.has_dispersion).
"""
import numpy as np
import taichi as ti

from dataclasses import replace

from renderer.spectral.ior import (LINE_C, LINE_D, LINE_F, SELLMEIER_PRESETS, cauchy_ior, cauchy_ior_np, sellmeier_ior,
                                   sellmeier_ior_np)

NONE, CAUCHY, SELLMEIER = 0, 1, 2


def cauchy_from_abbe(ior: float, abbe: float) -> tuple[float, float]:
    """(A, B in um^2) of the Cauchy curve through n(587.56 nm) = ior with Abbe number `abbe`."""
    inv2 = lambda nm: 1.0 / (nm * 1e-3) ** 2  # noqa: E731
    b = (ior - 1.0) / (abbe * (inv2(LINE_F) - inv2(LINE_C)))
    return ior - b * inv2(LINE_D), b


def dispersion_row(spec) -> dict:
    """The table columns of a MaterialSpec's dispersion: kind, coefficients b and c."""
    if spec.glass:
        b, c = SELLMEIER_PRESETS[spec.glass]
        return {"dispersion": SELLMEIER, "dispersion_b": tuple(b), "dispersion_c": tuple(c)}
    if spec.abbe > 0.0:
        a, b = cauchy_from_abbe(spec.ior, spec.abbe)
        return {"dispersion": CAUCHY, "dispersion_b": (a, b, 0.0, 0.0), "dispersion_c": (0.0,) * 4}
    return {"dispersion": NONE, "dispersion_b": (0.0,) * 4, "dispersion_c": (0.0,) * 4}


@ti.func
def ior_at(rec, lam_nm):
    """A dispersive material row's index of refraction at lam_nm (its `ior` if not dispersive)."""
    n = rec.ior
    if rec.dispersion == CAUCHY:
        n = cauchy_ior(lam_nm, rec.dispersion_b.x, rec.dispersion_b.y)
    elif rec.dispersion == SELLMEIER:
        n = sellmeier_ior(lam_nm, rec.dispersion_b, rec.dispersion_c)
    return ti.max(n, 1.0001)


def ior_at_np(spec, lam_nm) -> np.ndarray:
    """A MaterialSpec's index of refraction at lam_nm (float64), as `ior_at` gives it on the device."""
    row = dispersion_row(spec)
    lam = np.asarray(lam_nm, np.float64)
    n = np.full_like(lam, spec.ior)
    if row["dispersion"] == CAUCHY:
        n = cauchy_ior_np(lam, *row["dispersion_b"][:2])
    elif row["dispersion"] == SELLMEIER:
        n = sellmeier_ior_np(lam, row["dispersion_b"], row["dispersion_c"])
    return np.maximum(n, 1.0001)


def non_dispersive(spec):
    """The same material without dispersion: a plain dielectric with its index at the d line."""
    if not spec.is_dispersive:
        return spec
    return replace(spec, glass="", abbe=0.0, ior=float(ior_at_np(spec, [LINE_D])[0]))
