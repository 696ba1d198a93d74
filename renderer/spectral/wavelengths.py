"""Wavelength sampling for spectral rendering with hero wavelengths (Wilkie et al. 2014).

Wavelengths are in nanometres over [LAMBDA_MIN, LAMBDA_MAX] = [360, 830], the range of the CIE
1931 tables. Two densities:

uniform
    p(lambda) = 1 / 470 nm.
visible
    p(lambda) proportional to sech^2(a (lambda - c)), a = 0.0072 / nm, c = 538 nm: the
    "visible-importance" density of Radziszewski et al. 2009, the one pbrt-v4 samples with
    `SampleVisibleWavelengths`. It follows the sum of the colour matching functions closely, so
    spectra weighted by CMF / pdf have far less variance than with the uniform density. Its CDF
    is a tanh, so the exact inverse is an atanh; the normalisation is computed here from the
    bounds (not rounded constants), so the density integrates to 1 over the range exactly.

Hero wavelengths: `sample_hero_wavelengths(u)` returns HERO_COUNT = 4 wavelengths whose primary
samples are u, u + 1/4, u + 2/4, u + 3/4 (mod 1). Rotating in primary sample space is Wilkie's
rotation of the hero wavelength, carried over to a non-uniform density (as pbrt-v4 does): each
wavelength is distributed with the density on its own, they stratify the range together, and the
estimate of a spectral quantity f is mean_j f(lambda_j) / p(lambda_j). (When a path's direction
depends on the wavelength, e.g. at a dispersive interface, the integrator either continues with
the hero alone, or weights the four by the balance heuristic over their path pdfs; that choice is
the integrator's.)

Taichi funcs are f32 and branch-light; the `*_np` functions are float64 numpy references.
"""
from __future__ import annotations

import math

import numpy as np
import taichi as ti

LAMBDA_MIN = 360.0
LAMBDA_MAX = 830.0
LAMBDA_RANGE = LAMBDA_MAX - LAMBDA_MIN
HERO_COUNT = 4

VISIBLE_A = 0.0072  # 1/nm, width of the sech^2 lobe (Radziszewski et al. 2009)
VISIBLE_CENTER = 538.0  # nm
_T_LO = math.tanh(VISIBLE_A * (LAMBDA_MIN - VISIBLE_CENTER))
_T_HI = math.tanh(VISIBLE_A * (LAMBDA_MAX - VISIBLE_CENTER))
# p(lambda) = _NORM * sech^2(a (lambda - c)) integrates to _NORM / a * (T_HI - T_LO) = 1.
_NORM = VISIBLE_A / (_T_HI - _T_LO)

vec4 = ti.math.vec4


# --- uniform ---------------------------------------------------------------------------------


@ti.func
def sample_uniform_wavelength(u):
    return LAMBDA_MIN + u * LAMBDA_RANGE


@ti.func
def uniform_wavelength_pdf(lam):
    pdf = 0.0
    if lam >= LAMBDA_MIN and lam <= LAMBDA_MAX:
        pdf = 1.0 / LAMBDA_RANGE
    return pdf


# --- visible importance ----------------------------------------------------------------------


@ti.func
def sample_visible_wavelength(u):
    """The inverse CDF: lambda = c + atanh(T_lo + u (T_hi - T_lo)) / a, u in [0, 1)."""
    y = _T_LO + u * (_T_HI - _T_LO)  # in [-0.86, 0.97]: atanh's log stays far from 0 and inf
    lam = VISIBLE_CENTER + 0.5 * ti.log((1.0 + y) / (1.0 - y)) / VISIBLE_A
    return ti.min(ti.max(lam, LAMBDA_MIN), LAMBDA_MAX)  # f32 rounding at u -> 0 or 1


@ti.func
def visible_wavelength_pdf(lam):
    pdf = 0.0
    if lam >= LAMBDA_MIN and lam <= LAMBDA_MAX:
        e = ti.exp(VISIBLE_A * (lam - VISIBLE_CENTER))  # |exponent| <= 2.1: no overflow
        c = e + 1.0 / e  # 2 cosh
        pdf = _NORM * 4.0 / (c * c)
    return pdf


@ti.func
def sample_hero_wavelengths(u):
    """(lambdas, pdfs), two vec4: the visible density at primary samples u + j/4 (mod 1)."""
    lams = vec4(0.0)
    pdfs = vec4(0.0)
    for j in ti.static(range(HERO_COUNT)):
        uj = u + j / HERO_COUNT
        if uj >= 1.0:
            uj -= 1.0
        lams[j] = sample_visible_wavelength(uj)
        pdfs[j] = visible_wavelength_pdf(lams[j])
    return lams, pdfs


# --- numpy references ------------------------------------------------------------------------


def sample_uniform_wavelength_np(u):
    return LAMBDA_MIN + np.asarray(u, np.float64) * LAMBDA_RANGE


def uniform_wavelength_pdf_np(lam):
    lam = np.asarray(lam, np.float64)
    return np.where((lam >= LAMBDA_MIN) & (lam <= LAMBDA_MAX), 1.0 / LAMBDA_RANGE, 0.0)


def sample_visible_wavelength_np(u):
    y = _T_LO + np.asarray(u, np.float64) * (_T_HI - _T_LO)
    return VISIBLE_CENTER + np.arctanh(y) / VISIBLE_A


def visible_wavelength_pdf_np(lam):
    lam = np.asarray(lam, np.float64)
    pdf = _NORM / np.cosh(VISIBLE_A * (lam - VISIBLE_CENTER)) ** 2
    return np.where((lam >= LAMBDA_MIN) & (lam <= LAMBDA_MAX), pdf, 0.0)


def visible_wavelength_cdf_np(lam):
    lam = np.clip(np.asarray(lam, np.float64), LAMBDA_MIN, LAMBDA_MAX)
    return (np.tanh(VISIBLE_A * (lam - VISIBLE_CENTER)) - _T_LO) / (_T_HI - _T_LO)


def sample_hero_wavelengths_np(u):
    """(lambdas (..., 4), pdfs (..., 4)) for primary samples u (...)."""
    u = np.asarray(u, np.float64)[..., None]
    uj = np.mod(u + np.arange(HERO_COUNT) / HERO_COUNT, 1.0)
    lams = sample_visible_wavelength_np(uj)
    return lams, visible_wavelength_pdf_np(lams)
